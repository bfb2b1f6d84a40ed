"""Numba kernels of the mesh -> SDF import: exact point-triangle distances in a narrow band.

Grid convention: voxel (i, j, k) has its centre at ``origin + (i, j, k) * h``.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from llvmlite import ir
from numba.extending import intrinsic

from .._kernels import closest_on_triangle


@nb.njit(cache=True, inline="always")
def _closest_bary(px, py, pz, tri):
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
                        d2, _u, _v, _w = _closest_bary(px, py, pz, tri)
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
def sign_inputs(d_u, f_s, id_s, sheet, offset, h):
    """What the sign needs, per voxel, in one pass over the grid.

    d_u : (X, Y, Z) float32 distance to the nearest boundary or buried face (inf: none near);
    f_s : (X, Y, Z) float32 distance to the nearest sheet primitive ``sheet[id_s]`` (id_s
    int32, -1: none near), made in place the thickened sheet's distance (less that
    primitive's ``offset``, float64, rounded to float32). Returns in_sheet (f_s <= 0), free
    (``d_u > h``, h compared in float32, and not in_sheet) bool, and dist float32: the lesser
    of ``d_u`` and the unthickened sheet distance.
    """
    nx, ny, nz = d_u.shape
    in_sheet = np.empty((nx, ny, nz), np.bool_)
    free = np.empty((nx, ny, nz), np.bool_)
    dist = np.empty((nx, ny, nz), np.float32)
    hf = np.float32(h)
    for i in nb.prange(nx):
        for j in range(ny):
            for k in range(nz):
                d = d_u[i, j, k]
                dd = d
                f = f_s[i, j, k]
                s = id_s[i, j, k]
                if s >= 0:
                    off = offset[sheet[s]]
                    f = np.float32(f - off)
                    f_s[i, j, k] = f
                    dd = np.float32(min(np.float64(d), np.float64(f) + off))
                ins = f <= 0
                in_sheet[i, j, k] = ins
                free[i, j, k] = d > hf and not ins
                dist[i, j, k] = dd
    return in_sheet, free, dist


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
        d2, u, v, w = _closest_bary(points[q, 0], points[q, 1], points[q, 2], tris[tri_ids[q]])
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
        _d2, u, v, w = _closest_bary(
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


@nb.njit(cache=True, inline="always")
def _find(parent, a):
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@nb.njit(cache=True, inline="always")
def _step(p, a, ny, nz, nx):
    """Flat index of ``p``'s 6-neighbour ``a`` (0..5: +x, -x, +y, -y, +z, -z), -1 off the grid."""
    k = p % nz
    j = (p // nz) % ny
    i = p // (ny * nz)
    ax = a // 2
    st = 1 if a % 2 == 0 else -1
    if ax == 0:
        i += st
        if i < 0 or i >= nx:
            return -1
    elif ax == 1:
        j += st
        if j < 0 or j >= ny:
            return -1
    else:
        k += st
        if k < 0 or k >= nz:
            return -1
    return (i * ny + j) * nz + k


@nb.njit(cache=True)
def clear_components(flat, sign, in_sheet, dist, h):
    """Group the voxels ``flat`` joined by surface-free steps; collect the signs they touch.

    Two 6-neighbours ``h`` apart with ``dist[p] + dist[q] > h`` have no surface between them
    (the open balls of those radii cover the segment), so they share a side. flat : (N,)
    int64 sorted flat indices of the voxels to group; sign : (X, Y, Z) int8 known signs (0
    unknown; those ``in_sheet`` (X, Y, Z) bool count as unknown); dist : (X, Y, Z) float32
    distance to the nearest surface. Returns root (N,) int64 (a component id in 0..N-1 per
    voxel) and touch (N, 2) bool per root (a clear step reaches a +1 / -1 seed). Cost follows
    N, bar one int32 id per grid voxel.
    """
    nx, ny, nz = dist.shape
    n = flat.shape[0]
    cid = np.full(nx * ny * nz, -1, np.int32)
    for p in range(n):
        cid[flat[p]] = p
    sg = sign.ravel()
    sh = in_sheet.ravel()
    dv = dist.ravel()
    parent = np.arange(n)
    touch = np.zeros((n, 2), np.bool_)
    lim = h * 1.001
    for p in range(n):
        f = flat[p]
        dp = dv[f]
        for a in range(6):
            g = _step(f, a, ny, nz, nx)
            if g < 0:
                continue
            if not dp + dv[g] > lim:
                continue
            q = cid[g]
            if q >= 0:
                ra = _find(parent, p)
                rb = _find(parent, q)
                if ra != rb:
                    parent[ra] = rb
            elif sh[g]:
                continue
            elif sg[g] > 0:
                touch[p, 0] = True
            elif sg[g] < 0:
                touch[p, 1] = True
    root = np.empty(n, np.int64)
    for p in range(n):
        root[p] = _find(parent, p)
    comp = np.zeros((n, 2), np.bool_)
    for p in range(n):
        r = root[p]
        comp[r, 0] |= touch[p, 0]
        comp[r, 1] |= touch[p, 1]
    return root, comp


@nb.njit(cache=True)
def shell_pockets(sdf, lim):
    """Flat indices (sorted, int64) of the enclosed pockets of the shell ``0 < sdf <= lim``.

    sdf : (X, Y, Z) float32, lim : float32. The shell's 6-connected components (those of
    ``ndimage.label``) that have no 6-neighbour off the grid or with ``sdf > lim``; found by a
    union-find over the shell's voxels only (sorted, so each axis's neighbours are met by one
    merge-like sweep), one pass over the grid to list them.
    """
    nx, ny, nz = sdf.shape
    v = sdf.ravel()
    m = 0
    for p in range(v.size):
        if v[p] > 0 and v[p] <= lim:
            m += 1
    idx = np.empty(m, np.int64)
    m = 0
    for p in range(v.size):
        if v[p] > 0 and v[p] <= lim:
            idx[m] = p
            m += 1
    parent = np.arange(m)
    for off in (1, nz, ny * nz):
        q = 0
        for n in range(m):
            p = idx[n]
            if off == 1 and p % nz == nz - 1:
                continue
            if off == nz and (p // nz) % ny == ny - 1:
                continue
            target = p + off
            while q < m and idx[q] < target:
                q += 1
            if q < m and idx[q] == target:
                ra = _find(parent, n)
                rb = _find(parent, q)
                if ra != rb:
                    parent[ra] = rb
    open_ = np.zeros(m, np.bool_)
    for n in range(m):
        p = idx[n]
        for a in range(6):
            g = _step(p, a, ny, nz, nx)
            if g < 0 or v[g] > lim:
                open_[_find(parent, n)] = True
                break
    keep = np.empty(m, np.bool_)
    n_fill = 0
    for n in range(m):
        keep[n] = not open_[_find(parent, n)]
        n_fill += keep[n]
    out = np.empty(n_fill, np.int64)
    n_fill = 0
    for n in range(m):
        if keep[n]:
            out[n_fill] = idx[n]
            n_fill += 1
    return out


@nb.njit(cache=True)
def spread_signs(sign, todo, rounds):
    """Give voxels ``todo`` (flat indices) the sign of their signed 6-neighbours where those
    agree, in up to ``rounds`` synchronous rounds (each reads the signs of the round before);
    sign : (X, Y, Z) int8, in place. Returns the flat indices still unsigned.
    """
    nx, ny, nz = sign.shape
    sg = sign.ravel()
    val = np.zeros(todo.shape[0], np.int8)
    for _ in range(rounds):
        n = todo.shape[0]
        any_one = False
        for t in range(n):
            val[t] = _agreed(sg, todo[t], nx, ny, nz)
            any_one |= val[t] != 0
        if not any_one:
            break
        m = 0
        for t in range(n):
            if val[t] != 0:
                sg[todo[t]] = val[t]
            else:
                todo[m] = todo[t]
                m += 1
        todo = todo[:m]
    return todo


@nb.njit(cache=True, inline="always")
def _agreed(sg, p, nx, ny, nz):
    pos = False
    neg = False
    for a in range(6):
        g = _step(p, a, ny, nz, nx)
        if g >= 0:
            pos |= sg[g] > 0
            neg |= sg[g] < 0
    if pos and not neg:
        return 1
    if neg and not pos:
        return -1
    return 0


@nb.njit(cache=True)
def sign_near(sign, free, in_sheet, near):
    """Sign the voxels ``near`` (flat indices of the voxels not ``free``) from their ``free``
    6-neighbours where those agree; undecided ones ``in_sheet`` are inside (-1). sign : (X, Y,
    Z) int8, in place (only ``near`` voxels are written, only free ones read). Returns the
    flat indices of those left: undecided and not ``in_sheet``.
    """
    nx, ny, nz = sign.shape
    sg = sign.ravel()
    fr = free.ravel()
    sh = in_sheet.ravel()
    left = np.empty(near.shape[0], np.int64)
    m = 0
    for t in range(near.shape[0]):
        p = near[t]
        pos = False
        neg = False
        for a in range(6):
            g = _step(p, a, ny, nz, nx)
            if g >= 0 and fr[g]:
                pos |= sg[g] > 0
                neg |= sg[g] < 0
        if pos != neg:
            sg[p] = 1 if pos else -1
        elif sh[p]:
            sg[p] = -1
        else:
            left[m] = p
            m += 1
    return left[:m]


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
        # pass along x: the nearest band voxel on the line, ties to the lower index (what the
        # general pass gives in one dimension), by a sweep each way in memory order
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
    # passes along y and z: a feature's coordinate along the line is its position on it, so
    # only its squared distance across the line (``perp``) and its code travel
    for i in nb.prange(nx):  # pass along y, line by line within the plane (in cache)
        feat = np.empty(ny, np.int32)
        perp = np.empty(ny, np.int64)
        gpos = np.empty(ny, np.int64)
        gperp = np.empty(ny, np.int64)
        gfeat = np.empty(ny, np.int32)
        pick = np.empty(ny, np.int64)
        for k in range(nz):
            for j in range(ny):
                q = near[i, j, k]
                feat[j] = q
                if q >= 0:
                    t = (q >> 16) - i
                    perp[j] = t * t
            top = _lower_envelope(feat, perp, ny, gpos, gperp, gfeat)
            if top < 0:
                continue
            _envelope_query(gpos, gperp, top, ny, pick)
            for j in range(ny):
                near[i, j, k] = gfeat[pick[j]]
    for i in nb.prange(nx):  # pass along z, then the far field of the line
        px = origin[0] + i * h
        feat = np.empty(nz, np.int32)
        perp = np.empty(nz, np.int64)
        gpos = np.empty(nz, np.int64)
        gperp = np.empty(nz, np.int64)
        gfeat = np.empty(nz, np.int32)
        pick = np.empty(nz, np.int64)
        for j in range(ny):
            py = origin[1] + j * h
            for k in range(nz):
                q = near[i, j, k]
                feat[k] = q
                if q >= 0:
                    ti = (q >> 16) - i
                    tj = (q & 0xFFFF) - j
                    perp[k] = ti * ti + tj * tj
            top = _lower_envelope(feat, perp, nz, gpos, gperp, gfeat)
            if top < 0:
                continue
            _envelope_query(gpos, gperp, top, nz, pick)
            for k in range(nz):
                if band[i, j, k]:
                    continue
                l = pick[k]
                q = gfeat[l]
                si, sj, sk = q >> 16, q & 0xFFFF, gpos[l]
                t = win[si, sj, sk]
                d2, _u, _v, _w = _closest_bary(px, py, origin[2] + k * h, tris[t])
                d = np.sqrt(d2)
                s = sign[i, j, k]
                d = d - offset[t] if s > 0 else -d
                sdf[i, j, k] = s * max(abs(d), floor)
                for c in range(3):
                    rgb[i, j, k, c] = rgb[si, sj, sk, c]


@nb.njit(cache=True, inline="always")
def _bilinear(texture, u, v, hgt, wid, c):
    """Bilinear, repeat-wrapped value of channel ``c`` of ``texture`` at ``(u, v)`` (float64;
    the callers round it to float32). See :func:`bilinear_repeat`.
    """
    x = u * wid - 0.5
    y = (1.0 - v) * hgt - 0.5
    x0f = np.floor(x)
    y0f = np.floor(y)
    fx = np.float32(x - x0f)
    fy = np.float32(y - y0f)
    x0 = int(x0f) % wid
    y0 = int(y0f) % hgt
    x1 = (x0 + 1) % wid
    y1 = (y0 + 1) % hgt
    top = texture[y0, x0, c] * (1 - fx) + texture[y0, x1, c] * fx
    bot = texture[y1, x0, c] * (1 - fx) + texture[y1, x1, c] * fx
    return top * (1 - fy) + bot * fy


@nb.njit(cache=True, parallel=True)
def bilinear_repeat(texture, uv):
    """Bilinear, repeat-wrapped lookup of ``texture`` (H, W, C) float32 at ``uv`` (N, 2).

    Texel centres sit at ``(i + 0.5) / W``; v points up and row 0 is the top of the image.
    Returns (N, C) float32.
    """
    hgt, wid, nc = texture.shape
    out = np.empty((uv.shape[0], nc), np.float32)
    for n in nb.prange(uv.shape[0]):
        for c in range(nc):
            out[n, c] = _bilinear(texture, uv[n, 0], uv[n, 1], hgt, wid, c)
    return out


@nb.njit(cache=True, parallel=True)
def corner_mix(ids, bary, corner):
    """(N, D) float64 ``sum_c bary[n, c] * corner[ids[n], c]``, summed in the order c = 0, 1, 2
    (``np.einsum("nc,ncd->nd", bary, corner[ids])`` bit for bit, without the gather).

    ids : (N,) int64; bary : (N, 3) float64; corner : (T, 3, D) float32 or float64.
    """
    n = ids.shape[0]
    nd = corner.shape[2]
    out = np.empty((n, nd), np.float64)
    for q in nb.prange(n):
        t = ids[q]
        for d in range(nd):
            acc = 0.0
            for c in range(3):
                acc += bary[q, c] * corner[t, c, d]
            out[q, d] = acc
    return out


@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` with one rounding (LLVM's ``llvm.fma``), float64."""
    sig = nb.types.float64(nb.types.float64, nb.types.float64, nb.types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(fn, args)

    return sig, codegen


@nb.njit(cache=True, parallel=True)
def shade(mats, m, factor, texture, uv, transform, lin):
    """``lin[n] *= factor * texture(uv[n])`` (float32) where ``mats[n] == m`` (in place).

    mats : (N,) int32 material per point; factor : (3,) float32; texture : (H, W, 3) float32,
    or an empty array for none (factor only); uv : (N, 2) float64 (read with a texture);
    transform : (2, 3) float64 UV affine applied first, or an empty array for none; lin :
    (N, 3) float32 linear colour. The texture is sampled as :func:`bilinear_repeat`. The
    affine's row products are ``fma(v, a_r1, u * a_r0) + t_r``: what numpy's ``uv @ A.T + t``
    gives through BLAS with fused multiply-adds (this machine's OpenBLAS), bit for bit, at a
    fraction of its cost (its threads are slow on two rows' worth of work).
    """
    hgt, wid = texture.shape[0], texture.shape[1]
    textured = texture.size > 0
    affine = transform.size > 0
    for n in nb.prange(mats.shape[0]):
        if mats[n] != m:
            continue
        u = uv[n, 0] if textured else 0.0
        v = uv[n, 1] if textured else 0.0
        if textured and affine:
            # mypy reads _fma's signature with the typing context numba passes at compile time
            u, v = (
                _fma(v, transform[0, 1], u * transform[0, 0]) + transform[0, 2],  # type: ignore[call-arg]
                _fma(v, transform[1, 1], u * transform[1, 0]) + transform[1, 2],  # type: ignore[call-arg]
            )
        for c in range(3):
            col = factor[c]
            if textured:
                col = col * np.float32(_bilinear(texture, u, v, hgt, wid, c))
            lin[n, c] *= col
