"""trimesh scenes: the triangle meshes of a scene's nodes, as every stage that reads one walks them."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any


def triangle_meshes(scene: Any) -> Iterator[tuple[Any, str, Any, Any]]:
    """The nodes of ``scene`` that place a triangle mesh, in the scene graph's order.

    Parameters
    ----------
    scene : trimesh.Scene
        The scene.

    Yields
    ------
    node : hashable
        The node's name.
    geometry : str
        Its geometry's name (a key of ``scene.geometry``).
    mesh : trimesh.Trimesh
        That geometry: a triangle mesh with at least one face (point clouds, paths and empty
        meshes are passed over).
    transform : (4, 4) float64
        The node's world transform, as the scene graph holds it.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale._scenes import triangle_meshes
    >>> [(geometry, len(mesh.faces)) for _, geometry, mesh, _ in triangle_meshes(ingest.load_mesh_scene(data.table()))]
    [('Mesh table', 120)]
    """
    import trimesh

    for node in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[node]
        mesh = scene.geometry[geometry]
        if isinstance(mesh, trimesh.Trimesh) and len(mesh.faces) > 0:
            yield node, geometry, mesh, transform
