"""Selective scaling on real objects from ../shared/data: proportions kept, colours without seams.

Objects are imported at res 64 (a few voxels per board or leg; crossings are measured to sub-voxel
precision by linear interpolation of the distance).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import data_path
from scipy import ndimage

from partscale import shapes
from partscale.edit import scale
from partscale.surface import to_mesh

ingest = pytest.importorskip("partscale.ingest", reason="the import stage is not merged yet")


@pytest.fixture(scope="module")
def bookcase():
    return ingest.load(data_path("kenney/bookcaseOpen.glb"), res=64)


@pytest.fixture(scope="module")
def table():
    return ingest.load(data_path("kenney/table.glb"), res=64)


def crossings_along(c, axis, line):
    """World positions where the surface crosses a grid line (``line``: the other two indices)."""
    idx = list(line)
    idx.insert(axis, slice(None))
    s = c.sdf[tuple(idx)].astype(np.float64)
    x = c.axis_coords(axis)
    ch = np.flatnonzero((s[:-1] <= 0) != (s[1:] <= 0))
    return x[ch] + s[ch] / (s[ch] - s[ch + 1]) * c.voxel_size


def boards(c):
    """(thicknesses, starts) of the horizontal boards met by the bookcase's central vertical line."""
    pos = crossings_along(c, 1, (c.shape[0] // 2, c.shape[2] // 2))
    assert len(pos) % 2 == 0
    return pos[1::2] - pos[0::2], pos[0::2]


# -- proportions -------------------------------------------------------------------------------


def test_bookcase_twice_as_tall_by_tiling_one_shelf_period(bookcase):
    thick, starts = boards(bookcase)
    assert len(thick) == 4
    period = float(np.mean(np.diff(starts)))
    # one shelf period, from the middle of board 0 to the middle of board 1
    start = starts[0] + thick[0] / 2
    end = start + period
    lo, hi = bookcase.surface_bounds()[:, 1]
    # twice as many shelves: four more periods, 2.09 times as tall (exactly 2.00 would scale each
    # of the five copies by 0.93, the price of fitting a length that is not whole periods)
    dest = end + 4 * period
    out = scale(bookcase, axis="y", zone=(start, end), to=dest, mode="tile")
    new_lo, new_hi = out.surface_bounds()[:, 1]
    assert (new_hi - new_lo) / (hi - lo) == pytest.approx(2.09, abs=0.02)
    t2, s2 = boards(out)
    assert len(t2) == 8
    assert np.abs(t2 / np.mean(thick) - 1).max() <= 0.05, t2
    assert np.abs(np.diff(s2) / period - 1).max() <= 0.05, np.diff(s2)
    # global scaling to the same height doubles them
    g = scale(bookcase, axis="y", zone=(start, end), to=dest, mode="global")
    tg, sg = boards(g)
    assert len(tg) == 4
    assert np.min(np.diff(sg)) / period > 1.9 and np.min(tg) / np.mean(thick) > 1.8


def leg_widths(c, height=0.3):
    """Median x-width of each leg (sorted by position) in the horizontal slice at ``height``."""
    j = int(np.argmin(np.abs(c.axis_coords(1) - height)))
    lab, _ = ndimage.label(c.sdf[:, j, :] <= 0)
    out = []
    for sl in ndimage.find_objects(lab):
        widths = []
        for k in range(sl[1].start, sl[1].stop):
            pos = crossings_along(c, 0, (j, k))
            pos = pos[(pos >= c.axis_coords(0)[sl[0].start] - c.voxel_size)]
            pos = pos[(pos <= c.axis_coords(0)[sl[0].stop - 1] + c.voxel_size)]
            if len(pos) == 2:
                widths.append(pos[1] - pos[0])
        out.append((c.axis_coords(0)[sl[0].start], float(np.median(widths))))
    return [w for _, w in sorted(out)]


def test_table_forty_percent_longer_keeps_leg_thickness(table):
    lo, hi = table.surface_bounds()[:, 0]
    before = leg_widths(table)
    assert len(before) == 4
    start, end = -0.6, 0.6  # between the legs
    dest = end + 0.4 * (hi - lo)
    out = scale(table, axis="x", zone=(start, end), to=dest)
    new_lo, new_hi = out.surface_bounds()[:, 0]
    assert (new_hi - new_lo) / (hi - lo) == pytest.approx(1.4, abs=0.5 * table.voxel_size)
    after = leg_widths(out)
    assert len(after) == 4
    assert np.abs(np.subtract(after, before)).max() <= table.voxel_size, (before, after)
    # global scaling fattens them by more than a voxel
    g = leg_widths(scale(table, axis="x", zone=(start, end), to=dest, mode="global"))
    assert np.min(np.subtract(g, before)) > table.voxel_size
    mesh = to_mesh(out)
    assert mesh.is_watertight


# -- colour ------------------------------------------------------------------------------------


def seam_colour_check(c, axis, planes):
    """(p99 colour step across the planes, p99 colour step elsewhere) over surface mesh edges."""
    mesh = to_mesh(c)
    e = mesh.edges_unique
    col = mesh.visual.vertex_colors[:, :3].astype(np.float64)
    step = np.abs(col[e[:, 0]] - col[e[:, 1]]).max(axis=1)
    x = mesh.vertices[:, axis]
    a, b = np.minimum(x[e[:, 0]], x[e[:, 1]]), np.maximum(x[e[:, 0]], x[e[:, 1]])
    across = np.zeros(len(e), bool)
    far = np.ones(len(e), bool)
    for p in planes:
        across |= (a <= p) & (b >= p)
        far &= (np.abs(a - p) > 2 * c.voxel_size) & (np.abs(b - p) > 2 * c.voxel_size)
    assert across.sum() > 20
    return np.percentile(step[across], 99), np.percentile(step[far], 99)


def test_no_colour_seam_at_zone_planes_and_tile_seams(bookcase, table):
    # the table: a stretch between the legs
    out = scale(table, axis="x", zone=(-0.6, 0.6), to=1.3)
    d = out.meta["history"][-1]["to_snapped"]
    seam, elsewhere = seam_colour_check(out, 0, [-0.6, d])
    assert seam <= elsewhere, (seam, elsewhere)
    # the bookcase: one shelf period tiled three times
    thick, starts = boards(bookcase)
    period = float(np.mean(np.diff(starts)))
    s = starts[0] + thick[0] / 2
    out = scale(bookcase, axis="y", zone=(s, s + period), to=s + 3 * period, mode="tile")
    d = out.meta["history"][-1]["to_snapped"]
    planes = [s + m * (d - s) / 3 for m in range(4)]
    seam, elsewhere = seam_colour_check(out, 1, planes)
    assert seam <= elsewhere, (seam, elsewhere)


def test_no_colour_seam_on_a_colour_gradient():
    def rainbow(p):
        t = (p - p.min(axis=0)) / np.ptp(p, axis=0)
        return np.stack([40 + 180 * t[:, 0], 60 + 150 * t[:, 1], 200 - 150 * t[:, 2]], 1)

    c = shapes.grid(
        lambda p: shapes.sphere_sdf(p, (0, 0, 0), 0.5),
        ((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)),
        voxel_size=0.02,
        color=rainbow,
    )
    out = scale(c, axis="x", zone=(-0.2, 0.1), to=0.4)
    seam, elsewhere = seam_colour_check(out, 0, [-0.2, 0.4])
    assert seam <= elsewhere, (seam, elsewhere)


def test_no_colour_seam_between_tiles_of_a_periodic_pattern():
    w, g, h = 0.12, 0.08, 0.02
    p = w + g
    boxes = [((m * p, 0, 0), (m * p + w, 0.3, 0.2)) for m in range(4)]

    def stripes(q):  # colour varies within each bar, the same in every bar
        t = np.mod(q[:, 0], p) / p
        return np.stack([40 + 200 * t, 90 + 100 * q[:, 1], 150 - 100 * t], 1)

    c = shapes.grid(
        lambda q: shapes.boxes_sdf(q, boxes),
        (boxes[0][0], boxes[-1][1]),
        voxel_size=h,
        color=stripes,
    )
    s, e = w / 2, w / 2 + p
    out = scale(c, axis="x", zone=(s, e), to=e + 2 * p, mode="tile")
    d = out.meta["history"][-1]["to_snapped"]
    seam, elsewhere = seam_colour_check(out, 0, [s + m * (d - s) / 3 for m in range(4)])
    assert elsewhere > 0 and seam <= elsewhere, (seam, elsewhere)


def test_table_outside_the_zone_is_rigid(table):
    h = table.voxel_size
    start, end, dest = -0.6, 0.6, 1.3
    x = table.axis_coords(0)
    for mode, ok in (("stretch", True), ("tile", True), ("global", False)):
        out = scale(table, axis="x", zone=(start, end), to=dest, mode=mode)
        shift = out.shape[0] - table.shape[0]
        before = np.flatnonzero(x < start - h)
        after = np.flatnonzero(x > end + h)
        a = np.concatenate([table.sdf[before], table.sdf[after]])
        b = np.concatenate([out.sdf[before], out.sdf[after + shift]])
        band = np.abs(a) <= 3 * h
        p99 = np.percentile(np.abs(a - b)[band], 99) / h
        assert (p99 <= 0.05) == ok, (mode, p99)


@pytest.mark.parametrize("mode", ["stretch", "tile"])
def test_bookcase_distances_around_the_slab_match_a_full_recomputation(bookcase, mode):
    # The selective re-evaluation (only where something could have changed) against a
    # re-evaluation of the whole band of the final surface; the naive baseline fails it.
    from partscale.edit import naive_edit, reevaluate

    thick, starts = boards(bookcase)
    s = starts[0] + thick[0] / 2
    e = s + float(np.mean(np.diff(starts)))
    edit = {"axis": "y", "zone": [s, e], "to": s + 2.3 * (e - s), "mode": mode}
    h = bookcase.voxel_size
    for which, out, ok in (
        ("ours", scale(bookcase, axis="y", zone=(s, e), to=edit["to"], mode=mode), True),
        ("naive", naive_edit(bookcase, edit), False),
    ):
        ref = reevaluate(out)
        y = out.axis_coords(1)
        d = out.meta["history"][-1]["to_snapped"]
        near = ((y >= s - 3 * h) & (y <= d + 3 * h))[None, :, None] & (np.abs(ref.sdf) <= 3 * h)
        err = np.abs(out.sdf - ref.sdf)[near] / h
        med, p99 = np.median(err), np.percentile(err, 99)
        assert (med <= 0.05 and p99 <= 0.5) == ok, (which, med, p99)


@pytest.mark.parametrize("copies", [2, 3])
def test_tile_with_a_plane_just_above_a_thin_shelf_keeps_every_shelf(copies):
    """Sweet Home 3D's bookcase at 128: shelves about one voxel thick. A zone from the middle of a
    gap to 0.2 voxel above a shelf's top holds two shelves; each copy adds exactly two."""
    c = ingest.load(data_path("sweethome3d/bookcase.obj"), res=128)
    h = c.voxel_size
    y = c.axis_coords(1)

    def shelves(x):
        col = x.sdf[x.shape[0] // 2, :, x.shape[2] // 2] <= 0
        edges = np.flatnonzero(np.diff(col.astype(np.int8)))
        return edges[0::2] + 1, edges[1::2]  # first and last inside index of each shelf

    first, last = shelves(c)
    assert len(first) == 8 and (last - first).max() <= 1  # thin: one or two voxels inside
    start = y[(last[1] + first[2]) // 2]
    top = y[last[3]] + h * c.sdf[c.shape[0] // 2, last[3], c.shape[2] // 2] / (
        c.sdf[c.shape[0] // 2, last[3], c.shape[2] // 2]
        - c.sdf[c.shape[0] // 2, last[3] + 1, c.shape[2] // 2]
    )  # the shelf's top surface (linear zero crossing)
    end = top + 0.2 * h
    out = scale(c, axis="y", zone=(start, end), to=end + (copies - 1) * (end - start), mode="tile")
    assert len(shelves(out)[0]) == 8 + 2 * (copies - 1)
