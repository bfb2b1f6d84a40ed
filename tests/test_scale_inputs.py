"""The edit stage's public boundary: tile counts, positions and options it accepts or refuses.

Refusals are :class:`InputError` (one line, expected vs got), never a TypeError/ValueError or an
OverflowError from deeper down.
"""

from __future__ import annotations

import pytest

from partscale import shapes
from partscale.edit import scale, tile_count

H = 0.02


@pytest.fixture(scope="module")
def box():
    return shapes.box((0.0, 0.0, 0.0), (1.0, 0.5, 0.3), voxel_size=H)


@pytest.mark.parametrize(
    ("start", "end", "dest"),
    [(0.2, 0.4, 0.5), (0.1, 0.3, 0.4), (0.3, 0.6, 0.75), (0.0, 0.7, 1.05), (0.2, 0.6, 0.8)],
)
def test_tile_count_rounds_one_and_a_half_periods_up(start, end, dest):
    """The documented half-way case, whatever the float noise of ``dest - start``."""
    assert tile_count(end - start, dest - start) == 2


def test_tile_count_rounds_elsewhere_to_nearest():
    assert [tile_count(0.2, t) for t in (0.05, 0.25, 0.29, 0.31, 0.49, 0.5, 0.69)] == [
        1,
        1,
        1,
        2,
        2,
        3,
        3,
    ]


def test_half_way_tile_of_a_box_makes_two_copies(box):
    out = scale(box, axis="x", zone=(0.2, 0.4), to=0.5, mode="tile")
    assert out.meta["history"][-1]["copies"] == 2
