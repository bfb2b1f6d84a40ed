"""PLY and OBJ mesh writers (through trimesh), with sRGB vertex colours.

- ``.ply``: binary, vertex colours as sRGB uint8 (the PLY convention) and a ``parts`` int16
  vertex property (the part of the nearest voxel, -1 where none).
- ``.obj``: ``v x y z r g b`` with sRGB colours in [0, 1] (the common vertex-colour extension).
"""

from __future__ import annotations

from pathlib import Path

from ..csdf import CSDF


def write_ply(csdf: CSDF, mesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh marching-cubes surface of ``csdf``) as binary PLY."""
    mesh.export(path, file_type="ply", encoding="binary")


def write_obj(csdf: CSDF, mesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh surface of ``csdf``) as OBJ, no normals.

    A textured mesh (``--atlas``) also gets ``NAME.mtl`` and ``NAME.png`` beside the final file
    (named after it, not after the temporary it is written to), each written atomically.
    """
    if mesh.visual.kind != "texture":
        mesh.export(path, file_type="obj", include_normals=False, include_texture=False)
        return
    from trimesh.exchange.obj import export_obj

    from .._files import atomic_path, final_path

    final = final_path(path)
    text, files = export_obj(
        mesh,
        include_normals=False,
        include_texture=True,
        return_texture=True,
        mtl_name=final.stem + ".mtl",
    )
    for name, blob in files.items():
        if name.endswith(".mtl"):
            # trimesh names the image after the material: name it after the OBJ instead
            blob = blob.replace(b"material_0.png", (final.stem + ".png").encode())
        else:
            name = final.stem + ".png"
        with atomic_path(final.parent / name) as tmp:
            Path(tmp).write_bytes(blob)
    Path(path).write_text(text)
