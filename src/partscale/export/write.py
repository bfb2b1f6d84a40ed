"""The export entry points: writers and readers registered by suffix, one module per format."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .._files import atomic_path
from .._options import keyword_options
from ..csdf import CSDF
from ..errors import InputError
from ..progress import ProgressCallback, resolve
from .glb import write_glb
from .mesh import write_obj, write_ply
from .nrrd import read_nrrd, write_nrrd
from .resize import check_size, resize_grid
from .textures import read_png, read_raw, write_png, write_raw

MESH_WRITERS: dict[str, Callable[[CSDF, Any, Path], None]] = {
    ".glb": write_glb,
    ".ply": write_ply,
    ".obj": write_obj,
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
    csdf: CSDF, path: str | os.PathLike, *, progress: ProgressCallback | None = None
) -> Path:
    """Write the zero level of ``csdf`` as a coloured triangle mesh (.glb, .ply or .obj).

    Marching cubes via :func:`partscale.surface.to_mesh`: world units, faces outward, watertight
    where the CSDF's solid is closed. Colours are sRGB in PLY/OBJ and linear in glTF ``COLOR_0``.
    The file is written atomically. Returns the path written.
    """
    # trimesh and scikit-image load here, not at import: the CLI checks its options first, fast
    from ..surface import to_mesh

    path = Path(path)
    suffix = check_suffix(path, MESH_SUFFIXES, "a mesh file")
    report = resolve(progress)
    report(0.0, "marching cubes")
    mesh = to_mesh(csdf)
    report(0.6, f"writing {suffix[1:].upper()}")
    with atomic_path(path) as tmp:
        MESH_WRITERS[suffix](csdf, mesh, tmp)
    report(1.0, "written")
    return path


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
    """
    path = Path(path)
    suffix = check_suffix(path, TEXTURE_SUFFIXES, "a 3D texture file")
    if not path.is_file():
        raise InputError(f"{path}: expected an existing texture file, got no such file")
    return TEXTURE_READERS[suffix](path)
