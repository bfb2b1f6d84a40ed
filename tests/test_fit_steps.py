"""The named steps of fit's stretches and axes, of the zone candidates along an axis, of the
junction merge, and the tile join's jump that fit weighs: each on its own, against analytic
truth."""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

from partscale import shapes
from partscale.edit import Edit, ScrewZone
from partscale.errors import InputError
from partscale.zones import profile
from partscale.zones.suggest import Candidate, join_jump

# the modules (partscale.zones's names fit and suggest are the functions)
fit_mod = importlib.import_module("partscale.zones.fit")
suggest_mod = importlib.import_module("partscale.zones.suggest")

# -- the stretch edits absorbing a change over slabs (h = 1: lengths in voxels) -----------------


def test_rooms_are_what_each_zone_can_give_down_to_its_minimum():
    assert fit_mod._rooms([(0.0, 10.0), (0.0, 1.5)], 1.0) == [8.0, 0.0]


def test_peers_are_the_slabs_comparable_to_the_largest():
    # at least half the largest and the spread length long, largest first
    assert fit_mod._peers([6.0, 10.0, 4.0, 1.0], 2, 1.0) == [1, 0]
    assert fit_mod._peers([6.0, 10.0, 4.0, 1.0], 8, 1.0) == [1]


def test_growth_goes_to_the_next_slab_only_where_the_largest_would_more_than_double():
    zones = [(0.0, 10.0), (20.0, 28.0), (30.0, 31.0)]
    assert fit_mod._growth_count(zones, 9.0, 1.0, 2) == 1
    # 25 > 10: the second (8 >= half of 10) shares it; the third (1 voxel) never does
    assert fit_mod._growth_count(zones, 25.0, 1.0, 2) == 2


def test_a_shrink_takes_the_fewest_slabs_then_the_calmest_planes():
    inset, full = [(1.0, 9.0), (21.0, 27.0)], [(0.0, 10.0), (20.0, 28.0)]
    # 5 voxels: the inset planes' largest slab (room 6) alone
    zones, room, n = fit_mod._fewest_slabs([inset, full], -5.0, 1.0)
    assert (zones, room, n) == (inset, [6.0, 4.0], 1)
    # 7.5 voxels: the insets need both slabs, the full lengths the largest alone
    zones, room, n = fit_mod._fewest_slabs([inset, full], -7.5, 1.0)
    assert (zones, n) == (full, 1)
    # more than every slab can give: every slab's full length
    zones, room, n = fit_mod._fewest_slabs([inset, full], -40.0, 1.0)
    assert (zones, room, n) == (full, [8.0, 6.0], 2)


def test_even_plan_spreads_a_deep_shrink_over_peers_alike():
    zones = [(0.0, 10.0), (20.0, 30.0)]
    full = [10.0, 10.0]
    plan, even = fit_mod._even_plan([zones], full, -8.0, 1.0, 2, False)
    assert plan == (zones, [8.0, 8.0], 2) and even == [4.0, 4.0]
    # a shrink the largest alone gives within MAX_SHRINK: no even plan
    assert fit_mod._even_plan([zones], full, -4.0, 1.0, 2, False) == (None, [])
    # even growth: every slab, largest first, in proportion to its length
    plan, even = fit_mod._even_plan([[(0.0, 4.0), (10.0, 20.0)]], [4.0, 10.0], 3.0, 1.0, 2, True)
    assert plan == ([(10.0, 20.0), (0.0, 4.0)], [], 2) and even == [10.0, 4.0]


def test_shares_split_the_change_by_weight_in_whole_voxels_the_last_taking_the_rest():
    edits, left = fit_mod._shares([(0.0, 10.0), (20.0, 28.0)], [10.0, 8.0], [], 9.0, 1.0, "x")
    assert [(e.start, e.end, e.dest) for e in edits] == [(0.0, 10.0, 15.0), (20.0, 28.0, 32.0)]
    assert left == 0.0
    # a shrink gives no more than a slab's room: what is left is returned
    edits, left = fit_mod._shares([(0.0, 10.0)], [8.0], [8.0], -10.0, 1.0, "x")
    assert [e.dest for e in edits] == [2.0] and left == -2.0


def test_stretch_edits_compose_the_steps():
    slabs = [
        Candidate("x", "stretch", (0.0, 20.0), None, None, 1.0, "", (0.0, 20.0)),
        Candidate("x", "stretch", (40.0, 56.0), None, None, 1.0, "", (40.0, 56.0)),
    ]
    edits, left = fit_mod._stretch_edits(slabs, 5.0, 1.0, "x", spread_voxels=2)
    assert left == 0.0 and [float(e.dest - e.end) for e in edits] == [5.0]
    assert 0.0 <= edits[0].start < edits[0].end <= 20.0  # the largest slab, planes inside it
    # 30 voxels: the largest alone would more than double, both take it by their length
    edits, left = fit_mod._stretch_edits(slabs, 30.0, 1.0, "x", spread_voxels=2)
    assert left == 0.0 and sum(float(e.dest - e.end) for e in edits) == 30.0
    assert len(edits) == 2 and edits[0].dest - edits[0].end > edits[1].dest - edits[1].end
    assert fit_mod._stretch_edits(slabs, 0.0, 1.0, "x") == ([], 0.0)


# -- fit's axis steps ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def bookcase():
    return shapes.bookcase(height=1.22)  # four rows of 30 cm (15 voxels) along y


def test_targets_parse_each_axis_on_its_extent(bookcase):
    size, targets = fit_mod._targets(bookcase, None)
    ext = bookcase.surface_bounds()[1] - bookcase.surface_bounds()[0]
    assert list(size) == ["="] * 3 and targets == pytest.approx(ext)
    _, targets = fit_mod._targets(bookcase, ["=", "150%", 0.5])
    assert targets == pytest.approx([ext[0], 1.5 * ext[1], 0.5])
    with pytest.raises(InputError, match="expected three values"):
        fit_mod._targets(bookcase, ["1", "2"])


def test_an_axis_a_count_decides_must_stay(bookcase):
    ext = float(bookcase.surface_bounds()[1, 1] - bookcase.surface_bounds()[0, 1])
    fit_mod._check_unchanged(bookcase, 1, ext + 0.4 * bookcase.voxel_size, "add", "x", "=")
    with pytest.raises(InputError, match=r"add y: expected the size along y unchanged \(=\)"):
        fit_mod._check_unchanged(bookcase, 1, ext + 0.1, "add", "the count decides", "2m")
    with pytest.raises(InputError, match=r"size y: expected = \(the steps"):
        fit_mod._check_unchanged(bookcase, 1, ext + 0.1, "size", "the steps added move along", 2)


def test_moved_axes_are_a_flights_diagonal():
    flight = ScrewZone("y", (0.0, 0.2, 0.3), 0.5, 1)
    assert fit_mod._moved_axes([flight], 1) == {2}
    assert fit_mod._moved_axes([Edit("y", 0.0, 1.0, 2.0)], 1) == set()


def test_shrinkable_refuses_a_target_below_the_rigid_parts(bookcase):
    h = bookcase.voxel_size
    slab = Candidate("y", "stretch", (0.0, 0.2), None, None, 1.0, "", (0.0, 0.2))
    room = 0.2 - fit_mod.MIN_SLAB_VOXELS * h
    fit_mod._check_shrinkable([], [slab], 1.0 - room, 1.0, h, ("y", "m"))
    with pytest.raises(InputError, match="size y: expected at least"):
        fit_mod._check_shrinkable([], [slab], 1.0 - room - h, 1.0, h, ("y", "m"))


def test_whole_periods_tile_the_bookcases_rows(bookcase):
    p = profile(bookcase, 1)
    cands = suggest_mod.axis_candidates(bookcase, 1, prof=p, features=[])
    tiles = [c for c in cands if c.kind == "tile"]
    tiled, edits, why = fit_mod._whole_periods(bookcase, 1, p, tiles, 0.3, [])
    assert tiled is not None and tiled.k == 1 and tiled.period == pytest.approx(0.3)
    assert edits == [tiled.edit] and why[0].startswith("y: tile 1 more period(s)")
    # less than half a period: no whole period
    assert fit_mod._whole_periods(bookcase, 1, p, tiles, 0.1, [])[0] is None


# -- the zone candidates along an axis ----------------------------------------------------------


def test_repeat_tiles_of_the_bookcase_are_one_row(bookcase):
    p = profile(bookcase, 1)
    tiles = suggest_mod._repeat_tiles(p, suggest_mod.find_repeats(p))
    assert tiles and all(t.kind == "tile" and t.axis == "y" for t in tiles)
    assert tiles[0].period == pytest.approx(0.3, abs=0.5 * bookcase.voxel_size)
    assert tiles[0].count == 4


def test_slab_candidates_of_a_box_span_it():
    box = shapes.box((0, 0, 0), (1.0, 0.4, 0.4), voxel_size=0.02)
    p = profile(box, 0)
    slabs = suggest_mod._slab_candidates(p, box, [])
    assert len(slabs) == 1 and slabs[0].kind == "stretch"
    s, e = slabs[0].zone
    assert 0.0 <= s < 0.1 and 0.9 < e <= 1.0  # within its ends (a few voxels of edge rounding)


def test_part_planes_pull_a_slabs_planes_within_a_voxel():
    h = 0.1
    assert suggest_mod._at_part_planes(1.0, 2.0, np.zeros(0), h) == (1.0, 2.0, "")
    s, e, why = suggest_mod._at_part_planes(1.0, 2.0, np.array([1.05, 1.97, 5.0]), h)
    assert (s, e) == (1.05, 1.97) and why == ", planes at part boundaries"
    # a part plane outside the slab does not widen it
    s, e, _ = suggest_mod._at_part_planes(1.0, 2.0, np.array([0.95, 2.05]), h)
    assert (s, e) == (1.0, 2.0)


def test_part_rows_need_parts(bookcase):
    p = profile(bookcase, 1)
    assert suggest_mod._part_row_tiles(p, bookcase, []) == []  # no segmentation: no rows


# -- the tile join's jump, which fit weighs ------------------------------------------------------


def test_join_jump_is_small_air_to_air_and_large_where_a_board_meets_air(bookcase):
    # shelves on layers 3 + 15 i: one row from mid-air to mid-air joins like the original (the
    # stage's blend leaves a little); a join that puts a shelf's underside against air jumps
    # by the board
    assert join_jump(bookcase, 1, 10.5, 15.0) <= 0.15
    assert join_jump(bookcase, 1, 18.0, 7.0) >= 2.0
    # a plane through the middle of a board steps in the original too: not the join's doing
    assert join_jump(bookcase, 1, 18.5, 7.0) <= 0.15


def test_window_step_is_zero_for_a_linear_field_and_the_step_for_a_jump():
    h = 1.0
    ramp = np.broadcast_to(np.arange(8.0)[:, None, None] * 0.3 - 1.0, (8, 4, 4)).copy()
    ramp[:] = ramp[:, :1, :1]  # every column the same: the surface crosses near layer 3
    flat = np.zeros((8, 4, 4))  # on the surface everywhere, not changing
    assert suggest_mod._window_step(flat, h) == 0.0
    assert suggest_mod._window_step(ramp, h) == pytest.approx(0.0, abs=1e-6)
    jump = flat.copy()
    jump[4:] = 0.8  # a step of 0.8 voxel between the pair, none outside it
    assert suggest_mod._window_step(jump, h) == pytest.approx(0.8)
    assert math.isnan(suggest_mod._window_step(np.full((8, 4, 4), 5.0), h))  # no surface
