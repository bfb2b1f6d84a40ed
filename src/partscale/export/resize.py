"""Grid resizing for export: the whole CSDF resampled to a preset size (textures, meshes).

Not the edit stage's slab resampling (:mod:`partscale.edit`): this changes the voxel size and
keeps the world box.
"""

from __future__ import annotations

from typing import overload

import numba
import numpy as np

from .._memory import check_memory
from .._options import keyword_options, preset
from ..csdf import CSDF
from ..progress import ProgressCallback, resolve

PRESET_SIZES = (32, 64, 128, 256)


@overload
def check_size(size: int, what: str = ...) -> int: ...
@overload
def check_size(size: None, what: str = ...) -> None: ...
def check_size(size: int | None, what: str = "size") -> int | None:
    """Validate a preset grid size: None, or one of :data:`PRESET_SIZES` voxels along the longest side.

    Parameters
    ----------
    size : int or None
        Voxels along the longest side, or None to keep the grid.
    what : str
        Its name in the :class:`~partscale.errors.InputError`.

    Returns
    -------
    int or None
        The size.

    Examples
    --------
    >>> from partscale.export import check_size
    >>> check_size(64)
    64
    """
    return preset(size, what, PRESET_SIZES)


def _axis_weights(n_src: int, src_index: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per output index along one axis: lower source cell, linear weight, nearest source voxel."""
    x = np.clip(src_index, 0.0, n_src - 1.0)
    i0 = np.minimum(np.floor(x).astype(np.int64), n_src - 2)
    return i0, (x - i0).astype(np.float32), np.rint(x).astype(np.int64)


@numba.njit(cache=True, parallel=True)
def _resize_kernel(sdf, rgb, parts, ax, ay, az, out_sdf, out_rgb, out_parts):
    # trilinear is separable: per-axis cells and weights are precomputed, so each output voxel
    # costs 8 reads per channel and no coordinate arrays the size of the grid are needed
    (i0s, wxs, nxs), (j0s, wys, nys), (k0s, wzs, nzs) = ax, ay, az
    for a in numba.prange(out_sdf.shape[0]):
        i, fx, ni = i0s[a], wxs[a], nxs[a]
        for b in range(out_sdf.shape[1]):
            j, fy, nj = j0s[b], wys[b], nys[b]
            for c in range(out_sdf.shape[2]):
                k, fz, nk = k0s[c], wzs[c], nzs[c]
                w000 = (1 - fx) * (1 - fy) * (1 - fz)
                w100 = fx * (1 - fy) * (1 - fz)
                w010 = (1 - fx) * fy * (1 - fz)
                w110 = fx * fy * (1 - fz)
                w001 = (1 - fx) * (1 - fy) * fz
                w101 = fx * (1 - fy) * fz
                w011 = (1 - fx) * fy * fz
                w111 = fx * fy * fz
                out_sdf[a, b, c] = (
                    sdf[i, j, k] * w000
                    + sdf[i + 1, j, k] * w100
                    + sdf[i, j + 1, k] * w010
                    + sdf[i + 1, j + 1, k] * w110
                    + sdf[i, j, k + 1] * w001
                    + sdf[i + 1, j, k + 1] * w101
                    + sdf[i, j + 1, k + 1] * w011
                    + sdf[i + 1, j + 1, k + 1] * w111
                )
                for ch in range(3):
                    v = (
                        rgb[i, j, k, ch] * w000
                        + rgb[i + 1, j, k, ch] * w100
                        + rgb[i, j + 1, k, ch] * w010
                        + rgb[i + 1, j + 1, k, ch] * w110
                        + rgb[i, j, k + 1, ch] * w001
                        + rgb[i + 1, j, k + 1, ch] * w101
                        + rgb[i, j + 1, k + 1, ch] * w011
                        + rgb[i + 1, j + 1, k + 1, ch] * w111
                    )
                    out_rgb[a, b, c, ch] = min(max(int(v + 0.5), 0), 255)
                out_parts[a, b, c] = parts[ni, nj, nk]


@keyword_options
def resize_grid(csdf: CSDF, size: int, *, progress: ProgressCallback | None = None) -> CSDF:
    """Resample the whole grid to ``size`` voxels along its longest side (cubic voxels).

    The new grid covers the same world box: its longest side spans exactly the old grid's extent,
    the other sides the nearest whole number of new voxels, centred on the old grid. ``sdf`` and
    ``rgb`` are trilinear (distances stay in world units), ``parts`` take the nearest voxel; source
    positions beyond the old grid's outer voxel centres clamp to them.

    Parameters
    ----------
    csdf : CSDF
    size : int
        One of :data:`PRESET_SIZES`.

    Returns
    -------
    CSDF
        ``sdf`` (X', Y', Z') float32 with ``max(X', Y', Z') == size``; history records the step.

    Examples
    --------
    >>> from partscale import data, export, ingest
    >>> export.resize_grid(ingest.load(data.table(), res=64), 32).shape
    (32, 15, 20)
    """
    size = check_size(size)
    report = resolve(progress)
    old_shape = np.asarray(csdf.shape)
    extent = old_shape * csdf.voxel_size
    h = float(extent.max() / size)
    new_shape = np.maximum(np.rint(extent / h).astype(int), 2)
    new_shape[int(np.argmax(extent))] = size
    check_memory(tuple(new_shape), 4 + 3 + 2, what=f"resample to {size}")
    centre = csdf.origin + (old_shape - 1) / 2 * csdf.voxel_size
    origin = centre - (new_shape - 1) / 2 * h
    # continuous source index of every new voxel centre, per axis
    src = [
        (origin[a] + np.arange(new_shape[a]) * h - csdf.origin[a]) / csdf.voxel_size
        for a in range(3)
    ]
    report(0.0, "resampling")
    ax, ay, az = (_axis_weights(int(old_shape[a]), src[a]) for a in range(3))
    shape = tuple(int(n) for n in new_shape)
    sdf = np.empty(shape, np.float32)
    rgb = np.empty((*shape, 3), np.uint8)
    parts = np.empty(shape, np.int16)
    _resize_kernel(csdf.sdf, csdf.rgb, csdf.parts, ax, ay, az, sdf, rgb, parts)
    report(1.0, "resampled")
    op = {
        "op": "resample",
        "size": size,
        "from_shape": old_shape.tolist(),
        "to_shape": new_shape.tolist(),
        "from_voxel_size": csdf.voxel_size,
        "voxel_size": h,
    }
    return csdf.with_history(op, sdf=sdf, rgb=rgb, parts=parts, origin=origin, voxel_size=h)
