"""glTF 2.0 reader (``.gltf`` with its files, ``.glb``): trimesh, plus what trimesh misses.

trimesh keys materials by name, ignores ``KHR_texture_transform`` and reads only ``TEXCOORD_0``;
the document is rewritten before trimesh sees it (:func:`_prepare_gltf`). glTF colours
(``baseColorFactor``, ``COLOR_0``) are linear.
"""

from __future__ import annotations

import io
import json
import struct
from pathlib import Path

import numpy as np

from .._files import parse_json
from ..errors import InputError
from .mesh import ColoredMesh, read_scene, scene_to_mesh


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


def load_gltf(path: Path) -> ColoredMesh:
    """Read a ``.gltf``/``.glb`` (an existing, non-empty file) as a :class:`ColoredMesh`."""
    import trimesh

    suffix = path.suffix.lower()
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
    return scene_to_mesh(scene, path, linear_colors=True, uv_transforms=transforms)
