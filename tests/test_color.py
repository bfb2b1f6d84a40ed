"""Colour: the sRGB transfer function against its definition and published values, round trips,
and the part palette against an independent HSL conversion and what segmentation stores."""

from __future__ import annotations

import numpy as np
import pytest

from partscale import color, render, shapes
from partscale.segment import segment

# IEC 61966-2-1 reference points: (sRGB in [0, 1], linear), to 6 significant digits
KNOWN = [
    (0.0, 0.0),
    (0.04045, 0.0031308),  # the breakpoint: both branches meet here
    (0.5, 0.214041),
    (0.735357, 0.5),
    (1.0, 1.0),
]


@pytest.mark.parametrize("srgb, linear", KNOWN)
def test_float_conversions_hit_the_standards_values(srgb, linear):
    assert abs(float(color.srgb_to_linear(np.float32(srgb))) - linear) <= 2e-6
    assert abs(float(color.linear_to_srgb(linear)) - srgb) <= 2e-6


def test_srgb8_to_linear_is_the_curve_at_every_byte():
    s = np.arange(256) / 255.0
    # the curve by its definition, one branch at a time
    expect = np.empty(256)
    low = s <= 0.04045
    expect[low] = s[low] / 12.92
    expect[~low] = ((s[~low] + 0.055) / 1.055) ** 2.4
    got = color.srgb8_to_linear(np.arange(256, dtype=np.uint8))
    assert got.dtype == np.float64
    assert np.abs(got - expect).max() <= 1e-15
    assert got[0] == 0.0 and got[255] == 1.0
    assert (np.diff(got) > 0).all()


def test_output_precision_is_part_of_each_contract():
    assert color.srgb8_to_linear(np.zeros(3, np.uint8)).dtype == np.float64
    assert color.srgb_to_linear(np.zeros(3)).dtype == np.float32
    assert color.linear_to_srgb(np.zeros(3, np.float32)).dtype == np.float64
    assert color.linear_to_srgb8(np.zeros((2, 5, 3))).dtype == np.uint8
    assert color.linear_to_srgb8(np.zeros((2, 5, 3))).shape == (2, 5, 3)


def test_bytes_round_trip_exactly():
    b = np.arange(256, dtype=np.uint8)
    assert np.array_equal(color.linear_to_srgb8(color.srgb8_to_linear(b)[:, None])[:, 0], b)
    assert np.array_equal(color.linear_to_srgb8(color.srgb_to_linear(b / 255.0)[:, None])[:, 0], b)


def test_float_round_trip_within_half_a_byte():
    s = np.linspace(0.0, 1.0, 10001)
    back = color.linear_to_srgb(color.srgb_to_linear(s))
    assert np.abs(back - s).max() <= 0.5 / 255
    lin = np.linspace(0.0, 1.0, 10001)
    enc = color.linear_to_srgb8(lin[:, None])[:, 0]
    # encoding picks the nearest byte on the sRGB scale
    assert np.abs(enc / 255.0 - color.linear_to_srgb(lin)).max() <= 0.5 / 255 + 1e-12


def test_out_of_range_linear_is_clipped():
    out = color.linear_to_srgb8(np.array([[-0.5, 2.0, np.float32(1.0)]]))
    assert out.tolist() == [[0, 255, 255]]
    clipped = color.linear_to_srgb(np.array([-1.0, 3.0]))
    assert clipped[0] == 0.0 and abs(clipped[1] - 1.0) <= 1e-15


def _css_hsl(h, s, light):
    """CSS Color 4's hsl() -> sRGB in [0, 1] (h in turns): an independent HSL formula."""
    a = s * min(light, 1 - light)
    out = []
    for n in (0, 8, 4):
        k = (n + h * 12) % 12
        out.append(light - a * max(-1, min(k - 3, 9 - k, 1)))
    return out


def test_palette_is_golden_angle_hsl_with_alternating_lightness():
    # the formula the web page mirrors: HSL(i * 0.618033988749895 mod 1, 0.65, 0.55 | 0.42)
    assert color.palette_colour(0) == [215, 66, 66]
    for i in range(64):
        h = (i * 0.618033988749895) % 1.0
        expect = np.array(_css_hsl(h, 0.65, 0.55 if i % 2 == 0 else 0.42)) * 255
        got = np.array(color.palette_colour(i))
        # round-half cases may differ between the two formulas by float noise: one step at most
        assert np.abs(got - expect).max() <= 0.5 + 1e-9
    assert color.palette(5) == [color.palette_colour(i) for i in range(5)]
    assert len({tuple(c) for c in color.palette(32)}) == 32


def test_segmentation_stores_the_palette_and_render_falls_back_to_it():
    boxes = [((0.0, 0.0, 0.0), (0.3, 0.2, 0.4)), ((0.5, 0.0, 0.0), (0.7, 0.5, 0.2))]
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes), ((0, 0, 0), (0.7, 0.5, 0.4)), voxel_size=0.025
    )
    seg = segment(c, method="fast", cache=False)
    info = seg.meta["parts_info"]
    assert len(info) == 2
    assert [p["color"] for p in info] == color.palette(2)
    bare = seg.replace(meta={k: v for k, v in seg.meta.items() if k != "parts_info"})
    assert render.part_colors(bare).tolist() == color.palette(2)
