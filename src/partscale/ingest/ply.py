"""PLY reader (ASCII or binary) through trimesh: vertex or face colours are display sRGB."""

from __future__ import annotations

from pathlib import Path

from .mesh import ColoredMesh, read_scene, scene_to_mesh


def load_ply(path: Path) -> ColoredMesh:
    """Read a ``.ply`` (an existing, non-empty file) as a :class:`ColoredMesh`."""
    import trimesh

    scene = read_scene(path, lambda: trimesh.load_scene(str(path), process=False))
    return scene_to_mesh(scene, path, linear_colors=False)
