"""Closest-triangle propagation: the nearest triangle of every voxel of a box.

Triangles (the zero level set of the box's field, :func:`partscale._marching.march`, completed
by :func:`complete_table`) seed the eight corners of their cell; then raster sweeps, forward and
back, let each voxel test the nearest triangles of its 18 face and edge neighbours (exact
point-triangle distances, after a lower bound by the disk holding each triangle). A voxel the
seeds put within one voxel of a triangle is already exact and is not visited. Used by
:mod:`partscale.edit.reevaluate`; units are voxels (continuous indices of the box).
"""

from __future__ import annotations

import numba
import numpy as np

from .._kernels import closest_on_triangle

#: A squared distance (voxels^2) below which a seeded voxel is final (see :func:`_sweep`); the
#: margin is far above rounding and far below any distance from a grid node to a triangle
#: outside its eight cells (>= 1)
_DONE_D2 = 1.0 - 1e-9


@numba.njit(cache=True, inline="always")
def _tri_d2(tri, t, px, py, pz):
    """Squared distance from p to triangle ``t`` of ``tri`` (T, 9) and the closest point's
    barycentrics ``v, w``: the point is ``a + v (b - a) + w (c - a)``.
    """
    ax, ay, az = tri[t, 0], tri[t, 1], tri[t, 2]
    bx, by, bz = tri[t, 3], tri[t, 4], tri[t, 5]
    cx, cy, cz = tri[t, 6], tri[t, 7], tri[t, 8]
    d2, _, v, w = closest_on_triangle(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz)
    return d2, v, w


@numba.njit(cache=True, inline="always")
def _disk_d2(tri, t, px, py, pz):
    """A lower bound of the squared distance from p to triangle ``t`` of ``tri`` (F, 17).

    The triangle lies in the disk of its plane (unit normal ``tri[t, 13:16]``, offset
    ``tri[t, 16]``) around its centroid ``tri[t, 9:12]`` with radius ``tri[t, 12]``: the distance
    to that disk. The radius and the result carry margins (1e-9 relative, 1e-12 voxel^2) far
    above rounding, so a candidate the bound rejects could not have won. Near-degenerate triangles have a zero normal: the bound is then the bounding sphere's.
    """
    ex = px - tri[t, 9]
    ey = py - tri[t, 10]
    ez = pz - tri[t, 11]
    c2 = ex * ex + ey * ey + ez * ez
    h = px * tri[t, 13] + py * tri[t, 14] + pz * tri[t, 15] - tri[t, 16]
    h2 = h * h
    lat = np.sqrt(max(c2 - h2, 0.0)) - tri[t, 12]
    if lat > 0.0:
        h2 += lat * lat
    return h2 * (1.0 - 1e-9) - 1e-12


@numba.njit(cache=True, nogil=True)
def propagate(tri, order, shape, npass, first, last):
    """Nearest triangle of every voxel in ``order`` (ascending flat indices of the box).

    ``tri`` (F, 17): see :func:`complete_table`. Returns ``(best_d2, best_t, best_vw)``, flat,
    the box's size: float64 squared distances (voxels^2), int32 triangles (inf / -1 where none)
    and (size, 2) float32 barycentrics ``v, w`` of the closest point on the triangle (undefined
    where none; kept so the colour's lookup need not find the point again: 2 ms of a box's
    15 on the cabinet shrink at 128). Seeds,
    then ``npass`` raster sweeps alternating direction (raster order keeps memory access local;
    the band is thin, so two sweeps reach every voxel) over the voxels the seeds left more than
    a voxel from any triangle (the others are exact). Only voxels ``first ... last`` (flat
    indices) are read afterwards: the last sweep stops once it has passed them (what it would
    do beyond can no longer reach them).
    """
    size = shape[0] * shape[1] * shape[2]
    best_d2 = np.full(size, np.inf)
    best_t = np.full(size, -1, np.int32)
    best_vw = np.empty((size, 2), np.float32)
    # (the sweeps in a kernel of their own: compiled with the arrays as locals they ran 6 %
    # slower)
    _sweep(tri, order, shape, npass, first, last, best_d2, best_t, best_vw)
    return best_d2, best_t, best_vw


@numba.njit(cache=True, nogil=True)
def _seed(tri, shape, best_d2, best_t, best_vw):
    """Seeds of :func:`_sweep`: each triangle of ``tri`` offers itself to the eight corners of
    the cell it lies in (its centroid's), which keep the nearest (exact distances).
    """
    nx, ny, nz = shape
    syz = ny * nz
    for t in range(tri.shape[0]):
        # the corners read once: the writes below could alias the table for the compiler,
        # which then read them again for every corner (seeding took 11 ms a box, now 9)
        ax, ay, az = tri[t, 0], tri[t, 1], tri[t, 2]
        bx, by, bz = tri[t, 3], tri[t, 4], tri[t, 5]
        qx, qy, qz = tri[t, 6], tri[t, 7], tri[t, 8]
        cx = int(np.floor((ax + bx + qx) / 3.0))
        cy = int(np.floor((ay + by + qy) / 3.0))
        cz = int(np.floor((az + bz + qz) / 3.0))
        for di in range(2):
            i = cx + di
            if i < 0 or i >= nx:
                continue
            for dj in range(2):
                j = cy + dj
                if j < 0 or j >= ny:
                    continue
                for dk in range(2):
                    k = cz + dk
                    if k < 0 or k >= nz:
                        continue
                    d2, _, v, w = closest_on_triangle(
                        float(i), float(j), float(k), ax, ay, az, bx, by, bz, qx, qy, qz
                    )
                    f = i * syz + j * nz + k
                    if d2 < best_d2[f]:
                        best_d2[f] = d2
                        best_t[f] = t
                        best_vw[f, 0] = v
                        best_vw[f, 1] = w


@numba.njit(cache=True, nogil=True)
def _face_edge_offsets(syz, nz):
    """(19,) int64: flat offsets of a voxel and its 18 face and edge neighbours, in the order
    of :func:`_border_neighbours`' loops.

    The 8 corner neighbours (sqrt(3) away) add little: a corner's triangle almost always
    reaches the voxel through an edge neighbour too. Without them the propagation takes 17 %
    less time on the cabinet shrink at 128, and of the suite's 22 edits 101 band voxels
    (|sdf| <= 3 voxels) of 6.1M come out further, by at most 0.068 voxel; against exact
    distances, the largest error of their 1.8M targets within 4 voxels of the surface goes from
    0.055 to 0.079 voxel.
    """
    offs = np.empty(19, np.int64)
    o = 0
    for di in range(-1, 2):
        for dj in range(-1, 2):
            for dk in range(-1, 2):
                if di != 0 and dj != 0 and dk != 0:
                    continue
                offs[o] = di * syz + dj * nz + dk
                o += 1
    return offs


@numba.njit(cache=True, nogil=True, inline="always")
def _unflatten(f, ny, nz, syz, narrow):
    """Indices ``(i, j, k)`` of flat index ``f`` of a box (Y, Z) = (``ny``, ``nz``), ``syz =
    ny * nz``: with ``narrow`` (every flat index fits 32 bits) by 32-bit division, markedly
    cheaper than 64-bit.
    """
    if narrow:
        syz32 = np.uint32(syz)
        nz32 = np.uint32(nz)
        f32 = np.uint32(f)
        i = np.int64(f32 // syz32)
        r32 = f32 - np.uint32(i) * syz32
        j = np.int64(r32 // nz32)
        k = np.int64(r32 - np.uint32(j) * nz32)
        return i, j, k
    return f // syz, (f // nz) % ny, f % nz


@numba.njit(cache=True, nogil=True)
def _border_neighbours(i, j, k, nx, ny, nz, near):
    """The flat indices of voxel ``(i, j, k)``'s face and edge neighbours within the box (and
    its own), written to ``near``; returns their count. For voxels on the box's faces (the
    others use fixed offsets).
    """
    syz = ny * nz
    count = 0
    for di in range(-1, 2):
        ii = i + di
        if ii < 0 or ii >= nx:
            continue
        for dj in range(-1, 2):
            jj = j + dj
            if jj < 0 or jj >= ny:
                continue
            row = ii * syz + jj * nz
            for dk in range(-1, 2):
                kk = k + dk
                if kk < 0 or kk >= nz or (di != 0 and dj != 0 and dk != 0):
                    continue
                near[count] = row + kk
                count += 1
    return count


@numba.njit(cache=True, nogil=True, inline="always")
def _nearest_candidate(tri, cand_t, cand_bound, nc, b0, px, py, pz):
    """The least (squared distance, position) among candidates ``0 ... nc - 1`` (triangles
    ``cand_t``, lower bounds ``cand_bound``) and the current best ``b0`` at position -1:
    ``(d2, t, position, v, w)``, position -1 when none is nearer.

    A scan in neighbour order keeping strictly smaller distances ends on that minimum; it is
    found testing the smallest bound first: its distance then rejects more of the others by
    their bounds (~35 % fewer exact distances, results identical).
    """
    first_c = 0
    for c in range(1, nc):
        if cand_bound[c] < cand_bound[first_c]:
            first_c = c
    bd = b0
    bt = np.uint32(0)
    bpos = -1
    bv = bw = 0.0
    d2, v, w = _tri_d2(tri, cand_t[first_c], px, py, pz)
    if d2 < bd:
        bd, bt, bpos, bv, bw = d2, cand_t[first_c], first_c, v, w
    for c in range(nc):
        if c == first_c or cand_bound[c] >= bd:
            continue
        d2, v, w = _tri_d2(tri, cand_t[c], px, py, pz)
        if d2 < bd or (d2 == bd and c < bpos):
            bd, bt, bpos, bv, bw = d2, cand_t[c], c, v, w
    return bd, bt, bpos, bv, bw


@numba.njit(cache=True, nogil=True)
def _sweep(tri, order, shape, npass, first, last, best_d2, best_t, best_vw):
    """The work of :func:`propagate`, in ``best_d2``, ``best_t`` (inf / -1 on entry) and
    ``best_vw``: seeds (:func:`_seed`), then the raster sweeps.
    """
    nx, ny, nz = shape
    syz = ny * nz
    _seed(tri, shape, best_d2, best_t, best_vw)
    # stamp[t] == clock: triangle t was already tried at the current visit
    stamp = np.zeros(tri.shape[0], np.int32)
    # clock of each voxel's last change of best triangle (0: seeds) and of its last visit (-1:
    # none): a neighbour unchanged since this voxel's last visit offers a triangle this voxel
    # already tested against a best distance no smaller than its current one (same result)
    when = np.zeros(best_t.shape[0], np.int32)
    seen = np.full(best_t.shape[0], -1, np.int32)
    offs = _face_edge_offsets(syz, nz)
    # flat indices of the current voxel's neighbours; unsigned, as are the voxel's and the
    # triangles' indices below: numba then skips the wraparound of negative indices on every
    # access (~5-10 % of this kernel)
    near = np.empty(19, np.uint64)
    # the current visit's candidate triangles and their lower bounds
    cand_t = np.empty(19, np.uint32)
    cand_bound = np.empty(19)
    clock = 0
    m = order.shape[0]
    # 32-bit division wherever the box's indices fit
    narrow = nx * syz < 2**32
    for p in range(npass):
        for n in range(m):
            f = order[n] if p % 2 == 0 else order[m - 1 - n]
            if p == npass - 1 and (f > last if p % 2 == 0 else f < first):
                break
            # A voxel the seeds put nearer than one voxel to a triangle is done: every triangle
            # with a point that near lies in one of the eight cells around it, whose triangles
            # all seeded it; no neighbour can offer a nearer one (a third of the cabinet
            # shrink's relays at 128; the sweeps took 18 % longer visiting them)
            if best_d2[f] < _DONE_D2:
                continue
            i, j, k = _unflatten(f, ny, nz, syz, narrow)
            px, py, pz = float(i), float(j), float(k)
            fu = np.uint64(f)
            clock += 1
            prev = seen[fu]
            seen[fu] = clock
            if best_t[fu] >= 0:
                stamp[best_t[fu]] = clock
            # the neighbours' flat indices, then one test for all of them (inlined here: a
            # helper taking the arrays, even inlined, costs ~3x in this loop, reference counts
            # per call)
            if 0 < i < nx - 1 and 0 < j < ny - 1 and 0 < k < nz - 1:
                # inside the box: no bounds to test, the neighbours at fixed flat offsets
                for o in range(19):
                    near[o] = f + offs[o]
                count = 19
            else:
                count = _border_neighbours(i, j, k, nx, ny, nz, near)
            # the candidates: the neighbours' new triangles, each once, whose lower bound is
            # below the current best (a rejected one could not have won)
            b0 = best_d2[fu]
            nc = 0
            for o in range(count):
                g = near[o]
                # (a first visit, prev < 0, takes every neighbour: no need to read when)
                if prev >= 0 and when[g] <= prev:
                    continue
                ts = best_t[g]
                if ts < 0:
                    continue
                t = np.uint32(ts)  # numba: an unsigned index
                if stamp[t] == clock:
                    continue
                stamp[t] = clock
                bound = _disk_d2(tri, t, px, py, pz)
                if bound >= b0:
                    continue
                cand_t[nc] = t
                cand_bound[nc] = bound
                nc += 1
            if nc == 0:
                continue
            bd, bt, bpos, bv, bw = _nearest_candidate(tri, cand_t, cand_bound, nc, b0, px, py, pz)
            if bpos >= 0:
                best_d2[fu] = bd
                best_t[fu] = bt
                best_vw[fu, 0] = bv
                best_vw[fu, 1] = bw
                when[fu] = clock


@numba.njit(cache=True, nogil=True)
def complete_table(out):
    """Fill columns 9-16 of ``out`` (F, 17) float64 from each triangle's corners a, b, c
    (columns 0-8): centroid, radius of the disk around the centroid holding the triangle (with
    a 1e-9 relative margin), unit normal and plane offset (zero for near-degenerate triangles,
    whose normal is unreliable; see :func:`_disk_d2`).
    """
    for t in range(out.shape[0]):
        for d in range(3):
            out[t, 9 + d] = (out[t, d] + out[t, 3 + d] + out[t, 6 + d]) / 3.0
        r2 = 0.0
        long2 = 0.0
        for c in range(3):
            e2 = 0.0
            l2 = 0.0
            for d in range(3):
                e2 += (out[t, 3 * c + d] - out[t, 9 + d]) ** 2
                l2 += (out[t, 3 * c + d] - out[t, 3 * ((c + 1) % 3) + d]) ** 2
            r2 = max(r2, e2)
            long2 = max(long2, l2)
        out[t, 12] = np.sqrt(r2) * (1 + 1e-9)
        ux, uy, uz = out[t, 3] - out[t, 0], out[t, 4] - out[t, 1], out[t, 5] - out[t, 2]
        vx, vy, vz = out[t, 6] - out[t, 0], out[t, 7] - out[t, 1], out[t, 8] - out[t, 2]
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        area2 = np.sqrt(nx * nx + ny * ny + nz * nz)
        # |cross| against the longest edge squared: the normal's rounding error grows as its
        # inverse
        if area2 > 1e-6 * long2:
            out[t, 13] = nx / area2
            out[t, 14] = ny / area2
            out[t, 15] = nz / area2
            out[t, 16] = out[t, 13] * out[t, 9] + out[t, 14] * out[t, 10] + out[t, 15] * out[t, 11]
        else:
            for d in range(13, 17):
                out[t, d] = 0.0
    return out
