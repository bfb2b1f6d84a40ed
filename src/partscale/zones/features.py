"""Local features of a slab: what a whole-section comparison cannot see.

A knob, a handle or a keyhole is a few voxels of a cross-section of thousands: the soft Jaccard
distance between layers (:mod:`.profile`) barely moves across it, so a "constant" slab may hold
one, and stretching the slab squashes it into an oval or stretches it into a bar. Here each
voxel is compared with its own column along the axis instead (:func:`_feature_spans`); constant
slabs are cut around what is found (:func:`.suggest.constant_slabs`), and a user's stretch zone
that holds one is named (:func:`local_features`, :func:`feature_notes`).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..csdf import CSDF
from ..edit import Edit, Recipe, edit_label, unit_suffix
from .profile import _axis_index

#: Fewest voxels (at 128 voxels along the longest side) of a local feature a slab is split
#: around: a cabinet's knob or a keyhole is 36 to 60, the wear of worn wood at most about 25.
FEATURE_VOXELS = 27


def _feature_spans(csdf: CSDF, axis: int, first: int, last: int) -> list[tuple[int, int]]:
    """``(a, b)`` layer spans (inclusive, within ``first..last``) of the local features of the
    layers ``first..last``.

    A whole-section comparison cannot see a knob, a handle or a keyhole: a few voxels of a
    cross-section of thousands, which stretching would squash or smear. Here each voxel is
    compared with its own column along the axis. A voxel is in a bump when its occupancy is
    more than half a voxel above the lowest before it and the lowest after it within the run
    (a protrusion) or below the highest on both sides (a dip, a hole). A feature is a connected
    (26-neighbour) set of bump voxels that is

    - at least :func:`_feature_voxels` voxels (smaller sets are the noise of worn or scanned
      surfaces),
    - local: it spans at most half the run (a cushion's crown or a bowed board spans the run,
      and stretching it along the run keeps its look), and
    - sharp-edged: somewhere its occupancy changes by more than half a voxel from one layer to
      the next (a surface steeper than about 27 degrees to the axis: a knob's or a handle's
      flank, not a gentle bulge).

    A column that changes once (a splayed leg, an apron's curve, a bevel) is drift, which the
    whole-section test bounds.
    """
    h = np.float32(csdf.voxel_size)
    vmin = _feature_voxels(csdf)
    run = np.moveaxis(csdf.sdf, axis, 0)[first : last + 1]
    # only a column whose occupancy changes by more than half a voxel along the run can hold
    # a bump: most columns of a slab never do, so the rest of the work is on those alone
    occ_lo = np.clip(0.5 - run.max(axis=0) / h, 0.0, 1.0)
    occ_hi = np.clip(0.5 - run.min(axis=0) / h, 0.0, 1.0)
    cols = np.nonzero(occ_hi - occ_lo > 0.5)
    if cols[0].size == 0 or last - first < 2:
        return []
    occ = np.clip(0.5 - run[:, cols[0], cols[1]] / h, 0.0, 1.0)  # (L, K)
    jump = np.abs(np.diff(occ, axis=0))
    sharp = np.maximum(jump[:-1], jump[1:]) > 0.5  # (L - 2, K): at the inner layers
    # the run's two end layers may hold the edge of the next section (a side panel starting):
    # against them, a groove running the whole run would look like a dip, so they are no
    # reference
    inner = occ[1:-1]
    bump = (
        inner
        - np.maximum(
            np.minimum.accumulate(inner, axis=0), np.minimum.accumulate(inner[::-1], axis=0)[::-1]
        )
        > 0.5
    )
    bump |= (
        np.minimum(
            np.maximum.accumulate(inner, axis=0), np.maximum.accumulate(inner[::-1], axis=0)[::-1]
        )
        - inner
        > 0.5
    )
    if np.count_nonzero(bump & sharp) == 0 or np.count_nonzero(bump) < vmin:
        return []
    # label in the box of the columns that hold bumps, scattered back to their places
    hit = bump.any(axis=0)
    j, k = cols[0][hit], cols[1][hit]
    ja, ka = j.min(), k.min()
    box_shape = (len(inner), j.max() - ja + 1, k.max() - ka + 1)
    grid = np.zeros(box_shape, dtype=bool)
    grid[:, j - ja, k - ka] = bump[:, hit]
    edge = np.zeros(box_shape, dtype=bool)
    edge[:, j - ja, k - ka] = sharp[:, hit]
    lab, n = ndimage.label(grid, structure=np.ones((3, 3, 3)))
    size = np.bincount(lab.ravel())
    has_sharp = np.bincount(lab[edge], minlength=n + 1) > 0
    spans = sorted(
        (first + 1 + box[0].start, first + box[0].stop)  # inner layer 0 is layer first + 1
        for label, box in enumerate(ndimage.find_objects(lab), start=1)
        if size[label] >= vmin
        and has_sharp[label]
        and 2 * (box[0].stop - box[0].start) <= len(inner)
    )
    # features side by side across the section (a pair of knobs) share layers: one span each
    out: list[tuple[int, int]] = []
    for a, b in spans:
        if out and a <= out[-1][1] + 1:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
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


def _feature_voxels(csdf: CSDF) -> int:
    """Fewest voxels of a local feature (:func:`_feature_spans`).

    :data:`FEATURE_VOXELS` at 128 voxels along the longest side, scaled with the voxel volume so
    that a feature is the same share of the object at every resolution.
    """
    return max(8, round(FEATURE_VOXELS * (max(csdf.shape) / 128) ** 3))


def feature_notes(csdf: CSDF, recipe: Recipe) -> list[str]:
    """One line per stretch edit of ``recipe`` whose zone holds a local feature
    (:func:`local_features`): it is stretched with the zone, out of shape. Zones are read on
    ``csdf``, the recipe's input (recipe coordinates)."""
    sb = csdf.surface_bounds()
    units = csdf.meta.get("units")
    u = unit_suffix(units)
    lines = []
    for i, e in enumerate(recipe.edits):
        if not isinstance(e, Edit) or e.mode != "stretch":
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
