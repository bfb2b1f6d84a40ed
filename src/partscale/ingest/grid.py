"""SDF volumes -> CSDF: ``.npy``/``.npz`` grids and AutoSDF's HDF5 output.

A grid given at its own sampling is kept as it is (shifted so the surface is at 0). Resampled to
``res`` voxels along the object's longest side, the surface is first extracted (marching cubes
at ``iso``, the surface a renderer of the grid would show) and distances are then recomputed
exactly to it, so values near the surface are true distances at the new voxel size rather than
interpolated (and, for AutoSDF, clamped) values.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._options import keyword_options
from ..color import srgb_to_linear
from ..csdf import CSDF, check_number, check_origin, check_voxel_size, make
from ..errors import InputError, one_line
from ..progress import ProgressCallback, resolve, scaled
from .mesh import ColoredMesh, Material
from .mesh_sdf import check_res, from_mesh

AUTOSDF_DATASET = "pc_sdf_sample"
AUTOSDF_ISO = 0.02


def _check_volume(volume, name: str) -> np.ndarray:
    v = np.asarray(volume)
    if v.ndim != 3 or min(v.shape) < 2:
        raise InputError(f"{name}: expected a 3D SDF grid (X, Y, Z), got shape {v.shape}")
    if not (np.issubdtype(v.dtype, np.floating) or np.issubdtype(v.dtype, np.integer)):
        raise InputError(f"{name}: expected numeric SDF values, got dtype {v.dtype}")
    v = v.astype(np.float32, copy=False)
    bad = ~np.isfinite(v)
    if bad.any():
        raise InputError(
            f"{name}: expected finite SDF values, got {int(bad.sum())} NaN/inf voxel(s)"
        )
    return v


COLOR_RULE = (
    "integers in 0..255, or floats in [0, 1] (max <= 1.001, clipped) or in 0..255 (max > 2)"
)


def _check_colors(colors, shape, name: str) -> np.ndarray | None:
    """(X, Y, Z, 3) uint8 sRGB of a colour volume, by :data:`COLOR_RULE`.

    Integers must lie in 0..255 (never wrapped). Floats are [0, 1] when their max is at most
    1.001 (clipped to [0, 1]) and 0..255 when it is above 2 (at most 255.5); a max in (1.001, 2]
    or a min below -0.001 fits neither scale and is refused rather than guessed.
    """
    if colors is None:
        return None
    c = np.asarray(colors)
    if c.shape != (*shape, 3):
        raise InputError(f"{name}: expected a colour volume of shape {(*shape, 3)}, got {c.shape}")
    if c.dtype == np.uint8:
        return c
    if np.issubdtype(c.dtype, np.integer):
        ilo, ihi = int(c.min()), int(c.max())
        if ilo < 0 or ihi > 255:
            raise InputError(f"{name}: expected integer colours in 0..255, got [{ilo}, {ihi}]")
        return c.astype(np.uint8)
    if not np.issubdtype(c.dtype, np.floating):
        raise InputError(f"{name}: expected colours as {COLOR_RULE}, got dtype {c.dtype}")
    if not np.isfinite(c).all():
        raise InputError(f"{name}: expected finite colours, got NaN/inf")
    lo, hi = float(c.min()), float(c.max())
    if lo >= -1e-3 and hi <= 1.0 + 1e-3:
        return np.rint(np.clip(c, 0.0, 1.0) * 255.0).astype(np.uint8)
    if lo >= -1e-3 and 2.0 < hi <= 255.5:
        return np.rint(np.clip(c, 0.0, 255.0)).astype(np.uint8)
    raise InputError(f"{name}: expected colours as {COLOR_RULE}, got floats in [{lo:g}, {hi:g}]")


@keyword_options
def from_grid(
    sdf_volume,
    *,
    iso: float = 0.0,
    res: int | None = None,
    pad: int | None = None,
    colors=None,
    origin=(0.0, 0.0, 0.0),
    voxel_size: float = 1.0,
    source: str = "grid",
    progress: ProgressCallback | None = None,
) -> CSDF:
    """CSDF of a sampled signed distance volume.

    Parameters
    ----------
    sdf_volume : (X, Y, Z) float
        Signed distance samples (negative inside), world units; the surface is at ``iso``.
    iso : float
        Level of the surface in ``sdf_volume``.
    res : int, optional
        Resample to ``res`` voxels along the object's longest side (>= 16), re-distancing exactly
        to the marching-cubes surface. None keeps the grid as given (values shifted by ``-iso``).
    pad : int, optional
        Margin of empty voxels when resampling (see :func:`from_mesh`).
    colors : (X, Y, Z, 3) sRGB, optional
        Colour volume on the same grid; mid grey when omitted. Integers must lie in 0..255;
        floats are read as [0, 1] when their max is <= 1.001 (then clipped) and as 0..255 when
        it is > 2; anything else (a max in (1.001, 2], negatives) is refused, not guessed.
    origin : (3,) float
        World position of sample (0, 0, 0).
    voxel_size : float
        Sample spacing in world units.
    source : str
        Name used in messages and ``meta``.

    Returns
    -------
    CSDF

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import ingest
    >>> x, y, z = np.mgrid[-1:1:33j, -1:1:33j, -1:1:33j]
    >>> ball = ingest.from_grid(np.sqrt(x**2 + y**2 + z**2) - 0.5, origin=(-1, -1, -1), voxel_size=2 / 32)
    >>> ball.shape
    (33, 33, 33)
    """
    report = resolve(progress)
    v = _check_volume(sdf_volume, source)
    iso = check_number(iso, f"{source}: iso")
    origin = check_origin(origin, f"{source}: grid origin")
    voxel_size = check_voxel_size(voxel_size, f"{source}: grid voxel_size")
    col = _check_colors(colors, v.shape, source)
    inside = v <= iso
    if not inside.any() or inside.all():
        raise InputError(
            f"{source}: expected a surface at iso {iso:g}, got values in "
            f"[{float(v.min()):g}, {float(v.max()):g}]"
        )
    op = {"op": "import", "source": source, "iso": iso, "grid_shape": list(v.shape)}
    meta = {"source": source, "units": "m", "history": [op]}
    if res is None:
        report(1.0, "done")
        return make(v - np.float32(iso), col, None, origin, voxel_size, meta)

    res = check_res(res, source)
    mesh = grid_surface(v, iso, col, origin, voxel_size, source)
    report(0.1, "surface of the grid")
    out = from_mesh(mesh, res=res, pad=pad, progress=scaled(progress, 0.1, 1.0))
    op.update({k: out.meta["history"][0][k] for k in ("res", "pad")})
    return out.replace(meta=meta)


def grid_surface(v, iso, col, origin, voxel_size, source) -> ColoredMesh:
    """Marching-cubes surface of ``v`` at ``iso`` as a (vertex-coloured) :class:`ColoredMesh`.

    The volume is padded with outside values so the surface is closed even where the solid
    touches the grid's border.
    """
    from skimage import measure

    from ..surface import sample_linear

    outside = max(float(v.max()), iso + 1e-3)
    padded = np.pad(v, 1, mode="constant", constant_values=outside)
    verts, faces, _n, _vals = measure.marching_cubes(padded, level=iso, allow_degenerate=False)
    index = verts - 1.0
    world = np.asarray(origin, np.float64) + index * float(voxel_size)
    faces = faces.astype(np.int64)
    corner = None
    if col is not None:
        lin = srgb_to_linear(col.astype(np.float32) / 255.0)
        vc = np.clip(sample_linear(lin, index), 0.0, 1.0).astype(np.float32)
        corner = vc[faces]
    return ColoredMesh(
        vertices=world,
        faces=faces,
        face_material=np.zeros(len(faces), np.int32),
        materials=(Material(np.ones(3, np.float32) * (1.0 if col is not None else 0.2158)),),
        corner_color=corner,
        source=source,
    )


def read_grid(path: str | os.PathLike) -> dict:
    """Read an SDF volume from ``.npy`` or ``.npz``.

    ``.npy``: one (X, Y, Z) float array. ``.npz``: array ``sdf`` (or the only 3D array), and
    optionally ``rgb``/``colors`` (X, Y, Z, 3), ``origin`` (3,), ``voxel_size`` and ``iso``.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    dict
        :func:`from_grid` arguments (``sdf_volume``, ``colors``, ``origin``, ...), those the file
        holds.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import ingest
    >>> x, y, z = np.mgrid[-1:1:33j, -1:1:33j, -1:1:33j]
    >>> np.save("ball.npy", (np.sqrt(x**2 + y**2 + z**2) - 0.5).astype(np.float32))
    >>> ingest.from_grid(**ingest.read_grid("ball.npy")).shape
    (33, 33, 33)
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            if path.suffix.lower() == ".npy":
                return {"sdf_volume": np.load(fh, allow_pickle=False)}
            with np.load(fh, allow_pickle=False) as z:
                arrays = {n: z[n] for n in z.files}
    except InputError:
        raise
    except Exception as exc:  # numpy raises many kinds for a corrupt file
        raise InputError(f"{path}: expected a readable numpy grid, got {one_line(exc)}") from None
    if "sdf" in arrays:
        sdf = arrays["sdf"]
    else:
        cubes = [a for a in arrays.values() if a.ndim == 3]
        if len(cubes) != 1:
            raise InputError(
                f"{path}: expected an array 'sdf' (or exactly one 3D array), got {sorted(arrays)}"
            )
        sdf = cubes[0]
    out = {"sdf_volume": sdf}
    for key in ("rgb", "colors"):
        if key in arrays:
            out["colors"] = arrays[key]
    # checked by from_grid, which names the file
    for key in ("origin", "voxel_size", "iso"):
        if key in arrays:
            out[key] = arrays[key]
    return out


def read_autosdf(path: str | os.PathLike) -> dict:
    """Read AutoSDF's HDF5 output: dataset ``pc_sdf_sample``, an n^3 float32 SDF (flat or cubic).

    AutoSDF's convention: the object is normalised into the unit sphere, Y-up (as glTF, so no
    rotation), values clamped to +-0.2 and the surface at level 0.02; samples lie on
    ``linspace(-1, 1, n)`` along each axis, index (i, j, k) = (x, y, z).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.h5`` / ``.hdf5`` file.

    Returns
    -------
    dict
        :func:`from_grid` arguments: ``sdf_volume``, ``origin``, ``voxel_size`` and ``iso = 0.02``.

    Examples
    --------
    >>> import h5py
    >>> import numpy as np
    >>> from partscale import ingest
    >>> x, y, z = np.mgrid[-1:1:33j, -1:1:33j, -1:1:33j]
    >>> with h5py.File("ball.h5", "w") as f:
    ...     f["pc_sdf_sample"] = np.clip(np.sqrt(x**2 + y**2 + z**2) - 0.5, -0.2, 0.2).astype(np.float32)
    >>> ingest.read_autosdf("ball.h5")["iso"]
    0.02
    """
    import h5py

    path = Path(path)
    try:
        with h5py.File(path, "r") as f:
            if AUTOSDF_DATASET not in f:
                raise InputError(
                    f"{path}: expected an HDF5 dataset {AUTOSDF_DATASET!r} (AutoSDF), "
                    f"got {sorted(f.keys())}"
                )
            data = np.asarray(f[AUTOSDF_DATASET][()])
    except InputError:
        raise
    except Exception as exc:
        raise InputError(f"{path}: expected a readable HDF5 file, got {one_line(exc)}") from None
    n = round(data.size ** (1 / 3))
    if n**3 != data.size or n < 2:
        raise InputError(
            f"{path}: expected {AUTOSDF_DATASET} of n^3 values, got shape {data.shape}"
        )
    vol = data.reshape(n, n, n)
    return {
        "sdf_volume": vol,
        "iso": AUTOSDF_ISO,
        "origin": (-1.0, -1.0, -1.0),
        "voxel_size": 2.0 / (n - 1),
    }
