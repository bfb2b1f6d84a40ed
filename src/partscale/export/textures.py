"""3D textures for engines: RGBA volumes with sRGB colour in RGB and signed distance in A.

x fastest (then y, then z): the grid arrays are indexed ``(i, j, k) = (x, y, z)`` in C order
(z fastest in memory), so they are transposed on the way out. Each file has a JSON sidecar
``NAME.EXT.json`` (format :data:`TEXTURE_FORMAT`) giving size, origin, voxel size, encoding.

- ``.raw``: little-endian IEEE half floats, RGBA interleaved; RGB = sRGB / 255 in [0, 1];
  A = signed distance in world units (negative inside, iso level 0). Relative precision 2^-11.
- ``.png``: an RGBA8 flipbook atlas of the z slices that Unity's texture importer reads as a
  Texture3D (Texture Shape 3D, columns x rows from the sidecar). Tiles run left to right, top to
  bottom (slice 0 top left); inside a tile x runs right and y runs *up* (Unity's textures start at
  the bottom row). RGB = sRGB bytes; A = ``clamp(round(128 + d / (K h) * 127), 0, 255)`` with
  ``h`` the voxel size and ``K`` = :data:`DISTANCE_BAND_VOXELS`; decode
  ``d = (A - 128) / 127 * K h``; the surface is at A = 128. When the depth does not factor into
  a near-square tile grid, empty slices pad it along +z (the sidecar's size includes them).
"""

from __future__ import annotations

import hashlib
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path, read_json, staged_writes
from .._memory import check_memory
from ..csdf import CSDF, make
from ..errors import InputError

DISTANCE_BAND_VOXELS = 8.0
"""K of the 8-bit distance encoding: the PNG alpha covers distances within K voxels."""
ISO_LEVEL_8BIT = 128
TEXTURE_FORMAT = "partscale.texture3d"


def flipbook_layout(depth: int) -> tuple[int, int]:
    """Columns and rows of the PNG atlas for ``depth`` z slices (Unity makes one slice per cell).

    ``columns * rows == depth`` when ``depth`` factors as ``c x r`` with ``r <= c <= 2 r``
    (128 -> 16 x 8, 64 -> 8 x 8); otherwise the smallest larger count that does (37 -> 8 x 5)
    and the texture's grid is padded in z, because a prime depth would give a one-row strip
    wider than engines accept.

    Parameters
    ----------
    depth : int
        Number of z slices.

    Returns
    -------
    (int, int)
        Columns and rows.

    Examples
    --------
    >>> from partscale.export import flipbook_layout
    >>> flipbook_layout(128), flipbook_layout(37)
    ((16, 8), (8, 5))
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
    """Encode distances with the PNG flipbook's linear map: ``a = 128 + d / (8 h) * 127``, clamped.

    Parameters
    ----------
    sdf : (...) float
        World distances.
    voxel_size : float
        The grid's voxel size ``h``, world units.

    Returns
    -------
    (...) uint8
        Encoded distances, the surface at 128 (:data:`ISO_LEVEL_8BIT`).

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.export import encode_distance_8bit
    >>> encode_distance_8bit(np.array([-0.1, 0.0, 0.1]), 0.1)
    array([112, 128, 144], dtype=uint8)
    """
    scale = 127.0 / (DISTANCE_BAND_VOXELS * voxel_size)
    return np.clip(np.rint(ISO_LEVEL_8BIT + sdf * scale), 0, 255).astype(np.uint8)


def decode_distance_8bit(alpha: np.ndarray, voxel_size: float) -> np.ndarray:
    """Decode the PNG flipbook's 8-bit distances (the inverse of :func:`encode_distance_8bit`).

    Parameters
    ----------
    alpha : (...) uint8
        Encoded distances, the surface at 128.
    voxel_size : float
        The grid's voxel size, world units.

    Returns
    -------
    (...) float32
        World distances, within half a quantisation step inside the encoded band.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.export import decode_distance_8bit
    >>> decode_distance_8bit(np.array([112, 128, 144], np.uint8), 0.1).round(3)
    array([-0.101,  0.   ,  0.101], dtype=float32)
    """
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


def write_raw(csdf: CSDF, path: Path) -> list[Path]:
    """Write the ``.raw`` half-float RGBA volume and its sidecar; returns both paths."""
    side = _sidecar_path(path)
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
    _write_pair(path, data, side, _texture_header(csdf, encoding))
    return [path, side]


def write_png(csdf: CSDF, path: Path) -> list[Path]:
    """Write the ``.png`` flipbook atlas and its sidecar; returns both paths."""
    from PIL import Image

    side = _sidecar_path(path)
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
    buf = io.BytesIO()
    Image.fromarray(atlas, mode="RGBA").save(buf, format="PNG", compress_level=6)
    _write_pair(path, buf.getvalue(), side, _texture_header(csdf, encoding))
    return [path, side]


def _write_pair(path: Path, data: bytes, side: Path, header: dict[str, Any]) -> None:
    """Write a texture and its sidecar so that a reader never takes one for the other's pair.

    The sidecar records the texture's sha256 (``content_sha256``), which :func:`_read_sidecar`
    checks. Both are written to temporaries first and renamed as one set
    (:func:`partscale._files.staged_writes`): the texture, then the sidecar; where a rename
    fails, both keep what they had (and were one interrupted between the two, the old
    sidecar's checksum would not match, so the pair is refused rather than misread).
    """
    header = {**header, "content_sha256": hashlib.sha256(data).hexdigest()}
    with staged_writes():
        with atomic_path(path) as tmp:
            tmp.write_bytes(data)
        with atomic_path(side) as tmp_side:
            tmp_side.write_text(json.dumps(header, indent=2))


def _read_sidecar(path: Path) -> dict[str, Any]:
    side = _sidecar_path(path)
    if not side.is_file():
        raise InputError(f"{path}: expected its sidecar {side.name} beside it, got no such file")
    header = read_json(side, what=f"a {TEXTURE_FORMAT} sidecar")
    want = header.get("content_sha256") if isinstance(header, dict) else None
    if want is not None and want != hashlib.sha256(path.read_bytes()).hexdigest():
        raise InputError(
            f"{side}: expected the sidecar of {path.name}, got one describing another texture "
            "(its content_sha256 does not match; a write was interrupted?)"
        )
    try:
        if header.get("format") != TEXTURE_FORMAT:
            raise ValueError(f"format {header.get('format')!r}")
        header["size"] = [int(s) for s in header["size"]]
        header["origin"] = [float(o) for o in header["origin"]]
        header["voxel_size"] = float(header["voxel_size"])
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise InputError(f"{side}: expected a {TEXTURE_FORMAT} sidecar, got {exc}") from None
    return header


def read_raw(path: Path) -> CSDF:
    """Decode a ``.raw`` texture and its sidecar (``parts`` all -1)."""
    meta = {"source": str(path)}
    header = _read_sidecar(path)
    X, Y, Z = header["size"]
    h = header["voxel_size"]
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


def read_png(path: Path) -> CSDF:
    """Decode a ``.png`` flipbook and its sidecar (``parts`` all -1)."""
    from PIL import Image

    meta = {"source": str(path)}
    header = _read_sidecar(path)
    X, Y, Z = header["size"]
    h = header["voxel_size"]
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
