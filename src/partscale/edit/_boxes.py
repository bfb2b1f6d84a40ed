"""The boxes of a re-evaluation: their targets, relays and fields (numba kernels).

Targets are the voxels of the mask within the band; a box holds a run of target layers and
every surface point within the band of them; relays are the band voxels near its targets, the
only ones the propagation (:mod:`partscale.edit._propagate`) visits. Used by
:mod:`partscale.edit.reevaluate`.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def target_layers(sdf, mask, row0, lim):
    """Targets of :func:`reevaluate_arrays`: ``mask`` (M, Y, Z) uint8 nonzero where
    ``|sdf[row0 + m]| <= lim`` (float32).

    Returns ``(count (M,) int64, bounds (M, 4) int64)``: per layer, its number of targets and
    their first and last index along axes 1 and 2 (``Y, -1, Z, -1`` where none).
    """
    nm, na, nb = mask.shape
    count = np.zeros(nm, np.int64)
    bounds = np.empty((nm, 4), np.int64)
    for m in range(nm):
        c, a0, a1, b0, b1 = 0, na, -1, nb, -1
        for a in range(na):
            for b in range(nb):
                if mask[m, a, b] != 0 and abs(sdf[row0 + m, a, b]) <= lim:
                    c += 1
                    a0 = min(a0, a)
                    a1 = a
                    b0 = min(b0, b)
                    b1 = max(b1, b)
        count[m] = c
        bounds[m, 0], bounds[m, 1], bounds[m, 2], bounds[m, 3] = a0, a1, b0, b1
    return count, bounds


@numba.njit(cache=True, nogil=True)
def box_targets(sdf, mask, row0, lim, lo, shape):
    """(shape) uint8: 1 at the targets (see :func:`target_layers`) of the box at ``lo``."""
    out = np.zeros((shape[0], shape[1], shape[2]), np.uint8)
    for i in range(shape[0]):
        m = lo[0] + i - row0
        if m < 0 or m >= mask.shape[0]:
            continue
        for j in range(shape[1]):
            for k in range(shape[2]):
                if (
                    mask[m, lo[1] + j, lo[2] + k] != 0
                    and abs(sdf[lo[0] + i, lo[1] + j, lo[2] + k]) <= lim
                ):
                    out[i, j, k] = 1
    return out


@numba.njit(cache=True, nogil=True)
def _dilate_last(a, r):
    """(X, Y, Z) uint8: 1 where ``a`` has a nonzero within ``r`` along the last axis (zero
    beyond the ends).
    """
    nx, ny, nz = a.shape
    out = np.zeros((nx, ny, nz), np.uint8)
    for i in range(nx):
        for j in range(ny):
            last = -(r + 1)  # the latest nonzero at or before k
            for k in range(nz + r):
                if k < nz and a[i, j, k] != 0:
                    last = k
                if k - r >= 0 and k - last <= 2 * r:
                    out[i, j, k - r] = 1
    return out


@numba.njit(cache=True, nogil=True)
def relays(sub, t_box, r, lim):
    """Ascending flat indices of the box's voxels with ``|sub| <= lim`` (float32) within
    Chebyshev distance ``r`` of a target of ``t_box``.
    """
    reach = _dilate_last(t_box, r)
    reach = _dilate_last(reach.transpose(0, 2, 1), r).transpose(0, 2, 1)
    reach = _dilate_last(reach.transpose(2, 1, 0), r).transpose(2, 1, 0)
    nx, ny, nz = sub.shape
    out = np.empty(sub.size, np.int64)
    n = 0
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                if reach[i, j, k] != 0 and abs(sub[i, j, k]) <= lim:
                    out[n] = (i * ny + j) * nz + k
                    n += 1
    return out[:n]


@numba.njit(cache=True, nogil=True)
def box_copy(sdf, lo, hi):
    """(hi - lo) float32: a copy of box ``lo ... hi - 1`` of ``sdf``."""
    return sdf[lo[0] : hi[0], lo[1] : hi[1], lo[2] : hi[2]].astype(np.float32)


@numba.njit(cache=True, nogil=True)
def layer_targets(t_box, i0, i1):
    """Ascending flat indices of the nonzeros of ``t_box`` (X, Y, Z) uint8 in layers
    ``i0 ... i1 - 1``.
    """
    flat = t_box.reshape(-1)
    syz = t_box.shape[1] * t_box.shape[2]
    a, b = max(i0, 0) * syz, min(i1, t_box.shape[0]) * syz
    out = np.empty(max(b - a, 0), np.int64)
    n = 0
    for f in range(a, b):
        out[n] = f
        n += flat[f] != 0
    return out[:n]
