"""Numba kernels of the import's colour: barycentric mixes of corner values and texture
lookups (bilinear, repeat-wrapped), shaded by the material's factor.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from llvmlite import ir
from numba.extending import intrinsic


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
