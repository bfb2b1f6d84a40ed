"""Zones and fit on a completed scan: its voxel-scale roughness does not break its constant
runs apart, and its lengths are reached by stretching, not by repeating what noise made look
alike."""

import numpy as np
import pytest
from conftest import data_path
from scipy import ndimage

from partscale import edit, ingest, shapes, zones
from partscale.complete import complete
from partscale.csdf import make
from partscale.errors import InputError
from partscale.evaluate import virtual_scan

H = 0.01


def _rough_block(scan: bool):
    """A block 30 x 60 x 20 voxels whose surface is carved as a scan's: its boundary wanders by
    about a voxel (noise correlated over two voxels), the distances those of the voxel solid;
    marked a completion where ``scan``."""
    clean = shapes.box((0.0, 0.0, 0.0), (0.3, 0.6, 0.2), voxel_size=H, margin=4)
    rng = np.random.default_rng(7)
    wobble = ndimage.gaussian_filter(rng.normal(size=clean.shape), 2.0)
    wobble *= 0.9 / wobble.std()
    solid = clean.sdf / H + wobble < 0
    sdf = np.where(
        solid,
        -(ndimage.distance_transform_edt(solid) - 0.5),
        ndimage.distance_transform_edt(~solid) - 0.5,
    )
    meta = {"units": "m", "completion": {"observed": 0.5}} if scan else {"units": "m"}
    return make(sdf * H, clean.rgb, None, clean.origin, H, meta)


def test_rough_scan_keeps_its_constant_run():
    # the block's 60 layers along y are one constant run; the noise alone breaks it apart
    # when neighbouring layers are compared as a mesh's are (the block not marked a scan)
    def longest(c):
        return max((b - a + 1 for a, b in zones.calm_runs(zones.profile(c, "y"))), default=0)

    assert longest(_rough_block(scan=False)) < 30
    assert longest(_rough_block(scan=True)) >= 50


def test_fit_on_rough_scan_stretches_its_body():
    block = _rough_block(scan=True)
    recipe, why = zones.fit(block, ["=", "+20cm", "="])
    assert [e.mode for e in recipe.edits] == ["stretch"]
    e = recipe.edits[0]
    # the body (0 to 60 cm), more than half of it, not a few layers between noise
    assert 0.0 <= e.start and e.end <= 0.6 and e.end - e.start >= 0.3
    assert any("completed scan" in w and "--add" in w for w in why)
    # the same surface fitted as a mesh's: noise read as elements, a false period tiled
    recipe, _ = zones.fit(_rough_block(scan=False), ["=", "+20cm", "="])
    assert [e.mode for e in recipe.edits] != ["stretch"]


@pytest.fixture(scope="module")
def table_scan():
    mesh = ingest.load_mesh(data_path("sweethome3d/table.obj"))
    frames = virtual_scan(mesh, azimuths=(147.0, 267.0, 27.0), elevation=15.0)
    return complete(frames, res=96, upright=True)


def test_fit_on_completed_table_stretches_between_legs(table_scan):
    # three views of Sweet Home 3D's table (1.5 m), completed, made 20 % longer along its long
    # axis: the top and rails between the legs stretch, the legs keep their width, nothing
    # repeats (before, its noise broke every constant run: refused, or a false period tiled)
    sb = table_scan.surface_bounds()
    ext = sb[1] - sb[0]
    axis = "x" if ext[0] >= ext[2] else "z"
    a = "xyz".index(axis)
    size = ["="] * 3
    size[a] = "120%"
    recipe, why = zones.fit(table_scan, size)
    assert recipe.edits and all(e.mode == "stretch" for e in recipe.edits)
    assert any(w.startswith("a completed scan") for w in why)
    # the legs: the outer tenth at each end along the axis stays out of every zone
    for e in recipe.edits:
        assert e.start >= sb[0, a] + 0.1 * ext[a] and e.end <= sb[1, a] - 0.1 * ext[a]
    longer = edit.apply_recipe(table_scan, recipe)
    got = longer.surface_bounds()[1, a] - longer.surface_bounds()[0, a]
    assert abs(got - 1.2 * ext[a]) <= 1.5 * table_scan.voxel_size


def test_rough_scan_has_no_elements_made_of_noise():
    # "one more element" on a plain body: the scan's bumps are no grooves between elements
    # (read as a mesh's, the same surface holds "3 alike elements" along y)
    assert zones.find_elements(_rough_block(scan=False), "y").groups
    assert not zones.find_elements(_rough_block(scan=True), "y").groups
    with pytest.raises(InputError, match="found none"):
        zones.fit(_rough_block(scan=True), add={"y": 1})
