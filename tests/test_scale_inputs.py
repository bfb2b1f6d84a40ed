"""The edit stage's public boundary: tile counts, positions and options it accepts or refuses.

Refusals are :class:`InputError` (one line, expected vs got), never a TypeError/ValueError or an
OverflowError from deeper down.
"""

from __future__ import annotations

import numpy as np
import pytest

from partscale import shapes
from partscale.edit import reevaluate, scale, tile_count
from partscale.errors import InputError

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


def test_tile_count_is_zero_only_for_a_zero_destination():
    """0 copies (the zone removed) for ``dest == start`` exactly, never by rounding: a tile to
    30% of its length, or to a hair above its start, is still one copy."""
    assert tile_count(0.2, 0.0) == 0
    assert [tile_count(0.2, t) for t in (0.06, 0.02, 1e-12)] == [1, 1, 1]


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


@pytest.mark.parametrize(
    ("zone", "to", "what", "got"),
    [
        ((0.3, 0.7), "1e400%", "expected a finite percentage", "1e400%"),
        ((0.3, 0.7), "inf%", "expected a finite percentage", "inf%"),
        (("10%", "nan%"), 0.9, "expected a finite percentage", "nan%"),
        ((0.3, 0.7), "inf", "expected a finite number", "inf"),
        ((0.3, 0.7), float("inf"), "expected a finite number", "inf"),
        ((float("nan"), 0.7), 0.9, "expected a finite number", "nan"),
        ((0.3, 0.7), 1.7e308, "expected finite positions", "1.7e+308"),
    ],
)
def test_non_finite_positions_are_refused(box, zone, to, what, got):
    with pytest.raises(InputError, match=what) as exc:
        scale(box, axis="x", zone=zone, to=to)
    assert got in str(exc.value) and "\n" not in str(exc.value)


@pytest.mark.parametrize(
    ("zone", "to"),
    [
        ((np.float32(0.3), np.float32(0.7)), np.float32(0.9)),
        (np.array([0.3, 0.7]), np.float64(0.9)),
        ((np.int64(0), 0.5), np.int64(1)),
    ],
)
def test_numpy_numbers_are_positions(box, zone, to):
    out = scale(box, axis="x", zone=zone, to=to)
    want = scale(box, axis="x", zone=tuple(float(v) for v in zone), to=float(to))
    assert np.array_equal(out.sdf, want.sdf)


@pytest.mark.parametrize("flag", [True, np.bool_(False)])
def test_booleans_are_not_positions(box, flag):
    with pytest.raises(InputError, match="expected a number or a percentage"):
        scale(box, axis="x", zone=(0.3, 0.7), to=flag)


@pytest.mark.parametrize("zone", [None, 0.3, "30%", (0.1, 0.3, 0.5)])
def test_zone_must_be_two_positions(box, zone):
    with pytest.raises(InputError, match=r"expected \[START, END\], got"):
        scale(box, axis="x", zone=zone, to=0.9)


@pytest.mark.parametrize(
    ("kwargs", "fragments"),
    [
        ({"mask": np.ones((2, 2, 2), bool)}, ["mask", "expected", "(2, 2, 2)"]),
        ({"mask": np.full((57, 32, 22), 0.5)}, ["mask", "bool", "float64"]),
        ({"band": "3"}, ["band", "finite positive", "'3'"]),
        ({"band": -1}, ["band", "finite positive", "-1"]),
        ({"band": 0.0}, ["band", "finite positive", "0.0"]),
        ({"band": float("inf")}, ["band", "finite positive", "inf"]),
        ({"band": True}, ["band", "finite positive", "True"]),
    ],
)
def test_reevaluate_refuses_bad_mask_and_band(box, kwargs, fragments):
    with pytest.raises(InputError) as exc:
        reevaluate(box, **kwargs)
    for f in fragments:
        assert f in str(exc.value), (f, str(exc.value))


def test_reevaluate_takes_numpy_band_and_integer_mask(box):
    mask = np.zeros(box.shape, np.uint8)
    mask[:, :, :8] = 2
    out = reevaluate(box, mask, band=np.float32(2.0))
    want = reevaluate(box, mask.astype(bool), band=2.0)
    assert np.array_equal(out.sdf, want.sdf)


def test_recipe_refusals_echo_positions_only_where_they_still_mean_them(box):
    """A refused recipe step echoes the user's ``%`` with its world value; after an edit on the
    same axis that ``%`` of the input lies elsewhere, so only the world value is given."""
    from partscale.edit import apply_recipe

    bad = {"axis": "x", "zone": ["50%", "90%"], "to": "-5%"}
    with pytest.raises(InputError, match=r"DEST > START 50% \(.*\), got -5% \("):
        apply_recipe(box, {"edits": [bad]})
    grow = {"axis": "x", "zone": ["20%", "40%"], "to": "60%"}
    with pytest.raises(InputError, match="DEST > START") as err:
        apply_recipe(box, {"edits": [grow, bad]})
    assert "%" not in str(err.value), err.value


def test_a_recipe_too_large_is_refused_before_its_first_edit(box, monkeypatch):
    """Two edits whose first result fits but whose last would not: refused up front, naming the
    recipe and what it would need (a refusal at the second edit would name that edit)."""
    from partscale.edit import apply_recipe, recipe_shape
    from partscale.errors import MemoryLimitError

    edits = [{"axis": a, "zone": ["30%", "60%"], "to": "200%"} for a in "xy"]
    first, last = (np.prod(recipe_shape(box, {"edits": edits[:k]})) for k in (1, 2))
    assert last > 1.5 * first  # the case this test is about
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", str(int(64 * (first + last) / 2)))
    with pytest.raises(MemoryLimitError, match=r"a recipe of 2 edits: .* would need"):
        apply_recipe(box, {"edits": edits})
