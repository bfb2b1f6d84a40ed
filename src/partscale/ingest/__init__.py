"""Import: coloured meshes and SDF grids -> CSDF (the first stage of the pipeline).

Public API: :func:`load` (any supported file), :func:`load_mesh` + :func:`from_mesh` (meshes;
:func:`load_mesh_scene` reads one as a trimesh scene for the mesh route;
:func:`check_mesh_file` validates a mesh path, :func:`check_scene` its scene's geometry), :func:`from_grid`, :func:`read_grid` and
:func:`read_autosdf` (SDF volumes).

Modules: ``load`` (dispatch, the reader registries), one reader per format (``gltf``, ``obj``,
``ply``; ``grid`` for ``.npy``/``.npz``/AutoSDF volumes), ``mesh`` (:class:`ColoredMesh`, what
the mesh readers share), ``mesh_sdf`` (mesh -> CSDF).
"""

from __future__ import annotations

from .grid import from_grid, read_autosdf, read_grid
from .load import (
    GRID_READERS,
    MESH_READERS,
    MESH_SUFFIXES,
    check_mesh_file,
    load,
    load_mesh,
    load_mesh_scene,
)
from .mesh import ColoredMesh, Material, check_scene, from_trimesh
from .mesh_sdf import check_res, from_mesh

__all__ = [
    "GRID_READERS",
    "MESH_READERS",
    "MESH_SUFFIXES",
    "ColoredMesh",
    "Material",
    "check_mesh_file",
    "check_res",
    "check_scene",
    "from_grid",
    "from_mesh",
    "from_trimesh",
    "load",
    "load_mesh",
    "load_mesh_scene",
    "read_autosdf",
    "read_grid",
]
