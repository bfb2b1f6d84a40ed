"""Repetition by a turn about the vertical and a rise: a spiral stair's steps.

A spiral stair repeats by a *helical* motion: each tread is the one below turned by an angle
about a vertical axis and raised by a rise. :func:`find_helices` finds such motions on the
surface itself, as :func:`~partscale.zones.find_screws` finds diagonal shifts: surface samples
(voxels within half a voxel of it) moved by a candidate land on the surface again (``|sdf| <
1`` voxel there) for a share of them, the *support*. Candidates turn by
:data:`MIN_ANGLE`..:data:`MAX_ANGLE` degrees either way about the vertical through the middle of
the solid's footprint (then through the middle of its tallest column of voxels, where that
finds none) and rise every 2 voxels up to half the solid, coarse (nearest voxel) first; the best
are refined to sub-voxel with the axis free (Gauss-Newton on ``sdf(T p) - sdf(p)`` over the
samples that match). A candidate is a helix where

- its support is at least :data:`~partscale.zones.screw.MIN_SUPPORT` among the samples whose
  moved place lies inside the solid's box,
- at least :data:`~partscale.zones.screw.MIN_EXCLUSIVE` of the samples land on the surface
  under it and under neither its turn alone nor its rise alone (a round table's column and
  top match any turn, a bookcase's sides any rise: only treads are the steps' own),
- half of it reaches :data:`~partscale.zones.screw.DISCRETE` less support (steps are
  discrete; a column matches itself under every turn and rise),
- it rises at least a voxel and turns at least :data:`MIN_ANGLE` (a pure turn is a round
  object's symmetry, no stair),

and the fundamental one (its multiples match as well) is kept.

The steps it repeats (:class:`~partscale.edit.HelixZone`): everything above a level ``cut``
turns and rises by ``n`` steps. The cut lies between two treads near the middle of the stair,
where the level's surface matches the surface one step down the helix best and changes least
from the levels either side: only what repeats crosses it (the column, the handrail, the air
between turns), so both sides agree there and the column and the handrail run on.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage

from ..csdf import CSDF
from ..edit import HelixZone
from .screw import CUT_CALM, DISCRETE, MIN_EXCLUSIVE, MIN_OVERLAP, MIN_SUPPORT, SAMPLES, TIED

#: Least and most turn of a step, degrees (either way).
MIN_ANGLE = 4.0
MAX_ANGLE = 90.0
#: Coarse search: the turn's step moves the farthest sample this many voxels; rises every
#: :data:`COARSE` voxels; the best :data:`REFINED` (apart from one another) are refined.
ARC = 1.5
COARSE = 2.0
REFINED = 8
#: Gauss-Newton iterations of the refinement.
ITERATIONS = 12


@dataclass(frozen=True)
class Helix:
    """A repetition by a turn about the vertical and a rise (see module).

    Parameters
    ----------
    center, angle, rise
        The vertical axis and one step's turn and rise, as :class:`~partscale.edit.HelixZone`
        holds them (what :meth:`zone` passes on).
    support : float
        Share of moved surface samples landing on the surface.
    count : int
        Treads the repeat covers (counted by their tops' levels).
    cut : float
        The height (world y) of the level a count edit cuts at: between two treads.

    Examples
    --------
    >>> from partscale.zones import Helix
    >>> Helix((0.0, 0.0), 30.0, 0.15, 0.9, 12, 0.8).zone(1).to_json()["helix"]["angle"]
    30.0
    """

    center: tuple[float, float]
    angle: float
    rise: float
    support: float
    count: int
    cut: float

    def zone(self, n: int) -> HelixZone:
        """The count edit adding ``n`` steps (``-n``: removing them)."""
        return HelixZone(self.center, self.angle, self.rise, self.cut, n)

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what the editor's API and ``suggest --json`` hold)."""
        return {
            "center": list(self.center),
            "angle": self.angle,
            "rise": self.rise,
            "support": round(self.support, 4),
            "count": self.count,
            "cut": self.cut,
        }


class _Scorer:
    """Support of helical motions (radians, voxels, axis in voxel indices) of one CSDF's
    surface samples.
    """

    def __init__(self, csdf: CSDF):
        self.sdf = np.asarray(csdf.sdf)
        self.h = csdf.voxel_size
        pts = np.argwhere(np.abs(self.sdf) <= 0.5 * self.h)
        if len(pts) > SAMPLES:
            pts = pts[np.linspace(0, len(pts) - 1, SAMPLES).astype(np.int64)]
        self.pts = pts.astype(np.float64)
        self.v0 = self.sdf[tuple(pts.T)].astype(np.float64) / self.h
        solid = np.argwhere(self.sdf < 0)
        self.lo, self.hi = solid.min(axis=0), solid.max(axis=0)

    def place(self, x: np.ndarray) -> np.ndarray:
        """(S, 3) the samples moved by ``x = (angle, rise, cx, cz)``."""
        t, c = x[0], x[2:4]
        d = self.pts[:, [0, 2]] - c
        cs, sn = math.cos(t), math.sin(t)
        q = np.empty_like(self.pts)
        q[:, 0] = c[0] + cs * d[:, 0] - sn * d[:, 1]
        q[:, 2] = c[1] + sn * d[:, 0] + cs * d[:, 1]
        q[:, 1] = self.pts[:, 1] + x[1]
        return q

    def inside(self, q: np.ndarray) -> np.ndarray:
        """(S,) bool: the moved places inside the solid's box."""
        return ((q >= self.lo) & (q <= self.hi)).all(axis=1)

    def matches(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(S,) bool each: the samples moved by ``x`` that land on the surface (trilinear), and
        those whose moved place lies inside the solid's box.
        """
        q = self.place(x)
        ok = self.inside(q)
        hit = np.zeros(len(q), dtype=bool)
        v = ndimage.map_coordinates(self.sdf, q[ok].T, order=1, mode="nearest")
        hit[ok] = np.abs(v) < self.h
        return hit, ok

    def __call__(self, x: np.ndarray) -> float:
        """The support of ``x``; 0 where fewer than :data:`MIN_OVERLAP` land inside the box."""
        hit, ok = self.matches(x)
        if ok.mean() < MIN_OVERLAP:
            return 0.0
        return float(hit[ok].mean())

    def coarse(self, t: float, rises: np.ndarray, c: np.ndarray) -> np.ndarray:
        """(D,) supports of the turn ``t`` with each rise (nearest voxel, a voxel more of
        tolerance: the coarse grid lands up to a voxel off the exact motion).
        """
        q = self.place(np.array([t, 0.0, c[0], c[1]]))
        okxz = (
            (q[:, 0] >= self.lo[0])
            & (q[:, 0] <= self.hi[0])
            & (q[:, 2] >= self.lo[2])
            & (q[:, 2] <= self.hi[2])
        )
        y = q[:, 1][:, None] + rises[None, :]
        ok = okxz[:, None] & (y >= self.lo[1]) & (y <= self.hi[1])
        ix = np.clip(np.rint(q[:, 0]).astype(np.int64), 0, self.sdf.shape[0] - 1)
        iz = np.clip(np.rint(q[:, 2]).astype(np.int64), 0, self.sdf.shape[2] - 1)
        iy = np.clip(np.rint(y).astype(np.int64), 0, self.sdf.shape[1] - 1)
        v = self.sdf[ix[:, None], iy, iz[:, None]]
        hit = ok & (np.abs(v) < 2.0 * self.h)
        n_ok = ok.sum(axis=0)
        out = hit.sum(axis=0) / np.maximum(n_ok, 1)
        out[n_ok < MIN_OVERLAP * len(q)] = 0.0
        return out


def find_helices(csdf: CSDF) -> list[Helix]:
    """The helical repetitions of ``csdf`` (see module): spiral stairs' steps.

    Parameters
    ----------
    csdf : CSDF
        The object (up is +y).

    Returns
    -------
    list of Helix
        At most one (an object has one such repeat); empty where nothing repeats helically.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> zones.find_helices(shapes.box((0, 0, 0), (1.0, 0.5, 0.5), voxel_size=0.05))
    []
    """
    for score, found in _motions(csdf, _candidates, _refine, _is_helix):
        if found:
            best = max(s for s, _ in found)
            s, x = min((f for f in found if f[0] >= best - TIED), key=lambda f: abs(f[1][0]))
            return [_helix(csdf, score, s, x)]
    return []


def _motions(
    csdf: CSDF,
    starts: Callable[[_Scorer, np.ndarray], list[np.ndarray]],
    refine: Callable[[_Scorer, np.ndarray], tuple[np.ndarray, float]],
    keep: Callable[[_Scorer, np.ndarray, float], bool],
) -> Iterator[tuple[_Scorer, list[tuple[float, np.ndarray]]]]:
    """Per axis guess (:func:`_axes`), in turn: ``csdf``'s scorer and the supports and motions
    ``(s, x)`` that ``refine`` makes of the coarse motions ``starts(score, c)`` about it and
    ``keep(score, x, s)`` keeps (the search :func:`find_helices` and
    :func:`~partscale.zones.find_rotations` share); nothing where there is no scorer.
    """
    score = _scorer(csdf)
    if score is None:
        return
    for c in _axes(csdf, score):
        found = []
        for x0 in starts(score, c):
            x, s = refine(score, x0)
            if keep(score, x, s):
                found.append((s, x))
        yield score, found


def _scorer(csdf: CSDF) -> _Scorer | None:
    """The scorer of ``csdf``'s surface samples; None where it has no solid or no sample."""
    if not (csdf.sdf < 0).any():
        return None
    score = _Scorer(csdf)
    return score if len(score.pts) > 0 else None


def _axes(csdf: CSDF, score: _Scorer) -> list[np.ndarray]:
    """Axis guesses (voxel indices on x and z): the middle of the surface's bounds across y,
    and the middle of the tallest columns of voxels inside (a stair's newel) where apart.
    """
    sb = csdf.surface_bounds()
    mid = ((sb[0] + sb[1]) / 2 - csdf.origin) / csdf.voxel_size
    out = [mid[[0, 2]]]
    tall = (score.sdf < 0).sum(axis=1)
    cells = np.argwhere(tall >= 0.9 * tall.max()).astype(np.float64)
    col = cells.mean(axis=0)
    if np.linalg.norm(col - out[0]) > 2.0:
        out.append(col)
    return out


def _candidates(score: _Scorer, c: np.ndarray) -> list[np.ndarray]:
    """Coarse motions ``(angle, rise, cx, cz)`` about the axis ``c`` whose support reaches half
    the least and whose margin over their turn alone and their rise alone half the least
    exclusive share; the best :data:`REFINED`, apart from one another by two grid steps.
    """
    radius = float(np.hypot(*(score.pts[:, [0, 2]] - c).T).max())
    step = ARC / max(radius, 1.0)
    reach = np.arange(math.radians(MIN_ANGLE), math.radians(MAX_ANGLE) + 1e-9, step)
    angles = np.concatenate([-reach[::-1], reach])
    span = float(score.hi[1] - score.lo[1])
    rises = COARSE * np.arange(0, int(span / 2 / COARSE) + 1)
    if len(rises) < 2:
        return []
    up = score.coarse(0.0, rises, c)[1:]  # what a rise alone reaches (a bookcase's sides)
    cands = []
    for t in angles:
        s = score.coarse(float(t), rises, c)
        margin = s[1:] - np.maximum(s[0], up)
        for k in np.flatnonzero((s[1:] >= MIN_SUPPORT / 2) & (margin >= MIN_EXCLUSIVE / 2)):
            cands.append((float(s[1 + k]), float(t), float(rises[1 + k])))
    cands.sort(key=lambda x: -x[0])
    kept: list[tuple[float, float]] = []
    for _, t, dy in cands:
        if any(abs(t - a) <= 2 * step and abs(dy - b) <= 2 * COARSE for a, b in kept):
            continue
        kept.append((t, dy))
        if len(kept) == REFINED:
            break
    return [np.array([t, dy, c[0], c[1]]) for t, dy in kept]


def _refine(
    score: _Scorer, x: np.ndarray, free: tuple[int, ...] = (0, 1, 2, 3)
) -> tuple[np.ndarray, float]:
    """The motion ``x = (angle, rise, cx, cz)`` near ``x`` (axis free) that carries the matching
    samples' distances onto their own best (Gauss-Newton on ``sdf(T p) - sdf(p)``, voxels, over
    the samples within a voxel and a half, then one), and its support; only the parameters
    ``free`` move (a pure turn, :mod:`.rotation`, keeps the rise at 0).
    """
    x = x.astype(np.float64).copy()
    cols = list(free)
    sdf = score.sdf
    h = score.h
    for it in range(ITERATIONS):
        q = score.place(x)
        ok = score.inside(q)
        v = ndimage.map_coordinates(sdf, q.T, order=1, mode="nearest") / h
        res = v - score.v0
        use = ok & (np.abs(res) < (1.5 if it < ITERATIONS // 2 else 1.0))
        if use.sum() < 12:
            break
        qu = q[use]
        g = np.stack(
            [
                (
                    ndimage.map_coordinates(sdf, (qu + 0.5 * e).T, order=1, mode="nearest")
                    - ndimage.map_coordinates(sdf, (qu - 0.5 * e).T, order=1, mode="nearest")
                )
                / h
                for e in np.eye(3)
            ],
            axis=1,
        )
        cs, sn = math.cos(x[0]), math.sin(x[0])
        dx, dz = qu[:, 0] - x[2], qu[:, 2] - x[3]
        jac = np.stack(
            [
                -g[:, 0] * dz + g[:, 2] * dx,
                g[:, 1],
                g[:, 0] * (1 - cs) - g[:, 2] * sn,
                g[:, 0] * sn + g[:, 2] * (1 - cs),
            ],
            axis=1,
        )[:, cols]
        a = jac.T @ jac
        a += 1e-6 * np.trace(a) * np.eye(len(cols))
        dxv = -np.linalg.solve(a, jac.T @ res[use])
        dxv[0] = np.clip(dxv[0], -0.05, 0.05)
        dxv[1:] = np.clip(dxv[1:], -2.0, 2.0)
        x[cols] += dxv
        if abs(dxv[0]) < 1e-5 and np.abs(dxv[1:]).max() < 1e-3:
            break
    return x, score(x)


def _is_helix(score: _Scorer, x: np.ndarray, s: float) -> bool:
    """The rules of the module on the refined motion ``x`` of support ``s``."""
    if s < MIN_SUPPORT or x[1] < 1.0 or not MIN_ANGLE <= abs(math.degrees(x[0])) <= MAX_ANGLE:
        return False
    hit, ok = score.matches(x)
    for part in (np.array([x[0], 0.0, x[2], x[3]]), np.array([0.0, x[1], x[2], x[3]])):
        hit &= ~score.matches(part)[0]
    if hit.sum() / max(int(ok.sum()), 1) < MIN_EXCLUSIVE:
        return False
    half = x.copy()
    half[:2] /= 2
    return score(half) <= s - DISCRETE


def _helix(csdf: CSDF, score: _Scorer, s: float, x: np.ndarray) -> Helix:
    """The :class:`Helix` of the motion ``x`` (voxel units), with its count and cut."""
    h = csdf.voxel_size
    center = (float(csdf.origin[0] + x[2] * h), float(csdf.origin[2] + x[3] * h))
    return Helix(
        center,
        float(math.degrees(x[0])),
        float(x[1] * h),
        s,
        _count(score, x),
        _cut(csdf, score, x),
    )


def _count(score: _Scorer, x: np.ndarray) -> int:
    """Treads: the levels of the upward surface samples the motion carries onto the surface
    (one per tread but the top one, whose image is beyond), each holding a quarter of the
    largest's samples at least; plus the top one.
    """
    sdf = score.sdf
    p = score.pts.astype(np.int64)
    j = np.clip(p[:, 1] + 1, 0, sdf.shape[1] - 1)
    i = np.clip(p[:, 1] - 1, 0, sdf.shape[1] - 1)
    gy = sdf[p[:, 0], j, p[:, 2]] - sdf[p[:, 0], i, p[:, 2]]
    hit, _ = score.matches(x)
    ys = p[hit & (gy > 1.8 * score.h), 1]  # up-facing: the distance grows by ~2 voxels up
    if ys.size == 0:
        return 1
    counts = np.bincount(ys)
    levels = np.flatnonzero(counts >= 0.25 * counts.max())
    runs = 1 + int((np.diff(levels) > 1).sum()) if levels.size else 0
    return runs + 1


def _cut(csdf: CSDF, score: _Scorer, x: np.ndarray) -> float:
    """Height of the cut level: among the levels of the middle half of the solid, the one
    whose surface matches that one step down the helix best and changes least from the levels
    :data:`~partscale.zones.screw.CUT_CALM` either side (between treads, not across one),
    nearest the middle.
    """
    sdf = score.sdf
    h = csdf.voxel_size
    lo, hi = int(score.lo[1]), int(score.hi[1])
    mid = (lo + hi) / 2
    levels = np.arange(int(lo + (hi - lo) / 4), int(hi - (hi - lo) / 4) + 1)
    back = np.array([-x[0], -x[1], x[2], x[3]])
    cs, sn = math.cos(back[0]), math.sin(back[0])
    costs = []
    for j in levels:
        layer = sdf[:, int(j), :]
        band = np.argwhere(np.abs(layer) <= 2 * h)
        if band.size == 0:
            costs.append(np.inf)
            continue
        d = band.astype(np.float64) - back[2:]
        q = np.stack(
            [
                back[2] + cs * d[:, 0] - sn * d[:, 1],
                np.full(len(d), float(j) + back[1]),
                back[3] + sn * d[:, 0] + cs * d[:, 1],
            ]
        )
        v = ndimage.map_coordinates(sdf, q, order=1, mode="nearest")
        own = layer[band[:, 0], band[:, 1]]
        match = float(np.mean(np.abs(own - v)) / h)
        near = [sdf[:, int(np.clip(j + k, 0, sdf.shape[1] - 1)), :] for k in (-CUT_CALM, CUT_CALM)]
        change = max(float(np.mean(np.abs(n[band[:, 0], band[:, 1]] - own)) / h) for n in near)
        costs.append(match + change)
    costs_a = np.asarray(costs)
    good = np.flatnonzero(costs_a <= np.nanmin(costs_a) + 0.05)
    best = levels[good[np.argmin(np.abs(levels[good] - mid))]]
    return float(csdf.origin[1] + best * h)
