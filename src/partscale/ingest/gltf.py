"""glTF 2.0 reader (``.gltf`` with its files, ``.glb``): trimesh, plus what trimesh misses.

trimesh keys materials by name, ignores ``KHR_texture_transform`` and reads only ``TEXCOORD_0``;
the document is rewritten before trimesh sees it (:func:`_prepare_gltf`). glTF colours
(``baseColorFactor``, ``COLOR_0``) are linear.

A base-colour texture whose image is missing or cannot be decoded (trimesh drops it with no
word) is said in one line (a :class:`~partscale.errors.PartscaleWarning`, and in the mesh's
``notes``), and its material's base colour factor is used; on both routes
(:func:`load_gltf`, :func:`load_gltf_scene`).
"""

from __future__ import annotations

import base64
import binascii
import io
import json
import struct
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import unquote

import numpy as np

from .._files import parse_json
from ..errors import InputError, one_line
from .mesh import ColoredMesh, read_scene, say, scene_to_mesh

if TYPE_CHECKING:
    import trimesh


def _read_gltf(path: Path) -> tuple[dict, bytes] | None:
    """The glTF JSON document of a .gltf/.glb and, for a .glb, the bytes after its JSON chunk.

    The JSON is read strictly (:func:`partscale._files.parse_json`: nesting depth, digits,
    finite numbers), so a document nested thousands deep is an :class:`InputError` here, not
    a recursion error in trimesh. None when the container cannot be read (trimesh then
    reports what is wrong).
    """
    try:
        raw = path.read_bytes()
        if path.suffix.lower() == ".gltf":
            text, rest = raw, b""
        else:
            if len(raw) < 20 or raw[:4] != b"glTF" or raw[16:20] != b"JSON":
                return None
            length = struct.unpack("<I", raw[12:16])[0]
            text, rest = raw[20 : 20 + length], raw[20 + length :]
    except (OSError, struct.error):
        return None
    try:
        doc = parse_json(text, what=str(path), max_bytes=None)
    except InputError as exc:
        raise InputError(f"{exc} (a {path.suffix.lower()[1:]} mesh's JSON)") from None
    return (doc, rest) if isinstance(doc, dict) else None


def check_gltf(path: Path) -> None:
    """Raise :class:`InputError` if a ``.gltf``/``.glb`` file's JSON is not strict JSON within
    the nesting and number limits (what both mesh routes read before trimesh does).
    """
    if path.suffix.lower() in (".gltf", ".glb"):
        _read_gltf(path)


def _texture_transform(tt: dict) -> np.ndarray:
    """(2, 3) UV affine of a ``KHR_texture_transform``, acting on trimesh's v-up UVs."""
    ox, oy = (float(x) for x in tt.get("offset", [0.0, 0.0]))
    sx, sy = (float(x) for x in tt.get("scale", [1.0, 1.0]))
    r = float(tt.get("rotation", 0.0))
    c, s = np.cos(r), np.sin(r)
    # glTF: uv' = T * R * S * uv with R = [[c, s], [-s, c]] (in glTF's v-down frame)
    m = np.array([[c, s], [-s, c]]) @ np.diag([sx, sy])
    g = np.array([[m[0, 0], m[0, 1], ox], [m[1, 0], m[1, 1], oy], [0, 0, 1]])
    flip = np.array([[1.0, 0, 0], [0, -1.0, 1.0], [0, 0, 1]])  # v_gltf = 1 - v
    return (flip @ g @ flip)[:2]


_MAT_TAG = "partscale-material-"


def _rewrite_gltf(doc: dict, path: Path) -> dict[str, np.ndarray] | None:
    """Rename the materials of ``doc`` in place and move UV sets (see :func:`_prepare_gltf`).

    Trusts the document's structure: a wrong type surfaces as the built-in error it causes.
    """
    materials = doc.get("materials")
    meshes = doc.get("meshes")
    if materials is None or meshes is None:
        return None
    transforms: dict[str, np.ndarray] = {}
    tex_coord: dict[int, int] = {}
    labels: dict[int, str] = {}  # material index -> its name in the file, for messages
    for i, mat in enumerate(materials):
        labels[i] = mat.get("name") or f"#{i}"
        mat["name"] = tag = f"{_MAT_TAG}{i}"
        tex = (mat.get("pbrMetallicRoughness") or {}).get("baseColorTexture") or {}
        tt = (tex.get("extensions") or {}).get("KHR_texture_transform")
        n = tex.get("texCoord", 0)
        if tt is not None:
            n = tt.get("texCoord", n)  # the extension's override wins
            try:
                transforms[tag] = _texture_transform(tt)
            except (TypeError, ValueError):
                raise InputError(
                    f"{path}: expected KHR_texture_transform of material {labels[i]!r} to hold "
                    f"numbers, got {json.dumps(tt)[:80]}"
                ) from None
        if n != 0:
            tex_coord[i] = n
    for mesh in meshes:
        for prim in mesh.get("primitives") or []:
            m = prim.get("material")
            if m not in tex_coord:
                continue
            attr = prim.get("attributes") or {}
            key = f"TEXCOORD_{tex_coord[m]}"
            if key not in attr:
                raise InputError(
                    f"{path}: expected {key} on the primitives of material "
                    f"{labels[m]!r} (its baseColorTexture.texCoord), got none"
                )
            attr["TEXCOORD_0"] = attr[key]
    return transforms


def _prepare_gltf(path: Path) -> tuple[bytes, dict[str, np.ndarray]] | None:
    """A rewritten copy of a glTF for trimesh, and material tag -> UV affine.

    trimesh keys materials by name (unnamed or repeated names collide), ignores
    ``KHR_texture_transform`` (Khronos samples such as SheenChair tile their fabric with it) and
    reads only ``TEXCOORD_0``. So each material is renamed to a unique tag, and a
    primitive whose base-colour texture reads another UV set gets that set as ``TEXCOORD_0``.
    Raises :class:`InputError` when that set is missing. None when the JSON cannot be read.
    """
    got = _read_gltf(path)
    if got is None:
        return None
    doc, rest = got
    try:
        transforms = _rewrite_gltf(doc, path)
    except InputError:
        raise
    except (AttributeError, TypeError, KeyError, IndexError, ValueError):
        return None  # a malformed document: trimesh reports what is wrong with it
    if transforms is None:
        return None
    text = json.dumps(doc).encode("utf-8")
    if path.suffix.lower() == ".gltf":
        return text, transforms
    text += b" " * (-len(text) % 4)
    head = struct.pack("<4sII", b"glTF", 2, 20 + len(text) + len(rest))
    return head + struct.pack("<I4s", len(text), b"JSON") + text + rest, transforms


def _data_uri(uri: str) -> bytes:
    head, _, data = uri.partition(",")
    return base64.b64decode(data) if head.endswith(";base64") else unquote(data).encode()


def _buffer_view(doc: dict, rest: bytes, path: Path, index: int) -> bytes:
    """The bytes of buffer view ``index`` (a GLB's own buffer, a data URI or a file)."""
    view = doc["bufferViews"][index]
    buf = doc["buffers"][view["buffer"]]
    if "uri" in buf:
        uri = buf["uri"]
        data = (
            _data_uri(uri) if uri.startswith("data:") else (path.parent / unquote(uri)).read_bytes()
        )
    else:  # a GLB's BIN chunk: length, type, bytes
        length = struct.unpack("<I", rest[:4])[0]
        data = rest[8 : 8 + length]
    start = int(view.get("byteOffset", 0))
    return data[start : start + int(view["byteLength"])]


def _image_problem(doc: dict, rest: bytes, path: Path, image: dict) -> str | None:
    """Why the image ``image`` of ``doc`` cannot be shown (missing, unreadable), or None."""
    from PIL import Image

    uri = image.get("uri")
    where = f"image {unquote(uri)[:80]!r}" if uri and not uri.startswith("data:") else "an image"
    try:
        if uri is not None:
            if uri.startswith("data:"):
                data = _data_uri(uri)
            else:
                file = path.parent / unquote(uri)
                if not file.is_file():
                    return f"{where} is missing"
                data = file.read_bytes()
        else:
            data = _buffer_view(doc, rest, path, image["bufferView"])
        with Image.open(io.BytesIO(data)) as img:
            img.load()
    except (OSError, ValueError, binascii.Error, SyntaxError) as exc:
        return f"{where} is unreadable ({one_line(exc)})"
    return None


def _texture_notes(path: Path, got: tuple[dict, bytes] | None) -> list[str]:
    """A line per material whose base-colour texture is missing or cannot be decoded."""
    if got is None:
        return []
    doc, rest = got
    notes = []
    try:
        for i, mat in enumerate(doc.get("materials") or []):
            tex = (mat.get("pbrMetallicRoughness") or {}).get("baseColorTexture")
            if not tex or "index" not in tex:
                continue
            source = doc["textures"][tex["index"]].get("source")
            if source is None:
                continue  # only an extension's image (webp, basisu): left to the reader
            problem = _image_problem(doc, rest, path, doc["images"][source])
            if problem:
                label = mat.get("name") or f"#{i}"
                notes.append(
                    f"{path}: the base-colour texture of material {label!r}: {problem}; its "
                    "base colour is used"
                )
    except (AttributeError, TypeError, KeyError, IndexError, ValueError, struct.error):
        return notes  # a malformed document: trimesh reports what is wrong with it
    return notes


def _exact_factors(scene, doc: dict) -> None:
    """Give each material of ``scene`` (named by :func:`_rewrite_gltf`'s tags) the base colour
    factor of ``doc`` as written: trimesh rounds it to 8 bits, which in linear light moves a
    dark colour by several sRGB levels.
    """
    from trimesh.visual.material import PBRMaterial

    materials = doc.get("materials") or []
    for geom in scene.geometry.values():
        mat = getattr(getattr(geom, "visual", None), "material", None)
        name = getattr(mat, "name", None)
        if not isinstance(mat, PBRMaterial) or not str(name).startswith(_MAT_TAG):
            continue
        try:
            f = materials[int(str(name)[len(_MAT_TAG) :])]["pbrMetallicRoughness"]
            factor = np.asarray(f["baseColorFactor"], np.float64)
        except (KeyError, IndexError, TypeError, ValueError):
            continue  # no factor (trimesh's default) or a malformed one (trimesh's reading)
        if factor.shape == (4,) and np.isfinite(factor).all():
            # a float factor is taken as it is (trimesh's setter would round it again)
            mat._data["baseColorFactor"] = np.clip(factor, 0.0, 1.0)


def load_gltf(path: Path) -> ColoredMesh:
    """Read a ``.gltf``/``.glb`` (an existing, non-empty file) as a :class:`ColoredMesh`."""
    import trimesh

    suffix = path.suffix.lower()
    got = _read_gltf(path)
    notes = _texture_notes(path, got)
    prepared = _prepare_gltf(path)
    transforms = prepared[1] if prepared else {}

    def read():
        if prepared:
            return trimesh.load_scene(
                io.BytesIO(prepared[0]),
                file_type=suffix[1:],
                resolver=trimesh.resolvers.FilePathResolver(str(path)),
                process=False,
            )
        return trimesh.load_scene(str(path), process=False)

    scene = read_scene(path, read)
    if prepared and got:
        _exact_factors(scene, got[0])
    mesh = scene_to_mesh(scene, path, linear_colors=True, uv_transforms=transforms)
    say(notes)  # once read whole: a file refused gets its error line alone
    return replace(mesh, notes=tuple(notes))


def load_gltf_scene(path: Path) -> trimesh.Scene:
    """A ``.gltf``/``.glb`` as trimesh reads it, vertices as stored, for editing (the mesh
    route); a missing or unreadable texture is said as :func:`load_gltf` says it.
    """
    import trimesh

    notes = _texture_notes(path, _read_gltf(path))

    def read():
        return trimesh.load_scene(path, process=False, maintain_order=True)

    scene = read_scene(path, read)
    if scene.geometry:
        say(notes)
    return scene
