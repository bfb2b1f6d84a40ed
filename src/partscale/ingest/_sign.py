"""Numba kernels of the import's sign: what a voxel's neighbours say about its side.

Voxels are flat indices (C order) into an (X, Y, Z) grid; neighbours are the 6 face neighbours.
Groups of voxels are joined by a union-find over the voxels concerned only, so the cost follows
the voxels near the surface, not the grid.
"""

from __future__ import annotations

import numba as nb
import numpy as np


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
