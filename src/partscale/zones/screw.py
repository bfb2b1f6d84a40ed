"""Repetition by a rigid motion that is not a shift along one axis: a flight's steps.

A straight flight repeats by a *diagonal* shift: each step is the one below moved by
``(going, rise)`` along a horizontal axis and up. :func:`find_screws` finds such shifts on the
surface itself: surface samples (voxels within half a voxel of it) moved by a candidate shift
``t`` land on the surface again (``|sdf| < 1`` voxel there) for a share of them, the *support*.
Candidates run over the plane of up (y) and each horizontal axis, every 2 voxels up to half the
solid, coarse (nearest voxel) first, then refined to quarter voxels (trilinear). A candidate is
a screw where

- its support is at least :data:`MIN_SUPPORT` among the samples whose shifted place lies inside
  the solid's box (a share :data:`MIN_OVERLAP` of them at least),
- it is *diagonal*: at least :data:`MIN_EXCLUSIVE` of the samples land on the surface under
  it and under neither its part up alone nor its part across alone (a bookcase repeats
  straight up and its boards run straight across; a flight's floor and sides match any shift
  along them: only treads and risers are the steps' own),
- it is *discrete*: half of it reaches :data:`DISCRETE` less support (a bar along the
  diagonal matches itself at every shift; steps do not),

and the fundamental one of those along a line (multiples of a step match too) is kept.

The step it repeats, :func:`step_edit` (:mod:`partscale.edit.warp`'s screw zone): everything
beyond a cut plane across the flight's horizontal axis moves by ``n`` steps, so ``n`` more
steps stand between (the stringers and handrails, which the shift carries onto themselves, run
on). The cut lies where the surface on either side of it matches that shifted across it best,
in the middle of the repeat (a tread, not a riser).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage

from ..csdf import CSDF
from ..edit import AXES, ScrewZone

#: Least support of a screw (share of shifted surface samples landing on the surface) ...
MIN_SUPPORT = 0.6
#: ... and least share that only it carries onto the surface (:func:`_exclusive`) ...
MIN_EXCLUSIVE = 0.15
#: ... and half of it reaches at least this much less support (steps are discrete).
DISCRETE = 0.3
#: Least share of the samples whose shifted place is inside the solid's box.
MIN_OVERLAP = 0.3
#: Surface samples used.
SAMPLES = 4000
#: A sample counts where its normal's part square to the shift's plane is at most this share.
IN_PLANE = 0.7
#: Layers either side of a candidate cut compared for calm (the blend reaches two).
CUT_CALM = 3
#: Shifts within this support of the best are the refined plateau (:func:`_refine`).
PLATEAU = 0.003
#: Coarse search step, voxels; and how many of the best coarse shifts per axis are refined.
COARSE = 2.0
REFINED = 24
#: Shifts whose support is within this of the best count as tied (the shortest is the step).
TIED = 0.02


@dataclass(frozen=True)
class Screw:
    """A repetition by a diagonal shift (see module).

    Parameters
    ----------
    axis : {'x', 'z'}
        The horizontal axis the flight runs along.
    step : (3,) float
        The shift carrying one step onto the next (world units; up is +y).
    support : float
        Share of shifted surface samples landing on the surface.
    count : int
        Steps the repeat covers (the solid's extent along ``axis`` over the going, rounded).
    cut : float
        Where along ``axis`` a count edit cuts (world units): across a tread.

    Examples
    --------
    The repeat of a flight of six steps 0.2 long and 0.15 high along x, as :func:`find_screws`
    reports one:

    >>> from partscale.zones import Screw
    >>> s = Screw("x", (0.2, 0.15, 0.0), 0.9, 6, 0.5)
    >>> s.going, s.rise, s.zone(1).to_json()
    (0.2, 0.15, {'screw': {'axis': 'x', 'step': [0.2, 0.15, 0.0], 'cut': 0.5}, 'copies': 1})
    """

    axis: str
    step: tuple[float, float, float]
    support: float
    count: int
    cut: float

    @property
    def going(self) -> float:
        """A step's horizontal length (world units)."""
        return abs(self.step[AXES.index(self.axis)])

    @property
    def rise(self) -> float:
        """A step's height (world units)."""
        return self.step[1]

    def zone(self, n: int) -> ScrewZone:
        """The count edit adding ``n`` steps (``-n``: removing them)."""
        return ScrewZone(self.axis, self.step, self.cut, n)

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {
            "axis": self.axis,
            "step": list(self.step),
            "going": self.going,
            "rise": self.rise,
            "support": round(self.support, 4),
            "count": self.count,
            "cut": self.cut,
        }


def _samples(csdf: CSDF, axis: int) -> np.ndarray:
    """(S, 3) float64 voxel indices of up to :data:`SAMPLES` surface voxels, evenly spread,
    whose surface faces partly along ``axis`` or up (a tread, a riser): a face square to the
    third axis (a flight's side) matches itself under every shift in that plane and says
    nothing.
    """
    h = csdf.voxel_size
    sdf = np.asarray(csdf.sdf)
    pts = np.argwhere(np.abs(sdf) <= 0.5 * h)
    if len(pts) == 0:
        return pts.astype(np.float64)
    other = 3 - axis - 1  # the third axis (neither ``axis`` nor up)
    lo = np.clip(pts - 1, 0, np.array(sdf.shape) - 1)
    hi = np.clip(pts + 1, 0, np.array(sdf.shape) - 1)
    g = np.stack(
        [
            sdf[tuple(np.where(np.arange(3)[:, None] == k, hi.T, pts.T))]
            - sdf[tuple(np.where(np.arange(3)[:, None] == k, lo.T, pts.T))]
            for k in range(3)
        ],
        axis=1,
    )
    norm = np.linalg.norm(g, axis=1)
    keep = np.abs(g[:, other]) <= IN_PLANE * np.maximum(norm, 1e-12)
    pts = pts[keep & (norm > 0)].astype(np.float64)
    if len(pts) > SAMPLES:
        pts = pts[np.linspace(0, len(pts) - 1, SAMPLES).astype(np.int64)]
    return pts


class _Scorer:
    """Support of shifts (voxel units) of the surface samples of one CSDF."""

    def __init__(self, csdf: CSDF, axis: int):
        self.sdf = np.asarray(csdf.sdf)
        self.h = csdf.voxel_size
        self.pts = _samples(csdf, axis)
        solid = np.argwhere(self.sdf < 0)
        self.lo, self.hi = solid.min(axis=0), solid.max(axis=0)

    def matches(self, t: np.ndarray, *, fine: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(S,) bool each: the samples shifted by ``t`` (voxels) that land on the surface, and
        those whose shifted place lies inside the solid's box.
        """
        q = self.pts + t
        ok = ((q >= self.lo) & (q <= self.hi)).all(axis=1)
        hit = np.zeros(len(q), dtype=bool)
        if fine:
            v = ndimage.map_coordinates(self.sdf, q[ok].T, order=1, mode="nearest")
        else:
            i = np.rint(q[ok]).astype(np.int64)
            v = self.sdf[i[:, 0], i[:, 1], i[:, 2]]
        # the coarse pass lands up to a voxel off the exact shift: a voxel more of tolerance
        hit[ok] = np.abs(v) < (1.0 if fine else 2.0) * self.h
        return hit, ok

    def __call__(self, t: np.ndarray, *, fine: bool = False) -> float:
        """The support of shift ``t``: the share of the samples landing inside the solid's box
        (at least :data:`MIN_OVERLAP` of all) that land on the surface; 0 where too few do.
        """
        hit, ok = self.matches(t, fine=fine)
        if ok.mean() < MIN_OVERLAP:
            return 0.0
        return float(hit[ok].mean())


def find_screws(csdf: CSDF) -> list[Screw]:
    """The diagonal repetitions of ``csdf`` (see module): flights of steps.

    Parameters
    ----------
    csdf : CSDF
        The object (up is +y: each step rises along it).

    Returns
    -------
    list of Screw
        Best supported first; empty where nothing repeats diagonally.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> steps = [((0.2 * i, 0, 0), (0.2 * (i + 1), 0.15 * (i + 1), 0.8)) for i in range(6)]
    >>> flight = shapes.grid(lambda p: shapes.boxes_sdf(p, steps), [(0, 0, 0), (1.2, 0.9, 0.8)], voxel_size=0.02)
    >>> s = zones.find_screws(flight)[0]
    >>> s.axis, s.count, round(s.going, 2), round(s.rise, 2)
    ('x', 6, 0.2, 0.15)
    """
    if not (csdf.sdf < 0).any():
        return []
    found: list[tuple[float, np.ndarray, int]] = []
    scorers = {}
    for a in (0, 2):
        score = scorers[a] = _Scorer(csdf, a)
        if len(score.pts) == 0:
            continue
        span = score.hi - score.lo
        cands = []
        reach = COARSE * np.arange(1, int(span[a] / 2 / COARSE) + 1)
        dxs = np.concatenate([-reach[::-1], reach])
        dys = COARSE * np.arange(1, int(span[1] / 2 / COARSE) + 1)
        # what a shift across or up alone reaches (a floor, a side): a candidate must reach
        # more than that
        across = {}
        for dx in dxs:
            u = np.zeros(3)
            u[a] = dx
            across[float(dx)] = score(u)
        up = {float(dy): score(np.array([0.0, dy, 0.0])) for dy in dys}
        for dx in dxs:
            for dy in dys:
                t = np.zeros(3)
                t[a], t[1] = dx, dy
                s = score(t)
                margin = s - max(across[float(dx)], up[float(dy)])
                if s >= MIN_SUPPORT / 2 and margin >= MIN_EXCLUSIVE / 2:
                    cands.append((float(np.linalg.norm(t)), t))
        # shortest first: the step itself before its multiples (which match as well)
        cands.sort(key=lambda c: c[0])
        for _, t in cands[:REFINED]:
            t, s = _refine(score, t, a)
            if (
                s >= MIN_SUPPORT
                and _exclusive(score, t, a) >= MIN_EXCLUSIVE
                and score(t / 2, fine=True) <= s - DISCRETE
            ):
                found.append((s, t, a))
    screws = _fundamental(found)
    return [_screw(csdf, scorers[a], s, t, a) for s, t, a in screws]


def _refine(score: _Scorer, t: np.ndarray, a: int) -> tuple[np.ndarray, float]:
    """The shift near ``t`` (within a coarse step, to a quarter voxel) of best support, and its
    support: the middle of the shifts on a quarter-voxel grid whose support is within
    :data:`PLATEAU` of the best (the support counts samples within a voxel of the surface, so
    it is flat over the exact shift's neighbours; their middle is the shift).
    """

    def grid(centre: np.ndarray, reach: float, step: float) -> list[tuple[float, np.ndarray]]:
        offs = np.arange(-reach, reach + 1e-9, step)
        out = []
        for ox in offs:
            for oy in offs:
                u = centre.copy()
                u[a] += ox
                u[1] += oy
                out.append((score(u, fine=True), u))
        return out

    first = grid(t, COARSE, 0.5)
    centre = max(first, key=lambda g: g[0])[1]
    fine = grid(centre, 1.0, 0.25)
    best = max(g[0] for g in fine)
    mid = np.array([u for s, u in fine if s >= best - PLATEAU]).mean(axis=0)
    return mid, score(mid, fine=True)


def _exclusive(score: _Scorer, t: np.ndarray, a: int) -> float:
    """Share of the samples (among those landing inside the box) that ``t`` carries onto the
    surface and neither its part up nor its part across does: the steps' own surface (treads,
    risers), not a floor, a side or a board that a shift along it keeps.
    """
    up = np.array([0.0, t[1], 0.0])
    across = np.zeros(3)
    across[a] = t[a]
    hit, ok = score.matches(t, fine=True)
    for u in (up, across):
        hit &= ~score.matches(u, fine=True)[0]
    return float(hit.sum() / max(int(ok.sum()), 1))


def _fundamental(found: list[tuple[float, np.ndarray, int]]) -> list[tuple[float, np.ndarray, int]]:
    """One step per horizontal axis (a flight has one): among the shifts within
    :data:`TIED` of the best supported, the shortest (its multiples match as well); best
    supported first.
    """
    out = []
    for a in (0, 2):
        mine = [f for f in found if f[2] == a]
        if not mine:
            continue
        best = max(f[0] for f in mine)
        out.append(
            min((f for f in mine if f[0] >= best - TIED), key=lambda f: np.linalg.norm(f[1]))
        )
    return sorted(out, key=lambda f: -f[0])


def _screw(csdf: CSDF, score: _Scorer, s: float, t: np.ndarray, a: int) -> Screw:
    """The :class:`Screw` of shift ``t`` (voxels) along axis ``a``, with its cut."""
    h = csdf.voxel_size
    count = max(1, round(float(score.hi[a] - score.lo[a] + 1) / abs(float(t[a]))))
    cut = _cut(csdf, t, a, score)
    step = (float(t[0] * h), float(t[1] * h), float(t[2] * h))
    return Screw(AXES[a], step, s, count, cut)


def _cut(csdf: CSDF, t: np.ndarray, a: int, score: _Scorer) -> float:
    """World position along axis ``a`` of the cut plane: among the layers of the middle half of
    the solid along ``a``, the calmest (the surface changes least from the layers
    :data:`CUT_CALM` either side: a tread's middle, not a riser, where the blend of the two
    sides would show) where the surface matches the surface shifted by ``t`` (the mean
    ``|sdf(p) - sdf(p - t)|`` over its band voxels, in voxels), nearest the middle.
    """
    sdf = np.asarray(csdf.sdf)
    h = csdf.voxel_size
    lo, hi = int(score.lo[a]), int(score.hi[a])
    mid = (lo + hi) / 2
    layers = np.arange(int(lo + (hi - lo) / 4), int(hi - (hi - lo) / 4) + 1)
    costs = []
    for i in layers:
        layer = np.take(sdf, int(i), axis=a)
        band = np.argwhere(np.abs(layer) <= 2 * h)
        if band.size == 0:
            costs.append(np.inf)
            continue
        p = np.insert(band.astype(np.float64), a, float(i), axis=1)
        v = ndimage.map_coordinates(sdf, (p - t).T, order=1, mode="nearest")
        own = layer[band[:, 0], band[:, 1]]
        match = float(np.mean(np.abs(own - v)) / h)
        near = [
            np.take(sdf, int(np.clip(i + k, 0, sdf.shape[a] - 1)), axis=a)
            for k in (-CUT_CALM, CUT_CALM)
        ]
        change = max(float(np.mean(np.abs(n[band[:, 0], band[:, 1]] - own)) / h) for n in near)
        costs.append(match + change)
    costs_a = np.asarray(costs)
    good = np.flatnonzero(costs_a <= np.nanmin(costs_a) + 0.05)
    best = layers[good[np.argmin(np.abs(layers[good] - mid))]]
    return float(csdf.origin[a] + best * h)
