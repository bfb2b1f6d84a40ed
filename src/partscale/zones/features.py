"""Local features of a slab: what a whole-section comparison cannot see.

A knob, a handle, a hinge, a keyhole or a printed motif is a few voxels of a cross-section of
thousands: the soft Jaccard distance between layers (:mod:`.profile`) barely moves across it, so
a "constant" slab may hold one, and stretching the slab squashes it into an oval or smears it
into a bar. Here each voxel is compared with its own column along the axis instead
(:func:`run_features`), in shape and in colour; constant slabs are cut around what is found
(:func:`.suggest.constant_slabs`), tile planes are kept off it (:func:`.suggest.axis_candidates`)
and a user's stretch zone that holds one is named (:func:`local_features`,
:func:`feature_notes`).

RULE
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import ndimage

from ..csdf import BAND_VOXELS, CSDF
from ..edit import Recipe, edit_label, unit_suffix
from .profile import _axis_index

#: Voxels along the longest side at which the sizes below are given; they scale with it, so a
#: feature is the same share of the object at every resolution.
REFERENCE_VOXELS = 128
#: A shape feature moves the surface by more than this many voxels (at 128) somewhere.
FEATURE_HEIGHT = 1.0
#: Fewest voxels (at 128) of a feature: a knob 2 voxels across.
FEATURE_VOXELS = 2
#: A colour motif differs from its column on both sides by more than this in some sRGB channel
#: (of 255).
COLOUR_CONTRAST = 40.0
#: A colour motif is at least this many voxels (at 128) across in every direction (along the
#: axis, across the face and through the voxels within a voxel of it): no line of a texture.
MOTIF_ACROSS = 2
#: The share of a run's surface voxels whose detail is its finish: the strongest this share of
#: the surface reaches (its wear, grain or noise), which a feature must exceed ...
NOISE_SHARE = 0.02
#: ... by this factor.
NOISE_MARGIN = 2.0


@dataclass(frozen=True)
class Feature:
    """A local feature of a run of layers along an axis (:func:`run_features`).

    Attributes
    ----------
    first, last : int
        Its layers along the axis (inclusive).
    kind : {'shape', 'colour'}
        Found in the solid (a knob, a handle, a keyhole) or in the colour alone (a motif).
    across : ((int, int), (int, int))
        Its extent across the axis: inclusive index ranges along the other two axes, in order.
    voxels : int
        How many voxels it holds.
    """

    first: int
    last: int
    kind: Literal["shape", "colour"]
    across: tuple[tuple[int, int], tuple[int, int]]
    voxels: int


def _envelope_excess(x: np.ndarray) -> np.ndarray:
    """(L, K) how far each value of the columns ``x`` (L, K) stands above the lowest value
    before it and the lowest after it, or below the highest before and the highest after
    (whichever is more): a bump or a dip of the column, 0 on a monotone run."""
    lo = np.maximum(np.minimum.accumulate(x, axis=0), np.minimum.accumulate(x[::-1], axis=0)[::-1])
    hi = np.minimum(np.maximum.accumulate(x, axis=0), np.maximum.accumulate(x[::-1], axis=0)[::-1])
    return np.maximum(x - lo, hi - x)


def _noise(values: np.ndarray, n_surface: int) -> float:
    """The value the strongest :data:`NOISE_SHARE` of ``n_surface`` surface voxels reach, given
    ``values`` (the measure at those of them that can reach any; the rest count as 0)."""
    k = int(NOISE_SHARE * n_surface)
    if k < 1 or values.size < k:
        return 0.0
    return float(np.partition(values.ravel(), values.size - k)[values.size - k])


def _components(
    bump: np.ndarray,
    sharp: np.ndarray,
    peak: np.ndarray,
    threshold: float,
    cols: tuple[np.ndarray, np.ndarray],
    first: int,
    vmin: int,
    kind: Literal["shape", "colour"],
) -> list[Feature]:
    """The features among the connected (26-neighbour) sets of ``bump`` voxels (L, K: inner
    layers by columns ``cols``): at least ``vmin`` voxels, local (at most half the ``L`` layers
    long), holding a ``sharp`` voxel and one whose ``peak`` exceeds ``threshold``."""
    hit = bump.any(axis=0)
    if not hit.any():
        return []
    # label in the box of the columns that hold bumps, scattered back to their places
    j, k = cols[0][hit], cols[1][hit]
    ja, ka = int(j.min()), int(k.min())
    shape = (bump.shape[0], int(j.max()) - ja + 1, int(k.max()) - ka + 1)

    def scatter(a: np.ndarray) -> np.ndarray:
        g = np.zeros(shape, dtype=a.dtype)
        g[:, j - ja, k - ka] = a[:, hit]
        return g

    lab, n = ndimage.label(scatter(bump), structure=np.ones((3, 3, 3)))
    if n == 0:
        return []
    inside = lab > 0
    at = lab[inside]
    size = np.bincount(at, minlength=n + 1)
    has_sharp = np.bincount(at, weights=scatter(sharp)[inside], minlength=n + 1) > 0
    top = np.zeros(n + 1)
    np.maximum.at(top, at, scatter(peak)[inside])
    out = []
    for label, box in enumerate(ndimage.find_objects(lab), start=1):
        if box is None:
            continue
        length = box[0].stop - box[0].start
        if (
            size[label] >= vmin
            and has_sharp[label]
            and top[label] > threshold
            and 2 * length <= bump.shape[0]
        ):
            out.append(
                Feature(
                    first + 1 + box[0].start,  # inner layer 0 is layer first + 1
                    first + box[0].stop,
                    kind,
                    (
                        (ja + box[1].start, ja + box[1].stop - 1),
                        (ka + box[2].start, ka + box[2].stop - 1),
                    ),
                    int(size[label]),
                )
            )
    return out


def _shape_features(
    csdf: CSDF, axis: int, first: int, last: int, height: float, vmin: int
) -> list[Feature]:
    """The shape features of layers ``first..last`` (see :func:`run_features`)."""
    h = np.float32(csdf.voxel_size)
    run = np.moveaxis(csdf.sdf, axis, 0)[first : last + 1]
    # only a column whose occupancy changes by more than half a voxel along the run can hold
    # a bump: most columns of a slab never do, so the rest of the work is on those alone
    occ_lo = np.clip(0.5 - run.max(axis=0) / h, 0.0, 1.0)
    occ_hi = np.clip(0.5 - run.min(axis=0) / h, 0.0, 1.0)
    cols = np.nonzero(occ_hi - occ_lo > 0.5)
    if cols[0].size == 0:
        return []
    s = np.clip(run[:, cols[0], cols[1]] / h, -BAND_VOXELS, BAND_VOXELS)  # (L, K) voxels
    occ = np.clip(0.5 - s, 0.0, 1.0)
    jump = np.abs(np.diff(occ, axis=0))
    sharp = np.maximum(jump[:-1], jump[1:]) > 0.5  # (L - 2, K): at the inner layers
    # the run's two end layers may hold the edge of the next section (a side panel starting):
    # against them, a groove running the whole run would look like a dip, so they are no
    # reference
    bump = _envelope_excess(occ[1:-1]) > 0.5
    if not bump.any():
        return []
    # how far the surface moved there (unclipped distances: a bump a voxel or more high)
    moved = _envelope_excess(-s[1:-1])
    # the run's surface voxels: its cross-sections barely change, so its middle layer's times
    # its inner layers
    n_surface = (len(run) - 2) * int(np.count_nonzero(np.abs(run[len(run) // 2]) <= h))
    noise = _noise(moved[np.abs(s[1:-1]) <= 1.0], n_surface)
    threshold = max(height, NOISE_MARGIN * noise)
    return _components(bump, sharp, moved, threshold, cols, first, vmin, "shape")


def _colour_features(csdf: CSDF, axis: int, first: int, last: int, vmin: int) -> list[Feature]:
    """The colour motifs of layers ``first..last`` (see :func:`run_features`)."""
    h = np.float32(csdf.voxel_size)
    run = np.moveaxis(csdf.sdf, axis, 0)[first : last + 1]
    # columns along a face: within a voxel of the surface at every inner layer
    mid = np.nonzero(np.abs(run[len(run) // 2]) <= h)
    face = (np.abs(run[1:-1, mid[0], mid[1]]) <= h).all(axis=0)
    if not face.any():
        return []
    n_face = (len(run) - 2) * int(np.count_nonzero(face))
    rgb = np.moveaxis(csdf.rgb, axis, 0)[first : last + 1][:, mid[0][face], mid[1][face]]
    # only a column whose colour spans more than the least threshold's share of the noise can
    # reach it (the rest stay below it, and below what sets the noise's level there)
    span = (rgb.max(axis=0).astype(np.int16) - rgb.min(axis=0)).max(axis=1)
    keep = span > COLOUR_CONTRAST / NOISE_MARGIN
    if not keep.any():
        return []
    cols = (mid[0][face][keep], mid[1][face][keep])
    rgb = rgb[:, keep].astype(np.float32)  # (L, K, 3)
    inner = rgb[1:-1]
    dev = np.max([_envelope_excess(inner[..., c]) for c in range(3)], axis=0)  # (L - 2, K)
    threshold = max(COLOUR_CONTRAST, NOISE_MARGIN * _noise(dev, n_face))
    bump = dev > threshold
    if not bump.any():
        return []
    jump = np.abs(np.diff(rgb, axis=0)).max(axis=2) > threshold
    sharp = jump[:-1] | jump[1:]
    return _components(bump, sharp, dev, threshold, cols, first, vmin, "colour")


def run_features(csdf: CSDF, axis: int, first: int, last: int) -> list[Feature]:
    """The local features of layers ``first..last`` (inclusive) along ``axis`` (0, 1, 2), a
    run whose whole cross-sections barely change (see the module docstring for the rule), in
    order of their first layer.

    Each voxel is compared with its own column along the axis, inside the run. In shape, a
    voxel is in a bump when its occupancy stands more than half a voxel above the lowest
    before it and the lowest after it (a protrusion) or below the highest on both sides (a
    dip, a hole); in colour, a voxel within a voxel of a face is in a motif when some channel
    stands more than the colour threshold above or below its column on both sides in the same
    way. A feature is a connected (26-neighbour) set of such voxels that is

    - at least :data:`FEATURE_VOXELS` voxels (at 128),
    - local: it spans at most half the run (a cushion's crown or a bowed board spans the run,
      and stretching it along the run keeps its look),
    - sharp-edged: somewhere its occupancy changes by more than half a voxel (its colour by
      more than the threshold) from one layer to the next (a surface steeper than about 27
      degrees to the axis: a knob's or a handle's flank, not a gentle bulge), and
    - above the run's noise: the surface moves more than :data:`FEATURE_HEIGHT` voxels (at
      128) there (a colour more than :data:`COLOUR_CONTRAST`), and more than
      :data:`NOISE_MARGIN` times what the run's strongest :data:`NOISE_SHARE` of surface voxels
      reach (the finish of a worn, grained or scanned surface).

    A column that changes once (a splayed leg, an apron's curve, a bevel, one colour meeting
    another) is drift, which the whole-section test bounds.
    """
    if last - first < 2:
        return []
    scale = max(csdf.shape) / REFERENCE_VOXELS
    vmin = max(2, round(FEATURE_VOXELS * scale**3))
    found = _shape_features(csdf, axis, first, last, FEATURE_HEIGHT * scale, vmin)
    across = max(2, round(MOTIF_ACROSS * scale))
    found += [
        f
        for f in _colour_features(csdf, axis, first, last, vmin)
        if min(f.last - f.first, *(b - a for a, b in f.across)) + 1 >= across
    ]
    return sorted(found, key=lambda f: (f.first, f.last))


def _feature_spans(csdf: CSDF, axis: int, first: int, last: int) -> list[tuple[int, int]]:
    """``(a, b)`` layer spans (inclusive, within ``first..last``) of the local features of the
    layers ``first..last`` (:func:`run_features`); features side by side across the section
    (a pair of knobs) share one span."""
    out: list[tuple[int, int]] = []
    for f in run_features(csdf, axis, first, last):
        if out and f.first <= out[-1][1] + 1:
            out[-1] = (out[-1][0], max(out[-1][1], f.last))
        else:
            out.append((f.first, f.last))
    return out


def local_features(
    csdf: CSDF, axis: str | int, zone: tuple[float, float]
) -> list[tuple[float, float]]:
    """World ``(start, end)`` spans along ``axis`` (x, y, z or 0, 1, 2) of the local features (a
    knob, a handle, a keyhole: :func:`_feature_spans`) between the planes of ``zone`` (world
    units): what stretching that zone would stretch out of shape. Empty for a zone of constant
    section."""
    ax = _axis_index(axis)
    h = csdf.voxel_size
    o = float(csdf.origin[ax])
    first = max(int(np.ceil((zone[0] - o) / h - 1e-6)), 0)
    last = min(int(np.floor((zone[1] - o) / h + 1e-6)), csdf.shape[ax] - 1)
    if last - first < 2:
        return []
    return [(o + a * h, o + b * h) for a, b in _feature_spans(csdf, ax, first, last)]


def feature_notes(csdf: CSDF, recipe: Recipe) -> list[str]:
    """One line per stretch edit of ``recipe`` whose zone holds a local feature
    (:func:`local_features`): it is stretched with the zone, out of shape. Zones are read on
    ``csdf``, the recipe's input (recipe coordinates)."""
    sb = csdf.surface_bounds()
    units = csdf.meta.get("units")
    u = unit_suffix(units)
    lines = []
    for i, e in enumerate(recipe.edits):
        if e.mode != "stretch":
            continue
        ax = e.axis_index
        s, en, _ = e.resolve(float(sb[0, ax]), float(sb[1, ax]))
        found = local_features(csdf, ax, (s, en))
        if not found:
            continue
        where = ", ".join(f"{a:.4g}..{b:.4g}" for a, b in found)
        lines.append(
            f"{edit_label(i, len(recipe.edits))}the stretch zone "
            f"{s:.4g}..{en:.4g}{u} along {e.axis} holds {len(found)} local feature"
            f"{'s' if len(found) > 1 else ''} (a knob, a handle) at {where}{u}, stretched out "
            f"of shape with it; --snap (the editor's snapping) moves the zone into a constant slab"
        )
    return lines
