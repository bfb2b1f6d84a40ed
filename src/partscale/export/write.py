"""The export entry points: writers and readers registered by suffix, one module per format."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path
from .._options import keyword_options
from ..csdf import CSDF
from ..errors import InputError
from ..progress import ProgressCallback, resolve
from .atlas import bake, check_atlas, unwrap
from .glb import write_glb
from .mesh import write_obj, write_ply
from .nrrd import read_nrrd, write_nrrd
from .resize import check_size, resize_grid
from .simplify import check_budget, simplify
from .textures import read_png, read_raw, write_png, write_raw
from .usd import require_usd, write_usd

MESH_WRITERS: dict[str, Callable[[CSDF, Any, Path], None]] = {
    ".glb": write_glb,
    ".ply": write_ply,
    ".obj": write_obj,
    # USD layers and the USDZ package (usd-core, the optional extra partscale[usd])
    ".usd": write_usd,
    ".usda": write_usd,
    ".usdc": write_usd,
    ".usdz": write_usd,
}
"""Mesh writer by suffix: ``(csdf, trimesh surface, path)``, writing ``path`` as it is."""
TEXTURE_WRITERS: dict[str, Callable[[CSDF, Path], list[Path]]] = {
    ".raw": write_raw,
    ".png": write_png,
    ".nrrd": write_nrrd,
}
"""3D texture writer by suffix: ``(csdf, path) -> files written``, each atomically."""
TEXTURE_READERS: dict[str, Callable[[Path], CSDF]] = {
    ".raw": read_raw,
    ".png": read_png,
    ".nrrd": read_nrrd,
}
"""3D texture reader by suffix: ``(existing path) -> CSDF``."""
MESH_SUFFIXES = tuple(MESH_WRITERS)
TEXTURE_SUFFIXES = tuple(TEXTURE_WRITERS)


def check_suffix(path: Path, allowed: tuple[str, ...], what: str) -> str:
    """The lower-case suffix of ``path``, or :class:`InputError` when it is not ``allowed``."""
    suf = path.suffix.lower()
    if suf not in allowed:
        raise InputError(
            f"{path}: expected {what} ending in {', '.join(allowed)}, got {suf or 'no suffix'}"
        )
    return suf


@keyword_options
def export_mesh(
    csdf: CSDF,
    path: str | os.PathLike,
    *,
    faces: int | None = None,
    error: float | None = None,
    atlas: int | None = None,
    progress: ProgressCallback | None = None,
) -> Path:
    """Write the zero level of ``csdf`` as a coloured triangle mesh (.glb, .ply or .obj).

    Marching cubes via :func:`partscale.surface.to_mesh`: world units, faces outward, watertight
    where the CSDF's solid is closed. Colours are sRGB in PLY/OBJ and linear in glTF ``COLOR_0``.
    The file is written atomically.

    Parameters
    ----------
    csdf : CSDF
        The object.
    path : str or os.PathLike
        The mesh file; its suffix picks the format.
    faces : int, optional
        Triangle budget: decimate to at most this many (:func:`.simplify.simplify`).
    error : float, optional
        Or decimate as far as the surface stays within about this many voxels of the full one.
    atlas : int, optional
        Unwrap with xatlas and bake the colour into a ``atlas``² base-colour texture (one of
        :data:`ATLAS_SIZES`): GLB with an embedded PNG, OBJ with ``NAME.mtl`` and ``NAME.png``
        beside it (written too). PLY has no texture convention and is refused.

    Returns
    -------
    pathlib.Path
        ``path`` (with an atlas, an OBJ's ``.mtl`` and ``.png`` beside it are written too).

    Examples
    --------
    >>> from partscale import data, export, ingest
    >>> export.export_mesh(ingest.load(data.table(), res=64), "table.glb", faces=2000)
    PosixPath('table.glb')
    """
    # trimesh and scikit-image load here, not at import: the CLI checks its options first, fast
    from ..surface import to_mesh

    path = Path(path)
    suffix = check_suffix(path, MESH_SUFFIXES, "a mesh file")
    require_usd(path)
    check_budget(faces, error)
    atlas = check_atlas(atlas)
    if atlas is not None and suffix == ".ply":
        raise InputError(
            f"{path}: expected .glb or .obj with an atlas (PLY has no textures), got .ply"
        )
    report = resolve(progress)
    report(0.0, "marching cubes")
    mesh = to_mesh(csdf)
    if faces is not None or error is not None:
        report(0.3, "decimating")
        mesh = simplify(mesh, voxel_size=csdf.voxel_size, faces=faces, error=error)
    if atlas is not None:
        mesh = _atlased(csdf, mesh, atlas, lambda f, m: report(0.4 + 0.4 * f, m))
    report(0.8, f"writing {suffix[1:].upper()}")
    with atomic_path(path) as tmp:
        MESH_WRITERS[suffix](csdf, mesh, tmp)
    report(1.0, "written")
    return path


def _atlased(csdf: CSDF, mesh, size: int, report):
    """``mesh`` split along xatlas's chart seams, with UVs and the baked texture as its visual."""
    import trimesh
    from PIL import Image

    report(0.0, "unwrapping (xatlas)")
    vmap, faces, uv = unwrap(mesh.vertices, mesh.faces, size)
    vertices = mesh.vertices[vmap]
    report(0.7, "baking colour")
    image = bake(csdf, vertices, faces, uv, size)
    tuv = uv.astype(np.float64)
    tuv[:, 1] = 1.0 - tuv[:, 1]  # trimesh's convention: v = 0 at the image's bottom
    # white diffuse: OBJ readers multiply Kd by map_Kd
    material = trimesh.visual.material.SimpleMaterial(
        image=Image.fromarray(image, "RGB"),
        diffuse=(255, 255, 255, 255),
        ambient=(255, 255, 255, 255),
        specular=(0, 0, 0, 255),
    )
    out = trimesh.Trimesh(
        vertices,
        faces,
        visual=trimesh.visual.TextureVisuals(uv=tuv, material=material),
        process=False,
    )
    for k, v in mesh.vertex_attributes.items():
        out.vertex_attributes[k] = v[vmap]
    return out


@keyword_options
def export_texture(
    csdf: CSDF,
    path: str | os.PathLike,
    *,
    size: int | None = None,
    progress: ProgressCallback | None = None,
) -> list[Path]:
    """Write ``csdf`` as an RGBA 3D texture (.raw + sidecar, .png flipbook + sidecar, or .nrrd).

    Parameters
    ----------
    csdf : CSDF
    path : path
        Output; the suffix picks the format (see :mod:`.textures` and :mod:`.nrrd` for each
        layout and encoding).
    size : int, optional
        Resize the grid first to one of :data:`PRESET_SIZES` voxels along the longest side.

    Returns
    -------
    list of Path
        Every file written (texture first, then its sidecar), all written atomically together.

    Examples
    --------
    >>> from partscale import data, export, ingest
    >>> export.export_texture(ingest.load(data.table(), res=64), "table.raw", size=32)
    [PosixPath('table.raw'), PosixPath('table.raw.json')]
    """
    path = Path(path)
    suffix = check_suffix(path, TEXTURE_SUFFIXES, "a 3D texture file")
    size = check_size(size)
    report = resolve(progress)
    if size is not None:
        csdf = resize_grid(csdf, size, progress=lambda f, m: report(0.5 * f, m))
    report(0.5, f"encoding {suffix[1:].upper()}")
    written = TEXTURE_WRITERS[suffix](csdf, path)
    report(1.0, "written")
    return written


def read_texture(path: str | os.PathLike) -> CSDF:
    """Decode a texture written by :func:`export_texture` back into a CSDF.

    ``sdf`` comes back within the encoding's precision (half float: relative 2^-11; PNG: half a
    quantisation step inside the encoded band, clamped beyond); ``rgb`` exactly (NRRD holds no
    colour: mid grey); ``parts`` are not stored in textures (all -1).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.raw`` or ``.png`` texture with its JSON sidecar beside it, or a ``.nrrd``.

    Returns
    -------
    CSDF
        The decoded object.

    Examples
    --------
    >>> from partscale import data, export, ingest
    >>> table = ingest.load(data.table(), res=64)
    >>> files = export.export_texture(table, "table.raw")
    >>> export.read_texture("table.raw").shape == table.shape
    True
    """
    path = Path(path)
    suffix = check_suffix(path, TEXTURE_SUFFIXES, "a 3D texture file")
    if not path.is_file():
        raise InputError(f"{path}: expected an existing texture file, got no such file")
    return TEXTURE_READERS[suffix](path)
