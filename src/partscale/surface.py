"""The zero level set of a CSDF as a triangle mesh (marching cubes), with colours and parts.

Shared by export, segmentation and evaluation, so the surface every stage sees is the same one.
"""

from __future__ import annotations

import numpy as np
import trimesh
from skimage import measure

from ._kernels import trilinear
from .csdf import CSDF
from .errors import InputError


def sample_linear(volume: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Trilinear samples of ``volume`` at continuous voxel indices.

    Parameters
    ----------
    volume : (X, Y, Z) or (X, Y, Z, C) array
        The grid (distances, colours, any numbers).
    index : (N, 3) float64
        Continuous indices (voxel centres at integers); clamped to the grid.

    Returns
    -------
    (N,) or (N, C) float64
        The samples, one per index (per channel for a 4-D volume).

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.surface import sample_linear
    >>> volume = np.arange(8.0).reshape(2, 2, 2)
    >>> sample_linear(volume, np.array([[0.5, 0.5, 0.5], [0, 0, 1]]))
    array([3.5, 1. ])
    """
    vol = np.asarray(volume)
    idx = np.ascontiguousarray(index, np.float64).reshape(-1, 3)
    # the 8 corners around each sample: the cost follows the samples (a surface's vertices)
    if vol.ndim == 3:
        return trilinear(vol[..., None], idx)[:, 0]
    return trilinear(vol, idx)


def sample_nearest(volume: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Nearest-voxel samples of ``volume`` (any dtype) at continuous indices (N, 3).

    Parameters
    ----------
    volume : (X, Y, Z) or (X, Y, Z, C) array, any dtype
        The grid (part labels, colours, distances).
    index : (N, 3) float
        Continuous indices (voxel centres at integers), rounded to the nearest voxel and
        clamped to the grid.

    Returns
    -------
    (N,) or (N, C) array of ``volume``'s dtype
        The nearest voxel's value for each index.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.surface import sample_nearest
    >>> volume = np.arange(8.0).reshape(2, 2, 2)
    >>> sample_nearest(volume, np.array([[0.4, 0.6, 1.2], [5, -1, 0]]))
    array([3., 4.])
    """
    ijk = np.rint(index).astype(np.intp)
    for a in range(3):
        np.clip(ijk[:, a], 0, volume.shape[a] - 1, out=ijk[:, a])
    return volume[ijk[:, 0], ijk[:, 1], ijk[:, 2]]


def to_mesh(csdf: CSDF, *, level: float = 0.0, attributes: bool = True) -> trimesh.Trimesh:
    """Marching cubes of ``csdf.sdf`` at ``level``, in world units, faces outward.

    The grid is padded by one outside voxel so the mesh is closed even where the solid touches
    the border. With ``attributes``, vertex colours (sRGB uint8 RGBA, trimesh's convention) are
    trilinear samples of ``rgb`` and ``mesh.vertex_attributes['parts']`` holds the nearest
    voxel's part index; without, the mesh is the geometry alone (for measures of its shape).

    Parameters
    ----------
    csdf : CSDF
        The object.
    level : float
        The distance (world units) whose level set is meshed: 0.0 is the surface, a positive
        one an offset surface outside it.
    attributes : bool
        Give the vertices colours and part indices.

    Returns
    -------
    trimesh.Trimesh
        Vertices (V, 3) float64 in world units; faces (F, 3) int64 wound outward.

    Raises
    ------
    InputError
        The grid has no surface at ``level`` (all inside or all outside).

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.surface import to_mesh
    >>> ball = shapes.sphere((0, 0, 0), 0.5, voxel_size=0.05)
    >>> mesh = to_mesh(ball)
    >>> mesh.is_watertight, round(float(mesh.volume), 2), mesh.visual.vertex_colors[0].tolist()
    (True, 0.52, [60, 120, 200, 255])
    """
    sdf = csdf.sdf
    if not (sdf <= level).any() or not (sdf > level).any():
        raise InputError(f"CSDF: expected a surface at level {level}, got none in the grid")
    pad_value = max(float(sdf.max()), level + csdf.voxel_size)
    padded = np.pad(sdf, 1, mode="constant", constant_values=pad_value)
    verts, faces, _normals, _values = measure.marching_cubes(
        padded, level=level, allow_degenerate=False
    )
    index = verts - 1.0
    world = csdf.index_to_world(index)
    # wound so the enclosed volume is positive (faces outward, as trimesh expects): the signed
    # volume alone, not trimesh's mass properties (inertia too), which cost as much as the
    # marching cubes
    a, b, c = (world[faces[:, i]] for i in range(3))
    if np.einsum("ij,ij->", a, np.cross(b, c)) < 0:
        faces = faces[:, ::-1]
    if not attributes:
        return trimesh.Trimesh(world, faces, process=False)
    rgb = np.clip(np.rint(sample_linear(csdf.rgb, index)), 0, 255).astype(np.uint8)
    rgba = np.concatenate([rgb, np.full((len(rgb), 1), 255, np.uint8)], axis=1)
    mesh = trimesh.Trimesh(world, faces, vertex_colors=rgba, process=False)
    mesh.vertex_attributes["parts"] = sample_nearest(csdf.parts, index).astype(np.int16)
    return mesh
