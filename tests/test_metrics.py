"""The evaluation's metrics on constructed CSDFs whose right answer is known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from partscale import shapes
from partscale.edit import Edit, ResolvedEdit, apply_edit, resolve_edit
from partscale.errors import InputError
from partscale.evaluate import metrics as M

# voxel size of the constructed cases: incommensurate with their sizes, so no face lies exactly on
# a row of voxel centres (a degenerate case real objects do not have)
H = 0.0193


def _stretch_geo(mode="stretch"):
    # a 1.0-long box, zone [0.3, 0.7] moved to end at 0.9: 1.2 long after
    return ResolvedEdit(0, 0.3, 0.7, 0.9, 0.0, 1.0, mode)


def test_thickness_is_exact_for_a_box():
    a = shapes.box((0, 0, 0), (1.0, 0.2, 0.3), voxel_size=H)
    for axis, size in enumerate((1.0, 0.2, 0.3)):
        t = M.thickness(a, axis)
        # sub-voxel chord ends: exact through faces; lines grazing an edge (the sdf is not linear
        # there) come out at most a voxel short
        assert np.median(t) == pytest.approx(size, abs=1e-3 * H)
        assert t.max() < size + 1e-3 * H and t.min() > size - H


def test_box_stretched_keeps_its_thickness():
    a = shapes.box((0, 0, 0), (1.0, 0.2, 0.3), voxel_size=H)
    b = shapes.box((0, 0, 0), (1.2, 0.2, 0.3), voxel_size=H)  # the stretch's exact result
    m = M.evaluate(a, b, _stretch_geo())
    # no element lies wholly on one side of a zone plane along x: nothing to compare there
    assert math.isnan(m["prop_in"]) and math.isnan(m["prop_out"])
    # the far end moved by 0.2, not a whole number of voxels: marching cubes cuts its edges
    # differently (rigidity within 0.6 voxel), the solid itself is exactly where it should be
    assert m["length_err"] < 0.01 and m["rigid_err"] < 0.6
    assert m["sdf_err_mean"] < 0.05 and m["watertight"] and m["pieces"] == 1
    for axis in (1, 2):
        assert np.median(M.thickness(b, axis)) == pytest.approx((0.2, 0.3)[axis - 1], abs=1e-4)


def _dumbbell(length, plate):
    """Two end plates ``plate`` thick along x joined by a thin bar: a table seen from the front."""
    boxes = [
        ((0, 0, 0), (plate, 0.4, 0.4)),
        ((plate, 0.15, 0.15), (length - plate, 0.25, 0.25)),
        ((length - plate, 0, 0), (length, 0.4, 0.4)),
    ]
    return shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes), ((0, 0, 0), (length, 0.4, 0.4)), voxel_size=H
    )


def test_plates_outside_the_zone_keep_their_thickness_when_stretched_and_scale_globally():
    a = _dumbbell(1.0, 0.1)
    stretched = M.evaluate(a, _dumbbell(1.2, 0.1), _stretch_geo())
    assert stretched["prop_out"] < 1e-3 and stretched["rigid_err"] < 0.6
    scaled = M.evaluate(a, _dumbbell(1.2, 0.12), _stretch_geo("global"))
    assert scaled["prop_out"] == pytest.approx(0.2, abs=0.01)  # plates 1.2 times as thick


def test_box_scaled_globally_has_thickness_scaled_by_the_factor():
    # a plate thin along x, scaled globally by 1.5 along x
    a = shapes.box((0, 0, 0), (0.2, 0.6, 0.6), voxel_size=H)
    b = shapes.box((0, 0, 0), (0.3, 0.6, 0.6), voxel_size=H)
    ta, tb = np.median(M.thickness(a, 0)), np.median(M.thickness(b, 0))
    assert tb / ta == pytest.approx(1.5, abs=0.01)
    assert M.distribution_error(M.thickness(a, 0), M.thickness(b, 0)) == pytest.approx(
        0.5, abs=0.01
    )


def _comb(n, *, stretched_tooth=None):
    """Teeth 0.1 wide every 0.3 along x; optionally tooth 1 stretched x2 by zone [0.25, 0.55]."""
    if stretched_tooth is None:
        return shapes.bars(n, width=0.1, gap=0.2, height=0.4, depth=0.2, voxel_size=H)[0]
    boxes = []
    for m in range(n):
        lo, hi = 0.3 * m, 0.3 * m + 0.1
        if m == 1:
            lo, hi = 0.25 + 2 * (lo - 0.25), 0.25 + 2 * (hi - 0.25)
        elif m > 1:
            lo, hi = lo + 0.3, hi + 0.3
        boxes.append(((lo, 0, 0), (hi, 0.4, 0.2)))
    bounds = (boxes[0][0], boxes[-1][1])
    return shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), bounds, voxel_size=H)


COMB_ZONE = (0.25, 0.55, 0.85)  # one period around tooth 1, grown by one period


def test_comb_spacing_is_measured_right_before_and_after_tiling():
    a = _comb(6)
    b = _comb(7)  # the exact tiling result: 2 copies of the period, each at scale 1
    pa, pb = M.pitches(a, 0), M.pitches(b, 0)
    assert np.median(pa) == pytest.approx(0.3, abs=1e-3 * H)
    assert np.median(pb) == pytest.approx(0.3, abs=1e-3 * H)
    assert np.all(np.abs(pa - 0.3) < H) and np.all(np.abs(pb - 0.3) < H)
    geo = ResolvedEdit(0, *COMB_ZONE, 0.0, 1.6, "tile")
    m = M.evaluate(a, b, geo)
    assert m["pieces"] == m["pieces_expected"] == 7  # the tooth in the zone, copied once
    assert m["spacing_err"] < 0.01
    assert m["prop_in"] < 0.01 and m["prop_out"] < 0.01
    assert m["rigid_err"] < 0.6 and m["length_err"] < 0.01


def test_comb_stretched_has_spacing_and_proportion_errors():
    a = _comb(6)
    b = _comb(6, stretched_tooth=1)
    geo = ResolvedEdit(0, *COMB_ZONE, 0.0, 1.6, "stretch")
    m = M.evaluate(a, b, geo)
    # tooth 1 is twice as thick; its neighbours' pitches become 0.4 and 0.5 instead of 0.3
    assert m["prop_in"] == pytest.approx(1.0, abs=0.05)
    assert m["prop_out"] < 1e-3 and m["rigid_err"] < 0.6
    assert m["spacing_err"] == pytest.approx(0.5, abs=0.05)


def test_comb_scaled_globally_has_every_spacing_scaled():
    a = _comb(6)
    f = 1.9 / 1.6
    boxes = [((0.3 * m * f, 0, 0), ((0.3 * m + 0.1) * f, 0.4, 0.2)) for m in range(6)]
    b = shapes.grid(lambda p: shapes.boxes_sdf(p, boxes), (boxes[0][0], boxes[-1][1]), voxel_size=H)
    geo = ResolvedEdit(0, *COMB_ZONE, 0.0, 1.6, "global")
    m = M.evaluate(a, b, geo)
    assert m["spacing_err"] == pytest.approx(f - 1, abs=0.02)
    assert m["prop_out"] == pytest.approx(f - 1, abs=0.03)
    # tooth 2 lands at 0.71 instead of the rigid 0.90: ten voxels off
    assert m["rigid_err"] > 5
    assert m["length_err"] < 0.01


def test_no_repeated_elements_gives_no_spacing():
    a = shapes.box((0, 0, 0), (1.0, 0.2, 0.3), voxel_size=H)
    b = shapes.box((0, 0, 0), (1.2, 0.2, 0.3), voxel_size=H)
    assert math.isnan(M.evaluate(a, b, _stretch_geo())["spacing_err"])


def _colour_box(jump_at=None):
    def colour(p):
        x = p[:, 0]
        if jump_at is None:  # a gentle ramp: about 5 levels per voxel
            r = 60 + 150 * np.clip(x, 0, 1)
            return np.stack([r, np.full_like(r, 100), 255 - r], axis=1)
        red = x < jump_at
        return np.where(red[:, None], [220, 40, 40], [40, 40, 220])

    return shapes.grid(
        lambda p: shapes.box_sdf(p, (0, 0, 0), (1.0, 0.2, 0.3)),
        ((0, 0, 0), (1.0, 0.2, 0.3)),
        voxel_size=H,
        color=colour,
    )


def test_seam_with_a_colour_jump_is_detected_and_a_smooth_one_is_not():
    smooth = _colour_box()
    jump = _colour_box(jump_at=0.51)
    geo = ResolvedEdit(0, 0.3, 0.51, 0.51, 0.0, 1.0, "stretch")  # seams at 0.3 and 0.51
    colour_jump, shape_jump = M.seam_jumps(smooth, jump, geo)
    assert colour_jump > 200  # |(220,40,40) - (40,40,220)| = 255
    assert shape_jump < 1e-3  # same geometry
    colour_smooth, _ = M.seam_jumps(smooth, smooth, geo)
    assert colour_smooth < 1
    # a join between tile copies is compared with the original's median jump (none on a ramp)
    tile = ResolvedEdit(0, 0.3, 0.51, 0.51, 0.0, 1.0, "tile")
    assert M.seam_jumps(smooth, smooth, tile)[0] < 1


def test_seam_with_a_shape_jump_is_detected():
    a = shapes.box((0, 0, 0), (1.0, 0.2, 0.3), voxel_size=H)
    step = [((0, 0, 0), (0.51, 0.2, 0.3)), ((0.51, 0, 0), (1.0, 0.1, 0.3))]
    b = shapes.grid(lambda p: shapes.boxes_sdf(p, step), ((0, 0, 0), (1.0, 0.2, 0.3)), voxel_size=H)
    geo = ResolvedEdit(0, 0.3, 0.51, 0.51, 0.0, 1.0, "stretch")
    assert M.seam_jumps(a, b, geo)[1] > 0.5
    assert M.seam_jumps(a, a, geo)[1] < 1e-3


def test_distance_error_sees_a_stretched_sdf_that_was_not_re_evaluated():
    a = shapes.box((0, 0, 0), (1.0, 0.2, 0.3), voxel_size=H)
    mean, p99 = M.distance_error(a, M.to_mesh(a))
    assert mean < 0.05 and p99 < 0.6  # marching cubes chamfers the edges
    # the same surface, distances scaled by 2 (what a stretch without re-evaluation does)
    b = a.replace(sdf=a.sdf * 2)
    mean, p99 = M.distance_error(b, M.to_mesh(b))
    assert mean > 0.5 and p99 > 1.5


def test_pieces_and_watertightness():
    two = shapes.grid(
        lambda p: shapes.boxes_sdf(
            p, [((0, 0, 0), (0.2, 0.2, 0.2)), ((0.4, 0, 0), (0.6, 0.2, 0.2))]
        ),
        ((0, 0, 0), (0.6, 0.2, 0.2)),
        voxel_size=H,
    )
    watertight, pieces = M.topology(M.to_mesh(two))
    assert watertight and pieces == 2


def test_resolve_edit_rejects_a_zone_outside_the_solid():
    a = shapes.box((0, 0, 0), (1.0, 0.2, 0.3), voxel_size=H)
    geo = resolve_edit(a, Edit("x", "25%", "75%", "100%"))
    assert (geo.start, geo.end, geo.given_dest) == pytest.approx((0.25, 0.75, 1.0), abs=1e-6)
    # whole voxels, as edits do: 0.25 / H = 12.95 voxels
    assert (geo.dest - geo.end) / H == pytest.approx(13, abs=1e-9)
    assert geo.shift_voxels(H) == 13 and geo.mode == "stretch"
    with pytest.raises(InputError, match="inside the solid"):
        resolve_edit(a, Edit("x", "50%", "130%", "150%"))
    with pytest.raises(InputError, match="start < end"):
        resolve_edit(a, Edit("x", "60%", "40%", "80%"))


def test_comb_tiled_by_apply_edit_keeps_its_spacing():
    a = _comb(6)
    edit = Edit("x", COMB_ZONE[0], COMB_ZONE[1], COMB_ZONE[2], "tile")
    geo = resolve_edit(a, edit)
    m = M.evaluate(a, apply_edit(a, edit), geo)
    assert m["spacing_err"] < 0.05
    assert m["prop_in"] < 0.1 and m["prop_out"] < 0.05
    assert m["rigid_err"] < 0.5 and m["length_err"] < 0.5


def test_box_stretched_by_apply_edit_keeps_its_thickness():
    a = shapes.box((0, 0, 0), (1.0, 0.2, 0.3), voxel_size=H)
    edit = Edit("x", 0.3, 0.7, 0.9, "stretch")
    b = apply_edit(a, edit)
    m = M.evaluate(a, b, resolve_edit(a, edit))
    assert m["length_err"] < 0.5 and m["sdf_err_mean"] < 0.1 and m["rigid_err"] < 0.6
    for axis in (1, 2):
        assert np.median(M.thickness(b, axis)) == pytest.approx((0.2, 0.3)[axis - 1], abs=0.01 * H)


def test_plates_stretched_by_apply_edit_keep_their_thickness():
    a = _dumbbell(1.0, 0.1)
    edit = Edit("x", 0.3, 0.7, 0.9, "stretch")
    m = M.evaluate(a, apply_edit(a, edit), resolve_edit(a, edit))
    assert m["prop_out"] < 0.01 and m["length_err"] < 0.5


def _slanted_leg():
    """A leg 0.1 thick leaning 0.3 along x per unit of height (y in [0, 1]): nothing repeats."""

    def sdf(p):
        slab = (np.abs(p[:, 0] - 0.3 * p[:, 1] - 0.05) - 0.05) / np.hypot(1.0, 0.3)
        span = shapes.box_sdf(p, (-1.0, 0.0, 0.0), (2.0, 1.0, 0.2))
        return np.maximum(slab, span)

    return shapes.grid(sdf, ((0, 0, 0), (0.4, 1.0, 0.2)), voxel_size=H)


def test_tiling_a_slanted_leg_shows_a_seam_and_stretching_does_not():
    a = _slanted_leg()
    result = {}
    for mode in ("stretch", "tile"):
        edit = Edit("y", 0.3, 0.5, 0.7, mode)  # two copies of the slab
        result[mode] = M.evaluate(a, apply_edit(a, edit), resolve_edit(a, edit))
    # each copy starts back where the zone started: the leg jumps 0.3 * 0.2 = 0.06 (3 voxels)
    assert result["tile"]["seam_shape"] > 1.0
    assert result["stretch"]["seam_shape"] < 0.3
