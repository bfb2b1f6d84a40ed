"""Assets for engines and DCC tools: triangle budgets, baked texture atlases, readable layouts."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from conftest import ROOT, gltf_validator_report, render_glbs

from partscale import export, ingest
from partscale.surface import sample_linear, to_mesh

SUITE = json.loads((ROOT / "eval" / "suite.json").read_text())


def _chamfer_voxels(a: trimesh.Trimesh, b: trimesh.Trimesh, h: float, n: int = 3000) -> float:
    """Symmetric mean surface distance between ``a`` and ``b``, in voxels."""
    pa, _ = trimesh.sample.sample_surface(a, n, seed=0)
    pb, _ = trimesh.sample.sample_surface(b, n, seed=1)
    da = trimesh.proximity.closest_point(b, pa)[1]
    db = trimesh.proximity.closest_point(a, pb)[1]
    return float((da.mean() + db.mean()) / 2 / h)


@pytest.fixture(scope="module")
def table(request):
    from conftest import data_path

    return ingest.load(data_path("kenney/table.glb"), res=128)


@pytest.fixture(scope="module")
def wood():
    """Poly Haven's wooden table at 96: wood-grain textures, so colour varies over the surface."""
    from conftest import data_path

    return ingest.load(data_path("polyhaven/wooden_table_02/wooden_table_02_1k.gltf"), res=96)


@pytest.fixture(scope="module")
def atlased(wood, tmp_path_factory):
    """The wooden table with --faces 20000 --atlas 1024, as GLB and as OBJ (one unwrap each)."""
    d = tmp_path_factory.mktemp("atlas")
    return {
        s: export.export_mesh(wood, d / f"t{s}", faces=20000, atlas=1024) for s in (".glb", ".obj")
    }


@pytest.mark.slow
@pytest.mark.parametrize("entry", SUITE["objects"], ids=[o["name"] for o in SUITE["objects"]])
def test_faces_budget_on_the_suite(data, entry, tmp_path):
    c = ingest.load(data(entry["path"]), res=SUITE["res"])
    full = to_mesh(c)
    out = export.export_mesh(c, tmp_path / "m.glb", faces=20000)
    m = trimesh.load(out, force="mesh")
    assert len(m.faces) <= 20000
    if full.is_watertight:
        assert m.is_watertight
    assert _chamfer_voxels(full, m, c.voxel_size) <= 0.5


def test_error_budget_keeps_the_surface_close(table, tmp_path):
    full = to_mesh(table)
    out = export.export_mesh(table, tmp_path / "m.ply", error=0.1)
    m = trimesh.load(out, force="mesh")
    assert len(m.faces) < len(full.faces) / 4  # flat boards need few triangles
    assert m.is_watertight == full.is_watertight
    assert _chamfer_voxels(full, m, table.voxel_size) <= 0.1


def _texture_colour(mesh: trimesh.Trimesh, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Points on ``mesh`` and the bilinear sRGB colour of its texture there."""
    pts, fi = trimesh.sample.sample_surface(mesh, n, seed=3)
    tri = mesh.vertices[mesh.faces[fi]]
    bary = trimesh.triangles.points_to_barycentric(tri, pts)
    uv = np.einsum("ij,ijk->ik", bary, mesh.visual.uv[mesh.faces[fi]])
    mat = mesh.visual.material
    image = getattr(mat, "baseColorTexture", None) or mat.image
    img = np.asarray(image.convert("RGB"), np.float64)
    hgt, wid = img.shape[:2]
    # trimesh: v = 0 at the bottom row; texel centres at (i + 0.5) / size
    x = uv[:, 0] * wid - 0.5
    y = (1.0 - uv[:, 1]) * hgt - 0.5
    x0 = np.clip(np.floor(x).astype(int), 0, wid - 2)
    y0 = np.clip(np.floor(y).astype(int), 0, hgt - 2)
    fx = np.clip(x - x0, 0, 1)[:, None]
    fy = np.clip(y - y0, 0, 1)[:, None]
    col = (
        img[y0, x0] * (1 - fx) * (1 - fy)
        + img[y0, x0 + 1] * fx * (1 - fy)
        + img[y0 + 1, x0] * (1 - fx) * fy
        + img[y0 + 1, x0 + 1] * fx * fy
    )
    return pts, col


@pytest.mark.parametrize("suffix", [".glb", ".obj"])
def test_atlas_colour_matches_the_csdf(wood, atlased, suffix):
    out = atlased[suffix]
    m = trimesh.load(out, force="mesh")
    assert m.visual.kind == "texture"
    pts, col = _texture_colour(m, 10000)
    want = sample_linear(wood.rgb, wood.world_to_index(pts))
    assert want.std(axis=0).max() > 10  # the check means something: colour varies
    assert np.abs(col - want).mean() <= 8.0, np.abs(col - want).mean()
    if suffix == ".obj":
        assert out.with_suffix(".png").is_file()
        assert "map_Kd t.png" in out.with_suffix(".mtl").read_text()


@pytest.mark.parametrize(
    ("name", "kwargs"),
    [("v.glb", {}), ("d.glb", {"error": 0.1}), (".glb", None), (".obj", None)],
)
def test_trimesh_reads_colours(table, atlased, name, kwargs, tmp_path):
    if kwargs is None:
        out = atlased[name]
    else:
        out = export.export_mesh(table, tmp_path / name, **kwargs)
    for loaded in (trimesh.load(out), trimesh.load(out, force="mesh")):
        geoms = loaded.geometry.values() if isinstance(loaded, trimesh.Scene) else [loaded]
        for g in geoms:
            colours = (
                g.visual.to_color().vertex_colors
                if g.visual.kind == "texture"
                else g.visual.vertex_colors
            )
            assert g.visual.kind in ("texture", "vertex")
            # the Kenney table is light wood, sRGB about (243, 203, 168): blue far below white
            assert (255 - colours[:, :3].astype(float).mean(axis=0)).max() > 40


def test_atlased_glb_passes_khronos_validator(atlased):
    report = gltf_validator_report(atlased[".glb"])
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"]
    assert report["info"]["materialCount"] == 1


def test_budget_and_atlas_bad_input(cli, table, tmp_path):
    from partscale import save

    src = tmp_path / "t.csdf.npz"
    save(table, src)
    for args, frag in [
        (["--faces", "2"], "--faces"),
        (["--faces", "100", "--error", "0.2"], "--faces or --error"),
        (["--atlas", "1000"], "--atlas"),
    ]:
        proc = cli("export", src, "--mesh", tmp_path / "x.glb", *args)
        assert proc.returncode == 2 and frag in proc.stderr, proc.stderr
        assert not (tmp_path / "x.glb").exists()
    proc = cli("export", src, "--mesh", tmp_path / "x.ply", "--atlas", "512")
    assert proc.returncode == 2 and "PLY" in proc.stderr


def test_threejs_renders_the_atlas_like_the_vertex_colours(wood, atlased, tmp_path):
    """GLTFLoader in headless Chromium: the baked texture shows the colours the vertices carry."""
    full = export.export_mesh(wood, tmp_path / "v.glb")  # full resolution, vertex colours
    renders = render_glbs(atlased[".glb"], full)
    tex, ver = (r["unlit"] for r in renders)
    obj_t, obj_v = tex.sum(axis=2) > 0, ver.sum(axis=2) > 0
    both = obj_t & obj_v
    # same silhouette: the decimated surface is within a fraction of a voxel of the full one
    assert both.sum() >= 0.97 * max(obj_t.sum(), obj_v.sum()) and both.sum() > 5000
    assert ver[both].astype(float).std(axis=0).max() > 10  # varied colour on screen
    diff = np.abs(tex[both].astype(float) - ver[both].astype(float))
    assert diff.mean() <= 8.0, diff.mean()
    lit = renders[0]["lit"]
    assert lit[obj_t].mean() > 20  # lit with its own material, not black
