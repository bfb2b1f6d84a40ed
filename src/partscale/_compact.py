"""The compact layout of a ``.csdf.npz``: the band exact, the far field as coarse bounds.

A grid's band (voxels within ``band`` voxel sizes of the surface) grows with its surface, the
rest with its volume. The compact layout stores the band's distances, colours and parts exactly,
in C order of the voxels they belong to, and beyond it one value per block of ``step``³ voxels:
the smallest distance magnitude of the block's voxels beyond the band, with the colour and part
of the voxel that has it. Reading gives every voxel beyond the band that block's value with the
voxel's own sign (stored as one bit a voxel): a bound no larger than the voxel's distance, with
the sign kept, as the far field of a CSDF promises.

Arrays of a compact file (``n`` band voxels, ``C`` coarse blocks, shape ``(X, Y, Z)``):

=========  =======================  =============================================================
name       dtype, shape             what
=========  =======================  =============================================================
shape      int64 (3,)               the grid's shape
band       uint8 (ceil(XYZ/8),)     1 bit a voxel (``np.packbits`` of C order): in the band
inside     uint8 (ceil(XYZ/8),)     1 bit a voxel: ``sdf < 0``
sdf        float32 (n,)             the band's distances
rgb        uint8 (n, 3)             the band's colours
parts      int16 (n,)               the band's parts
far        float32 (cx, cy, cz)     each block's smallest distance magnitude beyond the band
far_rgb    uint8 (cx, cy, cz, 3)    the colour of the voxel that has it
far_parts  int16 (cx, cy, cz)       its part
=========  =======================  =============================================================
"""

from __future__ import annotations

import numba as nb
import numpy as np

STEP = 4
"""Voxels per side of a far-field block."""


@nb.njit(cache=True, nogil=True, parallel=True)
def _coarsen(sdf, rgb, parts, lim, step, far, far_rgb, far_parts):  # pragma: no cover - numba
    """Per block: the smallest |sdf| above ``lim`` and that voxel's colour and part."""
    cx, cy, cz = far.shape
    nx, ny, nz = sdf.shape
    for bi in nb.prange(cx):
        for bj in range(cy):
            for bk in range(cz):
                best = np.inf
                bx = by = bz = -1
                for i in range(bi * step, min(nx, bi * step + step)):
                    for j in range(bj * step, min(ny, bj * step + step)):
                        for k in range(bk * step, min(nz, bk * step + step)):
                            a = abs(sdf[i, j, k])
                            if a > lim and a < best:
                                best, bx, by, bz = a, i, j, k
                if bx < 0:  # all in the band: nobody reads it
                    far[bi, bj, bk] = 0.0
                    far_parts[bi, bj, bk] = -1
                    for c in range(3):
                        far_rgb[bi, bj, bk, c] = 0
                else:
                    far[bi, bj, bk] = best
                    far_parts[bi, bj, bk] = parts[bx, by, bz]
                    for c in range(3):
                        far_rgb[bi, bj, bk, c] = rgb[bx, by, bz, c]


@nb.njit(cache=True, nogil=True, parallel=True)
def _expand(far, far_rgb, far_parts, inside, step, sdf, rgb, parts):  # pragma: no cover - numba
    """Every voxel from its block's values, signed by ``inside``."""
    nx, ny, nz = sdf.shape
    for i in nb.prange(nx):
        bi = i // step
        for j in range(ny):
            bj = j // step
            for k in range(nz):
                bk = k // step
                d = far[bi, bj, bk]
                sdf[i, j, k] = -d if inside[i, j, k] else d
                parts[i, j, k] = far_parts[bi, bj, bk]
                for c in range(3):
                    rgb[i, j, k, c] = far_rgb[bi, bj, bk, c]


@nb.njit(cache=True, nogil=True, parallel=True)
def _split(sdf, lim, mask, inside, counts):  # pragma: no cover - numba
    """Band and inside masks of ``sdf``, and the band voxels of each x slab."""
    nx, ny, nz = sdf.shape
    for i in nb.prange(nx):
        n = 0
        for j in range(ny):
            for k in range(nz):
                d = sdf[i, j, k]
                b = abs(d) <= lim
                mask[i, j, k] = b
                inside[i, j, k] = d < 0
                n += b
        counts[i] = n


@nb.njit(cache=True, nogil=True, parallel=True)
def _gather(sdf, rgb, parts, mask, starts, band_sdf, band_rgb, band_parts):  # pragma: no cover
    """The band voxels' values in C order (slab ``i`` from ``starts[i]``)."""
    nx, ny, nz = sdf.shape
    for i in nb.prange(nx):
        q = starts[i]
        for j in range(ny):
            for k in range(nz):
                if mask[i, j, k]:
                    band_sdf[q] = sdf[i, j, k]
                    band_parts[q] = parts[i, j, k]
                    for c in range(3):
                        band_rgb[q, c] = rgb[i, j, k, c]
                    q += 1


@nb.njit(cache=True, nogil=True, parallel=True)
def _scatter(mask, starts, band_sdf, band_rgb, band_parts, sdf, rgb, parts):  # pragma: no cover
    """:func:`_gather` undone: the band voxels' values back into the grids."""
    nx, ny, nz = sdf.shape
    for i in nb.prange(nx):
        q = starts[i]
        for j in range(ny):
            for k in range(nz):
                if mask[i, j, k]:
                    sdf[i, j, k] = band_sdf[q]
                    parts[i, j, k] = band_parts[q]
                    for c in range(3):
                        rgb[i, j, k, c] = band_rgb[q, c]
                    q += 1


def _starts(counts: np.ndarray) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)


def encode(
    sdf: np.ndarray, rgb: np.ndarray, parts: np.ndarray, h: float, band: float, step: int = STEP
) -> dict[str, np.ndarray]:
    """The compact arrays (module docstring) of a CSDF's ``sdf`` (X, Y, Z) float32, ``rgb``
    (X, Y, Z, 3) uint8 and ``parts`` (X, Y, Z) int16; ``band`` in voxel sizes ``h``.
    """
    lim = np.float32(band * h)
    mask = np.empty(sdf.shape, bool)
    inside = np.empty(sdf.shape, bool)
    counts = np.empty(sdf.shape[0], np.int64)
    _split(sdf, lim, mask, inside, counts)
    n = int(counts.sum())
    band_sdf = np.empty(n, np.float32)
    band_rgb = np.empty((n, 3), np.uint8)
    band_parts = np.empty(n, np.int16)
    _gather(sdf, rgb, parts, mask, _starts(counts), band_sdf, band_rgb, band_parts)
    coarse = tuple(-(-n // step) for n in sdf.shape)
    far = np.empty(coarse, np.float32)
    far_rgb = np.empty((*coarse, 3), np.uint8)
    far_parts = np.empty(coarse, np.int16)
    _coarsen(sdf, rgb, parts, lim, step, far, far_rgb, far_parts)
    return {
        "shape": np.asarray(sdf.shape, np.int64),
        "band": np.packbits(mask),
        "inside": np.packbits(inside),
        "sdf": band_sdf,
        "rgb": band_rgb,
        "parts": band_parts,
        "far": far,
        "far_rgb": far_rgb,
        "far_parts": far_parts,
    }


def check(data: dict[str, np.ndarray], step: int = STEP) -> str | None:
    """What is wrong with compact arrays ``data`` (dtypes, shapes, counts), or None."""
    shape = data["shape"]
    if shape.shape != (3,) or shape.dtype.kind != "i" or (shape < 1).any():
        return f"expected shape to be 3 positive integers, got {shape!r}"
    n = int(np.prod(shape))
    bits = -(-n // 8)
    coarse = tuple(-(-int(s) // step) for s in shape)
    want = {
        "band": (np.uint8, (bits,)),
        "inside": (np.uint8, (bits,)),
        "far": (np.float32, coarse),
        "far_rgb": (np.uint8, (*coarse, 3)),
        "far_parts": (np.int16, coarse),
    }
    for name, (dt, sh) in want.items():
        a = data[name]
        if a.dtype != dt or a.shape != sh:
            return f"expected {name} of dtype {np.dtype(dt)} shape {sh}, got {a.dtype} {a.shape}"
    m = int(np.unpackbits(data["band"], count=n).sum())
    for name, dt, sh in (("sdf", np.float32, (m,)), ("rgb", np.uint8, (m, 3))):
        a = data[name]
        if a.dtype != dt or a.shape != sh:
            return f"expected {name} of dtype {np.dtype(dt)} shape {sh}, got {a.dtype} {a.shape}"
    if data["parts"].dtype != np.int16 or data["parts"].shape != (m,):
        return f"expected parts of dtype int16 shape {(m,)}, got {data['parts'].dtype} {data['parts'].shape}"
    if not np.isfinite(data["far"]).all():
        return "expected finite far values, got NaN or infinity"
    return None


def decode(
    data: dict[str, np.ndarray], step: int = STEP
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(sdf, rgb, parts)`` full grids from checked compact arrays (see :func:`check`)."""
    shape = tuple(int(s) for s in data["shape"])
    n = int(np.prod(shape))
    mask = np.unpackbits(data["band"], count=n).view(bool).reshape(shape)
    inside = np.unpackbits(data["inside"], count=n).view(bool).reshape(shape)
    sdf = np.empty(shape, np.float32)
    rgb = np.empty((*shape, 3), np.uint8)
    parts = np.empty(shape, np.int16)
    _expand(data["far"], data["far_rgb"], data["far_parts"], inside, step, sdf, rgb, parts)
    starts = _starts(mask.sum(axis=(1, 2)))
    _scatter(mask, starts, data["sdf"], data["rgb"], data["parts"], sdf, rgb, parts)
    return sdf, rgb, parts
