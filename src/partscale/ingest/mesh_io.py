"""Coloured triangle meshes read from glTF/GLB, OBJ+MTL and PLY (through trimesh).

Colour conventions
------------------
- Everything a user sees is 8-bit sRGB; arithmetic on colours is done in linear light.
- glTF: ``baseColorFactor`` and ``COLOR_0`` are linear, base-colour textures are sRGB; the
  colour at a point is ``texture(uv) * factor * vertex_colour`` in linear light (the glTF rule).
- OBJ/MTL ``Kd`` and PLY vertex colours are display (sRGB) values; ``map_Kd`` multiplies ``Kd``.
- UVs follow trimesh's convention (v up, image row 0 at v = 1); the sampler wraps (glTF's
  default ``REPEAT``) and filters bilinearly, in linear light.
"""

from __future__ import annotations

import io
import json
import os
import re
import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError, one_line

MESH_SUFFIXES = (".glb", ".gltf", ".obj", ".ply")


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB in [0, 1] -> linear in [0, 1] (IEC 61966-2-1), float32."""
    c = np.asarray(c, dtype=np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb8(c: np.ndarray) -> np.ndarray:
    """Linear in [0, 1] (clipped) -> sRGB uint8, same shape."""
    from . import _kernels

    c = np.asarray(c)
    flat = np.ascontiguousarray(c.reshape(-1, c.shape[-1] if c.ndim else 1))
    return _kernels.linear_to_srgb8(flat).reshape(c.shape)


@dataclass(frozen=True, eq=False)
class Material:
    """One surface material.

    factor : (3,) float32
        Linear RGB multiplier (glTF ``baseColorFactor``, MTL ``Kd`` linearised).
    texture : (H, W, 3) float32 or None
        Base-colour texture decoded to linear RGB, row 0 at the top of the image.
    uv_transform : (2, 3) float64 or None
        Affine map applied to UVs before lookup (glTF ``KHR_texture_transform``), in trimesh's
        v-up convention.
    """

    factor: np.ndarray
    texture: np.ndarray | None = None
    uv_transform: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class ColoredMesh:
    """A triangle soup with what is needed to evaluate its sRGB colour at any surface point.

    vertices : (V, 3) float64
        World positions (all node transforms applied), object units (metres for glTF).
    faces : (F, 3) int64
        Vertex indices of each triangle.
    face_material : (F,) int32
        Index into ``materials`` of each triangle.
    materials : tuple of Material
    uv : (F, 3, 2) float32 or None
        Texture coordinates at each triangle corner (NaN-free; zeros where a piece has none).
    corner_color : (F, 3, 3) float32 or None
        Linear vertex colour at each triangle corner (ones where a piece has none).
    source : str
        File it was read from.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_material: np.ndarray
    materials: tuple[Material, ...]
    uv: np.ndarray | None = None
    corner_color: np.ndarray | None = None
    source: str = ""

    def __post_init__(self) -> None:
        # read-only like a CSDF's arrays; a caller's writeable array is copied, not frozen
        for name in ("vertices", "faces", "face_material", "uv", "corner_color"):
            a = getattr(self, name)
            if a is not None and a.flags.writeable:
                a = np.array(a)
                a.flags.writeable = False
                object.__setattr__(self, name, a)

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    def color_at(self, tri_ids: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """sRGB colour at surface points given as triangle + barycentric coordinates.

        Parameters
        ----------
        tri_ids : (N,) int
            Triangle index of each point.
        bary : (N, 3) float
            Barycentric coordinates of each point in its triangle (rows sum to 1).

        Returns
        -------
        (N, 3) uint8 sRGB
        """
        tri_ids = np.asarray(tri_ids, dtype=np.int64)
        bary = np.asarray(bary, dtype=np.float64)
        lin = np.ones((len(tri_ids), 3), np.float32)
        if self.corner_color is not None:
            lin *= np.einsum("nc,ncj->nj", bary, self.corner_color[tri_ids]).astype(np.float32)
        mats = self.face_material[tri_ids]
        uv = None
        if self.uv is not None:
            uv = np.einsum("nc,ncj->nj", bary, self.uv[tri_ids])
        for m_id in np.unique(mats):
            mat = self.materials[m_id]
            sel = mats == m_id
            col = np.broadcast_to(mat.factor, (int(sel.sum()), 3)).astype(np.float32)
            if mat.texture is not None and uv is not None:
                u = uv[sel]
                if mat.uv_transform is not None:
                    u = u @ mat.uv_transform[:, :2].T + mat.uv_transform[:, 2]
                col = col * sample_texture(mat.texture, u)
            lin[sel] *= col
        return linear_to_srgb8(lin)


def sample_texture(texture: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear, repeat-wrapped lookup of ``texture`` (H, W, C) at ``uv`` (N, 2) -> (N, C)."""
    from . import _kernels

    return _kernels.bilinear_repeat(
        np.ascontiguousarray(texture, np.float32), np.ascontiguousarray(uv, np.float64)
    )


# -- reading ------------------------------------------------------------------------------


def _read_gltf(path: Path) -> tuple[dict, bytes] | None:
    """The glTF JSON document of a .gltf/.glb and, for a .glb, the bytes after its JSON chunk.

    None when the document cannot be read (trimesh then reports what is wrong).
    """
    try:
        raw = path.read_bytes()
        if path.suffix.lower() == ".gltf":
            doc = json.loads(raw.decode("utf-8"))
            rest = b""
        else:
            if len(raw) < 20 or raw[:4] != b"glTF" or raw[16:20] != b"JSON":
                return None
            length = struct.unpack("<I", raw[12:16])[0]
            doc = json.loads(raw[20 : 20 + length].decode("utf-8"))
            rest = raw[20 + length :]
    except (OSError, ValueError, UnicodeDecodeError, struct.error):
        return None
    return (doc, rest) if isinstance(doc, dict) else None


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
        args = []
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


def _read_texture(obj: Path, mtl: Path, name: str) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    tex = mtl.parent / name
    if not tex.is_file() and "\\" in name:  # written on Windows
        tex = mtl.parent / name.replace("\\", "/")
    if not tex.is_file():
        raise InputError(f"{obj}: expected the texture {tex} named by {mtl}, got no such file")
    try:
        with Image.open(tex) as img:
            return _image_linear(img)
    except (OSError, ValueError, UnidentifiedImageError) as exc:
        raise InputError(
            f"{obj}: expected a readable texture image {tex}, got {one_line(exc)}"
        ) from None


class _Utf8Resolver:
    """trimesh file resolver that hands text files (MTL) over as UTF-8.

    It keeps the text of each MTL it serves (``mtl``: name -> text), so the materials are read
    from exactly the files trimesh followed (only an OBJ's first ``mtllib``).
    """

    def __init__(self, source: str):
        import trimesh

        self._inner = trimesh.resolvers.FilePathResolver(source)
        self.mtl: dict[str, str] = {}

    def get(self, name: str) -> bytes:
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


def _obj_materials(obj: Path, mtl_texts: dict[str, str]) -> dict[str, Material]:
    """Materials of an OBJ's MTL files (name -> text, relative to the OBJ), by material name.

    They are read here rather than taken from trimesh, which takes the rest of a ``map_Kd``
    line as the file name (options break it), resolves it against the OBJ's folder rather than
    the MTL's, turns a missing texture into plain white and gives a textured material without
    ``Kd`` a diffuse of 0.4. Here options are parsed (``-o``/``-s`` become a UV affine), names
    resolve against the MTL's folder, a missing texture is an :class:`InputError` and a texture
    without ``Kd`` is unscaled (:data:`_KD_TEXTURED`); no ``Kd`` and no texture is
    :data:`_KD_PLAIN` grey.
    """
    out: dict[str, Material] = {}
    for lib, text in mtl_texts.items():
        mtl = obj.parent / lib
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
                kd = [_float_or_none(t) for t in mt[1:4]]
                if None in kd:
                    continue  # "Kd spectral file" / "Kd xyz x y z": not read, the default
                if not np.isfinite(kd).all():
                    raise InputError(
                        f"{obj}: expected Kd of material {cur_name!r} in {mtl.name} to be "
                        f"finite numbers, got {' '.join(mt[1:4])}"
                    )
                cur["kd"] = kd * 3 if len(kd) == 1 else kd
            elif key == "map_kd":
                cur["map"] = _map_kd(mline.strip())
        for name, e in entries.items():
            tex = uv_tf = None
            if "map" in e and e["map"][0]:
                tex = _read_texture(obj, mtl, e["map"][0])
                uv_tf = e["map"][1]
            default = _KD_TEXTURED if "map" in e else _KD_PLAIN
            kd = np.clip(np.asarray(e.get("kd", [default] * 3), np.float32), 0, 1)
            out.setdefault(name, Material(srgb_to_linear(kd), tex, uv_tf))
    return out


def _image_linear(img) -> np.ndarray | None:
    """(H, W, 3) float32 linear RGB of a PIL image (sRGB-encoded, 8 or 16 bits)."""
    if img is None:
        return None
    if img.mode.startswith("I") or img.mode == "F":
        # 16-bit (I;16*, or I as PIL reads 16-bit PNG) and float greyscale: convert("RGB")
        # would clip them to 255 (white); scale to [0, 1] instead
        a = np.asarray(img, dtype=np.float64)
        a = np.clip(a / (1.0 if img.mode == "F" else 65535.0), 0.0, 1.0)
        a = np.repeat(a[..., None].astype(np.float32), 3, axis=-1)
    else:
        a = np.asarray(img.convert("RGB"), dtype=np.float32) / 255.0
    return srgb_to_linear(a)


def _material_of(
    visual, is_gltf: bool, transforms: dict[str, np.ndarray], obj_mats: dict[str, Material]
) -> Material:
    from trimesh.visual.material import PBRMaterial, SimpleMaterial

    mat = getattr(visual, "material", None)
    if getattr(mat, "name", None) in obj_mats:
        return obj_mats[mat.name]
    if isinstance(mat, PBRMaterial):
        f = mat.baseColorFactor
        factor = (
            np.ones(3, np.float32)
            if f is None
            else np.asarray(f[:3], np.float32) / (255.0 if np.asarray(f).dtype == np.uint8 else 1)
        )
        if not is_gltf:  # a PBR material made by trimesh from MTL keeps display values
            factor = srgb_to_linear(factor)
        tex = _image_linear(mat.baseColorTexture)
        uv_tf = transforms.get(mat.name) if tex is not None else None
        return Material(factor, tex, uv_tf)
    if isinstance(mat, SimpleMaterial):
        d = np.asarray(mat.diffuse, dtype=np.float32)[:3] / 255.0
        return Material(srgb_to_linear(d), _image_linear(mat.image))
    return Material(np.ones(3, np.float32))


def load_mesh(path: str | os.PathLike) -> ColoredMesh:
    """Read a coloured triangle mesh: glTF/GLB, OBJ+MTL or PLY.

    All scene nodes are placed by their transforms. Each triangle keeps its material (base
    colour factor and texture), its corner UVs and vertex colours, so the colour at any surface
    point can be evaluated with :meth:`ColoredMesh.color_at`.

    Raises :class:`InputError` naming the file for a missing, unreadable, corrupt or empty mesh.
    """
    import trimesh

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: expected an existing mesh file, got no such file")
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise InputError(
            f"{path}: expected a mesh ({', '.join(MESH_SUFFIXES)}), got suffix {suffix or 'none'}"
        )
    if path.stat().st_size == 0:
        raise InputError(f"{path}: expected a {suffix[1:]} mesh, got an empty file (0 bytes)")
    is_gltf = suffix in (".glb", ".gltf")
    prepared = _prepare_gltf(path) if is_gltf else None
    transforms = prepared[1] if prepared else {}
    try:
        with warnings.catch_warnings():
            # trimesh's casts of junk numbers warn; what they produce is checked below
            warnings.simplefilter("ignore", RuntimeWarning)
            if prepared:
                scene = trimesh.load_scene(
                    io.BytesIO(prepared[0]),
                    file_type=suffix[1:],
                    resolver=trimesh.resolvers.FilePathResolver(str(path)),
                    process=False,
                )
            elif suffix == ".obj":
                # trimesh needs charset_normalizer for text that is not UTF-8: hand it UTF-8
                text = _decode_text(path.read_bytes())
                resolver = _Utf8Resolver(str(path))
                scene = trimesh.load_scene(
                    io.BytesIO(text.encode("utf-8")),
                    file_type="obj",
                    resolver=resolver,
                    process=False,
                )
            else:
                scene = trimesh.load_scene(str(path), process=False)
    except (InputError, MemoryError):
        raise
    except Exception as exc:  # trimesh's parsers raise many kinds (even ImportError) on junk
        msg = one_line(exc)
        if isinstance(exc, IndexError):  # an OBJ face naming a vertex that is not there
            msg = f"an index past its list ({msg})"
        raise InputError(f"{path}: expected a readable {suffix[1:]} mesh, got {msg}") from None
    # outside the try: a failure here is ours (or an InputError), not an unreadable OBJ
    obj_mats = _obj_materials(path, resolver.mtl) if suffix == ".obj" else {}
    verts, faces, mats, face_mat, uvs, colors = [], [], [], [], [], []
    any_uv = any_color = False
    n_v = 0
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        v = np.asarray(geom.vertices, np.float64)
        if v.ndim != 2 or v.shape[1] != 3:
            raise InputError(
                f"{path}: expected 3 coordinates per vertex in {geom_name!r}, got shape {v.shape}"
            )
        v = v @ transform[:3, :3].T + transform[:3, 3]
        f = np.asarray(geom.faces, np.int64)
        if f.min() < 0 or f.max() >= len(v):
            raise InputError(
                f"{path}: expected face indices in [0, {len(v)}) (the vertex count of "
                f"{geom_name!r}), got [{f.min()}, {f.max()}]"
            )
        if np.linalg.det(transform[:3, :3]) < 0:  # mirrored node: keep outward winding
            f = f[:, ::-1]
        visual = geom.visual
        mats.append(_material_of(visual, is_gltf, transforms, obj_mats))
        face_mat.append(np.full(len(f), len(mats) - 1, np.int32))
        uv = getattr(visual, "uv", None)
        if uv is not None and len(uv) == len(v):
            uvs.append(np.asarray(uv, np.float32)[f])
            any_uv = True
        else:
            uvs.append(np.zeros((len(f), 3, 2), np.float32))
        vc = None
        if visual.kind == "vertex":
            vc = np.asarray(visual.vertex_colors, np.float32)[:, :3] / 255.0
        elif visual.kind == "face":
            vc = np.repeat(np.asarray(visual.face_colors, np.float32)[:, None, :3] / 255.0, 3, 1)
        elif "color" in getattr(visual, "vertex_attributes", {}):  # COLOR_0 beside a texture
            raw = np.asarray(visual.vertex_attributes["color"])
            vc = raw[:, :3].astype(np.float32)
            if np.issubdtype(raw.dtype, np.integer):
                vc /= float(np.iinfo(raw.dtype).max)
        if vc is not None:
            if vc.ndim == 2:
                vc = vc[f]
            colors.append(vc if is_gltf else srgb_to_linear(vc))
            any_color = True
        else:
            colors.append(np.ones((len(f), 3, 3), np.float32))
        verts.append(v)
        faces.append(f + n_v)
        n_v += len(v)
    if not faces:
        raise InputError(f"{path}: expected a mesh with triangles, got none")
    vertices = np.concatenate(verts)
    if not np.isfinite(vertices).all():
        raise InputError(f"{path}: expected finite vertex positions, got NaN or inf")
    all_faces = np.concatenate(faces)
    ext = np.ptp(vertices[np.unique(all_faces)], axis=0)
    if not (ext.max() > 0):
        raise InputError(f"{path}: expected a mesh with non-zero extent, got all points equal")
    return ColoredMesh(
        vertices=vertices,
        faces=all_faces,
        face_material=np.concatenate(face_mat),
        materials=tuple(mats),
        uv=np.concatenate(uvs) if any_uv else None,
        corner_color=np.concatenate(colors) if any_color else None,
        source=str(path),
    )


def from_trimesh(mesh, *, color=(200, 200, 200), source: str = "") -> ColoredMesh:
    """A :class:`ColoredMesh` of one flat sRGB ``color`` from a ``trimesh.Trimesh`` (tests, demos)."""
    f = np.asarray(mesh.faces, np.int64)
    return ColoredMesh(
        vertices=np.asarray(mesh.vertices, np.float64).copy(),
        faces=f.copy(),
        face_material=np.zeros(len(f), np.int32),
        materials=(Material(srgb_to_linear(np.asarray(color[:3], np.float32) / 255.0)),),
        source=source,
    )
