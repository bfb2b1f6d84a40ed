"""PLY and OBJ mesh writers (through trimesh), with sRGB vertex colours.

- ``.ply``: binary, vertex colours as sRGB uint8 (the PLY convention) and a ``parts`` int16
  vertex property (the part of the nearest voxel, -1 where none).
- ``.obj``: ``v x y z r g b`` with sRGB colours in [0, 1] (the common vertex-colour extension).
"""

from __future__ import annotations

from pathlib import Path

from ..csdf import CSDF


def write_ply(csdf: CSDF, mesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh marching-cubes surface of ``csdf``) as binary PLY."""
    mesh.export(path, file_type="ply", encoding="binary")


def write_obj(csdf: CSDF, mesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh marching-cubes surface of ``csdf``) as OBJ, no normals."""
    mesh.export(path, file_type="obj", include_normals=False, include_texture=False)
