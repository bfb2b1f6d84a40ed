"""Binary glTF 2.0 (``.glb``) mesh writer.

Written here, not by trimesh, because glTF demands *linear* ``COLOR_0`` and trimesh writes the
grid's sRGB bytes there. Positions, unit normals from the SDF gradient, uint32 indices, and the
colour in the one layout each reader reads:

- atlased (``--atlas``): ``TEXCOORD_0`` and a material (rough dielectric) whose
  ``baseColorTexture`` is the baked sRGB PNG, embedded; no ``COLOR_0`` (it would multiply).
- vertex colours: ``COLOR_0`` as float32 linear RGB on a primitive *without* a material.
  trimesh reads ``COLOR_0`` as the mesh's colours only then (with a material it files them under
  ``vertex_attributes`` and shows the material's white); three.js, Blender and engines apply
  glTF's default material, times ``COLOR_0``.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import numpy as np

from ..color import srgb8_to_linear
from ..csdf import CSDF


def _sdf_normals(csdf: CSDF, world: np.ndarray) -> np.ndarray:
    """(N, 3) float32 unit normals: the normalised SDF gradient (central differences)."""
    from ..surface import sample_linear

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
    colors: np.ndarray | None,
    faces: np.ndarray,
    extras: dict[str, Any],
    uv: np.ndarray | None = None,
    png: bytes | None = None,
) -> None:
    """Write one indexed triangle mesh as a binary glTF 2.0 file.

    positions, normals : (V, 3) float32
    colors : (V, 3) float32 linear RGB in [0, 1], or None (with ``uv`` and ``png``)
    faces : (F, 3) uint32, counter-clockwise seen from outside
    uv : (V, 2) float32, v = 0 at the image's top; png : the base-colour texture
    """
    arrays = [
        ("POSITION", np.ascontiguousarray(positions, dtype="<f4")),
        ("NORMAL", np.ascontiguousarray(normals, dtype="<f4")),
    ]
    if colors is not None:
        arrays.append(("COLOR_0", np.ascontiguousarray(colors, dtype="<f4")))
    if uv is not None:
        arrays.append(("TEXCOORD_0", np.ascontiguousarray(uv, dtype="<f4")))
    indices = np.ascontiguousarray(faces, dtype="<u4").reshape(-1)
    blob: bytes | bytearray = bytearray()  # bytes once padded
    views: list[dict[str, Any]] = []
    accessors: list[dict[str, Any]] = []
    attributes: dict[str, int] = {}
    for name, arr in arrays:
        offset = len(blob)
        blob += arr.tobytes()
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": arr.nbytes, "target": 34962})
        acc = {
            "bufferView": len(views) - 1,
            "componentType": 5126,
            "count": len(arr),
            "type": "VEC2" if name == "TEXCOORD_0" else "VEC3",
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
    primitive = {"attributes": attributes, "indices": len(accessors) - 1, "mode": 4}
    textured = {}
    if png is not None:
        blob = bytearray(_pad4(bytes(blob)))
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(png)})
        blob += png
        primitive["material"] = 0
        textured = {
            "images": [{"bufferView": len(views) - 1, "mimeType": "image/png"}],
            # linear mipmapped minification: the atlas is padded so mip levels stay in charts
            "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 33071, "wrapT": 33071}],
            "textures": [{"sampler": 0, "source": 0}],
            # rough dielectric like paint; the texture alone decides the colour
            "materials": [
                {
                    "name": "baked colour",
                    "pbrMetallicRoughness": {
                        "baseColorTexture": {"index": 0},
                        "metallicFactor": 0.0,
                        "roughnessFactor": 0.9,
                    },
                }
            ],
        }
    blob = _pad4(bytes(blob))
    gltf = {
        "asset": {"version": "2.0", "generator": "partscale"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "csdf"}],
        "meshes": [{"name": "csdf", "primitives": [primitive]}],
        **textured,
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


def write_glb(csdf: CSDF, mesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh surface of ``csdf``) as a GLB at ``path``.

    A mesh with texture visuals (:func:`partscale.export.export_mesh` with ``atlas``) is written
    with its UVs and texture; otherwise with linear vertex colours.
    """
    positions = mesh.vertices.astype(np.float32)
    normals = _sdf_normals(csdf, mesh.vertices)
    extras = {
        "partscale": {
            "units": csdf.meta.get("units", "m"),
            "source": csdf.meta.get("source"),
            "voxel_size": csdf.voxel_size,
        }
    }
    faces = mesh.faces.astype(np.uint32)
    if mesh.visual.kind == "texture":
        from .atlas import png_bytes

        uv = np.array(mesh.visual.uv, np.float32)
        uv[:, 1] = 1.0 - uv[:, 1]  # trimesh keeps v = 0 at the bottom, glTF at the top
        mat = mesh.visual.material
        image = np.asarray((getattr(mat, "baseColorTexture", None) or mat.image).convert("RGB"))
        _write_glb(path, positions, normals, None, faces, extras, uv=uv, png=png_bytes(image))
        return
    colors = srgb8_to_linear(mesh.visual.vertex_colors[:, :3]).astype(np.float32)
    _write_glb(path, positions, normals, colors, faces, extras)
