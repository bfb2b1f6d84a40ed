"""Numba geometry kernels shared by the stages (import, re-evaluation, meshing).

Coordinates are whatever the caller uses (world units or continuous voxel indices); only
the trilinear samplers read a grid, at continuous voxel indices: :func:`trilinear` (many points,
every channel), :func:`trilinear_at` (one point, every channel, summed into a buffer) and
:func:`trilinear_point` (one point of a single-channel grid, the renderer's ray marcher).
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True, inline="always")
def closest_on_triangle(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """Squared distance from p to triangle abc and the closest point's barycentrics (u, v, w).

    The closest point is ``u a + v b + w c``. Ericson, Real-Time Collision Detection, 5.1.5
    (region tests on the Voronoi regions of the vertices, edges and face). A degenerate triangle
    falls back to its first vertex.
    """
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        u, v, w = 1.0, 0.0, 0.0
    else:
        bpx, bpy, bpz = px - bx, py - by, pz - bz
        d3 = abx * bpx + aby * bpy + abz * bpz
        d4 = acx * bpx + acy * bpy + acz * bpz
        cpx, cpy, cpz = px - cx, py - cy, pz - cz
        d5 = abx * cpx + aby * cpy + abz * cpz
        d6 = acx * cpx + acy * cpy + acz * cpz
        vc = d1 * d4 - d3 * d2
        vb = d5 * d2 - d1 * d6
        va = d3 * d6 - d5 * d4
        if d3 >= 0.0 and d4 <= d3:
            u, v, w = 0.0, 1.0, 0.0
        elif d6 >= 0.0 and d5 <= d6:
            u, v, w = 0.0, 0.0, 1.0
        elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            den = d1 - d3
            t = d1 / den if den != 0.0 else 0.0
            u, v, w = 1.0 - t, t, 0.0
        elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
            den = d2 - d6
            t = d2 / den if den != 0.0 else 0.0
            u, v, w = 1.0 - t, 0.0, t
        elif va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
            den = (d4 - d3) + (d5 - d6)
            t = (d4 - d3) / den if den != 0.0 else 0.0
            u, v, w = 0.0, 1.0 - t, t
        else:
            den = va + vb + vc
            if den <= 0.0:
                u, v, w = 1.0, 0.0, 0.0
            else:
                v = vb / den
                w = vc / den
                u = 1.0 - v - w
    qx = ax + v * abx + w * acx
    qy = ay + v * aby + w * acy
    qz = az + v * abz + w * acz
    dx, dy, dz = px - qx, py - qy, pz - qz
    return dx * dx + dy * dy + dz * dz, u, v, w


@nb.njit(cache=True, inline="always")
def grid_cell(x, n):
    """The cell of a continuous voxel index ``x`` on an axis of ``n`` voxels: the lower corner
    index and the fraction past it, ``x`` clamped to the grid (the last cell holds ``n - 1``,
    fraction 1; a one-voxel axis has the cell 0, fraction 0)."""
    if x < 0.0:
        x = 0.0
    elif x > n - 1.0:
        x = n - 1.0
    i = min(int(x), n - 2) if n > 1 else 0
    return i, x - i


@nb.njit(cache=True, inline="always")
def corner_weight(fx, fy, fz, di, dj, dk):
    """The trilinear weight of a cell's corner ``(di, dj, dk)`` (each 0 or 1) at the fractions
    ``(fx, fy, fz)`` past its lower corner: ``wx * wy * wz``, multiplied in that order."""
    return (fx if di else 1.0 - fx) * (fy if dj else 1.0 - fy) * (fz if dk else 1.0 - fz)


@nb.njit(cache=True, inline="always")
def trilinear_point(volume, x, y, z):
    """Trilinear sample of ``volume`` (X, Y, Z), each axis at least 2 voxels, at the continuous
    voxel index ``(x, y, z)``, clamped to the grid; linear along x, then y, then z (float64
    for a float64 or integer grid, else the grid's float type)."""
    i, fx = grid_cell(x, volume.shape[0])
    j, fy = grid_cell(y, volume.shape[1])
    k, fz = grid_cell(z, volume.shape[2])
    c00 = volume[i, j, k] * (1 - fx) + volume[i + 1, j, k] * fx
    c10 = volume[i, j + 1, k] * (1 - fx) + volume[i + 1, j + 1, k] * fx
    c01 = volume[i, j, k + 1] * (1 - fx) + volume[i + 1, j, k + 1] * fx
    c11 = volume[i, j + 1, k + 1] * (1 - fx) + volume[i + 1, j + 1, k + 1] * fx
    return (c00 * (1 - fy) + c10 * fy) * (1 - fz) + (c01 * (1 - fy) + c11 * fy) * fz


@nb.njit(cache=True, nogil=True, inline="always")
def trilinear_at(volume, x, y, z, out):
    """Trilinear sample of ``volume`` (X, Y, Z, C), any numeric dtype, at the continuous voxel
    index ``(x, y, z)`` (voxel centres at integers), clamped to the grid, added to ``out``
    (C,) float64 (zeroed by the caller)."""
    nx, ny, nz, nc = volume.shape
    x = min(max(x, 0.0), nx - 1.0)
    y = min(max(y, 0.0), ny - 1.0)
    z = min(max(z, 0.0), nz - 1.0)
    i0 = min(int(x), nx - 2) if nx > 1 else 0
    j0 = min(int(y), ny - 2) if ny > 1 else 0
    k0 = min(int(z), nz - 2) if nz > 1 else 0
    fx, fy, fz = x - i0, y - j0, z - k0
    for di in range(2):
        for dj in range(2):
            for dk in range(2):
                # a zero weight's corner may lie beyond a one-voxel-thin grid
                w = corner_weight(fx, fy, fz, di, dj, dk)
                if w == 0.0:
                    continue
                for c in range(nc):
                    out[c] += w * volume[i0 + di, j0 + dj, k0 + dk, c]


@nb.njit(cache=True, nogil=True)
def trilinear(volume, pts):
    """(N, C) float64 trilinear samples of ``volume`` (X, Y, Z, C), any numeric dtype, at
    continuous voxel indices ``pts`` (N, 3) (voxel centres at integers), clamped to the grid."""
    out = np.zeros((pts.shape[0], volume.shape[3]))
    for n in range(pts.shape[0]):
        trilinear_at(volume, pts[n, 0], pts[n, 1], pts[n, 2], out[n])
    return out
