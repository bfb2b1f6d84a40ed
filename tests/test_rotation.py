"""Elements repeated by a turn about the vertical: found and added or removed.

Analytic objects: a star base (a column with ``k`` arms, boxes in their own turned frames) and
a round table with ``k`` boxes (chairs) about it. Judged by geometry measured on the grids:
the arms' directions, sizes and reach (connected pieces of one level beyond the column), the
column and the table top within the hub.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import assert_bad_input, data_path
from scipy import ndimage

from partscale import shapes
from partscale.csdf import load, save
from partscale.edit import (
    Recipe,
    RotationZone,
    apply_recipe,
    apply_rotation,
    recipe_from_history,
    recipe_shape,
)
from partscale.errors import InputError
from partscale.ingest import load as import_file
from partscale.zones import find_rotations, fit

H = 0.01
#: The axis lies off the grid's voxel centres and off the origin.
CX, CZ = 0.013, -0.021
PHASE = 10.0


def _turn(d, deg):
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    return np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]], 1)


def _cyl(p, r, y0, y1):
    q = np.stack(
        [np.hypot(p[:, 0] - CX, p[:, 2] - CZ) - r, np.abs(p[:, 1] - (y0 + y1) / 2) - (y1 - y0) / 2],
        1,
    )
    return np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)


def _turned_boxes(p, k, lo, hi):
    """The union of ``k`` boxes ``lo..hi`` (in the frame of the first, along +x from the axis)
    turned by ``PHASE + m * 360 / k`` degrees about the axis."""
    d = np.full(len(p), np.inf)
    for m in range(k):
        local = p.copy()
        local[:, [0, 2]] = _turn(p[:, [0, 2]] - [CX, CZ], -(PHASE + m * 360 / k))
        d = np.minimum(d, shapes.box_sdf(local, lo, hi))
    return d


def star(k):
    """A column (radius 0.052, 0.5 tall) with ``k`` arms 0.35 long, 0.05 wide and thick (faces
    off the voxel centres)."""

    def sdf(p):
        arms = _turned_boxes(p, k, (0.0, 0.053, -0.0253), (0.35, 0.103, 0.0253))
        return np.minimum(_cyl(p, 0.0523, 0.0, 0.5), arms)

    b = np.array([[CX - 0.36, 0, CZ - 0.36], [CX + 0.36, 0.5, CZ + 0.36]])
    return shapes.grid(sdf, b, voxel_size=H, source="star base")


def table_and_chairs(k):
    """A round top (radius 0.3) on a column, and ``k`` boxes (0.16 x 0.4 x 0.16) about it."""

    def sdf(p):
        table = np.minimum(_cyl(p, 0.3031, 0.663, 0.703), _cyl(p, 0.0413, 0.0, 0.663))
        chairs = _turned_boxes(p, k, (0.363, 0.003, -0.0803), (0.523, 0.403, 0.0803))
        return np.minimum(table, chairs)

    b = np.array([[CX - 0.53, 0, CZ - 0.53], [CX + 0.53, 0.71, CZ + 0.53]])
    return shapes.grid(sdf, b, voxel_size=H, source="table and chairs")


def _pieces(c, y, r_min):
    """(direction in degrees, area in voxels, farthest reach) of each connected piece of the
    level ``y`` beyond ``r_min`` from the axis, by direction; the area from the distances
    (each voxel within half a voxel of the surface counts its share), which does not alias
    with the direction as a count of voxels inside does."""
    j = round((y - c.origin[1]) / c.voxel_size)
    x = c.origin[0] + np.arange(c.shape[0]) * c.voxel_size - CX
    z = c.origin[2] + np.arange(c.shape[2]) * c.voxel_size - CZ
    r = np.hypot(x[:, None], z[None, :])
    a = np.arctan2(np.broadcast_to(z[None, :], r.shape), np.broadcast_to(x[:, None], r.shape))
    level = c.sdf[:, j, :]
    share = np.clip(0.5 - level / c.voxel_size, 0.0, 1.0)
    lab, n = ndimage.label((level < 0) & (r > r_min))
    out = []
    for i in range(1, n + 1):
        m = lab == i
        if m.sum() < 8:
            continue
        mean = math.degrees(np.angle(np.exp(1j * a[m]).mean()))
        area = float(share[ndimage.binary_dilation(m, iterations=2) & (r > r_min)].sum())
        out.append((mean, area, float(r[m].max())))
    return sorted(out)


def _evenly(dirs, k):
    """Largest difference (degrees) of the gaps between sorted directions from 360 / k."""
    d = np.sort(np.asarray(dirs))
    gaps = np.diff(np.concatenate([d, [d[0] + 360]]))
    return float(np.abs(gaps - 360 / k).max())


def _same_within(a, b, radius):
    """Whether ``b`` holds ``a``'s solid within ``radius`` of the axis (the same sign at every
    voxel) and its surface there in place (distances within half a voxel where ``a``'s are
    within a voxel; deeper inside, a distance may change where an arm now meets the column
    elsewhere). ``b``'s grid may be larger: matched by world position."""
    h = a.voxel_size
    off = np.rint((a.origin - b.origin) / h).astype(int)
    x = a.origin[0] + np.arange(a.shape[0]) * h - CX
    z = a.origin[2] + np.arange(a.shape[2]) * h - CZ
    near = np.hypot(x[:, None], z[None, :]) < radius
    sub = b.sdf[
        off[0] : off[0] + a.shape[0], off[1] : off[1] + a.shape[1], off[2] : off[2] + a.shape[2]
    ]
    got, was = sub.transpose(1, 0, 2)[:, near], a.sdf.transpose(1, 0, 2)[:, near]
    at = np.abs(was) <= h
    return bool(np.array_equal(got < 0, was < 0) and np.abs(got - was)[at].max(initial=0) <= h / 2)


@pytest.fixture(scope="module", params=[4, 5])
def star_k(request):
    return request.param, star(request.param)


def test_star_found(star_k):
    """The turn within 0.5 degrees of 360 / k, the axis within 1 % of the bounding diagonal, k
    exact, a closed ring; the first arm's direction within a degree; the hub inside the
    column, the span about the arms' levels."""
    k, c = star_k
    (rot,) = find_rotations(c)
    assert abs(rot.angle - 360 / k) <= 0.5, rot
    sb = c.surface_bounds()
    diag = float(np.linalg.norm(sb[1] - sb[0]))
    assert math.hypot(rot.center[0] - CX, rot.center[1] - CZ) <= 0.01 * diag, rot
    assert rot.count == k and rot.closed, rot
    assert abs(((rot.phase - PHASE) + 180 / k) % (360 / k) - 180 / k) <= 1.0, rot
    assert rot.hub <= 0.0523 and rot.support >= 0.6, rot
    assert 0.053 - 3 * H <= rot.span[0] <= 0.053 and 0.103 <= rot.span[1] <= 0.103 + 3 * H, rot


@pytest.mark.parametrize("n", [1, -1])
def test_star_arm_added_and_removed(star_k, n):
    """fit --add y n: a rotation zone; k + n arms spaced evenly within a degree, each the same
    size as the old ones (area within 3 %, reach within a voxel); the column within the hub
    solid as it was, and as many voxels across above and below the arms; the
    recipe replays bit for bit and predicts the grid."""
    k, c = star_k
    recipe, why = fit(c, None, add={"y": n})
    (zone,) = recipe.edits
    assert isinstance(zone, RotationZone), why
    assert "closed ring" in why[0], why
    out = apply_recipe(c, recipe)
    arms, arms2 = _pieces(c, 0.078, 0.07), _pieces(out, 0.078, 0.07)
    assert len(arms) == k and len(arms2) == k + n, (arms, arms2)
    assert _evenly([a for a, _, _ in arms2], k + n) <= 1.0, arms2
    size = np.median([v for _, v, _ in arms])
    assert all(abs(v - size) <= 0.03 * size for _, v, _ in arms2), arms2
    reach = max(r for _, _, r in arms)
    assert all(abs(r - reach) <= H for _, _, r in arms2), arms2
    assert _same_within(c, out, zone.hub - H)
    for y in (0.3, 0.025):  # the column above the arms, and below them (outside the span)
        j, j2 = (round((y - g.origin[1]) / H) for g in (c, out))
        assert (c.sdf[:, j, :] < 0).sum() == (out.sdf[:, j2, :] < 0).sum() > 0, y
    again = apply_recipe(c, recipe_from_history(out, after=c))
    assert np.array_equal(again.sdf, out.sdf) and np.array_equal(again.rgb, out.rgb)
    assert recipe_shape(c, recipe) == out.shape


def test_chairs_about_a_round_table():
    """Six boxes about a round table: a closed ring of six at 60 degrees; +1 gives seven spaced
    evenly, each as large as before, the top and the column (the hub) as they were (sign,
    the surface within half a voxel); -2 gives four."""
    c = table_and_chairs(6)
    (rot,) = find_rotations(c)
    assert rot.count == 6 and rot.closed and abs(rot.angle - 60) <= 0.5, rot
    assert 0.3 <= rot.hub <= 0.363 and rot.span[1] <= 0.403 + 3 * H, rot
    chairs = _pieces(c, 0.2, 0.1)
    for n in (1, -2):
        out = apply_rotation(c, rot.zone(n))
        got = _pieces(out, 0.2, 0.1)
        assert len(got) == 6 + n and _evenly([a for a, _, _ in got], 6 + n) <= 1.0, got
        size = np.median([v for _, v, _ in chairs])
        assert all(abs(v - size) <= 0.03 * size for _, v, _ in got), got
        assert _same_within(c, out, rot.hub - H)  # the top and its column


def arc(k, step=30.0):
    """A column with ``k`` boxes (0.2 x 0.15 x 0.06) about it, the first at ``PHASE``, each
    next turned by ``step`` degrees: an open arc."""

    def sdf(p):
        d = np.full(len(p), np.inf)
        for m in range(k):
            local = p.copy()
            local[:, [0, 2]] = _turn(p[:, [0, 2]] - [CX, CZ], -(PHASE + m * step))
            d = np.minimum(
                d, shapes.box_sdf(local, (0.153, 0.053, -0.0303), (0.353, 0.203, 0.0303))
            )
        return np.minimum(_cyl(p, 0.0523, 0.0, 0.5), d)

    b = np.array([[CX - 0.36, 0, CZ - 0.36], [CX + 0.36, 0.5, CZ + 0.36]])
    return shapes.grid(sdf, b, voxel_size=H, source="arc of boxes")


def test_open_arc_continued_and_cut_short():
    """Four boxes 30 degrees apart about a column: an open arc of four at 30 degrees (within
    half a degree), the first at its direction; +1 adds a box 30 degrees past the last, as
    large, the others where they were (within a degree); -1 takes the last away."""
    c = arc(4)
    (rot,) = find_rotations(c)
    assert not rot.closed and rot.count == 4 and abs(rot.angle - 30) <= 0.5, rot
    assert abs(rot.phase - PHASE) <= 1.0, rot
    boxes = _pieces(c, 0.1, 0.1)
    size = np.median([v for _, v, _ in boxes])
    for n, want in ((1, [10, 40, 70, 100, 130]), (-1, [10, 40, 70])):
        got = _pieces(apply_rotation(c, rot.zone(n)), 0.1, 0.1)
        assert len(got) == len(want), got
        assert all(abs(a - w) <= 1.0 for (a, _, _), w in zip(got, want, strict=True)), got
        assert all(abs(v - size) <= 0.03 * size for _, v, _ in got), got


def test_rotation_zone_json_and_bad_input():
    """A rotation zone's JSON form parses back to itself; malformed ones, a ring whose angle
    and count disagree and removing every element are refused with one line."""
    z = RotationZone((0.1, -0.2), 72.0, 10.0, 5, True, 0.05, 0.4, (0.0, 0.1), -2)
    assert Recipe.parse({"edits": [z.to_json()]}).edits == (z,)
    assert Recipe.parse(json.loads(json.dumps({"edits": [z.to_json()]}))).edits == (z,)
    good = z.to_json()["rotation"]
    for bad in (
        {"rotation": {k: v for k, v in good.items() if k != "hub"}, "copies": 1},
        {"rotation": {**good, "count": 1}, "copies": 1},
        {"rotation": {**good, "closed": "yes"}, "copies": 1},
        {"rotation": {**good, "span": [0.1]}, "copies": 1},
        {"rotation": good, "copies": 0},
    ):
        with pytest.raises(InputError):
            Recipe.parse({"edits": [bad]})
    c = star(4)
    with pytest.raises(InputError, match="closed ring"):
        apply_rotation(c, RotationZone((CX, CZ), 80.0, 10.0, 4, True, 0.05, 0.4, (0.0, 0.1), 1))
    with pytest.raises(InputError, match="at most 3"):
        apply_rotation(c, RotationZone((CX, CZ), 90.0, 10.0, 4, True, 0.05, 0.4, (0.0, 0.1), -4))
    with pytest.raises(InputError, match="no zone along"):
        apply_recipe(c, [z.to_json(), {"axis": "x", "zone": [0.0, 0.1], "to": 0.2}])


def test_cli_suggest_and_add_an_arm(cli, tmp_path):
    """suggest names the ring; fit --add y 1 and scale --axis y --copies +1 write five arms;
    removing all four is refused with one line and no file."""
    src = tmp_path / "star.csdf.npz"
    save(star(4), src)
    r = cli("suggest", src)
    assert r.returncode == 0, r.stderr
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("rotation:"))
    assert "4 elements" in line and "90.0 degrees" in line and "closed ring" in line, line
    doc = json.loads(cli("suggest", src, "--json", check=True).stdout)
    assert doc["rotation"][0]["count"] == 4
    for args in (("fit", "--add", "y", "1"), ("scale", "--axis", "y", "--copies", "+1")):
        out = tmp_path / f"{args[0]}.csdf.npz"
        r = cli(args[0], src, "-o", out, *args[1:])
        assert r.returncode == 0, r.stderr
        assert "closed ring" in r.stderr, r.stderr
        assert len(_pieces(load(out), 0.078, 0.07)) == 5
    bad = tmp_path / "none.csdf.npz"
    assert_bad_input(cli("fit", src, "-o", bad, "--add", "y", "-4"), "at most 3")
    assert not bad.exists()


@pytest.mark.slow
def test_no_false_rotation_on_real_objects():
    """No rotation on tables, chairs, cabinets and shelves (square and rectangular tops, seats
    and backs are no ring of elements)."""
    for rel in [
        "kenney/table.glb",
        "kenney/chair.glb",
        "kenney/tableCoffee.glb",
        "kenney/bookcaseOpen.glb",
        "kenney/sideTableDrawers.glb",
        "kenney/desk.glb",
        "sweethome3d/squareTable.obj",
        "sweethome3d/table.obj",
        "sweethome3d/chair.obj",
        "sweethome3d/bookcase.obj",
        "sweethome3d/dresser.obj",
        "polyhaven/painted_wooden_cabinet/painted_wooden_cabinet_1k.gltf",
        "polyhaven/wooden_table_02/wooden_table_02_1k.gltf",
        "khronos/SheenChair.glb",
    ]:
        c = import_file(data_path(rel), res=96)
        assert find_rotations(c) == [], rel


def test_cli_copies_in_all_sets_the_ring_count(cli, tmp_path):
    """scale --axis y --copies N with no sign is N elements in all on a ring, as on an element
    group: 5 on a ring of four writes five arms (one added, not five); 4 is no change and is
    refused with one line and no file."""
    src = tmp_path / "star.csdf.npz"
    save(star(4), src)
    out = tmp_path / "five.csdf.npz"
    r = cli("scale", src, "-o", out, "--axis", "y", "--copies", "5")
    assert r.returncode == 0, r.stderr
    assert "add 1 element" in r.stderr, r.stderr
    assert len(_pieces(load(out), 0.078, 0.07)) == 5
    bad = tmp_path / "same.csdf.npz"
    assert_bad_input(
        cli("scale", src, "-o", bad, "--axis", "y", "--copies", "4"), "current one (4)"
    )
    assert not bad.exists()


def test_turned_arms_leave_no_distance_past_the_surface():
    """One more arm of a star base: no stored distance, within 0.2 of the surface, exceeds the
    way to the nearest voxel of the other sign by more than half a voxel (as on the input),
    so a sphere tracer cannot step through an arm that now lies where there was none (off the
    arms' levels the source's own distances would reach 19 voxels past one)."""
    c = star(4)
    (rot,) = find_rotations(c)
    out = apply_rotation(c, rot.zone(1))
    h = out.voxel_size
    inside = out.sdf < 0
    way = np.where(
        inside,
        ndimage.distance_transform_edt(inside),
        ndimage.distance_transform_edt(~inside),
    )
    way = (way - 0.5) * h
    near = way < 0.2
    assert (np.abs(out.sdf) - way)[near].max() <= 0.5 * h + 1e-6
