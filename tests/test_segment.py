"""Part segmentation: one part per separate solid, splits at inner corners, labels that cover the
surface, connected parts, reproducible and cached results, and labels that travel with the file."""

from __future__ import annotations

import os

import numpy as np
import pytest
from conftest import assert_bad_input, data_path
from scipy import ndimage

import partscale
from partscale import ingest, shapes
from partscale.edit import apply_edit
from partscale.errors import InputError, MemoryLimitError, PartscaleWarning
from partscale.segment import (
    DEFAULT_METHOD,
    coacd_method,
    concavity,
    part_concavities,
    segment,
)
from partscale.segment import labels as labels_mod
from partscale.surface import sample_nearest, to_mesh

H = 0.025  # voxel size of the analytic shapes (L: 47 x 47 x 19 voxels)
# CoACD with a light search: the same algorithm, seconds instead of tens of seconds
QUICK_COACD = {"preprocess_mode": "off", "resolution": 500, "mcts_iterations": 50, "mcts_nodes": 10}
METHODS = {"coacd": QUICK_COACD, "fast": {}}
BOXES = [
    ((0.0, 0.0, 0.0), (0.3, 0.2, 0.4)),
    ((0.5, 0.0, 0.0), (0.7, 0.5, 0.2)),
    ((0.0, 0.4, 0.5), (0.6, 0.7, 0.7)),
]
ARM = 0.3  # L: arms [0, 1] x [0, ARM] and [0, ARM] x [0, 1], thickness ARM; inner corner at ARM


def l_sdf(p):
    return np.minimum(
        shapes.box_sdf(p, (0, 0, 0), (1.0, ARM, ARM)), shapes.box_sdf(p, (0, 0, 0), (ARM, 1.0, ARM))
    )


@pytest.fixture(scope="module")
def lshape():
    return shapes.grid(l_sdf, ((0, 0, 0), (1, 1, ARM)), voxel_size=H)


@pytest.fixture(scope="module")
def boxes():
    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, BOXES), ((0, 0, 0), (0.7, 0.7, 0.7)), voxel_size=H
    )


def table_grid(voxel_size: float):
    """A tabletop on four legs (legs meet the top at z = 0.5)."""
    parts = [((0.0, 0.0, 0.5), (0.8, 0.5, 0.56))]
    for x in (0.0, 0.72):
        for y in (0.0, 0.42):
            parts.append(((x, y, 0.0), (x + 0.08, y + 0.08, 0.53)))
    return shapes.grid(
        lambda p: np.min([shapes.box_sdf(p, lo, hi) for lo, hi in parts], axis=0),
        ((0, 0, 0), (0.8, 0.5, 0.56)),
        voxel_size=voxel_size,
    )


@pytest.fixture(scope="module")
def table():
    return table_grid(H)


@pytest.fixture(scope="module")
def segmented(lshape, boxes, table, tmp_path_factory):
    """Every method on every analytic shape, computed once for the module."""
    cache = tmp_path_factory.mktemp("cache")
    out = {}
    for name, c in (("L", lshape), ("boxes", boxes), ("table", table)):
        for m, params in METHODS.items():
            out[name, m] = segment(c, method=m, cache_dir=cache, **params)
    return out


def inside_labels(c, box):
    lo, hi = np.asarray(box[0]), np.asarray(box[1])
    ijk = np.argwhere(c.sdf < 0)
    w = c.index_to_world(ijk)
    sel = np.all((w > lo) & (w < hi), axis=1)
    return c.parts[tuple(ijk[sel].T)]


@pytest.mark.parametrize("method", METHODS)
def test_disjoint_boxes_give_one_part_per_box(segmented, method):
    s = segmented["boxes", method]
    assert s.n_parts == len(BOXES)
    owners = []
    for b in BOXES:
        lab = inside_labels(s, b)
        assert lab.size and (lab == lab[0]).all(), np.unique(lab)
        owners.append(int(lab[0]))
    assert sorted(owners) == list(range(len(BOXES)))


@pytest.mark.parametrize("method", METHODS)
def test_l_shape_splits_in_two_at_the_inner_corner(segmented, method):
    s = segmented["L", method]
    assert s.n_parts == 2
    # the two far ends are in different parts
    far_x = s.parts[tuple(np.rint(s.world_to_index([[0.95, 0.15, 0.15]])[0]).astype(int))]
    far_y = s.parts[tuple(np.rint(s.world_to_index([[0.15, 0.95, 0.15]])[0]).astype(int))]
    assert {int(far_x), int(far_y)} == {0, 1}
    # where the surface changes part: one plane, x = ARM or y = ARM, within 2 voxels
    mesh = to_mesh(s)
    lab = mesh.vertex_attributes["parts"]
    e = mesh.edges_unique
    border = mesh.vertices[e[lab[e[:, 0]] != lab[e[:, 1]]]].mean(axis=1)  # edge midpoints
    assert len(border) > 0
    off = np.abs(border[:, :2] - ARM).max(axis=0)  # farthest border point from each plane
    # the border lies in one of the two corner planes (the other coordinate spans the arm)
    assert off.min() <= 2 * H, off / H
    axis = int(np.argmin(off))
    other = 1 - axis
    assert np.ptp(border[:, other]) >= ARM - 2 * H


@pytest.mark.parametrize("shape", ["L", "boxes", "table"])
@pytest.mark.parametrize("method", METHODS)
def test_surface_voxels_labelled_and_parts_connected(segmented, shape, method):
    s = segmented[shape, method]
    surface = np.abs(s.sdf) < s.voxel_size
    assert (s.parts[surface] >= 0).all()
    assert (s.parts[s.sdf > 4 * s.voxel_size] == -1).all()  # far outside: no part
    labels = np.unique(s.parts[s.parts >= 0])
    assert labels.tolist() == list(range(s.n_parts))
    for p in labels:
        _, n = ndimage.label(s.parts == p, structure=np.ones((3, 3, 3), bool))
        assert n == 1, (p, n)
    info = s.meta["parts_info"]
    assert [d["index"] for d in info] == list(range(s.n_parts))
    assert [d["voxels"] for d in info] == np.bincount(s.parts[s.parts >= 0]).tolist()
    assert len({tuple(d["color"]) for d in info}) == len(info)
    lo, hi = s.grid_bounds
    for d in info:
        assert np.all(np.asarray(d["bbox"][0]) >= lo) and np.all(np.asarray(d["bbox"][1]) <= hi)
        assert d["hull_volume"] > 0
    assert s.meta["segmentation"]["method"] == method
    assert s.meta["history"][-1]["op"] == "segment"


@pytest.mark.parametrize("method", METHODS)
def test_table_parts_are_top_and_legs(segmented, method):
    s = segmented["table", method]
    assert s.n_parts == 5
    top = inside_labels(s, ((0.1, 0.1, 0.51), (0.7, 0.4, 0.55)))
    leg = inside_labels(s, ((0.01, 0.01, 0.0), (0.07, 0.07, 0.45)))
    assert (top == top[0]).all() and (leg == leg[0]).all() and top[0] != leg[0]


@pytest.mark.parametrize("method", METHODS)
def test_parts_are_nearly_convex(segmented, method):
    # a tolerance well under the L's own concavity (about 20 voxels)
    for shape in ("L", "boxes", "table"):
        assert part_concavities(segmented[shape, method]).max() <= 3.0


def test_concavity_of_l_as_one_part_matches_its_notch(lshape):
    one = lshape.replace(parts=np.where(lshape.sdf < 3 * H, 0, -1))
    # the middle of the hull's facet x + y = 1 + ARM is (1 - ARM) / 2 from both arms
    truth = (1 - ARM) / 2 / H
    assert truth - 1.5 <= concavity(one, 0) <= truth + 1.0
    with pytest.raises(IndexError):
        concavity(one, 1)


@pytest.mark.parametrize("method", METHODS)
def test_same_seed_same_parts(lshape, method):
    options = QUICK_COACD if method == "coacd" else {}
    a = segment(lshape, method=method, seed=3, cache=False, **options)
    b = segment(lshape, method=method, seed=3, cache=False, **options)
    assert np.array_equal(a.parts, b.parts)
    assert a.meta["parts_info"] == b.meta["parts_info"]


def test_cache_skips_the_decomposition(boxes, tmp_path, monkeypatch):
    calls = []
    real = coacd_method.run

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(coacd_method, "run", counting)
    first = segment(boxes, method="coacd", cache_dir=tmp_path, **QUICK_COACD)
    assert len(calls) == 1
    key = first.meta["segmentation"]["key"]
    assert (tmp_path / f"{key}.npz").is_file()
    again = segment(boxes, method="coacd", cache_dir=tmp_path, **QUICK_COACD)
    assert len(calls) == 1
    assert np.array_equal(first.parts, again.parts)
    assert first.meta["parts_info"] == again.meta["parts_info"]
    # other parameters: another key, another run
    segment(boxes, method="coacd", cache_dir=tmp_path, seed=1, **QUICK_COACD)
    assert len(calls) == 2
    # the environment variable moves the default folder
    monkeypatch.setenv("PARTSCALE_CACHE", str(tmp_path / "env"))
    segment(boxes, method="coacd", **QUICK_COACD)
    assert (tmp_path / "env" / "segment" / f"{key}.npz").is_file()


def test_cache_moves_bboxes_with_the_origin(boxes, tmp_path):
    a = segment(boxes, method="fast", cache_dir=tmp_path)
    moved = boxes.replace(origin=np.add(boxes.origin, (1.0, 2.0, 3.0)))
    b = segment(moved, method="fast", cache_dir=tmp_path)
    assert a.meta["segmentation"]["key"] == b.meta["segmentation"]["key"]
    for da, db in zip(a.meta["parts_info"], b.meta["parts_info"], strict=True):
        np.testing.assert_allclose(np.asarray(db["bbox"]) - da["bbox"], [[1, 2, 3]] * 2)


def test_labels_survive_save_and_load(segmented, tmp_path):
    s = segmented["table", "fast"]
    path = partscale.save(s, tmp_path / "t.csdf.npz")
    back = partscale.load(path)
    assert np.array_equal(back.parts, s.parts)
    assert back.meta["parts_info"] == s.meta["parts_info"]
    # the mesh carries them too
    mesh = to_mesh(back)
    idx = back.world_to_index(mesh.vertices)
    assert np.array_equal(mesh.vertex_attributes["parts"], sample_nearest(back.parts, idx))


def test_labels_survive_a_stretch(segmented):
    s = segmented["table", "fast"]
    # stretch the middle of the tabletop along x by 0.2: the right legs move by 0.2
    out = apply_edit(s, {"axis": "x", "zone": [0.3, 0.5], "to": 0.7, "mode": "stretch"})
    assert out.n_parts == s.n_parts

    def part_at(c, point):
        return int(c.parts[tuple(np.rint(c.world_to_index([point])[0]).astype(int))])

    for x, y in ((0.04, 0.04), (0.04, 0.46), (0.76, 0.04), (0.76, 0.46)):
        moved = x + 0.2 if x > 0.5 else x
        assert part_at(out, (moved, y, 0.25)) == part_at(s, (x, y, 0.25))
    top = part_at(s, (0.4, 0.25, 0.53))
    assert {part_at(out, (x, 0.25, 0.53)) for x in np.linspace(0.1, 0.9, 17)} == {top}
    assert (out.parts[np.abs(out.sdf) < out.voxel_size] >= 0).all()
    # parts stay in one piece in the solid and on its surface (the edit's own labels farther
    # out, in the air, are its business)
    solid = out.sdf < out.voxel_size
    for p in range(out.n_parts):
        _, n = ndimage.label((out.parts == p) & solid, structure=np.ones((3, 3, 3), bool))
        assert n == 1, (p, n)


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"method": "magic"}, "method"),
        ({"threshold": 0.0}, "threshold"),
        ({"threshold": 1.5}, "threshold"),
        ({"max_parts": 0}, "max_parts"),
        ({"seed": -1}, "seed"),
        ({"method": "coacd", "preprocess_mode": "sometimes"}, "preprocess_mode"),
        # counts: one line naming the option, what it takes and what came
        ({"max_parts": 2.5}, r"^max_parts \(or None\): expected an integer >= 1, got 2.5$"),
        ({"seed": True}, "^seed: expected an integer >= 0, got True$"),
        ({"method": "fast", "max_depth": 0}, "^max_depth: expected an integer >= 1, got 0$"),
        ({"method": "coacd", "mcts_max_depth": 1.0}, "^mcts_max_depth: expected an integer >= 1"),
    ],
)
def test_bad_options_are_refused(boxes, kwargs, fragment):
    with pytest.raises(InputError, match=fragment):
        segment(boxes, cache=False, **kwargs)


def test_check_method_names_the_option_and_the_methods():
    from partscale.segment import METHODS, check_method

    assert [check_method(m) for m in METHODS] == list(METHODS)
    with pytest.raises(InputError) as err:
        check_method("magic", what="--method")
    assert str(err.value) == f"--method: expected one of {', '.join(METHODS)}, got 'magic'"


def test_unknown_method_option_lists_the_known_ones(boxes):
    with pytest.raises(TypeError, match="preprocess_resolution"):
        segment(boxes, method="coacd", cache=False, resolutoin=10)


def test_huge_request_is_refused_with_what_it_needs(boxes, monkeypatch):
    monkeypatch.setenv("PARTSCALE_MAX_MEMORY", "1000")
    with pytest.raises(MemoryLimitError, match="segment"):
        segment(boxes, method="fast", cache=False)


def test_object_without_surface_is_refused():
    empty = partscale.make(np.ones((8, 8, 8), np.float32))
    with pytest.raises(InputError, match="surface"):
        segment(empty, cache=False)


def test_cli_segments_and_refuses_bad_input(cli, boxes, tmp_path):
    src = partscale.save(boxes, tmp_path / "in.csdf.npz")
    out = tmp_path / "out.csdf.npz"
    proc = cli("segment", src, "-o", out, "--no-cache")
    assert proc.returncode == 0, proc.stderr
    got = partscale.load(out)
    assert got.n_parts == len(BOXES)
    # the command's default method is the library's, the fast one since it matched CoACD
    assert got.meta["segmentation"]["method"] == DEFAULT_METHOD == "fast"
    bad = tmp_path / "bad.csdf.npz"
    assert_bad_input(cli("segment", src, "-o", bad, "--method", "magic"), "method", "magic")
    assert_bad_input(cli("segment", src, "-o", bad, "--threshold", "0"), "threshold")
    assert_bad_input(cli("segment", src, "-o", bad, "--threshold", "1.5"), "threshold")
    empty = partscale.save(partscale.make(np.ones((8, 8, 8), np.float32)), tmp_path / "e.csdf.npz")
    assert_bad_input(cli("segment", empty, "-o", bad, "--method", "fast"), "surface")
    assert not bad.exists()


@pytest.fixture(scope="module")
def kenney_table():
    return ingest.load(data_path("kenney/table.glb"), res=64)


@pytest.mark.parametrize("method", METHODS)
def test_real_table_legs_and_top_are_separate_parts(kenney_table, method):
    s = segment(kenney_table, method=method, cache=False, **METHODS[method])
    inside = s.sdf <= 0
    assert (s.parts[np.abs(s.sdf) < s.voxel_size] >= 0).all()
    for p in range(s.n_parts):
        _, n = ndimage.label(s.parts == p, structure=np.ones((3, 3, 3), bool))
        assert n == 1, (p, n)
    # y is up (glTF): the layer just above the floor cuts the four legs
    ys = np.nonzero(inside.any(axis=(0, 2)))[0]
    layer = ys[0] + 1
    comp, n = ndimage.label(inside[:, layer, :])
    assert n == 4
    legs = [np.unique(s.parts[:, layer, :][comp == k]) for k in range(1, n + 1)]
    assert all(len(leg) == 1 for leg in legs), legs
    legs = {int(leg[0]) for leg in legs}
    assert len(legs) == 4
    x, z = s.shape[0] // 2, s.shape[2] // 2
    assert inside[x, ys[-1] - 1, z]
    assert int(s.parts[x, ys[-1] - 1, z]) not in legs
    assert part_concavities(s).max() <= 3.0  # voxels, at 64 voxels along the table


@pytest.mark.parametrize("method", METHODS)
def test_max_parts_bounds_the_count(table, method):
    s = segment(table, method=method, max_parts=2, cache=False, **METHODS[method])
    assert s.n_parts == 2
    for p in range(s.n_parts):
        _, n = ndimage.label(s.parts == p, structure=np.ones((3, 3, 3), bool))
        assert n == 1, (p, n)


def test_max_parts_cannot_join_separate_pieces(boxes):
    s = segment(boxes, method="fast", max_parts=1, cache=False)
    assert s.n_parts == len(BOXES)


def tilted_arch():
    """A half ring (radius 0.4, 0.1 thick, 0.2 deep) turned off every grid axis: no creases."""
    a, b = np.radians(35), np.radians(25)
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])

    def sdf(p):
        q = (p - 0.5) @ (rz @ rx)  # world -> arch frame
        ring = np.abs(np.hypot(q[..., 0], q[..., 1]) - 0.4) - 0.05
        return np.maximum(np.maximum(ring, np.abs(q[..., 2]) - 0.1), -q[..., 1])

    return shapes.grid(sdf, ((0, 0, 0), (1, 1, 1)), voxel_size=H)


def test_fast_cuts_a_tilted_curved_shell_across_its_bend(tmp_path):
    # slices along the grid axes would peel the arch into slivers and leave a bent, concave
    # rest (its inner radius is 14 voxels); cuts through its deepest point keep parts convex
    s = segment(tilted_arch(), method="fast", cache_dir=tmp_path)
    assert part_concavities(s).max() <= 3.0
    assert 2 <= s.n_parts <= 8


SIDES = [((0.0, 0.0, 0.0), (0.075, 1.0, 0.4)), ((0.525, 0.0, 0.0), (0.6, 1.0, 0.4))]
SHELVES = [((0.075, 0.3, 0.0), (0.525, 0.375, 0.4)), ((0.075, 0.65, 0.0), (0.525, 0.725, 0.4))]


def test_fast_keeps_boards_whole_at_t_junctions(tmp_path):
    # two side panels with two shelves between them: cutting at the shelves' faces chops each
    # panel in three; the slices of panel beside the shelves must go back to the panel
    boards = SIDES + SHELVES
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boards), ((0, 0, 0), (0.6, 1.0, 0.4)), voxel_size=H
    )
    s = segment(c, method="fast", cache_dir=tmp_path)
    assert s.n_parts == 4
    # every inside voxel centre in a board's box (the slices beside the shelves included)
    ijk = np.argwhere(c.sdf <= 0)
    w = c.index_to_world(ijk)
    seen = []
    for lo, hi in boards:
        mine = np.all((w > np.add(lo, 0.3 * H)) & (w < np.subtract(hi, 0.3 * H)), axis=1)
        labels = np.unique(s.parts[tuple(ijk[mine].T)])
        assert mine.sum() > 100 and len(labels) == 1
        seen.append(int(labels[0]))
    assert len(set(seen)) == 4
    assert part_concavities(s).max() <= 2.0  # boxes sampled on voxels: within 2 voxels


def test_railing_in_one_plane_is_merged_as_a_group():
    # stringer, seven balusters 4 voxels apart and a handrail, all 3 voxels thick in x: one
    # baluster with the stringer leaves a wide triangle of air in their hull, the whole comb
    # only its narrow gaps (2 voxels from the nearest baluster)
    boards = [((0, 0, 0), (0.075, 0.95, 0.075)), ((0, 0, 0.5), (0.075, 0.95, 0.575))]
    boards += [((0, y, 0.075), (0.075, y + 0.05, 0.5)) for y in np.arange(7) * 0.15]
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boards), ((0, 0, 0), (0.075, 0.95, 0.575)), voxel_size=H
    )
    w = c.index_to_world(np.indices(c.shape).reshape(3, -1).T)
    each = np.stack([shapes.box_sdf(w, lo, hi) for lo, hi in boards])
    labels = np.where(c.sdf.ravel() < 3 * H, each.argmin(axis=0), -1).reshape(c.shape)
    mesh = to_mesh(c)
    pair = np.where(np.isin(labels, (0, 5)), 0, np.where(labels >= 0, 1, -1))
    assert part_concavities(c, pair)[0] > 5.0  # stringer and one baluster: far from convex
    merged = labels_mod.merge_planar_groups(c, mesh, labels, tolerance=2.5)
    assert merged.max() == 0 and part_concavities(c, merged).max() <= 2.5
    kept = labels_mod.merge_planar_groups(c, mesh, labels, tolerance=1.0)
    assert kept.max() + 1 == len(boards)


def test_plane_cut_slivers_join_the_piece_they_touch_most():
    """A plane across a curved shell leaves slivers at its rim: each one smaller than the
    minimum piece joins the touching piece it has the most contact with; a sliver touching
    nothing, and pieces at the minimum size, stay."""
    from partscale.segment import absorb_slivers

    lab = np.zeros((12, 6, 6), np.int32)
    lab[0:5, :, :] = 1  # 180 voxels
    lab[5:10, :, :] = 2  # 180 voxels
    lab[5, 0:2, 0:2] = 3  # 4 voxels, touching 1 (4 faces) and 2 (8 faces)
    lab[11, 0:3, 0:3] = 4  # 9 voxels touching nothing
    out = absorb_slivers(lab.copy(), 4, min_size=8)
    assert (out[lab == 3] == 2).all()
    assert (out[lab == 4] == 4).all()
    assert np.array_equal(out[(lab == 1) | (lab == 2)], lab[(lab == 1) | (lab == 2)])
    assert np.array_equal(absorb_slivers(lab.copy(), 4, min_size=4), lab)


def _poison(entry, how):
    """Damage a cache entry the ways the fault campaign did."""
    import hashlib

    raw = entry.read_bytes()
    if how == "truncated":
        entry.write_bytes(raw[: len(raw) // 2])
    elif how == "bit-flipped":
        b = bytearray(raw)
        b[len(b) // 4] ^= 0x40  # inside the labels' compressed data
        entry.write_bytes(bytes(b))
    else:
        with np.load(entry) as z:
            parts, info, rough = z["parts"], str(z["info"]), str(z["rough"])
        if how == "info-not-facts":
            info = "[1, 2]"
        elif how == "rough-not-facts":
            rough = '{"relief": 0.1}'
        elif how == "all-zero":
            parts = np.zeros_like(parts)
        elif how == "float-parts":
            parts = parts.astype(np.float32)
        # a consistent checksum: only the content checks can catch these
        check = hashlib.sha256(
            np.ascontiguousarray(parts).tobytes() + info.encode() + rough.encode()
        ).hexdigest()
        np.savez_compressed(
            entry, parts=parts, info=np.array(info), rough=np.array(rough), check=np.array(check)
        )


@pytest.mark.parametrize(
    "how",
    ["truncated", "bit-flipped", "info-not-facts", "rough-not-facts", "all-zero", "float-parts"],
)
def test_damaged_cache_entry_is_discarded_and_recomputed(boxes, tmp_path, how):
    fresh = segment(boxes, method="fast", cache_dir=tmp_path)
    entry = tmp_path / f"{fresh.meta['segmentation']['key']}.npz"
    _poison(entry, how)
    with pytest.warns(PartscaleWarning, match="damaged.*discarded, recomputing"):
        again = segment(boxes, method="fast", cache_dir=tmp_path)
    assert np.array_equal(again.parts, fresh.parts)
    assert again.meta["parts_info"] == fresh.meta["parts_info"]
    # and the entry is whole again: the next run reads it without a note
    third = segment(boxes, method="fast", cache_dir=tmp_path)
    assert np.array_equal(third.parts, fresh.parts)


def test_damaged_cache_entry_cli_one_note_and_exit_0(boxes, tmp_path, cli, monkeypatch):
    src = partscale.save(boxes, tmp_path / "b.csdf.npz")
    cache = tmp_path / "cache"
    monkeypatch.setenv("PARTSCALE_CACHE", str(cache))
    cli("segment", src, "-o", tmp_path / "a.csdf.npz", check=True)
    (entry,) = (cache / "segment").glob("*.npz")
    _poison(entry, "truncated")
    proc = cli("segment", src, "-o", tmp_path / "b2.csdf.npz")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 2 and "partscale: note:" in lines[0] and "damaged" in lines[0], lines


def test_cache_is_capped_least_recently_used_first(lshape, boxes, tmp_path, monkeypatch):
    a = segment(boxes, method="fast", cache_dir=tmp_path)
    first = tmp_path / f"{a.meta['segmentation']['key']}.npz"
    os.utime(first, (1, 1))  # long unused
    monkeypatch.setenv("PARTSCALE_CACHE_MAX", str(first.stat().st_size + 1))
    b = segment(lshape, method="fast", cache_dir=tmp_path)
    assert not first.exists()
    assert (tmp_path / f"{b.meta['segmentation']['key']}.npz").is_file()


def test_segment_help_says_where_the_cache_is(cli):
    proc = cli("segment", "--help")
    text = " ".join(proc.stdout.split())
    assert "~/.cache/partscale/segment" in text and "1 GiB" in text


# --- rough surfaces: a completed scan's relief ------------------------------------------------

HN = 0.01  # the rough table's voxel size: 87 x 57 x 64 voxels


def _relief_of(c):
    from partscale.segment import surface_relief

    m = to_mesh(c)
    return surface_relief(m.vertices, m.vertex_normals, c.voxel_size)


def _roughened(c, rms_voxels: float, seed: int = 0):
    """``c`` with scan-like relief: a random field correlated over about a voxel added to its
    distances (the surface moves by it), as the sensor's noise leaves on a completed scan."""
    f = ndimage.gaussian_filter(np.random.default_rng(seed).standard_normal(c.shape), 0.8)
    f *= rms_voxels / f.std()
    return c.replace(sdf=(np.asarray(c.sdf) + f * c.voxel_size).astype(np.float32))


@pytest.fixture(scope="module")
def fine_table():
    return table_grid(HN)


def test_relief_tells_noise_from_shape():
    from partscale.segment.relief import CLEAN_RELIEF

    h = 0.01
    # clean shapes of every kind measure under the clean level: flat faces, a ball, a tube
    # 1.5 voxels in radius, a board one voxel thick (its two faces are apart)
    clean = {
        "box": shapes.box((0, 0, 0), (0.4, 0.3, 0.2), voxel_size=h),
        "ball": shapes.sphere((0, 0, 0), 0.12, voxel_size=h),
        "tube": shapes.grid(
            lambda p: np.maximum(np.hypot(p[:, 0], p[:, 1]) - 0.015, np.abs(p[:, 2]) - 0.2),
            ((-0.02, -0.02, -0.2), (0.02, 0.02, 0.2)),
            voxel_size=h,
        ),
        "board": shapes.box((0, 0, 0), (0.4, 0.3, 0.01), voxel_size=h),
    }
    for name, c in clean.items():
        assert _relief_of(c) <= 0.8 * CLEAN_RELIEF, name
    # the same box with a completed scan's relief (0.8 voxel RMS of displacement)
    assert _relief_of(_roughened(clean["box"], 0.8)) >= 2 * CLEAN_RELIEF


def test_rough_surface_keeps_boards_whole(fine_table):
    clean = segment(fine_table, cache=False)
    entry = clean.meta["history"][-1]
    assert clean.n_parts == 5 and entry["noise_added"] == 0 and entry["specks"] == 0
    rough = _roughened(fine_table, 0.8)
    s = segment(rough, cache=False)
    entry = s.meta["history"][-1]
    assert entry["noise_added"] > 0 and entry["relief"] > 0.2
    assert s.meta["segmentation"]["noise_added"] == entry["noise_added"]
    # taken as smooth, the relief shatters it; measured, the top and the legs stay whole
    shattered = segment(rough, cache=False, noise=0)
    assert shattered.meta["history"][-1]["noise_added"] == 0
    assert shattered.n_parts >= 50
    assert s.n_parts <= 8
    top = inside_labels(s, ((0.1, 0.1, 0.51), (0.7, 0.4, 0.55)))
    assert (top == top[0]).all()
    for x in (0.0, 0.72):
        for y in (0.0, 0.42):
            leg = inside_labels(s, ((x + 0.01, y + 0.01, 0.0), (x + 0.07, y + 0.07, 0.45)))
            assert np.bincount(leg).max() >= 0.7 * len(leg), (x, y)
            assert not np.isin(leg, top[:1]).any()  # no leg is part of the top


def test_rough_surface_note_and_noise_option(cli, tmp_path):
    src = tmp_path / "rough.csdf.npz"
    partscale.save(_roughened(shapes.box((0, 0, 0), (0.4, 0.3, 0.2), voxel_size=HN), 0.8), src)
    out = tmp_path / "parts.csdf.npz"
    proc = cli("segment", str(src), "-o", str(out), "--no-cache")
    assert proc.returncode == 0, proc.stderr
    assert "the surface is rough" in proc.stderr and "--noise 0" in proc.stderr
    proc = cli("segment", str(src), "-o", str(out), "--no-cache", "--noise", "0")
    assert proc.returncode == 0 and "the surface is rough" not in proc.stderr
    assert partscale.load(out).meta["history"][-1]["noise"] == 0
    assert_bad_input(
        cli("segment", str(src), "-o", str(out), "--noise", "lots"), "--noise", "auto", "lots"
    )


def test_junction_merge_joins_the_panel_a_shelf_slice_separated():
    # a side panel and a shelf meeting it (an L): labelled with the panel cut at the shelf's
    # faces and its slice beside the shelf given to the shelf, the two panel pieces touch only
    # that slice; they become one again, with the slice, and the shelf stays apart
    panel, shelf = SIDES[0], SHELVES[0]
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, [panel, shelf]), ((0, 0, 0), (0.6, 1.0, 0.4)), voxel_size=H
    )
    (x0, y0, z0), (x1, y1, z1) = panel
    sy0, sy1 = shelf[0][1], shelf[1][1]
    pieces = [  # the panel below the shelf, above it, and the shelf with the slice beside it
        ((x0, y0, z0), (x1, sy0, z1)),
        ((x0, sy1, z0), (x1, y1, z1)),
        ((x0, sy0, z0), shelf[1]),
    ]
    w = c.index_to_world(np.indices(c.shape).reshape(3, -1).T)
    each = np.stack([shapes.box_sdf(w, lo, hi) for lo, hi in pieces])
    labels = np.where(c.sdf.ravel() < 3 * H, each.argmin(axis=0), -1).reshape(c.shape)
    labels = labels.astype(np.int32)
    x = w[:, 0].reshape(c.shape)
    j = labels_mod._Junctions(c, to_mesh(c), labels, tolerance=1.5)
    assert 1 not in j.nbrs[0] and j.nbrs[2] == {0, 1}  # the pieces touch only the slice's part
    assert j.gap(0, 1) <= j.thickness(2)  # the slice is no thicker than the shelf's part
    out = labels_mod.merge_across_junctions(c, to_mesh(c), labels, tolerance=1.5)
    inside = c.sdf <= 0
    y, z = (w[:, k].reshape(c.shape) for k in (1, 2))
    below, above = np.unique(out[inside & (y < sy0)]), np.unique(out[inside & (y > sy1)])
    beyond = np.unique(out[inside & (x > x1 + H / 2)])  # the shelf past the panel's face
    assert len(below) == len(beyond) == 1 and below.tolist() == above.tolist() != beyond.tolist()
    # the slice's voxels strictly inside the panel (not on its outer faces) went with it
    core = inside & (x > x0) & (x < x1) & (z > z0) & (z < z1) & (y >= sy0) & (y <= sy1)
    assert core.any() and (out[core] == below[0]).all()
