"""PLY and OBJ mesh writers (through trimesh), with sRGB vertex colours.

- ``.ply``: binary, vertex colours as sRGB uint8 (the PLY convention) and a ``parts`` int16
  vertex property (the part of the nearest voxel, -1 where none).
- ``.obj``: ``v x y z r g b`` with sRGB colours in [0, 1] (the common vertex-colour extension);
  materials and textures in companion files named after the OBJ (:func:`save_obj`).
"""

from __future__ import annotations

import os
from pathlib import Path

from ..csdf import CSDF

#: MTL statements whose last token is a texture file name
_MTL_MAPS = ("map_", "bump", "disp", "decal", "refl", "norm")


def write_ply(csdf: CSDF, mesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh marching-cubes surface of ``csdf``) as binary PLY."""
    mesh.export(path, file_type="ply", encoding="binary")


def write_obj(csdf: CSDF, mesh, path: Path) -> None:
    """Write ``mesh`` (the trimesh surface of ``csdf``) as OBJ, no normals (:func:`save_obj`)."""
    save_obj(mesh, path, include_normals=False)


def save_obj(
    geometry, path: str | os.PathLike, *, include_normals: bool | None = None
) -> list[Path]:
    """Write a trimesh Trimesh or Scene as OBJ, its MTL and textures beside it, atomically.

    Companions are named after the OBJ's stem, so outputs sharing a folder never overwrite each
    other's: ``NAME.mtl``, and ``NAME.png`` (one texture) or ``NAME_0.png``, ``NAME_1.png``...
    (several; the extension is the image's format). A Scene keeps one ``usemtl`` group per
    material. ``path`` may be an :func:`partscale._files.atomic_path` temporary: companions are
    then named after its destination. Every file goes to a temporary first and all are renamed
    only once all are written (companions before the OBJ that refers to them); on any error none
    changes.

    Parameters
    ----------
    geometry : trimesh.Trimesh or trimesh.Scene
    path : path-like
        The ``.obj`` to write.
    include_normals : bool, optional
        Write ``vn`` lines; None: only where normals are stored (trimesh's rule).

    Returns
    -------
    list of Path
        The OBJ (its destination), then its companions.

    Examples
    --------
    >>> import trimesh
    >>> from partscale.export import save_obj
    >>> save_obj(trimesh.creation.box(), "box.obj")
    [PosixPath('box.obj')]
    """
    from trimesh.exchange.obj import export_obj

    from .._files import atomic_path, final_path, staged_writes
    from .._interrupt import raise_if_interrupted

    path = Path(path)
    final = final_path(path)
    text, extra = export_obj(
        geometry,
        include_normals=include_normals,
        include_texture=True,
        return_texture=True,
        mtl_name=final.stem + ".mtl",
    )
    # trimesh catches BaseException around each material: a Ctrl-C or SIGTERM there returns an
    # OBJ without its materials or UVs instead of stopping; the signal was noted, so stop here
    raise_if_interrupted()
    images = sorted(n for n in extra if not n.lower().endswith(".mtl"))
    renamed = {
        n: f"{final.stem}{Path(n).suffix.lower()}"
        if len(images) == 1
        else f"{final.stem}_{k}{Path(n).suffix.lower()}"
        for k, n in enumerate(images)
    }
    files = {
        renamed.get(n, n): _renamed_maps(blob, renamed) if n.lower().endswith(".mtl") else blob
        for n, blob in extra.items()
    }
    written = [final]
    with staged_writes():
        # the MTL, then the textures in name order, then the OBJ (renamed in this order, so the
        # OBJ never refers to companions not yet in place), all or none
        for name, blob in sorted(files.items(), key=lambda f: (f[0] != final.stem + ".mtl", f[0])):
            target = final.parent / name
            with atomic_path(target) as tmp:
                tmp.write_bytes(blob)
            written.append(target)
        with atomic_path(path) as tmp_obj:
            tmp_obj.write_bytes(text.encode("utf-8"))
    return written


def _renamed_maps(blob: bytes, renamed: dict[str, str]) -> bytes:
    """An MTL's texture references renamed (``renamed``: old file name to new)."""
    if not renamed:
        return blob
    lines = blob.decode("utf-8").split("\n")
    for i, line in enumerate(lines):
        words = line.split()
        if len(words) >= 2 and words[0].startswith(_MTL_MAPS) and words[-1] in renamed:
            lines[i] = line[: line.rindex(words[-1])] + renamed[words[-1]]
    return "\n".join(lines).encode("utf-8")
