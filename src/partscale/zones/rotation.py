"""Repetition by a turn about the vertical: arms of a star base, blades, chairs about a table.

A star base repeats by a *rotation*: each arm is the one before turned by an angle about a
vertical axis. :func:`find_rotations` finds such turns on the surface itself, as
:func:`~partscale.zones.find_helices` finds helical motions: surface samples (voxels within half
a voxel of it) turned by a candidate land on the surface again (``|sdf| < 1`` voxel there) for
a share of them, the *support*. Candidates turn by :data:`MIN_ANGLE`..:data:`MAX_ANGLE` degrees
about the vertical through the middle of the surface's bounds (or through the tallest column
inside), coarse (nearest voxel) first, then refined with the axis free (Gauss-Newton on the
turned samples' distances). A candidate is a rotation where

- its support is at least :data:`~partscale.zones.screw.MIN_SUPPORT` among the samples whose
  turned place lies inside the solid's box,
- at least :data:`~partscale.zones.screw.MIN_EXCLUSIVE` of the samples land on the surface
  under it and not under half of it (a round top, a column, a disc match every turn: only the
  elements are the repeat's own), and half of it reaches
  :data:`~partscale.zones.screw.DISCRETE` less support (elements are discrete),
- its elements can be told apart: each one's own surface (below) lies within its wedge, short
  of the rays half-way to the next (a square top over four legs, whose edges run from wedge to
  wedge, is no ring of four),

and the fundamental one (its multiples match as well) is kept.

Its elements are the samples it alone carries onto the surface: they give the levels they lie
between (the span: levels holding a few of them), the radius within which the object is the same under the turn (the hub:
a column, a round top, which stay) and the outer radius; their directions give the first
element's (the phase). A turn within :data:`CLOSE_TOL` degrees of a whole turn over a whole
number ``k`` of elements, with all ``k`` sectors holding one, is a *closed ring* (its angle is
then ``360 / k`` exactly); otherwise an *open arc* of the sectors that hold one, in a row.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage

from ..csdf import CSDF
from ..edit import RotationZone
from .helix import _motions, _Scorer
from .helix import _refine as _refine_motion
from .screw import DISCRETE, MIN_EXCLUSIVE, MIN_SUPPORT, TIED

#: Least and most turn from one element to the next, degrees (a half turn is the symmetry of
#: nearly every piece of furniture, no ring).
MIN_ANGLE = 10.0
MAX_ANGLE = 120.0
#: Coarse search: the turn's step moves the farthest sample this many voxels; the best
#: :data:`REFINED` local maxima are refined.
ARC = 1.0
REFINED = 6
#: A turn within this many degrees of 360 / k is a closed ring of k.
CLOSE_TOL = 1.0
#: A sector holds an element where it holds at least this share of the fullest sector's solid.
OCCUPIED = 0.2
#: A level is the elements' where it holds at least this many of their own samples, and this
#: share of the fullest level's.
LEVEL_SAMPLES = 3
LEVEL_SHARE = 0.02
#: A hub's ring holds at most this share of points near the surface that change under half the
#: turn (a voxel's noise).
SEPARABLE = 0.02
#: Each element's own surface lies within this share of its wedge (half-way to the next one's
#: on either side): a square top over four legs, whose edges run from wedge to wedge, is no
#: ring of four.
WEDGE = 0.95


@dataclass(frozen=True)
class Rotation:
    """A repetition by a turn about the vertical (see module).

    Parameters
    ----------
    center : (float, float)
        The vertical axis' place on x and z (world units).
    angle : float
        Degrees from one element to the next, from x toward z (negative: from z toward x).
    phase : float
        Degrees: the first element's direction from the axis.
    count : int
        Elements.
    closed : bool
        A whole ring (``count * angle`` is 360 degrees); else an open arc.
    support : float
        Share of turned surface samples landing on the surface.
    hub, radius : float
        Radii the elements lie between (world units): within ``hub`` the object is the same
        under the turn (a column, a round top).
    span : (float, float)
        Levels (world y) the elements lie between.
    width : float
        Degrees: how far each element's own surface reaches either side of its direction
        (a ring holds at most ``180 / width`` of them without two overlapping).

    Examples
    --------
    >>> from partscale.zones import Rotation
    >>> star = Rotation((0.0, 0.0), 72.0, 18.0, 5, True, 0.9, 0.04, 0.35, (0.0, 0.08))
    >>> star.zone(1).to_json()["rotation"]["count"]
    5
    """

    center: tuple[float, float]
    angle: float
    phase: float
    count: int
    closed: bool
    support: float
    hub: float
    radius: float
    span: tuple[float, float]
    width: float = 0.0

    def zone(self, n: int) -> RotationZone:
        """The count edit adding ``n`` elements (``-n``: removing them)."""
        return RotationZone(
            self.center,
            self.angle,
            self.phase,
            self.count,
            self.closed,
            self.hub,
            self.radius,
            self.span,
            n,
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what the editor's API and ``suggest --json`` hold)."""
        return {
            "center": list(self.center),
            "angle": self.angle,
            "phase": self.phase,
            "count": self.count,
            "closed": self.closed,
            "support": round(self.support, 4),
            "hub": self.hub,
            "radius": self.radius,
            "span": list(self.span),
            "width": self.width,
        }


def find_rotations(csdf: CSDF) -> list[Rotation]:
    """The rotational repetitions of ``csdf`` about the vertical (see module).

    Parameters
    ----------
    csdf : CSDF
        The object (up is +y: the turns sought are about the vertical, as for
        :func:`~partscale.zones.find_helices`).

    Returns
    -------
    list of Rotation
        At most one (the fundamental turn); empty where nothing repeats by a turn.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> zones.find_rotations(shapes.box((0, 0, 0), (1.0, 0.5, 0.5), voxel_size=0.05))
    []
    """
    for score, found in _motions(csdf, _turns, _refine, _is_rotation):
        if not found:
            continue
        best = max(s for s, _ in found)
        for s, x in sorted((f for f in found if f[0] >= best - TIED), key=lambda f: f[1][0]):
            rot = _rotation(csdf, score, s, x)
            if rot is not None:
                return [rot]
    return []


def _motion(x: np.ndarray) -> np.ndarray:
    """The helix scorer's motion ``(angle, rise, cx, cz)`` of a turn ``(angle, cx, cz)``."""
    return np.array([x[0], 0.0, x[1], x[2]])


def _candidates(score: _Scorer, c: np.ndarray) -> list[float]:
    """Coarse turns (radians) about the axis ``c`` whose support reaches half the least, and
    exceeds the support of their half by half the discrete margin; the best :data:`REFINED`
    local maxima.
    """
    radius = float(np.hypot(*(score.pts[:, [0, 2]] - c).T).max())
    step = ARC / max(radius, 1.0)
    angles = np.arange(math.radians(MIN_ANGLE), math.radians(MAX_ANGLE) + 1e-9, step)
    zero = np.zeros(1)
    s = np.array([score.coarse(float(t), zero, c)[0] for t in angles])
    half = np.array([score.coarse(float(t) / 2, zero, c)[0] for t in angles])
    ok = (s >= MIN_SUPPORT / 2) & (s - half >= DISCRETE / 2)
    peak = ok & (s >= np.maximum(np.roll(s, 1), np.roll(s, -1)))
    idx = np.flatnonzero(peak)
    idx = idx[np.argsort(-s[idx])][:REFINED]
    return [float(angles[i]) for i in idx]


def _turns(score: _Scorer, c: np.ndarray) -> list[np.ndarray]:
    """:func:`_candidates` about the axis ``c`` as turns ``(angle, cx, cz)``."""
    return [np.array([t, c[0], c[1]]) for t in _candidates(score, c)]


def _refine(score: _Scorer, x: np.ndarray) -> tuple[np.ndarray, float]:
    """The turn near ``x = (angle, cx, cz)`` (axis free), and its support: the helix's
    refinement (:func:`.helix._refine`) with the rise held at 0.
    """
    m, s = _refine_motion(score, _motion(x), free=(0, 2, 3))
    return m[[0, 2, 3]], s


def _own(score: _Scorer, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(S,) bool each: the samples the turn ``x`` carries onto the surface and its half does
    not (the elements' own surface), and those whose turned place lies inside the box.
    """
    hit, ok = score.matches(_motion(x))
    half = x.copy()
    half[0] /= 2
    hit &= ~score.matches(_motion(half))[0]
    return hit, ok


def _is_rotation(score: _Scorer, x: np.ndarray, s: float) -> bool:
    """The support, exclusive and discrete rules of the module on the refined turn ``x``."""
    if s < MIN_SUPPORT or not MIN_ANGLE <= abs(math.degrees(x[0])) <= MAX_ANGLE:
        return False
    hit, ok = _own(score, x)
    if hit.sum() / max(int(ok.sum()), 1) < MIN_EXCLUSIVE:
        return False
    half = x.copy()
    half[0] /= 2
    return score(_motion(half)) <= s - DISCRETE


def _rotation(csdf: CSDF, score: _Scorer, s: float, x: np.ndarray) -> Rotation | None:
    """The :class:`Rotation` of the turn ``x`` (voxel units): its elements' span, hub, radius,
    phase, count and whether they close a ring; None where the elements cannot be told apart.
    """
    h = csdf.voxel_size
    own, _ = _own(score, x)
    pts = score.pts[own]
    c = x[1:3]
    angle = math.degrees(x[0])
    k = round(360.0 / angle)
    ring = abs(angle - 360.0 / k) <= CLOSE_TOL  # a closed ring if every sector holds one
    d = pts[:, [0, 2]] - c
    r = np.hypot(d[:, 0], d[:, 1])
    # the levels holding the elements' own surface (a lone sample is noise at the tolerance)
    per = np.bincount(np.rint(pts[:, 1]).astype(np.int64))
    levels = np.flatnonzero(per >= max(LEVEL_SAMPLES, LEVEL_SHARE * per.max()))
    j0, j1 = int(levels[0]) - 1, int(levels[-1]) + 1
    j0, j1 = max(j0, 0), min(j1, score.sdf.shape[1] - 1)
    hub = _hub(score, c, x[0], j0, j1, float(r.min()))
    sector = math.radians(360.0 / k if ring else angle)
    theta = np.arctan2(d[:, 1], d[:, 0])
    phase = float(np.angle(np.exp(1j * theta * (2 * math.pi / sector)).mean()))
    phase *= sector / (2 * math.pi)
    solid = _solid_polar(score.sdf, c, j0, j1, hub)
    if solid is None:
        return None
    rr, tt = solid
    sectors = k if ring else math.ceil(360.0 / angle)
    m = np.mod(np.rint((tt - phase) / sector), sectors).astype(np.int64)
    fill = np.bincount(m, minlength=sectors)
    held = fill >= OCCUPIED * fill.max()
    closed = bool(held.all()) and ring
    if closed:
        angle = 360.0 / k
    if closed:
        first, count = 0, sectors
    else:
        run = _run(held)
        if run is None:
            return None
        first, count = run
        if count < 2:
            return None
    phase += first * sector
    # each element's own surface lies within its wedge, apart from the next one's (but where
    # it meets the hub: a column's face between two arms' roots is theirs too)
    alpha = np.angle(np.exp(1j * (theta - phase) * (2 * math.pi / sector))) * sector / (2 * math.pi)
    width = float(np.abs(alpha[r >= r.min() + 2.0]).max(initial=0.0))
    if width > WEDGE * sector / 2:
        return None
    return Rotation(
        (float(csdf.origin[0] + c[0] * h), float(csdf.origin[2] + c[1] * h)),
        angle,
        float(np.mod(math.degrees(phase) + 180.0, 360.0) - 180.0),
        int(count),
        closed,
        s,
        float(hub * h),
        float((rr.max() + 1.0) * h),
        (float(csdf.origin[1] + j0 * h), float(csdf.origin[1] + j1 * h)),
        math.degrees(width),
    )


def _ring_points(c: np.ndarray, radius: float, j0: int, j1: int, step: float = 1.0):
    """(N, 3) voxel-index points on the circle of ``radius`` about ``c`` (x, z) at every level
    ``j0..j1``, a point every ``step`` voxels of arc.
    """
    n = max(8, math.ceil(2 * math.pi * radius / step))
    t = 2 * math.pi * np.arange(n) / n
    js = np.arange(j0, j1 + 1, dtype=np.float64)
    xz = c + radius * np.stack([np.cos(t), np.sin(t)], axis=1)
    p = np.empty((len(js), n, 3))
    p[:, :, 0] = xz[:, 0]
    p[:, :, 1] = js[:, None]
    p[:, :, 2] = xz[:, 1]
    return p.reshape(-1, 3)


def _turned(p: np.ndarray, c: np.ndarray, t: float) -> np.ndarray:
    """Points ``p`` (N, 3) turned by ``t`` radians about the vertical through ``c`` (x, z)."""
    cs, sn = math.cos(t), math.sin(t)
    d = p[:, [0, 2]] - c
    q = p.copy()
    q[:, 0] = c[0] + cs * d[:, 0] - sn * d[:, 1]
    q[:, 2] = c[1] + sn * d[:, 0] + cs * d[:, 1]
    return q


def _hub(score: _Scorer, c: np.ndarray, t: float, j0: int, j1: int, r_own: float) -> float:
    """Radius (voxels) within which the object is the same under the turn ``t`` on the levels
    ``j0..j1``: the last ring, out from the axis to a voxel inside the elements' nearest
    sample, whose points near the surface change by at most half a voxel under it.
    """
    sdf = score.sdf
    h = score.h
    hub = 0.0
    for radius in np.arange(1.0, max(r_own - 1.0, 1.0), 1.0):
        p = _ring_points(c, float(radius), j0, j1)
        v = ndimage.map_coordinates(sdf, p.T, order=1, mode="nearest")
        w = ndimage.map_coordinates(sdf, _turned(p, c, t / 2).T, order=1, mode="nearest")
        near = np.minimum(np.abs(v), np.abs(w)) < 2 * h
        if near.any() and (np.abs(v - w)[near] > 0.5 * h).mean() > SEPARABLE:
            break
        hub = float(radius)
    return hub


def _solid_polar(sdf: np.ndarray, c: np.ndarray, j0: int, j1: int, hub: float):
    """(radius, direction radians) of the solid voxels beyond ``hub`` on levels ``j0..j1``;
    None where there are none.
    """
    ijk = np.argwhere(sdf[:, j0 : j1 + 1, :] < 0)
    d = ijk[:, [0, 2]] - c
    r = np.hypot(d[:, 0], d[:, 1])
    beyond = r > hub
    if not beyond.any():
        return None
    return r[beyond], np.arctan2(d[beyond, 1], d[beyond, 0])


def _run(held: np.ndarray) -> tuple[int, int] | None:
    """The one run of held sectors (circular): (first, length); None where there are several
    or none.
    """
    n = len(held)
    if not held.any():
        return None
    starts = [i for i in range(n) if held[i] and not held[i - 1]]
    if len(starts) != 1:
        return None
    first = starts[0]
    length = 0
    while length < n and held[(first + length) % n]:
        length += 1
    return first, length
