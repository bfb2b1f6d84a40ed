"""partscale.complete: five-star bases completed by rotational symmetry (synthetic and real)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import complete_tum_frame, data_path


def _legs_around(c, *, below: float, r0: float, r1: float, axis=None) -> tuple[int, np.ndarray]:
    """Legs of a base: the solid voxels of CSDF ``c`` (y up) below height ``below``, at radii
    r0..r1 from the vertical ``axis`` (x, z; default their median), binned by angle in 10
    degree bins; a leg is a peak of the (lightly smoothed, circular) histogram holding at least
    0.3 of the fullest bin, with a valley below half of it towards the next peak.
    Returns the number of legs and the histogram."""
    sdf = np.asarray(c.sdf)
    P = c.index_to_world(np.argwhere(sdf <= 0.5 * c.voxel_size))
    base = P[P[:, 1] < below]
    ax = np.median(base[:, [0, 2]], axis=0) if axis is None else np.asarray(axis)
    d = base[:, [0, 2]] - ax
    r = np.hypot(d[:, 0], d[:, 1])
    a = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 360
    hist = np.histogram(a[(r > r0) & (r < r1)], bins=36, range=(0, 360))[0]
    s = (np.roll(hist, 1) + 2 * hist + np.roll(hist, -1)) / 4.0
    peaks = np.flatnonzero(
        (s >= np.roll(s, 1)) & (s > np.roll(s, -1)) & (s >= 0.3 * s.max())
    ).tolist()
    legs = []
    for p in peaks:
        if legs:
            q = legs[-1]
            between = s[q : p + 1] if p > q else np.r_[s[q:], s[: p + 1]]
            if between.min() > 0.5 * min(s[p], s[q]):
                if s[p] > s[q]:
                    legs[-1] = p
                continue
        legs.append(p)
    if len(legs) > 1:  # the last and the first peak, across 360 degrees
        p, q = legs[0], legs[-1]
        if np.r_[s[q:], s[: p + 1]].min() > 0.5 * min(s[p], s[q]):
            legs.pop()
    return len(legs), hist


def _star_chair():
    """A swivel chair (metres, y up): seat, column, hub and five legs 72 degrees apart."""
    import trimesh

    parts = [
        trimesh.creation.box(
            [0.45, 0.06, 0.45], trimesh.transformations.translation_matrix([0, 0.48, 0])
        ),
        trimesh.creation.cylinder(0.025, 0.4, transform=_upright_at(0.25)),
        trimesh.creation.cylinder(0.05, 0.06, transform=_upright_at(0.035)),
    ]
    for i in range(5):
        leg = trimesh.creation.box([0.3, 0.05, 0.05])
        leg.apply_translation([0.18, 0.025, 0])
        leg.apply_transform(trimesh.transformations.rotation_matrix(2 * np.pi * i / 5, [0, 1, 0]))
        parts.append(leg)
    return trimesh.util.concatenate(parts)


def _upright_at(y: float) -> np.ndarray:
    import trimesh

    T = trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0])
    T[1, 3] = y
    return T


def _leg_angles_deg(i: int) -> float:
    # trimesh turns +x by +angle about +y towards -z: in the (x, z) plane the angle is negative
    return (-72.0 * i) % 360


def test_a_five_star_base_seen_in_part_completes_to_five_legs():
    # one view of a swivel chair whose two far legs return no depth (black plastic): the legs
    # seen vote for a 5-fold axis, and the copies complete the star where nothing was seen
    from partscale.complete import Frame, complete
    from partscale.evaluate import virtual
    from partscale.ingest import from_trimesh

    mesh = from_trimesh(_star_chair(), color=(40, 40, 40))
    (f,) = virtual.virtual_scan(mesh, 1, holes=0.0)
    P, _, pix = f.points()
    r = np.hypot(P[:, 0], P[:, 2])
    a = np.degrees(np.arctan2(P[:, 2], P[:, 0])) % 360
    hidden = []
    for i in range(5):
        gap = np.abs((a - _leg_angles_deg(i) + 180) % 360 - 180)
        on_leg = (r > 0.06) & (P[:, 1] < 0.1) & (gap < 15)
        hidden.append(on_leg)
    # the two legs farthest from the camera (largest distance along its view axis)
    depth_of = [np.median(f.depth.ravel()[pix[h]]) for h in hidden]
    far = np.argsort(depth_of)[-2:]
    depth = f.depth.copy().ravel()
    for i in far:
        depth[pix[hidden[i]]] = 0
    frame = Frame(depth.reshape(f.depth.shape), f.color, f.K, f.pose)

    def legs(symmetry: bool):
        c = complete([frame], res=64, symmetry=symmetry)
        return _legs_around(c, below=0.1, r0=0.1, r1=0.3, axis=(0.0, 0.0))

    n_sym, hist = legs(True)
    n_none, _ = legs(False)
    assert n_none == 3, "the scan should see three legs"
    assert n_sym == 5, f"expected five legs, got {n_sym} ({hist.tolist()})"
    # each completed leg is there along its length, not a stub
    for i in far:
        b = int(_leg_angles_deg(i) // 10)
        assert max(hist[b - 1], hist[b], hist[(b + 1) % 36]) >= 0.25 * hist.max()


@pytest.fixture(scope="module")
def tum_completions():
    from partscale.complete import complete_file

    out = {}
    for name in ("yellow", "purple"):
        out[name] = complete_file(
            data_path(f"scans/derived/tum_{name}_office_chair_partial.ply"), res=64, upright=True
        )
    out["frame_purple"] = complete_tum_frame((0, 255, 245, 480))
    return out


@pytest.mark.parametrize("name", ["yellow", "purple", "frame_purple"])
def test_real_tum_chairs_complete_with_a_five_legged_base(tum_completions, name):
    # the star bases are seen in part (four legs of five at most): completed, five legs
    # stand around the axis near the floor, and the object is upright on it
    c = tum_completions[name]
    rot = [s for s in c.meta["completion"]["symmetries"] if s["kind"] == "rotation"]
    assert rot and rot[0]["fold"] == 5
    n, hist = _legs_around(c, below=0.12, r0=0.1, r1=0.28)
    assert n == 5, f"expected five legs, got {n} ({hist.tolist()})"
    lo = c.index_to_world(np.argwhere(np.asarray(c.sdf) < 0)).min(axis=0)
    assert -0.03 <= lo[1] <= 0.03  # standing on y = 0


def test_real_tum_chairs_complete_watertight_and_upright(tum_completions):
    from partscale.surface import to_mesh

    for name, c in tum_completions.items():
        m = to_mesh(c)
        assert m.is_watertight, name
        ext = c.index_to_world(np.argwhere(np.asarray(c.sdf) < 0))
        # taller than wide is not asked of a chair; upright is: its top well above the floor
        assert ext[:, 1].max() >= 0.7, name


@pytest.mark.parametrize("name", ["yellow", "purple", "frame_purple"])
def test_real_tum_chairs_stand_on_a_column_from_hub_to_seat(tum_completions, name):
    # no scan reads the gas-lift column (the raw frame's depth is 0 over it): the column is
    # guessed along the base's axis, and seat and base become one solid piece
    from scipy import ndimage

    from partscale.complete import GUESSED, provenance
    from partscale.complete.column import MAX_RADIUS, MIN_RADIUS

    c = tum_completions[name]
    col = c.meta["completion"]["column"]
    assert col is not None and col["voxels_added"] > 0
    assert MIN_RADIUS <= col["radius"] <= MAX_RADIUS
    assert c.meta["history"][0]["column_radius_m"] == [MIN_RADIUS, MAX_RADIUS]
    lab, _ = ndimage.label(np.asarray(c.sdf) < 0)
    biggest = lab == np.argmax(np.bincount(lab.ravel())[1:]) + 1
    y = c.index_to_world(np.argwhere(biggest))[:, 1]
    assert y.min() <= 0.05 and y.max() >= 0.45, (y.min(), y.max())
    # its surface is counted as guessed
    mid = c.index_to_world(np.argwhere(provenance(c) == GUESSED))
    r = np.hypot(mid[:, 0] - col["axis_x"], mid[:, 2] - col["axis_z"])
    band = (mid[:, 1] > col["bottom"] + 0.05) & (mid[:, 1] < col["top"] - 0.05)
    assert (r[band] <= col["radius"] + c.voxel_size).sum() > 0


def _star_points(r0: float, legs: int = 5, step: float = 0.003) -> np.ndarray:
    """(N, 3) upright points: the tops of ``legs`` legs (0.05 wide, 5 cm high) from radius r0
    to 0.33 m about the y axis, no hub between them, under a seat 0.45 m wide at 0.48 m."""
    u, v = np.meshgrid(np.arange(r0, 0.33, step), np.arange(-0.025, 0.025, step))
    pts = []
    for i in range(legs):
        a = 2 * np.pi * i / legs
        x = u * np.cos(a) - v * np.sin(a)
        z = u * np.sin(a) + v * np.cos(a)
        pts.append(np.stack([x.ravel(), np.full(x.size, 0.05), z.ravel()], axis=1))
    s = np.arange(-0.225, 0.225, 0.01)
    sx, sz = np.meshgrid(s, s)
    pts.append(np.stack([sx.ravel(), np.full(sx.size, 0.48), sz.ravel()], axis=1))
    return np.concatenate(pts)


@pytest.mark.parametrize("cell", [0.006, 0.011])
def test_the_hub_test_is_a_length_of_the_base_not_of_the_grid(cell):
    # the legs seen start 5 cm from the axis (the hub unseen): at a fine grid's cell as at a
    # coarse one the five-star is found (five cells of the fine one, 3 cm, refused it); legs
    # that start near their tips (four feet, each a piece of its own) never turn
    from partscale.complete.symmetry import rotation_axis

    def free(p):
        return np.zeros(len(p), bool)

    rot = rotation_axis(_star_points(0.05), free, cell)
    assert rot is not None and rot.fold == 5
    assert np.hypot(rot.params["axis_x"], rot.params["axis_z"]) <= 2 * cell
    assert rotation_axis(_star_points(0.26, legs=4), free, cell) is None


def _legs_seen(legs: int, seen: tuple[int, ...]) -> np.ndarray:
    """(N, 3): :func:`_star_points` of a ``legs``-star starting 5 cm out, only the legs ``seen``
    (their indices round the star) kept under the seat."""
    P = _star_points(0.05, legs=legs)
    a = np.degrees(np.arctan2(P[:, 2], P[:, 0]))
    keep = P[:, 1] > 0.1
    for i in seen:
        keep |= np.abs((a - 360 * i / legs + 180) % 360 - 180) < 10
    return P[keep]


@pytest.mark.parametrize(("legs", "cell"), [(5, 0.006), (5, 0.011), (4, 0.006), (4, 0.011)])
def test_the_fold_is_read_from_the_angles_between_the_legs_seen(legs, cell):
    # three neighbouring legs, no hub: at the coarse cell a 4-fold turn about a point off the
    # hub lands three legs of a five-star on each other as well as the 5-fold does (the TUM
    # purple chair's trap); the angles between the legs about the hub where their lines meet
    # say which fold it is
    from partscale.complete.symmetry import rotation_axis

    def free(p):
        return np.zeros(len(p), bool)

    rot = rotation_axis(_legs_seen(legs, (0, 1, 2)), free, cell)
    assert rot is not None and rot.fold == legs
    assert np.hypot(rot.params["axis_x"], rot.params["axis_z"]) <= 2 * cell


@pytest.mark.parametrize("name", ["yellow", "purple"])
def test_real_tum_completions_segment_into_a_few_parts(tum_completions, name):
    # a completed scan keeps the sensor's noise as relief over its surface; segment measures it
    # and keeps bumpy boards whole: seat, back, column, the base's legs (a dozen parts at
    # most), where the clean-geometry tolerance alone cuts it into several times as many
    from partscale.segment import segment
    from partscale.segment.relief import CLEAN_RELIEF

    c = tum_completions[name]
    s = segment(c, cache=False)
    entry = s.meta["history"][-1]
    assert entry["relief"] > CLEAN_RELIEF and entry["noise_added"] > 0
    assert s.n_parts <= 12, s.n_parts
    assert segment(c, cache=False, noise=0).n_parts >= 3 * s.n_parts


@pytest.mark.parametrize(
    "name",
    ["yellow", "purple"],
)
def test_derived_tum_chairs_at_the_default_resolution_stand_on_five_legs(name):
    # the README's pictures complete the derived scans at the default --res 128, not 64
    from partscale.complete import complete_file
    from partscale.surface import to_mesh

    c = complete_file(data_path(f"scans/derived/tum_{name}_office_chair_partial.ply"), upright=True)
    assert c.meta["history"][0]["res"] == 128
    assert to_mesh(c).is_watertight
    assert c.meta["completion"]["column"] is not None
    rot = [s for s in c.meta["completion"]["symmetries"] if s["kind"] == "rotation"]
    n, hist = _legs_around(c, below=0.12, r0=0.1, r1=0.28)
    assert rot and rot[0]["fold"] == 5 and n == 5, (rot, n, hist.tolist())
    # base, column and seat are one solid from the floor up
    from scipy import ndimage

    lab, _ = ndimage.label(np.asarray(c.sdf) < 0)
    biggest = lab == np.argmax(np.bincount(lab.ravel())[1:]) + 1
    y = c.index_to_world(np.argwhere(biggest))[:, 1]
    assert y.min() <= 0.05 and y.max() >= 0.45, (y.min(), y.max())


def test_the_symmetry_tolerance_follows_the_scan_not_a_finer_grid():
    # at --res 256 the symmetry tests keep the default grid's voxel (a finer grid does not make
    # the sensor's points more exact): the derived purple chair's base still turns 5-fold, with
    # the support it has at 128 (its legs' copies missed each other at half the cell: no turn)
    from partscale.complete import complete_file

    c = complete_file(data_path("scans/derived/tum_purple_office_chair_partial.ply"), res=256)
    rot = [s for s in c.meta["completion"]["symmetries"] if s["kind"] == "rotation"]
    assert rot and rot[0]["fold"] == 5 and rot[0]["support"] >= 0.6, rot
    assert c.meta["completion"]["column"] is not None
    entry = c.meta["history"][0]
    # recorded: about the 128 grid's voxel (the object's observed extent over 128), not 256's
    assert entry["symmetry_res"] == 128 and entry["symmetry_voxel_m"] > 1.5 * c.voxel_size


@pytest.mark.parametrize(
    ("angles", "fold"),
    [
        ((0, 72), 5),
        ((10, 82, 154), 5),
        ((0, 144), 5),
        ((179, -109), 5),  # two legs 72 degrees apart across +-180
        ((0, 90), 4),
        ((0, 90, 180), 4),
        ((0, 110), None),  # neither fold's step
        ((175, -103), None),  # 82 degrees: within 10 of both steps
        ((30,), None),  # one leg: no angle between legs
    ],
)
def test_the_legs_angles_about_the_hub_give_one_fold_or_none(angles, fold):
    from partscale.complete.symmetry import _Arms

    r = np.linspace(0.1, 0.3, 30)
    X = np.concatenate(
        [np.stack([r * np.cos(np.radians(a)), r * np.sin(np.radians(a))], 1) for a in angles]
    )
    d = X / np.linalg.norm(X, axis=1)[:, None]
    assert _Arms(X, d, 0.01, np.zeros(2)).fold((5, 4)) == fold


@pytest.mark.parametrize(
    ("name", "view"),
    [
        ("kenney/kitchenCabinetDrawer.glb", dict(azimuths=(345.0,), elevation=45.0, floor=True)),
        ("kenney/desk.glb", dict(azimuths=(322.0,), elevation=30.0, floor=False)),
    ],
)
def test_a_plinth_or_a_frame_is_no_turning_base(name, view):
    # a cabinet's plinth and a desk's frame land on themselves turned a quarter about their
    # middle where one corner is seen, but no arms radiate from that axis: no rotation (the
    # turned copies of a rectangle stood off the object in unseen space)
    import dataclasses

    from partscale import ingest
    from partscale.complete import api
    from partscale.evaluate import virtual_scan

    mesh = ingest.load_mesh(data_path(name))
    mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * 0.7)
    sy = api.find_symmetries(api.observe(virtual_scan(mesh, **view)), 128, True)
    assert sy.rot is None


def test_the_arms_neighbourhood_sums_are_numpys_sums_over_both_ways_of_each_pair():
    # the kernel adds each pair to both its points in the order np.bincount adds over (i, j),
    # then (j, i), then each point itself: the same sums, bit for bit
    from scipy.spatial import cKDTree

    from partscale.complete.symmetry import _pair_sums

    X = _star_points(0.05)[:, [0, 2]]
    pairs = cKDTree(X).query_pairs(0.04, output_type="ndarray")
    i = np.concatenate([pairs[:, 0], pairs[:, 1], np.arange(len(X))])
    j = np.concatenate([pairs[:, 1], pairs[:, 0], np.arange(len(X))])
    Y = X[j] - X[i]
    want = [Y[:, 0], Y[:, 1], Y[:, 0] ** 2, Y[:, 0] * Y[:, 1], Y[:, 1] ** 2]
    n, sums = _pair_sums(X, pairs)
    assert len(pairs) > 10 * len(X)  # every point has neighbours
    np.testing.assert_array_equal(n, np.bincount(i, minlength=len(X)))
    for q, w in enumerate(want):
        np.testing.assert_array_equal(sums[q], np.bincount(i, w, len(X)))
