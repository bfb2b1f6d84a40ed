"""Numba kernels of the mesh -> SDF import: exact point-triangle distances in a narrow band,
and the band's signed field composed from them.

Grid convention: voxel (i, j, k) has its centre at ``origin + (i, j, k) * h``.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .._kernels import closest_on_triangle


@nb.njit(cache=True, inline="always")
def closest_bary(px, py, pz, tri):
    """Squared distance from p to triangle ``tri`` (3, 3) and the closest point's barycentrics."""
    return closest_on_triangle(
        px,
        py,
        pz,
        tri[0, 0],
        tri[0, 1],
        tri[0, 2],
        tri[1, 0],
        tri[1, 1],
        tri[1, 2],
        tri[2, 0],
        tri[2, 1],
        tri[2, 2],
    )


@nb.njit(cache=True, inline="always")
def _index_range(tri, a, origin, h, radius, n):
    mn = min(tri[0, a], tri[1, a], tri[2, a]) - radius
    mx = max(tri[0, a], tri[1, a], tri[2, a]) + radius
    return max(0, int(np.ceil((mn - origin[a]) / h))), min(
        n - 1, int(np.floor((mx - origin[a]) / h))
    )


@nb.njit(cache=True, parallel=True, nogil=True)
def band_distance(
    tris,
    slab_ptr,
    slab_tris,
    slab_width,
    origin,
    h,
    radius,
    dist2,
    tid,
    root=False,
    fresh=False,
    finish_root=False,
):
    """Minimum squared distance to ``tris`` for voxels within ``radius`` of some triangle.

    Parameters
    ----------
    tris : (T, 3, 3) float64
        Triangle corners, world units.
    slab_ptr : (S + 1,) int64, slab_tris : (M,) int64
        CSR lists of the triangles whose dilated x-range meets each slab of ``slab_width``
        x-layers; slabs are processed in parallel, each writing only its own layers (no races).
    origin : (3,) float64, h : float
        Grid placement: voxel centre = origin + index * h.
    radius : float
        Band half-width in world units; voxels farther than this from a triangle are skipped.
    dist2 : (X, Y, Z) float32, in/out
        Running minimum of the squared distance (inf to start: set by the caller, or by the
        kernel with ``fresh``).
    tid : (X, Y, Z) int32, in/out
        Index of the triangle achieving it.
    root : bool
        ``dist2`` holds distances instead (float32, unsquared) and gets the minimum with
        ``sqrt(float32(d2))`` (what ``np.sqrt`` of the squared band would give: both are
        monotone); ``tid`` is not written (any int32 array).
    fresh : bool
        ``dist2`` and ``tid`` are uninitialised: each slab first sets its layers to inf and -1
        (the first touch of the grid's pages, spread over the threads).
    finish_root : bool
        Each slab ends with its layers' square roots (float32, as ``np.sqrt``): ``dist2``
        leaves as distances.
    """
    nx, ny, nz = dist2.shape
    n_slabs = slab_ptr.shape[0] - 1
    r2 = radius * radius
    inf = np.inf
    # far above the rounding of a squared distance at these coordinates (~1e-16 of the
    # coordinates' magnitude times the radius)
    tol = 1e-6 * h * h
    for s in nb.prange(n_slabs):
        xs0 = s * slab_width
        xs1 = min(nx - 1, xs0 + slab_width - 1)
        if fresh:
            dist2[xs0 : xs1 + 1] = np.inf
            tid[xs0 : xs1 + 1] = -1
        for q in range(slab_ptr[s], slab_ptr[s + 1]):
            t = slab_tris[q]
            tri = tris[t]
            i_lo, i_hi = _index_range(tri, 0, origin, h, radius, nx)
            j_lo, j_hi = _index_range(tri, 1, origin, h, radius, ny)
            k_lo, k_hi = _index_range(tri, 2, origin, h, radius, nz)
            i_lo = max(i_lo, xs0)
            i_hi = min(i_hi, xs1)
            # plane of the triangle: skip whole runs of k farther than radius from it
            e1x, e1y, e1z = tri[1, 0] - tri[0, 0], tri[1, 1] - tri[0, 1], tri[1, 2] - tri[0, 2]
            e2x, e2y, e2z = tri[2, 0] - tri[0, 0], tri[2, 1] - tri[0, 1], tri[2, 2] - tri[0, 2]
            nxv = e1y * e2z - e1z * e2y
            nyv = e1z * e2x - e1x * e2z
            nzv = e1x * e2y - e1y * e2x
            nn = np.sqrt(nxv * nxv + nyv * nyv + nzv * nzv)
            planar = nn > 1e-30
            if planar:
                nxv /= nn
                nyv /= nn
                nzv /= nn
            box_lo_x = min(tri[0, 0], tri[1, 0], tri[2, 0])
            box_hi_x = max(tri[0, 0], tri[1, 0], tri[2, 0])
            box_lo_y = min(tri[0, 1], tri[1, 1], tri[2, 1])
            box_hi_y = max(tri[0, 1], tri[1, 1], tri[2, 1])
            box_lo_z = min(tri[0, 2], tri[1, 2], tri[2, 2])
            box_hi_z = max(tri[0, 2], tri[1, 2], tri[2, 2])
            for i in range(i_lo, i_hi + 1):
                px = origin[0] + i * h
                dx = max(box_lo_x - px, 0.0, px - box_hi_x)
                for j in range(j_lo, j_hi + 1):
                    py = origin[1] + j * h
                    dy = max(box_lo_y - py, 0.0, py - box_hi_y)
                    dxy2 = dx * dx + dy * dy
                    k0 = k_lo
                    k1 = k_hi
                    if planar:
                        pz0 = origin[2] + k0 * h
                        pd0 = (
                            (px - tri[0, 0]) * nxv
                            + (py - tri[0, 1]) * nyv
                            + (pz0 - tri[0, 2]) * nzv
                        )
                        step = nzv * h
                        if abs(step) > 1e-12:
                            ka = (-radius - pd0) / step
                            kb = (radius - pd0) / step
                            if ka > kb:
                                ka, kb = kb, ka
                            k1 = min(k1, k0 + int(np.floor(kb)))
                            k0 = k0 + max(0, int(np.ceil(ka)))
                        elif abs(pd0) > radius:
                            continue
                    # and the run of k whose box distance can be within the radius
                    rem = r2 * (1.0 + 1e-6) + tol - dxy2
                    if rem < 0.0:
                        continue
                    rz = np.sqrt(rem)
                    k0 = max(k0, int(np.ceil((box_lo_z - rz - origin[2]) / h)))
                    k1 = min(k1, int(np.floor((box_hi_z + rz - origin[2]) / h)))
                    pxy = 0.0
                    if planar:
                        pxy = (px - tri[0, 0]) * nxv + (py - tri[0, 1]) * nyv
                    for k in range(k0, k1 + 1):
                        pz = origin[2] + k * h
                        # a lower bound of the distance (to the box, to the plane): where it
                        # is surely no less than the running minimum, the exact distance
                        # cannot replace it (the test below is strict), so it is skipped
                        cur = dist2[i, j, k]
                        if root:
                            cur = cur * cur
                        if cur < inf:
                            dz = max(box_lo_z - pz, 0.0, pz - box_hi_z)
                            lb = dxy2 + dz * dz
                            if planar:
                                pd = pxy + (pz - tri[0, 2]) * nzv
                                lb = max(lb, pd * pd)
                            if lb > cur * (1.0 + 1e-6) + tol:
                                continue
                        d2, _u, _v, _w = closest_bary(px, py, pz, tri)
                        if root:
                            if d2 <= r2:
                                dr = np.sqrt(np.float32(d2))
                                if dr < dist2[i, j, k]:
                                    dist2[i, j, k] = dr
                        elif d2 <= r2 and d2 < dist2[i, j, k]:
                            dist2[i, j, k] = d2
                            tid[i, j, k] = t
        if finish_root:
            for i in range(xs0, xs1 + 1):
                for j in range(ny):
                    for k in range(nz):
                        dist2[i, j, k] = np.sqrt(dist2[i, j, k])


@nb.njit(cache=True, parallel=True)
def compose(sign, d_b, id_b, boundary, f_s, id_s, sheet, tiny, sdf, win, band_lim, band):
    """``sdf = min(sign * d_b, f_s)`` (float32) and the primitive achieving it (in place).

    sign : (X, Y, Z) int8; d_b, f_s : float32 boundary and thickened sheet distances; id_b,
    id_s : int32 indices into ``boundary`` and ``sheet`` (primitive ids, -1 none). Values
    within ``tiny`` of 0 become ``+-tiny``. Writes ``sdf`` float32, ``win`` int32 (-1 none)
    and ``band`` bool: ``|sdf| <= band_lim`` (float32).
    """
    nx, ny, nz = sign.shape
    for i in nb.prange(nx):
        for j in range(ny):
            for k in range(nz):
                v = np.float32(sign[i, j, k]) * d_b[i, j, k]
                w = -1
                b = id_b[i, j, k]
                if b >= 0:
                    w = boundary[b]
                f = f_s[i, j, k]
                if f < v:
                    v = f
                    w = sheet[id_s[i, j, k]]
                if v >= 0 and v < tiny:
                    v = tiny
                elif v < 0 and v > -tiny:
                    v = -tiny
                sdf[i, j, k] = v
                win[i, j, k] = w
                band[i, j, k] = abs(v) <= band_lim


@nb.njit(cache=True, parallel=True)
def closest_points(points, tris, tri_ids):
    """Distance and barycentrics of the closest point on ``tris[tri_ids[n]]`` to ``points[n]``.

    points : (N, 3) float64; tris : (T, 3, 3) float64; tri_ids : (N,) int64.
    Returns dist (N,) float64, bary (N, 3) float64.
    """
    n = points.shape[0]
    dist = np.empty(n, np.float64)
    bary = np.empty((n, 3), np.float64)
    for q in nb.prange(n):
        d2, u, v, w = closest_bary(points[q, 0], points[q, 1], points[q, 2], tris[tri_ids[q]])
        dist[q] = np.sqrt(d2)
        bary[q, 0] = u
        bary[q, 1] = v
        bary[q, 2] = w
    return dist, bary


@nb.njit(cache=True, parallel=True)
def voxel_closest(flat, shape, origin, h, tris, tri_ids):
    """Barycentrics (N, 3) float64 of the closest point on ``tris[tri_ids[n]]`` to the centre
    of voxel ``flat[n]`` (flat index, C order, into a grid of ``shape``): what
    :func:`closest_points` gives at ``origin + unravel(flat) * h``.
    """
    n = flat.shape[0]
    ny, nz = shape[1], shape[2]
    bary = np.empty((n, 3), np.float64)
    for q in nb.prange(n):
        f = flat[q]
        k = f % nz
        j = (f // nz) % ny
        i = f // (ny * nz)
        _d2, u, v, w = closest_bary(
            origin[0] + i * h, origin[1] + j * h, origin[2] + k * h, tris[tri_ids[q]]
        )
        bary[q, 0] = u
        bary[q, 1] = v
        bary[q, 2] = w
    return bary


def slab_lists(tris: np.ndarray, origin, h: float, radius: float, nx: int, slab_width: int):
    """CSR lists (slab_ptr, slab_tris) of triangles per slab of ``slab_width`` x-layers."""
    mn = tris[:, :, 0].min(axis=1) - radius
    mx = tris[:, :, 0].max(axis=1) + radius
    i0 = np.clip(np.ceil((mn - origin[0]) / h), 0, nx - 1).astype(np.int64)
    i1 = np.clip(np.floor((mx - origin[0]) / h), 0, nx - 1).astype(np.int64)
    s0 = i0 // slab_width
    s1 = i1 // slab_width
    count = np.maximum(s1 - s0 + 1, 0)
    tri_of = np.repeat(np.arange(len(tris), dtype=np.int64), count)
    first = np.repeat(s0, count)
    offset = np.arange(len(tri_of)) - np.repeat(np.cumsum(count) - count, count)
    slab = first + offset
    order = np.argsort(slab, kind="stable")
    n_slabs = (nx + slab_width - 1) // slab_width
    ptr = np.zeros(n_slabs + 1, np.int64)
    np.cumsum(np.bincount(slab, minlength=n_slabs), out=ptr[1:])
    return ptr, tri_of[order]
