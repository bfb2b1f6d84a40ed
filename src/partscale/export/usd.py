"""USD and USDZ mesh writer (``.usd``, ``.usda``, ``.usdc``, ``.usdz``), with Pixar's usd-core.

One ``UsdGeom.Mesh`` per mesh of the scene under one default prim ``/Root`` (an Xform of kind
``component``), points in world units with the node transforms applied, per-vertex normals, and
a ``UsdPreviewSurface`` material bound to each mesh:

- a textured mesh (an atlas from :func:`partscale.export.export_mesh`, or a glTF/OBJ material's
  base colour texture in the mesh route): ``primvars:st`` (vertex UVs, v = 0 at the image's
  bottom as USD has it) read by a ``UsdUVTexture`` whose ``rgb`` is the ``diffuseColor``; a
  colour factor other than white becomes the texture's ``scale``;
- vertex or face colours: ``primvars:displayColor`` (linear RGB) read by a
  ``UsdPrimvarReader_float3`` into ``diffuseColor``;
- a plain material: its colour as a constant ``diffuseColor``.

Stage metadata: ``upAxis = "Y"`` (partscale's up) and ``metersPerUnit`` from the object's units
(1 for metres, the glTF default). ``.usdz`` is a package made by
``UsdUtils.CreateNewARKitUsdzPackage``: the layer and its PNG textures inside, each file aligned
to 64 bytes, one default prim: what AR Quick Look reads. ``.usd``/``.usda``/``.usdc`` with
textures write them beside the layer as ``NAME.png`` (one texture) or ``NAME_<i>.png``.

usd-core is an optional dependency (``pip install 'partscale[usd]'``); :func:`require_usd`
says so in one line before any work is done.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._files import atomic_path, final_path, staged_writes
from .._scenes import triangle_meshes
from ..errors import InputError

if TYPE_CHECKING:
    import trimesh

    from ..csdf import CSDF

USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
"""The USD outputs: text or crate layers, and the ``.usdz`` package."""
USD_EXTRA = "partscale[usd]"
"""The optional extra that installs usd-core."""

ROOT_PRIM = "/Root"
"""The stage's default prim, parent of every mesh."""

#: a material with neither texture nor colour: light grey, like glTF's default white but softer
_DEFAULT_LINEAR = (0.5, 0.5, 0.5)


def require_usd(path: str | os.PathLike) -> None:
    """Raise :class:`InputError` when ``path`` is a USD output and usd-core cannot be imported.

    Parameters
    ----------
    path : str or os.PathLike
        An output file; only a suffix in :data:`USD_SUFFIXES` needs usd-core.

    Raises
    ------
    partscale.errors.InputError
        One line naming the extra to install.

    Examples
    --------
    >>> from partscale.export.usd import require_usd
    >>> require_usd("table.glb")  # not USD: nothing to check
    """
    if Path(path).suffix.lower() not in USD_SUFFIXES:
        return
    try:
        from pxr import Usd, UsdGeom, UsdShade, UsdUtils  # noqa: F401
    except ImportError as exc:
        raise InputError(
            f"{path}: expected usd-core to write USD, got none importable ({exc}); "
            f"install it with: pip install '{USD_EXTRA}'"
        ) from None


def write_usd(csdf: CSDF, mesh: trimesh.Trimesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh surface of ``csdf``) as USD at ``path`` (suffix picks the kind).

    Normals are the SDF's gradient (as in GLB); units come from ``csdf.meta['units']``. ``path``
    is written as it is (the caller writes atomically; textures beside it are named after
    :func:`partscale._files.final_path`).
    """
    import trimesh

    from .glb import _sdf_normals

    surface = mesh.copy()
    normals = _sdf_normals(csdf, mesh.vertices).astype(np.float64)
    scene = trimesh.Scene()
    scene.add_geometry(surface, geom_name="csdf", node_name="csdf")
    _write(scene, path, units=csdf.meta.get("units"), normals={"csdf": normals})


def save_usd(
    scene: trimesh.Scene, path: str | os.PathLike, *, units: str | None = None
) -> list[Path]:
    """Write a trimesh scene as USD (``.usd``, ``.usda``, ``.usdc``) or a USDZ package, atomically.

    Parameters
    ----------
    scene : trimesh.Scene
        The meshes, their node transforms and materials (the mesh route's result).
    path : str or os.PathLike
        The output; one of :data:`USD_SUFFIXES`.
    units : str, optional
        The scene's length unit (``m``, ``cm``, ``mm``, ``in``) for ``metersPerUnit``; metres
        when None.

    Returns
    -------
    list of Path
        The files written: the layer or package first, then textures written beside a layer.
        They land together: on any failure none of them is written and what was there stays.

    Examples
    --------
    >>> from partscale import data, meshedit
    >>> from partscale.export.usd import save_usd
    >>> save_usd(meshedit.load_scene(data.table()), "table.usdz")
    [PosixPath('table.usdz')]
    """
    path = Path(path)
    if path.suffix.lower() not in USD_SUFFIXES:
        raise InputError(
            f"{path}: expected a USD file ending in {', '.join(USD_SUFFIXES)}, got "
            f"{path.suffix or 'no suffix'}"
        )
    require_usd(path)
    with staged_writes(), atomic_path(path) as tmp:  # the layer and its textures: all or none
        beside = _write(scene, tmp, units=units)
    return [path, *beside]


def _write(
    scene: trimesh.Scene,
    path: Path,
    *,
    units: str | None,
    normals: dict[str, np.ndarray] | None = None,
) -> list[Path]:
    """Write ``scene`` at ``path`` (a temporary or the destination); returns textures beside."""
    if path.suffix.lower() == ".usdz":
        with tempfile.TemporaryDirectory(prefix="partscale-usdz-") as folder:
            layer = Path(folder) / f"{_safe(final_path(path).stem) or 'model'}.usdc"
            _stage(scene, layer, units, normals, Path(folder), lambda i, n: f"textures/{i}.png")
            _package(layer, path)
        return []
    dest = final_path(path)

    def name(i: int, n: int) -> str:
        return f"{dest.stem}.png" if n == 1 else f"{dest.stem}_{i}.png"

    return _stage(scene, path, units, normals, dest.parent, name, atomic=True)


def _package(layer: Path, path: Path) -> None:
    from pxr import Sdf, UsdUtils

    if not UsdUtils.CreateNewARKitUsdzPackage(Sdf.AssetPath(str(layer)), str(path)):
        raise InputError(f"{final_path(path)}: expected a USDZ package, got usd-core's refusal")


def _safe(name: str) -> str:
    """A valid USD prim name (identifier) made of ``name``."""
    s = re.sub(r"[^A-Za-z0-9_]", "_", str(name))
    return s if s and not s[0].isdigit() else f"_{s}"


def _meters_per_unit(units: str | None) -> float:
    from ..edit import SUFFIXES

    return SUFFIXES.get(str(units).lower(), 1.0) if units else 1.0


def _stage(scene, path: Path, units, normals, folder: Path, texture_name, *, atomic=False):
    """Author the stage at ``path``; textures go to ``folder`` under ``texture_name(i, n)``."""
    from pxr import Kind, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, _meters_per_unit(units))
    root = UsdGeom.Xform.Define(stage, ROOT_PRIM)
    stage.SetDefaultPrim(root.GetPrim())
    Usd.ModelAPI(root.GetPrim()).SetKind(Kind.Tokens.component)
    stage.DefinePrim(f"{ROOT_PRIM}/Materials", "Scope")
    items = _meshes(scene)
    images = [img for _, _, _, look in items if (img := look.get("image")) is not None]
    textures = {id(img): texture_name(i, len(images)) for i, img in enumerate(images)}
    used: set[str] = set()
    for node, mesh, matrix, look in items:
        name = _unique(_safe(node), used)
        prim = _define_mesh(stage, f"{ROOT_PRIM}/{name}", mesh, matrix, (normals or {}).get(node))
        img = look.get("image")
        _bind(stage, prim, mesh, look, textures.get(id(img)) if img is not None else None)
    written = []
    for img, rel in ((img, textures[id(img)]) for img in images):
        out = folder / rel
        out.parent.mkdir(parents=True, exist_ok=True)
        if atomic:
            with atomic_path(out) as tmp:
                img.save(tmp, format="PNG")
            written.append(out)
        else:
            img.save(out, format="PNG")
    stage.GetRootLayer().Save()
    return written


def _unique(name: str, used: set[str]) -> str:
    out, i = name, 1
    while out in used or out == "Materials":
        out, i = f"{name}_{i}", i + 1
    used.add(out)
    return out


def _meshes(scene) -> list[tuple[str, Any, np.ndarray, dict[str, Any]]]:
    """(node name, trimesh, 4x4 world transform, look) for every triangle mesh of ``scene``."""
    return [
        (str(node), mesh, np.asarray(matrix, np.float64), _look(mesh))
        for node, _, mesh, matrix in triangle_meshes(scene)
    ]


def _look(mesh) -> dict[str, Any]:
    """What colours a mesh: ``image`` (PIL RGB) and ``scale`` (linear RGB), or ``colors``, or
    ``diffuse`` (linear RGB); plus ``name``, ``metallic`` and ``roughness``.
    """
    from trimesh.visual import TextureVisuals
    from trimesh.visual.material import PBRMaterial

    from ..color import srgb8_to_linear

    vis = mesh.visual
    if not isinstance(vis, TextureVisuals):
        if vis.kind in ("vertex", "face"):
            rgb = vis.vertex_colors if vis.kind == "vertex" else vis.face_colors
            return {"colors": srgb8_to_linear(np.asarray(rgb)[:, :3]), "kind": vis.kind}
        return {"diffuse": _DEFAULT_LINEAR}
    mat = vis.material
    look: dict[str, Any] = {"name": getattr(mat, "name", None), "roughness": 0.9, "metallic": 0.0}
    if isinstance(mat, PBRMaterial):
        factor = mat.baseColorFactor
        lin = np.asarray(factor if factor is not None else [255] * 4, np.float64)[:3] / 255.0
        image = mat.baseColorTexture
        if mat.metallicFactor is not None:
            look["metallic"] = float(mat.metallicFactor)
        if mat.roughnessFactor is not None:
            look["roughness"] = float(mat.roughnessFactor)
    else:  # SimpleMaterial: an MTL's Kd (display values) and map_Kd
        kd = getattr(mat, "diffuse", None)
        kd = np.asarray(kd if kd is not None else [255] * 3)
        lin = srgb8_to_linear(kd[None, :3].astype(np.uint8))[0]
        image = getattr(mat, "image", None)
    if image is not None and vis.uv is not None and len(vis.uv) == len(mesh.vertices):
        look["image"] = image.convert("RGB")
        look["scale"] = tuple(float(c) for c in lin)
    else:
        look["diffuse"] = tuple(float(c) for c in lin)
    return look


def _define_mesh(stage, prim_path: str, mesh, matrix: np.ndarray, normals: np.ndarray | None):
    from pxr import Gf, UsdGeom, Vt

    m = UsdGeom.Mesh.Define(stage, prim_path)
    pts = np.asarray(mesh.vertices, np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
    faces = np.asarray(mesh.faces, np.int32)
    linear = matrix[:3, :3]
    if np.linalg.det(linear) < 0:  # a mirroring transform turns the winding
        faces = faces[:, ::-1]
    m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(pts.astype(np.float32)))
    m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)))
    m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(faces.ravel())))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    m.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]))
    m.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    m.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
    n = np.asarray(mesh.vertex_normals if normals is None else normals, np.float64)
    n = n @ np.linalg.inv(linear)  # normals take the inverse transpose
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where(length > 1e-12, n / np.maximum(length, 1e-12), (0.0, 1.0, 0.0))
    m.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(n.astype(np.float32)))
    m.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    return m


def _bind(stage, mesh_prim, mesh, look: dict[str, Any], texture: str | None) -> None:
    """Author the mesh's primvars and a UsdPreviewSurface material bound to it."""
    from pxr import Gf, Sdf, UsdGeom, UsdShade, Vt

    base = _unique_material(stage, look.get("name") or mesh_prim.GetPrim().GetName())
    material = UsdShade.Material.Define(stage, base)
    surface = UsdShade.Shader.Define(stage, f"{base}/PreviewSurface")
    surface.CreateIdAttr("UsdPreviewSurface")
    surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(look.get("roughness", 0.9))
    surface.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(look.get("metallic", 0.0))
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    diffuse = surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f)
    api = UsdGeom.PrimvarsAPI(mesh_prim)
    if texture is not None:
        uv = np.asarray(mesh.visual.uv, np.float32)
        st = api.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
        st.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(uv[:, :2])))
        reader = UsdShade.Shader.Define(stage, f"{base}/stReader")
        reader.CreateIdAttr("UsdPrimvarReader_float2")
        reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
        reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)
        tex = UsdShade.Shader.Define(stage, f"{base}/BaseColor")
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(Sdf.AssetPath(f"./{texture}"))
        tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("sRGB")
        tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("repeat")
        tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("repeat")
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
            reader.ConnectableAPI(), "result"
        )
        scale = look.get("scale", (1.0, 1.0, 1.0))
        if any(abs(c - 1.0) > 1e-6 for c in scale):
            tex.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(*scale, 1.0))
        tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
        diffuse.ConnectToSource(tex.ConnectableAPI(), "rgb")
    elif "colors" in look:
        interp = UsdGeom.Tokens.vertex if look["kind"] == "vertex" else UsdGeom.Tokens.uniform
        colors = np.ascontiguousarray(look["colors"], np.float32)
        UsdGeom.Gprim(mesh_prim).CreateDisplayColorPrimvar(interp).Set(
            Vt.Vec3fArray.FromNumpy(colors)
        )
        reader = UsdShade.Shader.Define(stage, f"{base}/displayColorReader")
        reader.CreateIdAttr("UsdPrimvarReader_float3")
        reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("displayColor")
        reader.CreateOutput("result", Sdf.ValueTypeNames.Float3)
        diffuse.ConnectToSource(reader.ConnectableAPI(), "result")
    else:
        diffuse.Set(Gf.Vec3f(*look.get("diffuse", _DEFAULT_LINEAR)))
    UsdShade.MaterialBindingAPI.Apply(mesh_prim.GetPrim()).Bind(material)


def _unique_material(stage, name: str) -> str:
    base, i = f"{ROOT_PRIM}/Materials/{_safe(name)}", 1
    out = base
    while stage.GetPrimAtPath(out):
        out, i = f"{base}_{i}", i + 1
    return out


def usd_faces(path: str | os.PathLike) -> int:
    """The number of faces of every mesh on the USD stage at ``path`` (layer or package).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.usd``, ``.usda``, ``.usdc`` or ``.usdz`` file.

    Returns
    -------
    int
        Faces (triangles, as written by :func:`write_usd` and :func:`save_usd`) summed over
        the meshes.

    Examples
    --------
    >>> from partscale import data, meshedit
    >>> from partscale.export.usd import save_usd, usd_faces
    >>> usd_faces(save_usd(meshedit.load_scene(data.table()), "table.usdc")[0])
    120
    """
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    return sum(
        len(UsdGeom.Mesh(p).GetFaceVertexCountsAttr().Get() or [])
        for p in stage.Traverse()
        if p.IsA(UsdGeom.Mesh)
    )
