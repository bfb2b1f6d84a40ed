"""``partscale export``: a CSDF as a coloured mesh and/or 3D textures."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..errors import InputError
from ..progress import ProgressCallback, scaled
from ._common import check_output, done, progress_bar


def export(
    path: Annotated[Path, typer.Argument(help="A .csdf.npz file.")],
    mesh: Annotated[
        Path | None,
        typer.Option("--mesh", help="Coloured mesh to write: OUT.glb, OUT.ply or OUT.obj."),
    ] = None,
    texture: Annotated[
        list[Path] | None,
        typer.Option(
            "--texture",
            help="3D texture to write (repeatable): OUT.raw (half float + JSON sidecar), "
            "OUT.png (Unity flipbook + JSON sidecar) or OUT.nrrd (SDF for ParaView/Slicer).",
        ),
    ] = None,
    size: Annotated[
        int | None,
        typer.Option(
            "--size",
            help="Resize the grid first to this many voxels along the longest side: "
            "32, 64, 128 or 256.",
        ),
    ] = None,
) -> None:
    """Export a CSDF as a mesh (marching cubes, vertex colours) and/or RGBA 3D textures."""
    # heavy modules (numba, trimesh, scikit-image) load only when this command runs
    from .. import export as export_mod
    from ..csdf import load

    textures = list(texture or [])
    if mesh is None and not textures:
        raise InputError("export: expected at least one output (--mesh or --texture), got none")
    if mesh is not None:
        check_output(mesh, suffixes=export_mod.MESH_SUFFIXES, what="a mesh file")
    for t in textures:
        check_output(t, suffixes=export_mod.TEXTURE_SUFFIXES, what="a 3D texture file")
    outputs = [mesh, *textures] if mesh is not None else textures
    if len({p.resolve() for p in outputs}) != len(outputs):
        raise InputError("export: expected distinct output files, got the same one twice")
    for p in outputs:
        if not p.parent.is_dir():
            raise InputError(f"{p}: expected an existing output folder, got none at {p.parent}")
    export_mod.check_size(size)
    c = load(path)
    written: list[Path] = []
    with progress_bar("export") as bar:
        n = len(outputs) + (size is not None)
        steps = iter(range(n))

        def part() -> ProgressCallback:
            i = next(steps)
            return scaled(bar, i / n, (i + 1) / n)

        if size is not None:
            c = export_mod.resize_grid(c, size, progress=part())
        if mesh is not None:
            export_mod.export_mesh(c, mesh, progress=part())
            written.append(mesh)
        for t in textures:
            written += export_mod.export_texture(c, t, progress=part())
    done(f"wrote {', '.join(map(str, written))} ({' x '.join(map(str, c.shape))} voxels)")
