"""Zones beyond slabs across an axis: radial (an annulus about the vertical) and oblique planes.

Analytic objects are judged against the analytic shape the edit should give (true distances in
the band, radii, thicknesses); real ones against measurements of their own grid before.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_bad_input, data_path

from partscale import shapes
from partscale.csdf import BAND_VOXELS, load, save
from partscale.edit import (
    ObliqueZone,
    RadialZone,
    Recipe,
    ScrewZone,
    apply_oblique,
    apply_radial,
    apply_recipe,
    recipe_from_history,
    reevaluate,
)
from partscale.errors import InputError
from partscale.ingest import load as import_file
from partscale.zones import find_radial, fit

H = 0.01


def _cyl(p, r, y0, y1):
    q = np.stack(
        [np.hypot(p[:, 0], p[:, 2]) - r, np.abs(p[:, 1] - (y0 + y1) / 2) - (y1 - y0) / 2], 1
    )
    return np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)


def round_table_sdf(top_r=0.5):
    """A disc top (0.04 thick) on a column (r 0.06) on a round foot (r 0.25), about y."""

    def sdf(p):
        d = np.minimum(_cyl(p, top_r, 0.7, 0.74), _cyl(p, 0.06, 0.05, 0.7))
        return np.minimum(d, _cyl(p, 0.25, 0.0, 0.05))

    return sdf


def round_table(top_r=0.5):
    b = np.array([[-top_r, 0, -top_r], [top_r, 0.74, top_r]])
    return shapes.grid(round_table_sdf(top_r), b, voxel_size=H, source="round table")


def _extent(c, ax):
    sb = c.surface_bounds()
    return float(sb[1, ax] - sb[0, ax])


def _radius_at(c, y):
    """The solid's largest distance from the y axis at height ``y`` (voxel centres inside)."""
    j = round((y - c.origin[1]) / c.voxel_size)
    inside = np.argwhere(c.sdf[:, j, :] < 0)
    xz = c.origin[[0, 2]] + inside * c.voxel_size
    return float(np.hypot(xz[:, 0], xz[:, 1]).max())


def test_round_table_grows_its_top_only():
    """fit 125 % in x and z: a radial zone; the top's radius 1.25 x within a voxel, the
    column's and the foot's within half a voxel, the top as thick; every distance within the
    band true to the analytic result within half a voxel."""
    c = round_table()
    recipe, why = fit(c, ["125%", "=", "125%"])
    assert isinstance(recipe.edits[0], RadialZone), why
    assert "radial zone" in why[0] and "round" in why[0], why
    out = apply_recipe(c, recipe)
    assert abs(_extent(out, 0) - 1.25) <= H and abs(_extent(out, 2) - 1.25) <= H
    for y, r in ((0.3, 0.06), (0.025, 0.25)):
        assert abs(_radius_at(out, y) - _radius_at(c, y)) <= H / 2, (y, r)
    assert abs(_extent(out, 1) - 0.74) <= H / 2
    # true distances in the band, against the analytic table with a 0.625 top
    truth = round_table_sdf(0.625)
    pts = np.argwhere(np.abs(out.sdf) <= BAND_VOXELS * H)
    world = out.origin + pts * H
    err = np.abs(out.sdf[tuple(pts.T)] - truth(world)) / H
    assert np.percentile(err, 99) <= 0.5 and err.mean() <= 0.1, (err.mean(), np.percentile(err, 99))


def test_radial_far_field_keeps_sign_and_bounds_the_distance():
    """Beyond the band (where the radial edit takes the nearest source voxel's value, not a
    blend), every voxel of the round table grown to 1.25 x keeps the analytic result's sign and
    stores at most a voxel more than its analytic distance: a sphere tracer stepping by it never
    crosses the surface."""
    out = apply_radial(round_table(), RadialZone("y", (0.0, 0.0), 0.1, 0.4, 0.525))
    far = np.argwhere(np.abs(out.sdf) > BAND_VOXELS * H)
    truth = round_table_sdf(0.625)(out.origin + far * H)
    got = out.sdf[tuple(far.T)]
    assert far.shape[0] > out.sdf.size // 2
    assert np.array_equal(np.sign(got), np.sign(truth))
    over = (np.abs(got) - np.abs(truth)) / H
    assert over.max() <= 1.0, over.max()


def test_radial_history_replays():
    c = round_table()
    zone = RadialZone("y", (0.0, 0.0), 0.1, 0.45, 0.6)
    out = apply_radial(c, zone)
    again = apply_recipe(c, recipe_from_history(out, after=c))
    assert np.array_equal(again.sdf, out.sdf) and np.array_equal(again.rgb, out.rgb)
    assert Recipe.parse(Recipe((zone,)).to_json()) == Recipe((zone,))


def test_polygonal_top_stays_regular():
    """kenney/tableRound (a hexagonal top on a pedestal) 20 % wider and deeper: a radial zone
    with the polygon's gauge; the pedestal's radius within half a voxel, the top as thick, and
    the top's outline a regular polygon: every face as far from the centre as the others,
    within a voxel."""
    c = import_file(data_path("kenney/tableRound.glb"), res=128)
    frame = find_radial(c)
    assert frame is not None and frame.sides >= 5
    recipe, why = fit(c, ["120%", "=", "120%"])
    assert isinstance(recipe.edits[0], RadialZone), why
    out = apply_recipe(c, recipe)
    h = c.voxel_size
    for ax in (0, 2):
        assert abs(_extent(out, ax) - 1.2 * _extent(c, ax)) <= h
    # the pedestal at a quarter of the height: its largest radius unchanged
    y = c.surface_bounds()[0, 1] + 0.25 * _extent(c, 1)
    assert abs(_radius_at(out, y) - _radius_at(c, y)) <= h / 2
    assert abs(_extent(out, 1) - _extent(c, 1)) <= h / 2
    # each face's distance from the centre (support along its normal) alike, within a voxel
    top = np.argwhere((out.sdf < 0).any(axis=1))
    xz = out.origin[[0, 2]] + top * h - np.array(frame.center)
    a = np.deg2rad(frame.phase) + 2 * np.pi * np.arange(frame.sides) / frame.sides
    support = (xz @ np.stack([np.cos(a), np.sin(a)])).max(axis=0)
    assert np.ptp(support) <= h, support


def test_lamp_base_grows_its_pole_does_not(cli, tmp_path):
    """kenney/lampRoundFloor: a radial zone over the base's height only (--span): the base's
    radius grows by the shift, the pole's and the shade's stay."""
    src = tmp_path / "lamp.csdf.npz"
    cli("import", data_path("kenney/lampRoundFloor.glb"), "-o", src, "--res", "128", check=True)
    c = load(src)
    sb = c.surface_bounds()
    y0, height = float(sb[0, 1]), _extent(c, 1)
    base_top = y0 + 0.03 * height
    out = tmp_path / "wide.csdf.npz"
    proc = cli(
        "scale",
        src,
        "-o",
        out,
        "--radial",
        "--zone",
        "30%",
        "90%",
        "--by",
        "+5cm",
        "--span",
        repr(y0 - 0.01),
        repr(base_top),
    )
    assert proc.returncode == 0, proc.stderr
    o = load(out)
    h = c.voxel_size
    yb = y0 + 0.01
    assert abs(_radius_at(o, yb) - _radius_at(c, yb) - 0.05) <= h
    for share in (0.5, 0.95):  # the pole, the shade
        y = y0 + share * height
        assert abs(_radius_at(o, y) - _radius_at(c, y)) <= h / 2, share


def test_oblique_stretch_keeps_a_turned_bar_thick():
    """A bar 0.1 thick turned 30 degrees about z, stretched along its own length by 0.2 with
    --normal along it: its thickness unchanged within half a voxel, its length 0.2 longer, the
    part before the zone where it was."""
    t = np.deg2rad(30)
    u = np.array([np.cos(t), np.sin(t), 0.0])  # along the bar
    w = np.array([-np.sin(t), np.cos(t), 0.0])  # across it

    def bar(length):
        def sdf(p):
            q = np.stack([p @ u - length / 2, p @ w, p[:, 2] - 0.05], axis=1)
            d = np.abs(q) - np.array([length / 2, 0.05, 0.05])
            return np.minimum(d.max(1), 0) + np.linalg.norm(np.maximum(d, 0), axis=1)

        return sdf

    c = shapes.grid(bar(0.8), np.array([[-0.1, -0.1, 0], [0.8, 0.5, 0.1]]), voxel_size=H)
    out = apply_oblique(c, ObliqueZone(tuple(u), 0.3, 0.5, 0.7))
    truth = bar(1.0)
    pts = np.argwhere(np.abs(out.sdf) <= BAND_VOXELS * H)
    err = np.abs(out.sdf[tuple(pts.T)] - truth(out.origin + pts * H)) / H
    assert np.percentile(err, 99) <= 0.5, np.percentile(err, 99)
    inside = out.origin + np.argwhere(out.sdf < 0) * H
    thick = np.ptp(inside @ w)
    assert abs(thick - 0.1) <= H / 2 + H, thick  # voxel centres: within a voxel of 0.1
    assert abs(np.ptp(inside @ u) - np.ptp((c.origin + np.argwhere(c.sdf < 0) * H) @ u) - 0.2) <= H


def test_bad_warps(cli, tmp_path):
    c = round_table()
    with pytest.raises(InputError, match="inside the object"):
        apply_radial(c, RadialZone("y", (0.0, 0.0), 0.8, 0.9, 1.0))
    with pytest.raises(InputError, match="non-zero"):
        apply_oblique(c, ObliqueZone((0.0, 0.0, 0.0), 0.1, 0.2, 0.3))
    mixed = {
        "edits": [
            {"radial": {"center": [0, 0]}, "zone": [0.1, 0.4], "to": 0.5},
            {"axis": "x", "zone": [0.1, 0.2], "to": 0.3},
        ]
    }
    with pytest.raises(InputError, match="no zone along x"):
        apply_recipe(c, mixed)
    src = tmp_path / "t.csdf.npz"
    save(c, src)
    out = tmp_path / "o.csdf.npz"
    assert_bad_input(
        cli(
            "scale",
            src,
            "-o",
            out,
            "--radial",
            "--axis",
            "x",
            "--zone",
            "10%",
            "90%",
            "--by",
            "5cm",
        ),
        "--axis",
    )
    assert_bad_input(
        cli(
            "scale",
            src,
            "-o",
            out,
            "--normal",
            "0",
            "0",
            "0",
            "--zone",
            "0.1",
            "0.2",
            "--to",
            "0.3",
        ),
        "non-zero",
    )
    assert_bad_input(
        cli("scale", src, "-o", out, "--radial", "--zone", "120%", "130%", "--to", "140%"),
        "inside the object",
    )
    assert_bad_input(cli("scale", src, "-o", out, "--center", "0", "0"), "--center")
    assert not out.exists()


# -- steps: repetition by a diagonal shift ---------------------------------------------------------


def flight(n=6, going=0.2, rise=0.15, width=0.6, solid=True):
    """A straight flight along x: ``n`` steps ``going`` deep and ``rise`` high; solid (each step
    a box down to the floor) or open (treads 4 cm thick on two stringers 4 cm wide)."""
    if solid:
        boxes = [((going * i, 0, 0), (going * (i + 1), rise * (i + 1), width)) for i in range(n)]
        sdf = lambda p: shapes.boxes_sdf(p, boxes)  # noqa: E731
    else:
        treads = [
            (
                (going * i, rise * (i + 1) - 0.04, 0.04),
                (going * (i + 1), rise * (i + 1), width - 0.04),
            )
            for i in range(n)
        ]
        slope = rise / going

        def stringer(p, z0):
            # a slab 4 cm thick along the diagonal, 4 cm wide in z, over the flight's length
            u = (p[:, 0] * going + p[:, 1] * rise) / np.hypot(going, rise)
            v = (p[:, 1] - slope * p[:, 0]) * going / np.hypot(going, rise)
            q = np.stack(
                [
                    np.abs(u - n * np.hypot(going, rise) / 2) - n * np.hypot(going, rise) / 2,
                    np.abs(v - 0.02) - 0.04,
                    np.abs(p[:, 2] - z0 - 0.02) - 0.02,
                ],
                1,
            )
            return np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)

        def sdf(p):
            d = shapes.boxes_sdf(p, treads)
            return np.minimum(d, np.minimum(stringer(p, 0.0), stringer(p, width - 0.04)))

    bounds = np.array([[0, 0, 0], [going * n, rise * n + 0.05, width]])
    return shapes.grid(sdf, bounds, voxel_size=H, source="flight")


def _tread_heights(c):
    """Heights (voxels) of the top surface along x at mid-width: one value per column."""
    inside = c.sdf[:, :, c.shape[2] // 2] < 0
    return np.where(inside.any(1), inside.shape[1] - 1 - np.argmax(inside[:, ::-1], 1), -1)


def _pieces(c):
    """Connected pieces of the solid (face-connected voxels inside) of at least 8 voxels."""
    from scipy import ndimage

    lab, _ = ndimage.label(c.sdf < 0)
    return int((np.bincount(lab.ravel())[1:] >= 8).sum())


def _largest(c):
    """Voxels of the largest connected piece of the solid."""
    from scipy import ndimage

    lab, _ = ndimage.label(c.sdf < 0)
    return int(np.bincount(lab.ravel())[1:].max())


def _risers(c):
    """Rises (voxels) between consecutive treads along the flight (a level a single column
    wide is no tread: the sheet where two of the analytic steps' boxes touch)."""
    top = _tread_heights(c)
    top = top[top >= 0]
    starts = np.concatenate([[True], np.diff(top) != 0])
    runs = np.diff(np.concatenate([np.flatnonzero(starts), [len(top)]]))
    levels = top[starts][runs > 1]
    return np.diff(levels)


@pytest.mark.parametrize("solid", [True, False])
def test_flight_step_found_and_one_more_added(solid):
    """A flight's step found to a quarter voxel; +1 step: the total rise grows by one rise
    within half a voxel, every riser equal within a voxel, no new piece; -1 removes one."""
    from partscale.zones import find_screws

    c = flight(solid=solid)
    (s,) = find_screws(c)[:1]
    assert abs(s.going - 0.2) <= H / 4 and abs(s.rise - 0.15) <= H / 4, s
    assert s.axis == "x"
    for n in (1, -1):
        recipe, why = fit(c, None, add={"y": n})
        out = apply_recipe(c, recipe)
        assert abs(_extent(out, 1) - _extent(c, 1) - n * 0.15) <= H / 2, why
        r = _risers(out)
        assert len(r) == len(_risers(c)) + n and np.ptp(r) <= 1, r
        assert _pieces(out) <= _pieces(c)


def _treads(mesh, quantum: float) -> np.ndarray:
    """The heights of a flight's treads: its upward faces grouped by height (to ``quantum``),
    the groups of more than half the largest one's area."""
    up = mesh.face_normals[:, 1] > 0.9
    ys = np.round(mesh.triangles_center[up][:, 1] / quantum) * quantum
    levels = np.unique(ys)
    area = np.array([mesh.area_faces[up][ys == y].sum() for y in levels])
    return levels[area > 0.5 * area.max()]


@pytest.mark.parametrize(
    "rel",
    ["kenney/stairsOpenSingle.glb", "kenney/stairs.glb", "sweethome3d/staircase.obj"],
)
def test_real_flights_step_and_one_more(rel):
    """The step found on real flights matches the mesh's own treads (going and rise from its
    upward faces' heights and starts) within half a voxel; +1 step: the total rise grows by one
    rise within half a voxel, the flight one piece."""
    import trimesh

    from partscale.zones import find_screws

    path = data_path(rel)
    c = import_file(path, res=128)
    h = c.voxel_size
    (s,) = find_screws(c)[:1]
    # the mesh's treads: upward faces grouped by height
    m = trimesh.load(path, force="mesh")
    treads = _treads(m, h / 4)
    rise = float(np.median(np.diff(treads)))
    scale = _extent(c, 1) / float(np.ptp(m.vertices[:, 1]))  # the import's units
    assert abs(s.rise - rise * scale) <= h / 2, (s.rise, rise * scale)
    recipe, why = fit(c, None, add={"y": 1})
    out = apply_recipe(c, recipe)
    assert abs(_extent(out, 1) - _extent(c, 1) - s.rise) <= h / 2 + 1e-9, why
    # at most the new tread is a piece of its own (open treads are); the stringers run on: the
    # largest piece (they and what joins them) is no smaller: not split at the cut
    assert _pieces(out) <= _pieces(c) + 1, (_pieces(c), _pieces(out))
    assert _largest(out) >= _largest(c)


@pytest.mark.parametrize(
    "args", [("fit", "--add", "y", "1"), ("scale", "--axis", "y", "--copies", "+1")]
)
def test_one_more_step_on_a_mesh_goes_through_its_csdf(args, cli, tmp_path):
    """One more step on a mesh in one command: the mesh route cannot cut along steps, so the
    step zone is applied to the mesh's CSDF and the result written remeshed, saying so: the
    flight has one more tread, every rise the source's within a voxel, one watertight piece."""
    import trimesh

    src = data_path("kenney/stairs_short.glb")
    out = tmp_path / "more.glb"
    proc = cli(args[0], src, "-o", out, *args[1:])
    assert proc.returncode == 0, proc.stderr
    assert "not a step zone: the edit is applied to the mesh's CSDF" in proc.stderr, proc.stderr
    m0 = trimesh.load(src, force="mesh")
    m1 = trimesh.load(out, force="mesh")
    h = float(np.ptp(m0.vertices, axis=0).max()) / 128  # the default import's voxel
    t0, t1 = _treads(m0, h / 2), _treads(m1, h)
    assert len(t1) == len(t0) + 1, (t0, t1)
    rise = float(np.median(np.diff(t0)))
    assert np.all(np.abs(np.diff(t1) - rise) <= h), (np.diff(t1), rise)
    assert m1.is_watertight and len(m1.split(only_watertight=False)) == 1


def test_a_turned_mesh_is_not_remeshed_square(cli, tmp_path):
    """A flight turned 20 degrees about up, edited --square: the steps would go through its
    CSDF, remeshed turned square and never turned back: refused in one line, nothing written."""
    import trimesh

    m = trimesh.load(data_path("kenney/stairs_short.glb"), force="mesh")
    m.apply_transform(trimesh.transformations.rotation_matrix(np.radians(20), [0, 1, 0]))
    src = tmp_path / "turned.glb"
    m.export(src)
    out = tmp_path / "more.glb"
    proc = cli("fit", src, "-o", out, "--add", "y", "1", "--square")
    assert_bad_input(proc, "--square", "step zone", "import with --square")
    assert not out.exists()


@pytest.mark.slow
def test_no_false_steps_on_tables_chairs_cabinets():
    from partscale.zones import find_screws

    for rel in [
        "kenney/table.glb",
        "kenney/chair.glb",
        "kenney/bookcaseOpen.glb",
        "kenney/sideTableDrawers.glb",
        "sweethome3d/bookcase.obj",
        "sweethome3d/railing.obj",
        "sweethome3d/dresser.obj",
        "polyhaven/painted_wooden_cabinet/painted_wooden_cabinet_1k.gltf",
    ]:
        c = import_file(data_path(rel), res=96)
        assert find_screws(c) == [], rel


def splayed_stool_sdf(p):
    """A disc seat (r 0.2, 0.04 thick, top at 0.44) on four round legs (r 0.02) splayed
    outward: from under the seat at radius 0.1 down to the floor at radius 0.2."""
    d = _cyl(p, 0.2, 0.40, 0.44)
    for k in range(4):
        a = np.deg2rad(45 + 90 * k)
        u = np.array([np.cos(a), 0.0, np.sin(a)])
        top, foot = 0.1 * u + [0, 0.41, 0], 0.2 * u + [0, 0.02, 0]
        ab = foot - top
        t = np.clip((p - top) @ ab / (ab @ ab), 0.0, 1.0)
        d = np.minimum(d, np.linalg.norm(p - (top + t[:, None] * ab), axis=1) - 0.02)
    return d


def test_radial_edit_of_a_splayed_stool_keeps_true_distances():
    """A stool whose legs turn with the radial direction, its seat grown by a radial zone: the
    distances the edit keeps instead of re-evaluating are within half a voxel
    (p99) of re-evaluating the whole band of the same warped grid."""
    b = np.array([[-0.22, 0.0, -0.22], [0.22, 0.44, 0.22]])
    c = shapes.grid(splayed_stool_sdf, b, voxel_size=H, source="stool")
    out = apply_radial(c, RadialZone("y", (0.0, 0.0), 0.06, 0.18, 0.22))
    full = reevaluate(out, band=BAND_VOXELS + 1.0)
    band = np.abs(full.sdf) <= BAND_VOXELS * H
    err = np.abs(out.sdf - full.sdf)[band] / H
    assert np.percentile(err, 99) <= 0.5, np.percentile(err, 99)


def test_count_in_all_sets_a_flights_step_count():
    """add_axis with in_all (scale --copies N, no sign): N steps in all along the flight's
    repeat, so 7 on a flight of six is one more step (one more riser) and 4 two fewer; 6 is
    refused (no change)."""
    from partscale.zones import add_axis, find_screws

    c = flight()
    count = find_screws(c)[0].count
    assert count == 6
    for total, n in ((7, 1), (4, -2)):
        (zone,), _ = add_axis(c, 1, total, in_all=True)
        assert isinstance(zone, ScrewZone) and zone.copies == n, zone
    out = apply_recipe(c, Recipe((add_axis(c, 1, 7, in_all=True)[0][0],)))
    assert len(_risers(out)) == len(_risers(c)) + 1
    with pytest.raises(InputError, match="current one \\(6\\)"):
        add_axis(c, 1, 6, in_all=True)
