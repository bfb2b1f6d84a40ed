"""Wavefront OBJ + MTL reader: geometry and UVs through trimesh, materials read here.

Colour convention: MTL ``Kd`` and vertex colours are display (sRGB) values, as the tools that
write them (Sweet Home 3D's colour pickers, three.js's MTL loader, which converts ``Kd`` from
sRGB) mean them; ``map_Kd`` multiplies ``Kd`` (in linear light). Blender's OBJ importer and
trimesh instead copy ``Kd`` unchanged into a linear base colour, which shows a desk top stored
as 179,107,56 as 218,173,129. Both of partscale's routes use this module's convention: the
CSDF route (:func:`load_obj`) and the mesh route (:func:`load_obj_scene`, whose glTF base
colour factors are ``Kd`` linearised). OBJ and MTL carry no encoding: UTF-8 when it decodes,
else Latin-1.

A missing material library or a missing or unreadable texture is said in one line (a
:class:`~partscale.errors.PartscaleWarning`, and in the mesh's ``notes``) and its material's own
colour is used (``Kd``, or grey where the library is missing), on both routes.
"""

from __future__ import annotations

import io
import re
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..color import srgb_to_linear
from ..errors import InputError, one_line
from .mesh import ColoredMesh, Material, image_linear, read_scene, say, scene_to_mesh

if TYPE_CHECKING:
    import trimesh
    from PIL import Image

# MTL texture options and how many arguments each takes (-o/-s/-t: u and optional v, w)
_MTL_OPTION_ARGS = {
    "-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1, "-imfchan": 1,
    "-mm": 2, "-texres": 1, "-type": 1, "-o": 3, "-s": 3, "-t": 3,
}  # fmt: skip


def _decode_text(data: bytes) -> str:
    # OBJ/MTL carry no encoding: UTF-8 when it decodes, else Latin-1 (every byte is a character)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _float_or_none(tok: str) -> float | None:
    try:
        return float(tok)
    except ValueError:
        return None


def _is_number(tok: str) -> bool:
    """Whether ``tok`` is a finite number (nan, inf and overflowing ones are not)."""
    x = _float_or_none(tok)
    return x is not None and bool(np.isfinite(x))


def _map_kd(line: str) -> tuple[str, np.ndarray | None]:
    """File name and (2, 3) UV affine (``-o``/``-s``) of an MTL ``map_Kd`` line.

    Options come before the file name; the rest of the line (spaces kept) is the name.
    """
    toks = [(m.start(), m.group()) for m in re.finditer(r"\S+", line)][1:]
    scale, offset = [1.0, 1.0], [0.0, 0.0]
    i = 0
    while i < len(toks) and toks[i][1].lower() in _MTL_OPTION_ARGS:
        opt = toks[i][1].lower()
        n = _MTL_OPTION_ARGS[opt]
        args: list[str] = []
        i += 1
        while len(args) < n and i < len(toks) - 1:
            if opt in ("-o", "-s", "-t") and not _is_number(toks[i][1]):
                break  # v and w are optional
            args.append(toks[i][1])
            i += 1
        if opt in ("-o", "-s") and args:
            vals = [float(a) for a in args[:2]]
            target = offset if opt == "-o" else scale
            target[: len(vals)] = vals
    name = line[toks[i][0] :].strip() if i < len(toks) else ""
    if scale == [1.0, 1.0] and offset == [0.0, 0.0]:
        return name, None
    return name, np.array([[scale[0], 0.0, offset[0]], [0.0, scale[1], offset[1]]])


def _read_texture(obj: Path, mtl: Path, name: str, notes: list[str]) -> Image.Image | None:
    """The texture ``name`` an MTL names, loaded; None (and a line in ``notes``) when it is
    missing or unreadable.
    """
    from PIL import Image, UnidentifiedImageError

    tex = mtl.parent / name
    if not tex.is_file() and "\\" in name:  # written on Windows
        tex = mtl.parent / name.replace("\\", "/")
    if not tex.is_file():
        notes.append(
            f"{obj}: the texture {tex} named by {mtl.name} is missing; its material's colour "
            "is used"
        )
        return None
    try:
        with Image.open(tex) as img:
            img.load()
            return img.copy()
    except (OSError, ValueError, UnidentifiedImageError) as exc:
        notes.append(
            f"{obj}: the texture {tex} named by {mtl.name} is unreadable ({one_line(exc)}); "
            "its material's colour is used"
        )
        return None


class _Utf8Resolver:
    """trimesh file resolver that hands text files (MTL) over as UTF-8.

    It keeps the text of each MTL it serves (``mtl``: name -> text), so the materials are read
    from exactly the files trimesh followed (only an OBJ's first ``mtllib``).
    """

    def __init__(self, source: str, fallback_mtl: str | None = None):
        import trimesh

        self._inner = trimesh.resolvers.FilePathResolver(source)
        self.mtl: dict[str, str] = {}
        # served for a material library that is missing (its materials, plain grey)
        self._fallback = fallback_mtl

    def get(self, name: str) -> bytes:
        if name.lower().endswith(".mtl") and self._fallback is not None:
            data = self._fallback.encode("utf-8")
        else:
            data = self._inner.get(name)
        if name.lower().endswith(".mtl"):
            text = _decode_text(data)
            self.mtl[name] = text
            data = text.encode("utf-8")
        return data

    def __getitem__(self, name: str) -> bytes:
        return self.get(name)

    def __getattr__(self, name: str):
        return getattr(self._inner, name)


# MTL Kd when a material gives none: trimesh's diffuse for an untextured material (kept so its
# colour does not change); a texture alone is shown as it is.
_KD_PLAIN = 0.4
_KD_TEXTURED = 1.0


def _obj_materials(
    obj: Path, mtl_texts: dict[str, str], notes: list[str]
) -> dict[str, tuple[Material, Image.Image | None]]:
    """Materials of an OBJ's MTL files (name -> text, relative to the OBJ), by material name,
    each with its texture image as read (None: no texture, or a missing one).

    They are read here rather than taken from trimesh, which takes the rest of a ``map_Kd``
    line as the file name (options break it), resolves it against the OBJ's folder rather than
    the MTL's, turns a missing texture into plain white and gives a textured material without
    ``Kd`` a diffuse of 0.4. Here options are parsed (``-o``/``-s`` become a UV affine), names
    resolve against the MTL's folder, a missing or unreadable texture is a line in ``notes``
    (the material keeps its ``Kd``) and a texture without ``Kd`` is unscaled
    (:data:`_KD_TEXTURED`); no ``Kd`` and no texture is :data:`_KD_PLAIN` grey.
    """
    out: dict[str, tuple[Material, Image.Image | None]] = {}
    for lib, text in mtl_texts.items():
        mtl = obj.parent / lib
        for name, e in _mtl_entries(obj, mtl, text).items():
            img = uv_tf = None
            if "map" in e and e["map"][0]:
                img = _read_texture(obj, mtl, e["map"][0], notes)
                uv_tf = e["map"][1] if img is not None else None
            default = _KD_TEXTURED if img is not None else _KD_PLAIN
            diffuse = np.clip(np.asarray(e.get("kd", [default] * 3), np.float32), 0, 1)
            material = Material(srgb_to_linear(diffuse), image_linear(img), uv_tf)
            out.setdefault(name, (material, img))
    return out


def _mtl_entries(obj: Path, mtl: Path, text: str) -> dict[str, dict]:
    """Material name -> ``{"kd": [r, g, b], "map": (file, uv affine)}`` (keys present where
    the MTL gives them) of one MTL's text.
    """
    entries: dict[str, dict] = {}
    cur: dict | None = None
    for mline in text.splitlines():
        mt = mline.split()
        if len(mt) < 2:
            continue
        key = mt[0].lower()
        if key == "newmtl":
            cur_name = " ".join(mt[1:])
            cur = entries.setdefault(cur_name, {})
        elif cur is None:
            continue
        elif key == "kd":
            kd_or_none = [_float_or_none(t) for t in mt[1:4]]
            if None in kd_or_none:
                continue  # "Kd spectral file" / "Kd xyz x y z": not read, the default
            kd = [x for x in kd_or_none if x is not None]
            if not np.isfinite(kd).all():
                raise InputError(
                    f"{obj}: expected Kd of material {cur_name!r} in {mtl.name} to be "
                    f"finite numbers, got {' '.join(mt[1:4])}"
                )
            cur["kd"] = kd * 3 if len(kd) == 1 else kd
        elif key == "map_kd":
            cur["map"] = _map_kd(mline.strip())
    return entries


def _missing_mtllib(obj: Path, text: str) -> str | None:
    """The note for an OBJ whose material library (its first ``mtllib``, the one read) is
    missing, or None. trimesh would import it all white with no word.
    """
    for line in text.splitlines():
        if line.startswith("mtllib"):
            name = line[len("mtllib") :].strip()
            if not name:
                return None
            mtl = obj.parent / name
            candidates = {name, name.replace("\\", "/"), name.split()[0]}
            if any((obj.parent / c).is_file() for c in candidates):
                return None
            got = "a directory" if mtl.is_dir() else "missing"
            return f"{obj}: its material library {mtl.name} is {got}; its materials are grey"
    return None


def _grey_library(text: str) -> str:
    """An MTL text giving every material ``text`` uses (``usemtl``) plain grey Kd."""
    names = {
        line[len("usemtl") :].strip() for line in text.splitlines() if line.startswith("usemtl")
    }
    return "".join(
        f"newmtl {n}\nKd {_KD_PLAIN} {_KD_PLAIN} {_KD_PLAIN}\n" for n in sorted(names) if n
    )


_FACE_TOKEN = re.compile(r"^(-?\d+)(?://(-?\d+))?$")


def _fill_missing_uvs(text: str) -> str:
    """``text`` with a UV (0, 0) given to the face corners without one, where other faces have.

    trimesh drops every UV of a mesh in which some faces have ``vt`` and others not; a corner
    without one reads the texture at (0, 0) (the material's colour where it has no texture).
    """
    lines = text.split("\n")
    faces = [i for i, ln in enumerate(lines) if ln.startswith("f ") or ln.startswith("f\t")]
    with_vt = without_vt = False
    for i in faces:
        for tok in lines[i].split()[1:]:
            parts = tok.split("/")
            if len(parts) >= 2 and parts[1]:
                with_vt = True
            else:
                without_vt = True
    if not (with_vt and without_vt):
        return text
    n_vt = sum(1 for ln in lines if ln.startswith("vt ") or ln.startswith("vt\t"))
    new = n_vt + 1  # the appended vt, by absolute index
    for i in faces:
        toks = lines[i].split()
        out = []
        for tok in toks[1:]:
            m = _FACE_TOKEN.match(tok)
            if m is None:
                out.append(tok)  # has its vt (or is junk: trimesh says what is wrong)
            elif m.group(2) is None:
                out.append(f"{m.group(1)}/{new}")
            else:
                out.append(f"{m.group(1)}/{new}/{m.group(2)}")
        lines[i] = " ".join([toks[0], *out])
    return "\n".join(lines) + "\nvt 0 0\n"


def _read_obj(path: Path, **kwargs) -> tuple[trimesh.Scene, dict, list[str]]:
    """The trimesh scene of an OBJ (``kwargs`` to its loader), the materials read here
    (:func:`_obj_materials`) and the notes for the user (each said once as a warning).
    """
    import trimesh

    resolver: _Utf8Resolver | None = None
    notes: list[str] = []

    def read():
        nonlocal resolver
        # trimesh needs charset_normalizer for text that is not UTF-8: hand it UTF-8
        text = _decode_text(path.read_bytes())
        missing = _missing_mtllib(path, text)
        if missing:
            notes.append(missing)
        resolver = _Utf8Resolver(str(path), _grey_library(text) if missing else None)
        return trimesh.load_scene(
            io.BytesIO(_fill_missing_uvs(text).encode("utf-8")),
            file_type="obj",
            # trimesh annotates Resolver | Mapping but only calls get()/[]; subclassing its
            # Resolver ABC would import trimesh with this module
            resolver=resolver,  # type: ignore[arg-type]
            process=False,
            **kwargs,
        )

    scene = read_scene(path, read)
    assert resolver is not None
    # outside read_scene: a failure here is ours (or an InputError), not an unreadable OBJ
    materials = _obj_materials(path, resolver.mtl, notes)
    return scene, materials, notes


def load_obj(path: Path) -> ColoredMesh:
    """Read an ``.obj`` (an existing, non-empty file) and its MTL as a :class:`ColoredMesh`."""
    scene, materials, notes = _read_obj(path)
    mats = {name: m for name, (m, _) in materials.items()}
    mesh = scene_to_mesh(scene, path, linear_colors=False, materials=mats)
    say(notes)
    return replace(mesh, notes=tuple(notes))


def load_obj_scene(path: Path) -> trimesh.Scene:
    """An ``.obj`` as a trimesh Scene for editing and writing as glTF: one node per OBJ group
    (named after it), vertices as stored, materials as :func:`load_obj` reads them.

    Each material becomes a glTF (PBR) one whose base colour factor is ``Kd`` linearised (the
    convention of this module), kept in floating point (trimesh would round a linear factor to
    8 bits, losing dark colours), with its texture image; a ``map_Kd``'s ``-o``/``-s`` are
    applied to the UVs. Faces without ``vt`` beside faces with keep a UV (0, 0).
    """
    import trimesh
    from trimesh.visual import TextureVisuals

    # not maintain_order: trimesh then keeps one UV per position, breaking UV seams
    scene, materials, notes = _read_obj(path, split_groups=True)
    several = len(materials) > 1
    out = trimesh.Scene()
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        visual = getattr(geom, "visual", None)
        mat_name = str(getattr(getattr(visual, "material", None), "name", None) or "")
        name = str(geom_name)
        # trimesh names a group's mesh GROUP_MATERIAL when the file has several materials
        if several and mat_name and name.endswith(f"_{mat_name}") and len(name) > len(mat_name) + 1:
            name = name[: -len(mat_name) - 1]
        name = trimesh.util.unique_name(name, out.geometry)
        if isinstance(geom, trimesh.Trimesh) and mat_name in materials:
            material, img = materials[mat_name]
            uv = getattr(visual, "uv", None)
            if uv is not None and material.uv_transform is not None:
                tf = material.uv_transform
                uv = np.asarray(uv, np.float64) @ tf[:, :2].T + tf[:, 2]
            geom.visual = TextureVisuals(uv=uv, material=_pbr(mat_name, material, img))
        out.add_geometry(geom, node_name=name, geom_name=name, transform=transform)
    if not out.geometry:
        raise InputError(f"{path}: expected a mesh with triangles, got none")
    say(notes)
    return out


def _pbr(name: str, material: Material, image: Image.Image | None):
    """A trimesh PBR material of ``material``: linear factor in float64, texture image."""
    from trimesh.visual.material import PBRMaterial

    pbr = PBRMaterial(name=name, baseColorTexture=image, metallicFactor=0.0, roughnessFactor=1.0)
    # trimesh's setter rounds to uint8, and its glTF writer passes floats through as they are
    pbr._data["baseColorFactor"] = np.append(np.asarray(material.factor, np.float64), 1.0)
    return pbr
