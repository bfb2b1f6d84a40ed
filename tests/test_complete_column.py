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
