"""Elements: seats, doors, shelf rows counted and added or removed whole (partscale.zones.elements).

Analytic objects (a sofa of unequal cushions, a cabinet with a mirrored door pair, shelves of
unequal height, a round table) are counted by geometry read straight off the grid (crowns of
the seat, knobs, boards), not by the detector under test; real objects from ../shared/data
likewise where the count shows in the geometry.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_bad_input, data_path

from partscale import shapes
from partscale.csdf import load, make, save
from partscale.edit import apply_recipe
from partscale.errors import InputError
from partscale.ingest import load as import_file
from partscale.zones import add_axis, count_zone, find_elements, fit

H = 0.01


def _extent(c, ax):
    sb = c.surface_bounds()
    return float(sb[1, ax] - sb[0, ax])


# -- analytic objects ---------------------------------------------------------------------------


def sofa(widths=(0.55, 0.6, 0.55), arm=0.15, gap=0.02):
    """Two armrests, a base and a back, and a seat cushion per width, ``gap`` apart."""
    width = 2 * arm + sum(widths) + gap * (len(widths) - 1)
    boxes = [
        ((0, 0, 0), (arm, 0.6, 0.8)),
        ((width - arm, 0, 0), (width, 0.6, 0.8)),
        ((arm, 0, 0), (width - arm, 0.2, 0.65)),
        ((arm, 0, 0.65), (width - arm, 0.8, 0.8)),
    ]
    x = arm
    for w in widths:
        boxes.append(((x, 0.2, 0), (x + w, 0.4, 0.65)))
        x += w + gap
    bounds = np.array([[0, 0, 0], [width, 0.8, 0.8]])
    return shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H, source="sofa")


def cabinet(doors=2, door=0.47, gap=0.02, knob=0.03):
    """A carcass with ``doors`` door panels on its front (z max), ``gap`` apart; mirrored pairs:
    each left door's knob near its right edge, each right door's near its left."""
    width = 0.02 * 2 + doors * door + (doors - 1) * gap
    boxes = [((0, 0, 0), (width, 0.8, 0.4))]
    x = 0.02
    for k in range(doors):
        boxes.append(((x, 0.02, 0.4), (x + door, 0.78, 0.42)))
        kx = x + door - 0.05 - knob if k % 2 == 0 else x + 0.05
        boxes.append(((kx, 0.38, 0.42), (kx + knob, 0.38 + knob, 0.42 + knob)))
        x += door + gap
    bounds = np.array([[0, 0, 0], [width, 0.8, 0.42 + knob]])
    return shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H, source="cab")


def shelves(heights=(0.21, 0.30, 0.41), board=0.02, width=0.8, depth=0.3, side=0.02):
    """Side panels and boards with compartments of unequal ``heights`` between them."""
    ys = np.concatenate([[0], np.cumsum(np.asarray(heights) + board)])
    top = ys[-1] + board
    boxes = [((0, 0, 0), (side, top, depth)), ((width - side, 0, 0), (width, top, depth))]
    boxes += [((side, y, 0), (width - side, y + board, depth)) for y in ys]
    bounds = np.array([[0, 0, 0], [width, top, depth]])
    return shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H, source="shelf")


def round_table(top_r=0.5, column_r=0.06, foot_r=0.25):
    """A disc top on a column on a round foot (y up), centred on x = z = 0."""

    def cyl(p, r, y0, y1):
        q = np.stack(
            [np.hypot(p[:, 0], p[:, 2]) - r, np.abs(p[:, 1] - (y0 + y1) / 2) - (y1 - y0) / 2], 1
        )
        return np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)

    def sdf(p):
        return np.minimum(
            np.minimum(cyl(p, top_r, 0.7, 0.74), cyl(p, column_r, 0.05, 0.7)),
            cyl(p, foot_r, 0, 0.05),
        )

    bounds = np.array([[-top_r, 0, -top_r], [top_r, 0.74, top_r]])
    return shapes.grid(sdf, bounds, voxel_size=H, source="round table")


# -- counting by geometry -------------------------------------------------------------------------


def _top_heights(c):
    """(X, Z) int: the index of the highest solid voxel of each column (y up), -1 where none."""
    inside = c.sdf < 0
    return np.where(inside.any(1), inside.shape[1] - 1 - np.argmax(inside[:, ::-1, :], 1), -1)


def seat_crowns(c, z_share=(0.3, 0.6), rise=1):
    """Seat cushions: crowns along x of the seat's top surface (median over the seat's depth,
    between the armrests): runs within ``rise`` voxels of the highest cushion, apart where it
    dips by more (a voxel for soft cushions; the analytic sofa's gaps are 20 voxels deep)."""
    top = _top_heights(c)
    z0, z1 = (int(s * c.shape[2]) for s in z_share)
    line = np.median(top[:, z0:z1], axis=1)
    arms = np.flatnonzero(line >= line.max() - 1)
    inner = line[arms.min() + 1 : arms.max()]
    seat = inner < line.max() - 1
    high = seat & (inner >= inner[seat].max() - rise)
    return int(np.count_nonzero(np.diff(np.concatenate([[0], high.astype(int)])) == 1))


def knobs(c, axis_front=2):
    """Knobs on the front face (z max): solid blobs standing proud of the doors."""
    from scipy import ndimage

    inside = c.sdf < 0
    depth = np.where(
        inside.any(axis_front),
        inside.shape[axis_front] - 1 - np.argmax(inside[:, :, ::-1], axis_front),
        -1,
    )
    face = np.median(depth[depth >= 0])
    _, n = ndimage.label(depth >= face + 2)
    return n


def boards(c, axis=1):
    """Boards along ``axis``: runs of layers whose cross-section holds much more solid."""
    occ = (c.sdf < 0).sum(axis=tuple(a for a in range(3) if a != axis))
    full = occ >= 0.8 * occ.max()
    return int(np.count_nonzero(np.diff(full.astype(int)) == 1) + full[0])


# -- finding elements -----------------------------------------------------------------------------


def test_unequal_cushions_are_one_group():
    c = sofa()
    found = find_elements(c, "x")
    g = found.best
    assert g is not None and len(g.members) == 3, found
    lengths = sorted(found.elements[i].length for i in g.members)
    # each from separator to separator: the gaps' and the armrests' faces blend a voxel or two
    assert lengths[0] == pytest.approx(0.55, abs=4 * H), lengths
    assert lengths[-1] == pytest.approx(0.6, abs=4 * H), lengths
    assert seat_crowns(c) == 3


def test_mirrored_doors_are_one_group():
    c = cabinet()
    found = find_elements(c, "x")
    g = found.best
    assert g is not None and len(g.members) == 2 and g.mirrored, found
    assert knobs(c) == 2


def test_mirrored_pair_built_from_a_real_object():
    """A real TV unit's left half (its left door, knob by the middle) beside its own mirror
    image: two elements of one group, the second mirrored, the knobs kept apart."""
    c = import_file(data_path("kenney/cabinetTelevisionDoors.glb"), res=96)
    sb = c.surface_bounds()
    mid = round((0.5 * (sb[0, 0] + sb[1, 0]) - c.origin[0]) / c.voxel_size)
    half_sdf, half_rgb = c.sdf[:mid], c.rgb[:mid]
    pair = make(
        np.concatenate([half_sdf, half_sdf[::-1]]),
        np.concatenate([half_rgb, half_rgb[::-1]]),
        None,
        c.origin,
        c.voxel_size,
        {"units": "m"},
    )
    found = find_elements(pair, "x")
    g = found.best
    assert g is not None and g.mirrored, found
    a, b = (found.elements[i] for i in g.members[-2:])
    assert abs(a.length - b.length) <= 2 * c.voxel_size
    assert found.elements[g.members[-1]].mirrored != found.elements[g.members[-2]].mirrored


def test_compartments_of_unequal_height_are_one_group():
    c = shelves()
    found = find_elements(c, "y")
    g = found.best
    assert g is not None and len(g.members) == 3, found
    assert boards(c) == 4


def test_no_group_on_a_table_or_a_flight_or_a_round_top():
    table = shapes.grid(
        lambda p: shapes.boxes_sdf(
            p,
            [((0, 0.7, 0), (1.2, 0.75, 0.6))]
            + [((x, 0, z), (x + 0.06, 0.7, z + 0.06)) for x in (0, 1.14) for z in (0, 0.54)],
        ),
        np.array([[0, 0, 0], [1.2, 0.75, 0.6]]),
        voxel_size=H,
    )
    steps = [((0.2 * i, 0, 0), (0.2 * (i + 1), 0.15 * (i + 1), 0.8)) for i in range(6)]
    flight = shapes.grid(
        lambda p: shapes.boxes_sdf(p, steps), np.array([[0, 0, 0], [1.2, 0.9, 0.8]]), voxel_size=H
    )
    assert find_elements(table, "x").best is None
    assert find_elements(flight, "x").best is None
    assert find_elements(round_table(), "x").best is None


@pytest.mark.parametrize("rel", ["kenney/tableCross.glb", "kenney/stairsOpen.glb"])
def test_two_halves_of_one_object_about_a_board_are_no_pair(rel, cli, tmp_path):
    """A trestle table's crossed legs and their stretcher, a staircase's middle stringer: across
    them the object's two halves mirror each other and reach its ends, nothing ending either:
    no elements along z (one more of them tiled half a table, a crossed leg cut through);
    fit --add z 1 refuses in one line, naming a resize by length."""
    src = data_path(rel)
    assert find_elements(import_file(src, res=128), "z").best is None
    out = tmp_path / "o.glb"
    assert_bad_input(cli("fit", src, "-o", out, "--add", "z", "1"), "found none", "by length")
    assert not out.exists()


def test_a_row_of_slats_is_searched_within_a_bounded_number_of_comparisons(monkeypatch):
    """Dozens of slats offer exponentially many ways to cut the axis into elements (a row of
    64 took 1.2 million comparisons and over a minute): the search stays within three times
    MAX_CHAIN_STEPS comparisons, and narrow boards a voxel or two apart stay separate
    candidates instead of merging into one separator from end to end."""
    from partscale.zones import elements, profile

    calls = []
    alike = elements._alike
    monkeypatch.setattr(elements, "_alike", lambda *a: calls.append(1) or alike(*a))
    bars, _ = shapes.bars(64, width=0.04, gap=0.04, height=0.1, depth=0.1, voxel_size=H)
    find_elements(bars, "x")
    assert 0 < len(calls) <= 3 * elements.MAX_CHAIN_STEPS, len(calls)
    slats, _ = shapes.bars(12, width=0.06, gap=0.02, height=0.3, depth=0.3, voxel_size=H)
    cands = elements._candidates(slats, profile(slats, 0))
    assert len(cands) >= 12, cands
    assert max(c.hi - c.lo for c in cands) <= 8 + 1e-9, cands  # one slat and its gap


def _bar_widths(c):
    """Widths (voxels) of the solid runs along x through the middle of the grid."""
    row = c.sdf[:, c.shape[1] // 2, c.shape[2] // 2] < 0
    step = np.diff(np.concatenate([[0], row.astype(int), [0]]))
    return np.flatnonzero(step == -1) - np.flatnonzero(step == 1)


@pytest.mark.parametrize("n", [1, -2])
def test_one_more_slat_of_a_long_row_is_one_slat(n):
    """24 slats: each is too short to be an element (MIN_SHARE), and two halves of twelve are
    no pair a designer counts; "one more" adds one slat (one period), "-2" removes two, every
    slat as wide as before and the row longer by exactly n periods (within half a voxel)."""
    slats, _ = shapes.bars(24, width=0.06, gap=0.02, height=0.3, depth=0.3, voxel_size=H)
    assert find_elements(slats, "x").best is None
    recipe, why = fit(slats, add={"x": n})
    verb = "add" if n > 0 else "remove"
    assert why[0].startswith(f"x: {verb} {abs(n)} piece(s), a period of 8"), why
    out = apply_recipe(slats, recipe)
    widths = _bar_widths(out)
    assert len(widths) == 24 + n, widths
    assert set(widths.tolist()) <= set(_bar_widths(slats).tolist()), widths
    assert abs(_extent(out, 0) - _extent(slats, 0) - n * 0.08) <= H / 2


# -- count edits ----------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [1, -1])
def test_one_more_or_one_fewer_seat(n):
    c = sofa()
    recipe, why = fit(c, None, add={"x": n})
    assert [e.mode for e in recipe.edits] == ["tile"], why
    assert why[0].startswith(f"x: {'add' if n > 0 else 'remove'} 1 element"), why
    out = apply_recipe(c, recipe)
    assert seat_crowns(out, rise=3) == 3 + n
    # one cushion and its gap more or fewer: the typical 0.55 m one (median 0.55) or 0.6 m
    grew = _extent(out, 0) - _extent(c, 0)
    assert 0.55 - 2 * H <= n * grew <= 0.62 + 2 * H, grew
    # nothing else changed: armrests, height, depth
    assert (
        abs(_extent(out, 1) - _extent(c, 1)) <= H / 2
        and abs(_extent(out, 2) - _extent(c, 2)) <= H / 2
    )


def test_a_third_door_with_its_knob():
    c = cabinet()
    recipe, why = fit(c, None, add={"x": 1})
    out = apply_recipe(c, recipe)
    assert knobs(out) == 3, why
    assert find_elements(out, "x").best is not None
    g = find_elements(out, "x").best
    assert g is not None and len(g.members) == 3


def test_one_more_shelf_row_of_unequal_ones():
    c = shelves()
    recipe, why = fit(c, None, add={"y": 1})
    out = apply_recipe(c, recipe)
    assert boards(out) == 5, why
    # the copied row is a whole compartment of the original's and its board
    grew = _extent(out, 1) - _extent(c, 1)
    assert min(abs(grew - (hh + 0.02)) for hh in (0.21, 0.30, 0.41)) <= H, grew


def test_count_zone_is_whole_elements_in_whole_voxels():
    c = sofa()
    found = find_elements(c, "x")
    z = count_zone(c, found, 1)
    steps = z.length / H
    assert abs(steps - round(steps)) < 1e-6
    # the zone holds its element whole: its planes lie outside the element or in its gap
    (m,) = z.members
    e = found.elements[m]
    assert z.start <= e.start + H + 1e-9 and z.end >= e.end - H - 1e-9


def test_fit_size_prefers_whole_elements():
    """A 2-cushion sofa 45 % wider: one more cushion and the rest stretched, not two fat seats."""
    c = sofa(widths=(0.6, 0.6))
    recipe, why = fit(c, ["145%", "=", "="])
    assert recipe.edits[0].mode == "tile", why
    out = apply_recipe(c, recipe)
    assert seat_crowns(out, rise=3) == 3, why
    assert abs(_extent(out, 0) - 1.45 * _extent(c, 0)) <= H


def test_bad_counts():
    with pytest.raises(InputError, match="other than 0"):
        fit(sofa(), None, add={"x": 0})
    with pytest.raises(InputError, match="found none"):
        fit(sofa(), None, add={"y": 1})
    with pytest.raises(InputError, match="unchanged"):
        fit(sofa(), ["120%", "=", "="], add={"x": 1})
    with pytest.raises(InputError, match="at most 2 of its 3"):
        fit(sofa(), None, add={"x": -3})
    with pytest.raises(InputError, match="whole number"):
        fit(sofa(), None, add={"x": 1.5})
    with pytest.raises(InputError, match="other than 0"):
        add_axis(sofa(), 0, 0)


# -- refusals -------------------------------------------------------------------------------------


def oval_table():
    """An elliptical top (0.6 x 0.4 half-axes, not a polygon: no radial zone fits it) on a
    column on a round foot."""

    def sdf(p):
        q = np.hypot(p[:, 0] / 0.6, p[:, 2] / 0.4) - 1.0  # a bound of the ellipse's distance
        top = np.maximum(q * 0.4, np.abs(p[:, 1] - 0.72) - 0.02)
        col = np.maximum(np.hypot(p[:, 0], p[:, 2]) - 0.06, np.abs(p[:, 1] - 0.375) - 0.325)
        return np.minimum(top, col)

    bounds = np.array([[-0.6, 0.05, -0.4], [0.6, 0.74, 0.4]])
    return shapes.grid(sdf, bounds, voxel_size=H, source="oval table")


def test_round_top_is_refused_then_allowed():
    c = oval_table()
    with pytest.raises(InputError, match=r"round or curved.*alternatives"):
        fit(c, ["120%", "=", "120%"])
    recipe, _ = fit(c, ["120%", "=", "120%"], allow_deform=True)
    assert recipe.edits


# -- the CLI --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def sofa_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("elements") / "sofa.csdf.npz"
    save(sofa(widths=(0.6, 0.6)), path)
    return path


def test_cli_fit_add_and_scale_copies(cli, sofa_file, tmp_path):
    out = tmp_path / "three.csdf.npz"
    proc = cli("fit", sofa_file, "-o", out, "--add", "x", "1")
    assert proc.returncode == 0, proc.stderr
    assert "add 1 element" in proc.stderr
    assert seat_crowns(load(out), rise=3) == 3
    out2 = tmp_path / "one.csdf.npz"
    proc = cli("scale", sofa_file, "-o", out2, "--axis", "x", "--copies", "-1")
    assert proc.returncode == 0, proc.stderr
    assert seat_crowns(load(out2), rise=3) == 1
    proc = cli("suggest", sofa_file, "--axis", "x")
    assert "x: 2 alike elements" in proc.stdout, proc.stdout
    # no sign: N elements in all (3 of 2 is one more), the current count refused
    out3 = tmp_path / "three_in_all.csdf.npz"
    proc = cli("scale", sofa_file, "-o", out3, "--axis", "x", "--copies", "3")
    assert proc.returncode == 0, proc.stderr
    assert seat_crowns(load(out3), rise=3) == 3
    assert_bad_input(
        cli("scale", sofa_file, "-o", tmp_path / "same.csdf.npz", "--axis", "x", "--copies", "2"),
        "current one (2)",
    )


def test_cli_fit_add_bad_input(cli, sofa_file, tmp_path):
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(cli("fit", sofa_file, "-o", out, "--add", "x", "0"), "other than 0")
    assert_bad_input(cli("fit", sofa_file, "-o", out, "--add", "y", "1"), "found none")
    assert_bad_input(
        cli("fit", sofa_file, "-o", out, "--add", "x", "1", "--size", "120%", "=", "="), "unchanged"
    )
    assert_bad_input(cli("fit", sofa_file, "-o", out), "--size", "--add")
    assert not out.exists()


def test_cli_refuses_a_round_top(cli, tmp_path):
    src = tmp_path / "round.csdf.npz"
    save(oval_table(), src)
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(
        cli("fit", src, "-o", out, "--size", "120%", "=", "120%"),
        "round or curved",
        "--allow-deform",
    )
    assert not out.exists()
    proc = cli("fit", src, "-o", out, "--size", "120%", "=", "120%", "--allow-deform")
    assert proc.returncode == 0, proc.stderr
    assert out.exists()


# -- real objects ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def sofa2():
    return import_file(data_path("sweethome3d/sofa2.obj"), res=128)


def test_real_two_seat_sofa_gets_a_third_seat(sofa2):
    assert seat_crowns(sofa2) == 2
    recipe, why = fit(sofa2, None, add={"x": 1})
    assert seat_crowns(apply_recipe(sofa2, recipe)) == 3, why


def test_real_sofa_mesh_gets_a_third_seat_without_cracks(cli, sofa2, tmp_path):
    """sweethome3d/sofa2 as a mesh, one more seat: its seat's two planes cut its triangles
    differently, so the mesh route's copies would meet with cracks; fit says so and goes
    through the mesh's CSDF: one watertight piece, the surface of the CSDF edit that has three
    seats (test above) within half a voxel."""
    import trimesh

    from partscale.surface import sample_linear

    out = tmp_path / "three.glb"
    proc = cli("fit", data_path("sweethome3d/sofa2.obj"), "-o", out, "--add", "x", "1")
    assert proc.returncode == 0, proc.stderr
    assert "seams cannot be welded on the mesh" in proc.stderr, proc.stderr
    assert "warning: seam" not in proc.stderr  # not written with cracks, then warned about
    m = trimesh.load(out, force="mesh")
    assert m.is_watertight and len(m.split(only_watertight=False)) == 1
    recipe, _ = fit(sofa2, None, add={"x": 1})
    edited = apply_recipe(sofa2, recipe)
    assert seat_crowns(edited) == 3
    d = sample_linear(edited.sdf, edited.world_to_index(np.asarray(m.vertices)))
    assert np.abs(d).max() <= edited.voxel_size / 2, np.abs(d).max() / edited.voxel_size


def test_a_sofa_mesh_whose_csdf_edit_would_not_fit_keeps_the_mesh_route(
    cli, sofa2, tmp_path, monkeypatch
):
    """Where the CSDF that unweldable seams go through would not fit in memory, fit says so
    before any work and writes the mesh route's result with its seams as they are (it cut the
    mesh, then refused in the CSDF's memory check)."""
    import re

    import trimesh

    from partscale.edit import check_recipe_memory
    from partscale.errors import MemoryLimitError

    recipe, _ = fit(sofa2, None, add={"x": 1})
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", "1M")
    with pytest.raises(MemoryLimitError) as caught:
        check_recipe_memory(sofa2, recipe, what="three seats")
    need = float(re.search(r"need ([\d.]+) MiB", str(caught.value)).group(1))
    # below the CSDF edit's need, above the import's (a third less: two seats of three)
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", f"{need - 2:.1f}M")
    out = tmp_path / "three.glb"
    proc = cli("fit", data_path("sweethome3d/sofa2.obj"), "-o", out, "--add", "x", "1")
    assert proc.returncode == 0, proc.stderr
    assert "would go through the mesh's CSDF, too large here" in proc.stderr, proc.stderr
    assert "warning: seam" in proc.stderr and "mesh route" in proc.stderr
    m = trimesh.load(out, force="mesh")
    # one seat (84 cm) longer
    assert np.ptp(m.vertices[:, 0]) >= np.ptp(sofa2.surface_bounds()[:, 0]) + 0.8


def test_suggest_reads_a_mesh_as_fit_does(cli, tmp_path):
    """suggest on a mesh (what a new user tries first): imported as fit imports it, the same
    elements listed; a file that is neither is refused in one line naming both."""
    proc = cli("suggest", data_path("sweethome3d/sofa2.obj"), "--axis", "x")
    assert proc.returncode == 0, proc.stderr
    assert "x: 2 alike elements, mirrored" in proc.stdout, proc.stdout
    notes = tmp_path / "notes.txt"
    notes.write_text("a sofa")
    assert_bad_input(cli("suggest", notes), ".csdf.npz file or a mesh", "got .txt")


def test_real_two_seat_sofa_45_percent_wider_is_three_seats(sofa2):
    recipe, why = fit(sofa2, ["145%", "=", "="])
    out = apply_recipe(sofa2, recipe)
    assert seat_crowns(out) == 3, why


def seat_dips(c, z_share, drop=2):
    """Narrow dips (at most 8 voxels wide, ``drop`` below the seat line's median) in the seat's
    top line between the armrests: the gaps between seat cushions (and the folds near the
    arms, which stay as they are: compare counts before and after)."""
    top = _top_heights(c)
    z0, z1 = (int(s * c.shape[2]) for s in z_share)
    line = np.median(top[:, z0:z1], axis=1)
    arms = np.flatnonzero(line >= line.max() - 1)
    inner = line[arms.min() + 1 : arms.max()]
    seat = inner[inner < line.max() - 1]
    low = np.concatenate([[0], (seat <= np.median(seat) - drop).astype(int), [0]])
    starts, ends = np.flatnonzero(np.diff(low) == 1), np.flatnonzero(np.diff(low) == -1)
    return sum(
        1 for a, b in zip(starts, ends, strict=True) if 0 < a and b < len(seat) and b - a <= 8
    )


def test_real_sofa_03_one_more_and_one_fewer_cushion():
    """polyhaven/sofa_03's three seat cushions: +1 gives one more dip between cushions, -1 one
    fewer (its cushions are in front, z from 60 to 85 % of its depth)."""
    c = import_file(data_path("polyhaven/sofa_03/sofa_03_1k.gltf"), res=128)
    found = find_elements(c, "x")
    assert found.best is not None and len(found.best.members) == 3
    before = seat_dips(c, (0.6, 0.85))
    for n in (1, -1):
        recipe, why = fit(c, None, add={"x": n})
        assert seat_dips(apply_recipe(c, recipe), (0.6, 0.85)) == before + n, why


def test_real_door_unit_gets_a_third_door():
    c = import_file(data_path("kenney/cabinetTelevisionDoors.glb"), res=128)
    recipe, why = fit(c, None, add={"x": 1})
    out = apply_recipe(c, recipe)
    g = find_elements(out, "x").best
    assert g is not None and len(g.members) == 3, why


@pytest.mark.parametrize(
    ("rel", "axis"),
    [
        ("sweethome3d/bookcase.obj", "y"),
        ("polyhaven/wooden_display_shelves_01/wooden_display_shelves_01_2k.gltf", "z"),
        ("kenney/sideTableDrawers.glb", "x"),
    ],
)
def test_real_one_more_row_or_drawer(rel, axis):
    c = import_file(data_path(rel), res=128)
    ax = "xyz".index(axis)
    g = find_elements(c, axis).best
    assert g is not None
    n0 = len(g.members)
    recipe, why = fit(c, None, add={axis: 1})
    out = apply_recipe(c, recipe)
    g1 = find_elements(out, axis).best
    assert g1 is not None and len(g1.members) == n0 + 1, why
    # the other axes are untouched
    for other in {0, 1, 2} - {ax}:
        assert abs(_extent(out, other) - _extent(c, other)) <= c.voxel_size / 2


def test_real_round_table_is_refused_not_made_wavy(cli, tmp_path):
    """kenney/tableRound (a hexagonal top on a pedestal) 20 % wider only (x alone: no radial
    zone grows one axis): refused in one line naming what it would need and the alternatives,
    nothing written; with --allow-deform written, and the notes say what was deformed. (x and
    z alike take a radial zone: tests/test_warp.py.)"""
    src = data_path("kenney/tableRound.glb")
    c = tmp_path / "round.csdf.npz"
    cli("import", src, "-o", c, "--res", "96", check=True)
    out = tmp_path / "wide.csdf.npz"
    proc = cli("fit", c, "-o", out, "--size", "120%", "=", "=")
    assert_bad_input(proc, "round or curved", "to grow", "--allow-deform")
    assert not out.exists()
    proc = cli("fit", c, "-o", out, "--size", "120%", "=", "=", "--allow-deform")
    assert proc.returncode == 0, proc.stderr
    assert out.exists() and ("thin slab" in proc.stderr or "GLOBAL" in proc.stderr), proc.stderr


def test_recipe_holds_a_count(cli, sofa_file, tmp_path):
    """A recipe may say "one more seat" ({"axis": "x", "copies": "+1"}): resolved on the object
    into the same zone edit fit --add makes; apply_recipe alone refuses it unresolved."""
    import json

    from partscale.edit import Recipe
    from partscale.zones import resolve_counts

    c = load(sofa_file)
    counted = Recipe.parse({"edits": [{"axis": "x", "copies": "+1"}]})
    resolved, notes = resolve_counts(c, counted)
    assert resolved == fit(c, None, add={"x": 1})[0] and notes
    with pytest.raises(InputError, match="unresolved"):
        apply_recipe(c, counted)
    rec = tmp_path / "r.json"
    rec.write_text(json.dumps(counted.to_json()))
    out = tmp_path / "o.csdf.npz"
    proc = cli("scale", sofa_file, "-o", out, "--recipe", rec)
    assert proc.returncode == 0, proc.stderr
    assert seat_crowns(load(out), rise=3) == 3
