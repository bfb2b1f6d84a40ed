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
    """(..., C) uint8 sRGB (or any numbers in 0..255) -> (..., C) float64 linear in [0, 1].

    Parameters
    ----------
    srgb : (..., C) uint8 or array_like of numbers in 0..255
        8-bit sRGB values (the CSDF's ``rgb``, a texture's pixels).

    Returns
    -------
    (..., C) float64
        The same values in linear light, in [0, 1].

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.color import srgb8_to_linear
    >>> srgb8_to_linear(np.array([0, 128, 255], np.uint8)).round(4)
    array([0.    , 0.2159, 1.    ])
    """
    c = np.asarray(srgb, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def srgb_to_linear(srgb: np.ndarray) -> np.ndarray:
    """(...) sRGB in [0, 1] -> (...) float32 linear in [0, 1], computed in float32.

    Parameters
    ----------
    srgb : (...) array_like of float
        sRGB values in [0, 1] (a glTF colour factor, a normalised texture).

    Returns
    -------
    (...) float32
        The same values in linear light.

    Examples
    --------
    >>> from partscale.color import srgb_to_linear
    >>> srgb_to_linear([0.0, 0.5, 1.0])
    array([0.        , 0.21404114, 1.        ], dtype=float32)
    """
    c = np.asarray(srgb, dtype=np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """(...) linear (clipped to [0, 1]) -> (...) float64 sRGB in [0, 1].

    Parameters
    ----------
    linear : (...) array_like of float
        Linear-light values; those outside [0, 1] are clipped to it first.

    Returns
    -------
    (...) float64
        sRGB values in [0, 1].

    Examples
    --------
    >>> from partscale.color import linear_to_srgb
    >>> linear_to_srgb([-0.1, 0.2158605, 1.5])
    array([0.        , 0.50196078, 1.        ])
    """
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

    Parameters
    ----------
    linear : (..., C) float array
        Linear-light values, any float precision; clipped to [0, 1].

    Returns
    -------
    (..., C) uint8
        sRGB in 0..255, the same shape as ``linear``.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.color import linear_to_srgb8
    >>> linear_to_srgb8(np.array([[0.0, 0.2158605, 1.0]]))
    array([[  0, 128, 255]], dtype=uint8)
    """
    c = np.asarray(linear)
    flat = np.ascontiguousarray(c.reshape(-1, c.shape[-1] if c.ndim else 1))
    return _encode_srgb8(flat).reshape(c.shape)


def palette_colour(i: int) -> list[int]:
    """The sRGB display colour ``[r, g, b]`` (0..255) of part ``i``.

    HLS with hue ``(i * 0.618033988749895) mod 1``, lightness 0.55 for even ``i`` and 0.42 for
    odd ``i``, saturation 0.65 (Python's ``colorsys.hls_to_rgb``), each channel
    ``round(255 * x)``: golden-angle hues and alternating lightness, so parts with nearby
    indices look different.

    Parameters
    ----------
    i : int
        The part's index (0 and up).

    Returns
    -------
    list of int
        ``[r, g, b]``, each in 0..255.

    Examples
    --------
    >>> from partscale.color import palette_colour
    >>> palette_colour(0), palette_colour(1)
    ([215, 66, 66], [37, 78, 177])
    """
    h = (i * GOLDEN_RATIO_CONJUGATE) % 1.0
    light = PALETTE_LIGHTNESS[i % 2]
    r, g, b = colorsys.hls_to_rgb(h, light, PALETTE_SATURATION)
    return [round(r * 255), round(g * 255), round(b * 255)]


def palette(n: int) -> list[list[int]]:
    """``n`` distinct sRGB display colours: :func:`palette_colour` of ``0 .. n - 1``.

    Parameters
    ----------
    n : int
        How many colours (one per part).

    Returns
    -------
    list of list of int
        ``n`` colours ``[r, g, b]``, each channel in 0..255.

    Examples
    --------
    >>> from partscale.color import palette
    >>> palette(3)
    [[215, 66, 66], [37, 78, 177], [153, 215, 66]]
    """
    return [palette_colour(i) for i in range(n)]
