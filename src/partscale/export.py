"""Export a CSDF: a coloured mesh for every tool, 3D textures for engines and volume viewers.

Formats (chosen by the output's suffix)
---------------------------------------
Meshes (:func:`export_mesh`): marching cubes of the zero level (:func:`partscale.surface.to_mesh`),
faces outward, world units, per-vertex colours.

- ``.glb``: written here, not by trimesh, because glTF demands *linear* ``COLOR_0`` and trimesh
  writes the grid's sRGB bytes there. Positions, unit normals from the SDF gradient, ``COLOR_0``
  as float32 linear RGB, uint32 indices, one unlit-looking (non-metallic) material.
- ``.ply``: binary, vertex colours as sRGB uint8 (the PLY convention) and a ``parts`` int16
  vertex property (the part of the nearest voxel, -1 where none).
- ``.obj``: ``v x y z r g b`` with sRGB colours in [0, 1] (the common vertex-colour extension).

3D textures (:func:`export_texture`): RGBA with colour in RGB and signed distance in A, x
fastest (then y, then z). The grid arrays are indexed ``(i, j, k) = (x, y, z)`` in C order (z
fastest in memory), so they are transposed on the way out.

- ``.raw``: little-endian IEEE half floats, RGBA interleaved; RGB = sRGB / 255 in [0, 1];
  A = signed distance in world units (negative inside, iso level 0). Relative precision 2^-11.
  Sidecar ``NAME.raw.json``.
- ``.png``: an RGBA8 flipbook atlas of the z slices that Unity's texture importer reads as a
  Texture3D (Texture Shape 3D, columns x rows from the sidecar). Tiles run left to right, top to
  bottom (slice 0 top left); inside a tile x runs right and y runs *up* (Unity's textures start at
  the bottom row). RGB = sRGB bytes; A = ``clamp(round(128 + d / (K h) * 127), 0, 255)`` with
  ``h`` the voxel size and ``K`` = :data:`DISTANCE_BAND_VOXELS`; decode ``d = (A - 128) / 127 * K h``;
  the surface is at A = 128. When the depth does not factor into a near-square tile grid, empty
  slices pad it along +z (the sidecar's size includes them). Sidecar ``NAME.png.json``.
- ``.nrrd``: the SDF alone (float32, world units) with space origin and spacing, for ParaView and
  3D Slicer.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import struct
from pathlib import Path
from typing import Any

import numba
import numpy as np

from ._files import atomic_path
from ._memory import check_memory
from ._options import keyword_options
from .csdf import CSDF, make
from .errors import InputError
from .progress import ProgressCallback, resolve

PRESET_SIZES = (32, 64, 128, 256)
MESH_SUFFIXES = (".glb", ".ply", ".obj")
TEXTURE_SUFFIXES = (".raw", ".png", ".nrrd")
DISTANCE_BAND_VOXELS = 8.0
"""K of the 8-bit distance encoding: the PNG alpha covers distances within K voxels."""
ISO_LEVEL_8BIT = 128
TEXTURE_FORMAT = "partscale.texture3d"


# -- colour --------------------------------------------------------------------------------
def srgb_to_linear(srgb: np.ndarray) -> np.ndarray:
    """(..., C) uint8 sRGB -> (..., C) float64 linear in [0, 1] (the IEC 61966-2-1 curve)."""
    c = np.asarray(srgb, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """(..., C) float linear in [0, 1] -> (..., C) float64 sRGB in [0, 1]."""
    c = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


# -- checks --------------------------------------------------------------------------------
def _suffix(path: Path, allowed: tuple[str, ...], what: str) -> str:
    suf = path.suffix.lower()
    if suf not in allowed:
        raise InputError(
            f"{path}: expected {what} ending in {', '.join(allowed)}, got {suf or 'no suffix'}"
        )
    return suf


def check_size(size: int | None) -> int | None:
    """Validate a preset texture/mesh size (voxels along the grid's longest side)."""
    if size is None:
        return None
    if (
        isinstance(size, bool)
        or not isinstance(size, (int, np.integer))
        or size not in PRESET_SIZES
    ):
        raise InputError(f"size: expected one of {', '.join(map(str, PRESET_SIZES))}, got {size!r}")
    return int(size)


# -- resampling ----------------------------------------------------------------------------
def _axis_weights(n_src: int, src_index: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per output index along one axis: lower source cell, linear weight, nearest source voxel."""
    x = np.clip(src_index, 0.0, n_src - 1.0)
    i0 = np.minimum(np.floor(x).astype(np.int64), n_src - 2)
    return i0, (x - i0).astype(np.float32), np.rint(x).astype(np.int64)


@numba.njit(cache=True, parallel=True)
def _resample_kernel(sdf, rgb, parts, ax, ay, az, out_sdf, out_rgb, out_parts):
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
def resample(csdf: CSDF, size: int, *, progress: ProgressCallback | None = None) -> CSDF:
    """Resample to ``size`` voxels along the grid's longest side (cubic voxels).

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
    axes = tuple(_axis_weights(int(old_shape[a]), src[a]) for a in range(3))
    shape = tuple(int(n) for n in new_shape)
    sdf = np.empty(shape, np.float32)
    rgb = np.empty((*shape, 3), np.uint8)
    parts = np.empty(shape, np.int16)
    _resample_kernel(csdf.sdf, csdf.rgb, csdf.parts, *axes, sdf, rgb, parts)
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


# -- meshes --------------------------------------------------------------------------------
def _sdf_normals(csdf: CSDF, world: np.ndarray) -> np.ndarray:
    """(N, 3) float32 unit normals: the normalised SDF gradient (central differences)."""
    from .surface import sample_linear

    idx = csdf.world_to_index(world)
    g = np.empty_like(idx)
    for a in range(3):
        e = np.zeros(3)
        e[a] = 0.5
        g[:, a] = sample_linear(csdf.sdf, idx + e) - sample_linear(csdf.sdf, idx - e)
    n = np.linalg.norm(g, axis=1, keepdims=True)
    bad = n[:, 0] < 1e-12
    g[bad] = (0.0, 1.0, 0.0)
    n[bad] = 1.0
    g = (g / n).astype(np.float32)
    # renormalise in float32 so the validator's unit-length check holds to the last bit
    return g / np.linalg.norm(g, axis=1, keepdims=True)


def _pad4(b: bytes, fill: bytes = b"\x00") -> bytes:
    return b + fill * (-len(b) % 4)


def _write_glb(
    path: Path,
    positions: np.ndarray,
    normals: np.ndarray,
    colors: np.ndarray,
    faces: np.ndarray,
    extras: dict[str, Any],
) -> None:
    """Write one indexed triangle mesh as a binary glTF 2.0 file.

    positions, normals, colors : (V, 3) float32 (colours linear RGB in [0, 1])
    faces : (F, 3) uint32, counter-clockwise seen from outside
    """
    arrays = [
        ("POSITION", np.ascontiguousarray(positions, dtype="<f4")),
        ("NORMAL", np.ascontiguousarray(normals, dtype="<f4")),
        ("COLOR_0", np.ascontiguousarray(colors, dtype="<f4")),
    ]
    indices = np.ascontiguousarray(faces, dtype="<u4").reshape(-1)
    blob = bytearray()
    views, accessors, attributes = [], [], {}
    for name, arr in arrays:
        offset = len(blob)
        blob += arr.tobytes()
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": arr.nbytes, "target": 34962})
        acc = {
            "bufferView": len(views) - 1,
            "componentType": 5126,
            "count": len(arr),
            "type": "VEC3",
        }
        if name == "POSITION":
            acc["min"] = arr.min(axis=0).astype(float).tolist()
            acc["max"] = arr.max(axis=0).astype(float).tolist()
        attributes[name] = len(accessors)
        accessors.append(acc)
    offset = len(blob)
    blob += indices.tobytes()
    views.append({"buffer": 0, "byteOffset": offset, "byteLength": indices.nbytes, "target": 34963})
    accessors.append(
        {
            "bufferView": len(views) - 1,
            "componentType": 5125,
            "count": len(indices),
            "type": "SCALAR",
        }
    )
    blob = _pad4(bytes(blob))
    gltf = {
        "asset": {"version": "2.0", "generator": "partscale"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "csdf"}],
        "meshes": [
            {
                "name": "csdf",
                "primitives": [
                    {
                        "attributes": attributes,
                        "indices": len(accessors) - 1,
                        "material": 0,
                        "mode": 4,
                    }
                ],
            }
        ],
        # white base colour so COLOR_0 alone decides the colour; rough dielectric like paint
        "materials": [
            {
                "name": "vertex colour",
                "pbrMetallicRoughness": {
                    "baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.9,
                },
            }
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
        "extras": extras,
    }
    js = _pad4(json.dumps(gltf, separators=(",", ":")).encode(), b" ")
    total = 12 + 8 + len(js) + 8 + len(blob)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(js), b"JSON"))
        f.write(js)
        f.write(struct.pack("<I4s", len(blob), b"BIN\x00"))
        f.write(blob)


@keyword_options
def export_mesh(
    csdf: CSDF, path: str | os.PathLike, *, progress: ProgressCallback | None = None
) -> Path:
    """Write the zero level of ``csdf`` as a coloured triangle mesh (.glb, .ply or .obj).

    Marching cubes via :func:`partscale.surface.to_mesh`: world units, faces outward, watertight
    where the CSDF's solid is closed. Colours are sRGB in PLY/OBJ and linear in glTF ``COLOR_0``.
    The file is written atomically. Returns the path written.
    """
    # trimesh and scikit-image load here, not at import: the CLI checks its options first, fast
    from .surface import to_mesh

    path = Path(path)
    suffix = _suffix(path, MESH_SUFFIXES, "a mesh file")
    report = resolve(progress)
    report(0.0, "marching cubes")
    mesh = to_mesh(csdf)
    report(0.6, f"writing {suffix[1:].upper()}")
    with atomic_path(path) as tmp:
        if suffix == ".glb":
            positions = mesh.vertices.astype(np.float32)
            colors = srgb_to_linear(mesh.visual.vertex_colors[:, :3]).astype(np.float32)
            normals = _sdf_normals(csdf, mesh.vertices)
            extras = {
                "partscale": {
                    "units": csdf.meta.get("units", "m"),
                    "source": csdf.meta.get("source"),
                    "voxel_size": csdf.voxel_size,
                }
            }
            _write_glb(tmp, positions, normals, colors, mesh.faces.astype(np.uint32), extras)
        elif suffix == ".ply":
            mesh.export(tmp, file_type="ply", encoding="binary")
        else:
            mesh.export(tmp, file_type="obj", include_normals=False, include_texture=False)
    report(1.0, "written")
    return path


# -- 3D textures ---------------------------------------------------------------------------
def flipbook_layout(depth: int) -> tuple[int, int]:
    """(columns, rows) of the PNG atlas for ``depth`` z slices (Unity makes one slice per cell).

    ``columns * rows == depth`` when ``depth`` factors as ``c x r`` with ``r <= c <= 2 r``
    (128 -> 16 x 8, 64 -> 8 x 8); otherwise the smallest larger count that does (37 -> 8 x 5)
    and the texture's grid is padded in z, because a prime depth would give a one-row strip
    wider than engines accept.
    """
    d = max(int(depth), 1)
    while True:
        cols = next(c for c in range(math.ceil(math.sqrt(d)), d + 1) if d % c == 0)
        if cols <= 2 * (d // cols):
            return cols, d // cols
        d += 1


def _pad_z(csdf: CSDF, depth: int) -> CSDF:
    """Extend the grid to ``depth`` slices along +z with empty (outside) voxels.

    Padded distances are lower bounds of the true ones, as sphere tracing needs: the solid lies
    at or below the last slice, so a point ``k`` further out is at least ``sqrt(d^2 + k^2)`` from
    it (``d`` the last slice's distance); where the solid touches the border it is closed half a
    voxel beyond the last centre.
    """
    n = depth - csdf.shape[2]
    if n <= 0:
        return csdf
    h = csdf.voxel_size
    edge = csdf.sdf[:, :, -1:].astype(np.float64)
    k = np.arange(1, n + 1, dtype=np.float64) * h
    pad = np.where(edge > 0, np.sqrt(edge**2 + k**2), k - h / 2).astype(np.float32)
    rgb = np.repeat(csdf.rgb[:, :, -1:], n, axis=2)
    parts = np.full((*csdf.shape[:2], n), -1, np.int16)
    return csdf.replace(
        sdf=np.concatenate([csdf.sdf, pad], axis=2),
        rgb=np.concatenate([csdf.rgb, rgb], axis=2),
        parts=np.concatenate([csdf.parts, parts], axis=2),
    )


def _sidecar_path(path: Path) -> Path:
    return path.with_name(path.name + ".json")


def _texture_header(csdf: CSDF, encoding: dict[str, Any]) -> dict[str, Any]:
    return {
        "format": TEXTURE_FORMAT,
        "version": 1,
        "size": list(csdf.shape),
        "origin": csdf.origin.tolist(),
        "origin_meaning": "world position of voxel (0, 0, 0)'s centre",
        "voxel_size": csdf.voxel_size,
        "units": csdf.meta.get("units", "m"),
        "order": "x fastest, then y, then z",
        "channels": {
            "r": "red, sRGB",
            "g": "green, sRGB",
            "b": "blue, sRGB",
            "a": "signed distance to the surface, negative inside",
        },
        "color_space": "sRGB",
        "encoding": encoding,
        "source": csdf.meta.get("source"),
        "history": csdf.meta.get("history", []),
    }


def _rgba_half(csdf: CSDF) -> np.ndarray:
    """(Z, Y, X, 4) float16: the x-fastest RGBA volume of the raw format."""
    out = np.empty((*csdf.shape[::-1], 4), dtype="<f2")
    out[..., :3] = (csdf.rgb.transpose(2, 1, 0, 3).astype(np.float32) / 255.0).astype("<f2")
    out[..., 3] = csdf.sdf.transpose(2, 1, 0).astype("<f2")
    return out


def encode_distance_8bit(sdf: np.ndarray, voxel_size: float) -> np.ndarray:
    """(...) float distances -> (...) uint8 with the PNG flipbook's linear map (module doc)."""
    scale = 127.0 / (DISTANCE_BAND_VOXELS * voxel_size)
    return np.clip(np.rint(ISO_LEVEL_8BIT + sdf * scale), 0, 255).astype(np.uint8)


def decode_distance_8bit(alpha: np.ndarray, voxel_size: float) -> np.ndarray:
    """(...) uint8 -> (...) float32 world distances (inverse of :func:`encode_distance_8bit`)."""
    step = DISTANCE_BAND_VOXELS * voxel_size / 127.0
    return ((alpha.astype(np.float32) - ISO_LEVEL_8BIT) * step).astype(np.float32)


def _atlas(csdf: CSDF) -> tuple[np.ndarray, int, int]:
    """(rows * Y, cols * X, 4) uint8 flipbook of the z slices (layout in the module doc)."""
    X, Y, Z = csdf.shape
    cols, rows = flipbook_layout(Z)
    alpha = encode_distance_8bit(csdf.sdf, csdf.voxel_size)
    # (X, Y, Z, 4) -> (Z, Y, X, 4), then y flipped so y runs up inside each tile
    vol = np.concatenate([csdf.rgb, alpha[..., None]], axis=-1).transpose(2, 1, 0, 3)[:, ::-1]
    tiles = vol.reshape(rows, cols, Y, X, 4).transpose(0, 2, 1, 3, 4)
    return np.ascontiguousarray(tiles.reshape(rows * Y, cols * X, 4)), cols, rows


@keyword_options
def export_texture(
    csdf: CSDF,
    path: str | os.PathLike,
    *,
    size: int | None = None,
    progress: ProgressCallback | None = None,
) -> list[Path]:
    """Write ``csdf`` as an RGBA 3D texture (.raw + sidecar, .png flipbook + sidecar, or .nrrd).

    Parameters
    ----------
    csdf : CSDF
    path : path
        Output; the suffix picks the format (see the module doc for each layout and encoding).
    size : int, optional
        Resample first to one of :data:`PRESET_SIZES` voxels along the longest side.

    Returns
    -------
    list of Path
        Every file written (texture first, then its sidecar), all written atomically together.
    """
    path = Path(path)
    suffix = _suffix(path, TEXTURE_SUFFIXES, "a 3D texture file")
    size = check_size(size)
    report = resolve(progress)
    if size is not None:
        csdf = resample(csdf, size, progress=lambda f, m: report(0.5 * f, m))
    report(0.5, f"encoding {suffix[1:].upper()}")
    if suffix == ".nrrd":
        import nrrd

        header = {
            "type": "float",
            "dimension": 3,
            "space dimension": 3,
            "space directions": np.eye(3) * csdf.voxel_size,
            "space origin": csdf.origin.astype(float),
            "kinds": ["domain", "domain", "domain"],
            "space units": [csdf.meta.get("units", "m")] * 3,
            "encoding": "gzip",
            "content": "partscale signed distance, negative inside, iso level 0",
        }
        with atomic_path(path) as tmp:
            nrrd.write(str(tmp), csdf.sdf, header, index_order="F")
        report(1.0, "written")
        return [path]

    side = _sidecar_path(path)
    if suffix == ".raw":
        X, Y, Z = csdf.shape
        data = _rgba_half(csdf).tobytes()
        encoding = {
            "name": "rgba16f",
            "type": "float16",
            "byte_order": "little",
            "channels_interleaved": "RGBA",
            "rgb": "sRGB / 255 in [0, 1]",
            "a": "signed distance in world units",
            "iso_level": 0.0,
            "precision": "relative 2^-11 (IEEE half float)",
            "bytes": len(data),
            # x-fastest RGBA half is Unity's own Texture3D memory layout
            "unity": f"new Texture3D({X}, {Y}, {Z}, TextureFormat.RGBAHalf, false) then "
            "SetPixelData(bytes, 0) and Apply(); sample the alpha as the distance",
        }
        header = _texture_header(csdf, encoding)
        with contextlib.ExitStack() as stack:
            tmp = stack.enter_context(atomic_path(path))
            tmp_side = stack.enter_context(atomic_path(side))
            tmp.write_bytes(data)
            tmp_side.write_text(json.dumps(header, indent=2))
        report(1.0, "written")
        return [path, side]

    from PIL import Image

    check_memory(csdf.shape, 4 * 3, what="PNG flipbook")
    source_depth = csdf.shape[2]
    cols, rows = flipbook_layout(source_depth)
    csdf = _pad_z(csdf, cols * rows)
    atlas, cols, rows = _atlas(csdf)
    k = DISTANCE_BAND_VOXELS
    encoding = {
        "name": "rgba8-flipbook",
        "type": "uint8",
        "rgb": "sRGB bytes",
        "a": f"a = clamp(round({ISO_LEVEL_8BIT} + d / ({k:g} * voxel_size) * 127), 0, 255)",
        "decode": f"d = (a - {ISO_LEVEL_8BIT}) / 127 * {k:g} * voxel_size",
        "distance_band_voxels": k,
        "distance_step": k * csdf.voxel_size / 127,
        "iso_level": ISO_LEVEL_8BIT,
        "iso_level_normalized": ISO_LEVEL_8BIT / 255,
        "precision": "half a step (band / 254) within the encoded range, clamped beyond it",
        "flipbook": {
            "columns": cols,
            "rows": rows,
            "tile_size": [csdf.shape[0], csdf.shape[1]],
            "tile_order": "slice z = row * columns + column; rows from the top of the image",
            "tile_axes": "x to the right, y up (row 0 of a tile is y = Y - 1)",
            "padded_slices": cols * rows - source_depth,
            "padding": "slices beyond the source depth are empty space added along +z so the "
            "tiles fill the atlas; size and origin above describe the padded grid",
            "atlas_size": [int(atlas.shape[1]), int(atlas.shape[0])],
            # Unity's defaults (Max Size 2048, Non-Power of 2 ToNearest, compression) would
            # rescale or quantise the atlas and break the decode formula above.
            "unity": f"Texture Shape 3D, Columns {cols}, Rows {rows}, sRGB (Color Texture) on, "
            f"Alpha Source Input Texture Alpha, Non-Power of 2 None, Max Size >= "
            f"{max(atlas.shape[:2])}, Generate Mip Maps off, Filter Mode Bilinear, Wrap Mode "
            "Clamp, Compression None",
        },
    }
    header = _texture_header(csdf, encoding)
    with contextlib.ExitStack() as stack:
        tmp = stack.enter_context(atomic_path(path))
        tmp_side = stack.enter_context(atomic_path(side))
        Image.fromarray(atlas, mode="RGBA").save(tmp, format="PNG", compress_level=6)
        tmp_side.write_text(json.dumps(header, indent=2))
    report(1.0, "written")
    return [path, side]


def _read_sidecar(path: Path) -> dict[str, Any]:
    side = _sidecar_path(path)
    if not side.is_file():
        raise InputError(f"{path}: expected its sidecar {side.name} beside it, got no such file")
    try:
        header = json.loads(side.read_text())
        if header.get("format") != TEXTURE_FORMAT:
            raise ValueError(f"format {header.get('format')!r}")
        header["size"] = [int(s) for s in header["size"]]
        header["origin"] = [float(o) for o in header["origin"]]
        header["voxel_size"] = float(header["voxel_size"])
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{side}: expected a {TEXTURE_FORMAT} sidecar, got {exc}") from None
    return header


def read_texture(path: str | os.PathLike) -> CSDF:
    """Decode a texture written by :func:`export_texture` back into a CSDF.

    ``sdf`` comes back within the encoding's precision (half float: relative 2^-11; PNG: half a
    quantisation step inside the encoded band, clamped beyond); ``rgb`` exactly (NRRD holds no
    colour: mid grey); ``parts`` are not stored in textures (all -1).
    """
    path = Path(path)
    suffix = _suffix(path, TEXTURE_SUFFIXES, "a 3D texture file")
    if not path.is_file():
        raise InputError(f"{path}: expected an existing texture file, got no such file")
    meta = {"source": str(path)}
    if suffix == ".nrrd":
        import nrrd

        try:
            data, header = nrrd.read(str(path), index_order="F")
            origin = np.asarray(header["space origin"], dtype=np.float64)
            spacing = np.diag(np.asarray(header["space directions"], dtype=np.float64))
        except Exception as exc:  # pynrrd raises several unrelated types on bad files
            raise InputError(f"{path}: expected an NRRD volume, got {exc}") from None
        if not np.allclose(spacing, spacing[0]):
            raise InputError(f"{path}: expected cubic voxels, got spacing {spacing.tolist()}")
        return make(data.astype(np.float32), None, None, origin, float(spacing[0]), meta)

    header = _read_sidecar(path)
    X, Y, Z = header["size"]
    h = header["voxel_size"]
    if suffix == ".raw":
        raw = path.read_bytes()
        if len(raw) != X * Y * Z * 4 * 2:
            raise InputError(
                f"{path}: expected {X * Y * Z * 8} bytes for {X}x{Y}x{Z} RGBA half floats, "
                f"got {len(raw)}"
            )
        vol = np.frombuffer(raw, dtype="<f2").reshape(Z, Y, X, 4).transpose(2, 1, 0, 3)
        rgb = np.clip(np.rint(vol[..., :3].astype(np.float32) * 255), 0, 255).astype(np.uint8)
        sdf = vol[..., 3].astype(np.float32)
        return make(sdf, rgb, None, header["origin"], h, meta)

    from PIL import Image

    try:
        with Image.open(path) as im:
            atlas = np.asarray(im.convert("RGBA"))
    except OSError as exc:
        raise InputError(f"{path}: expected a PNG image, got {exc}") from None
    cols = int(header["encoding"]["flipbook"]["columns"])
    rows = int(header["encoding"]["flipbook"]["rows"])
    if atlas.shape != (rows * Y, cols * X, 4) or cols * rows != Z:
        raise InputError(
            f"{path}: expected a {cols * X}x{rows * Y} atlas of {Z} tiles, "
            f"got {atlas.shape[1]}x{atlas.shape[0]}"
        )
    vol = atlas.reshape(rows, Y, cols, X, 4).transpose(0, 2, 1, 3, 4).reshape(Z, Y, X, 4)
    vol = vol[:, ::-1].transpose(2, 1, 0, 3)
    sdf = decode_distance_8bit(vol[..., 3], h)
    return make(sdf, np.ascontiguousarray(vol[..., :3]), None, header["origin"], h, meta)
