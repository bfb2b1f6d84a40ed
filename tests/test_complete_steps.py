"""partscale.complete's named steps, each on its own: the fusion's (points on the grid, carving,
pieces, distances) on analytic voxel input, and the completion's (symmetries and the frame they
fix, symmetric copies, the grid, the metadata) on a virtual scan of the shipped table, whose
left-right mirror plane is known."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from partscale import data, ingest
from partscale.complete import api, fuse
from partscale.evaluate import virtual_scan

NEVER = lambda p: np.zeros(len(p), bool)  # noqa: E731


def _unit_grid(shape) -> fuse.GridFrame:
    return fuse.GridFrame(np.eye(4), tuple(shape), np.zeros(3), 1.0)


def _points(P, kind=fuse.OBSERVED):
    P = np.asarray(P, float)
    N = np.tile([0.0, 1.0, 0.0], (len(P), 1))
    return P, np.full((len(P), 3), 128, np.uint8), np.full(len(P), kind, np.uint8), N


def test_surface_on_grid_keeps_the_points_inside_and_marks_their_voxels():
    grid = _unit_grid((8, 8, 8))
    P, C, K, N = _points([[1.2, 2.0, 3.0], [7.4, 0, 0], [9.0, 1, 1], [-1.0, 0, 0]])
    K[0] = fuse.MIRRORED
    sp = fuse.surface_on_grid(grid, P, C, K, N)
    # the two outside the grid (x 9 rounds past 7, x -1 below 0) are dropped
    assert len(sp.points) == 2
    assert sp.occ.sum() == 2 and sp.occ[1, 2, 3] and sp.occ[7, 0, 0]
    # only the observed point's voxel is observed
    assert sp.occ_obs.sum() == 1 and sp.occ_obs[7, 0, 0]


def test_carve_drops_free_voxels_but_never_one_that_holds_a_surface_point():
    grid = _unit_grid((10, 10, 10))
    P, C, K, N = _points([[5.0, 5.0, 5.0]])
    sp = fuse.surface_on_grid(grid, P, C, K, N)
    within = np.zeros(grid.shape, bool)
    within[3:8, 3:8, 3:8] = True
    # everything at x >= 5 was seen through; the rest lies behind the point (normal +y: y <= 5)
    solid = fuse.carve(grid, sp, within, lambda p: p[:, 0] >= 5, [], lambda p: p[:, 1] + 10)
    assert solid[5, 5, 5]  # the point's own voxel, though free
    assert not solid[6, 4, 4] and not solid[5, 4, 4]  # free
    assert solid[4, 4, 4] and solid[3, 5, 7]  # not free, not in front of the point
    assert not solid[4, 6, 4]  # in front of the point's surface by a voxel: unknown space
    # a symmetric view's free space carves too, but not next to what was observed
    solid2 = fuse.carve(grid, sp, within, NEVER, [lambda p: p[:, 2] <= 4], lambda p: p[:, 1] + 10)
    assert not solid2[3, 3, 3] and not solid2[4, 4, 4]  # 1.73 voxels from the observed one
    assert solid2[4, 5, 4] and solid2[5, 5, 4]  # within 1.5 voxels of it
    assert solid2[4, 4, 5]  # where the symmetric view saw nothing free


def test_floor_reach_carries_a_leg_cut_at_the_floor_band_down_to_the_floor():
    # a leg's front (x = 5, z = 5) seen from y = 4 up (the scan's points below the cut at 3 were
    # taken for the floor) and a seat's front seen from y = 7 up, at x = 12: heights are y
    grid = _unit_grid((16, 12, 10))
    leg = [[5.0, y, 5.0] for y in np.arange(4.0, 9.0, 0.5)]
    seat = [[12.0, y, 5.0] for y in np.arange(7.0, 9.0, 0.5)]
    P, C, K, N = _points(leg + seat)
    sp = fuse.surface_on_grid(grid, P, C, K, N)
    closed = fuse._edt(~sp.occ) <= 1.5
    reach = fuse.floor_reach(grid, sp, closed, NEVER, lambda p: p[:, 1], 3.0)
    assert reach[5, 0:4, 5].all()  # the leg's voxels down to the floor
    assert reach[4, 0, 5] and reach[5, 0, 6]  # and its closure's, as wide as it is
    assert not reach[12, :7].any()  # the seat ends far above the cut: it floats
    assert not reach[:, 5:].any()  # nothing above the cut's band
    # where a camera saw through the voxels below (x >= 5 free below y = 2), the carry stops
    seen = fuse.floor_reach(
        grid, sp, closed, lambda p: (p[:, 0] >= 5) & (p[:, 1] < 2), lambda p: p[:, 1], 3.0
    )
    assert seen[4, 0:4, 5].all() and seen[5, 2:4, 5].all() and not seen[5:, :2].any()
    # nothing within reach of the cut: nothing carried
    assert not fuse.floor_reach(grid, sp, closed, NEVER, lambda p: p[:, 1] + 10, 3.0).any()


def test_floor_base_carries_a_bins_bottom_down_to_the_floor():
    # a bin (x, z 2-12) whose walls were carried down to the floor by the floor reach, its
    # bottom (solid from y = 3, the cut) above a hollow skirt; a seat at x 14-18 from y = 7;
    # heights are y, the floor at y = 0 (voxel centres at 0, 1, 2, ...)
    grid = _unit_grid((20, 12, 16))
    solid = np.zeros(grid.shape, bool)
    solid[2:13, 3:10, 2:13] = True
    solid[2, 0:3, 2:13] = solid[12, 0:3, 2:13] = True
    solid[2:13, 0:3, 2] = solid[2:13, 0:3, 12] = True
    solid[14:19, 7:9, 2:13] = True
    base = fuse.floor_base(grid, solid, NEVER, lambda p: p[:, 1], 3.0)
    assert (base >= solid).all()  # nothing removed
    assert base[3:12, 0:3, 3:12].all()  # the skirt's inside, down to the floor
    assert not base[14:19, :7].any()  # the seat ends far above the cut: it floats
    # where a camera saw through the voxels below (x >= 8 free below y = 2), the carry stops
    seen = fuse.floor_base(
        grid, solid, lambda p: (p[:, 0] >= 8) & (p[:, 1] < 2), lambda p: p[:, 1], 3.0
    )
    assert seen[3:8, 0:3, 3:12].all() and not seen[8:12, 0:2, 3:12].any()
    # no floor within reach of the bottom: nothing added
    assert (fuse.floor_base(grid, solid, NEVER, lambda p: p[:, 1] + 10, 3.0) == solid).all()


def test_nearest_surface_point_is_exact_near_the_surface_and_on_the_right_side_far_off():
    # two walls of points, x = 2 (normal -x) and x = 37 (normal +x), each a fine sheet: every
    # voxel of the slab between them lies behind its nearest wall, the voxels beyond in front
    grid = _unit_grid((40, 24, 24))
    y, z = np.meshgrid(np.arange(2, 22, 0.25), np.arange(2, 22, 0.25))
    wall = np.stack([np.zeros(y.size), y.ravel(), z.ravel()], axis=1)
    P = np.concatenate([wall + np.array([2.0, 0, 0]), wall + np.array([37.0, 0, 0])])
    N = np.zeros_like(P)
    N[: len(wall), 0], N[len(wall) :, 0] = -1.0, 1.0
    sp = fuse.surface_on_grid(
        grid, P, np.zeros((len(P), 3), np.uint8), np.zeros(len(P), np.uint8), N
    )
    flat = np.arange(int(np.prod(grid.shape)))
    centres = grid.centres(flat)
    nn = fuse.nearest_surface_point(centres, flat, sp, grid.h)
    from scipy.spatial import cKDTree

    d_exact, _ = cKDTree(sp.points).query(centres)
    d = np.linalg.norm(centres - sp.points[nn], axis=1)
    near = d_exact < fuse.NEAREST_EXACT_VOXELS * grid.h - 1e-9
    assert np.allclose(d[near], d_exact[near])  # exact within the radius
    # far off: a point within a voxel's diagonal of the nearest, on the same wall
    assert (d[~near] <= d_exact[~near] + np.sqrt(3) * grid.h + 1e-9).all()
    side = np.einsum("ni,ni->n", centres - sp.points[nn], sp.normals[nn]) <= 0
    inside = (centres[:, 0] >= 2) & (centres[:, 0] <= 37)
    assert (side == inside).all() and (~near & inside).sum() > 1000


def test_drop_pieces_keeps_large_pieces_and_well_observed_small_ones():
    solid = np.zeros((20, 20, 20), bool)
    solid[2:12, 2:12, 2:12] = True  # 1000 voxels
    solid[15, 15, 15] = True  # a speck nobody saw much of
    solid[18, 2:4, 2:4] = True  # 4 voxels, all observed
    obs = np.zeros_like(solid)
    obs[18, 2:4, 2:4] = True
    obs[2, 2:4, 2] = True
    kept = fuse.drop_pieces(solid, obs)
    assert kept[5, 5, 5] and kept[18, 2, 2]
    assert not kept[15, 15, 15]
    one = np.zeros_like(solid)
    one[1:3, 1:3, 1:3] = True
    assert fuse.drop_pieces(one, obs) is one  # a single piece is left as it is


def test_drop_pieces_keeps_a_small_piece_seen_well_beside_a_large_one():
    # a railing's baluster seen in part beside its well-seen rail: under 2 % of the rail's
    # voxels and 5 % of its observed ones, but observed on PIECE_OBSERVED_VOXELS voxels, it stays
    solid = np.zeros((80, 80, 80), bool)
    obs = np.zeros_like(solid)
    solid[2:78, 2:78, 2:40] = True  # the large piece, its whole surface observed
    obs[2:78, 2:78, 2] = obs[2:78, 2:78, 39] = True
    n = fuse.PIECE_OBSERVED_VOXELS
    solid[60, 60, 50 : 50 + n] = obs[60, 60, 50 : 50 + n] = True  # a rod, each voxel seen
    solid[70, 70, 50 : 50 + n - 1] = obs[70, 70, 50 : 50 + n - 1] = True  # one voxel fewer
    kept = fuse.drop_pieces(solid, obs)
    assert kept[60, 60, 50] and not kept[70, 70, 50]


def test_edt_is_the_exact_distance_to_the_nearest_false_voxel():
    # a random mask, and a strided view of one (the bytes handed on as uint8 must be its own)
    rng = np.random.default_rng(3)
    big = rng.random((31, 26, 40)) < 0.97
    for mask in (big, big[::2, :, 1::3]):
        d = fuse._edt(mask)
        assert d.dtype == np.float32 and d.shape == mask.shape
        np.testing.assert_allclose(d, ndimage.distance_transform_edt(mask), atol=1e-5)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_points_mapped_in_blocks_are_the_whole_product_bit_for_bit(dtype):
    # across several blocks and a short last one: each row's product is the one a single
    # product of all rows gives, so mapping in blocks changes no completion
    from partscale.complete.carve import ROWS, affine_rows

    rng = np.random.default_rng(7)
    P = rng.normal(size=(2 * ROWS + 123, 3)).astype(dtype)
    a = 0.4
    A = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]) * 1.7
    b = np.array([0.3, -1.2, 2.5])
    got = affine_rows(P, A, b)
    assert got.dtype == dtype and got.shape == P.shape
    np.testing.assert_array_equal(got, P @ A.T.astype(dtype) + b.astype(dtype))


def test_grid_centres_of_every_voxel_are_those_of_their_flat_indices():
    grid = fuse.GridFrame(np.eye(4), (5, 7, 4), np.array([-0.3, 0.1, 2.0]), 0.013)
    np.testing.assert_array_equal(grid.all_centres(), grid.centres(np.arange(5 * 7 * 4)))


def test_distances_of_a_voxel_box_are_its_voxel_distances():
    solid = np.zeros((20, 20, 20), bool)
    solid[5:15, 5:15, 5:15] = True
    h = 0.01
    sdf = fuse.distances(solid, h)
    assert sdf.dtype == np.float32
    # outside: k voxels from the face, (k - 0.5) voxels; inside: drawn in by BACK_SHIFT
    for k in (1, 2, 4):
        assert sdf[14 + k, 10, 10] == pytest.approx((k - 0.5) * h, abs=1e-6)
        assert sdf[15 - k, 10, 10] == pytest.approx(-(k - 0.5 - fuse.BACK_SHIFT) * h, abs=1e-6)


@pytest.fixture(scope="module")
def table_observation():
    return api.observe(virtual_scan(ingest.load_mesh(data.table()), 1))


def test_find_symmetries_turns_the_table_so_its_mirror_plane_is_x0(table_observation):
    ob = table_observation
    sy = api.find_symmetries(ob, 48, True)
    assert sy.syms, "expected the table's left-right mirror plane"
    m = sy.syms[0]
    # in the turned upright frame the plane is x = 0: the mirror negates x and nothing else
    assert np.allclose(m.A, np.diag([-1.0, 1.0, 1.0]), atol=1e-9)
    assert np.abs(m.b).max() <= 1e-9
    assert np.allclose(sy.Uinv @ sy.U, np.eye(4), atol=1e-12)
    # up is the floor's normal (the floor was seen)
    assert ob.floor is not None and sy.up_from == "floor"
    assert np.allclose(sy.U[1, :3], ob.floor[0].normal, atol=1e-9)
    # without symmetry: no planes, no turn, the observation's own frame
    plain = api.find_symmetries(ob, 48, False)
    assert not plain.syms and plain.rot is None and np.array_equal(plain.U, ob.U)


def test_symmetric_copies_are_the_observed_points_mirrored_where_the_plane_holds(
    table_observation,
):
    ob = table_observation
    sy = api.find_symmetries(ob, 48, True)
    s = api.symmetric_copies(ob, sy)
    obs = s.kind == fuse.OBSERVED
    assert obs.sum() == len(ob.points)  # the observed points are all kept
    mir = s.points[~obs]
    assert len(mir) > 0.2 * len(ob.points)
    # the first plane's copies (all but those dropped in free space) are observed points with x
    # negated (the plane is x = 0); the rest are the turning base's and the other plane's
    from scipy.spatial import cKDTree

    d, _ = cKDTree(s.points[obs] * [-1, 1, 1]).query(mir)
    first = int(sy.syms[0].where(s.points[obs]).sum())
    assert (d <= 1e-9).sum() >= first - s.n_dropped
    n_rot = 0 if sy.rot is None else sy.rot.fold - 1
    n_mirror = len(sy.syms) + (len(sy.syms) == 2)
    assert len(s.views) == n_mirror + n_rot


def test_plan_grid_puts_res_voxels_along_the_longest_side(table_observation):
    ob = table_observation
    sy = api.find_symmetries(ob, 48, False)
    s = api.symmetric_copies(ob, sy)
    for upright in (False, True):
        opts = api.Settings(res=40, box=None, upright=upright, closure=1.5, source="t")
        g = api.plan_grid(s, sy, opts)
        ext = g.hi - g.lo
        assert g.frame.h == pytest.approx(float(ext.max()) / 40, rel=1e-12)
        # every surface point lies inside the grid, at least the band's width from its faces
        ijk = (g.points - g.frame.origin) / g.frame.h
        assert ijk.min() >= 2 and (np.asarray(g.frame.shape) - 1 - ijk).min() >= 2
        frame = "upright" if upright else "input"
        # upright: laid along the walls (no mirror plane searched for here)
        turned = sy.Uinv @ api.lengthwise(s.points, s.normals, sy.syms)
        assert np.allclose(g.frame.grid_to_world, turned if upright else np.eye(4)), frame
        R = g.frame.grid_to_world[:3, :3]
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-9)


def test_complete_reports_its_steps_by_name_and_its_shares_sum_to_one(table_observation):
    said: list[str] = []
    frames = virtual_scan(ingest.load_mesh(data.table()), 1)
    c = api.complete(frames, res=32, symmetry=False, progress=lambda f, m: said.append(m))
    steps = ["symmetries", "symmetric copies", "grid", "carving and closing", "guessed parts"]
    assert [m for m in said if m in steps][: len(steps)] == steps
    assert said[0] == "reading the scan" and said[-1] == "done"
    done = c.meta["completion"]
    assert done["observed"] + done["mirrored"] + done["guessed"] == pytest.approx(1.0, abs=2e-4)


def test_a_chair_standing_on_the_floor_is_completed_down_to_it():
    # the scan's points within 3 cm of the floor are taken for the floor, the legs' feet with
    # them: the completed legs reach the floor (they ended 2 cm, 3 voxels, above it), and not
    # below it
    from conftest import data_path

    mesh = ingest.load_mesh(data_path("kenney/chair.glb"))
    floor = float(np.asarray(mesh.vertices)[:, 1].min())
    c = api.complete(virtual_scan(mesh, 1), res=128)
    from partscale.evaluate import surface_samples

    lowest = surface_samples(c, 20000)[0][:, 1].min() - floor
    assert -c.voxel_size <= lowest <= 0.5 * c.voxel_size, (lowest, c.voxel_size)


def test_upsample_reads_between_pixels_on_a_surface_never_across_an_edge():
    from partscale.complete.scan import Frame, upsample

    # left half a wall 1 m away, right half one 2 m away, seen by a 8 x 8 camera
    depth = np.where(np.arange(8)[None, :] < 4, 1.0, 2.0).repeat(8, axis=0).astype(np.float32)
    depth[2:5, 0:3] = 0  # a hole three pixels wide
    K = np.array([[10.0, 0, 3.5], [0, 10.0, 3.5], [0, 0, 1]])
    f = Frame(depth, None, K, np.eye(4))
    up = upsample(f, 3)
    assert up.shape == (24, 24)
    d = up.depth[up.depth > 0]
    assert set(np.unique(d).tolist()) == {1.0, 2.0}  # nothing hung between the walls
    assert (up.depth[9:12, 3:6] == 0).all()  # its middle stays a hole
    assert (up.depth[3:6, 3:6] > 0).all()  # the pixel above it blends across its rim
    # the same rays: every reading is still read, and nothing lands beyond its wall's readings
    # by more than a fine pixel (the image's border)
    P, _, _ = f.points()
    Q, _, _ = up.points()
    assert np.isclose(np.linalg.norm(P[:, None] - Q[None], axis=2).min(axis=1), 0).all()
    for z in (1.0, 2.0):
        a, b = P[P[:, 2] == z], Q[Q[:, 2] == z]
        assert (b[:, :2].min(0) >= a[:, :2].min(0) - z / 10 / 3 - 1e-9).all()
        assert (b[:, :2].max(0) <= a[:, :2].max(0) + z / 10 / 3 + 1e-9).all()
    assert len(Q) >= 7 * len(P)


def test_a_sparse_far_scan_is_upsampled_and_keeps_what_it_saw():
    # a chair 0.95 m tall seen from 3 m by a 320 x 240 sensor: its pixels are over a voxel of a
    # 128 grid across it, so readings closed into specks of their own (dropped, or joined by
    # struts); upsampled, the chair closes whole
    import dataclasses

    from conftest import data_path

    from partscale.complete import complete
    from partscale.evaluate import completion

    mesh = ingest.load_mesh(data_path("kenney/chair.glb"))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)
    frames = virtual_scan(mesh, azimuths=(307.0,), elevation=15.0, floor=False, distance=1.5)
    c = complete(frames, res=128)
    done = c.meta["completion"]
    assert done["upsampled"] and done["upsampled"][0] >= 2
    assert done["guard"]["evidence"]["on_surface"] >= 0.95 and not done["struts"]
    gt = ingest.from_mesh(mesh, res=128)
    tau = completion.f_tau(gt)
    G, _ = completion.surface_samples(gt, tau=tau)
    raw = completion.chamfer_fscore(api.observe(frames).points, G, tau)["fscore"]
    P, _ = completion.surface_samples(c, tau=tau)
    assert completion.chamfer_fscore(P, G, tau)["fscore"] >= raw - 0.01


def test_a_board_thinner_than_a_voxel_seen_from_both_sides_keeps_its_solid():
    # a board 0.8 voxel thick, its two faces read (normals out of each face), no free space:
    # each voxel it holds lies ahead of one face, and made outside on that account the board
    # vanished (three views of a bookcase lost a third of its boards)
    grid = _unit_grid((20, 20, 12))
    x, y = np.meshgrid(np.arange(3, 17, 0.25), np.arange(3, 17, 0.25))
    face = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    P = np.concatenate([face + np.array([0, 0, 5.1]), face + np.array([0, 0, 5.9])])
    N = np.zeros_like(P)
    N[: len(face), 2], N[len(face) :, 2] = -1.0, 1.0
    C = np.full((len(P), 3), 128, np.uint8)
    K = np.full(len(P), fuse.OBSERVED, np.uint8)
    sdf, _, _ = fuse.fuse(
        np.eye(4), grid.shape, np.zeros(3), 1.0, P, C, K, N, NEVER, [], lambda p: p[:, 1] + 10, 1.5
    )
    inside = sdf[5:15, 5:15, :] < 0
    assert inside.any(axis=2).all()  # solid across the whole board
    assert not (sdf[5:15, 5:15, :4] < 0).any() and not (sdf[5:15, 5:15, 8:] < 0).any()


@pytest.fixture(scope="module")
def sofa_frame():
    """One range frame of a 3 m sofa from 30 degrees, 20 above, at 1.5 times the framing
    distance (its points about 1.3 voxels apart at --res 128)."""
    from conftest import data_path

    mesh = ingest.load_mesh(data_path("polyhaven/sofa_03/sofa_03_1k.gltf"))
    (f,) = virtual_scan(mesh, azimuths=(30.0,), elevation=20.0, floor=False, distance=1.5)
    return f


def _tunnels(c) -> int:
    """Tunnels through the completion's surface (its genus, summed over its pieces)."""
    from partscale.surface import to_mesh

    parts = to_mesh(c).split(only_watertight=False)
    return sum((2 - p.euler_number) // 2 for p in parts)


def test_a_sparse_point_cloud_closes_without_a_lace_of_tunnels(sofa_frame, tmp_path):
    # the frame as a point cloud in its camera's frame (what a user's scanner writes): about
    # half the pixels of the frame made from it hold a point, its points lie 1.4 voxels apart
    # at --res 128, and its closure was a lace of 135 tunnels; upsampled (readings blended
    # across the empty pixels), under 80
    import trimesh

    from partscale.complete import complete_file

    P, C, _ = sofa_frame.points()
    cam = (P - sofa_frame.pose[:3, 3]) @ sofa_frame.pose[:3, :3]
    trimesh.PointCloud(cam, colors=C).export(tmp_path / "sofa.ply")
    c = complete_file(tmp_path / "sofa.ply", res=128)
    assert c.meta["completion"]["upsampled"] == [2]
    assert _tunnels(c) < 80


def test_on_a_fine_grid_the_closure_reaches_as_far_as_the_points_lie_apart(sofa_frame):
    # at --res 256 the frame's points lie about 2.5 voxels apart (upsampled three times for
    # the surface), and a closure of 1.5 voxels behind them closed into a lace of 202 tunnels:
    # it reaches 1.5 point spacings instead (3.8 voxels, recorded), and the surface has 78
    from partscale.complete import complete

    c = complete([sofa_frame], res=256)
    assert c.meta["history"][-1]["closure_voxels"] >= 3.0
    assert _tunnels(c) < 120


def test_drop_pieces_takes_a_rod_touching_along_edges_for_one_piece():
    # a rod a voxel thick across the grid's axes touches itself only along edges: as pieces of
    # one voxel each it would be dropped, voxel by voxel; as one piece it is observed on
    # PIECE_OBSERVED_VOXELS voxels and stays
    solid = np.zeros((80, 80, 80), bool)
    obs = np.zeros_like(solid)
    solid[2:78, 2:78, 2:40] = True
    obs[2:78, 2:78, 2] = obs[2:78, 2:78, 39] = True
    n = fuse.PIECE_OBSERVED_VOXELS
    k = np.arange(n)
    solid[10 + k, 10 + k, 60] = obs[10 + k, 10 + k, 60] = True
    kept = fuse.drop_pieces(solid, obs)
    assert kept[10 + k, 10 + k, 60].all()


def test_the_benchmarks_truth_is_the_exterior_a_sensor_can_see():
    # Sweet Home's kitchen cabinet is modelled with its carcass's inside behind shut doors, a
    # sealed cavity no view reaches (a third of its surface); its open bookcase has none
    from conftest import data_path

    from partscale import ingest
    from partscale.evaluate import exterior, surface_samples
    from partscale.surface import sample_linear

    cabinet = ingest.from_mesh(
        ingest.load_mesh(data_path("sweethome3d/kitchenCabinet.obj")), res=128
    )
    outside = exterior(cabinet)
    G = surface_samples(cabinet, 20000)[0]
    E = surface_samples(outside, 20000)[0]
    v = cabinet.voxel_size
    # the exterior is the cabinet's own surface, less its inside
    on = sample_linear(cabinet.sdf, cabinet.world_to_index(E))
    assert np.abs(on).max() <= 0.25 * v  # marching cubes against trilinear, within a cell
    inside = sample_linear(outside.sdf, outside.world_to_index(G)) < -0.1 * v
    assert inside.mean() >= 0.25  # the carcass's inside: 32 % of the samples
    bookcase = ingest.from_mesh(ingest.load_mesh(data_path("sweethome3d/bookcase.obj")), res=128)
    assert exterior(bookcase) is bookcase


def test_a_closed_cabinet_from_three_views_is_completed_solid_down_to_the_floor():
    # a closed box 0.9 m wide, 0.8 tall, 0.6 deep: 128 voxels between its sides, beyond the
    # slabs' reach; filled between them, it came out a hollow shell a voxel or two thick (the
    # shell had fewer boundary voxels than the box filled), and filled, 3 cm off the floor
    import trimesh

    from partscale.complete import complete
    from partscale.ingest import from_trimesh

    b = trimesh.creation.box(extents=[0.9, 0.8, 0.6])
    b.apply_translation([0, 0.4, 0])
    box = from_trimesh(b, color=(200, 180, 150))
    c = complete(virtual_scan(box, 3), res=128, upright=True)
    solid = c.sdf < 0
    ys = c.origin[1] + np.arange(c.shape[1]) * c.voxel_size
    centre = solid[c.shape[0] // 2, :, c.shape[2] // 2]
    assert centre[(ys > 0.02) & (ys < 0.78)].all()  # solid through its middle
    assert ys[np.flatnonzero(centre)].min() <= 0.5 * c.voxel_size  # down to the floor


@pytest.mark.parametrize(("azimuth", "elevation"), [(30.0, 15.0), (120.0, 0.0)])
def test_a_closed_cabinet_from_one_view_is_completed_solid_not_an_open_shell(azimuth, elevation):
    # the same box from one camera that sees its front and one side: the fill between its
    # sides (one seen, one mirrored) is a body with a ragged back and tunnels where the sensor's
    # holes lie on both sides; weighed by its faces alone it lost to the thin shell, and the
    # completion was a box open at the back
    import trimesh

    from partscale.complete import complete
    from partscale.ingest import from_trimesh

    b = trimesh.creation.box(extents=[0.9, 0.8, 0.6])
    b.apply_translation([0, 0.4, 0])
    box = from_trimesh(b, color=(200, 180, 150))
    scan = virtual_scan(box, azimuths=(azimuth,), elevation=elevation)
    c = complete(scan, res=128, upright=True)
    solid = c.sdf < 0
    volume = solid.sum() * c.voxel_size**3
    assert volume >= 0.8 * (0.9 * 0.8 * 0.6)  # an open shell: 5 % of it
    assert volume <= 1.15 * (0.9 * 0.8 * 0.6)


def test_fill_regions_keeps_a_body_and_drops_sheets_that_leave_voids():
    # a U-shaped thin shell (front and two sides, open at the back); a body filling it with a
    # ragged back (more faces than the open shell) is kept, unless the camera saw the space
    # behind it (a compartment it looked into); sheets one voxel thick across it, 6 voxels
    # apart, each a pair of surfaces inside the object, are not
    shell = np.zeros((40, 40, 40), bool)
    shell[4:36, 4:36, 34:36] = True  # front
    shell[4:6, 4:36, 4:36] = shell[34:36, 4:36, 4:36] = True  # sides
    body = np.zeros_like(shell)
    body[6:34, 4:36, 4:34] = True
    rng = np.random.default_rng(0)
    for i in range(6, 34):
        for j in range(4, 36):
            body[i, j, 4 : 4 + rng.integers(0, 4)] = False  # a ragged back
    assert fuse._faces(shell | body) > fuse._faces(shell)
    unseen = np.zeros_like(shell)
    assert fuse._fill_regions(shell, body, unseen).sum() == body.sum()
    seen_behind = unseen.copy()
    seen_behind[:, :, :4] = True
    assert not fuse._fill_regions(shell, body, seen_behind).any()
    sheets = np.zeros_like(shell)
    sheets[6:34, 4:36, 8:34:6] = True
    assert not fuse._fill_regions(shell, sheets, unseen).any()


def test_close_tunnels_closes_small_unseen_holes_through_the_fill_only():
    # a block with three holes through it along x: a tunnel 5 voxels across (closed), the same
    # where the camera saw through it (stays), and a window 20 voxels across (stays)
    fill = np.zeros((30, 60, 40), bool)
    fill[5:25, 5:55, 5:35] = True
    g = np.indices(fill.shape[1:])
    tunnel = (g[0] - 15) ** 2 + (g[1] - 12) ** 2 <= 2.5**2
    seen_tunnel = (g[0] - 40) ** 2 + (g[1] - 12) ** 2 <= 2.5**2
    window = (np.abs(g[0] - 30) < 10) & (np.abs(g[1] - 26) < 6)
    for hole in (tunnel, seen_tunnel, window):
        fill[5:25][:, hole] = False
    free = np.zeros_like(fill)
    free[:, seen_tunnel] = True
    out = fuse._close_tunnels(fill, free)
    assert out[5:25][:, tunnel].all()
    assert not out[:, seen_tunnel].any()
    assert not out[5:25][:, window].any()
    assert (out >= fill).all()
    assert not fuse._close_tunnels(np.zeros_like(fill), free).any()  # no fill: none


def _surface_of(solid: np.ndarray) -> fuse.SurfacePoints:
    """Surface points at the centres of ``solid``'s boundary voxels (unit grid), each facing
    the way of its first empty face neighbour."""
    P, N = [], []
    for ax in range(3):
        for side in (1, -1):
            open_side = ~np.roll(np.pad(solid, 1), -side, axis=ax)[1:-1, 1:-1, 1:-1]
            ijk = np.argwhere(solid & open_side)
            P.append(ijk.astype(float))
            n = np.zeros((len(ijk), 3))
            n[:, ax] = side
            N.append(n)
    P, N = np.concatenate(P), np.concatenate(N)
    _, C, K, _ = _points(P)
    return fuse.surface_on_grid(_unit_grid(solid.shape), P, C, K, N)


@pytest.mark.parametrize("fine", [False, True], ids=["on threads", "a fine grid, in turn"])
def test_close_holes_shuts_unseen_holes_through_a_sheet_only(fine, monkeypatch):
    # a board two voxels thick with three holes through it along z: one 6 voxels across that
    # no camera saw through (a sensor's blotch: closed), the same where the camera saw through
    # (a gap between slats: stays), and a window 20 voxels across (stays); a tube along z, its
    # inside unseen (a bin seen from the side): a hole in each of its slices, running on through
    # all of them (stays); a gap 2 voxels wide and 16 long between two boards, closed at its
    # ends (between a sofa's seat and its back): a hole in the slices across the boards, whose
    # faces around it turn along the slice, not across it (stays)
    solid = np.zeros((60, 80, 40), bool)
    solid[5:55, 5:35, 5:7] = True
    g = np.indices(solid.shape[:2])
    blotch = (g[0] - 15) ** 2 + (g[1] - 12) ** 2 <= 3**2
    gap = (g[0] - 40) ** 2 + (g[1] - 12) ** 2 <= 3**2
    window = (np.abs(g[0] - 30) < 10) & (np.abs(g[1] - 26) < 6)
    for hole in (blotch, gap, window):
        solid[hole, 5:7] = False
    ring = (np.abs(g[0] - 30) <= 4) & (np.abs(g[1] - 60) <= 4)
    ring &= ~((np.abs(g[0] - 30) <= 2) & (np.abs(g[1] - 60) <= 2))
    solid[ring, 15:35] = True
    boards = np.zeros_like(solid)
    boards[10:30, 45:49, 20:24] = True
    boards[12:28, 47:49, 21:23] = False  # the gap: 16 long (x), 2 wide (z), 2 deep (y)
    solid |= boards
    seen = np.zeros_like(solid)
    seen[gap] = True

    def free(P):
        i = np.rint(P).astype(int)
        return seen[i[:, 0], i[:, 1], i[:, 2]]

    if fine:
        # a grid above THREAD_VOXELS: the axes' labellings one after another (each holds
        # arrays of the whole grid), with the same result
        def no_threads(fn, items):
            raise AssertionError("threads on a fine grid")

        monkeypatch.setattr(fuse, "THREAD_VOXELS", 0)
        monkeypatch.setattr(fuse, "thread_map", no_threads)
    grid = _unit_grid(solid.shape)
    out = fuse.close_holes(solid, grid, _surface_of(solid), free)
    assert out[blotch, 5:7].all()
    assert not out[gap, 5:7].any()
    assert not out[window, 5:7].any()
    assert (out >= solid).all()
    assert (out ^ solid).sum() == 2 * blotch.sum()  # nothing else: not the tube, not the gap
    empty = np.zeros_like(solid)
    assert not fuse.close_holes(empty, grid, _surface_of(solid), free).any()


def _rim(solid: np.ndarray, x0: int, x1: int, z0: int, z1: int, y0: int, y1: int) -> None:
    """A level rectangle's rim one voxel thick set in ``solid`` (y up): x0..x1, z0..z1 around,
    y0..y1 tall."""
    solid[x0:x1, y0:y1, z0:z1] = True
    solid[x0 + 1 : x1 - 1, y0:y1, z0 + 1 : z1 - 1] = False


def test_close_lids_fills_a_thin_plate_at_the_top_of_a_low_rim_only():
    # y is up. A table top seen from its own height: its edge a rim 3 voxels tall, with a gap
    # in each slice where the sensor missed it (whole over the three): a plate 2 voxels thick
    # at the rim's top fills it, not the rim's height. A rim as tall, where a camera saw
    # through the middle: stays open. A bin's wall, 20 voxels tall: stays open. A shelf's
    # front edge between two sides and a back that run on above it: its plate at the edge's
    # top, not above
    up = lambda P: np.asarray(P)[:, 1]  # noqa: E731
    solid = np.zeros((120, 40, 60), bool)
    _rim(solid, 5, 35, 5, 35, 20, 23)  # the table's top
    for y, x in ((20, 10), (21, 20), (22, 30)):
        solid[x, y, 5] = False  # one voxel missing from its front edge, a different one a slice
    _rim(solid, 40, 70, 5, 35, 20, 23)  # seen through
    _rim(solid, 75, 95, 5, 25, 5, 25)  # the bin
    solid[100:118, 5:35, 40] = solid[100:118, 5:35, 58] = True  # the shelf's sides
    solid[100, 5:35, 40:59] = True  # its back
    solid[117, 14:16, 40:59] = True  # its front edge, 2 voxels tall

    seen = np.zeros_like(solid)
    seen[50:60, :, 15:25] = True

    def free(P):
        i = np.rint(P).astype(int)
        return seen[i[:, 0], i[:, 1], i[:, 2]]

    out = fuse.close_lids(solid, _unit_grid(solid.shape), up, free)
    assert (out >= solid).all()
    assert out[6:34, 21:23, 6:34].all()  # the table's plate: the rim's top two slices
    assert not out[6:34, 20, 6:34].any()
    assert not (out ^ solid)[40:100].any()  # seen through; the bin
    assert out[101:117, 14:16, 41:58].all()  # the shelf, at its edge's height
    assert not (out ^ solid)[100:118, 16:].any()
    extra = (out ^ solid).sum()
    assert extra == 28 * 2 * 28 + 16 * 2 * 17  # nothing else (the rim's gaps stay notches)
    assert not fuse.close_lids(np.zeros_like(solid), _unit_grid(solid.shape), up, free).any()


def test_close_lids_takes_a_thick_plate_s_edge_by_its_size():
    # y is up. A coffee table's top, a solid plate, seen from below its top at three sides: its
    # edge a rim 12 voxels tall round 68 x 50 voxels no camera saw: a plate (a rim up to a
    # quarter of its narrower width tall is a plate's edge, more than the 6 slices of a table's
    # top and apron). The same rim round 18 x 18 voxels (a bin, a box open at its top): stays
    # open
    up = lambda P: np.asarray(P)[:, 1]  # noqa: E731
    solid = np.zeros((110, 30, 60), bool)
    _rim(solid, 5, 75, 5, 57, 10, 22)  # the coffee table's top
    _rim(solid, 85, 105, 5, 25, 10, 22)  # the box
    out = fuse.close_lids(solid, _unit_grid(solid.shape), up, lambda P: np.zeros(len(P), bool))
    assert out[6:74, 20:22, 6:56].all()  # the plate: the rim's top two slices
    assert not out[6:74, :20, 6:56].any()
    assert not (out ^ solid)[80:].any()  # the box
    assert (out ^ solid).sum() == 68 * 2 * 50


def test_close_lids_makes_an_object_s_top_as_thick_as_a_top_where_nothing_saw_under_it():
    # y is up, 5 mm voxels. A table 40 slices tall on four legs: its top's edge a rim 3 slices
    # tall (36-38) at the top of the object, a shelf's frame 3 slices tall (10-12) lower down.
    # The top is LID_TOP (30 mm, 6 slices: 33-38) thick where no camera saw under its edge,
    # and as thick as its edge (36-38) along its front, where one saw up to the edge; the
    # shelf as thick as its frame's face (3 slices, seen to end: fuse._edge_faces), more than
    # LID_THICK (2)
    h = 0.005
    up = lambda P: np.asarray(P)[:, 1]  # noqa: E731
    solid = np.zeros((50, 45, 40), bool)
    _rim(solid, 5, 45, 5, 35, 36, 39)  # the top's edge
    _rim(solid, 5, 45, 5, 35, 10, 13)  # the shelf's frame
    for x, z in ((5, 5), (43, 5), (5, 33), (43, 33)):
        solid[x : x + 2, 0:39, z : z + 2] = True  # the legs
    seen = np.zeros_like(solid)
    seen[:, 20:36, 6:10] = True  # a camera looked under the top's front edge

    def free(P):
        i = np.rint(np.asarray(P) / h).astype(int)
        return seen[i[:, 0], i[:, 1], i[:, 2]]

    grid = fuse.GridFrame(np.eye(4), solid.shape, np.zeros(3), h)
    out = fuse.close_lids(solid, grid, up, free)
    assert fuse.LID_TOP / h == pytest.approx(6)
    assert out[7:43, 33:39, 10:34].all()  # the top, 6 slices, where nothing saw under it
    assert out[7:43, 36:39, 6:10].all()  # along its front: its edge's 3 slices
    assert not out[7:43, 33:36, 6:10].any()
    assert not (out ^ solid)[:, 13:33].any()  # nothing between them
    assert out[6:44, 10:13, 6:34].all()  # the shelf: its frame's three slices
    assert not (out ^ solid)[:, :10].any()
    assert (out >= solid).all()


def _bookcase() -> np.ndarray:
    """y up, unit voxels: two side panels 58 slices tall, shelves 2 slices thick every 10 from
    slice 5, whole at 5, 15 and 25 (seen from above), only their front edges (a strip one
    voxel deep along z = 5) at 35 and 45 (seen end on); nothing at 55."""
    solid = np.zeros((30, 60, 20), bool)
    solid[2:4, 0:58, 5:15] = solid[26:28, 0:58, 5:15] = True  # the sides
    for y in (5, 15, 25):
        solid[2:28, y : y + 2, 5:15] = True
    for y in (35, 45):
        solid[4:26, y : y + 2, 5:6] = True
    return solid


def test_repeat_plates_carries_a_bookcase_s_shelves_on_where_their_edges_are_seen():
    # the shelves at 35 and 45 are carried on at the spacing, as thick and as deep as the
    # whole ones; at 55 the sides run on but no edge was seen: no shelf
    solid = _bookcase()
    up = lambda P: np.asarray(P)[:, 1]  # noqa: E731
    never = lambda P: np.zeros(len(P), bool)  # noqa: E731
    out = fuse.repeat_plates(solid, _unit_grid(solid.shape), _surface_of(solid), up, never)
    assert out[2:28, 35:37, 5:15].all()
    assert out[2:28, 45:47, 5:15].all()
    assert not (out ^ solid)[:, :35].any()
    assert not (out ^ solid)[:, 37:45].any()
    assert not (out ^ solid)[:, 47:].any()


def test_repeat_plates_carries_no_shelf_a_camera_saw_through_nor_a_stair_s_treads():
    solid = _bookcase()
    up = lambda P: np.asarray(P)[:, 1]  # noqa: E731
    # a camera saw through where the shelf at 45 would be: only the one at 35 is carried on
    seen = lambda P: np.abs(np.asarray(P)[:, 1] - 45.5) < 1.5  # noqa: E731
    out = fuse.repeat_plates(solid, _unit_grid(solid.shape), _surface_of(solid), up, seen)
    assert out[2:28, 35:37, 5:15].all()
    assert not (out ^ solid)[:, 40:].any()
    # a stair's treads, each 8 voxels on from the one below, overlap too little to repeat
    stair = np.zeros((40, 40, 10), bool)
    for k in range(4):
        stair[8 * k : 8 * k + 10, 5 + 8 * k : 7 + 8 * k, :] = True
    never = lambda P: np.zeros(len(P), bool)  # noqa: E731
    out = fuse.repeat_plates(stair, _unit_grid(stair.shape), _surface_of(stair), up, never)
    assert (out == stair).all()


def test_a_cabinet_seen_from_above_its_front_has_no_holes_where_the_sensor_had_none():
    # Kenney's bedside cabinet in one frame from 30 degrees above, 20 degrees off its front:
    # its front and top, closed thinly behind the readings, had about 75 holes through them
    # where the sensor's frame has pixels without a reading (which carve nothing)
    import dataclasses

    from conftest import data_path

    from partscale.complete import complete

    mesh = ingest.load_mesh(data_path("kenney/cabinetBedDrawer.glb"))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)  # Kenney units
    c = complete(virtual_scan(mesh, azimuths=(200.0,), elevation=30.0), res=128, upright=True)
    assert _tunnels(c) <= 10  # 3 as made today


def test_a_completions_memory_grows_per_voxel_within_what_its_check_counts():
    # the check before any work refuses what would not fit: the working set (numpy's arrays on
    # every thread, traced) grows with the grid by no more than it counts a voxel, the colours
    # filled on a thread beside the guessed parts included (the scan's own arrays come on top)
    import dataclasses
    import math
    import tracemalloc

    from conftest import data_path

    from partscale.complete import complete

    # a closed cabinet seen from above its front: filled, its struts searched (Kenney's, at
    # its real size)
    mesh = ingest.load_mesh(data_path("kenney/kitchenCabinetDrawer.glb"))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)
    frames = virtual_scan(mesh, azimuths=(345.0,), elevation=45.0)
    complete(frames, res=32, symmetry=False)  # the kernels compiled, the pool started
    peaks, sizes = [], []
    for res in (100, 170):
        tracemalloc.start()
        try:
            before = tracemalloc.get_traced_memory()[0]
            c = complete(frames, res=res, upright=True)
            peaks.append(tracemalloc.get_traced_memory()[1] - before)
        finally:
            tracemalloc.stop()
        sizes.append(math.prod(c.shape))
    assert sizes[1] <= fuse.THREAD_VOXELS  # the steps ran on threads at once
    assert sizes[1] >= 3 * sizes[0]
    per_voxel = (peaks[1] - peaks[0]) / (sizes[1] - sizes[0])
    assert per_voxel <= fuse.peak_bytes(sizes[1]) / sizes[1], per_voxel
