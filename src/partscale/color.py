"""Colour: the sRGB transfer function in each form partscale needs, and the part palette.

The CSDF stores 8-bit sRGB; arithmetic on colours (texture filtering, glTF factors, shading) is
done in linear light. Every conversion uses the IEC 61966-2-1 curve::

    linear = s / 12.92                     if s <= 0.04045
             ((s + 0.055) / 1.055) ** 2.4  otherwise
    s      = 12.92 * linear                if linear <= 0.0031308
             1.055 * linear ** (1 / 2.4) - 0.055  otherwise

The name says the input and output convention (``srgb8`` is uint8 in 0..255; plain ``srgb`` and
``linear`` are floats in [0, 1]); the precision each returns is part of its contract, because
callers' results depend on it bit for bit.

The part palette (:func:`palette_colour`) is what ``segment`` stores in ``meta['parts_info']``
and ``render --parts`` falls back to; the web editor mirrors it for parts without a stored colour.
"""

from __future__ import annotations

import colorsys

import numba
import numpy as np

GOLDEN_RATIO_CONJUGATE = 0.618033988749895
"""Hue step between consecutive parts (golden angle), so nearby indices get distant hues."""
PALETTE_SATURATION = 0.65
PALETTE_LIGHTNESS = (0.55, 0.42)
"""HLS lightness of even and odd part indices."""


def srgb8_to_linear(srgb: np.ndarray) -> np.ndarray:
    """(..., C) uint8 sRGB (or any numbers in 0..255) -> (..., C) float64 linear in [0, 1]."""
    c = np.asarray(srgb, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def srgb_to_linear(srgb: np.ndarray) -> np.ndarray:
    """(...) sRGB in [0, 1] -> (...) float32 linear in [0, 1], computed in float32."""
    c = np.asarray(srgb, dtype=np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """(...) linear (clipped to [0, 1]) -> (...) float64 sRGB in [0, 1]."""
    c = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


@numba.njit(cache=True, parallel=True)
def _encode_srgb8(lin):
    # (N, C) float -> (N, C) uint8; in float64 whatever the input precision
    out = np.empty(lin.shape, np.uint8)
    for n in numba.prange(lin.shape[0]):
        for c in range(lin.shape[1]):
            v = min(max(np.float64(lin[n, c]), 0.0), 1.0)
            s = v * 12.92 if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
            out[n, c] = np.uint8(min(max(np.rint(s * 255.0), 0.0), 255.0))
    return out


def linear_to_srgb8(linear: np.ndarray) -> np.ndarray:
    """(..., C) float linear (clipped to [0, 1]) -> (..., C) uint8 sRGB, rounded to nearest.

    Evaluated in float64 by a parallel numba kernel (the import colours millions of points).
    """
    c = np.asarray(linear)
    flat = np.ascontiguousarray(c.reshape(-1, c.shape[-1] if c.ndim else 1))
    return _encode_srgb8(flat).reshape(c.shape)


def palette_colour(i: int) -> list[int]:
    """sRGB display colour ``[r, g, b]`` (0..255) of part ``i``.

    HLS with hue ``(i * 0.618033988749895) mod 1``, lightness 0.55 for even ``i`` and 0.42 for
    odd ``i``, saturation 0.65 (Python's ``colorsys.hls_to_rgb``), each channel
    ``round(255 * x)``: golden-angle hues and alternating lightness, so parts with nearby
    indices look different.
    """
    h = (i * GOLDEN_RATIO_CONJUGATE) % 1.0
    light = PALETTE_LIGHTNESS[i % 2]
    r, g, b = colorsys.hls_to_rgb(h, light, PALETTE_SATURATION)
    return [round(r * 255), round(g * 255), round(b * 255)]


def palette(n: int) -> list[list[int]]:
    """``n`` distinct sRGB display colours: :func:`palette_colour` of ``0 .. n - 1``."""
    return [palette_colour(i) for i in range(n)]
