"""Spiral stairs: repetition by a turn about the vertical and a rise, found and edited.

The analytic stair: a round column, treads (boxes in their own turned frames) each turned by
ANGLE about the column and raised by RISE, and a handrail along the helix (a tube: the distance
to densely sampled helix points less its radius). Judged by geometry measured on the grids:
the treads' top levels and their directions, the column's top, the handrail's pieces.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import assert_bad_input, data_path
from scipy import ndimage
from scipy.spatial import cKDTree

from partscale import shapes
from partscale.csdf import make, save
from partscale.edit import (
    HelixZone,
    Recipe,
    apply_helix,
    apply_recipe,
    recipe_from_history,
    recipe_shape,
)
from partscale.errors import InputError
from partscale.ingest import load as import_file
from partscale.zones import find_helices, find_screws, fit

H = 0.02
N, ANGLE, RISE = 14, 30.0, 0.18
RADIUS, COLUMN = 0.6, 0.08
#: Tread tops lie half a voxel off the voxel centres (a level is then one layer, not two).
LIFT = 0.01


def _turn(d, deg):
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    return np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]], 1)


def _column_top():
    return N * RISE + 0.1


def spiral_sdf(p):
    top = _column_top()
    q = np.stack([np.hypot(p[:, 0], p[:, 2]) - COLUMN, np.abs(p[:, 1] - top / 2) - top / 2], 1)
    d = np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)
    for k in range(N):
        local = p.copy()
        local[:, [0, 2]] = _turn(p[:, [0, 2]], -k * ANGLE)  # the tread's own frame
        y = RISE * (k + 1) + LIFT
        d = np.minimum(d, shapes.box_sdf(local, (0, y - 0.04, -0.11), (RADIUS, y, 0.11)))
    t = np.radians(np.linspace(0, (N - 1) * ANGLE, int((N - 1) * ANGLE * 2) + 1))
    r = RADIUS - 0.05
    rail = np.stack([r * np.cos(t), RISE * (1 + t / math.radians(ANGLE)) + 0.8, r * np.sin(t)], 1)
    dist, _ = cKDTree(rail).query(p)
    return np.minimum(d, dist - 0.025)


@pytest.fixture(scope="module")
def spiral():
    b = np.array([[-RADIUS, 0, -RADIUS], [RADIUS, _column_top() + 0.85, RADIUS]])
    return shapes.grid(spiral_sdf, b, voxel_size=H, source="spiral stair")


def _treads(c):
    """(heights, directions in degrees) of the treads' tops: levels where many voxels of the
    ring between the column and the handrail have solid below and air above."""
    inside = c.sdf < 0
    top = inside[:, :-1] & ~inside[:, 1:]
    x = c.origin[0] + np.arange(c.shape[0]) * c.voxel_size
    z = c.origin[2] + np.arange(c.shape[2]) * c.voxel_size
    r = np.hypot(x[:, None], z[None, :])
    ring = (r > 0.2) & (r < 0.45)
    counts = (top & ring[:, None, :]).sum((0, 2))
    levels = np.flatnonzero(counts > 0.3 * counts.max())
    ys = c.origin[1] + (levels + 0.5) * c.voxel_size
    dirs = []
    for j in levels:
        ij = np.argwhere(top[:, j, :] & ring)
        a = np.arctan2(z[ij[:, 1]], x[ij[:, 0]])
        dirs.append(math.degrees(np.angle(np.exp(1j * a).mean())))
    return ys, np.array(dirs)


def _column_height(c):
    """Top of the solid on the axis (world y, at the zero crossing)."""
    i = round(-c.origin[0] / c.voxel_size)
    k = round(-c.origin[2] / c.voxel_size)
    col = c.sdf[i, :, k]
    j = int(np.flatnonzero(col < 0).max())
    return float(c.origin[1] + (j + col[j] / (col[j] - col[j + 1])) * c.voxel_size)


def _pieces(c):
    """Connected pieces of the solid: (count, top of the second largest: the handrail)."""
    lab, _ = ndimage.label(c.sdf < 0)
    sizes = np.bincount(lab.ravel())
    sizes[0] = 0
    rail = int(np.argsort(sizes)[-2])
    top = np.argwhere(lab == rail)[:, 1].max()
    return int((sizes >= 8).sum()), float(c.origin[1] + top * c.voxel_size)


def test_spiral_step_found(spiral):
    """The step's angle within 0.5 degrees, its rise within 1 %, its axis within 1 % of the
    bounding diagonal; 14 treads counted; the cut between two treads near the middle."""
    (hx,) = find_helices(spiral)
    assert abs(hx.angle - ANGLE) <= 0.5, hx
    assert abs(hx.rise - RISE) <= 0.01 * RISE, hx
    sb = spiral.surface_bounds()
    diag = float(np.linalg.norm(sb[1] - sb[0]))
    assert math.hypot(*hx.center) <= 0.01 * diag, hx
    assert hx.count == N, hx
    tops = RISE * np.arange(1, N + 1) + LIFT
    gap = np.min(np.abs(hx.cut - tops))
    assert H <= gap <= RISE - 0.04 - H, (hx.cut, gap)  # between a tread's top and the next's foot
    # the other sense: the stair mirrored in z turns the other way
    mirrored = make(
        spiral.sdf[:, :, ::-1].copy(), spiral.rgb[:, :, ::-1].copy(), None, spiral.origin, H
    )
    (mx,) = find_helices(mirrored)
    assert abs(mx.angle + ANGLE) <= 0.5 and abs(mx.rise - RISE) <= 0.01 * RISE, mx


@pytest.mark.parametrize("n", [1, -2])
def test_spiral_steps_added_and_removed(spiral, n):
    """fit --add y n: a helix zone; n more treads, every rise equal within a voxel, each tread
    turned by the angle from the one below within 2 degrees (the new top one at the next
    angle); the column longer by n rises within a voxel; the handrail one piece, its top moved
    by n rises within a voxel; the recipe replays bit for bit and predicts the grid."""
    recipe, why = fit(spiral, None, add={"y": n})
    (zone,) = recipe.edits
    assert isinstance(zone, HelixZone), why
    assert "spiral stair" in why[0], why
    out = apply_recipe(spiral, recipe)
    ys = _treads(spiral)[0]
    ys2, dirs2 = _treads(out)
    assert len(ys) == N and len(ys2) == N + n, (len(ys), len(ys2))
    assert np.abs(np.diff(ys2) - RISE).max() <= H, np.diff(ys2)
    turns = (np.diff(dirs2) + 180) % 360 - 180
    assert np.abs(turns - ANGLE).max() <= 2.0, turns
    assert abs(((dirs2[-1] - (N - 1 + n) * ANGLE) + 180) % 360 - 180) <= 2.0, dirs2[-1]
    assert abs(_column_height(out) - _column_height(spiral) - n * RISE) <= H
    count, top = _pieces(spiral)
    count2, top2 = _pieces(out)
    assert count2 == count == 2, (count, count2)  # the stair and its handrail
    assert abs(top2 - top - n * RISE) <= H, (top, top2)
    again = apply_recipe(spiral, recipe_from_history(out, after=spiral))
    assert np.array_equal(again.sdf, out.sdf) and np.array_equal(again.rgb, out.rgb)
    assert recipe_shape(spiral, recipe) == out.shape


def test_helix_zone_json_and_bad_input():
    """A helix zone's JSON form parses back to itself; malformed ones and a zero turn are
    refused with one line."""
    z = HelixZone((0.1, -0.2), 30.0, 0.18, 1.3, -2)
    assert Recipe.parse({"edits": [z.to_json()]}).edits == (z,)
    assert Recipe.parse(json.loads(json.dumps({"edits": [z.to_json()]}))).edits == (z,)
    for bad in (
        {"helix": {"center": [0, 0], "angle": 30, "rise": 0.1}, "copies": 1},
        {"helix": {"center": [0], "angle": 30, "rise": 0.1, "cut": 1}, "copies": 1},
        {"helix": {"center": [0, 0], "angle": 30, "rise": 0.1, "cut": 1}, "copies": 0},
    ):
        with pytest.raises(InputError):
            Recipe.parse({"edits": [bad]})
    post = shapes.box((-0.1, 0, -0.1), (0.1, 1.0, 0.1), voxel_size=0.05)
    with pytest.raises(InputError, match="angle"):
        apply_helix(post, HelixZone((0.0, 0.0), 0.0, 0.2, 0.5, 1))
    with pytest.raises(InputError, match="no zone along"):
        apply_recipe(post, [z.to_json(), {"axis": "y", "zone": [0.2, 0.4], "to": 0.5}])


def test_cli_suggest_and_fit_add_a_step(spiral, cli, tmp_path):
    """suggest names the spiral stair's step; fit --add y 1 writes one more tread; removing
    all treads is refused with one line."""
    src = tmp_path / "spiral.csdf.npz"
    save(spiral, src)
    r = cli("suggest", src)
    assert r.returncode == 0, r.stderr
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("helix:"))
    assert "30.0 degrees" in line and "14 steps" in line, line
    out = tmp_path / "more.csdf.npz"
    r = cli("fit", src, "-o", out, "--add", "y", "1")
    assert r.returncode == 0, r.stderr
    assert "spiral stair" in r.stderr
    from partscale.csdf import load

    assert len(_treads(load(out))[0]) == N + 1
    bad = tmp_path / "none.csdf.npz"
    assert_bad_input(cli("fit", src, "-o", bad, "--add", "y", f"-{N}"), "at most")
    assert not bad.exists()


@pytest.mark.slow
def test_no_false_helix_on_real_objects():
    """No helix on tables, chairs, a round table and a stool (a pure turn is no helix),
    cabinets and bookcases; straight flights keep their diagonal step and show no helix."""
    for rel in [
        "kenney/table.glb",
        "kenney/chair.glb",
        "kenney/chairDesk.glb",
        "kenney/tableRound.glb",
        "kenney/tableCross.glb",
        "kenney/bookcaseOpen.glb",
        "kenney/sideTableDrawers.glb",
        "kenney/lampRoundFloor.glb",
        "sweethome3d/railing.obj",
        "polyhaven/painted_wooden_stool/painted_wooden_stool_1k.gltf",
    ]:
        c = import_file(data_path(rel), res=96)
        assert find_helices(c) == [], rel
    for rel in ["kenney/stairs.glb", "sweethome3d/staircase.obj"]:
        c = import_file(data_path(rel), res=128)  # as the flights' own tests find their step
        assert find_helices(c) == [], rel
        assert find_screws(c), rel
        recipe, _ = fit(c, None, add={"y": 1})
        assert not isinstance(recipe.edits[0], HelixZone), rel


def test_count_in_all_sets_the_spirals_step_count(spiral):
    """add_axis with in_all (scale --copies N, no sign): N steps in all, so N + 1 on a spiral
    of N steps is one more step and N - 2 two fewer; N itself is refused (no change)."""
    from partscale.zones import add_axis

    for total, n in ((N + 1, 1), (N - 2, -2)):
        (zone,), _ = add_axis(spiral, 1, total, in_all=True)
        assert isinstance(zone, HelixZone) and zone.copies == n, zone
    with pytest.raises(InputError, match=f"current one \\({N}\\)"):
        add_axis(spiral, 1, N, in_all=True)
