"""Zones that are not slabs across an axis: radial, oblique planes, steps and turned elements.

All are *warps*: a map from every output point to the source point it shows, applied to the
CSDF by resampling (sdf and colour trilinear, parts nearest), then re-evaluated wherever the map
is not a shift by whole voxels, so that every stored distance near the surface is again the
distance to the edited surface (:func:`partscale.edit.reevaluate`).

Radial zone (:class:`RadialZone`), about a line parallel to ``axis`` through ``center``: the
annulus ``r0 <= r <= r1`` becomes ``r0 <= r <= to``; inside ``r0`` nothing moves, outside ``r1``
everything moves outward by ``to - r1`` along its own radius. With ``span`` only the levels
between its two positions along the axis move (a lamp's base grows, its shade above does not;
what crosses the span's ends must lie inside ``r0``). ``r`` is the *gauge* radius of a
regular polygon of ``sides`` sides (its faces at ``phase`` degrees and every ``360 / sides``):
the largest of the point's projections on the face normals over ``cos(180 / sides)``, so the
circles of equal ``r`` are the polygon's own outline scaled and a polygonal top keeps straight
sides; ``sides = 0`` is the plain (round) radius. A round table's top grows, its column and
foot keep their size.

Oblique zone (:class:`ObliqueZone`): the slab between the planes ``p . n = s0`` and
``p . n = s1`` (``n`` any unit vector) becomes ``s0 .. to``; what lies beyond ``s1`` moves by
``(to - s1) n``. The grid grows to hold the moved content (its voxel size never changes).

Rotation zone (:class:`RotationZone`): elements repeated by a turn about the vertical (a star
base's arms, chairs about a round table) are added or removed whole: beyond the hub radius and
on the levels the elements span, every column shows the source turned about the axis
(:func:`rotation_source`): a closed ring's elements spaced evenly again, each an old one turned
rigidly; an open arc continued by its angle, or cut short.

Growing radial and oblique zones re-evaluate only the voxels whose nearest surface point could
have moved: a voxel whose field is flat along every direction the map moves content along
keeps its resampled distance (the planar edits' rule; the inverse of a growing map brings
nothing closer).

Conventions: world units, ``(i, j, k) = (x, y, z)``, voxel centres at ``origin + index *
voxel_size``, sdf negative inside, sRGB colours.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from .._memory import check_memory
from ..csdf import BAND_VOXELS, CSDF
from ..errors import InputError
from ._warp_kernels import gather_columns, opposite_distance, reevaluation_mask, resample_affine
from .recipe import AXES, HelixZone, ObliqueZone, RadialZone, RotationZone, ScrewZone
from .reevaluate import reevaluate_arrays
from .resolved import BYTES_PER_VOXEL

#: Voxels beyond the band resampled trilinearly (the rest take their nearest source value: they
#: only keep the sign far from the surface).
RESAMPLE_MARGIN = 2.0

#: A slope of the field at most this along every direction a growing map moves content along
#: counts as flat there: the voxel's nearest surface point lies square to them, and its
#: resampled distance is kept (the planar edits' rule, :mod:`partscale.edit.reevaluate`).
LATERAL = 0.05


def gauge(d: np.ndarray, sides: int, phase: float) -> np.ndarray:
    """The gauge radius of 2D offsets: Euclidean, or that of a regular polygon.

    Parameters
    ----------
    d : (..., 2) float
        Offsets from the axis, on the two other axes in order.
    sides : int
        0 for round; else the regular ``sides``-gon whose face normals lie at ``phase`` degrees and
        every ``360 / sides`` (its circumradius is 1 on its outline).
    phase : float
        Degrees.

    Returns
    -------
    (...,) float64
        The gauge radius of each offset.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.edit import gauge
    >>> gauge(np.array([[1.0, 0.0], [0.0, 1.0]]), 0, 0.0)
    array([1., 1.])
    >>> gauge(np.array([[1.0, 0.0], [0.6, 0.6]]), 4, 0.0).round(3)  # a square's corner is farther
    array([1.414, 0.849])
    """
    if sides == 0:
        return np.hypot(d[..., 0], d[..., 1])
    a = np.deg2rad(phase) + 2 * np.pi * np.arange(sides) / sides
    normals = np.stack([np.cos(a), np.sin(a)], axis=1)  # (K, 2)
    return (d @ normals.T).max(axis=-1) / math.cos(math.pi / sides)


def _radial_source(r: np.ndarray, zone: RadialZone) -> np.ndarray:
    """Source gauge radius of output radius ``r`` (the radial map, see module)."""
    r0, r1, to = zone.r0, zone.r1, zone.to
    inside = r0 + (r - r0) * (r1 - r0) / (to - r0)
    return np.where(r <= r0, r, np.where(r <= to, inside, r - (to - r1)))


def warp_source(
    zone: RadialZone | ObliqueZone | ScrewZone | HelixZone | RotationZone,
    points: np.ndarray,
    voxel_size: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The map of a warp zone: each output point's source point, and how much of it shows.

    What :func:`apply_warp` resamples, on any points: the editor's shader (``web/src/warp.ts``)
    implements the same map and is tested against this function.

    Parameters
    ----------
    zone : RadialZone, ObliqueZone, ScrewZone, HelixZone or RotationZone
        The zone (its normal need not be unit; a step is snapped to whole voxels as
        :func:`apply_screw` snaps it).
    points : (N, 3) float
        Output points, world units.
    voxel_size : float
        The grid's voxel size (a step's snapping and the width of the blend at a cut).

    Returns
    -------
    src : (N, 3) float64
        The source point each output point shows beyond the cut (radial, oblique, rotation:
        everywhere; a rotation's is the point's own place within the hub and off the span).
    weight : (N,) float64
        0..1: the share of ``src`` in the output, the rest being the point's own place (radial,
        oblique and rotation: 1; steps: 0 before the cut, 1 beyond it, linear over
        :data:`CUT_BLEND` voxels either side of it).

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.edit import ObliqueZone, warp_source
    >>> src, w = warp_source(ObliqueZone((1.0, 0.0, 0.0), 0.3, 0.6, 0.8), np.array([[1.0, 0, 0]]), 0.05)
    >>> src.round(3).tolist(), w.tolist()
    ([[0.8, 0.0, 0.0]], [1.0])
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    h = float(voxel_size)
    one = np.ones(len(p))
    if isinstance(zone, RadialZone):
        ax = AXES.index(zone.axis)
        others = [a for a in range(3) if a != ax]
        c = np.array(zone.center, dtype=np.float64)
        d = p[:, others] - c
        r = gauge(d, zone.sides, zone.phase)
        k = np.where(r > 0, _radial_source(r, zone) / np.maximum(r, 1e-300), 1.0)
        if zone.span is not None:  # only the levels the zone spans move
            k = np.where((p[:, ax] >= zone.span[0]) & (p[:, ax] <= zone.span[1]), k, 1.0)
        src = p.copy()
        src[:, others] = c + d * k[:, None]
        return src, one
    if isinstance(zone, ObliqueZone):
        n = np.asarray(zone.normal, dtype=np.float64)
        n = n / max(float(np.linalg.norm(n)), 1e-300)
        s0, s1, to = zone.s0, zone.s1, zone.to
        s = p @ n
        back = np.where(
            s <= s0, 0.0, np.where(s <= to, (s - s0) * (1 - (s1 - s0) / (to - s0)), to - s1)
        )
        return p - back[:, None] * n, one
    if isinstance(zone, ScrewZone):
        a = AXES.index(zone.axis)
        unit = np.rint(np.asarray(zone.step) / h).astype(np.int64)
        direction = 1.0 if unit[a] > 0 else -1.0
        beyond = (p[:, a] - zone.cut) * direction / h
        return p - _screw_shift(zone, h) * h, np.clip(beyond / (2 * CUT_BLEND) + 0.5, 0.0, 1.0)
    if isinstance(zone, RotationZone):
        return _rotation_points(zone, p), one
    c = np.array([zone.center[0], zone.center[1]], dtype=np.float64)
    src = p.copy()
    src[:, [0, 2]] = _turn(p[:, [0, 2]] - c, -zone.copies * zone.angle) + c
    src[:, 1] -= zone.copies * zone.rise
    return src, np.clip((p[:, 1] - zone.cut) / h / (2 * CUT_BLEND) + 0.5, 0.0, 1.0)


def check_radial(csdf: CSDF, zone: RadialZone) -> None:
    """Refuse (:class:`InputError`, one line) a radial zone that cannot apply to ``csdf``."""
    if zone.axis not in AXES:
        raise InputError(f"radial axis: expected one of x, y, z, got {zone.axis!r}")
    vals = (zone.r0, zone.r1, zone.to, *zone.center, zone.phase)
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"radial zone: expected finite numbers, got {zone.to_json()}")
    if not 0 <= zone.r0 < zone.r1:
        raise InputError(
            f"radial zone: expected radii 0 <= R0 < R1, got {zone.r0:.4g} {zone.r1:.4g}"
        )
    if zone.to <= zone.r0:
        raise InputError(
            f"radial to: expected a radius beyond R0 ({zone.r0:.4g}), got {zone.to:.4g}"
        )
    if zone.sides != 0 and not 3 <= zone.sides <= 64:
        raise InputError(f"radial sides: expected 0 (round) or 3..64, got {zone.sides}")
    if zone.span is not None and not (
        all(math.isfinite(v) for v in zone.span) and zone.span[0] < zone.span[1]
    ):
        raise InputError(f"radial span: expected two finite levels LO < HI, got {list(zone.span)}")
    rmax = radial_extent(csdf, zone)
    if zone.r0 >= rmax:
        raise InputError(
            f"radial zone: expected R0 inside the object (its outline reaches {rmax:.4g} from "
            f"the centre), got {zone.r0:.4g}"
        )


def radial_extent(csdf: CSDF, zone: RadialZone) -> float:
    """The largest gauge radius of the solid about ``zone``'s axis (world units).

    Parameters
    ----------
    csdf : CSDF
        The object.
    zone : RadialZone
        Its axis, centre, sides and phase are used (not its radii).

    Returns
    -------
    float
        What ``100%`` of a radial zone's radii refers to.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.edit import RadialZone, radial_extent
    >>> disc = shapes.box((-0.5, 0, -0.5), (0.5, 0.05, 0.5), voxel_size=0.05)
    >>> 0.5 < radial_extent(disc, RadialZone("y", (0.0, 0.0), 0.1, 0.4, 0.5)) < 0.75
    True
    """
    ax = AXES.index(zone.axis)
    others = [a for a in range(3) if a != ax]
    inside = np.asarray(csdf.sdf < 0)
    foot = inside.any(axis=ax)  # (U, V) in the order of the two other axes
    iu, iv = np.nonzero(foot)
    if iu.size == 0:
        raise InputError("radial zone: expected a solid, got an empty grid")
    h = csdf.voxel_size
    d = np.stack(
        [
            csdf.origin[others[0]] + iu * h - zone.center[0],
            csdf.origin[others[1]] + iv * h - zone.center[1],
        ],
        axis=1,
    )
    return float(gauge(d, zone.sides, zone.phase).max())


def _resample(
    csdf: CSDF,
    origin: np.ndarray,
    shape: tuple[int, ...],
    normal: np.ndarray,
    levels: np.ndarray,
    mats: np.ndarray,
    backs: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The output arrays on the grid ``origin``/``shape``: sdf (X, Y, Z) float32, rgb
    (X, Y, Z, 3) uint8, parts (X, Y, Z) int16, each voxel ``p`` showing the source point
    ``A_m p + b_m`` (``mats[m]`` = ``[A | b]``, (M + 1, 3, 4), ``m`` the slab of ``p . normal``
    among the increasing ``levels`` (M,)), and ``moved`` (X, Y, Z) bool: the voxels that show
    another place than their own shifted by whole voxels (the surface there may have changed).
    Trilinear near the surface where moved; farther out the nearest value keeps the sign
    (re-evaluation covers the band).
    """
    h = csdf.voxel_size
    check_memory(shape, BYTES_PER_VOXEL, what="the warped grid")
    sdf = np.empty(shape, dtype=np.float32)
    rgb = np.empty((*shape, 3), dtype=np.uint8)
    parts = np.empty(shape, dtype=csdf.parts.dtype)
    moved = np.empty(shape, dtype=bool)
    resample_affine(
        csdf.sdf,
        csdf.rgb,
        csdf.parts,
        np.asarray(csdf.origin, dtype=np.float64),
        float(h),
        np.asarray(origin, dtype=np.float64),
        np.asarray(normal, dtype=np.float64),
        np.asarray(levels, dtype=np.float64),
        np.ascontiguousarray(mats, dtype=np.float64),
        np.zeros((len(mats), 3)) if backs is None else np.ascontiguousarray(backs, np.float64),
        np.float32((BAND_VOXELS + RESAMPLE_MARGIN) * h),
        sdf,
        rgb,
        parts,
        moved,
    )
    return sdf, rgb, parts, moved


def _finish(
    csdf: CSDF,
    origin: np.ndarray,
    arrays: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    entry: dict[str, Any],
    keep_square_to: np.ndarray | None = None,
    bound_far: bool = False,
) -> CSDF:
    """Re-evaluate the voxels near the surface within the band of a moved one, and the new
    CSDF with its history entry. With ``keep_square_to`` (K, 3) (the directions a map that only
    grows moves content along), a voxel whose field is flat along all of them keeps its
    resampled distance (:func:`~partscale.edit._warp_kernels.reevaluation_mask`). With
    ``bound_far``, the distances beyond the band are bounded (:func:`_bound_far`).
    """
    sdf, rgb, parts, moved = arrays
    h = csdf.voxel_size
    band = BAND_VOXELS + 1.0
    r = math.ceil(band) + 1
    # a voxel's nearest surface point is within the band: only moved voxels that near count
    dirs = np.zeros((0, 3)) if keep_square_to is None else np.asarray(keep_square_to, np.float64)
    mask = reevaluation_mask(sdf, moved, float(h), band, r, dirs, LATERAL)
    n = reevaluate_arrays(sdf, rgb, parts, h, mask, band=band)
    if bound_far:
        _bound_far(sdf, float(h), band)
    entry = {**entry, "reevaluated_voxels": int(n)}
    return _handed_over(csdf, entry, sdf, rgb, parts, origin)


def _handed_over(
    csdf: CSDF,
    entry: dict[str, Any],
    sdf: np.ndarray,
    rgb: np.ndarray,
    parts: np.ndarray,
    origin: np.ndarray,
) -> CSDF:
    """The warped CSDF with its history entry: ``sdf``, ``rgb``, ``parts`` were made by the
    warp and nothing else holds them, so they are made read-only and the CSDF takes them as
    they are instead of copying them (the planar edits do the same; a copy of the three
    arrays cost ~0.02-0.17 s of a 128 grid's warp on a loaded machine).
    """
    for a in (sdf, rgb, parts):
        a.flags.writeable = False
    return csdf.with_trusted_history(entry, sdf=sdf, rgb=rgb, parts=parts, origin=origin)


def _bound_far(sdf: np.ndarray, h: float, band: float) -> None:
    """In place on ``sdf`` (X, Y, Z) float32: beyond ``band`` voxels, no distance larger than
    the one to the nearest voxel of the other sign less half a voxel. A map that puts elements
    where the source had none (a turned arm) leaves, off its levels and past the band, the
    source's distances there, far larger than the way to the new surface: a sphere tracer
    would step through it.
    """
    far = np.abs(sdf) > band * h
    if not far.any():
        return
    edt = opposite_distance(sdf < 0)  # scipy's exact transform of either side, 3-6x faster
    bound = ((edt[far] - 0.5) * h).astype(np.float32)
    sdf[far] = np.copysign(np.minimum(np.abs(sdf[far]), bound), sdf[far])


def moved_axes(zone: RadialZone | ObliqueZone | ScrewZone | HelixZone | RotationZone) -> set[int]:
    """The world axes along which ``zone`` moves content (planar edits on them and this zone
    do not mix in one recipe: their positions could not be carried through it).
    """
    if isinstance(zone, RadialZone):
        return {a for a in range(3) if a != AXES.index(zone.axis)}
    if isinstance(zone, ScrewZone):
        return {a for a in range(3) if abs(zone.step[a]) > 1e-9} | {AXES.index(zone.axis)}
    if isinstance(zone, HelixZone):  # a turn about the vertical and a rise
        return {0, 1, 2}
    if isinstance(zone, RotationZone):  # turns about the vertical
        return {0, 2}
    return {a for a in range(3) if abs(zone.normal[a]) > 1e-9}


def warp_grid(
    origin: np.ndarray,
    shape: tuple[int, ...],
    h: float,
    zone: RadialZone | ObliqueZone | ScrewZone | HelixZone | RotationZone,
) -> tuple[np.ndarray, tuple[int, ...]]:
    """Origin and shape of the grid ``zone`` gives from the grid ``origin``/``shape``/``h``
    without computing anything.
    """
    origin = np.asarray(origin, dtype=np.float64)
    lo = origin - h / 2
    hi = origin + (np.asarray(shape) - 0.5) * h
    if isinstance(zone, ScrewZone):
        move = _screw_shift(zone, h) * h
        a, b = np.minimum(lo, lo + move) + h / 2, np.maximum(hi, hi + move) - h / 2
    elif isinstance(zone, HelixZone):
        a, b = _helix_bounds(zone, lo, hi, h)
    elif isinstance(zone, RotationZone):  # the disc the elements turn in
        reach = np.array([zone.radius + h, 0.0, zone.radius + h])
        c = np.array([zone.center[0], 0.0, zone.center[1]])
        a = np.minimum(lo + h / 2, c - reach)
        b = np.maximum(hi - h / 2, c + reach)
        a[1], b[1] = lo[1] + h / 2, hi[1] - h / 2
    elif isinstance(zone, RadialZone):
        shift = zone.shift
        grow = np.zeros(3)
        others = [a for a in range(3) if a != AXES.index(zone.axis)]
        grow[others] = max(shift, 0.0) / (math.cos(math.pi / zone.sides) if zone.sides else 1.0)
        a, b = lo + h / 2 - grow, hi - h / 2 + grow
    else:
        n = np.asarray(zone.normal, dtype=np.float64)
        n = n / max(float(np.linalg.norm(n)), 1e-300)
        move = n * zone.shift
        a, b = np.minimum(lo, lo + move) + h / 2, np.maximum(hi, hi + move) - h / 2
    i0 = np.floor((a - origin) / h + 1e-9).astype(np.int64)
    i1 = np.ceil((b - origin) / h - 1e-9).astype(np.int64)
    return origin + i0 * h, tuple(int(v) for v in (i1 - i0 + 1))


def apply_warp(
    csdf: CSDF,
    zone: RadialZone | ObliqueZone | ScrewZone | HelixZone | RotationZone,
    *,
    record: dict[str, Any] | None = None,
) -> CSDF:
    """Apply a zone that is not a slab across an axis: radial, oblique or steps.

    Dispatches to :func:`apply_radial`, :func:`apply_oblique`, :func:`apply_screw`,
    :func:`apply_helix` or :func:`apply_rotation` by the kind of ``zone``.

    Parameters
    ----------
    csdf : CSDF
        The object.
    zone : RadialZone, ObliqueZone, ScrewZone, HelixZone or RotationZone
        The zone.
    record : dict, optional
        More keys for its history entry (a recipe's step).

    Returns
    -------
    CSDF
        The object with ``zone`` applied.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.edit import ObliqueZone, apply_warp
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.1, 0.1), voxel_size=0.05)
    >>> out = apply_warp(bar, ObliqueZone((1.0, 0.0, 0.0), 0.3, 0.6, 0.8))
    >>> out.meta["history"][-1]["op"], round(float(out.surface_bounds()[1, 0]), 2)
    ('oblique', 1.2)
    """
    if isinstance(zone, RadialZone):
        return apply_radial(csdf, zone, record=record)
    if isinstance(zone, ScrewZone):
        return apply_screw(csdf, zone, record=record)
    if isinstance(zone, HelixZone):
        return apply_helix(csdf, zone, record=record)
    if isinstance(zone, RotationZone):
        return apply_rotation(csdf, zone, record=record)
    return apply_oblique(csdf, zone, record=record)


#: Voxels either side of a screw's cut plane over which the two sides are blended.
CUT_BLEND = 2.0


def _screw_shift(zone: ScrewZone, h: float) -> np.ndarray:
    """(3,) int64: the zone's whole shift, ``copies`` steps, each step snapped to whole
    voxels (so everything beyond the cut is an exact copy).
    """
    return np.rint(np.asarray(zone.step) / h).astype(np.int64) * zone.copies


def screw_ground(csdf: CSDF, zone: ScrewZone) -> float | None:
    """The floor a flight stands on beyond a screw zone's cut, or None.

    Parameters
    ----------
    csdf : CSDF
        The object (a flight of steps).
    zone : ScrewZone
        Its cut and step (``copies`` is not used).

    Returns
    -------
    float or None
        The world height (up, y) of the lowest solid voxel centre, where the solid beyond the
        cut reaches it (within a voxel): :func:`apply_screw` keeps such a flight on the floor
        (lifted, the rows from there up by the rise are filled from the flight shifted along
        it only; lowered, what goes below is cut off half a voxel below it). None for a flight
        that does not reach the floor beyond the cut (left as it is).

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import shapes
    >>> from partscale.edit import ScrewZone, screw_ground
    >>> steps = [((0.2 * i, 0, 0), (0.2 * (i + 1), 0.2 * (i + 1), 0.4)) for i in range(4)]
    >>> flight = shapes.grid(lambda p: shapes.boxes_sdf(p, steps), np.array([[0, 0, 0], [0.8, 0.8, 0.4]]), voxel_size=0.05)
    >>> round(screw_ground(flight, ScrewZone("x", (0.2, 0.2, 0.0), 0.5, 1)), 3)
    0.05
    """
    a = AXES.index(zone.axis)
    h = csdf.voxel_size
    unit = np.rint(np.asarray(zone.step) / h).astype(np.int64)
    solid = np.argwhere(csdf.sdf < 0)
    if solid.size == 0:
        return None
    floor = int(solid[:, 1].min())
    cut_i = (zone.cut - csdf.origin[a]) / h
    beyond = solid[(solid[:, a] - cut_i) * np.sign(unit[a]) > 0]
    if beyond.size == 0 or beyond[:, 1].min() > floor + 1:
        return None
    return float(csdf.origin[1] + floor * h)


def _ground(csdf, zone, unit, shift, off, placed, far, after) -> None:
    """A flight standing on the floor beyond the cut (a solid flight, a stringer down to the
    floor) stays on it: lifted, its lowest ``shift`` voxels up are filled from the side shifted
    along the flight only; lowered, what went below the floor is cut off at it (in ``after``,
    in place). An open flight that does not reach the floor there is left as it is (filling
    would add treads at the old heights).
    """
    up = 1
    rise = int(shift[up])
    floor_y = screw_ground(csdf, zone)
    if rise == 0 or floor_y is None:
        return
    floor = round(float(floor_y - csdf.origin[up]) / csdf.voxel_size)
    h = np.float32(csdf.voxel_size)
    if rise < 0:  # lowered: what went below the floor is cut off there
        rows = int(off[up] + floor)
        sl = [slice(None)] * 3
        sl[up] = slice(0, rows)
        below = np.arange(rows, dtype=np.float32)
        shape = [1, 1, 1]
        shape[up] = -1
        plane = ((rows - 0.5 - below) * h).reshape(shape)  # distance below the floor face
        after[0][tuple(sl)] = np.maximum(after[0][tuple(sl)], plane)
        return
    flat = shift.copy()
    flat[up] = 0
    sl = [slice(None)] * 3
    sl[up] = slice(int(off[up] + floor), int(off[up] + floor + rise + 1))
    box = tuple(sl)
    base = placed(csdf.sdf, off + flat, far)[box]
    lifted = after[0][box]
    take = base < lifted
    lifted[take] = base[take]
    rgb = placed(csdf.rgb, off + flat, 0)[box]
    parts = placed(csdf.parts, off + flat, -1)[box]
    after[1][box][take] = rgb[take]
    after[2][box][take] = parts[take]


def apply_screw(csdf: CSDF, zone: ScrewZone, *, record: dict[str, Any] | None = None) -> CSDF:
    """Add (or remove) steps of a flight that repeats by a diagonal shift.

    ``zone.copies`` steps added (or removed) along a diagonal repetition (see
    :class:`~partscale.edit.ScrewZone`): what lies beyond the cut moves by that many steps,
    each step snapped to whole voxels; the two sides are blended over :data:`CUT_BLEND`
    voxels either side of the cut and re-evaluated there. ``meta['history']`` gains
    ``{"op": "screw", ...}`` with the snapped step.

    Parameters
    ----------
    csdf : CSDF
        The object (a flight of steps).
    zone : ScrewZone
        The step, the cut and how many steps to add or remove.
    record : dict, optional
        More keys for the history entry (a recipe's step).

    Returns
    -------
    CSDF
        The object with ``zone.copies`` more steps (fewer where it is negative).

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import shapes
    >>> from partscale.edit import ScrewZone, apply_screw
    >>> steps = [((0.2 * i, 0, 0), (0.2 * (i + 1), 0.2 * (i + 1), 0.4)) for i in range(4)]
    >>> flight = shapes.grid(lambda p: shapes.boxes_sdf(p, steps), np.array([[0, 0, 0], [0.8, 0.8, 0.4]]), voxel_size=0.05)
    >>> out = apply_screw(flight, ScrewZone("x", (0.2, 0.2, 0.0), 0.5, 1))
    >>> [round(float(v), 2) for v in out.surface_bounds()[1, :2]]
    [1.0, 1.0]
    """
    h = csdf.voxel_size
    a = AXES.index(zone.axis)
    if zone.copies == 0 or not all(math.isfinite(v) for v in (*zone.step, zone.cut)):
        raise InputError(
            f"screw: expected finite values and copies other than 0, got {zone.to_json()}"
        )
    unit = np.rint(np.asarray(zone.step) / h).astype(np.int64)
    if unit[a] == 0:
        raise InputError(
            f"screw step: expected a shift along {zone.axis} of at least a voxel, got {zone.step[a]:.4g}"
        )
    shift = unit * zone.copies
    origin, shape = warp_grid(csdf.origin, csdf.shape, h, zone)
    check_memory(shape, BYTES_PER_VOXEL, what=f"{zone.copies:+d} steps")
    far = np.float32(max(float(csdf.sdf.max()), h))
    off = np.rint((csdf.origin - origin) / h).astype(np.int64)

    def placed(arr: np.ndarray, at: np.ndarray, fill) -> np.ndarray:
        # fill: a value, or (sdf) the whole grid's distance bound beyond the placed copy
        if isinstance(fill, np.ndarray) and fill.shape == tuple(shape):
            out = fill
        else:
            out = np.full((*shape, *arr.shape[3:]), fill, dtype=arr.dtype)
        sl = tuple(slice(int(at[k]), int(at[k]) + arr.shape[k]) for k in range(3))
        out[sl] = arr
        return out

    lo, hi = csdf.origin, csdf.origin + (np.asarray(csdf.shape) - 1) * h

    def bound(at: np.ndarray) -> np.ndarray:  # beyond a copy placed at ``at`` (output indices)
        move = (at - off) * h
        return _margin_bound(origin, shape, h, lo + move, hi + move)

    before = [
        placed(x, off, f) for x, f in ((csdf.sdf, bound(off)), (csdf.rgb, 0), (csdf.parts, -1))
    ]
    after = [
        placed(x, off + shift, f)
        for x, f in ((csdf.sdf, bound(off + shift)), (csdf.rgb, 0), (csdf.parts, -1))
    ]
    _ground(csdf, zone, unit, shift, off, placed, far, after)
    # the side of the cut each output layer along the axis lies on, blended near it
    x = origin[a] + np.arange(shape[a]) * h
    direction = 1.0 if unit[a] > 0 else -1.0
    beyond = (x - zone.cut) * direction / h
    w = np.clip(beyond / (2 * CUT_BLEND) + 0.5, 0.0, 1.0).astype(np.float32)
    shp = [1, 1, 1]
    shp[a] = -1
    wb = w.reshape(shp)
    sdf = ((1 - wb) * before[0] + wb * after[0]).astype(np.float32)
    side = wb >= 0.5
    rgb = np.where(side[..., None], after[1], before[1])
    parts = np.where(side, after[2], before[2])
    # re-evaluated within the blend and the band of it
    reach = CUT_BLEND + BAND_VOXELS + 1
    near_cut = (np.abs(beyond) <= reach).reshape(shp)
    mask = np.broadcast_to(near_cut, shape) & (np.abs(sdf) <= (BAND_VOXELS + 1) * h)
    n = reevaluate_arrays(sdf, rgb, parts, h, np.ascontiguousarray(mask), band=BAND_VOXELS + 1.0)
    snapped = ScrewZone(zone.axis, tuple(float(v * h) for v in unit), zone.cut, zone.copies)  # type: ignore[arg-type]
    entry = {"op": "screw", **snapped.to_json(), "reevaluated_voxels": int(n), **(record or {})}
    return _handed_over(csdf, entry, sdf, rgb, parts, origin)


def apply_radial(csdf: CSDF, zone: RadialZone, *, record: dict[str, Any] | None = None) -> CSDF:
    """Stretch the annulus of a radial zone.

    The annulus of ``zone`` stretched (see module); ``meta['history']`` gains
    ``{"op": "radial", ...}`` (:meth:`RadialZone.to_json`).

    Parameters
    ----------
    csdf : CSDF
    zone : RadialZone
        Radii in world units. Everything beyond ``r0`` is resampled, so ``to`` is kept as given
        (no snapping to whole voxels).

    Returns
    -------
    CSDF
        A grid grown to hold the outline moved by ``to - r1`` on each side across the axis;
        inside ``r0`` (and outside ``span``) the voxels are the input's own.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.edit import RadialZone, apply_radial
    >>> disc = shapes.box((-0.5, 0, -0.5), (0.5, 0.1, 0.5), voxel_size=0.04)
    >>> out = apply_radial(disc, RadialZone("y", (0.0, 0.0), 0.1, 0.4, 0.5))
    >>> round(float(out.surface_bounds()[1, 0]), 2)  # its sides moved out by 0.1
    0.6
    """
    check_radial(csdf, zone)
    h = csdf.voxel_size
    ax = AXES.index(zone.axis)
    others = [a for a in range(3) if a != ax]
    origin, shape = warp_grid(csdf.origin, csdf.shape, h, zone)
    # the map moves points across the axis only, the same at every level: it is computed once
    # for the grid's cross-section (U, V) and the levels are gathered through it
    uu = origin[others[0]] + np.arange(shape[others[0]]) * h
    vv = origin[others[1]] + np.arange(shape[others[1]]) * h
    uv = np.stack(np.meshgrid(uu, vv, indexing="ij"), axis=-1)  # (U, V, 2)
    pts = np.zeros((*uv.shape[:2], 3))
    pts[..., others] = uv
    # the span is applied by level below: the map of the cross-section itself
    src = warp_source(replace(zone, span=None), pts.reshape(-1, 3), h)[0]
    src = src[:, others].reshape(uv.shape)  # (U, V, 2) world
    iu = (src[..., 0] - csdf.origin[others[0]]) / h
    iv = (src[..., 1] - csdf.origin[others[1]]) / h
    # levels: the output's along the axis are the source's (the grid does not grow along it)
    levels = csdf.origin[ax] + np.arange(shape[ax]) * h
    inside = np.ones(shape[ax], dtype=bool)
    if zone.span is not None:  # only the levels the zone spans move
        inside = (levels >= zone.span[0]) & (levels <= zone.span[1])
    arrays = _gather_levels(csdf, ax, others, iu, iv, inside, origin)
    entry = {"op": "radial", **zone.to_json(), **(record or {})}
    # growing, the map moves content across the axis only: a voxel whose nearest surface point
    # lies along the axis keeps its distance
    keep = np.eye(3)[others] if zone.to >= zone.r1 else None
    return _finish(csdf, origin, arrays, entry, keep)


def _gather_levels(
    csdf: CSDF,
    ax: int,
    others: list[int],
    iu: np.ndarray,
    iv: np.ndarray,
    inside: np.ndarray,
    origin: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The output arrays of a map across ``ax`` that is the same at every level: output column
    ``(u, v)`` shows the source at continuous indices ``(iu, iv)`` (U, V) on the levels where
    ``inside`` (L,) holds, and its own place on the others; sdf and colour bilinear within the
    band and :data:`RESAMPLE_MARGIN` of the surface, else (and parts) nearest; and the (X, Y, Z) bool of voxels whose source is not their own place shifted by
    whole voxels.
    """
    h = csdf.voxel_size
    order = (others[0], ax, others[1])
    # the output's own place in source indices (whole voxels: the grid grew by whole voxels)
    ou = int(np.rint((origin[others[0]] - csdf.origin[others[0]]) / h))
    ov = int(np.rint((origin[others[1]] - csdf.origin[others[1]]) / h))
    shape = [0, 0, 0]
    shape[others[0]], shape[ax], shape[others[1]] = iu.shape[0], csdf.shape[ax], iu.shape[1]
    out = np.empty(shape, dtype=np.float32)
    out_rgb = np.empty((*shape, 3), dtype=np.uint8)
    out_parts = np.empty(shape, dtype=csdf.parts.dtype)
    moved = np.empty(shape, dtype=bool)
    view = (0, 1, 2)
    gather_columns(
        np.moveaxis(csdf.sdf, order, view),
        np.moveaxis(csdf.rgb, order, view),
        np.moveaxis(csdf.parts, order, view),
        np.ascontiguousarray(iu, dtype=np.float64),
        np.ascontiguousarray(iv, dtype=np.float64),
        np.ascontiguousarray(inside, dtype=np.bool_),
        ou,
        ov,
        np.float32((BAND_VOXELS + RESAMPLE_MARGIN) * h),
        np.moveaxis(out, order, view),
        np.moveaxis(out_rgb, order, view),
        np.moveaxis(out_parts, order, view),
        np.moveaxis(moved, order, view),
    )
    return out, out_rgb, out_parts, moved


def check_oblique(csdf: CSDF, zone: ObliqueZone) -> np.ndarray:
    """``zone``'s normal as a unit (3,) float64, or :class:`InputError` (one line)."""
    n = np.asarray(zone.normal, dtype=np.float64)
    if n.shape != (3,) or not np.isfinite(n).all() or np.linalg.norm(n) < 1e-9:
        raise InputError(f"normal: expected a non-zero vector nx ny nz, got {list(zone.normal)}")
    n = n / np.linalg.norm(n)
    if not all(math.isfinite(v) for v in (zone.s0, zone.s1, zone.to)):
        raise InputError(f"oblique zone: expected finite positions, got {zone.to_json()}")
    if not zone.s0 < zone.s1:
        raise InputError(f"oblique zone: expected START < END, got {zone.s0:.4g} {zone.s1:.4g}")
    if zone.to <= zone.s0:
        raise InputError(
            f"oblique to: expected a position beyond START ({zone.s0:.4g}), got {zone.to:.4g}"
        )
    return n


def apply_oblique(csdf: CSDF, zone: ObliqueZone, *, record: dict[str, Any] | None = None) -> CSDF:
    """Stretch the slab of an oblique zone along its normal.

    The slab of ``zone`` stretched along its normal (see module); ``meta['history']`` gains
    ``{"op": "oblique", ...}`` (:meth:`ObliqueZone.to_json`, the normal made unit).

    The shift ``to - s1`` is kept as given (an oblique shift is not a whole number of voxels
    along every axis); everything beyond the zone is resampled and re-evaluated.

    Parameters
    ----------
    csdf : CSDF
        The object.
    zone : ObliqueZone
        The slab, world units.
    record : dict, optional
        More keys for the history entry (a recipe's step).

    Returns
    -------
    CSDF
        The edited object, its grid grown to hold it.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.edit import ObliqueZone, apply_oblique
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.1, 0.1), voxel_size=0.05)
    >>> out = apply_oblique(bar, ObliqueZone((1.0, 0.0, 0.0), 0.3, 0.6, 0.8))
    >>> round(float(out.surface_bounds()[1, 0]), 2)
    1.2
    """
    n = check_oblique(csdf, zone)
    h = csdf.voxel_size
    s0, s1, to = zone.s0, zone.s1, zone.to
    origin, shape = warp_grid(csdf.origin, csdf.shape, h, zone)

    length, target = s1 - s0, to - s0
    # the map p -> p - back(p . n) n: identity up to s0, a stretch along n up to ``to``, then a
    # shift by to - s1
    mats = np.zeros((3, 3, 4))
    mats[:, :, :3] = np.eye(3)
    backs = np.array([[0.0, 0.0, 0.0], [s0, 1 - length / target, 0.0], [0.0, 0.0, to - s1]])
    arrays = _resample(csdf, origin, shape, n, np.array([s0, to]), mats, backs)
    unit = ObliqueZone((float(n[0]), float(n[1]), float(n[2])), s0, s1, to)
    entry = {"op": "oblique", **unit.to_json(), **(record or {})}
    # growing, the map moves content along n only: a voxel whose nearest surface point lies
    # square to n keeps its distance
    return _finish(csdf, origin, arrays, entry, n[None, :] if to >= s1 else None)


def _turn(d: np.ndarray, degrees: float) -> np.ndarray:
    """(..., 2) offsets on x and z turned by ``degrees`` from x toward z."""
    t = math.radians(degrees)
    c, s = math.cos(t), math.sin(t)
    return np.stack([c * d[..., 0] - s * d[..., 1], s * d[..., 0] + c * d[..., 1]], axis=-1)


def _helix_bounds(
    zone: HelixZone, lo: np.ndarray, hi: np.ndarray, h: float
) -> tuple[np.ndarray, np.ndarray]:
    """World box (voxel centres) holding the grid ``lo``..``hi`` (voxel faces) and what a helix
    zone moves: the part the output's upper side shows (from the blend's lowest layer) turned
    and raised by ``copies`` steps.
    """
    n = zone.copies
    y0 = max(float(lo[1]), zone.cut - (CUT_BLEND + 1) * h - n * zone.rise)
    a, b = lo + h / 2, hi - h / 2
    if y0 >= hi[1]:
        return a, b
    c = np.asarray(zone.center, dtype=np.float64)
    corners = np.array([[x, z] for x in (lo[0], hi[0]) for z in (lo[2], hi[2])]) - c
    xz = _turn(corners, n * zone.angle) + c
    mlo = np.array([xz[:, 0].min(), y0 + n * zone.rise, xz[:, 1].min()])
    mhi = np.array([xz[:, 0].max(), hi[1] + n * zone.rise, xz[:, 1].max()])
    return np.minimum(a, mlo + h / 2), np.maximum(b, mhi - h / 2)


def _margin_bound(
    origin: np.ndarray,
    shape: tuple[int, ...],
    h: float,
    lo: np.ndarray,
    hi: np.ndarray,
    above: float = math.inf,
) -> np.ndarray:
    """(X, Y, Z) float32 on the grown grid: a distance no larger than the true one where a
    placed copy of the input's grid (its voxel centres ``lo``..``hi``) does not reach (its own
    voxels replace it): the distance to that box, and below the level ``above`` (from where a
    helix moves content) no more than the height to it. A far constant there would let a
    sphere tracer step through the object.
    """
    d2 = np.zeros(shape, dtype=np.float32)
    for a in range(3):
        x = origin[a] + np.arange(shape[a]) * h
        gap = np.maximum(np.maximum(lo[a] - x, x - hi[a]), 0.0).astype(np.float32)
        sh = [1, 1, 1]
        sh[a] = -1
        d2 = d2 + gap.reshape(sh) ** 2
    y = (origin[1] + np.arange(shape[1]) * h).reshape(1, -1, 1)
    return np.minimum(np.sqrt(d2), np.maximum(above - y, 0.0)).astype(np.float32)


def check_helix(zone: HelixZone) -> None:
    """Refuse (:class:`InputError`, one line) a helix zone that cannot apply."""
    vals = (*zone.center, zone.angle, zone.rise, zone.cut)
    if zone.copies == 0 or not all(math.isfinite(v) for v in vals):
        raise InputError(
            f"helix: expected finite values and copies other than 0, got {zone.to_json()}"
        )
    if not 0 < abs(zone.angle) < 180:
        raise InputError(f"helix angle: expected 0 < |angle| < 180 degrees, got {zone.angle:.4g}")


def apply_helix(csdf: CSDF, zone: HelixZone, *, record: dict[str, Any] | None = None) -> CSDF:
    """Add (or remove) steps of a stair that repeats by a turn about the vertical and a rise.

    ``zone.copies`` steps added (or removed) along a helical repetition (see
    :class:`~partscale.edit.HelixZone`): every point above the level ``zone.cut`` shows the
    source ``copies`` steps back along the helix (turned by ``-copies * angle`` about the axis
    and lowered by ``copies * rise``; sdf and colour trilinear near the surface, parts nearest),
    blended with its own place over :data:`CUT_BLEND` voxels either side of the cut; then every
    voxel in the band of one that moved is re-evaluated (a turn is no whole-voxel shift). A
    column about the axis comes out longer by ``copies`` rises and a handrail that follows the
    helix runs on. ``meta['history']`` gains ``{"op": "helix", ...}``.

    Parameters
    ----------
    csdf : CSDF
        The object (a spiral stair).
    zone : HelixZone
        The step (angle, rise, axis), the cut and how many steps to add or remove.
    record : dict, optional
        More keys for the history entry (a recipe's step).

    Returns
    -------
    CSDF
        The edited object, its grid grown to hold the turned upper part.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.edit import HelixZone, apply_helix
    >>> post = shapes.box((-0.1, 0, -0.1), (0.1, 1.0, 0.1), voxel_size=0.05)
    >>> out = apply_helix(post, HelixZone((0.0, 0.0), 90.0, 0.2, 0.5, 1))
    >>> round(float(out.surface_bounds()[1, 1]), 2)  # a square post turned a quarter: 0.2 taller
    1.2
    """
    check_helix(zone)
    h = csdf.voxel_size
    origin, shape = warp_grid(csdf.origin, csdf.shape, h, zone)
    check_memory(shape, BYTES_PER_VOXEL, what=f"{zone.copies:+d} steps")
    off = np.rint((csdf.origin - origin) / h).astype(np.int64)
    sl = tuple(slice(int(off[k]), int(off[k]) + csdf.shape[k]) for k in range(3))
    # the side of the cut each output level lies on, blended near it
    y = origin[1] + np.arange(shape[1]) * h
    w = np.clip((y - zone.cut) / h / (2 * CUT_BLEND) + 0.5, 0.0, 1.0).astype(np.float32)
    top = csdf.origin + (np.asarray(csdf.shape) - 1) * h
    above = float(y[int(np.argmax(w > 0))]) if w.any() else math.inf
    sdf = _margin_bound(origin, shape, h, csdf.origin, top, above)
    rgb = np.zeros((*shape, 3), dtype=np.uint8)
    parts = np.full(shape, -1, dtype=csdf.parts.dtype)
    sdf[sl], rgb[sl], parts[sl] = csdf.sdf, csdf.rgb, csdf.parts
    moved = np.zeros(shape, dtype=bool)
    if w.any():
        j0 = int(np.argmax(w > 0))
        sub_origin = origin.copy()
        sub_origin[1] = y[j0]
        c = np.array([zone.center[0], 0.0, zone.center[1]])
        t = math.radians(-zone.copies * zone.angle)
        rot = np.array([[math.cos(t), 0, -math.sin(t)], [0, 1, 0], [math.sin(t), 0, math.cos(t)]])
        mats = np.zeros((1, 3, 4))
        mats[0, :, :3] = rot
        mats[0, :, 3] = c - rot @ c - np.array([0.0, zone.copies * zone.rise, 0.0])
        a_sdf, a_rgb, a_parts, a_moved = _resample(
            csdf, sub_origin, (shape[0], shape[1] - j0, shape[2]), np.zeros(3), np.zeros(0), mats
        )
        wb = w[j0:].reshape(1, -1, 1)
        sdf[:, j0:] = (1 - wb) * sdf[:, j0:] + wb * a_sdf
        side = wb >= 0.5
        rgb[:, j0:] = np.where(side[..., None], a_rgb, rgb[:, j0:])
        parts[:, j0:] = np.where(side, a_parts, parts[:, j0:])
        moved[:, j0:] = a_moved | (wb < 1)
    entry = {"op": "helix", **zone.to_json(), **(record or {})}
    return _finish(csdf, origin, (sdf, rgb, parts, moved), entry)


def check_rotation(zone: RotationZone) -> None:
    """Refuse (:class:`InputError`, one line) a rotation zone that cannot apply."""
    vals = (*zone.center, zone.angle, zone.phase, zone.hub, zone.radius, *zone.span)
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"rotation: expected finite values, got {zone.to_json()}")
    if not 0 < abs(zone.angle) <= 180:
        raise InputError(
            f"rotation angle: expected 0 < |angle| <= 180 degrees, got {zone.angle:.4g}"
        )
    if zone.count < 2 or zone.copies == 0:
        raise InputError(
            f"rotation: expected at least 2 elements and copies other than 0, got count "
            f"{zone.count}, copies {zone.copies}"
        )
    if zone.count + zone.copies < 1:
        raise InputError(
            f"rotation copies: expected to remove at most {zone.count - 1} of the "
            f"{zone.count} elements, got {zone.copies}"
        )
    if zone.closed and abs(zone.count * abs(zone.angle) - 360.0) > 1e-6 * 360:
        raise InputError(
            f"rotation: a closed ring of {zone.count} expected an angle of "
            f"{360 / zone.count:.6g} degrees, got {zone.angle:.6g}"
        )
    if not 0 <= zone.hub < zone.radius or not zone.span[0] < zone.span[1]:
        raise InputError(
            "rotation: expected 0 <= hub < radius and span Y0 < Y1, got hub "
            f"{zone.hub:.4g}, radius {zone.radius:.4g}, span {list(zone.span)}"
        )


def rotation_source(theta: np.ndarray, zone: RotationZone) -> np.ndarray:
    """Source directions (degrees) of output directions ``theta`` (degrees, from x toward z)
    about a rotation zone's axis: the map of :func:`apply_rotation` on the plane.

    Parameters
    ----------
    theta : (...,) float64
        Directions after the edit.
    zone : RotationZone
        The zone.

    Returns
    -------
    (...,) float64
        Directions before it (a removed element's place on an open arc shows the empty place
        past the arc's end).

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.edit import RotationZone
    >>> from partscale.edit.warp import rotation_source
    >>> ring = RotationZone((0.0, 0.0), 90.0, 0.0, 4, True, 0.1, 0.5, (0.0, 0.1), 1)
    >>> rotation_source(np.array([0.0, 72.0, 144.0]), ring).round(1)  # five arms from four
    array([  0.,  90., 180.])
    """
    sign = 1.0 if zone.angle > 0 else -1.0
    a = abs(zone.angle)
    rel = np.mod(sign * (theta - zone.phase), 360.0)  # 0..360 from the first element
    k, n = zone.count, zone.copies
    if zone.closed:
        step = 360.0 / (k + n)
        m = np.rint(rel / step)
        alpha = np.clip(rel - m * step, -a / 2, a / 2)  # within the element's own sector
        src = np.mod(np.rint(m * k / (k + n)), k) * a + alpha
        return zone.phase + sign * src
    # an open arc: directions measured from the middle of the longer of the two arcs
    mid = (k - 1 + max(n, 0)) * a / 2
    rel = np.mod(rel - mid + 180.0, 360.0) + mid - 180.0
    m = np.rint(rel / a)
    src = rel.copy()
    if n > 0:  # new elements: the last one turned on by an angle each
        new = (m >= k) & (m <= k - 1 + n)
        src[new] = rel[new] - (m[new] - (k - 1)) * a
    else:  # the last -n removed: their places show the empty place past the end
        gone = (m >= k + n) & (m <= k - 1)
        src[gone] = rel[gone] + (k - m[gone]) * a
    return zone.phase + sign * src


def _rotation_points(zone: RotationZone, p: np.ndarray) -> np.ndarray:
    """(N, 3) source points of output points ``p`` (N, 3) under a rotation zone: beyond the hub
    and on the span's levels turned by :func:`rotation_source` about the axis, else their own.
    """
    c = np.array(zone.center, dtype=np.float64)
    d = p[:, [0, 2]] - c
    r = np.hypot(d[:, 0], d[:, 1])
    theta = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
    t = np.radians(rotation_source(theta, zone))
    turn = (r > zone.hub) & (p[:, 1] >= zone.span[0]) & (p[:, 1] <= zone.span[1])
    src = p.copy()
    src[turn, 0] = c[0] + r[turn] * np.cos(t[turn])
    src[turn, 2] = c[1] + r[turn] * np.sin(t[turn])
    return src


def apply_rotation(csdf: CSDF, zone: RotationZone, *, record: dict[str, Any] | None = None) -> CSDF:
    """Add (or remove) elements of a ring or arc that repeats by a turn about the vertical.

    ``zone.copies`` elements more (or fewer) of a rotational repetition (see
    :class:`~partscale.edit.RotationZone`): every column of the plane beyond ``zone.hub``
    shows, on the levels of ``zone.span``, the source turned about the axis by
    :func:`rotation_source` (sdf and colour bilinear, parts nearest); within the hub and on the
    other levels, its own place. Each element is moved rigidly (a closed ring's ``count +
    copies`` are spaced evenly, each a turned copy of the nearest old one; an open arc goes on
    by the angle, or loses its last elements); then every voxel in the band of one that moved
    is re-evaluated. ``meta['history']`` gains ``{"op": "rotation", ...}``.

    Parameters
    ----------
    csdf : CSDF
        The object (up is +y).
    zone : RotationZone
        The elements and how many to add or remove.
    record : dict, optional
        More keys for the history entry (a recipe's step).

    Returns
    -------
    CSDF
        The edited object, its grid grown to hold the disc the elements turn in.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.edit import RotationZone, apply_rotation
    >>> arms = [((0.1, 0, -0.03), (0.5, 0.06, 0.03)), ((-0.03, 0, 0.1), (0.03, 0.06, 0.5))]
    >>> arms += [((-0.5, 0, -0.03), (-0.1, 0.06, 0.03)), ((-0.03, 0, -0.5), (0.03, 0.06, -0.1))]
    >>> cross = shapes.grid(lambda p: shapes.boxes_sdf(p, arms), [(-0.5, 0, -0.5), (0.5, 0.06, 0.5)], voxel_size=0.02)
    >>> out = apply_rotation(cross, RotationZone((0.0, 0.0), 90.0, 0.0, 4, True, 0.05, 0.52, (-0.1, 0.2), -1))
    >>> bool(out.sdf[out.sdf.shape[0] // 2 - 20, 1, out.sdf.shape[2] // 2] < 0)  # no arm along -x
    False
    """
    check_rotation(zone)
    h = csdf.voxel_size
    origin, shape = warp_grid(csdf.origin, csdf.shape, h, zone)
    check_memory(shape, BYTES_PER_VOXEL, what=f"{zone.copies:+d} elements")
    others = [0, 2]
    c = np.array(zone.center, dtype=np.float64)
    uu = origin[0] + np.arange(shape[0]) * h
    vv = origin[2] + np.arange(shape[2]) * h
    # the map turns points about the vertical, the same on every level of the span: computed
    # once for the grid's cross-section (U, V) at a level of it, the levels gathered through it
    pts = np.zeros((shape[0], shape[2], 3))
    pts[..., 0], pts[..., 2] = uu[:, None], vv[None, :]
    pts[..., 1] = zone.span[0]
    src = warp_source(zone, pts.reshape(-1, 3), h)[0].reshape(pts.shape)
    su, sv = src[..., 0], src[..., 2]
    turn = np.hypot(uu[:, None] - c[0], vv[None, :] - c[1]) > zone.hub
    # whole voxels where nothing turns (exactly the column's own place)
    iu = (su - csdf.origin[0]) / h
    iv = (sv - csdf.origin[2]) / h
    ou = np.rint((origin[0] - csdf.origin[0]) / h)
    ov = np.rint((origin[2] - csdf.origin[2]) / h)
    still = ~turn | ((np.abs(iu - np.rint(iu)) < 1e-9) & (np.abs(iv - np.rint(iv)) < 1e-9))
    iu = np.where(still & ~turn, np.arange(shape[0])[:, None] + ou, iu)
    iv = np.where(still & ~turn, np.arange(shape[2])[None, :] + ov, iv)
    levels = csdf.origin[1] + np.arange(shape[1]) * h
    inside = (levels >= zone.span[0]) & (levels <= zone.span[1])
    arrays = _gather_levels(csdf, 1, others, iu, iv, inside, origin)
    entry = {"op": "rotation", **zone.to_json(), **(record or {})}
    # off the span's levels and within the hub the source's own distances stay: where arms now
    # lie that were not there they would reach past them (bounded)
    return _finish(csdf, origin, arrays, entry, bound_far=True)
