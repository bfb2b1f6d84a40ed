"""Numba kernel of the import beyond the band: each voxel takes the distance to the surface
of its nearest band voxel and that voxel's colour (an exact Euclidean feature transform).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._distance import closest_bary


@nb.njit(cache=True, inline="always")
def _envelope_query(gpos, gperp, top, n, pick):
    """Query phase of :func:`_lower_envelope`'s line: ``pick`` (n,) int64 gets, for each position,
    the index of the envelope's feature nearest it (the first of equals, as scipy).
    """
    l = 0
    for ii in range(n):
        t = gpos[l] - ii
        d1 = gperp[l] + t * t
        while l < top:
            t = gpos[l + 1] - ii
            d2 = gperp[l + 1] + t * t
            if d1 <= d2:
                break
            d1 = d2
            l += 1
        pick[ii] = l


@nb.njit(cache=True, inline="always")
def _lower_envelope(feat, perp, n, gpos, gperp, gfeat):
    """Stack phase of one line of Maurer et al.'s exact feature transform; returns its top.

    feat : (n,) int32 each position's nearest feature so far (< 0: none), perp : (n,) int64
    its squared distance across the line (read where ``feat >= 0``). Leaves the features whose
    parabolas make the lower envelope in ``gpos`` (their positions on the line), ``gperp`` and
    ``gfeat``; returns the index of the last one (-1: no feature). The test and tie rules of
    scipy's ``_VoronoiFT`` in exact integers (scipy's doubles hold these integers exactly), so
    the transform is scipy's voxel for voxel.
    """
    l = -1
    for ii in range(n):
        q = feat[ii]
        if q < 0:
            continue
        wr = perp[ii]
        while l >= 1:
            a = gpos[l] - gpos[l - 1]
            b = ii - gpos[l]
            c = a + b
            if c * gperp[l] - b * gperp[l - 1] - a * wr - a * b * c <= 0:
                break
            l -= 1
        l += 1
        gpos[l] = ii
        gperp[l] = wr
        gfeat[l] = q
    return l


@nb.njit(cache=True, inline="always")
def _line_buffers(n):
    """Scratch of one line of ``n`` voxels: feat, perp, gpos, gperp, gfeat, pick."""
    return (
        np.empty(n, np.int32),
        np.empty(n, np.int64),
        np.empty(n, np.int64),
        np.empty(n, np.int64),
        np.empty(n, np.int32),
        np.empty(n, np.int64),
    )


@nb.njit(cache=True, inline="always")
def _nearest_along(near, i, c, axis, buf):
    """Nearest features on the line of ``near`` through plane ``i`` along ``axis`` (1: y, at
    z = ``c``; 2: z, at y = ``c``), from the features the earlier passes left on it.

    A feature (``i << 16 | j``) lies in the line's plane of ``axis``'s coordinate, so only its
    squared distance across the line travels: ``(fi - i)**2 + (fj - j)**2`` (the second term
    is 0 along y, where the feature's ``j`` is the voxel's own). Leaves in ``buf`` (see
    :func:`_line_buffers`) the lower envelope (``gpos``, ``gfeat``) and each position's pick
    in it; returns the envelope's top (-1: no feature on the line).
    """
    feat, perp, gpos, gperp, gfeat, pick = buf
    n = near.shape[axis]
    for t in range(n):
        j, k = (t, c) if axis == 1 else (c, t)
        q = near[i, j, k]
        feat[t] = q
        if q >= 0:
            ti = (q >> 16) - i
            tj = (q & 0xFFFF) - j
            perp[t] = ti * ti + tj * tj
    top = _lower_envelope(feat, perp, n, gpos, gperp, gfeat)
    if top >= 0:
        _envelope_query(gpos, gperp, top, n, pick)
    return top


@nb.njit(cache=True, inline="always")
def _nearest_along_x(band, j, near):
    """Pass along x of the y-plane ``j``: each voxel's nearest band voxel on its x line, ties
    to the lower index (what the general pass gives in one dimension), by a sweep each way in
    memory order; ``near`` gets ``i << 16 | j`` of it (-1 none).
    """
    nx, nz = band.shape[0], band.shape[2]
    last = np.full(nz, -1, np.int64)
    for i in range(nx):
        for k in range(nz):
            if band[i, j, k]:
                last[k] = i
            near[i, j, k] = last[k]
    last[:] = -1
    for i in range(nx - 1, -1, -1):
        for k in range(nz):
            if band[i, j, k]:
                last[k] = i
            lo = near[i, j, k]
            hi = last[k]
            if lo < 0 or (hi >= 0 and hi - i < i - lo):
                lo = hi
            near[i, j, k] = (lo << 16) | j if lo >= 0 else -1


@nb.njit(cache=True, parallel=True)
def far_field(band, origin, h, tris, win, offset, sign, floor, sdf, rgb):
    """Fill the voxels outside ``band`` from their nearest band voxel (in place).

    band : (X, Y, Z) bool; win : (X, Y, Z) int32, each band voxel's nearest primitive of
    ``tris`` (T, 3, 3); offset : (T,) half-thickness of thickened sheets; sign : (X, Y, Z) int8.
    The nearest band voxel is the Euclidean feature transform of ``scipy.ndimage`` (the same
    voxel, ties included), computed here in parallel passes along x, y, then z, the last one
    filling each line as it goes; between passes one int32 per voxel holds the nearest feature
    found so far in its z-plane (``i << 16 | j``, -1 none; ``mesh_sdf.MAX_RES`` keeps
    grids below 2**15 voxels a side). A voxel gets ``sign * max(distance
    to its band voxel's primitive (less the offset outside), floor)`` and that band voxel's
    colour: ``sdf`` (X, Y, Z) float32, ``rgb`` (X, Y, Z, 3) uint8. Band voxels are only read,
    so the lines are independent.
    """
    nx, ny, nz = band.shape
    if nx >= 1 << 15 or ny >= 1 << 16:
        raise ValueError("far_field: grid too large for its int32 (i, j) pairs")
    near = np.empty((nx, ny, nz), np.int32)
    for j in nb.prange(ny):
        _nearest_along_x(band, j, near)
    for i in nb.prange(nx):  # pass along y, line by line within the plane (in cache)
        buf = _line_buffers(ny)
        for k in range(nz):
            if _nearest_along(near, i, k, 1, buf) < 0:
                continue
            gfeat, pick = buf[4], buf[5]
            for j in range(ny):
                near[i, j, k] = gfeat[pick[j]]
    for i in nb.prange(nx):  # pass along z, then the far field of the line
        buf = _line_buffers(nz)
        for j in range(ny):
            if _nearest_along(near, i, j, 2, buf) >= 0:
                _fill_line(band, origin, h, tris, win, offset, sign, floor, sdf, rgb, i, j, buf)


@nb.njit(cache=True, inline="always")
def _fill_line(band, origin, h, tris, win, offset, sign, floor, sdf, rgb, i, j, buf):
    """The far field of the z line ``(i, j)`` from its nearest features (see :func:`far_field`)."""
    gpos, gfeat, pick = buf[2], buf[4], buf[5]
    px = origin[0] + i * h
    py = origin[1] + j * h
    for k in range(band.shape[2]):
        if band[i, j, k]:
            continue
        l = pick[k]
        q = gfeat[l]
        si, sj, sk = q >> 16, q & 0xFFFF, gpos[l]
        t = win[si, sj, sk]
        d2, _u, _v, _w = closest_bary(px, py, origin[2] + k * h, tris[t])
        d = np.sqrt(d2)
        s = sign[i, j, k]
        d = d - offset[t] if s > 0 else -d
        sdf[i, j, k] = s * max(abs(d), floor)
        for c in range(3):
            rgb[i, j, k, c] = rgb[si, sj, sk, c]
