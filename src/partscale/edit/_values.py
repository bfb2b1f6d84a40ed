"""What re-evaluated voxels take from their nearest surface point: distance, colour and part,
and the writes (numba kernels). Used by :mod:`partscale.edit.reevaluate`.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def box_values(
    sdf,
    rgb,
    parts,
    mask,
    row0,
    capping,
    sub,
    tri,
    best_d2,
    best_t,
    best_vw,
    wanted,
    lo,
    h,
    use_far,
    far,
):
    """What the ``wanted`` voxels (flat indices of the box ``sub`` at ``lo``) that found a
    triangle take: ``(gi (N, 3) int64, distance (N,) float32, colour (N, 3) uint8, part (N,))``,
    colour and part at their closest point, less the code-2 voxels that keep their value; see
    :func:`reevaluate_arrays`. Reads the arrays only (every box's values come before any write:
    no voxel sees another's new colour).
    """
    ny, nz = sub.shape[1], sub.shape[2]
    syz, nzu = np.uint64(ny * nz), np.uint64(nz)
    m = wanted.shape[0]
    gi = np.empty((m, 3), np.int64)
    new = np.empty(m, np.float32)
    col8 = np.empty((m, 3), np.uint8)
    new_parts = np.empty(m, parts.dtype)
    col = np.empty(3)
    n = 0
    for f in wanted:
        t = best_t[f]
        if t < 0:
            continue
        # unsigned division: numba's signed one also corrects the rounding of negatives
        fu = np.uint64(f)
        r = fu % syz
        i, j, k = np.int64(fu // syz), np.int64(r // nzu), np.int64(r % nzu)
        old = sub[i, j, k]
        sign = -1.0 if old <= 0 else 1.0  # sdf <= 0 is inside
        d = np.float32(sign * np.sqrt(best_d2[f]) * h)
        # a voxel the surface passes through stays on its side (outside: > 0), never flips
        d = old if sign > 0 and d <= 0 else d
        gx, gy, gz = lo[0] + i, lo[1] + j, lo[2] + k
        # code 2 (uint8 masks): the old value is an upper bound of the distance, kept where
        # smaller
        if capping and mask[gx - row0, gy, gz] == 2 and abs(old) <= abs(d):
            continue
        # the closest point from its barycentrics, kept by the propagation
        v, w = np.float64(best_vw[f, 0]), np.float64(best_vw[f, 1])
        qx = tri[t, 0] + v * (tri[t, 3] - tri[t, 0]) + w * (tri[t, 6] - tri[t, 0]) + lo[0]
        qy = tri[t, 1] + v * (tri[t, 4] - tri[t, 1]) + w * (tri[t, 7] - tri[t, 1]) + lo[1]
        qz = tri[t, 2] + v * (tri[t, 5] - tri[t, 2]) + w * (tri[t, 8] - tri[t, 2]) + lo[2]
        part = _colour_and_part(sdf, rgb, parts, qx, qy, qz, col)
        if use_far and d > far and (d != old or part != parts[gx, gy, gz]):
            part = -1
        gi[n, 0], gi[n, 1], gi[n, 2] = gx, gy, gz
        new[n] = d
        for c in range(3):
            col8[n, c] = np.uint8(min(max(np.rint(col[c]), 0.0), 255.0))
        new_parts[n] = part
        n += 1
    return gi[:n], new[:n], col8[:n], new_parts[:n]


@numba.njit(cache=True, nogil=True, inline="always")
def _colour_and_part(sdf, rgb, parts, x, y, z, col):
    """Colour and part of the surface point ``(x, y, z)`` (continuous indices, within the grid;
    every axis of 2 voxels or more), from the 8 corners of its cell in one pass.

    ``col`` (3,) float64 receives the trilinear colour of ``rgb``: the weights of
    :func:`~partscale._kernels.trilinear_at`, computed here in the same pass over the corners as
    the part (calling it besides cost 3 ms of a box's 17 on the cabinet shrink at 128). The part
    is the label of the nearest inside
    (``sdf <= 0``) corner: the solid carries the parts; an outside corner's label is only its
    nearest part, and where a node lies exactly on the surface (``sdf == 0``, e.g. grid-aligned
    faces) the nearest corner can be an outside one labelled with another part. A point whose
    cell has no inside corner (none after marching cubes, kept for safety) takes the nearest
    corner.
    """
    nx, ny, nz = sdf.shape
    cx = min(max(x, 0.0), nx - 1.0)
    cy = min(max(y, 0.0), ny - 1.0)
    cz = min(max(z, 0.0), nz - 1.0)
    i0, j0, k0 = min(int(cx), nx - 2), min(int(cy), ny - 2), min(int(cz), nz - 2)
    fx, fy, fz = cx - i0, cy - j0, cz - k0
    # fallback: the nearest corner whatever its side
    pi = min(max(int(np.rint(x)), 0), nx - 1)
    pj = min(max(int(np.rint(y)), 0), ny - 1)
    pk = min(max(int(np.rint(z)), 0), nz - 1)
    best = np.inf
    col[0] = col[1] = col[2] = 0.0
    for di in range(2):
        wx = fx if di else 1.0 - fx
        ex = (i0 + di - x) ** 2
        for dj in range(2):
            wxy = wx * (fy if dj else 1.0 - fy)
            exy = ex + (j0 + dj - y) ** 2
            for dk in range(2):
                qi, qj, qk = i0 + di, j0 + dj, k0 + dk
                w = wxy * (fz if dk else 1.0 - fz)
                if w != 0.0:
                    for c in range(3):
                        col[c] += w * rgb[qi, qj, qk, c]
                d2 = exy + (qk - z) ** 2
                if sdf[qi, qj, qk] <= 0 and d2 < best:
                    best = d2
                    pi, pj, pk = qi, qj, qk
    return parts[pi, pj, pk]


@numba.njit(cache=True, nogil=True)
def write(sdf, rgb, parts, gi, new, col, new_parts):
    """Write distances ``new``, colours ``col`` (N, 3) uint8 and parts at voxels ``gi`` (N, 3)."""
    for q in range(gi.shape[0]):
        i, j, k = gi[q, 0], gi[q, 1], gi[q, 2]
        sdf[i, j, k] = new[q]
        for c in range(3):
            rgb[i, j, k, c] = col[q, c]
        parts[i, j, k] = new_parts[q]
