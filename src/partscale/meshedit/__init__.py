"""The mesh route: edits applied to the source mesh itself, not to its CSDF.

``partscale scale IN.glb -o OUT.glb ...`` (mesh in, mesh out) takes this route: the same
:class:`partscale.edit.Recipe` (stretch, tile, global; several zones and axes) cuts the source's
triangles at the zone planes and moves its vertices, so UVs, materials, textures, normals and the
node structure survive and the triangle count grows only by the cuts and the tiled copies.
Tiling cannot blend: a seam is welded where the slab's cross-sections at its two planes match,
and reported (:class:`Seam`) where they do not.

Public API
----------
- :func:`edit_mesh_file` ``(src, dst, recipe) -> MeshEditResult``
- :func:`apply_recipe_to_scene` ``(scene, recipe) -> (scene, seams)``
- :func:`load_scene`, :func:`save_scene`; :data:`MESH_SUFFIXES` (in), :data:`OUTPUT_SUFFIXES`.
- :func:`mesh_frame` ``(path) -> MeshFrame``: a mesh's bounds and units where the CLI resolves
  ``--by``/``--copies`` (``--snap`` and ``fit`` use the mesh's CSDF: zones work on profiles).
- :func:`is_mesh_route` ``(src, dst) -> bool``: whether an edit takes this route (a mesh in and
  out); :func:`check_route` (that, refusing a mesh in with a CSDF out), :func:`check_square`,
  :func:`edit_target` (what its options resolve against) and
  :func:`report_lines` (what it says it did): the dispatch ``scale`` and ``fit`` share;
  :func:`off_plane_zones` names a recipe's zones off the axis planes, which the mesh route
  refuses (``fit`` then edits the mesh's CSDF and remeshes it).
"""

from ..ingest import MESH_SUFFIXES  # the mesh route reads what the CSDF route reads
from .dispatch import check_route, check_square, edit_target, is_mesh_route, report_lines
from .route import (
    OUTPUT_SUFFIXES,
    MeshEditResult,
    MeshFrame,
    Seam,
    apply_recipe_to_scene,
    edit_mesh_file,
    load_scene,
    mesh_frame,
    off_plane_zones,
    save_scene,
)

__all__ = [
    "MESH_SUFFIXES",
    "OUTPUT_SUFFIXES",
    "MeshEditResult",
    "MeshFrame",
    "Seam",
    "apply_recipe_to_scene",
    "check_route",
    "check_square",
    "edit_mesh_file",
    "edit_target",
    "is_mesh_route",
    "load_scene",
    "mesh_frame",
    "off_plane_zones",
    "report_lines",
    "save_scene",
]
