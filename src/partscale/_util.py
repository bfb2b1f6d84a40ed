"""The part palette (display colours of part indices)."""

from __future__ import annotations

import colorsys


def palette_colour(i: int) -> list[int]:
    """sRGB display colour of part ``i``: golden-angle hues, alternating lightness, so parts
    with nearby indices look different."""
    h = (i * 0.618033988749895) % 1.0
    light = 0.55 if i % 2 == 0 else 0.42
    r, g, b = colorsys.hls_to_rgb(h, light, 0.65)
    return [round(r * 255), round(g * 255), round(b * 255)]
