"""The coloured triangle mesh every mesh reader returns, and what the readers share.

Colour conventions
------------------
- Everything a user sees is 8-bit sRGB; arithmetic on colours is done in linear light.
- glTF: ``baseColorFactor`` and ``COLOR_0`` are linear, base-colour textures are sRGB; the
  colour at a point is ``texture(uv) * factor * vertex_colour`` in linear light (the glTF rule).
- OBJ/MTL ``Kd`` and PLY vertex colours are display (sRGB) values; ``map_Kd`` multiplies ``Kd``.
- UVs follow trimesh's convention (v up, image row 0 at v = 1); the sampler wraps (glTF's
  default ``REPEAT``) and filters bilinearly, in linear light.

The readers (:mod:`.gltf`, :mod:`.obj`, :mod:`.ply`) each parse their format with trimesh (plus
what trimesh misses) and hand the scene to :func:`scene_to_mesh`.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, overload

import numpy as np

from .._scenes import triangle_meshes
from ..color import linear_to_srgb8, srgb_to_linear
from ..errors import InputError, PartscaleWarning, one_line

if TYPE_CHECKING:
    from PIL import Image


@dataclass(frozen=True, eq=False)
class Material:
    """One surface material.

    Parameters
    ----------
    factor : (3,) float32
        Linear RGB multiplier (glTF ``baseColorFactor``, MTL ``Kd`` linearised).
    texture : (H, W, 3) float32 or None
        Base-colour texture decoded to linear RGB, row 0 at the top of the image.
    uv_transform : (2, 3) float64 or None
        Affine map applied to UVs before lookup (glTF ``KHR_texture_transform``), in trimesh's
        v-up convention.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> material = ingest.load_mesh(data.table()).materials[0]
    >>> [round(float(v), 2) for v in material.factor], material.texture is None
    ([0.9, 0.6, 0.39], True)
    """

    factor: np.ndarray
    texture: np.ndarray | None = None
    uv_transform: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class ColoredMesh:
    """A triangle soup with what is needed to evaluate its sRGB colour at any surface point.

    Parameters
    ----------
    vertices : (V, 3) float64
        World positions (all node transforms applied), object units (metres for glTF).
    faces : (F, 3) int64
        Vertex indices of each triangle.
    face_material : (F,) int32
        Index into ``materials`` of each triangle.
    materials : tuple of Material
        The surface materials.
    uv : (F, 3, 2) float32 or None
        Texture coordinates at each triangle corner (NaN-free; zeros where a piece has none).
    corner_color : (F, 3, 3) float32 or None
        Linear vertex colour at each triangle corner (ones where a piece has none).
    source : str
        File it was read from.
    notes : tuple of str
        What the reader said to the user while reading (a missing texture or material library
        replaced by the material's colour); the import records them in its history.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> mesh = ingest.load_mesh(data.table())
    >>> mesh.faces.shape, len(mesh.materials)
    ((120, 3), 1)
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_material: np.ndarray
    materials: tuple[Material, ...]
    uv: np.ndarray | None = None
    corner_color: np.ndarray | None = None
    source: str = ""
    notes: tuple[str, ...] = ()

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
        """Number of triangles."""
        return len(self.faces)

    def color_at(self, tri_ids: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """SRGB colour at surface points given as triangle + barycentric coordinates.

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
        from . import _shading

        tri_ids = np.ascontiguousarray(tri_ids, dtype=np.int64)
        bary = np.ascontiguousarray(bary, dtype=np.float64)
        # numba passes over the points (the import colours millions): each step's arithmetic
        # is the plain numpy one's (einsum's order, float32 products, the UV affine as BLAS
        # computes it), bit for bit
        if self.corner_color is not None:
            lin = _shading.corner_mix(tri_ids, bary, self.corner_color).astype(np.float32)
        else:
            lin = np.ones((len(tri_ids), 3), np.float32)
        mats = self.face_material[tri_ids]
        uv = None if self.uv is None else _shading.corner_mix(tri_ids, bary, self.uv)
        none = np.zeros((0, 0, 3), np.float32)
        for m_id in np.flatnonzero(np.bincount(mats, minlength=len(self.materials))):
            mat = self.materials[m_id]
            tex, tf = none, np.zeros((0, 3))
            if mat.texture is not None and uv is not None:
                tex = np.ascontiguousarray(mat.texture, np.float32)
                if mat.uv_transform is not None:
                    tf = np.ascontiguousarray(mat.uv_transform, np.float64)
            factor = np.ascontiguousarray(mat.factor, np.float32)
            _shading.shade(mats, m_id, factor, tex, uv if uv is not None else bary, tf, lin)
        return linear_to_srgb8(lin)


def sample_texture(texture: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear, repeat-wrapped lookup of ``texture`` (H, W, C) at ``uv`` (N, 2) -> (N, C)."""
    from . import _shading

    return _shading.bilinear_repeat(
        np.ascontiguousarray(texture, np.float32), np.ascontiguousarray(uv, np.float64)
    )


def read_scene(path: Path, read: Callable):
    """``read()`` (a trimesh scene of ``path``), its failures turned into :class:`InputError`."""
    suffix = path.suffix.lower()
    try:
        with warnings.catch_warnings():
            # trimesh's casts of junk numbers warn; what they produce is checked afterwards
            warnings.simplefilter("ignore", RuntimeWarning)
            return read()
    except (InputError, MemoryError):
        raise
    except Exception as exc:  # trimesh's parsers raise many kinds (even ImportError) on junk
        msg = one_line(exc)
        if isinstance(exc, IndexError):  # an OBJ face naming a vertex that is not there
            msg = f"an index past its list ({msg})"
        raise InputError(f"{path}: expected a readable {suffix[1:]} mesh, got {msg}") from None


def say(notes: list[str] | tuple[str, ...]) -> None:
    """Say each note once (a :class:`~partscale.errors.PartscaleWarning`), once the file has
    been read whole: a file refused afterwards gets its one error line alone.
    """
    for note in notes:
        warnings.warn(note, PartscaleWarning, stacklevel=3)


MAX_COORDINATE = 1e12
"""Largest magnitude of a placed vertex coordinate (a million km in metres): beyond it squared
lengths leave the float range."""


def check_scene(scene, path: Path) -> None:
    """Check every triangle mesh a trimesh scene places, before any arithmetic on it.

    Each mesh a node places: vertices of 3 finite coordinates, face indices within its
    vertices, a finite node transform, placed coordinates within :data:`MAX_COORDINATE`; at
    least one triangle in all; a non-zero extent. The one check of a scene's geometry, on both mesh routes (import
    and the mesh route's edits).

    Parameters
    ----------
    scene : trimesh.Scene
    path : Path
        The file it was read from (for messages).

    Returns
    -------
    None
        Raises :class:`~partscale.errors.InputError` naming the file and the mesh at fault.

    Examples
    --------
    >>> import trimesh
    >>> from pathlib import Path
    >>> from partscale import ingest
    >>> ingest.check_scene(trimesh.Scene(trimesh.creation.box()), Path("box.glb"))
    >>> points = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 5]], process=False)
    >>> ingest.check_scene(trimesh.Scene(points), Path("bad.glb"))
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: bad.glb: expected face indices in [0, 3) (the vertex count of ...), got [0, 5]
    """
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for node, geom_name, geom, transform in triangle_meshes(scene):
        v = np.asarray(geom.vertices, np.float64)
        if v.ndim != 2 or v.shape[1] != 3:
            raise InputError(
                f"{path}: expected 3 coordinates per vertex in {geom_name!r}, got shape {v.shape}"
            )
        if not np.isfinite(v).all():  # before arithmetic: inf would warn and spread NaN
            raise InputError(
                f"{path}: expected finite vertex coordinates, got "
                f"{int((~np.isfinite(v)).any(axis=1).sum())} vertex(es) with NaN/inf in {geom_name!r}"
            )
        f = np.asarray(geom.faces)
        if f.ndim != 2 or f.shape[1] != 3 or f.dtype.kind not in "iu":
            raise InputError(
                f"{path}: expected triangles of 3 vertex indices in {geom_name!r}, got shape "
                f"{f.shape}"
            )
        if f.min() < 0 or f.max() >= len(v):
            raise InputError(
                f"{path}: expected face indices in [0, {len(v)}) (the vertex count of "
                f"{geom_name!r}), got [{f.min()}, {f.max()}]"
            )
        T = np.asarray(transform, np.float64)
        if T.shape != (4, 4) or not np.isfinite(T).all():
            raise InputError(
                f"{path}: expected a finite node transform for {node!r}, got NaN or inf"
            )
        used = v[np.unique(f)]
        with np.errstate(over="ignore", invalid="ignore"):
            placed = used @ T[:3, :3].T + T[:3, 3]
        if not (np.abs(placed) <= MAX_COORDINATE).all():  # NaN fails too
            raise InputError(
                f"{path}: expected placed vertex positions within +-{MAX_COORDINATE:g}, got "
                f"{float(np.nanmax(np.abs(placed))):.3g} in {geom_name!r} (node {node!r})"
            )
        lo, hi = np.minimum(lo, placed.min(axis=0)), np.maximum(hi, placed.max(axis=0))
    if not np.isfinite(lo).all():
        raise InputError(f"{path}: expected a mesh with triangles, got none")
    ext = hi - lo
    if not (ext.max() > 0):
        raise InputError(f"{path}: expected a mesh with non-zero extent, got all points equal")
    if not np.isfinite(ext).all():
        raise InputError(f"{path}: expected a mesh of finite extent, got {ext.tolist()}")


def scene_to_mesh(
    scene,
    path: Path,
    *,
    linear_colors: bool,
    uv_transforms: dict[str, np.ndarray] | None = None,
    materials: dict[str, Material] | None = None,
) -> ColoredMesh:
    """One :class:`ColoredMesh` of every triangle mesh in a trimesh scene, nodes placed.

    Parameters
    ----------
    scene : trimesh.Scene
    path : Path
        The file it was read from (for messages and ``source``).
    linear_colors : bool
        Whether the file's colour factors and vertex colours are linear (glTF) or display sRGB.
    uv_transforms : dict, optional
        Material name -> (2, 3) UV affine, for materials trimesh made.
    materials : dict, optional
        Material name -> :class:`Material` the reader made itself (used instead of trimesh's).
    """
    from trimesh.visual import ColorVisuals, TextureVisuals

    check_scene(scene, path)
    uv_transforms = uv_transforms or {}
    materials = materials or {}
    verts, faces, mats, face_mat, uvs, colors = [], [], [], [], [], []
    any_uv = any_color = False
    n_v = 0
    for _, _, geom, transform in triangle_meshes(scene):
        v = np.asarray(geom.vertices, np.float64)  # checked by check_scene
        v = v @ transform[:3, :3].T + transform[:3, 3]
        f = np.asarray(geom.faces, np.int64)
        if np.linalg.det(transform[:3, :3]) < 0:  # mirrored node: keep outward winding
            f = f[:, ::-1]
        visual = geom.visual
        mats.append(material_of(visual, linear_colors, uv_transforms, materials))
        face_mat.append(np.full(len(f), len(mats) - 1, np.int32))
        uv = getattr(visual, "uv", None)
        if uv is not None and len(uv) == len(v):
            uvs.append(np.asarray(uv, np.float32)[f])
            any_uv = True
        else:
            uvs.append(np.zeros((len(f), 3, 2), np.float32))
        vc = None
        if isinstance(visual, ColorVisuals) and visual.kind == "vertex":
            vc = np.asarray(visual.vertex_colors, np.float32)[:, :3] / 255.0
        elif isinstance(visual, ColorVisuals) and visual.kind == "face":
            vc = np.repeat(np.asarray(visual.face_colors, np.float32)[:, None, :3] / 255.0, 3, 1)
        elif isinstance(visual, TextureVisuals) and "color" in visual.vertex_attributes:
            # COLOR_0 beside a texture
            raw = np.asarray(visual.vertex_attributes["color"])
            vc = raw[:, :3].astype(np.float32)
            if np.issubdtype(raw.dtype, np.integer):
                vc /= float(np.iinfo(raw.dtype).max)
        if vc is not None:
            if vc.ndim == 2:
                vc = vc[f]
            colors.append(vc if linear_colors else srgb_to_linear(vc))
            any_color = True
        else:
            colors.append(np.ones((len(f), 3, 3), np.float32))
        verts.append(v)
        faces.append(f + n_v)
        n_v += len(v)
    vertices = np.concatenate(verts)
    all_faces = np.concatenate(faces)
    return ColoredMesh(
        vertices=vertices,
        faces=all_faces,
        face_material=np.concatenate(face_mat),
        materials=tuple(mats),
        uv=np.concatenate(uvs) if any_uv else None,
        corner_color=np.concatenate(colors) if any_color else None,
        source=str(path),
    )


@overload
def image_linear(img: None) -> None: ...
@overload
def image_linear(img: Image.Image) -> np.ndarray: ...
def image_linear(img: Image.Image | None) -> np.ndarray | None:
    """(H, W, 3) float32 linear RGB of a PIL image (sRGB-encoded, 8 or 16 bits)."""
    if img is None:
        return None
    if img.mode.startswith("I") or img.mode == "F":
        # 16-bit (I;16*, or I as PIL reads 16-bit PNG) and float greyscale: convert("RGB")
        # would clip them to 255 (white); scale to [0, 1] instead
        a: np.ndarray = np.asarray(img, dtype=np.float64)
        a = np.clip(a / (1.0 if img.mode == "F" else 65535.0), 0.0, 1.0)
        a = np.repeat(a[..., None].astype(np.float32), 3, axis=-1)
    else:
        a = np.asarray(img.convert("RGB"), dtype=np.float32) / 255.0
    return srgb_to_linear(a)


def material_of(
    visual,
    linear_colors: bool,
    uv_transforms: dict[str, np.ndarray],
    materials: dict[str, Material],
) -> Material:
    """The :class:`Material` of a trimesh visual: ``materials[name]`` when the reader made it,
    else from trimesh's material (factors linear when ``linear_colors``, else display sRGB).
    """
    from trimesh.visual.material import PBRMaterial, SimpleMaterial

    mat = getattr(visual, "material", None)
    if mat is not None and getattr(mat, "name", None) in materials:
        return materials[mat.name]
    if isinstance(mat, PBRMaterial):
        f = mat.baseColorFactor
        factor = (
            np.ones(3, np.float32)
            if f is None
            else np.asarray(f[:3], np.float32) / (255.0 if np.asarray(f).dtype == np.uint8 else 1)
        )
        if not linear_colors:  # a PBR material made by trimesh from MTL keeps display values
            factor = srgb_to_linear(factor)
        tex = image_linear(mat.baseColorTexture)
        uv_tf = uv_transforms.get(mat.name) if tex is not None else None
        return Material(factor, tex, uv_tf)
    if isinstance(mat, SimpleMaterial):
        d = np.asarray(mat.diffuse, dtype=np.float32)[:3] / 255.0
        return Material(srgb_to_linear(d), image_linear(mat.image))
    return Material(np.ones(3, np.float32))


def from_trimesh(mesh, *, color=(200, 200, 200), source: str = "") -> ColoredMesh:
    """A :class:`ColoredMesh` of one flat sRGB colour from a ``trimesh.Trimesh`` (tests, demos).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The triangles, object units.
    color : (3,) int
        sRGB colour of every face.
    source : str
        What messages and ``meta['source']`` call it.

    Returns
    -------
    ColoredMesh
        The mesh, ready for :func:`from_mesh`.

    Examples
    --------
    >>> import trimesh
    >>> from partscale import ingest
    >>> mesh = ingest.from_trimesh(trimesh.creation.box((1, 0.5, 0.5)), color=(200, 50, 50))
    >>> ingest.from_mesh(mesh, res=32).rgb[16, 8, 8].tolist()
    [200, 50, 50]
    """
    f = np.asarray(mesh.faces, np.int64)
    return ColoredMesh(
        vertices=np.asarray(mesh.vertices, np.float64).copy(),
        faces=f.copy(),
        face_material=np.zeros(len(f), np.int32),
        materials=(Material(srgb_to_linear(np.asarray(color[:3], np.float32) / 255.0)),),
        source=source,
    )
