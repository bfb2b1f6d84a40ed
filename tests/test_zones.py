"""Zones that find themselves: suggest, snap, fit, designer units and recipe coordinates."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from conftest import ROOT, assert_bad_input

from partscale import shapes
from partscale.csdf import load, save
from partscale.edit import (
    Edit,
    Recipe,
    apply_edit,
    apply_recipe,
    parse_position,
    recipe_from_history,
)
from partscale.errors import InputError
from partscale.zones import fit, parse_length, parse_size, snap, suggest

H = 0.02


def shelf(n=5, pitch=0.3, board=0.04, width=0.8, depth=0.3, side=0.04):
    """Two side panels and ``n`` boards along y, ``pitch`` apart (a bookcase)."""
    height = (n - 1) * pitch + board
    boxes = [((0, 0, 0), (side, height, depth)), ((width - side, 0, 0), (width, height, depth))]
    boxes += [((0, m * pitch, 0), (width, m * pitch + board, depth)) for m in range(n)]
    bounds = np.array([[0, 0, 0], [width, height, depth]], float)
    return shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H, source="shelf")


def table(length=1.2, height=0.7, depth=0.6, top=0.05, leg=0.06):
    boxes = [((0, height - top, 0), (length, height, depth))]
    for x in (0, length - leg):
        for z in (0, depth - leg):
            boxes.append(((x, 0, z), (x + leg, height, z + leg)))
    bounds = np.array([[0, 0, 0], [length, height, depth]], float)
    return shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H, source="table")


@pytest.fixture(scope="module")
def bookcase():
    return shelf()


@pytest.fixture(scope="module")
def desk():
    return table()


def extent(c, ax):
    sb = c.surface_bounds()
    return float(sb[1, ax] - sb[0, ax])


# -- suggest on synthetic objects ----------------------------------------------------------------


def test_shelf_period_count_and_gaps(bookcase):
    tiles = [c for c in suggest(bookcase, "y") if c.kind == "tile"]
    assert tiles, "a shelf of five boards repeats along y"
    t = tiles[0]
    assert abs(t.period - 0.3) <= H / 2  # the pitch, within half a voxel
    assert t.count >= 4
    assert t.zone[1] - t.zone[0] == pytest.approx(t.period)
    # both planes lie in a gap between boards, not in one
    for plane in t.zone:
        in_board = min(abs(plane - (m * 0.3 + 0.02)) for m in range(5))
        assert in_board >= 0.02, plane
    assert 0 < t.score <= 1


def test_no_tile_on_a_table_and_its_top_is_a_constant_slab(desk):
    cands = suggest(desk)
    assert not [c for c in cands if c.kind == "tile"]  # two legs are no repeat
    x = [c for c in cands if c.axis == "x" and c.kind == "stretch"]
    assert x and x[0].zone[0] <= 0.3 and x[0].zone[1] >= 0.9  # between the legs
    y = [c for c in cands if c.axis == "y" and c.kind == "stretch"]
    assert y and y[0].zone[1] - y[0].zone[0] >= 0.5  # the legs below the top


def drawer_pair():
    """Two drawers between three boards under a top, their handles mirrored about the middle."""
    boxes = [((0, 0.56, 0), (1.1, 0.6, 0.3))]
    boxes += [((x, 0, 0), (x + 0.04, 0.56, 0.3)) for x in (0.1, 0.53, 0.96)]
    boxes += [((0.14, 0.1, 0.28), (0.53, 0.5, 0.3)), ((0.57, 0.1, 0.28), (0.96, 0.5, 0.3))]
    boxes += [((0.36, 0.25, 0.3), (0.42, 0.35, 0.36)), ((0.68, 0.25, 0.3), (0.74, 0.35, 0.36))]
    bounds = np.array([[0, 0, 0], [1.1, 0.6, 0.36]], float)
    return shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H)


def test_mirrored_drawers_tile_one_drawer_and_its_divider():
    tiles = [c for c in suggest(drawer_pair(), "x") if c.kind == "tile"]
    assert tiles, "two drawers between boards repeat along x, though mirrored"
    t = tiles[0]
    # one drawer (0.14..0.53) and one divider (0.04): the shift from one drawer to the next
    assert abs(t.period - 0.43) <= H / 2 and t.count == 2
    # the planes at the start of a drawer and of the next, or at their ends
    assert min(abs(t.zone[0] - 0.14), abs(t.zone[0] - 0.53)) <= H / 2, t.zone
    assert "mirrored" in t.reason


def test_a_row_of_equal_parts_of_the_segmentation_is_a_repeat():
    # three seat blocks glued into one bar: a constant cross-section, but three equal parts
    w = 0.3
    bar = shapes.grid(
        lambda p: shapes.boxes_sdf(p, [((0, 0, 0), (3 * w, 0.2, 0.4))]),
        np.array([[0, 0, 0], [3 * w, 0.2, 0.4]], float),
        voxel_size=H,
    )
    boxes = [{"index": i, "bbox": [[i * w, 0, 0], [(i + 1) * w, 0.2, 0.4]]} for i in range(3)]
    assert not [c for c in suggest(bar, "x") if c.kind == "tile"]
    tiles = [c for c in suggest(bar.replace(meta={**bar.meta, "parts_info": boxes}), "x")]
    tiles = [c for c in tiles if c.kind == "tile"]
    assert tiles and abs(tiles[0].period - w) <= H / 2 and tiles[0].count == 3
    assert abs(tiles[0].zone[0] - w) <= H / 2  # the planes between parts
    pair = bar.replace(meta={**bar.meta, "parts_info": boxes[:2]})
    assert not [c for c in suggest(pair, "x") if c.kind == "tile"]  # two equal parts: no row


def rod():
    """A round rod along the diagonal of x and y: every x layer differs from its neighbour."""
    a, b, r = np.array([0.0, 0.0, 0.1]), np.array([0.6, 0.6, 0.1]), 0.06

    def sdf(p):
        t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
        return np.linalg.norm(p - (a + t[:, None] * (b - a)), axis=1) - r

    return shapes.grid(sdf, [[-r, -r, 0.1 - r], [0.6 + r, 0.6 + r, 0.1 + r]], voxel_size=H)


def test_a_diagonal_rod_has_no_candidate_across_it():
    assert suggest(rod(), "x") == []


# -- snap and fit on synthetic objects -----------------------------------------------------------


def test_snap_tile_moves_planes_to_one_period_in_the_gaps(bookcase):
    e, moves = snap(bookcase, Edit("y", "40%", "60%", "80%", "tile"))
    assert float(e.end) - float(e.start) == pytest.approx(0.3, abs=H / 2)
    assert moves and {m.plane for m in moves} <= {"start", "end", "to"}
    out = apply_edit(bookcase, e)
    # one whole board more, every board as thick as before: 6 boards along a side-free column
    col = out.sdf[out.shape[0] // 2, :, out.shape[2] // 2] <= 0
    runs = np.diff(np.concatenate([[0], col.astype(np.int8), [0]]))
    lengths = np.flatnonzero(runs == -1) - np.flatnonzero(runs == 1)
    assert len(lengths) == 6 and lengths.max() - lengths.min() <= 1


def test_snap_refuses_a_tile_on_a_non_repeating_axis(desk):
    with pytest.raises(InputError, match="repeated element"):
        snap(desk, Edit("x", "40%", "60%", "80%", "tile"))


def test_fit_tiles_whole_periods_and_hits_the_length(bookcase):
    target = extent(bookcase, 1) + 0.3 + 0.1  # one shelf and a bit
    recipe, why = fit(bookcase, ["=", repr(target), "="])
    modes = [e.mode for e in recipe.edits]
    assert modes[0] == "tile" and "global" not in modes
    out = apply_recipe(bookcase, recipe)
    assert abs(extent(out, 1) - target) <= H / 2
    assert any("tile" in w for w in why)


def test_fit_stretches_a_table_and_refuses_below_its_rigid_parts(desk):
    recipe, _ = fit(desk, ["150cm", "=", "="])
    assert [e.mode for e in recipe.edits] == ["stretch"]
    out = apply_recipe(desk, recipe)
    assert abs(extent(out, 0) - 1.5) <= H / 2
    with pytest.raises(InputError, match="rigid"):
        fit(desk, ["5cm", "=", "="])


def test_fit_says_where_a_change_asked_was_snapped_to_whole_voxels(desk):
    # +3.5 voxels asked: the table grows by whole voxels, and a line gives both lengths; a
    # change of whole voxels gets no such line
    h = desk.voxel_size
    recipe, why = fit(desk, [f"+{3.5 * h}", "=", "="])
    grown = extent(apply_recipe(desk, recipe), 0) - extent(desk, 0)
    assert abs(grown - 3.5 * h) >= 0.4 * h  # not what was asked ...
    snapped = [w for w in why if "asked: edits move whole voxels" in w]
    assert len(snapped) == 1, why  # ... and said
    assert f"of the +{3.5 * h * 100:.1f} cm asked" in snapped[0], snapped  # the desk is in m
    _, exact = fit(desk, [f"+{4 * h}", "=", "="])
    assert not [w for w in exact if "asked" in w], exact


@pytest.mark.parametrize("size", [["150cm", "=", "="], ["=", "90cm", "="]])
def test_fit_stretch_planes_leave_no_seam_on_the_table(desk, size):
    """The table's legs meet the top and their sdf feels it a few voxels along: fit puts the
    stretch planes where the surface does not change within the blend's reach, so no seam shows
    (planes 3 voxels in from the slab's ends gave 0.34 and 1.16 voxels)."""
    from partscale.evaluate import metrics as M
    from partscale.evaluate import zones_from_history

    recipe, _ = fit(desk, size)
    out = apply_recipe(desk, recipe)
    _, shape = M.seam_jumps(desk, out, zones_from_history(out, desk))
    assert shape <= 0.05


@pytest.mark.parametrize(("pitch", "more"), [(0.265, 2), (0.255, 1)])
def test_fit_tiles_a_non_whole_voxel_period_as_exact_copies(pitch, more):
    """Boards at a pitch of 13.25 (12.75) voxels: fit tiles a whole number of voxels (the
    measured period was tiled as is, each copy resampled and the content after it moved by a
    rounded length), so every copy is an exact shift of the original's layers: each board keeps
    its thickness, and the spacing error stays under 0.01 (0.011-0.012 before)."""
    from partscale.evaluate import metrics as M
    from partscale.evaluate import zones_from_history

    side, board, n = 0.1, 0.04, 6
    length = (n - 1) * pitch + board + 2 * side
    boxes = [((0, 0, 0), (side, 0.5, 0.3)), ((length - side, 0, 0), (length, 0.5, 0.3))]
    boxes += [((side + m * pitch, 0, 0), (side + m * pitch + board, 0.5, 0.3)) for m in range(n)]
    boxes.append(((0, 0, 0), (length, 0.04, 0.3)))
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes),
        np.array([[0, 0, 0], [length, 0.5, 0.3]]),
        voxel_size=H,
    )
    recipe, _ = fit(c, [repr(extent(c, 0) + more * pitch), "=", "="])
    t = recipe.edits[0]
    assert t.mode == "tile"
    copy = (float(t.end) - float(t.start)) / H
    grow = (float(t.dest) - float(t.end)) / H
    assert abs(copy - round(copy)) <= 1e-6 and abs(grow - more * round(copy)) <= 1e-6, (copy, grow)
    out = apply_recipe(c, recipe)
    assert abs(extent(out, 0) - extent(c, 0) - more * pitch) <= H / 2 + 1e-9
    line = (slice(None), int(0.3 / H), int(0.15 / H))
    thick, _ = _runs_along(out.sdf, 0, line[1:])
    # the first and last boards lie against the end panels: n + more runs
    assert len(thick) == n + more and set(thick[1:-1].tolist()) == {board / H}, thick
    assert M.spacing_error(c, out, zones_from_history(out, c)) <= 0.01


def _panel_and_boards(panel, x0, pitch, board, n):
    """A panel ``panel`` thick at x = 0 and ``n`` boards ``board`` thick every ``pitch`` from
    ``x0``, all 0.5 tall on a 0.04 plinth, 0.3 deep: a shelf whose remainder has a choice."""
    length = x0 + (n - 1) * pitch + board
    boxes = [((0, 0, 0), (panel, 0.5, 0.3)), ((0, 0, 0), (length, 0.04, 0.3))]
    boxes += [((x0 + m * pitch, 0, 0), (x0 + m * pitch + board, 0.5, 0.3)) for m in range(n)]
    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes),
        np.array([[0, 0, 0], [length, 0.5, 0.3]]),
        voxel_size=H,
    )


@pytest.mark.parametrize("rest", [1, 4, -3])
def test_fit_puts_the_remainder_in_a_long_span_not_in_a_board(rest):
    """A 5-voxel end panel, a 30-voxel empty span, then five 2-voxel boards 13 voxels apart: the
    remainder after whole periods (``rest`` voxels) goes into the span. Every board and the
    panel keep their thickness and the boards their pitch, within half a voxel (the old code
    stretched the panel, the only slab outside the repeat's region, by 1, 4 and -1 voxels)."""
    panel, span, pitch, board, n = 0.1, 0.6, 0.26, 0.04, 5
    x0 = panel + span
    c = _panel_and_boards(panel, x0, pitch, board, n)
    target = extent(c, 0) + pitch + rest * H
    recipe, why = fit(c, [repr(target), "=", "="])
    assert [e.mode for e in recipe.edits] == ["tile", "stretch"], why
    s = recipe.edits[1]
    assert panel <= float(s.start) and float(s.end) <= x0, s  # inside the span
    assert not [w for w in why if "thin slab" in w], why
    out = apply_recipe(c, recipe)
    assert abs(extent(out, 0) - target) <= H / 2 + 1e-9
    line = (int(0.3 / H), int(0.15 / H))
    (t0, x_0), (t1, x_1) = _runs_along(c.sdf, 0, line), _runs_along(out.sdf, 0, line)
    assert len(t1) == len(t0) + 1, (t0, t1)
    # thicknesses: the panel, then one board (all the same); pitches: the original's
    assert abs(t1[0] - t0[0]) <= 0.5 and np.abs(t1[1:] - t0[1]).max() <= 0.5, (t0, t1)
    assert np.abs(np.diff(x_1[1:]) - pitch / H).max() <= 0.5, x_1
    assert abs((x_1[1] - x_1[0]) - (x_0[1] - x_0[0]) - rest) <= 0.5, (x_0, x_1)


def _sideboard(bays=(0.6, 0.44, 0.52), board=0.04):
    """A sideboard along x: ``bays`` (inner widths) between dividers ``board`` thick, a top and a
    bottom board, 0.5 tall, 0.3 deep, each bay with a shelf at its own height (so no bay's
    cross-section matches another's: no repeat)."""
    xs = np.concatenate([[0.0], np.cumsum(np.array(bays) + board)])
    length = float(xs[-1] + board)
    boxes = [((0, 0, 0), (length, board, 0.3)), ((0, 0.5 - board, 0), (length, 0.5, 0.3))]
    boxes += [((x, 0, 0), (x + board, 0.5, 0.3)) for x in xs]
    boxes += [
        ((x + board, y, 0), (x + board + w, y + board, 0.3))
        for x, w, y in zip(xs[:-1], bays, (0.14, 0.24, 0.34), strict=True)
    ]
    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes),
        np.array([[0, 0, 0], [length, 0.5, 0.3]]),
        voxel_size=H,
    )


@pytest.mark.parametrize("shrink", [0.1, 0.6])
def test_fit_shrinks_comparable_bays_alike(shrink):
    """Three unequal bays (30, 22, 26 voxels inside): a shrink the largest bay takes within half
    its length goes to it alone (fewest seams); a larger one (0.6 m, as much as the largest bay
    holds) narrows every bay by the same fraction, within 1.5 voxels of each bay's share, and
    every divider keeps its thickness (the old rule took it from the two larger bays only: 29.5,
    22.5, 26 voxels became 12.5, 22.5, 13)."""
    bays = np.array([0.6, 0.44, 0.52])
    c = _sideboard(tuple(bays))
    target = extent(c, 0) - shrink
    recipe, why = fit(c, [repr(target), "=", "="])
    assert {e.mode for e in recipe.edits} == {"stretch"}, why
    out = apply_recipe(c, recipe)
    assert abs(extent(out, 0) - target) <= H / 2 + 1e-9
    line = (int(0.45 / H), int(0.15 / H))  # above the shelves
    (t0, x0), (t1, x1) = _runs_along(c.sdf, 0, line), _runs_along(out.sdf, 0, line)
    assert len(t1) == len(t0) == len(bays) + 1, (t0, t1)
    assert np.abs(t1 - t0).max() <= 0.5, (t0, t1)  # the dividers
    inner0, inner1 = np.diff(x0) - t0[1:], np.diff(x1) - t1[1:]
    if shrink <= 0.5 * bays.max():
        assert len(recipe.edits) == 1, why
        assert np.abs((inner0 - inner1)[1:]).max() <= 0.5, (inner0, inner1)
    else:
        share = shrink / H * inner0 / inner0.sum()
        assert np.abs((inner0 - inner1) - share).max() <= 1.5, (inner0, inner1, share)


def _cabinet(knob: bool = True, crown: bool = False, h: float = 0.01):
    """A cabinet 0.8 x 0.6 x 0.3 m: with ``knob`` a ball 3.5 cm across on its front at x 0.62
    (a few voxels of a 30 x 60 voxel cross-section); with ``crown`` a cushion-like top raised
    1.5 cm at most, gently, over x 0.1 to 0.7."""

    def sdf(p):
        d = shapes.box_sdf(p, (0, 0, 0), (0.8, 0.6, 0.3))
        if knob:
            d = np.minimum(d, shapes.sphere_sdf(p, (0.62, 0.45, 0.315), 0.035))
        if crown:  # a flat ellipsoid; its scaled-sphere distance is exact across the top
            r = np.array([0.3, 0.015, 0.14])
            q = (p - (0.4, 0.6, 0.15)) / r
            d = np.minimum(d, (np.linalg.norm(q, axis=-1) - 1) * r.min())
        return d

    return shapes.grid(sdf, np.array([[0, 0, 0], [0.8, 0.62, 0.35]]), voxel_size=h)


def test_a_knob_ends_the_constant_slab_and_fit_keeps_it_round():
    """A knob is a few voxels of the cross-section, which the whole-section test cannot see: no
    stretch candidate crosses it, the door either side of it is a candidate, and fitting the
    cabinet to 60 % of its width leaves the knob as wide as it was (within a voxel; the slab
    through it squashed it from 7 to 4 voxels)."""
    c = _cabinet()
    h = c.voxel_size
    stretch = [x for x in suggest(c, "x") if x.kind == "stretch"]
    assert all(x.zone[1] <= 0.585 + h / 2 or x.zone[0] >= 0.655 - h / 2 for x in stretch), [
        x.zone for x in stretch
    ]
    assert any(x.zone[0] <= 0.05 and x.zone[1] >= 0.5 for x in stretch), [x.zone for x in stretch]
    assert all("next to a local feature" in x.reason for x in stretch if x.zone[1] >= 0.5), [
        x.reason for x in stretch
    ]
    target = 0.6 * extent(c, 0)
    out = apply_recipe(c, fit(c, [repr(target), "=", "="])[0])
    assert abs(extent(out, 0) - target) <= h / 2 + 1e-9
    line = (round((0.45 - c.origin[1]) / h), round((0.33 - c.origin[2]) / h))  # through the ball
    (w0, _), (w1, _) = _runs_along(c.sdf, 0, line), _runs_along(out.sdf, 0, line)
    assert len(w0) == len(w1) == 1 and abs(w1[0] - w0[0]) <= 1, (w0, w1)


def test_local_features_name_the_knob_a_stretch_zone_holds():
    """local_features: the knob's span (within a voxel) for a zone across it, nothing for a zone
    beside it; feature_notes says so for a stretch across it only."""
    from partscale.zones import feature_notes, local_features

    c = _cabinet()
    h = c.voxel_size
    (got,) = local_features(c, 0, (0.05, 0.75))
    assert abs(got[0] - 0.585) <= h and abs(got[1] - 0.655) <= h, got
    assert local_features(c, 0, (0.05, 0.5)) == []
    # the axis by name as every zones function takes it; a wrong one is the user's error
    assert local_features(c, "X", (0.05, 0.75)) == [got]
    with pytest.raises(InputError, match="axis: expected one of x, y, z, got 'w'"):
        local_features(c, "w", (0.05, 0.75))
    across = Edit("x", 0.05, 0.75, 0.9, "stretch")
    (line,) = feature_notes(c, Recipe((across,)))
    assert "1 local feature" in line and "--snap" in line, line
    beside = Edit("x", 0.05, 0.5, 0.6, "stretch")
    assert feature_notes(c, Recipe((beside, Edit("x", 0.05, 0.75, 0.9, "tile")))) == []


def test_cli_scale_says_when_its_stretch_zone_holds_a_knob(cli, tmp_path):
    src, out = tmp_path / "c.csdf.npz", tmp_path / "o.csdf.npz"
    save(_cabinet(), src)
    args = ("scale", src, "-o", out, "--axis", "x", "--zone", "5cm", "75cm", "--to", "90cm")
    proc = cli(*args)
    assert proc.returncode == 0, proc.stderr
    assert "holds 1 local feature" in proc.stderr, proc.stderr
    proc = cli(*args, "--snap")
    assert proc.returncode == 0, proc.stderr
    assert "snap: moved" in proc.stderr and "local feature" not in proc.stderr, proc.stderr


def test_a_gentle_crown_along_the_whole_slab_stays_in_it():
    """A cushion's crown rises and falls along the slab too, but gently and over most of it:
    no knob. The slab is not cut around it (stretching it keeps its look)."""
    c = _cabinet(knob=False, crown=True)
    stretch = [x for x in suggest(c, "x") if x.kind == "stretch"]
    assert any(x.zone[0] <= 0.15 and x.zone[1] >= 0.65 for x in stretch), [x.zone for x in stretch]


def _boards(n, pitch, side=0.1, gap=0.11, board=0.04):
    """Two ``side`` end panels and ``n`` separate boards along x, ``pitch`` apart, ``gap`` from
    the panels: ``n + 2`` pieces (the default gap puts the boards' faces half-way between voxel
    centres, so each board is sampled ``board / H`` voxels thick)."""
    length = 2 * side + 2 * gap + (n - 1) * pitch + board
    x0 = side + gap
    boxes = [((0, 0, 0), (side, 0.5, 0.3)), ((length - side, 0, 0), (length, 0.5, 0.3))]
    boxes += [((x0 + m * pitch, 0, 0), (x0 + m * pitch + board, 0.5, 0.3)) for m in range(n)]
    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes),
        np.array([[0, 0, 0], [length, 0.5, 0.3]]),
        voxel_size=H,
    )


def _pieces(c):
    from scipy import ndimage

    return ndimage.label(c.sdf <= 0)[1]


@pytest.mark.parametrize("fewer", [1, 2])
def test_fit_shrinks_by_removing_whole_periods(fewer):
    """Six 2-voxel boards 13 voxels apart, fitted ``fewer`` periods shorter: whole periods are
    removed (a tile to its start, 0 copies), so every board left keeps its thickness and pitch
    within half a voxel and ``fewer`` boards are gone (the old code tiled 1 + fewer periods into
    one copy: boards 1 voxel thick, 4-5 voxels apart)."""
    n, pitch, board = 6, 0.26, 0.04
    c = _boards(n, pitch, board=board)
    target = extent(c, 0) - fewer * pitch
    recipe, why = fit(c, [repr(target), "=", "="])
    t = recipe.edits[0]
    assert t.mode == "tile" and float(t.dest) == float(t.start), (recipe, why)
    assert any("0 copies" in w for w in why), why
    out = apply_recipe(c, recipe)
    assert out.meta["history"][-1]["copies"] == 0
    assert abs(extent(out, 0) - target) <= H / 2 + 1e-9
    assert _pieces(out) == _pieces(c) - fewer == n + 2 - fewer
    line = (int(0.25 / H), int(0.15 / H))
    assert set(_runs_along(c.sdf, 0, line)[0][1:-1].tolist()) == {board / H}
    thick, centre = _runs_along(out.sdf, 0, line)
    assert len(thick) == n + 2 - fewer, thick
    assert np.abs(thick[1:-1] - board / H).max() <= 0.5, thick
    assert np.abs(np.diff(centre[1:-1]) - pitch / H).max() <= 0.5, centre


def test_tile_to_the_zone_start_removes_it_and_joins_the_sides(bookcase):
    """A tile with ``to`` at the zone's start makes 0 copies: the zone is cut out, the object is
    shorter by the zone's length (within half a voxel) and its two sides join with no gap (the
    bookcase stays one piece), the other boards keep their thickness; stretch refuses it."""
    start, end = 0.3 + 0.13, 0.6 + 0.13  # one period, planes in gaps between boards
    out = apply_edit(bookcase, Edit("y", start, end, start, "tile"))
    assert abs(extent(out, 1) - (extent(bookcase, 1) - (end - start))) <= H / 2 + 1e-9
    assert _pieces(bookcase) == 1 and _pieces(out) == 1
    h = out.meta["history"][-1]
    assert h["copies"] == 0 and h["to_snapped"] == h["edit"]["zone"][0]
    line = (int(0.4 / H), int(0.15 / H))
    (t0, x0), (t1, x1) = _runs_along(bookcase.sdf, 1, line), _runs_along(out.sdf, 1, line)
    # the board at 0.6 is gone; the others keep their thickness, those beyond move by the zone
    assert len(t1) == len(t0) - 1 and np.abs(t1 - np.delete(t0, 2)).max() <= 0.5, (t0, t1)
    moved = np.concatenate([x0[:2], x0[3:] - (end - start) / H])
    assert np.abs(x1 - moved).max() <= 0.5, (x0, x1)
    from partscale.edit import describe_changes

    assert any("tile 0 copies: zone removed" in w for w in describe_changes([h], out))
    # a start a third of a voxel off the grid: the removed length is snapped, and said so
    off = start + H / 3
    out = apply_edit(bookcase, Edit("y", off, end, off, "tile"))
    said = describe_changes([out.meta["history"][-1]], out)
    assert any(w.startswith("zone start and destination") for w in said), said
    with pytest.raises(InputError, match="mode tile"):
        apply_edit(bookcase, Edit("y", start, end, start, "stretch"))
    # DEST an ulp before START (a float round trip, as a removal read back from its history
    # gives: the bookcase fitted to 80 % at 256 could not be scored) is the same removal
    ulp = apply_edit(bookcase, Edit("y", start, end, np.nextafter(start, -np.inf), "tile"))
    exact = apply_edit(bookcase, Edit("y", start, end, start, "tile"))
    assert ulp.meta["history"][-1]["copies"] == 0 and np.array_equal(ulp.sdf, exact.sdf)
    with pytest.raises(InputError, match="DEST == START"):
        apply_edit(bookcase, Edit("y", start, end, np.nextafter(start, -np.inf), "stretch"))


def test_a_removed_zone_carries_the_planes_of_the_edits_after_it(bookcase):
    """In a recipe, a zone removed (tile to its start) moves the planes beyond it by its length:
    a stretch drawn on the input beyond it applies where it was drawn, and recipe_shape predicts
    the grid."""
    from partscale.edit import recipe_shape

    recipe = Recipe(
        (Edit("y", 0.43, 0.73, 0.43, "tile"), Edit("y", 1.0, 1.1, 1.2, "stretch")),
    )
    out = apply_recipe(bookcase, recipe)
    assert out.shape == recipe_shape(bookcase, recipe)
    assert abs(extent(out, 1) - (extent(bookcase, 1) - 0.3 + 0.1)) <= H / 2 + 1e-9
    assert out.meta["history"][-1]["edit"]["zone"] == pytest.approx([0.7, 0.8], abs=1e-9)


def test_fit_says_when_only_a_thin_slab_can_take_the_remainder():
    """Boards 8 voxels apart (gaps of 6) 8 voxels from a 5-voxel panel: no slab is long enough
    and 3 voxels are beyond the copies' tolerance; with allow_deform the panel takes them, and
    the note says so (the old code said nothing); without, the copies do."""
    panel, pitch, board, n = 0.1, 0.16, 0.04, 5
    x0 = panel + 0.16
    c = _panel_and_boards(panel, x0, pitch, board, n)
    # no thin slab is stretched unless asked: the copies absorb the 3 voxels instead
    recipe, why = fit(c, [repr(extent(c, 0) + pitch + 3 * H), "=", "="])
    assert [e.mode for e in recipe.edits] == ["tile"], why
    assert not any("thin slab" in w for w in why), why
    recipe, why = fit(c, [repr(extent(c, 0) + pitch + 3 * H), "=", "="], allow_deform=True)
    assert [e.mode for e in recipe.edits] == ["tile", "stretch"], why
    assert float(recipe.edits[1].end) <= panel, recipe  # the panel: the only slab outside
    thin = [w for w in why if "thin slab" in w]
    assert len(thin) == 1 and "could take it" in thin[0], why


def _frame():
    """Three 3-voxel posts 0.5 tall and two low panels 9 voxels wide between them, of different
    heights (no repeat; their constant slabs are 7 voxels)."""
    boxes = [((x, 0, 0), (x + 0.06, 0.5, 0.3)) for x in (0.0, 0.24, 0.48)]
    boxes += [((0.06, 0, 0), (0.24, 0.3, 0.3)), ((0.3, 0, 0), (0.48, 0.2, 0.3))]
    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes), np.array([[0, 0, 0], [0.54, 0.5, 0.3]]), voxel_size=H
    )


def test_fit_grows_two_comparable_thin_slabs_alike():
    """The frame (:func:`_frame`): no slab is 10 voxels long, so thin slabs take a growth of
    10 voxels, and the two panels share it (5 each, within a voxel) while the posts keep their
    width (one panel took all 10 before)."""
    c = _frame()
    recipe, why = fit(c, [repr(extent(c, 0) + 10 * H), "=", "="], allow_deform=True)
    out = apply_recipe(c, recipe)
    line = (int(0.4 / H), int(0.15 / H))  # above the panels: through the three posts
    (t0, x0), (t1, x1) = _runs_along(c.sdf, 0, line), _runs_along(out.sdf, 0, line)
    assert len(t1) == len(t0) == 3 and np.abs(t1 - t0).max() <= 0.5, (t0, t1)
    grown = np.diff(x1) - np.diff(x0)  # each panel's growth, voxels
    assert np.abs(grown - 5).max() <= 1, (grown, why)


def test_fit_scales_globally_rather_than_more_than_double_thin_slabs():
    """The same frame 30 voxels longer: each 7-voxel panel slab would grow by 15, a lump (a
    spiral staircase's steps came out so): global scaling, and the note says why."""
    c = _frame()
    with pytest.raises(InputError, match="size x: expected a part-aware way"):
        fit(c, [repr(extent(c, 0) + 30 * H), "=", "="])
    recipe, why = fit(c, [repr(extent(c, 0) + 30 * H), "=", "="], allow_deform=True)
    assert [e.mode for e in recipe.edits] == ["global"], why
    assert "thin slabs would more than double" in why[0], why


def _depths(csdf):
    """Voxels along x of each level of a :func:`_flight`, first tread to landing."""
    top = (csdf.sdf[:, :, csdf.shape[2] // 2] <= 0).sum(axis=1)
    levels = top[top > 0]
    cuts = np.flatnonzero(np.diff(levels) != 0) + 1
    return np.diff(np.concatenate([[0], cuts, [levels.size]]))


def _flight(treads=(8, 9, 7, 9, 8, 9), landing=14, rise=6):
    """A solid flight of stairs along x, 10 voxels deep (sizes in voxels): ``treads`` (7 to 9:
    under MIN_SPREAD_VOXELS, uneven as hand-built steps, so no repeat is found) rising ``rise``
    each, then a ``landing`` at the top."""
    xs = H * np.array([0, *np.cumsum(treads), sum(treads) + landing])
    boxes = [
        ((a, 0, 0), (b, (i + 1) * rise * H, 10 * H))
        for i, (a, b) in enumerate(itertools.pairwise(xs))
    ]
    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes),
        np.array([[0, 0, 0], [xs[-1], (len(treads) + 1) * rise * H, 10 * H]]),
        voxel_size=H,
    )


def _fit_flight(c, note):
    """Fit the flight ``c`` 30 % longer: stretches only, the first note starting ``note``, the
    length exact; the depths of its 7 levels before, what each grew by, and the notes."""
    target = 1.3 * extent(c, 0)
    recipe, why = fit(c, [repr(target), "=", "="], allow_deform=True)
    assert {e.mode for e in recipe.edits} == {"stretch"}, why
    assert why[0].startswith(f"x: {len(recipe.edits)} {note}"), why
    out = apply_recipe(c, recipe)
    assert abs(extent(out, 0) - target) <= H / 2 + 1e-9
    d0, d1 = _depths(c), _depths(out)
    assert len(d1) == len(d0) == 7, (d0, d1)
    return d0, d1 - d0, why


def test_fit_deepens_every_tread_of_a_flight_alike():
    """A flight 30 % longer: the landing alone would more than double, so the treads and the
    landing share the growth, each the same fraction of its slab (before, the landing took it
    all: kenney/stairs 130 % got a tread 1.5 m deep). Every level grows by less than three
    quarters of its depth and at least four grow; the steps keep their number; the first tread,
    a thin slab at the object's end (as a leg would be), keeps its depth."""
    d0, grown, _ = _fit_flight(_flight(), "constant slabs of comparable length")
    assert abs(grown[0]) <= 1, (d0, grown)
    assert (grown <= 0.75 * d0).all(), (d0, grown)
    assert (grown >= 2).sum() >= 4, (d0, grown)


def test_fit_deepens_every_thin_tread_alike_with_no_long_slab():
    """A flight whose landing is a tread's depth has no long slab: the treads (thin slabs) share
    a 30 % growth, each the same fraction, instead of the fewest of them each doubled (before:
    three of seven levels deepened by 6 voxels, the rest not at all; kenney/stairs 130 % along
    its height raised four risers of ten). The treads at the object's ends keep their depth.
    Why thin slabs take it is said once, in the first note, not once per tread."""
    d0, grown, why = _fit_flight(_flight(landing=8), "thin constant slabs of comparable length")
    assert [w for w in why if "could take it" in w] == why[:1], why
    stretches = [w for w in why if "stretch" in w]
    assert len(stretches) >= 5 and all(w.endswith(" voxels)") for w in stretches), why
    assert abs(grown[0]) <= 1 and abs(grown[-1]) <= 1, (d0, grown)
    # the five inner treads grow, each by a like share of its depth (its slab's fraction,
    # rounded to whole voxels), at most 3/4 of it
    share = grown[1:-1] / d0[1:-1]
    assert (grown[1:-1] >= 2).all() and (share <= 0.75).all(), (d0, grown)
    assert share.max() <= 1.5 * share.min(), (d0, grown)


def _splayed_stool():
    """A 4 cm top on two legs 5 cm thick splayed 10 cm over their 62 cm (capsules): their
    section drifts a sixth of a voxel a layer, so constant slabs are 3 voxels long."""

    def capsule(p, a, b, r):
        a, b = np.asarray(a, float), np.asarray(b, float)
        t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
        return np.linalg.norm(p - a - t[:, None] * (b - a), axis=1) - r

    def sdf(p):
        d = shapes.box_sdf(p, (0, 0.6, 0), (0.5, 0.64, 0.2))
        d = np.minimum(d, capsule(p, (0.04, 0.0, 0.1), (0.14, 0.62, 0.1), 0.025))
        return np.minimum(d, capsule(p, (0.46, 0.0, 0.1), (0.36, 0.62, 0.1), 0.025))

    return shapes.grid(sdf, np.array([[0, -0.03, 0], [0.5, 0.64, 0.2]]), voxel_size=0.01)


def test_fit_shrinks_a_splayed_leg_run_whole():
    """The stool to 70 % of its height: the legs' drift-split slabs (3 voxels each, a voxel of
    room apiece) shrink as one run, one stretch, with the top as thick as before; the old rule
    counted only the pieces' rooms and refused ("expected at least 53.0 cm")."""
    c = _splayed_stool()
    h = c.voxel_size
    target = 0.7 * extent(c, 1)
    recipe, why = fit(c, ["=", repr(target), "="])
    assert [e.mode for e in recipe.edits] == ["stretch"], why
    assert "the drifting run of slabs" in why[1], why
    out = apply_recipe(c, recipe)
    assert abs(extent(out, 1) - target) <= h / 2 + 1e-9
    line = (round((0.25 - c.origin[0]) / h), round((0.1 - c.origin[2]) / h))  # through the top
    (t0, _), (t1, _) = _runs_along(c.sdf, 1, line), _runs_along(out.sdf, 1, line)
    assert len(t0) == len(t1) == 1 and abs(t1[0] - t0[0]) <= 0.5, (t0, t1)
    assert _pieces(out) == 1


def test_fit_goes_global_only_as_a_last_resort_and_says_so():
    with pytest.raises(InputError, match="global scaling along x"):
        fit(rod(), ["120%", "=", "="])
    recipe, why = fit(rod(), ["120%", "=", "="], allow_deform=True)
    assert [e.mode for e in recipe.edits] == ["global"]
    assert "GLOBAL" in why[0] and "last resort" in why[0]


# -- units ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "want"),
    [
        ("=", 2.0),
        ("2.1", 2.1),
        ("210cm", 2.1),
        ("2100mm", 2.1),
        ("+20cm", 2.2),
        ("-5cm", 1.95),
        ("120%", 2.4),
        (1.5, 1.5),
    ],
)
def test_parse_size(spec, want):
    assert parse_size(spec, extent=2.0, units="m") == pytest.approx(want)


@pytest.mark.parametrize(
    ("spec", "units", "fragment"),
    [
        ("0", "m", "positive"),
        ("-250cm", "m", "positive"),
        ("2ft", "m", "unit"),
        ("20cm", "voxels", "bare number"),
        ("abc", "m", "expected a number"),
        ("+5%", "m", "percentage"),
    ],
)
def test_parse_size_refuses(spec, units, fragment):
    with pytest.raises(InputError, match=fragment):
        parse_size(spec, extent=2.0, units=units)


def test_positions_and_lengths_with_units():
    assert parse_position("30cm", "zone", "m") == pytest.approx(0.3)
    assert parse_position("45%", "zone", "m") == "45%"
    assert parse_position(" 0.25 ", "zone") == pytest.approx(0.25)
    with pytest.raises(InputError, match="bare number"):
        parse_position("30cm", "zone", None)  # units unknown: refused, not guessed
    with pytest.raises(InputError, match="unit of mm, cm, m"):
        parse_position("2ft", "zone", "m")
    with pytest.raises(InputError, match="number or a percentage"):
        parse_position("abc", "zone", "m")
    assert parse_length("-5cm", units="m") == pytest.approx(-0.05)


# -- recipe coordinates --------------------------------------------------------------------------


def test_recipe_positions_refer_to_the_input(desk):
    # two zones drawn on the original, the second beyond the first
    recipe = Recipe((Edit("x", 0.2, 0.4, 0.5, "stretch"), Edit("x", 0.8, 1.0, 1.1, "stretch")))
    out = apply_recipe(desk, recipe)
    by_hand = apply_edit(apply_edit(desk, recipe.edits[0]), Edit("x", 0.9, 1.1, 1.2, "stretch"))
    assert np.array_equal(out.sdf, by_hand.sdf)
    again = apply_recipe(desk, recipe_from_history(out, after=desk))
    assert np.array_equal(out.sdf, again.sdf) and np.array_equal(out.rgb, again.rgb)


def test_history_of_separate_runs_replays_on_the_original(desk):
    one = apply_edit(desk, Edit("x", 0.2, 0.4, 0.5, "stretch"))
    two = apply_edit(one, Edit("x", 0.9, 1.1, 1.2, "tile"))
    rec = recipe_from_history(two, after=desk)
    assert float(rec.edits[1].start) == pytest.approx(0.8)  # on the original
    again = apply_recipe(desk, rec)
    assert np.array_equal(two.sdf, again.sdf)


# -- the CLI -------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def shelf_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("zones") / "shelf.csdf.npz"
    save(shelf(), path)
    return path


def test_cli_suggest_json_and_png(cli, shelf_file, tmp_path):
    png = tmp_path / "s.png"
    proc = cli("suggest", shelf_file, "--json", "--png", png)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    got = doc["candidates"]
    assert [g["score"] for g in got] == sorted((g["score"] for g in got), reverse=True)
    # the shelves' compartments are elements along y, one group
    els = doc["elements"]["y"]
    assert els["groups"] and els["groups"][0]["count"] >= 3
    tiles = [g for g in got if g["kind"] == "tile"]
    assert [g["axis"] for g in tiles] == ["y"]
    assert {"axis", "kind", "zone", "period", "count", "score"} <= set(tiles[0])
    assert png.stat().st_size > 1000


def test_cli_scale_snap_by_and_copies(cli, shelf_file, tmp_path):
    out = tmp_path / "o.csdf.npz"
    proc = cli(
        "scale",
        shelf_file,
        "-o",
        out,
        "--axis",
        "y",
        "--zone",
        "40%",
        "60%",
        "--copies",
        "+1",
        "--snap",
    )
    assert proc.returncode == 0, proc.stderr
    assert "snap: moved" in proc.stderr
    entry = load(out).meta["history"][-1]
    assert entry["snapped"] and entry["copies"] == 2
    # a zone a third of a period wide: --copies +1 is still one more period once it snaps (the
    # growth it meant, a third of a period, rounded to none before)
    args = ("scale", shelf_file, "-o", out, "--axis", "y", "--zone", "40%", "48%")
    proc = cli(*args, "--copies", "+1", "--snap")
    assert proc.returncode == 0, proc.stderr
    grown = load(out)
    assert grown.meta["history"][-1]["copies"] == 2
    assert abs(extent(grown, 1) - (extent(load(shelf_file), 1) + 0.3)) <= H / 2 + 1e-9
    proc = cli(
        "scale", shelf_file, "-o", out, "--axis", "x", "--zone", "20cm", "60cm", "--by", "+10cm"
    )
    assert proc.returncode == 0, proc.stderr
    assert abs(extent(load(out), 0) - 0.9) <= H / 2


def test_cli_fit_writes_the_recipe(cli, shelf_file, tmp_path):
    out, rec = tmp_path / "f.csdf.npz", tmp_path / "r.json"
    proc = cli("fit", shelf_file, "-o", out, "--size", "=", "+30cm", "=", "--recipe-out", rec)
    assert proc.returncode == 0, proc.stderr
    assert "tile" in proc.stderr
    assert Recipe.load(rec).edits[0].mode == "tile"


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["fit", "{shelf}", "-o", "{out}", "--size", "0", "=", "="], ["size x", "positive"]),
        (["fit", "{shelf}", "-o", "{out}", "--size", "-2m", "=", "="], ["size x", "positive"]),
        (["fit", "{shelf}", "-o", "{out}", "--size", "3ft", "=", "="], ["unit"]),
        (["fit", "{shelf}", "-o", "{out}", "--size", "=", "5cm", "="], ["rigid"]),
        # refused with the memory it would need, before its choices are printed
        (
            ["fit", "{shelf}", "-o", "{out}", "--size", "1000000m", "=", "="],
            ["fit to 1000000m x = x =", "would need"],
        ),
        (
            [
                "scale",
                "{ball}",
                "-o",
                "{out}",
                "--axis",
                "x",
                "--zone",
                "40%",
                "60%",
                "--to",
                "80%",
                "--mode",
                "tile",
                "--snap",
            ],
            ["repeated element"],
        ),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(cli, shelf_file, tmp_path, args, fragments):
    ball = tmp_path / "rod.csdf.npz"
    save(rod(), ball)
    out = tmp_path / "o.csdf.npz"
    args = [a.format(ball=ball, shelf=shelf_file, out=out) for a in args]
    assert_bad_input(cli(*args), *fragments)
    assert not out.exists()


# -- real objects (the must-show) --------------------------------------------------------

PERIODS = {  # object, axis, the suite's period in % of the extent
    "bookcase": ("kenney/bookcaseOpen.glb", 1, 27.25),
    "bookshelf": ("polyhaven/wooden_bookshelf_worn/wooden_bookshelf_worn_1k.gltf", 1, 13.8),
    "railing": ("sweethome3d/railing.obj", 0, 12.5),
    "display": ("polyhaven/wooden_display_shelves_01/wooden_display_shelves_01_2k.gltf", 2, 32.5),
    "drawers": ("kenney/sideTableDrawers.glb", 0, 44.5),
    "sofa": ("polyhaven/sofa_03/sofa_03_1k.gltf", 0, 22.75),
}
PLAIN = {
    "table": "kenney/table.glb",
    "chair": "kenney/chair.glb",
    "stool": "polyhaven/painted_wooden_stool/painted_wooden_stool_1k.gltf",
    "sheen": "khronos/SheenChair.glb",
    "cabinet": "polyhaven/painted_wooden_cabinet/painted_wooden_cabinet_1k.gltf",
}


@pytest.fixture(scope="module")
def real():
    """Each real object imported once per module at --res 128 (skips when the data is absent)."""
    from conftest import data_path

    from partscale.ingest import load as ingest

    cache: dict = {}

    def get(rel):
        if rel not in cache:
            cache[rel] = ingest(data_path(rel), res=128)
        return cache[rel]

    return get


def best_period_error(c, ax, pct):
    """|best tile period - the suite's| in voxels (inf without a tile candidate)."""
    tiles = [x for x in suggest(c, ax) if x.kind == "tile"]
    if not tiles:
        return np.inf
    return abs(tiles[0].period - pct / 100 * extent(c, ax)) / c.voxel_size


@pytest.mark.slow
def test_periods_of_the_suites_repeating_objects(real):
    errors = {k: best_period_error(real(p), ax, pct) for k, (p, ax, pct) in PERIODS.items()}
    within = {k for k, v in errors.items() if v <= 1.0}
    # the issue asks 5 of 6; all six are found: the drawers (mirror images) and the sofa (soft
    # cushions) by the bounded detector, the other four by the full cross-section match
    assert len(within) >= 5 and within == set(PERIODS), errors


# more tables, chairs and a stool, from another catalogue (for the false-repeat check only)
MORE_PLAIN = {
    "sh_table": "sweethome3d/table.obj",
    "sh_chair": "sweethome3d/chair.obj",
    "sh_stool": "sweethome3d/stool.obj",
}


@pytest.mark.slow
def test_no_false_repeats_on_non_repeating_objects(real):
    flagged = [
        (k, a)
        for k, p in {**PLAIN, **MORE_PLAIN}.items()
        for a in range(3)
        if [x for x in suggest(real(p), a) if x.kind == "tile"]
    ]
    # the issue asks at least 10 clean object-axes; all 24 are
    assert flagged == [], flagged


@pytest.mark.slow
def test_stretch_candidates_on_the_table_and_the_chair(real):
    t = real(PLAIN["table"])
    lo, e = t.surface_bounds()[0, 0], extent(t, 0)
    assert any(
        c.kind == "stretch" and c.zone[0] <= lo + 0.25 * e and c.zone[1] >= lo + 0.75 * e
        for c in suggest(t, "x")
    )
    ch = real(PLAIN["chair"])
    lo, e = ch.surface_bounds()[0, 1], extent(ch, 1)
    # the legs between the rung and the seat: the suite's zone 18-37 %, nothing beyond 45 %
    assert any(
        c.kind == "stretch"
        and c.zone[0] <= lo + 0.18 * e
        and lo + 0.37 * e <= c.zone[1] <= lo + 0.45 * e
        for c in suggest(ch, "y")
    )


@pytest.mark.slow
@pytest.mark.parametrize("name", ["bookcase", "railing"])
def test_snapped_naive_zone_gives_the_suite_surface(real, name):
    suite = {  # single-edit entries (a recipe entry may share the object)
        o["path"]: o
        for o in json.loads((ROOT / "eval" / "suite.json").read_text())["objects"]
        if "edit" in o
    }
    rel, ax, _ = PERIODS[name]
    c = real(rel)
    given = suite[rel]["edit"]
    hand = apply_edit(c, {**given, "mode": "tile"})
    lo, hi = c.surface_bounds()[:, ax]
    _s, e, d = Edit.parse({**given, "mode": "tile"}).resolve(lo, hi)
    naive = Edit(given["axis"], "40%", "60%", lo + 0.6 * (hi - lo) + (d - e), "tile")
    snapped, _ = snap(c, naive)
    got = apply_edit(c, snapped)
    assert got.shape == hand.shape
    near = (np.abs(got.sdf) < 2 * c.voxel_size) | (np.abs(hand.sdf) < 2 * c.voxel_size)
    assert np.abs(got.sdf[near] - hand.sdf[near]).max() <= 0.5 * c.voxel_size
    # every copy of a shelf (baluster) keeps its thickness and spacing: along the line crossing
    # the most elements, each run of solid in the result is as thick as one in the original, and
    # each pitch between consecutive runs is one of the original's, within a voxel
    line = _most_crossed_line(c.sdf, ax)
    before = _runs_along(c.sdf, ax, line)
    after = _runs_along(got.sdf, ax, line)
    copies = round(
        (float(snapped.dest) - float(snapped.end)) / (float(snapped.end) - float(snapped.start))
    )
    assert copies >= 1 and len(after[0]) == len(before[0]) + copies, (before, after)
    for got_v, orig_v in ((after[0], before[0]), (np.diff(after[1]), np.diff(before[1]))):
        gap = np.abs(got_v[:, None] - orig_v[None, :]).min(axis=1)
        assert gap.max() <= 1.0, (name, got_v, orig_v)


def _runs_along(sdf, ax, line):
    """(thicknesses, centres) in voxels of the runs of solid along ``ax`` at lateral ``line``."""
    col = np.moveaxis(sdf, ax, 0)[(slice(None), *line)] <= 0
    d = np.diff(np.concatenate([[0], col.astype(np.int8), [0]]))
    start, stop = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    return (stop - start).astype(float), (start + stop - 1) / 2.0


def _most_crossed_line(sdf, ax):
    """The lateral index (2 ints) of the line along ``ax`` that crosses the most solid runs."""
    solid = np.moveaxis(sdf, ax, 0) <= 0
    starts = (np.diff(solid.astype(np.int8), axis=0) == 1).sum(axis=0)
    return np.unravel_index(int(np.argmax(starts)), starts.shape)


#: The metrics fit must not lose on against the hand-picked zone's best mode (with the tie
#: tolerances the suite's tables use); the length is checked on its own (0.5 voxel).
FIT_METRICS = ("prop_out", "prop_in", "spacing_err", "seam_color", "seam_shape", "pieces")


@pytest.mark.slow
def test_fit_reaches_each_suite_length_no_worse_than_the_hand_zone(real):
    """For every single-edit suite entry: fit to the length the hand-given edit reaches hits it
    within half a voxel, and on each metric is no worse than the better of stretch and tile
    with the hand-picked zone (the one with fewer failures). The cabinet's hand stretch fails
    prop. in and spacing; fit there trades them for seam jumps still under the suite's
    thresholds: asserted as no failure at all rather than metric by metric."""
    from dataclasses import replace

    from partscale.edit import resolve_edit
    from partscale.evaluate import failures_of, metric_score, winners, zones_from_history
    from partscale.evaluate import metrics as M
    from partscale.evaluate.suite import Entry, fit_recipe

    objs = json.loads((ROOT / "eval" / "suite.json").read_text())["objects"]
    worse = {}
    for o in (o for o in objs if "edit" in o):
        a = real(o["path"])
        edit = Edit.parse(o["edit"])
        ref = M.Reference(a)
        geo = resolve_edit(a, edit)
        orig = M.evaluate_original(ref, geo)
        hand = {
            mode: M.evaluate(ref, apply_edit(a, replace(edit, mode=mode)), replace(geo, mode=mode))
            for mode in ("stretch", "tile")
        }
        best = min(hand, key=lambda m: len(failures_of(hand[m], orig)))
        b = apply_recipe(a, fit_recipe(a, Entry(o["name"], o["path"], edit)))
        got = M.evaluate(ref, b, zones_from_history(b, a))
        # no tile leaves a loose sliver where a zone plane cuts an element (the drawers' END
        # plane cuts a thin rail: 21 pieces for 20 when the seams kept its sliver); an entry
        # judging hardware draws its hand zone through the handles on purpose: fit only there
        checked = [("fit", got)] if o.get("hardware") else [("tile", hand["tile"]), ("fit", got)]
        for mode, r in checked:
            assert r["pieces"] == r["pieces_expected"], (o["name"], mode, r["pieces"])
        sb = b.surface_bounds()
        assert abs(sb[1, geo.axis] - sb[0, geo.axis] - geo.target_length) <= 0.5 * a.voxel_size
        if o["name"] == "cabinet-narrower" or o.get("hardware"):
            # the cabinet's hand stretch fails prop. in and spacing; the dresser's is drawn
            # through its handles: fit keeps them and trades a little seam, under the threshold
            assert failures_of(got, orig) == [], failures_of(got, orig)
            continue
        rows = [{**got, "mode": "fit"}, {**hand[best], "mode": best}]
        for k in FIT_METRICS:
            f, h = metric_score(k, got, orig), metric_score(k, hand[best], orig)
            # the suite's tie rule; an unmeasured hand value still counts against fit
            if math.isfinite(f) and not (math.isfinite(h) and "fit" in winners(rows, k, orig)):
                worse[(o["name"], k)] = (f, best, h)
    assert worse == {}, worse


@pytest.mark.slow
def test_snapped_naive_zone_on_the_mirrored_drawers_runs_boundary_to_boundary(real):
    """The drawers repeat mirrored (handles face the divider): a 40-60 % tile zone snaps to one
    drawer and the divider, both planes on the ends of an element (within a voxel), not
    through a drawer (the layer-matching phase put them at 34.3-78.4 %)."""
    from partscale.zones import find_bounded_repeats, profile

    rel, ax, _ = PERIODS["drawers"]
    c = real(rel)
    lo, hi = c.surface_bounds()[:, ax]
    snapped, moves = snap(c, Edit("x", "40%", "60%", lo + 0.9 * (hi - lo), "tile"))
    p = profile(c, ax)
    ends = np.array([x for r in find_bounded_repeats(p) for e in r.elements for x in e])
    assert ends.size, "the drawers are found between their boards"
    for plane in (float(snapped.start), float(snapped.end)):
        assert np.abs(ends - p.index(plane)).min() <= 1.0, (plane, p.world(ends))
    assert moves


def _front_protrusions(c):
    """(y index, x start, x width) in voxels of each piece standing in front (+z) of every
    front face that at least 1 % of the (x, y) columns reach: handles and knobs."""
    from scipy import ndimage

    solid = c.sdf <= 0
    has = solid.any(axis=2)
    front = solid.shape[2] - 1 - np.argmax(solid[:, :, ::-1], axis=2)
    count = np.bincount(front[has], minlength=solid.shape[2])
    face = int(np.flatnonzero(count >= 0.01 * has.sum())[-1])
    lab, _ = ndimage.label(solid[:, :, face + 1 :], structure=np.ones((3, 3, 3)))
    return sorted(
        (b[1].start, b[0].start, b[0].stop - b[0].start) for b in ndimage.find_objects(lab)
    )


@pytest.mark.slow
def test_fit_keeps_the_cabinets_handle_and_knob_whole(real):
    """painted_wooden_cabinet fitted to 80 % of its width: its left drawer's cup handle and the
    door's knob keep their width within a voxel (the constant slab through the handle
    squashed it from 13 voxels to 2)."""
    c = real(PLAIN["cabinet"])
    out = apply_recipe(c, fit(c, ["80%", "=", "="])[0])
    before, after = _front_protrusions(c), _front_protrusions(out)
    assert len(before) >= 2 and len(after) == len(before), (before, after)
    for (y0, _, w0), (y1, _, w1) in zip(before, after, strict=True):
        assert y1 == y0 and abs(w1 - w0) <= 1, (before, after)
