"""Thin features: measured on analytic slabs, warned about by ``partscale info``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from partscale import shapes
from partscale.csdf import save
from partscale.thickness import thin_features

H = 0.02


def slabs(thickness: float, n: int = 4):
    """``n`` slabs ``thickness`` voxels thick across x, every ten voxels, 0.3 x 0.2 m."""
    p = 10 * H
    boxes = [((m * p + 0.3 * H, 0, 0), (m * p + (0.3 + thickness) * H, 0.3, 0.2)) for m in range(n)]
    bounds = np.array([[0, 0, 0], [(n - 1) * p + (thickness + 1.3) * H, 0.3, 0.2]])
    return shapes.grid(lambda q: shapes.boxes_sdf(q, boxes), bounds, voxel_size=H)


@pytest.mark.parametrize("thickness", [0.9, 1.3])
def test_thin_slabs_are_measured_and_a_finer_resolution_named(thickness):
    t = thin_features(slabs(thickness))
    assert t.worth_warning and t.gap_voxels == 0
    # the slabs' inside voxels, all of them: one or two layers of 16 x 11 per slab
    assert t.solid_voxels >= 4 * 14 * 9
    assert abs(t.typical - thickness) <= 0.05
    assert (t.below_one_solid > 0) == (thickness < 1)
    # the named resolution holds the slabs at >= 1.5 voxels
    assert t.needed_resolution * thickness / t.resolution >= 1.5


def test_thick_bodies_and_their_rims_are_not_thin():
    for c in (
        slabs(4.0),
        shapes.sphere((0, 0, 0), 0.3, voxel_size=H),
        shapes.box((0, 0, 0), (0.31, 0.23, 0.17), voxel_size=H),
    ):
        t = thin_features(c)
        assert not t.worth_warning and t.message(H) is None, t


def test_a_thin_gap_is_a_feature_too():
    # two blocks 0.8 voxel apart, a voxel centre in the slit between them
    boxes = [((0, 0, 0), (0.2 + 0.6 * H, 0.3, 0.2)), ((0.2 + 1.4 * H, 0, 0), (0.4, 0.3, 0.2))]
    c = shapes.grid(
        lambda q: shapes.boxes_sdf(q, boxes), ((0, 0, 0), (0.4, 0.3, 0.2)), voxel_size=H
    )
    t = thin_features(c)
    assert t.worth_warning and t.below_one_gap > 0 and t.solid_voxels == 0
    assert abs(t.typical - 0.8) <= 0.05


def test_info_warns_about_thin_features(tmp_path, cli):
    thin = save(slabs(0.9), tmp_path / "thin.csdf.npz")
    thick = save(slabs(4.0), tmp_path / "thick.csdf.npz")
    out = cli("info", thin, check=True).stdout
    assert "warning:     thin features" in out and "--res " in out, out
    clean = cli("info", thick, check=True).stdout
    assert "warning" not in clean
    assert "relief:" in clean and "(smooth)" in clean  # a clean grid is no scan
    s = json.loads(cli("info", thin, "--json", check=True).stdout)["thin_features"]
    assert s["below_one_voxel"]["solid"] > 0 and s["needed_resolution"] > s["resolution"]


def test_import_records_pieces_thinner_than_a_voxel_and_info_names_a_resolution():
    """A board 0.6 voxel thick (res 40 over 1 m: voxels of 2.5 cm, board 1.5 cm; its 4 broad
    triangles are thin, the edges are not): the import
    thickens it to hold it, records how thin it was, and the warning names a finer grid."""
    trimesh = pytest.importorskip("trimesh")
    from partscale import ingest

    board = trimesh.creation.box(bounds=[[0, 0, 0], [1.0, 0.015, 0.5]])
    c = ingest.from_mesh(ingest.from_trimesh(board), res=40)
    rec = c.meta["history"][0]
    assert rec["thin_piece_triangles"] == 4 and rec["below_one_voxel_triangles"] >= 2
    assert abs(rec["thin_piece_thickness_voxels"]["median"] - 0.6) <= 0.02
    t = thin_features(c)
    assert t.worth_warning and "thickened at import" in t.message(c.voxel_size)
    # 1.5 voxels across the 1.5 cm board: voxels of 1 cm, 100 along the metre
    assert t.needed_resolution >= 100
