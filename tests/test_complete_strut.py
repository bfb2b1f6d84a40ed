"""partscale.complete.strut: pieces the completion left apart are joined to the object by thin
guessed struts, never across space a camera surely saw through, never over long gaps."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

H = 0.01
RADIUS = 0.012


def _two_blocks(gap: int):
    """(sdf, prov, origin): a large block and a small one ``gap`` voxels above it (a seat and a
    chair's back), as the fusion writes them (surface voxels observed)."""
    from edt import edt

    solid = np.zeros((40, 30 + gap, 40), bool)
    solid[5:35, 3:10, 5:35] = True  # the seat, 9000 voxels
    solid[10:30, 10 + gap : 20 + gap, 15:20] = True  # the back, 1000 voxels
    e_out = edt(np.ascontiguousarray(~solid)) - 0.5
    e_in = edt(np.ascontiguousarray(solid)) - 0.5
    sdf = (np.where(solid, -e_in, e_out) * H).astype(np.float32)
    prov = np.where(np.abs(sdf) <= H, 1, 0).astype(np.uint8)
    return sdf, prov, np.zeros(3)


def _struts(sdf, prov, origin, sure_free, max_gap=0.1, mirror=None):
    from partscale.complete import GUESSED
    from partscale.complete.strut import add_struts

    return add_struts(sdf, prov, origin, H, sure_free, GUESSED, max_gap, RADIUS, mirror)


def _pieces(sdf) -> int:
    return ndimage.label(sdf < 0)[1]


def _nothing_free(p):
    return np.zeros(len(p), bool)


def test_a_piece_across_a_short_unseen_gap_is_joined_by_a_thin_guessed_strut():
    from partscale.complete import GUESSED
    from partscale.complete.tidy import fill_contacts
    from partscale.csdf import make
    from partscale.surface import to_mesh

    sdf, prov, origin = _two_blocks(gap=6)
    assert _pieces(sdf) == 2
    out, p2, struts = _struts(sdf, prov, origin, _nothing_free)
    assert _pieces(out) == 1
    assert len(struts) == 1 and struts[0].piece_voxels == 1000
    # the shortest path: straight down the 6 voxels between them, a strut of the radius
    assert 0.05 <= struts[0].gap <= 0.07
    added = (out < 0) & ~(sdf < 0)
    assert added.sum() == struts[0].voxels
    assert 0 < added.sum() <= 6 * 9 + 9  # 6 layers of at most a 3x3 cross-section, and ends
    assert ((out < 0) >= (sdf < 0)).all()  # nothing removed
    assert (p2[added & (np.abs(out) <= H)] == GUESSED).all()
    assert (p2 == GUESSED).sum() > 0
    fixed, _ = fill_contacts(out, H)
    assert to_mesh(make(fixed, voxel_size=H)).is_watertight


def test_no_strut_across_surely_free_space_or_over_a_long_gap():
    sdf, prov, origin = _two_blocks(gap=6)

    def free_between(p):
        # the camera saw through the whole layer between seat and back
        y = p[:, 1] / H
        return (y > 10.5) & (y < 15.5)

    out, _, struts = _struts(sdf, prov, origin, free_between)
    assert struts == [] and _pieces(out) == 2
    assert (out == sdf).all()
    # the same gap with nothing seen through, but longer than the bound
    out, _, struts = _struts(sdf, prov, origin, _nothing_free, max_gap=0.04)
    assert struts == [] and _pieces(out) == 2


def test_a_strut_goes_around_what_the_camera_saw_through():
    sdf, prov, origin = _two_blocks(gap=6)
    core = np.zeros(sdf.shape, bool)
    core[8:32, 10:16, 13:40] = True  # seen through: under the back and in front of it

    def free_in_front(p):
        i = np.rint(p / H).astype(int)
        return core[i[:, 0], i[:, 1], i[:, 2]]

    out, _, struts = _struts(sdf, prov, origin, free_in_front)
    assert len(struts) == 1 and _pieces(out) == 1
    added = (out < 0) & ~(sdf < 0)
    assert not (added & core).any()
    assert struts[0].gap > 0.06  # longer than straight down


def test_the_strut_is_the_shortest_path_though_a_longer_one_winds_near_the_piece(monkeypatch):
    # the search starts among the voxels near both the piece and the object and widens: a path
    # found there that winds (through an opening at the top of one wall the camera saw
    # through, down between the walls, out through an opening at the bottom of the other) is
    # not taken when a shorter one (over both walls) leaves that first search
    from edt import edt
    from skimage.graph import MCP_Geometric

    from partscale.complete import strut

    monkeypatch.setattr(strut, "FIRST_BALL", 8)
    solid = np.zeros((24, 30, 40), bool)
    solid[2:10, 0:20, 5:35] = True  # the piece
    solid[14:22, 0:20, 5:35] = True  # the object, 4 voxels from it
    solid[14:22, 0:3, 0:40] = True  # (the larger)
    wall = np.zeros(solid.shape, bool)  # two walls seen through between them, 24 voxels tall
    wall[11, 0:24, :] = True
    wall[13, 0:24, :] = True
    wall[11, 17:19, 18:22] = False  # an opening near the top of the first
    wall[13, 3:5, 18:22] = False  # and one near the bottom of the second

    def free_walls(p):
        i = np.rint(p / H).astype(int)
        return wall[i[:, 0], i[:, 1], i[:, 2]]

    e_out = edt(np.ascontiguousarray(~solid)) - 0.5
    e_in = edt(np.ascontiguousarray(solid)) - 0.5
    sdf = (np.where(solid, -e_in, e_out) * H).astype(np.float32)
    prov = np.where(np.abs(sdf) <= H, 1, 0).astype(np.uint8)
    lab, _ = ndimage.label(solid)
    costs, _ = MCP_Geometric(np.where(wall, np.inf, 1.0)).find_costs(np.argwhere(lab == 1))
    truth = (costs[lab == 2].min() - 1.0) * H  # over the walls: 0.122; winding: 0.158
    _, _, struts = _struts(sdf, prov, np.zeros(3), free_walls, max_gap=0.4)
    assert len(struts) == 1
    assert struts[0].gap <= truth + 1e-6 and truth < 0.13
    assert struts[0].start[1] >= 19 * H  # over the top, not through the openings


@pytest.mark.parametrize("gap", [12, 20])
def test_a_piece_beyond_the_first_ball_is_joined_over_the_shortest_path(gap):
    from skimage.graph import MCP_Geometric

    from partscale.complete.strut import FIRST_BALL

    assert gap > FIRST_BALL
    sdf, prov, origin = _two_blocks(gap=gap)
    core = np.zeros(sdf.shape, bool)
    core[8:32, 10 : 10 + gap, 13:40] = True  # seen through: under the back and in front of it

    def free_in_front(p):
        i = np.rint(p / H).astype(int)
        return core[i[:, 0], i[:, 1], i[:, 2]]

    lab, _ = ndimage.label(sdf < 0)
    costs, _ = MCP_Geometric(np.where(core, np.inf, 1.0)).find_costs(np.argwhere(lab == 2))
    truth = (costs[lab == 1].min() - 1.0) * H  # the shortest path over the whole grid
    _, _, struts = _struts(sdf, prov, origin, free_in_front, max_gap=0.4)
    assert len(struts) == 1
    assert struts[0].gap <= truth + 1e-6


def _mirror_x(p):
    # the plane x = 19.5 voxels, holding everywhere
    return np.c_[39 * H - p[:, 0], p[:, 1], p[:, 2]], np.ones(len(p), bool)


def _armrests():
    from edt import edt

    solid = np.zeros((40, 30, 40), bool)
    solid[5:35, 3:10, 5:35] = True  # the seat
    solid[5:9, 15:19, 10:30] = True  # two armrests above it, mirror images across x
    solid[31:35, 15:19, 10:30] = True
    e_out = edt(np.ascontiguousarray(~solid)) - 0.5
    e_in = edt(np.ascontiguousarray(solid)) - 0.5
    sdf = (np.where(solid, -e_in, e_out) * H).astype(np.float32)
    return sdf, np.where(np.abs(sdf) <= H, 1, 0).astype(np.uint8), np.zeros(3)


def test_a_strut_beside_the_mirror_plane_gets_its_image_where_nothing_was_seen_through():
    sdf, prov, origin = _armrests()
    assert _pieces(sdf) == 3
    out, _, struts = _struts(sdf, prov, origin, _nothing_free, mirror=_mirror_x)
    assert _pieces(out) == 1
    assert len(struts) == 1 and struts[0].mirrored_voxels == struts[0].voxels > 0
    added = (out < 0) & ~(sdf < 0)
    assert (added == added[::-1]).all()  # two bars, mirror images

    def free_right(p):
        # seen through under the right armrest: its image is not drawn, it gets its own strut
        # around what was seen
        x, y, z = (p / H).T
        return (x > 25) & (y > 10.5) & (y < 14.5) & (z > 8) & (z < 32)

    out, _, struts = _struts(sdf, prov, origin, free_right, mirror=_mirror_x)
    assert _pieces(out) == 1 and len(struts) == 2
    assert all(s.mirrored_voxels == 0 for s in struts)
    added = (out < 0) & ~(sdf < 0)
    assert not (added[26:, 11:15, 9:32]).any()


@pytest.mark.slow
def test_the_derived_yellow_chair_completes_to_one_piece():
    # its back hangs on a bar behind the seat that the scan does not show; three leg ends
    # were apart too (5 pieces at --res 128 without struts)
    from conftest import data_path

    from partscale.complete import GUESSED, complete_file, provenance
    from partscale.surface import to_mesh

    c = complete_file(
        data_path("scans/derived/tum_yellow_office_chair_partial.ply"), res=64, upright=True
    )
    struts = c.meta["completion"]["struts"]
    assert struts and all(0 < s["gap"] <= 0.2 * 0.9 for s in struts)
    assert _pieces(np.asarray(c.sdf)) == 1
    assert to_mesh(c).is_watertight
    assert (provenance(c) == GUESSED).any()
    assert c.meta["history"][0]["strut_max_gap_share"] == 0.2
    # a sphere tracer (render) steps by |sdf|: no value may overstate the distance to the other
    # side by more than two voxels (beyond the band the fusion's values measured to the solid
    # before the column and the struts: 20 voxels too far, and renders showed the column in rings)
    from edt import edt

    s = np.ascontiguousarray(np.asarray(c.sdf) < 0)
    d = np.where(s, edt(s), edt(~s)) * c.voxel_size
    assert (np.abs(c.sdf) - d).max() <= 2 * c.voxel_size


def test_what_a_strut_joins_is_read_by_one_labelling_as_scipy_propagates_it():
    # the pieces a strut joined are found by labelling the solid once, not by a dilation
    # repeated until nothing changes: the same voxels, seeds outside the solid included
    from scipy import ndimage

    from partscale.complete.strut import _reached

    rng = np.random.default_rng(1)
    grew = 0
    for _ in range(20):
        shape = tuple(int(n) for n in rng.integers(4, 32, 3))
        solid = ndimage.gaussian_filter(rng.random(shape), 1.2) > rng.uniform(0.45, 0.55)
        seed = (rng.random(shape) > 0.995) & (solid | (rng.random(shape) > 0.5))
        want = ndimage.binary_propagation(seed, mask=solid)
        assert (want == _reached(seed, solid)).all()
        grew += int(want.sum() > seed.sum())
    assert grew >= 10  # most seeds reach more of the solid


def test_pieces_touching_along_an_edge_get_no_strut():
    # a rod a voxel thick across the axes touches the seat only along edges: the contact fill
    # joins it (tidy.fill_contacts), no strut is drawn and nothing is added
    from edt import edt

    solid = np.zeros((40, 40, 70), bool)
    solid[5:35, 3:10, 5:35] = True
    k = np.arange(20)
    solid[20, 10 + k, 35 + k] = True  # each voxel touches the next (and the seat) along an edge
    e_out = edt(np.ascontiguousarray(~solid)) - 0.5
    e_in = edt(np.ascontiguousarray(solid)) - 0.5
    sdf = (np.where(solid, -e_in, e_out) * H).astype(np.float32)
    prov = np.where(np.abs(sdf) <= H, 1, 0).astype(np.uint8)
    assert _pieces(sdf) == 21
    out, _, struts = _struts(sdf, prov, np.zeros(3), _nothing_free)
    assert struts == [] and (out == sdf).all()


@pytest.mark.parametrize("share", [0.5, 0.99, 0.9995])
def test_the_struts_distances_are_scipys_exact_distances_bit_for_bit(share):
    # the struts' search compares sums of two distances with its radius: they must be the
    # exact distances scipy gives, not close ones
    from partscale.complete.strut import _distances

    mask = np.random.default_rng(5).random((37, 44, 29)) < share
    got = _distances(mask)
    assert got.dtype == np.float64
    np.testing.assert_array_equal(got, ndimage.distance_transform_edt(mask))
