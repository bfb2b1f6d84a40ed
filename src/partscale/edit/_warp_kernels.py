"""Numba kernels of the warps (:mod:`partscale.edit.warp`): one pass over the output grid each.

The warps' maps are sampled voxel by voxel here, without whole-grid temporaries of points,
source places and corner indices: the arrays are written straight into the output (through
views in any axis order), in parallel over the output's first axis.

- :func:`gather_columns`: a map across one axis that is the same at every level (radial zones,
  turns about an axis): sdf and colour bilinear in the cross-section near the surface, else
  (and parts everywhere) the nearest source voxel.
- :func:`resample_affine`: a map that is affine on each of the slabs ``p . n`` between given
  levels (oblique zones, helices): sdf and colour trilinear near the surface where the map is no
  shift by whole voxels (as ``scipy.ndimage.map_coordinates(order=1, mode='nearest')``), else
  the nearest source voxel.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, parallel=True)
def gather_columns(src, rgb, parts, iu, iv, inside, ou, ov, lim, out, out_rgb, out_parts, moved):
    """Output column ``(u, v)`` (of views ordered (U, L, V)) shows the source columns about the
    continuous indices ``iu[u, v]``, ``iv[u, v]`` on the levels where ``inside``, and its own
    place (whole voxels ``u + ou``, ``v + ov``, clamped) on the others.

    Parameters
    ----------
    src : (Us, L, Vs) float32
    rgb : (Us, L, Vs, 3) uint8
    parts : (Us, L, Vs) int
    iu, iv : (U, V) float64
        Source indices of each output column.
    inside : (L,) bool
    ou, ov : int
        The output's first column in source indices.
    lim : float32
        Where the nearest source value lies within ``lim`` of the surface, sdf and colour are
        bilinear (float32 weights, as numpy); beyond, the nearest source value's.
    out, out_rgb, out_parts, moved : (U, L, V[, 3])
        Written: sdf and colour (see ``lim``), parts nearest; ``moved`` where the source is not
        the column's own place and the level is inside.
    """
    nu, nl, nv = src.shape
    nv_out = iu.shape[1]
    for u in numba.prange(iu.shape[0]):
        # the row's corners and weights, then the levels with the row innermost (contiguous)
        own_u = min(max(u + ou, 0), nu - 1)
        own_v = np.empty(nv_out, np.int64)
        mapped = np.empty(nv_out, np.bool_)
        a0 = np.empty(nv_out, np.int64)
        a1 = np.empty(nv_out, np.int64)
        b0 = np.empty(nv_out, np.int64)
        b1 = np.empty(nv_out, np.int64)
        pu = np.empty(nv_out, np.int64)
        pv = np.empty(nv_out, np.int64)
        w = np.empty((nv_out, 4), np.float32)
        for v in range(nv_out):
            su, sv = iu[u, v], iv[u, v]
            own_v[v] = min(max(v + ov, 0), nv - 1)
            mapped[v] = abs(su - (u + ou)) > 1e-6 or abs(sv - (v + ov)) > 1e-6
            u0 = np.int64(math.floor(su))
            v0 = np.int64(math.floor(sv))
            fu = np.float32(su - u0)
            fv = np.float32(sv - v0)
            a0[v] = min(max(u0, 0), nu - 1)
            a1[v] = min(max(u0 + 1, 0), nu - 1)
            b0[v] = min(max(v0, 0), nv - 1)
            b1[v] = min(max(v0 + 1, 0), nv - 1)
            w[v, 0] = (np.float32(1) - fu) * (np.float32(1) - fv)
            w[v, 1] = fu * (np.float32(1) - fv)
            w[v, 2] = (np.float32(1) - fu) * fv
            w[v, 3] = fu * fv
            pu[v] = min(max(np.int64(np.rint(su)), 0), nu - 1)
            pv[v] = min(max(np.int64(np.rint(sv)), 0), nv - 1)
        for lv in range(nl):
            if not inside[lv]:
                for v in range(nv_out):
                    out[u, lv, v] = src[own_u, lv, own_v[v]]
                    for c in range(3):
                        out_rgb[u, lv, v, c] = rgb[own_u, lv, own_v[v], c]
                    out_parts[u, lv, v] = parts[own_u, lv, own_v[v]]
                    moved[u, lv, v] = False
                continue
            for v in range(nv_out):
                moved[u, lv, v] = mapped[v]
                out_parts[u, lv, v] = parts[pu[v], lv, pv[v]]
                # beyond ``lim`` of the surface the nearest source value (only its sign and a
                # bound are read there, as in :func:`resample_affine`): a quarter of the reads
                d = src[pu[v], lv, pv[v]]
                if not abs(d) <= lim:
                    out[u, lv, v] = d
                    for c in range(3):
                        out_rgb[u, lv, v, c] = rgb[pu[v], lv, pv[v], c]
                    continue
                x0, x1, y0, y1 = a0[v], a1[v], b0[v], b1[v]
                out[u, lv, v] = (
                    w[v, 0] * src[x0, lv, y0]
                    + w[v, 1] * src[x1, lv, y0]
                    + w[v, 2] * src[x0, lv, y1]
                    + w[v, 3] * src[x1, lv, y1]
                )
                for c in range(3):
                    x = (
                        w[v, 0] * np.float32(rgb[x0, lv, y0, c])
                        + w[v, 1] * np.float32(rgb[x1, lv, y0, c])
                        + w[v, 2] * np.float32(rgb[x0, lv, y1, c])
                        + w[v, 3] * np.float32(rgb[x1, lv, y1, c])
                    )
                    out_rgb[u, lv, v, c] = np.uint8(min(max(np.rint(x), 0.0), 255.0))


@numba.njit(cache=True, inline="always")
def _corners(shape, x, y, z):
    """The two corner indices and the fractions of trilinear sampling at continuous indices,
    the indices clamped to the grid (``map_coordinates(order=1, mode='nearest')``).
    """
    nx, ny, nz = shape[0], shape[1], shape[2]
    x = min(max(x, 0.0), nx - 1.0)
    y = min(max(y, 0.0), ny - 1.0)
    z = min(max(z, 0.0), nz - 1.0)
    i0 = min(np.int64(math.floor(x)), nx - 1)
    j0 = min(np.int64(math.floor(y)), ny - 1)
    k0 = min(np.int64(math.floor(z)), nz - 1)
    i1, j1, k1 = min(i0 + 1, nx - 1), min(j0 + 1, ny - 1), min(k0 + 1, nz - 1)
    return i0, j0, k0, i1, j1, k1, x - i0, y - j0, z - k0


@numba.njit(cache=True, inline="always")
def _trilinear(a, x, y, z):
    """``a`` (X, Y, Z) trilinear at continuous indices (clamped)."""
    i0, j0, k0, i1, j1, k1, fx, fy, fz = _corners(a.shape, x, y, z)
    c00 = a[i0, j0, k0] * (1.0 - fx) + a[i1, j0, k0] * fx
    c10 = a[i0, j1, k0] * (1.0 - fx) + a[i1, j1, k0] * fx
    c01 = a[i0, j0, k1] * (1.0 - fx) + a[i1, j0, k1] * fx
    c11 = a[i0, j1, k1] * (1.0 - fx) + a[i1, j1, k1] * fx
    return (c00 * (1.0 - fy) + c10 * fy) * (1.0 - fz) + (c01 * (1.0 - fy) + c11 * fy) * fz


@numba.njit(cache=True, inline="always")
def _trilinear_rgb(a, ch, x, y, z):
    """``a[..., ch]`` (X, Y, Z, 3) trilinear at continuous indices (clamped)."""
    i0, j0, k0, i1, j1, k1, fx, fy, fz = _corners(a.shape, x, y, z)
    c00 = a[i0, j0, k0, ch] * (1.0 - fx) + a[i1, j0, k0, ch] * fx
    c10 = a[i0, j1, k0, ch] * (1.0 - fx) + a[i1, j1, k0, ch] * fx
    c01 = a[i0, j0, k1, ch] * (1.0 - fx) + a[i1, j0, k1, ch] * fx
    c11 = a[i0, j1, k1, ch] * (1.0 - fx) + a[i1, j1, k1, ch] * fx
    return (c00 * (1.0 - fy) + c10 * fy) * (1.0 - fz) + (c01 * (1.0 - fy) + c11 * fy) * fz


@numba.njit(cache=True, parallel=True)
def resample_affine(
    sdf,
    rgb,
    parts,
    src_origin,
    h,
    origin,
    normal,
    levels,
    mats,
    backs,
    lim,
    out,
    out_rgb,
    out_parts,
    moved,
):
    """Each output voxel ``p`` shows the source at ``A_m p + b_m - back_m(s) normal``, ``s = p .
    normal``, ``m`` the slab of ``s`` among ``levels`` (how many levels lie below it), and
    ``back_m(s) = (s - backs[m, 0]) * backs[m, 1] + backs[m, 2]``.

    Parameters
    ----------
    sdf : (X, Y, Z) float32
    rgb : (X, Y, Z, 3) uint8
    parts : (X, Y, Z) int
    src_origin : (3,) float64
    h : float
    origin : (3,) float64
        The output grid's origin (same voxel size).
    normal : (3,) float64
    levels : (M,) float64
        Increasing.
    mats : (M + 1, 3, 4) float64
        ``[A | b]`` of each slab (world units).
    backs : (M + 1, 3) float64
        Each slab's shift along ``normal`` (see above).
    lim : float
        Distances (world) at most this far from the surface are trilinear where moved.
    out, out_rgb, out_parts, moved : (X', Y', Z'[, 3])
        Written.
    """
    nx, ny, nz = sdf.shape
    for i in numba.prange(out.shape[0]):
        px = origin[0] + i * h
        for j in range(out.shape[1]):
            py = origin[1] + j * h
            for k in range(out.shape[2]):
                pz = origin[2] + k * h
                s = px * normal[0] + py * normal[1] + pz * normal[2]
                m = 0
                while m < levels.shape[0] and s > levels[m]:
                    m += 1
                q0 = mats[m, 0, 0] * px + mats[m, 0, 1] * py + mats[m, 0, 2] * pz + mats[m, 0, 3]
                q1 = mats[m, 1, 0] * px + mats[m, 1, 1] * py + mats[m, 1, 2] * pz + mats[m, 1, 3]
                q2 = mats[m, 2, 0] * px + mats[m, 2, 1] * py + mats[m, 2, 2] * pz + mats[m, 2, 3]
                back = (s - backs[m, 0]) * backs[m, 1] + backs[m, 2]
                q0 -= back * normal[0]
                q1 -= back * normal[1]
                q2 -= back * normal[2]
                x = (q0 - src_origin[0]) / h
                y = (q1 - src_origin[1]) / h
                z = (q2 - src_origin[2]) / h
                o0, o1, o2 = (q0 - px) / h, (q1 - py) / h, (q2 - pz) / h
                mv = max(abs(o0 - np.rint(o0)), max(abs(o1 - np.rint(o1)), abs(o2 - np.rint(o2))))
                is_moved = mv > 1e-6
                a = min(max(np.int64(np.rint(x)), 0), nx - 1)
                b = min(max(np.int64(np.rint(y)), 0), ny - 1)
                c = min(max(np.int64(np.rint(z)), 0), nz - 1)
                d = sdf[a, b, c]
                moved[i, j, k] = is_moved
                out_parts[i, j, k] = parts[a, b, c]
                if is_moved and abs(d) <= lim:
                    out[i, j, k] = np.float32(_trilinear(sdf, x, y, z))
                    for ch in range(3):
                        v = np.rint(_trilinear_rgb(rgb, ch, x, y, z))
                        out_rgb[i, j, k, ch] = np.uint8(min(max(v, 0.0), 255.0))
                else:
                    out[i, j, k] = d
                    for ch in range(3):
                        out_rgb[i, j, k, ch] = rgb[a, b, c, ch]


@numba.njit(cache=True)
def reevaluation_mask(sdf, moved, h, band, reach, dirs, lateral):
    """(X, Y, Z) bool: the voxels within ``band`` voxels of the surface and within ``reach``
    face steps (the L1 ball ``scipy.ndimage.binary_dilation(iterations=reach)`` gives) of a
    moved one that is as near, less those whose field is flat along every row of ``dirs``
    (K, 3) unit vectors (slope at most ``lateral``, one-sided differences either way): their nearest surface
    point lies square to every direction the map moves along, and a map that only grows keeps
    that distance (its inverse brings nothing closer).
    """
    nx, ny, nz = sdf.shape
    lim = np.float32(band * h)
    far = np.uint8(255)
    d = np.full((nx, ny, nz), far, np.uint8)
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                if moved[i, j, k] and abs(sdf[i, j, k]) <= lim:
                    d[i, j, k] = 0
    # city-block distance transform, two raster passes (exact for the L1 metric)
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                v = np.int64(d[i, j, k])
                if i > 0:
                    v = min(v, np.int64(d[i - 1, j, k]) + 1)
                if j > 0:
                    v = min(v, np.int64(d[i, j - 1, k]) + 1)
                if k > 0:
                    v = min(v, np.int64(d[i, j, k - 1]) + 1)
                d[i, j, k] = min(v, 255)
    for i in range(nx - 1, -1, -1):
        for j in range(ny - 1, -1, -1):
            for k in range(nz - 1, -1, -1):
                v = np.int64(d[i, j, k])
                if i < nx - 1:
                    v = min(v, np.int64(d[i + 1, j, k]) + 1)
                if j < ny - 1:
                    v = min(v, np.int64(d[i, j + 1, k]) + 1)
                if k < nz - 1:
                    v = min(v, np.int64(d[i, j, k + 1]) + 1)
                d[i, j, k] = min(v, 255)
    mask = np.zeros((nx, ny, nz), np.bool_)
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                if d[i, j, k] > reach or not abs(sdf[i, j, k]) <= lim:
                    continue
                keep = dirs.shape[0] > 0
                if keep:
                    ip, im = min(i + 1, nx - 1), max(i - 1, 0)
                    jp, jm = min(j + 1, ny - 1), max(j - 1, 0)
                    kp, km = min(k + 1, nz - 1), max(k - 1, 0)
                    c = np.float64(sdf[i, j, k])
                    # one-sided differences each way: a ridge (two surfaces equally near) is
                    # flat in the central difference but not on either side
                    fx, bx = (sdf[ip, j, k] - c) / h, (c - sdf[im, j, k]) / h
                    fy, by = (sdf[i, jp, k] - c) / h, (c - sdf[i, jm, k]) / h
                    fz, bz = (sdf[i, j, kp] - c) / h, (c - sdf[i, j, km]) / h
                    for m in range(dirs.shape[0]):
                        ex, ey, ez = dirs[m, 0], dirs[m, 1], dirs[m, 2]
                        if (
                            abs(fx * ex + fy * ey + fz * ez) > lateral
                            or abs(bx * ex + by * ey + bz * ez) > lateral
                        ):
                            keep = False
                            break
                mask[i, j, k] = not keep
    return mask


@numba.njit(cache=True, inline="always")
def _envelope(f, d, v, z):
    """``d[q] = min_p (q - p)^2 + f[p]`` over a line (Felzenszwalb and Huttenlocher's lower
    envelope of parabolas): ``f``, ``d`` (N,) float64 (``inf``: no site; all ``inf`` where the
    line has none); ``v`` (N,) int64 and ``z`` (N + 1,) float64 scratch. Integer inputs give
    integer results, exactly.
    """
    n = f.shape[0]
    k = -1
    for q in range(n):
        fq = f[q]
        if fq == np.inf:
            continue
        s = -np.inf
        while k >= 0:
            p = v[k]
            s = ((fq + q * q) - (f[p] + p * p)) / (2.0 * (q - p))
            if s > z[k]:
                break
            k -= 1
        k += 1
        v[k] = q
        z[k] = -np.inf if k == 0 else s
        z[k + 1] = np.inf
    if k < 0:
        d[:] = np.inf
        return
    k = 0
    for q in range(n):
        while z[k + 1] < q:
            k += 1
        p = v[k]
        d[q] = (q - p) * (q - p) + f[p]


@numba.njit(cache=True, parallel=True)
def _edt_axis(sq, axis):
    """In place on ``sq`` (X, Y, Z) float64: the lower envelope (:func:`_envelope`) along
    ``axis``, the lines in parallel.
    """
    shape = sq.shape
    n = shape[axis]
    a, b = [shape[i] for i in range(3) if i != axis]
    for line in numba.prange(a * b):
        x, y = line // b, line % b
        f = np.empty(n)
        d = np.empty(n)
        v = np.empty(n, np.int64)
        z = np.empty(n + 1)
        for t in range(n):
            if axis == 0:
                f[t] = sq[t, x, y]
            elif axis == 1:
                f[t] = sq[x, t, y]
            else:
                f[t] = sq[x, y, t]
        _envelope(f, d, v, z)
        for t in range(n):
            if axis == 0:
                sq[t, x, y] = d[t]
            elif axis == 1:
                sq[x, t, y] = d[t]
            else:
                sq[x, y, t] = d[t]


@numba.njit(cache=True, parallel=True)
def opposite_distance(inside):
    """(X, Y, Z) float64: each voxel's Euclidean distance (voxels) to the nearest voxel of the
    other side of ``inside`` (X, Y, Z) bool (``inf`` where there is none): what
    ``scipy.ndimage.distance_transform_edt`` gives for ``inside`` at the inside voxels and for
    ``~inside`` at the others, exactly (squared distances are integers), by the separable exact
    transform of Felzenszwalb and Huttenlocher, in parallel over lines.
    """
    nx, ny, nz = inside.shape
    to_out = np.empty((nx, ny, nz))
    to_in = np.empty((nx, ny, nz))
    for i in numba.prange(nx):
        for j in range(ny):
            for k in range(nz):
                to_out[i, j, k] = np.inf if inside[i, j, k] else 0.0
                to_in[i, j, k] = 0.0 if inside[i, j, k] else np.inf
    for axis in range(3):
        _edt_axis(to_out, axis)
        _edt_axis(to_in, axis)
    out = np.empty((nx, ny, nz))
    for i in numba.prange(nx):
        for j in range(ny):
            for k in range(nz):
                out[i, j, k] = np.sqrt(to_out[i, j, k] if inside[i, j, k] else to_in[i, j, k])
    return out
