"""Round and polygonal outlines in plan: the axis, the outline's shape and the annulus to grow.

:func:`find_radial` reads an object's footprint seen along an axis (y: a table from above): its
centre (the footprint's bounding box middle), and its outline radius at every angle from there.
The outline is *round* where that radius is constant to :data:`ROUND_TOL` voxels, a *regular
polygon* of ``k`` sides (3..:data:`MAX_SIDES`) where the gauge of such a polygon
(:func:`partscale.edit.gauge`, its faces at the phase of the radius' ``k``-th harmonic) explains
it to :data:`ROUND_TOL` voxels; otherwise there is no radial frame (a rectangle, a chair).

:func:`radial_zones` finds the annuli of constant radial section: the object binned by gauge
radius, each ring's occupancy per level along the axis; neighbouring rings whose occupancy
profiles differ by less than :data:`RING_STEP` at every level are one run, the way
:func:`~partscale.zones.suggest.constant_slabs` reads layers. Growing such an annulus keeps what
lies inside it (a column, a foot) and what lies outside (a top's rim) as they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..csdf import CSDF
from ..edit import AXES, RadialZone, gauge

#: Outline residual (RMS, voxels) below which a footprint counts as round or a regular polygon.
ROUND_TOL = 1.0
#: Most sides of a polygonal outline read as such (beyond it, round).
MAX_SIDES = 12
#: Arc (voxels) of the outline per angle sampled: every sample holds a footprint pixel.
ARC_VOXELS = 2.0
#: Rings whose occupancy differs by less than this at every level are alike (a foot's rim or a
#: column's face changes a level's occupancy from 1 to 0 over a ring or two).
RING_STEP = 0.3
#: Shortest constant annulus, voxels; and how far its radii are moved in from its ends.
MIN_RING = 4
RING_INSET = 2


@dataclass(frozen=True)
class RadialFrame:
    """An outline that is round or a regular polygon about an axis (:func:`find_radial`).

    Parameters
    ----------
    axis, center, sides, phase
        The outline's axis, centre (world units), sides (0: round) and first face normal's
        direction (degrees), as :class:`~partscale.edit.RadialZone` holds them (what
        :meth:`zone` passes on).
    radius : float
        The outline's largest gauge radius (world units).
    residual : float
        RMS of the outline about the model, voxels.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> slab = shapes.box((-0.5, 0, -0.5), (0.5, 0.1, 0.5), voxel_size=0.025)  # a square top
    >>> frame = zones.find_radial(slab)
    >>> frame.axis, frame.sides  # a square
    ('y', 4)
    >>> abs(frame.radius - 0.5 * 2**0.5) < slab.voxel_size  # its corners' radius, within a voxel
    True
    """

    axis: str
    center: tuple[float, float]
    sides: int
    phase: float
    radius: float
    residual: float

    def zone(
        self, r0: float, r1: float, to: float, span: tuple[float, float] | None = None
    ) -> RadialZone:
        """The radial zone ``r0..r1`` to ``to`` about this frame (``span``: heights it applies between)."""
        return RadialZone(self.axis, self.center, r0, r1, to, self.sides, self.phase, span)


def _outline(csdf: CSDF, axis: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The footprint's centre (2,) and its outline radius (N,) at N angles from -180 degrees
    (voxels; NaN where no footprint pixel lies in that direction), and the footprint's pixel
    offsets (P, 2).
    """
    foot = np.asarray(csdf.sdf < 0).any(axis=axis)
    iu, iv = np.nonzero(foot)
    # the middle of the surface's own bounds (interpolated to the zero crossing: a surface
    # through voxel centres does not shift it by half a voxel), in voxel indices
    others = [a for a in range(3) if a != axis]
    sb = csdf.surface_bounds()
    center = (sb[0, others] + sb[1, others]) / 2
    center = (center - csdf.origin[others]) / csdf.voxel_size
    d = np.stack([iu, iv], axis=1) - center
    ang = np.arctan2(d[:, 1], d[:, 0])
    r = np.hypot(d[:, 0], d[:, 1]) + 0.5  # to the pixel's outer edge
    n = int(np.clip(round(2 * np.pi * r.max() / ARC_VOXELS), 32, 720))
    bins = ((ang + np.pi) / (2 * np.pi) * n).astype(np.int64) % n
    out = np.full(n, -np.inf)
    np.maximum.at(out, bins, r)
    out[~np.isfinite(out)] = np.nan
    return center, out, d


def find_radial(csdf: CSDF, axis: str | int = "y") -> RadialFrame | None:
    """The radial frame of ``csdf`` about ``axis`` (see module).

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : {'x', 'y', 'z'} or {0, 1, 2}
        The axis (a table's vertical: ``'y'``).

    Returns
    -------
    RadialFrame or None
        The frame, or None where the footprint is neither round nor a regular polygon.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> ball = shapes.sphere((0, 0, 0), 0.5, voxel_size=0.025)
    >>> frame = zones.find_radial(ball)
    >>> frame.sides, round(frame.radius, 1)
    (0, 0.5)
    """
    ax = AXES.index(axis) if isinstance(axis, str) else int(axis)
    if not (csdf.sdf < 0).any():
        return None
    h = csdf.voxel_size
    center, r, _ = _outline(csdf, ax)
    ok = np.isfinite(r)
    if ok.mean() < 0.9:  # a footprint with holes in its outline (a U, a ring of legs)
        return None
    n = r.size
    theta = -np.pi + (np.arange(n) + 0.5) * 2 * np.pi / n
    dirs = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    best: tuple[float, int, float] | None = None
    spectrum = np.fft.rfft(np.where(ok, r - np.nanmean(r), 0.0))
    for k in [0, *range(3, MAX_SIDES + 1)]:
        if k == 0:
            phase = 0.0
            model_shape = np.ones(n)
        else:
            # the radius peaks at the vertices; faces lie halfway between them
            vertex = -np.angle(spectrum[k]) / k
            phase = float(np.rad2deg(vertex + np.pi / k))
            model_shape = 1.0 / gauge(dirs, k, phase)
        scale = float(np.nanmedian(r[ok] / model_shape[ok]))
        res = float(np.sqrt(np.nanmean((r[ok] - scale * model_shape[ok]) ** 2)))
        if best is None or res < best[0] - 0.05:
            best = (res, k, phase)
    assert best is not None
    res, k, phase = best
    if res > ROUND_TOL:
        return None
    others = [a for a in range(3) if a != ax]
    cw = (
        float(csdf.origin[others[0]] + center[0] * h),
        float(csdf.origin[others[1]] + center[1] * h),
    )
    frame = RadialFrame(AXES[ax], cw, k, phase % 360.0 if k else 0.0, 0.0, res)
    from ..edit import radial_extent

    rad = radial_extent(csdf, frame.zone(0.0, 1.0, 2.0))
    return RadialFrame(frame.axis, frame.center, k, frame.phase, rad, res)


def radial_zones(csdf: CSDF, frame: RadialFrame) -> list[tuple[float, float]]:
    """The annuli of constant radial section of an object about its radial frame.

    Each is moved :data:`RING_INSET` voxels in from its ends (see module).

    Parameters
    ----------
    csdf : CSDF
        The object.
    frame : RadialFrame
        Its frame (:func:`find_radial`).

    Returns
    -------
    list of (float, float)
        ``(r0, r1)`` gauge radii (world units), longest first.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> slab = shapes.box((-0.5, 0, -0.5), (0.5, 0.1, 0.5), voxel_size=0.025)  # a square top
    >>> rings = zones.radial_zones(slab, zones.find_radial(slab))
    >>> all(0 <= r0 < r1 for r0, r1 in rings)
    True
    """
    ax = AXES.index(frame.axis)
    others = [a for a in range(3) if a != ax]
    h = csdf.voxel_size
    inside = np.moveaxis(np.asarray(csdf.sdf < 0), ax, -1)  # (U, V, levels)
    u = csdf.origin[others[0]] + np.arange(inside.shape[0]) * h - frame.center[0]
    v = csdf.origin[others[1]] + np.arange(inside.shape[1]) * h - frame.center[1]
    d = np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1)
    ring = np.floor(gauge(d, frame.sides, frame.phase) / h).astype(np.int64)  # (U, V)
    n_ring = int(ring.max()) + 1
    levels = inside.shape[2]
    # occupancy of each (ring, level): solid pixels over the ring's pixels
    count = np.bincount(ring.ravel(), minlength=n_ring).astype(np.float64)
    key = (ring[..., None] * levels + np.arange(levels)).ravel()
    solid = np.bincount(key[inside.ravel()], minlength=n_ring * levels).reshape(n_ring, levels)
    occ = solid / np.maximum(count, 1)[:, None]
    filled = occ.max(axis=1) > 0.5
    step = np.abs(np.diff(occ, axis=0)).max(axis=1)
    calm = (step < RING_STEP) & filled[:-1] & filled[1:]
    out = []
    i = 0
    while i < len(calm):
        if not calm[i]:
            i += 1
            continue
        j = i
        while j + 1 < len(calm) and calm[j + 1]:
            j += 1
        a, b = i + RING_INSET, j + 1 - RING_INSET  # rings i..j+1 alike; inset from both ends
        if b - a >= MIN_RING:
            out.append((a * h, b * h))
        i = j + 1
    out.sort(key=lambda z: z[0] - z[1])
    return out
