"""Which voxels of a planar edit's output must be re-evaluated (:func:`recompute_mask`).

The paper's rule (voxels whose old distance reaches the zone's planes, and the resampled slab),
less those provably unchanged: a growing slab keeps the distance of a voxel whose nearest
surface point lies square to the axis; a tile copy at scale ~1 keeps the voxels whose distance
ball stays within their copy. Used by :mod:`partscale.edit.scale`.
"""

from __future__ import annotations

import numba
import numpy as np

from .resample import SEAM_VOXELS, Plan

#: An axial slope of the source distance below this counts as "nearest surface point lateral".
_LATERAL = 0.05

#: A slab scaled by less than this relative amount counts as rigid (error <= 1% of |distance|,
#: 0.04 voxel at the band's edge): tiles of whole periods are copies, not stretches.
_RIGID = 0.01
#: voxels either side of a tile seam whose zero level the seam may change: the blend window
#: (SEAM_VOXELS) and the cells it shares with the next layer
_CHANGED_VOXELS = SEAM_VOXELS + 1.0


def recompute_mask(
    src_sdf: np.ndarray,
    out_sdf: np.ndarray,
    plan: Plan,
    *,
    mode: str,
    y: np.ndarray,
    start: float,
    end: float,
    dest: float,
    h: float,
    band: float,
) -> tuple[np.ndarray, int]:
    """Voxels (axis-first, output grid) whose distance could have changed and must be recomputed.

    Returns ``(mask, j0)``: ``mask`` (uint8) covers output layers ``j0 ...`` only (those within
    reach of the edit; the layers beyond have nothing to recompute).

    The paper's rule: voxels whose old |distance| exceeds their distance to the zone's planes, plus
    the resampled slab. Among those, a voxel keeps its resampled value when that value is provably
    still the distance: the slab grows (scale >= 1, so the inverse map is 1-Lipschitz and old
    distances are lower bounds) and its nearest surface point lies square to the axis (axial slope
    of the source distance ~ 0), so its distance is carried over unchanged; or, in a tile copy at
    scale ~1, the ball of its distance lies within its copy (a pure translation). A removed zone
    (tile, 0 copies) is one join at START: only voxels whose ball reaches it are recomputed.
    """
    lim = (band + 1.0) * h * max(1.0, 1.0 / plan.scale)
    none = np.zeros((0, *out_sdf.shape[1:]), np.uint8), 0
    n_copies = int(plan.copy.max()) + 1
    if mode == "tile" and abs(plan.scale - 1.0) <= _RIGID:
        # Copies at scale ~1 are translations of the slab, and the first and last copy continue
        # the content before and after the zone exactly: a voxel's neighbourhood is unchanged
        # unless the ball of its distance reaches an internal seam (or it lies in a blend).
        if dest == start:  # 0 copies: the two sides meet at START, whose distances may change
            seams = np.array([start])
        else:
            seams = start + (dest - start) / n_copies * np.arange(1, n_copies)
        if seams.size == 0:
            return none
        to_seam = np.abs(y[:, None] - seams[None, :]).min(axis=1)
        # the blend changes voxels up to SEAM_VOXELS from a seam, and so the zero level (the
        # marching-cubes surface distances are taken to) in the cells they share with the
        # layer beyond: one voxel more
        reach = np.maximum(to_seam - _CHANGED_VOXELS * h, 0.0).astype(np.float32)
        rows = np.flatnonzero(reach <= lim)
        if rows.size == 0:
            return none
        j0 = int(rows[0])
        mask = np.zeros((int(rows[-1]) + 1 - j0, *out_sdf.shape[1:]), np.uint8)
        a = np.abs(out_sdf[rows])
        mask[rows - j0] = (a <= lim) & (a >= reach[rows, None, None])
        return mask, j0
    if mode == "global":
        j0, j1 = 0, out_sdf.shape[0]
        gap = np.zeros(j1, np.float32)  # |sdf| >= 0 always: only the band counts
    else:
        # distance of each output layer to the zone (0 inside the slab), one voxel of slack;
        # layers farther from the zone than the band cannot be affected
        gap = np.where(y < start, start - y, np.where(y > dest, y - dest, 0.0))
        gap = np.maximum(gap - h, 0.0).astype(np.float32)
        rows = np.flatnonzero(gap <= lim)
        if rows.size == 0:
            return none
        j0, j1 = int(rows[0]), int(rows[-1]) + 1
    row = np.arange(j0, j1)
    n_src = src_sdf.shape[0]
    xc = np.clip(plan.xa[row], 0, n_src - 1)
    i0 = np.floor(xc).astype(np.int64)
    i1 = np.minimum(i0 + 1, n_src - 1)
    if plan.scale < 1.0 - _RIGID:
        # A shrinking slab can bring surface closer: everything affected is recomputed. Outside
        # the slab, a voxel whose nearest point is square to the axis still has that point, so
        # its old distance caps the new one (code 2): the exact value wherever nothing came
        # closer, immune to the facets' chamfer of sharp edges.
        rule, room = _SHRINK, np.zeros(0)
    elif mode == "tile":
        # Copies are not one monotone map: a slab voxel keeps its value only if the ball of its
        # distance stays inside its own copy (and it is not in a seam blend). Voxels outside the
        # slab see every copy farther than its source, so the growth argument holds for them.
        # (Copies at scale ~1, translations, were handled above.)
        rule = _TILE
        period = (dest - start) / n_copies
        yy, c = y[row], plan.copy[row]
        room = np.minimum(yy - (start + c * period), start + (c + 1) * period - yy)
        room = room - _CHANGED_VOXELS * h  # the ball must stay clear of the seam's changes
    else:
        rule, room = _GROW, np.zeros(0)
    mask = np.zeros((j1 - j0, *out_sdf.shape[1:]), np.uint8)
    # first and last marked layer of each row of the cross-section (nj, -1 where none)
    first = np.full(mask.shape[1], j1 - j0, np.int64)
    last = np.full(mask.shape[1], -1, np.int64)
    _mask_rows(
        src_sdf,
        out_sdf,
        j0,
        i0,
        i1,
        gap[j0:j1],
        np.float32(lim),
        np.float32(_LATERAL),
        h,
        rule,
        plan.in_slab[row],
        plan.beta[row] == 0,
        room,
        mask,
        first,
        last,
    )
    lo, hi = int(first.min()), int(last.max())
    if hi < lo:
        return none
    # only the layers holding marks travel on (a view): the rest of the band needs nothing
    return mask[lo : hi + 1], j0 + lo


# rules of _mask_rows: how a voxel whose nearest point is square to the axis is treated
_GROW, _SHRINK, _TILE = 0, 1, 2


@numba.njit(cache=True, parallel=True)
def _mask_rows(
    src, out, j0, i0, i1, gap, lim, lateral, h, rule, in_slab, unblended, room, mask, first, last
):
    """:func:`recompute_mask`'s per-voxel rule over output layers ``j0 ...`` (into ``mask``).

    A voxel is affected where ``gap[j] <= |sdf| <= lim``; its axial slope is the largest
    central difference of the source at the layers ``i0[j]``, ``i1[j]`` it was read from (as
    float32, exactly the vectorised rule's arithmetic); slope <= ``lateral`` keeps it (per
    ``rule``), else it is marked 1. ``_SHRINK`` marks every affected voxel: 2 where it is kept
    outside the slab, else 1. ``first[a]``, ``last[a]``: the first and last layer marked in
    row ``a`` of the cross-section (left as they are where none).
    """
    nj, na, nb_ = mask.shape[0], mask.shape[1], mask.shape[2]
    n_src = src.shape[0]
    for a in numba.prange(na):
        for jj in range(nj):
            j = j0 + jj
            g0 = gap[jj]
            for b in range(nb_):
                v = abs(out[j, a, b])
                if not (v <= lim and v >= g0):
                    continue
                slope = np.float32(0.0)
                for i in (i0[jj], i1[jj]):
                    up = min(i + 1, n_src - 1)
                    dn = max(i - 1, 0)
                    g = np.float64(src[up, a, b] - src[dn, a, b]) / max((up - dn) * h, h)
                    slope = np.float32(max(np.float64(slope), abs(g)))
                keep = slope <= lateral
                if rule == _SHRINK:
                    mask[jj, a, b] = 2 if keep and not in_slab[jj] else 1
                    first[a] = min(first[a], jj)
                    last[a] = jj
                    continue
                if rule == _TILE and in_slab[jj]:
                    keep = keep and unblended[jj] and np.float64(v) < room[jj]
                if not keep:
                    mask[jj, a, b] = 1
                    first[a] = min(first[a], jj)
                    last[a] = jj
