"""partscale.complete: the completed grid meshes watertight, without floating specks."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import complete_tum_frame
from scipy import ndimage


def _sdf_of(solid: np.ndarray, h: float = 0.01) -> np.ndarray:
    """(X, Y, Z) float32 SDF of a voxel solid as the fusion makes it: the outside half a voxel
    short of its neighbours' centres, the inside BACK_SHIFT further (ties of +-0.1 voxel)."""
    from edt import edt

    from partscale.complete.fuse import BACK_SHIFT

    e_out = edt(np.ascontiguousarray(~solid)) - 0.5
    e_in = edt(np.ascontiguousarray(solid)) - 0.5 - BACK_SHIFT
    return (np.where(solid, -e_in, e_out) * h).astype(np.float32)


def _mesh(sdf, h=0.01):
    from partscale.csdf import make
    from partscale.surface import to_mesh

    return to_mesh(make(sdf, voxel_size=h))


def test_a_tied_diagonal_contact_is_filled_so_the_mesh_is_watertight():
    # three voxel layers from the raw frame's yellow chair at --res 128: solid voxels touching
    # only along edges, every value +-0.1 voxel (the fusion's values in front of and behind a
    # surface point): marching cubes joins them by edges of four faces
    from partscale.complete.tidy import fill_contacts

    layers = [[[1, 1], [0, 1]], [[0, 1], [1, 0]], [[1, 1], [0, 1]]]
    solid = np.zeros((7, 6, 6), bool)
    solid[2:5, 2:4, 2:4] = np.array(layers, bool)
    sdf = np.where(solid, -0.001, 0.001).astype(np.float32)
    assert not _mesh(sdf).is_watertight
    out, n = fill_contacts(sdf, 0.01)
    assert 1 <= n <= 4
    assert ((out < 0) >= solid).all()  # filled, nothing removed
    assert _mesh(out).is_watertight


@pytest.mark.parametrize("contact", ["edge", "corner"])
def test_blocks_touching_diagonally_are_bridged(contact):
    from partscale.complete.tidy import fill_contacts

    solid = np.zeros((14, 14, 14), bool)
    solid[2:7, 2:7, 2:7] = True
    if contact == "edge":
        solid[7:12, 7:12, 2:7] = True  # touches the first block along an edge only
    else:
        solid[7:12, 7:12, 7:12] = True  # at a corner only
    out, n = fill_contacts(_sdf_of(solid), 0.01)
    assert ndimage.label(solid)[1] == 2
    assert 1 <= n <= 10  # a few voxels bridge the contact, the blocks are kept
    assert ((out < 0) >= solid).all()
    assert ndimage.label(out < 0)[1] == 1
    assert _mesh(out).is_watertight


def test_later_rounds_find_what_whole_grid_rounds_find():
    # later rounds look only around the voxels filled before: on noisy grids (contacts at the
    # borders, fills that make new contacts, grids two voxels thin) they fill exactly what
    # whole-grid rounds fill
    from partscale.complete.tidy import FILL_VOXELS, _ambiguous, fill_contacts

    rng = np.random.default_rng(7)
    most_rounds = 0
    for _ in range(60):
        shape = tuple(int(x) for x in rng.integers(2, 10, 3))
        solid = rng.random(shape) < rng.uniform(0.2, 0.8)
        sdf = np.where(solid, -rng.random(shape), rng.random(shape)).astype(np.float32) * 0.01
        ref, total, rounds = sdf.copy(), 0, 0
        while (fill := _ambiguous(ref < 0)).any():
            ref[fill] = np.minimum(ref[fill], np.float32(-FILL_VOXELS * 0.01))
            total, rounds = total + int(fill.sum()), rounds + 1
        out, n = fill_contacts(sdf, 0.01)
        assert n == total and np.array_equal(out, ref), shape
        most_rounds = max(most_rounds, rounds)
    assert most_rounds >= 3  # fills that made new contacts were among them


def test_specks_are_dropped_and_parts_kept():
    from partscale.complete.tidy import SPECK_SHARE, drop_specks

    solid = np.zeros((40, 40, 40), bool)
    solid[2:30, 2:30, 2:30] = True  # the body, 21952 voxels
    solid[34:38, 34:38, 2:30] = True  # a separate part (a leg), 448 voxels: 0.02 of the body
    solid[34, 5, 5] = solid[36, 20, 36] = True  # specks of one voxel
    solid[34:36, 34:36, 34:37] = True  # a speck of 12 voxels
    solid[30, 30, 10] = True  # a bump touching the body along an edge only: noise too
    assert 12 < SPECK_SHARE * 21952 < 448
    out, n = drop_specks(_sdf_of(solid), 0.01)
    assert n == 4
    kept = out < 0
    assert kept[2:30, 2:30, 2:30].all() and kept[34:38, 34:38, 2:30].all()
    assert not kept[34, 5, 5] and not kept[36, 20, 36] and not kept[34:36, 34:36, 34:37].any()
    assert not kept[30, 30, 10]
    assert ndimage.label(kept)[1] == 2


@pytest.mark.slow
def test_raw_frame_yellow_chair_is_watertight_without_specks():
    # at --res 128 the raw frame's yellow chair kept 432 solid pieces (6-connected), 408 of
    # under 10 voxels (flying pixels, bumps touching the chair along an edge), and marching
    # cubes met three diagonal contacts (edges of four faces)
    from partscale.complete.tidy import SPECK_SHARE
    from partscale.surface import to_mesh

    c = complete_tum_frame((365, 225, 540, 440))
    assert to_mesh(c).is_watertight
    lab, n = ndimage.label(np.asarray(c.sdf) < 0)
    size = np.bincount(lab.ravel())[1:]
    assert size.min() >= SPECK_SHARE * size.max()
    assert n <= 10, f"expected the chair's few parts, got {n} solid components"
    assert c.meta["completion"]["specks_dropped"] >= 100


def test_a_chain_of_pieces_touching_at_edges_is_a_thin_part_not_specks():
    # a rod about a voxel thick lying across the grid's axes is a staircase of voxels that touch
    # only along edges: 45 pieces of one voxel (6-connected), each under SPECK_SHARE of the body,
    # together above it (a railing's baluster seen from three views fell apart into such pieces)
    from partscale.complete.tidy import SPECK_SHARE, drop_specks

    solid = np.zeros((70, 50, 40), bool)
    solid[2:20, 2:20, 2:20] = True  # the body, 5832 voxels
    k = np.arange(45)
    solid[22 + k, 2 + k, 30] = True  # the rod: 45 voxels, each touching the next along an edge
    solid[60 + np.arange(3), 2 + np.arange(3), 5] = True  # a short chain: 3 voxels, noise
    solid[20, 20, 10] = True  # a bump touching the body along an edge only: noise
    solid[40, 45, 10] = True  # a speck
    assert 3 < SPECK_SHARE * 5832 < 45
    out, n = drop_specks(_sdf_of(solid), 0.01)
    kept = out < 0
    assert kept[22 + k, 2 + k, 30].all()
    assert not kept[60:63, 2:5, 5].any() and not kept[20, 20, 10] and not kept[40, 45, 10]
    assert n == 5  # the short chain's three voxels, the bump and the speck
