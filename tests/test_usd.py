"""USD and USDZ export, opened with usd-core and checked by USD's own compliance checker.

The ARKit rules of ``UsdUtils.ComplianceChecker`` (what ``usdchecker --arkit`` runs) hold each
package to what AR Quick Look reads: one default prim, the layer and textures inside, files
stored uncompressed at 64-byte offsets, only UsdPreviewSurface/UsdUVTexture/primvar readers.
"""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import ROOT, assert_bad_input, data_path, run_cli

import partscale
from partscale import data, export, ingest, meshedit
from partscale.edit import Recipe

pxr = pytest.importorskip("pxr", reason="usd-core not installed (pip install 'partscale[usd]')")
from pxr import Sdf, Usd, UsdGeom, UsdShade  # noqa: E402


def compliance_failures(path: Path) -> list[str]:
    """Errors and failed checks of USD's compliance checker (ARKit rules for a .usdz)."""
    try:
        from pxr.UsdUtils.complianceChecker import (
            ComplianceChecker,
            ShaderPropertyTypeConformanceChecker,
        )
    except ImportError:
        pytest.skip("this usd-core has no UsdUtils.ComplianceChecker (removed in 26.x)")
    checker = ComplianceChecker(arkit=path.suffix == ".usdz", skipARKitRootLayerCheck=False)
    # The usd-core wheels ship no shader definitions (shaderDefs.usda), so the one rule that
    # looks shader inputs up in the Sdr registry cannot run; check_shader_inputs() below holds
    # the inputs to UsdPreviewSurface's and UsdUVTexture's types instead.
    checker._rules = [
        r for r in checker._rules if not isinstance(r, ShaderPropertyTypeConformanceChecker)
    ]
    checker.CheckCompliance(str(path))
    return [*checker.GetErrors(), *checker.GetFailedChecks()]


#: the UsdPreviewSurface specification's input types for what we author
SPEC_TYPES = {
    "diffuseColor": "color3f",
    "roughness": "float",
    "metallic": "float",
    "file": "asset",
    "st": "float2",
    "sourceColorSpace": "token",
    "wrapS": "token",
    "wrapT": "token",
    "scale": "float4",
    "varname": "string",
}


def check_shader_inputs(stage) -> None:
    for prim in stage.Traverse():
        if prim.IsA(UsdShade.Shader):
            for inp in UsdShade.Shader(prim).GetInputs():
                want = SPEC_TYPES[inp.GetBaseName()]
                assert str(inp.GetTypeName()) == want, (prim.GetPath(), inp.GetBaseName())


def the_meshes(stage) -> list:
    return [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]


def base_color(mesh):
    """(the diffuseColor input's source shader or None, the bound material)."""
    material, _ = UsdShade.MaterialBindingAPI(mesh.GetPrim()).ComputeBoundMaterial()
    assert material, f"{mesh.GetPath()} has no bound material"
    surface = material.ComputeSurfaceSource()[0]
    assert surface.GetIdAttr().Get() == "UsdPreviewSurface"
    diffuse = surface.GetInput("diffuseColor")
    src = diffuse.GetConnectedSource()
    return (UsdShade.Shader(src[0].GetPrim()) if src else None), material


def check_package_layout(path: Path) -> list[str]:
    """The package's file names; each stored uncompressed at a 64-byte aligned offset."""
    with zipfile.ZipFile(path) as z:
        infos = z.infolist()
        raw = path.read_bytes()
        for info in infos:
            assert info.compress_type == zipfile.ZIP_STORED, info.filename
            # the local header: 30 bytes, then the name and the extra field, then the data
            name_len, extra_len = np.frombuffer(
                raw[info.header_offset + 26 : info.header_offset + 30], "<u2"
            )
            start = info.header_offset + 30 + int(name_len) + int(extra_len)
            assert start % 64 == 0, (info.filename, start)
        return [i.filename for i in infos]


def check_stage_basics(stage) -> None:
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    root = stage.GetDefaultPrim()
    assert root and root.GetPath() == Sdf.Path("/Root")
    check_shader_inputs(stage)


def check_textured(path: Path, expected: trimesh.Trimesh) -> None:
    """One mesh with ``expected``'s points and triangles, UVs, a texture inside the package."""
    stage = Usd.Stage.Open(str(path))
    check_stage_basics(stage)
    (mesh,) = the_meshes(stage)
    points = np.asarray(mesh.GetPointsAttr().Get())
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get())
    assert (counts == 3).all() and len(counts) == len(expected.faces)
    assert np.abs(points - expected.vertices).max() < 1e-5
    st = UsdGeom.PrimvarsAPI(mesh.GetPrim()).GetPrimvar("st")
    uv = np.asarray(st.Get())
    assert st.GetInterpolation() == UsdGeom.Tokens.vertex and uv.shape == (len(points), 2)
    assert np.abs(uv - expected.visual.uv).max() < 1e-6  # v = 0 at the bottom, as trimesh
    tex, _ = base_color(mesh)
    assert tex is not None and tex.GetIdAttr().Get() == "UsdUVTexture"
    asset = tex.GetInput("file").Get()
    resolved = asset.resolvedPath
    assert resolved.startswith(str(path.resolve())) or resolved.startswith(str(path)), resolved
    inside = resolved[resolved.index("[") + 1 : -1]
    assert inside in check_package_layout(path)
    assert compliance_failures(path) == []


@pytest.fixture(scope="module")
def wooden_table():
    """The textured wooden table imported at 64 voxels."""
    return ingest.load(data_path("polyhaven/wooden_table_02/wooden_table_02_1k.gltf"), res=64)


def test_usdz_of_a_textured_object_has_the_atlas_inside_and_passes_arkit(wooden_table, tmp_path):
    usdz = export.export_mesh(wooden_table, tmp_path / "table.usdz", atlas=512, faces=4000)
    glb = export.export_mesh(wooden_table, tmp_path / "table.glb", atlas=512, faces=4000)
    expected = trimesh.load(glb, force="mesh", process=False)
    assert 0 < len(expected.faces) <= 4000
    check_textured(usdz, expected)
    # the baked texture in the package is the GLB's, texel for texel
    from PIL import Image

    with zipfile.ZipFile(usdz) as z:
        (png,) = [n for n in z.namelist() if n.endswith(".png")]
        with z.open(png) as f:
            texels = np.asarray(Image.open(f).convert("RGB"))
    assert np.array_equal(texels, np.asarray(expected.visual.material.baseColorTexture)[..., :3])


def test_usda_writes_its_texture_beside_and_it_resolves(wooden_table, tmp_path):
    out = export.export_mesh(wooden_table, tmp_path / "table.usda", atlas=256, faces=2000)
    assert (tmp_path / "table.png").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.png", "table.usda"]  # no temps
    stage = Usd.Stage.Open(str(out))
    check_stage_basics(stage)
    (mesh,) = the_meshes(stage)
    tex, _ = base_color(mesh)
    assert Path(tex.GetInput("file").Get().resolvedPath) == tmp_path / "table.png"
    assert compliance_failures(out) == []


def test_mesh_route_result_as_usdz_keeps_the_source_texture(tmp_path):
    src = data_path("polyhaven/wooden_table_02/wooden_table_02_1k.gltf")
    longer = Recipe.parse({"edits": [{"axis": "x", "zone": ["30%", "70%"], "to": "125%"}]})
    res = meshedit.edit_mesh_file(src, tmp_path / "longer.usdz", longer)
    ref = meshedit.edit_mesh_file(src, tmp_path / "longer.glb", longer)
    assert res.written == [tmp_path / "longer.usdz"] and res.faces_out == ref.faces_out
    scene = meshedit.load_scene(tmp_path / "longer.glb")
    stage = Usd.Stage.Open(str(tmp_path / "longer.usdz"))
    check_stage_basics(stage)
    meshes = the_meshes(stage)
    assert len(meshes) == len(scene.graph.nodes_geometry)
    faces = sum(len(m.GetFaceVertexCountsAttr().Get()) for m in meshes)
    assert faces == res.faces_out
    # world points: the same box as the GLB result's (node transforms applied)
    pts = np.vstack([np.asarray(m.GetPointsAttr().Get()) for m in meshes])
    assert np.abs(pts.min(0) - scene.bounds[0]).max() < 1e-5
    assert np.abs(pts.max(0) - scene.bounds[1]).max() < 1e-5
    names = check_package_layout(tmp_path / "longer.usdz")
    textured = 0
    for m in meshes:
        assert UsdGeom.PrimvarsAPI(m.GetPrim()).GetPrimvar("st").IsDefined()
        tex, _ = base_color(m)
        if tex is not None:
            resolved = tex.GetInput("file").Get().resolvedPath
            assert resolved[resolved.index("[") + 1 : -1] in names
            textured += 1
    assert textured == len(meshes)
    assert compliance_failures(tmp_path / "longer.usdz") == []


def test_shipped_table_as_usdz_both_routes(tmp_path):
    # the mesh route: the table's materials are plain colours (no texture)
    wide = Recipe.parse({"edits": [{"axis": "x", "zone": ["30%", "70%"], "to": "120%"}]})
    res = meshedit.edit_mesh_file(data.table(), tmp_path / "wide.usdz", wide)
    stage = Usd.Stage.Open(str(tmp_path / "wide.usdz"))
    check_stage_basics(stage)
    assert sum(len(m.GetFaceVertexCountsAttr().Get()) for m in the_meshes(stage)) == res.faces_out
    for m in the_meshes(stage):
        _, material = base_color(m)
        assert material
    assert compliance_failures(tmp_path / "wide.usdz") == []
    # the CSDF route without an atlas: vertex colours as displayColor, read by the material
    c = ingest.load(data.table(), res=48)
    out = export.export_mesh(c, tmp_path / "table.usdz", faces=3000)
    stage = Usd.Stage.Open(str(out))
    check_stage_basics(stage)
    (mesh,) = the_meshes(stage)
    colors = np.asarray(mesh.GetDisplayColorPrimvar().Get())
    assert colors.shape == (len(mesh.GetPointsAttr().Get()), 3)
    assert 0 <= colors.min() and colors.max() <= 1 and colors.std() > 0.01  # the table's colours
    reader, _ = base_color(mesh)
    assert reader.GetIdAttr().Get() == "UsdPrimvarReader_float3"
    assert reader.GetInput("varname").Get() == "displayColor"
    assert check_package_layout(out) == ["table.usdc"]
    assert compliance_failures(out) == []


def test_cli_export_usdz(tmp_path):
    c = ingest.load(data.table(), res=48)
    src = partscale.save(c, tmp_path / "t.csdf.npz")
    proc = run_cli("export", src, "--mesh", tmp_path / "t.usdz", "--atlas", "256", check=True)
    assert "t.usdz" in proc.stderr + proc.stdout and "note:" not in proc.stderr
    plain = run_cli("export", src, "--mesh", tmp_path / "v.usdz", check=True)
    assert "add --atlas" in plain.stderr  # vertex colours: AR Quick Look would show none
    (tmp_path / "v.usdz").unlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csdf.npz", "t.usdz"]
    assert compliance_failures(tmp_path / "t.usdz") == []


def _without_usd(tmp_path: Path) -> dict[str, str]:
    """An environment whose Python cannot import pxr, as without usd-core installed."""
    site = tmp_path / "nousd"
    site.mkdir()
    (site / "sitecustomize.py").write_text(
        "import sys\n"
        "class _NoUsd:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'pxr' or name.startswith('pxr.'):\n"
        "            raise ImportError(f'No module named {name!r}')\n"
        "        return None\n"
        "sys.meta_path.insert(0, _NoUsd())\n"
    )
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT / "src")])
    return env


@pytest.mark.parametrize("command", ["export", "scale"])
def test_usd_output_without_usd_core_is_one_line_naming_the_extra(command, tmp_path):
    env = _without_usd(tmp_path)
    probe = subprocess.run([sys.executable, "-c", "import pxr"], env=env, capture_output=True)
    assert probe.returncode != 0  # the block works
    if command == "export":
        src = partscale.save(ingest.load(data.table(), res=32), tmp_path / "t.csdf.npz")
        args = ["export", str(src), "--mesh", str(tmp_path / "out.usdz")]
    else:
        args = [
            "scale", str(data.table()), "-o", str(tmp_path / "out.usdz"),
            "--axis", "x", "--zone", "30%", "70%", "--to", "120%",
        ]  # fmt: skip
    proc = subprocess.run(
        [sys.executable, "-m", "partscale", *args], env=env, capture_output=True, text=True
    )
    assert_bad_input(proc, "partscale[usd]", "out.usdz")
    assert not (tmp_path / "out.usdz").exists()


def test_save_usd_failing_after_its_textures_leaves_nothing_half_written(tmp_path, monkeypatch):
    from partscale.export import usd

    scene = meshedit.load_scene(data_path("polyhaven/wooden_table_02/wooden_table_02_1k.gltf"))
    (tmp_path / "table.png").write_bytes(b"the user's own picture")
    real = usd._stage

    def stage_then_fail(*args, **kwargs):
        real(*args, **kwargs)  # layer and textures written to their temporaries
        raise OSError("disk full")

    monkeypatch.setattr(usd, "_stage", stage_then_fail)
    with pytest.raises(partscale.InputError, match="disk full"):  # one line, not a traceback
        export.save_usd(scene, tmp_path / "table.usda")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.png"]  # no layer, no temps
    assert (tmp_path / "table.png").read_bytes() == b"the user's own picture"
    monkeypatch.undo()
    written = export.save_usd(scene, tmp_path / "table.usda")
    assert written[0] == tmp_path / "table.usda" and len(written) > 1
    assert all(p.is_file() for p in written)
