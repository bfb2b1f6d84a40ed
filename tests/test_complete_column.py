"""partscale.complete.column: a swivel chair's column between its base's hub and its seat."""

from __future__ import annotations

import numpy as np
import pytest

from partscale.complete import column as column_mod
from partscale.complete.carve import Carver
from partscale.complete.scan import Frame
from partscale.complete.symmetry import Symmetry

H = 0.01


def _rotation(x: float = 0.0, z: float = 0.0, base_top: float = 0.15) -> Symmetry:
    return Symmetry(
        "rotation",
        np.eye(3),
        np.zeros(3),
        1.0,
        0.0,
        fold=5,
        bands=((-np.inf, base_top),),
        params={"fold": 5, "axis_x": x, "axis_z": z},
    )


def _chair(hub: bool = True, inner: float = 0.1) -> np.ndarray:
    """(N, 3) upright surface points: five legs ``inner``-0.3 m from the y axis at 0.05 m, a
    hub's top (radius 0.05 m at 0.12 m) when ``hub``, and a seat 0.4 m across at 0.45 m."""
    g = np.arange(-0.2, 0.2, 0.01)
    sx, sz = np.meshgrid(g, g)
    seat = np.stack([sx.ravel(), np.full(sx.size, 0.45), sz.ravel()], axis=1)
    r = np.arange(inner, 0.3, 0.01)
    legs = [
        np.stack([r * np.cos(a), np.full_like(r, 0.05), r * np.sin(a)], 1)
        for a in 2 * np.pi * np.arange(5) / 5
    ]
    parts = [seat, *legs]
    if hub:
        a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        parts.append(np.stack([0.05 * np.cos(a), np.full_like(a, 0.12), 0.05 * np.sin(a)], 1))
        parts.append(np.array([[0.0, 0.12, 0.0]]))
    return np.concatenate(parts)


def _four_legs() -> np.ndarray:
    """(N, 3): a chair whose four legs (at +-0.18 m) reach from the floor to its seat, with a
    cross brace meeting under the seat's centre at 0.12 m."""
    y = np.arange(0.0, 0.45, 0.01)
    legs = [
        np.stack([np.full_like(y, sx), y, np.full_like(y, sz)], 1)
        for sx in (-0.18, 0.18)
        for sz in (-0.18, 0.18)
    ]
    t = np.arange(-0.18, 0.18, 0.01)
    brace = [
        np.stack([t, np.full_like(t, 0.12), t], 1),
        np.stack([t, np.full_like(t, 0.12), -t], 1),
    ]
    seat = _chair()[_chair()[:, 1] > 0.4]
    return np.concatenate([seat, *legs, *brace])


def _never_free(p: np.ndarray) -> np.ndarray:
    return np.zeros(len(p), bool)


def test_a_hub_under_a_seat_gets_the_widest_column_nothing_contradicts():
    col = column_mod.find_column(_chair(), _rotation(), _never_free, H)
    assert col is not None
    assert col.radius == pytest.approx(column_mod.MAX_RADIUS)
    assert col.bottom == pytest.approx(0.12) and col.top == pytest.approx(0.45)
    assert col.contradicted == 0.0


def test_the_column_narrows_to_what_the_sure_free_space_leaves():
    def free(p):  # seen through beyond 2.2 cm of the axis
        return np.hypot(p[:, 0], p[:, 2]) > 0.022

    col = column_mod.find_column(_chair(), _rotation(), free, H)
    assert col is not None
    assert col.radius <= 0.022
    assert col.radius >= column_mod.MIN_RADIUS


def test_no_column_without_a_hub_or_without_a_rotation():
    # four legs of a table, a chair's legs: nothing near the axis below the seat
    assert column_mod.find_column(_chair(hub=False), _rotation(), _never_free, H) is None
    assert column_mod.find_column(_chair(), None, _never_free, H) is None
    # a hub under the seat, but legs carry the seat: no column
    assert column_mod.find_column(_four_legs(), _rotation(), _never_free, H) is None


def test_an_unseen_hub_is_guessed_out_to_the_legs_inner_ends():
    # the legs' copies start 7 cm from the axis (beyond HUB_REACH), within a quarter of the
    # base's radius (the turn's own hub test), and nothing is nearer: a hub joins their ends
    # to the column; legs starting at a third of it (a table's feet) still get none
    col = column_mod.find_column(_chair(hub=False, inner=0.07), _rotation(), _never_free, H)
    assert col is not None
    assert 0.07 < col.hub_radius <= 0.07 + H + 1e-9
    assert col.hub_bottom == pytest.approx(0.05)
    assert col.bottom == pytest.approx(0.05) and col.top == pytest.approx(0.45)
    # a seen hub needs none
    assert column_mod.find_column(_chair(), _rotation(), _never_free, H).hub_radius == 0.0
    # surface rising 9 cm beside the axis is not a hub (a disc no taller than wide)
    y = np.arange(0.05, 0.145, 0.005)
    pillar = np.stack([np.full_like(y, 0.075), y, np.zeros_like(y)], axis=1)
    chair = np.concatenate([_chair(hub=False, inner=0.07), pillar])
    assert column_mod.find_column(chair, _rotation(), _never_free, H) is None


def test_a_guessed_hub_joins_the_legs_to_the_column():
    from scipy import ndimage

    origin = np.array([-0.195, 0.0, -0.195])
    sdf = np.ones((40, 60, 40), np.float32)
    x, z = np.meshgrid(*(origin[0] + np.arange(40) * H,) * 2, indexing="ij")
    ring = (np.hypot(x, z) >= 0.06) & (np.hypot(x, z) <= 0.19)
    sdf[:, 4:7][ring[:, None, :].repeat(3, axis=1)] = -1.0  # the legs' ends, y 0.04-0.06
    sdf[:, 45:50] = -1.0  # the seat, y 0.45-0.49
    prov = np.zeros(sdf.shape, np.uint8)
    plain = column_mod.Column(0.0, 0.0, 0.065, 0.445, 0.02, 0.0)
    hubbed = column_mod.Column(0.0, 0.0, 0.065, 0.445, 0.02, 0.0, 0.07, 0.045)
    out, _, _ = column_mod.add_column(sdf, prov, plain, np.eye(4), origin, H, _never_free, 3)
    assert ndimage.label(out < 0)[1] == 2  # the column's foot meets nothing inside the ring
    out, p, _ = column_mod.add_column(sdf, prov, hubbed, np.eye(4), origin, H, _never_free, 3)
    assert ndimage.label(out < 0)[1] == 1
    assert (out[18:22, 4:7, 18:22] < 0).all()  # solid under the column's foot
    assert (p == 3).any()


def test_no_column_where_the_cameras_saw_through_the_thinnest():
    def free(p):  # seen through everywhere beyond 1 cm of the axis
        return np.hypot(p[:, 0], p[:, 2]) > 0.01

    assert column_mod.find_column(_chair(), _rotation(), free, H) is None


def test_sure_free_space_needs_readings_around_the_ray():
    # a wall 2 m away with a hole of one pixel: the hole filling carves in front of it, the
    # sure free space does not (no reading along that ray)
    K = np.array([[100.0, 0, 32], [0, 100.0, 32], [0, 0, 1]])
    depth = np.full((64, 64), 2.0, np.float32)
    depth[32, 32] = 0.0
    frame = Frame(depth, None, K, np.eye(4))
    in_hole = np.array([[0.0, 0.0, 1.0]])
    beside = np.array([[0.1, 0.1, 1.0]])  # pixel (42, 42): readings all around
    assert Carver([frame], 0.01).free(in_hole)[0]
    assert not column_mod.sure_carver([frame], 0.01).free(in_hole)[0]
    assert column_mod.sure_carver([frame], 0.01).free(beside)[0]
    # a point behind the wall is not free either way
    assert not column_mod.sure_carver([frame], 0.01).free(beside * 3)[0]


def test_the_column_joins_base_and_seat_and_is_guessed_surface():
    from scipy import ndimage

    sdf = np.ones((20, 60, 20), np.float32)
    sdf[:, 5:10] = -1.0  # the base's slab, y 0.05-0.09
    sdf[:, 45:50] = -1.0  # the seat, y 0.45-0.49
    prov = np.zeros(sdf.shape, np.uint8)
    col = column_mod.Column(0.0, 0.0, 0.095, 0.445, 0.03, 0.0)
    origin = np.array([-0.095, 0.0, -0.095])
    out, p, n = column_mod.add_column(sdf, prov, col, np.eye(4), origin, H, _never_free, 3)
    assert ndimage.label(sdf < 0)[1] == 2
    assert ndimage.label(out < 0)[1] == 1
    assert n > 0
    assert (p == 3).any()

    # where the sure free space says so, the column is cut
    def free(q):
        return q[:, 1] > 0.3

    cut, _, _ = column_mod.add_column(sdf, prov, col, np.eye(4), origin, H, free, 3)
    assert ndimage.label(cut < 0)[1] == 2


def _mirrors(*thetas: float) -> list[Symmetry]:
    """Vertical mirror planes through the y axis at angles ``thetas`` (radians)."""
    return [
        Symmetry("mirror", np.eye(3), np.zeros(3), 1.0, 0.0, params={"theta": t, "offset": 0.0})
        for t in thetas
    ]


def _pedestal_table(base_x: float = 0.0) -> np.ndarray:
    """(N, 3) upright surface points: a plinth 0.4 m square (its top at 0.06 m, centred at
    ``base_x``) and a top 0.8 m square at 0.72 m, nothing between (the pedestal unseen)."""
    g = np.arange(-0.2, 0.2, 0.01)
    bx, bz = np.meshgrid(g + base_x, g)
    base = np.stack([bx.ravel(), np.full(bx.size, 0.06), bz.ravel()], axis=1)
    t = np.arange(-0.4, 0.4, 0.01)
    tx, tz = np.meshgrid(t, t)
    top = np.stack([tx.ravel(), np.full(tx.size, 0.72), tz.ravel()], axis=1)
    return np.concatenate([base, top])


def test_a_top_over_a_plinth_gets_a_pedestal_on_the_mirror_planes_crossing():
    # no turning base, two mirror planes crossing on the y axis, nothing seen between the
    # plinth and the top: a column from the plinth's top to the top
    col = column_mod.find_pedestal(_pedestal_table(), _mirrors(0.0, np.pi / 2), _never_free, H)
    assert col is not None and col.of == "pedestal"
    assert abs(col.x) < 1e-9 and abs(col.z) < 1e-9
    assert col.bottom == pytest.approx(0.06) and col.top == pytest.approx(0.72)
    assert col.radius == pytest.approx(column_mod.MAX_RADIUS)
    assert col.as_dict()["of"] == "pedestal"


def test_no_pedestal_without_two_crossing_planes_a_gap_or_a_plinth_around_the_axis():
    table = _pedestal_table()
    assert column_mod.find_pedestal(table, _mirrors(0.0), _never_free, H) is None
    # two planes 10 degrees apart cross nowhere firm
    assert column_mod.find_pedestal(table, _mirrors(0.0, 0.17), _never_free, H) is None
    # legs carry the top (each a ring of points 2 cm across): no height without surface
    y, a = np.arange(0.0, 0.72, 0.005), np.linspace(0, 2 * np.pi, 12, endpoint=False)
    Y, A = np.meshgrid(y, a)
    legs = [
        np.stack([sx + 0.02 * np.cos(A).ravel(), Y.ravel(), sz + 0.02 * np.sin(A).ravel()], 1)
        for sx in (-0.35, 0.35)
        for sz in (-0.35, 0.35)
    ]
    both = _mirrors(0.0, np.pi / 2)
    assert column_mod.find_pedestal(np.concatenate([table, *legs]), both, _never_free, H) is None
    # what lies below stands to one side of the crossing: no pedestal under it
    assert column_mod.find_pedestal(_pedestal_table(base_x=0.35), both, _never_free, H) is None

    # the cameras saw through where even the thinnest column would stand
    def free(p):
        return np.hypot(p[:, 0], p[:, 2]) > 0.01

    assert column_mod.find_pedestal(table, both, free, H) is None


def test_kenneys_round_table_seen_from_above_its_top_stands_on_a_guessed_pedestal():
    # three views 30 degrees above, 120 degrees apart: its top hides its pedestal, and the
    # plinth and the top were two pieces (no turning base, no strut that long); the mirror
    # planes' crossing carries a pedestal between them: one piece, nothing said
    import dataclasses
    import warnings

    from conftest import data_path

    from partscale import ingest
    from partscale.complete import complete
    from partscale.evaluate import virtual_scan

    mesh = ingest.load_mesh(data_path("kenney/tableRound.glb"))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)  # Kenney units
    frames = virtual_scan(mesh, azimuths=(353.0, 113.0, 233.0), elevation=30.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = complete(frames, res=128)
    m = c.meta["completion"]
    assert m["column"] is not None and m["column"]["of"] == "pedestal"
    assert m["pieces"] == 1 and m["guard"]["caveats"] == []
