"""Import: coloured meshes and SDF grids -> CSDF (the first stage of the pipeline).

Public API: :func:`load` (any supported file), :func:`load_mesh` + :func:`from_mesh` (meshes),
:func:`from_grid`, :func:`read_grid` and :func:`read_autosdf` (SDF volumes).
"""

from __future__ import annotations

from .grid import from_grid, read_autosdf, read_grid
from .load import load
from .mesh_io import ColoredMesh, Material, from_trimesh, load_mesh
from .mesh_sdf import BAND, from_mesh

__all__ = [
    "BAND",
    "ColoredMesh",
    "Material",
    "from_grid",
    "from_mesh",
    "from_trimesh",
    "load",
    "load_mesh",
    "read_autosdf",
    "read_grid",
]
