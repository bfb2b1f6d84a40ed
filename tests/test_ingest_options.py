"""Import options a DCC user needs: --up, --units, --scale (recorded in meta)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from partscale import ingest


@pytest.fixture(scope="module")
def table_mesh():
    from conftest import data_path

    return trimesh.load(data_path("kenney/table.glb"), force="mesh")


def _extent(c) -> np.ndarray:
    b = c.surface_bounds()
    return b[1] - b[0]


@pytest.fixture(scope="module")
def reference(table_mesh, tmp_path_factory):
    p = tmp_path_factory.mktemp("ref") / "y.glb"
    table_mesh.export(p)
    return ingest.load(p, res=48)


def test_up_z_file_comes_in_y_up(table_mesh, reference, tmp_path):
    zup = table_mesh.copy()
    # a Z-up exporter writes (x, y, z)_yup as (x, -z, y)
    zup.vertices = table_mesh.vertices[:, [0, 2, 1]] * (1, -1, 1)
    p = tmp_path / "z.glb"
    zup.export(p)
    plain = ingest.load(p, res=48)
    fixed = ingest.load(p, res=48, up="z")
    h = reference.voxel_size
    assert np.abs(_extent(fixed) - _extent(reference)).max() <= h
    # without --up the table lies on its back: its height is along z
    assert abs(_extent(plain)[2] - _extent(reference)[1]) <= h
    assert fixed.meta["history"][0]["up"] == "z"


@pytest.mark.parametrize(("units", "factor"), [("cm", 100.0), ("mm", 1000.0), ("in", 1 / 0.0254)])
def test_units_give_metres(table_mesh, reference, units, factor, tmp_path):
    big = table_mesh.copy()
    big.vertices = table_mesh.vertices * factor
    p = tmp_path / "big.glb"
    big.export(p)
    c = ingest.load(p, res=48, units=units)
    assert np.abs(_extent(c) - _extent(reference)).max() <= reference.voxel_size * 1.01
    assert c.meta["history"][0]["units"] == units
    assert c.meta["units"] == "m"


def test_scale_multiplies(reference, tmp_path, table_mesh):
    p = tmp_path / "t.glb"
    table_mesh.export(p)
    c = ingest.load(p, res=48, scale=2.0)
    assert np.abs(_extent(c) - 2 * _extent(reference)).max() <= 2 * reference.voxel_size * 1.01
    assert c.meta["history"][0]["scale"] == 2.0


def test_cli_import_options_bad_input(cli, tmp_path, table_mesh):
    p = tmp_path / "t.glb"
    table_mesh.export(p)
    for args, frag in [
        (["--up", "w"], "--up"),
        (["--units", "ft"], "--units"),
        (["--scale", "-1"], "--scale"),
    ]:
        proc = cli("import", p, "-o", tmp_path / "o.csdf.npz", "--res", "32", *args)
        assert proc.returncode == 2 and frag in proc.stderr, proc.stderr
    proc = cli("import", p, "-o", tmp_path / "o.csdf.npz", "--res", "32", "--units", "cm")
    assert proc.returncode == 0, proc.stderr
