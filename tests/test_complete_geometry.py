"""partscale.complete: mirror planes of a one-sided scan, and the solid between opposite surfaces."""

from __future__ import annotations

import numpy as np
import pytest


def _box_faces(lo, hi, faces, n_per_face, rng):
    """Points (N, 3) and outward normals on the given faces ('+x', '+y', '+z') of a box."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    P, N = [], []
    for f in faces:
        a = "xyz".index(f[1])
        u = rng.uniform(lo, hi, (n_per_face, 3))
        u[:, a] = hi[a] if f[0] == "+" else lo[a]
        n = np.zeros(3)
        n[a] = 1.0 if f[0] == "+" else -1.0
        P.append(u)
        N.append(np.broadcast_to(n, u.shape))
    return np.concatenate(P), np.concatenate(N)


def test_mirror_plane_of_a_one_sided_scan_maps_points_within_a_quarter_cell():
    # a table seen from the front right (+x, +y, +z faces): four legs and a top, symmetric
    # about the vertical plane x = c; the right side of each leg has no counterpart in the scan
    from partscale.complete import symmetry

    rng = np.random.default_rng(0)
    c, cell = 0.0137, 0.012
    parts = []
    for x0 in (-0.30, 0.22):
        for z0 in (-0.15, 0.07):
            parts.append(
                _box_faces([x0, 0, z0], [x0 + 0.08, 0.5, z0 + 0.08], ["+x", "+z"], 300, rng)
            )
    parts.append(_box_faces([-0.30, 0.5, -0.15], [0.30, 0.56, 0.15], ["+y", "+z", "+x"], 2500, rng))
    P = np.concatenate([p for p, _ in parts])
    N = np.concatenate([n for _, n in parts])
    P[:, 0] += c
    colors = np.full((len(P), 3), 128, np.uint8)
    none_free = lambda p: np.zeros(len(p), bool)  # noqa: E731
    planes = symmetry.mirror_planes(P, colors, none_free, cell, max_planes=1, normals=N)
    assert planes, "expected the left-right plane"
    true = P * [-1, 1, 1] + [2 * c, 0, 0]
    # every mirrored point within a quarter of a cell of where the true plane puts it
    assert np.abs(planes[0].apply(P) - true).max() <= 0.25 * cell


def test_a_block_seen_on_its_sides_completes_solid_down_to_its_unseen_bottom():
    # a chest-like block scanned from three views above: its top and sides are seen, its
    # bottom never; the solid between opposite sides fills it, not a hollow shell open below
    import trimesh

    from partscale.complete import api
    from partscale.evaluate import virtual
    from partscale.ingest import from_trimesh

    box = trimesh.creation.box([0.6, 0.3, 0.4])
    box.apply_translation([0, 0.15, 0])
    c = api.complete(virtual.virtual_scan(from_trimesh(box), 3), res=48)
    inside = np.asarray(c.sdf) < 0
    volume = inside.sum() * c.voxel_size**3
    assert volume >= 0.85 * (0.6 * 0.3 * 0.4)
    assert volume <= 1.15 * (0.6 * 0.3 * 0.4)


def _fuse_args(P, N, shape, closure):
    """Positional arguments of ``fuse.fuse`` for observed grey points ``P`` with normals ``N``
    on a unit grid at the origin: nothing seen free, no symmetry, the support far below."""
    from partscale.complete import fuse

    never = lambda p: np.zeros(len(p), bool)  # noqa: E731
    above = lambda p: p[:, 1] + 10.0  # noqa: E731
    args = (np.eye(4), shape, np.zeros(3), 1.0, P, np.full((len(P), 3), 128, np.uint8))
    return (*args, np.full(len(P), fuse.OBSERVED, np.uint8), N, never, [], above, closure)


def _grid_face(lo, hi, axis, side, rows=None):
    """Points (N, 3) every half voxel on one face of a box, and their normals; ``rows``: keep
    only those whose z lies within half a voxel of a row start ``lo_z + 12 k``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    a, b = (x for x in range(3) if x != axis)
    U, V = np.meshgrid(
        np.arange(lo[a], hi[a] + 1e-9, 0.5), np.arange(lo[b], hi[b] + 1e-9, 0.5), indexing="ij"
    )
    P = np.zeros((U.size, 3))
    P[:, a], P[:, b] = U.ravel(), V.ravel()
    P[:, axis] = hi[axis] if side > 0 else lo[axis]
    if rows:
        P = P[(P[:, 2] - lo[2]) % 12 < 1]
    N = np.zeros_like(P)
    N[:, axis] = side
    return P, N


def test_the_fill_is_kept_where_it_closes_a_part_and_dropped_where_it_leaves_voids():
    # two parts on one grid (voxel units): a block seen on all sides but its bottom, whose fill
    # closes it; and a long box whose two sides were seen only along thin rows 12 voxels apart,
    # whose fill is slabs with wide voids between them, each void a surface inside the object
    from partscale.complete import fuse

    a_lo, a_hi, b_lo, b_hi = (4, 2, 4), (16, 14, 16), (24, 2, 4), (36, 14, 64)
    faces = [
        _grid_face(a_lo, a_hi, ax, s) for ax in range(3) for s in (1, -1) if (ax, s) != (1, -1)
    ]
    faces += [_grid_face(b_lo, b_hi, 0, s, rows=True) for s in (1, -1)]
    faces.append(_grid_face(b_lo, b_hi, 1, 1))
    P = np.concatenate([p for p, _ in faces])
    N = np.concatenate([n for _, n in faces])
    shape = (42, 18, 70)
    args = _fuse_args(P, N, shape, closure=2.0)
    with_fill = fuse.fuse(*args)[0] < 0
    without = fuse.fuse(*args, fill_between=False)[0] < 0

    def area(inside, box):
        return sum(int((np.diff(inside[box], axis=a) != 0).sum()) for a in range(3))

    # the block is solid deep inside (the thin closure alone leaves it hollow) ...
    assert with_fill[10, 8, 10]
    assert not without[10, 8, 10]
    # ... while the long box has at most 3 % more surface than its thin closure alone
    b = (slice(22, 39), slice(0, 17), slice(2, 67))
    assert area(with_fill, b) <= 1.03 * area(without, b)


def test_a_slab_seen_on_top_front_and_one_side_completes_to_its_thickness():
    # a table top 6 voxels thick seen from one camera above the front right: its top, front and
    # right side; no surface faces another, so the fill between opposite surfaces finds
    # nothing; the side faces show the thickness, and the solid reaches the unseen underside
    from partscale.complete import fuse

    lo, hi = (4, 20, 4), (44, 26, 34)
    faces = [_grid_face(lo, hi, 1, 1), _grid_face(lo, hi, 2, 1), _grid_face(lo, hi, 0, 1)]
    P = np.concatenate([p for p, _ in faces])
    N = np.concatenate([n for _, n in faces])
    shape = (50, 32, 40)
    args = _fuse_args(P, N, shape, closure=1.5)
    sdf = fuse.fuse(*args)[0]
    thin = fuse.fuse(*args, fill_between=False)[0]
    # under the middle of the top: solid down to a voxel above the underside (y = 20) ...
    assert (sdf[24, 21:26, 19] < 0).all()
    assert not (thin[24, 21:23, 19] < 0).all()
    # ... and no further than a voxel below it
    assert (sdf[24, :19, 19] > 0).all()


def test_depth_smoothing_moves_no_reading_across_an_edge_or_along_a_slope():
    # a near sloped board (1.0-1.3 m) in front of a far wall (2.5 m), with sensor noise: the
    # smoothed readings stay on their own surface (none hangs between the two) and the board's
    # edge pixels are not pulled towards its middle (a one-sided mean would be, along the slope)
    from partscale.complete.scan import Frame, denoise

    rng = np.random.default_rng(0)
    H, W = 60, 80
    u = np.arange(W)[None, :].repeat(H, 0).astype(float)
    board = 1.0 + 0.3 * u / W
    truth = np.where(u < 40, board, 2.5)
    sigma = 0.004
    depth = (truth + rng.normal(0, sigma, truth.shape)).astype(np.float32)
    out = denoise(Frame(depth, np.zeros((H, W, 3), np.uint8), np.eye(3), np.eye(4), False)).depth
    err = out - truth
    # no reading off its surface by more than 4 noise sigmas (a blend across the edge: ~1 m)
    assert np.abs(err).max() <= 4 * sigma
    # the board's last column (its edge) is unbiased within half a sigma; its noise is reduced
    assert abs(err[:, 39].mean()) <= 0.5 * sigma
    assert err[:, 10:30].std() <= 0.6 * sigma


def _long_cushion(rounded: bool):
    """Points (N, 3) and normals of a part 90 voxels long, 20 thick (y 20-40) and 20 deep seen on
    its front (+z) and right end (+x): a cushion (``rounded``: the vertical edge between them a
    quarter circle of radius 6, every face turned off the axes above and below a band half-way
    up) or a flat rim with sharp edges (a stool's seat)."""
    x_end, z_front, r = 94, 24, 6 if rounded else 0
    ys = np.arange(20, 40.01, 0.5)
    fx, fy = np.meshgrid(np.arange(4, x_end - r + 1e-9, 0.5), ys)
    ez, ey = np.meshgrid(np.arange(4, z_front - r + 1e-9, 0.5), ys)
    a, ay = np.meshgrid(np.radians(np.arange(0, 90.01, 1.0)), ys)
    arc_n = np.stack([np.cos(a.ravel()), 0 * a.ravel(), np.sin(a.ravel())], axis=1)
    P = np.concatenate(
        [
            np.stack([fx.ravel(), fy.ravel(), np.full(fx.size, z_front)], axis=1),
            np.stack([np.full(ez.size, x_end), ey.ravel(), ez.ravel()], axis=1),
            np.stack([x_end - r + r * arc_n[:, 0], ay.ravel(), z_front - r + r * arc_n[:, 2]], 1),
        ]
    )
    N = np.concatenate(
        [np.tile([0.0, 0, 1], (fx.size, 1)), np.tile([1.0, 0, 0], (ez.size, 1)), arc_n]
    )
    if rounded:
        g = np.clip((np.abs(P[:, 1] - 30) - 1) / 3, 0, 1) * np.radians(60)
        N = N * np.cos(g)[:, None]
        N[:, 1] = np.sin(g) * np.sign(P[:, 1] - 30)
    return P, N


@pytest.mark.parametrize("rounded", [False, True])
def test_a_width_carries_a_sharp_rim_across_but_not_a_rounded_cushion_end(rounded):
    # walked in from the end along the front, the side face runs on past the reach: the walk
    # measured the part's width. A stool's flat rim with sharp edges is carried across by it
    # (its seat is that rim's thickness); a cushion's rounded end (SheenChair's) is a flat band
    # whose carry would be a sure sheet deep inside a thicker part, and is not
    from partscale.complete import fuse

    P, N = _long_cushion(rounded)
    shape = (100, 46, 30)
    _, sure, unsure = fuse._fills(
        P, N, np.rint(P).astype(np.int64), np.zeros(3), 1.0, np.zeros(shape, bool)
    )
    # inside the part, away from its end: under the band, across its depth
    inner = (sure | unsure)[: 94 - 10, 22:38, 6:22]
    if rounded:
        assert not inner.any()
    else:
        assert inner.mean() >= 0.5


@pytest.mark.parametrize("band", [None, 1e9])
def test_a_width_is_carried_only_from_a_band_not_from_a_cabinets_side(monkeypatch, band):
    # a cabinet 90 long, 70 tall and 60 deep seen on its top and its right end, every edge
    # sharp: walked in from an edge, each face runs on past the reach along the other (a
    # width). A rim a few voxels high is carried across by it (the test above); a face as tall
    # or deep as the width is not: carried in, it would fill what no camera saw of a cabinet
    # open at the front (a TV unit's space under each shelf, from three views). SLAB_BAND
    # raised past any face (band=1e9) carries it: the rule is what keeps the inside empty
    from partscale.complete import fuse

    # two faces with one edge each: too few of their points measure for SLAB_EDGE_SHARE (a real
    # cabinet's faces have edges all round, and shelves', doors' and sensor holes' edges)
    monkeypatch.setattr(fuse, "SLAB_EDGE_SHARE", 0.001)
    if band is not None:
        monkeypatch.setattr(fuse, "SLAB_BAND", band)
    lo, hi = (4, 4, 4), (94, 74, 64)
    top, n_top = _grid_face(lo, hi, 1, 1)
    end, n_end = _grid_face(lo, hi, 0, 1)
    P, N = np.concatenate([top, end]), np.concatenate([n_top, n_end])
    shape = (100, 80, 70)
    _, sure, unsure = fuse._fills(
        P, N, np.rint(P).astype(np.int64), np.zeros(3), 1.0, np.zeros(shape, bool)
    )
    inner = (sure | unsure)[10:88, 10:68, 10:58]
    if band is None:
        assert inner.mean() <= 0.01
    else:
        assert inner.mean() >= 0.5


def test_the_fusion_fills_enclosed_space_as_scipy_does():
    # holes are filled by labelling the empty space once (faces of the array are outside),
    # not by scipy's dilation repeated until nothing changes: the same voxels
    from scipy import ndimage

    from partscale.complete.fuse import _fill_holes

    rng = np.random.default_rng(2)
    grew = 0
    for _ in range(20):
        shape = tuple(int(n) for n in rng.integers(4, 32, 3))
        # mostly solid, so empty pockets are enclosed
        m = ndimage.gaussian_filter(rng.random(shape), 1.2) < rng.uniform(0.5, 0.56)
        want = ndimage.binary_fill_holes(m)
        assert (want == _fill_holes(m)).all()
        grew += int(want.sum() > m.sum())
    assert grew >= 4  # enclosed pockets in several cases


def _face(axis: int, at: float, way: float, ranges, step: float = 0.5):
    """Points (N, 3) and normals on the plane ``axis = at`` facing ``way`` (+1 or -1) over
    ``ranges``: (lo, hi) of the other two axes in order, every ``step`` voxels."""
    others = [a for a in range(3) if a != axis]
    u, v = np.meshgrid(*(np.arange(lo, hi + 1e-9, step) for lo, hi in ranges), indexing="ij")
    P = np.zeros((u.size, 3))
    P[:, axis] = at
    P[:, others[0]], P[:, others[1]] = u.ravel(), v.ravel()
    N = np.zeros_like(P)
    N[:, axis] = way
    return P, N


def _points(*faces):
    return np.concatenate([f[0] for f in faces]), np.concatenate([f[1] for f in faces])


def test_a_top_seen_from_inside_its_compartment_is_as_thick_as_its_board():
    # a cabinet open at the front (+z), y up: a top board 5 voxels thick (y 35-40) on side
    # panels 4 thick. Its edges run down the side panels, 32 voxels: as a slab's thickness
    # that carried the top down through the compartment's back, which no camera saw. Where
    # the top's underside was seen (the front three quarters) it measures the board, and the
    # top is carried no deeper than that anywhere
    from partscale.complete import fuse

    P, N = _points(
        _face(1, 40, 1, [(4, 36), (4, 36)]),  # top
        _face(0, 36, 1, [(8, 40), (4, 36)]),  # side panels, outside
        _face(0, 4, -1, [(8, 40), (4, 36)]),
        _face(0, 32, -1, [(8, 35), (4, 36)]),  # and inside
        _face(0, 8, 1, [(8, 35), (4, 36)]),
        _face(2, 36, 1, [(4, 36), (35, 40)]),  # front edges of the boards
        _face(2, 36, 1, [(32, 36), (8, 35)]),
        _face(2, 36, 1, [(4, 8), (8, 35)]),
        _face(1, 35, -1, [(8, 32), (12, 36)]),  # the top's underside, front three quarters
    )
    shape = (44, 48, 44)
    x, y, z = np.indices(shape)
    cabinet = (x >= 4) & (x <= 36) & (y >= 8) & (y <= 40) & (z >= 4) & (z <= 36)
    seen_free = (x >= 9) & (x <= 31) & (y >= 9) & (y <= 34) & (z >= 12)
    _, sure, unsure = fuse._fills(
        P, N, np.rint(P).astype(np.int64), np.zeros(3), 1.0, ~cabinet | seen_free
    )
    slab = sure | unsure
    # the compartment's unseen back, below the top board, away from the side panels
    assert not slab[12:29, 10:34, 6:11].any()
    # the board itself is carried through
    assert slab[12:29, 35:40, 6:11].mean() >= 0.95


def test_no_thickness_is_measured_down_a_leg():
    # a seat (y 36-40) on a leg 3 voxels square (x, z 4-7) joined below by a rail whose
    # underside (y 10) was seen: marched down from the seat's top above the leg, the first
    # surface facing up is the rail's underside, 30 voxels down along the leg's faces; that is
    # no thickness of the seat. Where the seat's own underside was seen it is
    from partscale.complete import fuse

    P, N = _points(
        _face(1, 40, 1, [(4, 36), (4, 36)]),  # seat top
        _face(1, 36, -1, [(10, 36), (10, 36)]),  # its underside, away from the leg
        _face(0, 4, -1, [(10, 35), (4, 7)]),  # the leg's four faces
        _face(0, 7, 1, [(10, 35), (4, 7)]),
        _face(2, 4, -1, [(4, 7), (10, 35)]),
        _face(2, 7, 1, [(4, 7), (10, 35)]),
        _face(1, 10, -1, [(4, 36), (4, 7)]),  # the rail's underside
    )
    shape = (40, 44, 40)
    idx = np.rint(P).astype(np.int64)
    facing = fuse._facing(N, idx, shape)
    _, seen = fuse._between(P, N, np.zeros(3), 1.0, facing, np.zeros(shape, bool))
    top = N[:, 1] > 0
    over_leg = top & (P[:, 0] >= 5) & (P[:, 0] <= 6) & (P[:, 2] >= 5) & (P[:, 2] <= 6)
    middle = top & (np.abs(P[:, 0] - 22) <= 6) & (np.abs(P[:, 2] - 22) <= 6)
    assert over_leg.sum() >= 4 and not seen[over_leg].any()
    assert (seen[middle] >= 3).all() and (seen[middle] <= 4).all()


def test_legs_flush_below_a_top_do_not_hang_a_wall_under_it():
    # the shipped depth frame of the table (a corner, 25 degrees down): its legs are flush
    # with its top's edge, so walks down the edge above a leg measure the top as thick as the
    # legs are tall (47 voxels at --res 128, the rest of the edge 2 to 7); near the corners
    # most measurements were theirs, and the top was carried down into a wall under the end
    # no camera saw past. Just below the apron, the completion holds the legs and little more
    import warnings

    from partscale import data, ingest
    from partscale.complete import complete, read_frame

    s = data.table_scan()
    frame = read_frame(s / "depth.png", s / "color.jpg", s / "intrinsics.json")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = complete([frame], res=96, upright=True)
    truth = ingest.load(data.table(), res=96)

    def area_at(obj, share):
        sb = obj.surface_bounds()
        y = sb[0, 1] + share * (sb[1, 1] - sb[0, 1])
        j = int(np.rint((y - obj.origin[1]) / obj.voxel_size))
        return float((obj.sdf[:, j, :] < 0).sum()) * obj.voxel_size**2

    # the legs' cross-section (0.078 m2 imported from the mesh); the wall made it 0.195
    assert area_at(c, 0.75) <= 1.25 * area_at(truth, 0.75)


def _plates_at_centre(obj) -> np.ndarray:
    """(P,) metres: the thickness of each plate (a table's top, a shelf) that a line up through
    the middle of ``obj``'s plan crosses, lowest first (between its surfaces, interpolated)."""
    sb = obj.surface_bounds()
    i, _, k = np.rint(((sb[0] + sb[1]) / 2 - obj.origin) / obj.voxel_size).astype(int)
    col = obj.sdf[i, :, k]
    j = np.flatnonzero((col[:-1] < 0) != (col[1:] < 0))
    y = obj.origin[1] + (j - col[j] / (col[j + 1] - col[j])) * obj.voxel_size
    return np.diff(y)[::2]


def _truth_and_completion(rel: str, azimuths: tuple, elevation: float, scale: float = 1.0):
    """The test object ``rel`` (its vertices times ``scale``: metres) voxelised at --res 128,
    and its completion at 128 from virtual views at ``azimuths`` and ``elevation`` (degrees)."""
    import dataclasses
    import warnings

    from conftest import data_path

    from partscale import ingest
    from partscale.complete import complete
    from partscale.evaluate.virtual import virtual_scan

    mesh = ingest.load_mesh(data_path(rel))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * scale)
    frames = virtual_scan(mesh, azimuths=azimuths, elevation=elevation)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = complete(frames, res=128, upright=True)
    return ingest.from_mesh(mesh, res=128), c


def test_a_table_s_top_seen_from_its_own_height_is_as_thick_as_a_top():
    # Sweet Home's table (its 30 mm top flush with its apron) from three level views: nothing
    # seen measures its top's thickness. Closed two slices thick (at --res 128) it was 16 mm
    # between its surfaces, its underside, 29 % of its surface, 2 cm over the true one; a
    # top's thickness (fuse.LID_TOP, 30 mm) makes it 27 mm
    t, c = _truth_and_completion("sweethome3d/table.obj", (87.0, 207.0, 327.0), 0.0)
    (truth,) = _plates_at_centre(t)
    assert truth == pytest.approx(0.030, abs=0.002)
    (made,) = _plates_at_centre(c)
    assert made >= 0.8 * truth
    # its face runs on down its apron (9 cm in all): that is no measure of the top
    assert made <= 1.25 * truth


def test_a_table_s_top_is_as_thick_as_its_edge_s_face_seen_from_above():
    # Sweet Home's square table (0.74 m tall, a top 57 mm thick, four legs, no apron) from three
    # views 15 degrees above its top: the face of its edge is seen down to its underside, and
    # the space under it seen free. Closed as a top (fuse.LID_TOP, 3 slices at --res 128), it
    # was 21 mm between its surfaces, its underside (half its surface) 3 cm over the true one;
    # as tall as its edge's face (fuse._edge_faces), 0.8 of it at least
    t, c = _truth_and_completion(
        "sweethome3d/squareTable.obj", (336.0, 96.0, 216.0), 15.0, scale=0.74 / 1.30
    )
    (truth,) = _plates_at_centre(t)
    assert truth == pytest.approx(0.057, abs=0.003)
    (made,) = _plates_at_centre(c)
    assert made >= 0.8 * truth


def _plate_heights(obj) -> np.ndarray:
    """(P,) metres: the middle of each plate a line up through the middle of ``obj``'s plan
    crosses, above its lowest surface, lowest first."""
    sb = obj.surface_bounds()
    i, _, k = np.rint(((sb[0] + sb[1]) / 2 - obj.origin) / obj.voxel_size).astype(int)
    col = obj.sdf[i, :, k]
    j = np.flatnonzero((col[:-1] < 0) != (col[1:] < 0))
    y = obj.origin[1] + (j - col[j] / (col[j + 1] - col[j])) * obj.voxel_size - sb[0][1]
    return (y[0::2] + y[1::2]) / 2


def test_a_bookcase_s_shelves_seen_end_on_repeat_those_seen_from_above():
    # Sweet Home's bookcase (2.1 m tall, eight shelves and its top 28 cm apart) from three
    # views 15 degrees above its middle: the cameras stand at 1.9 m, and the three highest
    # shelves are seen end on (their faces too obliquely for a reading, 60-75 points of their
    # front edges each). They were missing (F@1% 0.830, below the raw scan's 0.860); carried
    # on from the five below them (fuse.repeat_plates), each lies within 3 cm of the true one
    t, c = _truth_and_completion("sweethome3d/bookcase.obj", (40.0, 160.0, 280.0), 15.0)
    truth = _plate_heights(t)
    assert len(truth) == 8
    made = _plate_heights(c)
    for y in truth[-3:]:  # the three highest
        assert np.abs(made - y).min() <= 0.03


def test_a_shelf_seen_at_its_edge_is_as_thick_as_its_edge():
    # Sweet Home's bedside table (0.5 m tall, four legs, a top and two shelves 18 mm thick)
    # from three level views: each shelf's edge is seen all round and nothing of its faces.
    # Closed two slices (7 mm at --res 128) thick under the edge's most common top, its lower
    # shelf was 5 mm between its surfaces; as tall as its edge (fuse._rim_tops), 16 mm
    t, c = _truth_and_completion(
        "sweethome3d/bedsideTable.obj",
        (3.0, 123.0, 243.0),
        0.0,
        scale=0.5 / 5.02,  # dm
    )
    truth = _plates_at_centre(t)
    assert truth == pytest.approx([0.018] * 3, abs=0.001)  # the shelves and the top
    made = _plates_at_centre(c)
    assert len(made) == 3
    assert made[0] >= 0.8 * truth[0]  # the lower shelf
