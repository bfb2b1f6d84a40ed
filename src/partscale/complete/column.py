"""A swivel chair's column, the gas lift between a turning base's hub and the seat, and a
pedestal between a table's plinth and its top.

Sensors rarely read it (a thin black cylinder: the TUM frame's depth is 0 over its pixels), so
the completion would leave the seat floating above its base. Where a rotation of the base was
found (:func:`partscale.complete.symmetry.rotation_axis`), the surface has a hub on its axis
(points within ``HUB_REACH`` of it in the base) and a seat above it on the same axis, and the
seat is carried by nothing else (a stretch of height between them holds no surface anywhere:
the legs of a four-legged chair span every height), a cylinder is guessed along the axis from
the hub's top to the seat's underside. Its radius is the largest in [``MIN_RADIUS``,
``MAX_RADIUS``] that the free space seen *surely* (:func:`sure_carver`: the ray and its
neighbours all reached a reading beyond) does not contradict; where it contradicts even the
thinnest (``MAX_CONTRADICTED``) there is no column; the sure free space alone carves it. Free space inferred from missing readings
(the hole filling of a raw frame, the silhouette of a cropped scan) is no evidence here: the
column's own pixels are such holes.

Where no surface of the base comes within ``HUB_REACH`` of the axis (the hub unseen, and the
legs' turned copies starting farther out), the hub is guessed too: a disc about the axis
reaching a voxel past the legs' inner ends, from their lowest point to the column's foot,
when those ends lie within the turn's own hub test (``symmetry.HUB_SHARE`` of the base's
radius) and the disc is no taller than its radius.

Without a turning base, a top over a plinth with nothing seen between them (a pedestal table
seen from above its top, which hides the pedestal) gets the same column on the crossing of two
mirror planes (:func:`find_pedestal`): Kenney's round table from three views 30 degrees above
was its top and its plinth apart, and is one piece with it.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..csdf import BAND_VOXELS
from .carve import Carver
from .scan import Frame
from .symmetry import HUB_SHARE

MIN_RADIUS = 0.02
"""Metres: the thinnest column guessed (office chairs' gas lifts are 4-6 cm across)."""
MAX_RADIUS = 0.03
"""Metres: the thickest column guessed."""
HUB_REACH = 0.06
"""Metres from the axis within which surface points make the hub (below) and the seat (above)."""
MIN_POINTS = 5
"""Surface points within ``HUB_REACH`` of the axis that make a hub, and a seat."""
MIN_GAP_VOXELS = 3
"""Voxels of height without surface near the axis between hub and seat, and of height without
surface anywhere (``EMPTY_SHARE``) between them, for a column to be added."""
EMPTY_SHARE = 0.001
"""Share of the surface points a voxel's height may hold and count as empty (flying pixels)."""
MAX_CONTRADICTED = 0.05
"""Share of the thinnest column's surface samples that may lie in sure free space."""
SURE_RAYS = 3
"""Pixels across the block of rays that must all reach beyond a point for it to be surely free."""
SURE_MARGIN_VOXELS = 1.0
"""Voxels a point must lie in front of the readings to be surely free."""
RADIUS_STEP = 0.0025
"""Metres between the radii tried, from ``MAX_RADIUS`` down."""
PEDESTAL_CROSS_DEG = 30.0
"""Degrees at least between two mirror planes whose crossing is a pedestal's axis
(:func:`find_pedestal`)."""


@dataclass(frozen=True)
class Column:
    """A vertical cylinder in the upright frame: axis (x, z), heights ``bottom`` to ``top``,
    ``radius``; ``contradicted``: the share of its surface samples surely free at that radius
    (0 unless even ``MIN_RADIUS`` is, by at most ``MAX_CONTRADICTED``); ``hub_radius``: the
    guessed hub's, a disc from ``hub_bottom`` to ``bottom`` (0: the hub was seen or copied).
    """

    x: float
    z: float
    bottom: float
    top: float
    radius: float
    contradicted: float
    hub_radius: float = 0.0
    hub_bottom: float = 0.0
    of: str = "turning base"

    def as_dict(self) -> dict:
        """The column as JSON-ready numbers (``meta['completion']['column']``)."""
        return {
            "axis_x": round(self.x, 6),
            "axis_z": round(self.z, 6),
            "bottom": round(self.bottom, 6),
            "top": round(self.top, 6),
            "radius": round(self.radius, 6),
            "contradicted": round(self.contradicted, 4),
            "hub_radius": round(self.hub_radius, 6),
            "hub_bottom": round(self.hub_bottom, 6),
            "of": self.of,
        }


def sure_carver(frames: list[Frame], margin: float) -> Carver:
    """The :class:`~partscale.complete.carve.Carver` of the space ``frames`` surely saw through
    by ``margin``: a point's pixel and every pixel of the ``SURE_RAYS`` square around it read a
    depth beyond it. Pixels without a reading, and a cropped scan's background, say nothing.
    """
    return Carver(frames, margin, sure_rays=SURE_RAYS)


def find_column(points: np.ndarray, rotation, free_up, h: float) -> Column | None:
    """The column of a turning base under a seat, or None.

    points : (N, 3) upright surface points (observed and copies); rotation : the base's
    :class:`~partscale.complete.symmetry.Symmetry` (kind "rotation") or None; free_up : upright
    points (M, 3) -> (M,) bool, the sure free space (a :func:`sure_carver`'s ``free``); h : the
    grid's voxel.
    """
    if rotation is None:
        return None
    x, z = float(rotation.params["axis_x"]), float(rotation.params["axis_z"])
    base_top = float(rotation.bands[0][1])
    P = np.asarray(points, np.float64)
    off_axis = np.hypot(P[:, 0] - x, P[:, 2] - z)
    low = P[:, 1] < base_top
    reach, hub_radius = HUB_REACH, 0.0
    if (low & (off_axis <= HUB_REACH)).sum() < MIN_POINTS:
        # no hub seen or copied: one is guessed out to the legs' inner ends, if they start
        # where the turn's hub test put them (a quarter of the base's radius)
        rl = np.sort(off_axis[low])
        if len(rl) < MIN_POINTS:
            return None
        inner = float(rl[MIN_POINTS - 1])
        if inner > HUB_SHARE * float(np.percentile(rl, 98)):
            return None
        reach = hub_radius = inner + h
    near = off_axis <= reach
    y = np.sort(P[near, 1])
    if len(y) < 2 * MIN_POINTS:
        return None
    # the widest stretch of height without surface near the axis that starts in the base: the
    # hub below it, the seat above it
    gaps = np.diff(y)
    starts_low = y[:-1] < base_top
    if not starts_low.any():
        return None
    i = int(np.argmax(np.where(starts_low, gaps, -np.inf)))
    bottom, top = float(y[i]), float(y[i + 1])
    if top - bottom < MIN_GAP_VOXELS * h or i + 1 < MIN_POINTS or len(y) - i - 1 < MIN_POINTS:
        return None
    # a seat carried by its column alone: somewhere between hub and seat a stretch of height
    # holds no surface anywhere (the legs of a four-legged chair span every height)
    counts = np.histogram(P[:, 1], bins=np.arange(bottom, top + h, h))[0]
    starts, ends = _empty_runs(counts, len(P))
    if not len(starts) or (ends - starts).max() < MIN_GAP_VOXELS:
        return None
    radius, share = _radius(x, z, bottom, top, free_up, h)
    if share > MAX_CONTRADICTED:
        return None  # the cameras saw through where even the thinnest column would stand
    hub_bottom = float(P[near & low, 1].min()) if hub_radius else 0.0
    if hub_radius and bottom - hub_bottom > hub_radius:
        # a hub is a squat disc where the legs meet: surface that high so near the axis is
        # something else (a column seen off the axis), not the legs' inner ends
        return None
    return Column(x, z, bottom, top, radius, share, hub_radius, hub_bottom)


def _radius(x: float, z: float, bottom: float, top: float, free_up, h: float):
    """The largest radius in [``MIN_RADIUS``, ``MAX_RADIUS``] of a column on (``x``, ``z``) from
    ``bottom`` to ``top`` whose surface the sure free space ``free_up`` leaves alone (its ends
    excluded: the hub's and the seat's own edges), and the share of that surface surely free
    (above 0 only at ``MIN_RADIUS``).
    """
    a = np.linspace(0.0, 2 * np.pi, 48, endpoint=False)
    heights = np.arange(bottom + h, top - h + 1e-9, h / 2)
    if len(heights) == 0:
        heights = np.array([(bottom + top) / 2])
    share = 1.0
    radius = MIN_RADIUS
    for r in np.arange(MAX_RADIUS, MIN_RADIUS - 1e-9, -RADIUS_STEP):
        ring = np.stack(
            [
                np.broadcast_to(x + r * np.cos(a), (len(heights), len(a))),
                np.broadcast_to(heights[:, None], (len(heights), len(a))),
                np.broadcast_to(z + r * np.sin(a), (len(heights), len(a))),
            ],
            axis=-1,
        ).reshape(-1, 3)
        share = float(free_up(ring).mean())
        radius = float(r)
        if share == 0.0:
            break
    return radius, share


def find_pedestal(points: np.ndarray, mirrors, free_up, h: float) -> Column | None:
    """The column of a pedestal under a top, or None.

    Where two of the vertical mirror planes ``mirrors`` (upright
    :class:`~partscale.complete.symmetry.Symmetry`, kind "mirror") cross at
    ``PEDESTAL_CROSS_DEG`` or more (a round or square table, a bar stool on a disc) and a
    stretch of height at least ``MIN_GAP_VOXELS`` tall holds no surface anywhere (the top is
    carried by nothing seen: the legs of a four-legged table span every height), a column
    stands on their crossing from the highest surface below that stretch to the lowest above
    it, when what lies below and what lies above both surround the crossing (points within
    each quarter turn about it), as thick as the sure free space ``free_up`` allows
    (:func:`find_column`'s radii); None where it contradicts even the thinnest.

    points : (N, 3) upright surface points (observed and copies); h : the grid's voxel.
    """
    axis = _crossing(mirrors)
    if axis is None:
        return None
    x, z = axis
    P = np.asarray(points, np.float64)
    gap = _empty_stretch(P[:, 1], h)
    if gap is None:
        return None
    bottom, top = gap
    for part in (P[P[:, 1] <= bottom], P[P[:, 1] >= top]):
        quarter = (np.arctan2(part[:, 2] - z, part[:, 0] - x) // (np.pi / 2)).astype(np.int64)
        if len(part) < MIN_POINTS or len(np.unique(quarter)) < 4:
            return None
    radius, share = _radius(x, z, bottom, top, free_up, h)
    if share > MAX_CONTRADICTED:
        return None
    return Column(x, z, bottom, top, radius, share, of="pedestal")


def _crossing(mirrors) -> tuple[float, float] | None:
    """(x, z) where the first two vertical mirror planes at ``PEDESTAL_CROSS_DEG`` or more to
    each other cross (each ``params`` ``theta``, ``offset``: the plane
    ``x cos(theta) + z sin(theta) = offset``); None where no two do.
    """
    planes = [(m.params["theta"], m.params["offset"]) for m in mirrors if m.kind == "mirror"]
    for (t1, d1), (t2, d2) in itertools.combinations(planes, 2):
        if abs(np.sin(t1 - t2)) >= np.sin(np.radians(PEDESTAL_CROSS_DEG)):
            A = np.array([[np.cos(t1), np.sin(t1)], [np.cos(t2), np.sin(t2)]])
            x, z = np.linalg.solve(A, [d1, d2])
            return float(x), float(z)
    return None


def _empty_stretch(y: np.ndarray, h: float) -> tuple[float, float] | None:
    """(bottom, top): the heights of the surface below and above the tallest stretch of voxel
    heights holding at most ``EMPTY_SHARE`` of heights ``y`` (N,) each, at least
    ``MIN_GAP_VOXELS`` of them, with surface below and above it; None where there is none.

    >>> import numpy as np
    >>> y = np.concatenate([np.zeros(50), np.full(50, 0.5)])
    >>> _empty_stretch(y, 0.1)
    (0.0, 0.5)
    >>> # two flying pixels high above the top: a stretch with no surface above it is no gap
    >>> print(_empty_stretch(np.concatenate([np.linspace(0.0, 0.3, 2000), [0.62, 0.77]]), 0.05))
    None
    """
    if len(y) < 2:
        return None
    # bins of h from the lowest height, the highest inside the last (an arange to the highest
    # plus h may end a rounding short of it and leave it out)
    lo_y = float(y.min())
    edges = lo_y + h * np.arange(int(np.floor((float(y.max()) - lo_y) / h)) + 2)
    counts = np.histogram(y, bins=edges)[0]
    starts, ends = _empty_runs(counts, len(y))
    # between surface: a run from the lowest bin or to the highest holds the extremes' few points
    inside = (starts > 0) & (ends < len(counts))
    starts, ends = starts[inside], ends[inside]
    if not len(starts):
        return None
    k = int(np.argmax(ends - starts))
    if ends[k] - starts[k] < MIN_GAP_VOXELS:
        return None
    lo, hi = edges[starts[k]], edges[ends[k]]
    return float(y[y <= lo].max()), float(y[y >= hi].min())


def _empty_runs(counts: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The runs of bins of ``counts`` (B,) holding at most ``EMPTY_SHARE`` of ``n`` points each
    (flying pixels): their first bins (R,) and the bins just past them (R,).

    >>> import numpy as np
    >>> _empty_runs(np.array([9, 0, 0, 9, 0, 9]), 100)
    (array([1, 4]), array([3, 5]))
    """
    empty = np.concatenate([[False], counts <= EMPTY_SHARE * n, [False]])
    change = np.flatnonzero(np.diff(empty.astype(np.int8)))
    return change[::2], change[1::2]


def add_column(
    sdf: np.ndarray,
    prov: np.ndarray,
    column: Column,
    grid_to_upright: np.ndarray,
    origin: np.ndarray,
    h: float,
    free_up,
    guessed: int,
) -> tuple[np.ndarray, np.ndarray, int]:
    """The SDF (X, Y, Z) float32 (world units, negative inside) and provenance (X, Y, Z) uint8
    with ``column`` (and its guessed hub) united in (reaching a voxel into the hub and the
    seat), except where ``free_up`` (upright points -> bool) is true; its new surface marked
    ``guessed``. Returns them and the number of voxels the column made solid.
    """
    A, b = grid_to_upright[:3, :3], grid_to_upright[:3, 3]
    # the grid's voxels whose centres lie in the column's box, grown by the band (and a voxel):
    # every voxel whose distance the column can change within the band is rewritten
    wide = max(column.radius, column.hub_radius)
    foot = min(column.bottom, column.hub_bottom) if column.hub_radius else column.bottom
    lo = np.array([column.x - wide, foot - h, column.z - wide])
    hi = np.array([column.x + wide, column.top + h, column.z + wide])
    corners = np.array(list(itertools.product(*zip(lo, hi, strict=True))))
    g = (corners - b) @ A  # upright -> grid (A is a rotation)
    grow = BAND_VOXELS + 1
    i0 = np.maximum(np.floor((g.min(axis=0) - origin) / h).astype(np.int64) - grow, 0)
    i1 = np.minimum(np.ceil((g.max(axis=0) - origin) / h).astype(np.int64) + grow + 1, sdf.shape)
    if (i1 <= i0).any():
        return sdf, prov, 0
    sl = tuple(slice(int(s), int(e)) for s, e in zip(i0, i1, strict=True))
    ijk = np.indices(tuple(i1 - i0)).reshape(3, -1).T + i0
    up = (origin + ijk * h) @ A.T + b
    r = np.hypot(up[:, 0] - column.x, up[:, 2] - column.z)
    y = up[:, 1]
    # each reaches a voxel beyond its ends: the column into the hub and the seat, the guessed
    # hub into the legs below and the column above
    d = _cylinder(r, y, column.radius, column.bottom - h, column.top + h)
    if column.hub_radius:
        d = np.minimum(
            d, _cylinder(r, y, column.hub_radius, column.hub_bottom - h, column.bottom + h)
        )
    d = d.reshape(tuple(i1 - i0)).astype(np.float32)
    inside = d < 0
    free = np.zeros(d.shape, bool)
    free[inside] = free_up(up[inside.ravel()])
    old = sdf[sl]
    take = (d < old) & ~free
    # a surely free voxel next to the column keeps the column's surface outside it
    new = np.where(take, d, old)
    sdf = sdf.copy()
    prov = prov.copy()
    sdf[sl] = new
    p = prov[sl]
    p[take & (np.abs(d) <= h)] = guessed
    # what the column buried is no longer surface
    p[take & (d < -h)] = 0
    prov[sl] = p
    return sdf, prov, int((take & (d < 0) & (old >= 0)).sum())


def _cylinder(r: np.ndarray, y: np.ndarray, radius: float, lo: float, hi: float) -> np.ndarray:
    """(N,) signed distance bound (negative inside) of the vertical cylinder of ``radius``
    from height ``lo`` to ``hi``, at points ``r`` (N,) off its axis and at heights ``y`` (N,).
    """
    return np.maximum(r - radius, np.maximum(lo - y, y - hi))
