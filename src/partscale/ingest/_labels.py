"""Numba kernels over the labels of the far field's connected components: sizes, the
voxels whose winding number decides each component's side, and the sides painted back.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def label_stats(labels, key, n_labels, k):
    """Voxel count per label and the flat indices of each label's ``k`` largest ``key``.

    labels : (X, Y, Z) int32 (0: none); key : (X, Y, Z) float32, capped at 1e30. Ties go to
    the earlier voxel (C order). Returns size (n_labels + 1,) int64 and picks (M,) int64,
    label by label, largest first, M <= k * n_labels.
    """
    lab = labels.ravel()
    kv = key.ravel()
    cap = np.float32(1e30)
    size = np.zeros(n_labels + 1, np.int64)
    best = np.full((n_labels + 1, k), -1, np.int64)
    bestv = np.empty((n_labels + 1, k), np.float32)
    for p in range(lab.shape[0]):
        lb = lab[p]
        if lb <= 0:
            continue
        size[lb] += 1
        v = min(kv[p], cap)
        # insertion into the row, kept sorted by key descending (first come first on ties)
        pos = k
        while pos > 0 and (best[lb, pos - 1] < 0 or bestv[lb, pos - 1] < v):
            pos -= 1
        if pos < k:
            for q in range(k - 1, pos, -1):
                best[lb, q] = best[lb, q - 1]
                bestv[lb, q] = bestv[lb, q - 1]
            best[lb, pos] = p
            bestv[lb, pos] = v
    out = np.empty(n_labels * k, np.int64)
    m = 0
    for lbl in range(1, n_labels + 1):
        for q in range(k):
            if best[lbl, q] >= 0:
                out[m] = best[lbl, q]
                m += 1
    return size, out[:m]


@nb.njit(cache=True)
def random_picks(labels, start, count, rnd, size, extra):
    """Continue a scan of ``labels`` (X, Y, Z) int32 from flat index ``start`` over its next
    ``len(rnd)`` labelled voxels (``count`` seen before): voxel number n of the scan is picked
    where ``rnd[n - count] * size[label] < extra[label]``. Returns (picks (M,) int64 flat
    indices, the flat index to continue from).
    """
    lab = labels.ravel()
    out = np.empty(rnd.shape[0], np.int64)
    m = 0
    n = 0
    p = start
    while n < rnd.shape[0] and p < lab.shape[0]:
        lb = lab[p]
        if lb > 0:
            if rnd[n] * size[lb] < extra[lb]:
                out[m] = p
                m += 1
            n += 1
        p += 1
    return out[:m], p


@nb.njit(cache=True, parallel=True)
def paint_labels(labels, value, out):
    """``out[p] = value[labels[p]]`` where ``labels`` (X, Y, Z) int32 > 0 (in place)."""
    nx = labels.shape[0]
    for i in nb.prange(nx):
        for j in range(labels.shape[1]):
            for kk in range(labels.shape[2]):
                lb = labels[i, j, kk]
                if lb > 0:
                    out[i, j, kk] = value[lb]
