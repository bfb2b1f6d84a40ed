"""One entry point for every supported input: dispatch on the file's content, then its suffix.

Readers, one module per format, are registered by suffix in :data:`MESH_READERS` (meshes ->
:class:`ColoredMesh`) and by sniffed kind in :data:`GRID_READERS` (SDF volumes -> the keyword
arguments of :func:`from_grid`).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._files import check_input_file
from .._options import keyword_options
from ..csdf import CSDF
from ..errors import InputError, one_line
from ..progress import ProgressCallback, resolve, scaled
from .gltf import check_gltf, load_gltf, load_gltf_scene
from .grid import from_grid, read_autosdf, read_grid
from .mesh import ColoredMesh, check_scene
from .mesh_sdf import check_pad, check_res, from_mesh
from .obj import load_obj, load_obj_scene
from .ply import load_ply

if TYPE_CHECKING:
    import trimesh

FORMATS = ".glb, .gltf, .obj, .ply (meshes); .npy, .npz, .h5/.hdf5 AutoSDF (SDF grids)"

MESH_READERS: dict[str, Callable[[Path], ColoredMesh]] = {
    ".glb": load_gltf,
    ".gltf": load_gltf,
    ".obj": load_obj,
    ".ply": load_ply,
}
"""Mesh reader by lower-case suffix: ``(path) -> ColoredMesh`` of an existing, non-empty file."""
MESH_SUFFIXES = tuple(MESH_READERS)

GRID_READERS: dict[str, Callable[[Path], dict[str, Any]]] = {
    "npy": read_grid,
    "npz": read_grid,
    "hdf5": read_autosdf,
}
"""SDF volume reader by :func:`sniff` kind: ``(path) -> from_grid keyword arguments``."""


def load_mesh(path: str | os.PathLike) -> ColoredMesh:
    """Read a coloured triangle mesh: glTF/GLB, OBJ+MTL or PLY (by suffix, :data:`MESH_READERS`).

    All scene nodes are placed by their transforms. Each triangle keeps its material (base
    colour factor and texture), its corner UVs and vertex colours, so the colour at any surface
    point can be evaluated with :meth:`ColoredMesh.color_at`.

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file.

    Returns
    -------
    ColoredMesh
        Its triangles in world positions, with their materials.

    Raises
    ------
    InputError
        Naming the file for a missing, unreadable, corrupt or empty mesh.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> mesh = ingest.load_mesh(data.table())
    >>> mesh.vertices.shape[1], mesh.faces.dtype
    (3, dtype('int64'))
    """
    path = check_mesh_file(path)
    return MESH_READERS[path.suffix.lower()](path)


def load_mesh_scene(path: str | os.PathLike) -> trimesh.Scene:
    """Read a mesh file as a ``trimesh.Scene`` to edit and write again (the mesh route).

    Vertices, nodes and UVs are kept as stored (no merging or reordering); materials follow
    the conventions of :func:`load_mesh`, so both routes show one file in the same colours.
    An OBJ gets one node per group (named after it), its materials as glTF ones whose base
    colour factor is ``Kd`` linearised (``Kd`` is a display sRGB colour), and faces without
    ``vt`` beside faces with keep a UV (0, 0). A missing material library or texture is said
    (a :class:`~partscale.errors.PartscaleWarning`) and the material's own colour used, as
    :func:`load_mesh` does.

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file (one of :data:`MESH_SUFFIXES`).

    Returns
    -------
    trimesh.Scene
        Its meshes, materials and node transforms.

    Raises
    ------
    InputError
        As :func:`load_mesh` raises it.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> scene = ingest.load_mesh_scene(data.table())
    >>> len(scene.geometry), scene.extents.round(2).tolist()
    (1, [2.44, 0.95, 1.3])
    """
    import trimesh

    path = check_mesh_file(path)
    suffix = path.suffix.lower()
    scene: trimesh.Scene
    if suffix == ".obj":
        scene = load_obj_scene(path)
    elif suffix in (".gltf", ".glb"):
        scene = load_gltf_scene(path)
    else:
        try:
            scene = trimesh.load_scene(path, process=False, maintain_order=True)
        except Exception as exc:  # trimesh's parsers raise many kinds on junk
            raise InputError(
                f"{path}: expected a readable {suffix[1:]} mesh, got {one_line(exc)}"
            ) from None
    if not scene.geometry:
        raise InputError(f"{path}: expected a mesh with triangles, got none")
    check_scene(scene, path)  # import's own checks: triangles, indices, finite, extent
    return scene


def check_mesh_file(path: str | os.PathLike) -> Path:
    """Check that ``path`` is an existing, non-empty file with a :data:`MESH_SUFFIXES` suffix.

    Parameters
    ----------
    path : str or os.PathLike
        A path given as a mesh file: checked, not read.

    Returns
    -------
    pathlib.Path
        The path.

    Raises
    ------
    InputError
        Naming the file, otherwise.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> ingest.check_mesh_file(data.table()).name
    'table.glb'
    """
    path = check_input_file(path, what="an existing mesh file")
    suffix = path.suffix.lower()
    if suffix not in MESH_READERS:
        raise InputError(
            f"{path}: expected a mesh ({', '.join(MESH_SUFFIXES)}), got suffix {suffix or 'none'}"
        )
    if path.stat().st_size == 0:
        raise InputError(f"{path}: expected a {suffix[1:]} mesh, got an empty file (0 bytes)")
    check_gltf(path)  # strict JSON (depth, numbers) before trimesh parses it, on every route
    return path


def sniff(path: Path) -> str:
    """Kind of file: 'mesh', 'npy', 'npz', 'hdf5'; :class:`InputError` if unknown or missing."""
    if not path.exists():
        raise InputError(f"{path}: expected an existing input file, got no such file")
    if not path.is_file():
        raise InputError(f"{path}: expected a file, got a directory")
    with open(path, "rb") as fh:
        head = fh.read(16)
    suffix = path.suffix.lower()
    if not head:
        raise InputError(f"{path}: expected one of {FORMATS}, got an empty file (0 bytes)")
    if head.startswith(b"glTF") or head[:3] == b"ply":
        return "mesh"
    if head.startswith(b"\x93NUMPY"):
        return "npy"
    if head.startswith(b"\x89HDF\r\n\x1a\n"):
        return "hdf5"
    if head.startswith(b"PK") and suffix == ".npz":
        return "npz"
    if suffix in MESH_READERS:
        return "mesh"  # a corrupt mesh: the mesh reader says what is wrong
    if suffix in (".npy", ".npz"):
        return suffix[1:]
    if suffix in (".h5", ".hdf5"):
        return "hdf5"
    raise InputError(
        f"{path}: expected one of {FORMATS}, got unknown format {suffix or '(no suffix)'}"
    )


@keyword_options
def load(
    path: str | os.PathLike,
    *,
    res: int = 128,
    pad: int | None = None,
    iso: float | None = None,
    colors: str | os.PathLike | None = None,
    up: str = "y",
    scale: float | None = None,
    units: str | None = None,
    square: bool = False,
    progress: ProgressCallback | None = None,
) -> CSDF:
    """Import any supported file as a CSDF.

    Parameters
    ----------
    path : path
        Mesh (``.glb``, ``.gltf``, ``.obj`` + ``.mtl``, ``.ply``) or SDF grid (``.npy``,
        ``.npz``, AutoSDF ``.h5``).
    res : int
        Voxels along the object's longest side (>= 16); grids are resampled to it.
    pad : int, optional
        Empty voxels around the object (default ``partscale.csdf.BAND_VOXELS + 2``).
    iso : float, optional
        Surface level of a grid (default 0, AutoSDF 0.02); not valid for meshes.
    colors : path, optional
        ``.npy`` colour volume (X, Y, Z, 3) for a grid, sRGB: integers in 0..255, or floats in
        [0, 1] (max <= 1.001) or 0..255 (max > 2); other ranges are refused (see ``from_grid``).
    up : str
        The mesh's up axis, one of :data:`UP_AXES` (``'z'`` for Z-up CAD and Blender exports):
        the mesh is rotated (a proper rotation) so that it points along +y, partscale's up.
    scale : float, optional
        Multiply the mesh's coordinates by this (> 0), after ``units``.
    units : str, optional
        The mesh's length unit, one of :data:`partscale.edit.SUFFIXES` (mm, cm, m, in; ``'cm'``
        for an armchair 190 units wide): converted to metres.
    square : bool
        Turn the mesh about up so that its walls run along x and z
        (:func:`partscale.orient.square_turn`; zones are planes square to the axes). Meshes
        only.
    progress : callable(fraction, message), optional

    Returns
    -------
    CSDF
        ``meta['source']`` is the file; ``meta['history'][0]`` records the import parameters
        (with ``up``, ``units`` and ``scale`` where given) and, for a mesh, the turn about up
        that would square it: ``turned_deg`` where ``square`` made it (0.0 where none was
        needed or found), else ``off_square_deg`` where one was found.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> table = ingest.load(data.table(), res=64)
    >>> table.shape, table.meta["units"], table.meta["history"][0]["op"]
    ((75, 36, 46), 'm', 'import')
    """
    path = Path(path)
    report = resolve(progress)
    kind = sniff(path)
    res = check_res(res, str(path))
    if not isinstance(square, bool):
        raise InputError(f"{path}: expected square True or False, got {square!r}")
    if pad is not None:
        check_pad(pad, str(path))
    if kind == "mesh":
        if iso is not None:
            raise InputError(
                f"{path}: expected no iso for a mesh (it is for SDF grids), got {iso}",
                params=("iso",),
            )
        if colors is not None:
            raise InputError(f"{path}: expected no colour volume for a mesh, got {colors}")
        report(0.0, "reading mesh")
        mesh = load_mesh(path)
        mesh, placed = _place(mesh, up=up, scale=scale, units=units, name=str(path))
        mesh, found = _square(mesh, square)
        placed.update(found)
        out = from_mesh(mesh, res=res, pad=pad, progress=scaled(progress, 0.05, 1.0))
    else:
        if up != "y" or scale is not None or units is not None or square:
            raise InputError(
                f"{path}: expected up, scale, units and square only for meshes, got an SDF grid",
                params=("up", "scale", "units", "square"),
            )
        placed = {}
        args = GRID_READERS[kind](path)
        if iso is not None:
            args["iso"] = iso
        if colors is not None:
            args["colors"] = _read_colors(Path(colors))
        out = from_grid(**args, res=res, pad=pad, source=str(path), progress=progress)
    meta = dict(out.meta)
    meta["source"] = str(path)
    first, *rest = meta["history"]
    meta["history"] = [{**first, "source": str(path), "format": kind, **placed}, *rest]
    return out.replace(meta=meta)


#: up axes a mesh may have (``--up``) and the rotation taking each onto +y (rows: new x, y, z)
UP_AXES: dict[str, tuple[tuple[int, int, int], ...]] = {
    "y": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "-y": ((1, 0, 0), (0, -1, 0), (0, 0, -1)),
    "z": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
    "-z": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "x": ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
    "-x": ((0, 1, 0), (-1, 0, 0), (0, 0, 1)),
}


def _place(mesh: ColoredMesh, *, up: str, scale, units, name: str):
    """``mesh`` turned Y-up and scaled to metres, and what was done (for the history)."""
    import dataclasses
    import math

    import numpy as np

    key = str(up).lower()
    if key not in UP_AXES:
        raise InputError(
            f"{name}: expected up one of {', '.join(UP_AXES)}, got {up!r}", params=("up",)
        )
    unit = 1.0
    if units is not None:
        # the unit table's one home: the lengths a designer types take the same units (the
        # edit package, with its kernels, only loaded when a unit is given)
        from ..edit import SUFFIXES as UNITS

        if str(units).lower() not in UNITS:
            raise InputError(
                f"{name}: expected units one of {', '.join(UNITS)}, got {units!r}",
                params=("units",),
            )
        unit = UNITS[str(units).lower()]
    if scale is not None and not (
        isinstance(scale, int | float) and math.isfinite(scale) and scale > 0
    ):
        raise InputError(
            f"{name}: expected scale a finite number > 0, got {scale!r}", params=("scale",)
        )
    factor = unit * (1.0 if scale is None else float(scale))
    placed: dict = {}
    if key == "y" and factor == 1.0:
        if units is not None:
            placed["units"] = str(units).lower()
        return mesh, placed
    rot = np.asarray(UP_AXES[key], np.float64)
    vertices = (mesh.vertices @ rot.T) * factor
    placed = {"up": key, "scale": factor}
    if units is not None:
        placed["units"] = str(units).lower()
    return dataclasses.replace(mesh, vertices=vertices), placed


def _square(mesh: ColoredMesh, square: bool) -> tuple[ColoredMesh, dict]:
    """``mesh`` turned square about up where ``square`` (and a turn is found), and what was
    found or done (for the history).
    """
    import dataclasses

    from ..orient import square_turn, turn_about_up

    turn = square_turn(mesh.vertices[mesh.faces])
    if not square:
        return mesh, {} if turn is None else {"off_square_deg": round(turn, 2)}
    if turn is None:
        return mesh, {"turned_deg": 0.0}
    turned = dataclasses.replace(mesh, vertices=turn_about_up(mesh.vertices, turn))
    return turned, {"turned_deg": round(turn, 2)}


def _read_colors(path: Path):
    import numpy as np

    check_input_file(path, what="an existing colour volume (.npy)")
    try:
        with open(path, "rb") as fh:
            return np.load(fh, allow_pickle=False)
    except Exception as exc:
        raise InputError(f"{path}: expected a .npy colour volume, got {one_line(exc)}") from None
