"""``partscale export``: a CSDF as a coloured mesh and/or 3D textures."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..errors import InputError
from ..progress import ProgressCallback, scaled
from ._common import CsdfIn, check_output, done, progress_bar

#: the default budget: decimate while the surface stays within a tenth of a voxel
DEFAULT_ERROR = 0.1


def export(
    path: CsdfIn,
    mesh: Annotated[
        Path | None,
        typer.Option(
            "--mesh",
            metavar="FILE",
            help="Coloured mesh to write: OUT.glb, OUT.ply or OUT.obj; OUT.usd, OUT.usda, "
            "OUT.usdc or OUT.usdz (AR Quick Look; with --atlas for a baked texture) with the "
            "optional partscale\\[usd].",
        ),
    ] = None,
    texture: Annotated[
        list[Path] | None,
        typer.Option(
            "--texture",
            metavar="FILE",
            help="3D texture to write (repeatable): OUT.raw (half float + JSON sidecar), "
            "OUT.png (Unity flipbook + JSON sidecar) or OUT.nrrd (SDF for ParaView/Slicer).",
        ),
    ] = None,
    faces: Annotated[
        int | None,
        typer.Option(
            "--faces",
            metavar="N",
            help="Triangle budget: decimate the mesh to at most N triangles (meshoptimizer); "
            "instead of --error.",
        ),
    ] = None,
    error: Annotated[
        float | None,
        typer.Option(
            "--error",
            metavar="VOXELS",
            help="Decimate the mesh as far as its surface stays within this distance of the "
            "full one; 0 keeps full resolution.",
            show_default=f"{DEFAULT_ERROR}",
        ),
    ] = None,
    atlas: Annotated[
        int | None,
        typer.Option(
            "--atlas",
            metavar="TEXELS",
            help="Unwrap (xatlas) and bake the colour into a square base-colour texture this "
            "many texels wide: 256, 512, 1024, 2048 or 4096 (GLB embeds it; OBJ writes NAME.mtl "
            "+ NAME.png).",
        ),
    ] = None,
    grid: Annotated[
        int | None,
        typer.Option(
            "--grid",
            metavar="N",
            help="Resample the grid first to N voxels along its longest side: 32, 64, 128 or 256.",
        ),
    ] = None,
) -> None:
    """Export a CSDF as a mesh (marching cubes, vertex colours) and/or RGBA 3D textures."""
    # heavy modules (numba, trimesh, scikit-image) load only when this command runs
    from ..csdf import load

    textures = list(texture or [])
    outputs = _check_outputs(mesh, textures, grid)
    error = _budget(mesh, faces, error, atlas)
    c = load(path)
    c, written = _write(c, outputs, mesh, textures, grid, faces, error, atlas)
    if mesh is not None:
        written += _beside(mesh, atlas)
        done(_mesh_summary(mesh, faces, error))
        if mesh.suffix.lower() == ".usdz" and atlas is None:
            typer.echo(
                "note: vertex colours written as displayColor; AR Quick Look shows textures "
                "only: add --atlas 1024 to bake them into one",
                err=True,
            )
    sizes = ", ".join(f"{p} ({_kb(p)})" for p in written)
    done(f"wrote {sizes} ({' x '.join(map(str, c.shape))} voxels)")


def _check_outputs(mesh: Path | None, textures: list[Path], grid: int | None) -> list[Path]:
    """The output files (the mesh first), checked: at least one, known suffixes, distinct, in
    existing folders; and ``--grid``."""
    from .. import export as export_mod

    if mesh is None and not textures:
        raise InputError("export: expected at least one output (--mesh or --texture), got none")
    if mesh is not None:
        check_output(mesh, suffixes=export_mod.MESH_SUFFIXES, what="a mesh file")
        export_mod.require_usd(mesh)
    for t in textures:
        check_output(t, suffixes=export_mod.TEXTURE_SUFFIXES, what="a 3D texture file")
    outputs = [mesh, *textures] if mesh is not None else textures
    if len({p.resolve() for p in outputs}) != len(outputs):
        raise InputError("export: expected distinct output files, got the same one twice")
    for p in outputs:
        if not p.parent.is_dir():
            raise InputError(f"{p}: expected an existing output folder, got none at {p.parent}")
    export_mod.check_size(grid, what="--grid")
    return outputs


def _budget(
    mesh: Path | None, faces: int | None, error: float | None, atlas: int | None
) -> float | None:
    """The mesh's decimation error (None: full resolution, or a --faces budget), the budget
    and the atlas checked against the mesh asked for."""
    from .. import export as export_mod

    if faces is not None and error is not None:
        raise InputError("export: expected --faces or --error, got both")
    if faces is None and error is None:
        error = DEFAULT_ERROR
    if error == 0:
        error = None  # full resolution
    if mesh is not None:
        export_mod.check_budget(faces, error)
        export_mod.check_atlas(atlas)
        if atlas is not None and mesh.suffix.lower() == ".ply":
            raise InputError(
                f"{mesh}: expected .glb, .obj or USD with --atlas (PLY has no textures)"
            )
    elif faces is not None or atlas is not None:
        raise InputError("export: expected --mesh with --faces, --error or --atlas, got no --mesh")
    return error


def _write(c, outputs, mesh, textures, grid, faces, error, atlas):
    """Every output written (renamed into place only once all are: all of them, or none), with
    one progress bar; returns the CSDF written from (resized with ``grid``) and the files."""
    from .. import export as export_mod
    from .._files import staged_writes

    written: list[Path] = []
    with progress_bar("export") as bar, staged_writes():
        n = len(outputs) + (grid is not None)
        steps = iter(range(n))

        def part() -> ProgressCallback:
            i = next(steps)
            return scaled(bar, i / n, (i + 1) / n)

        if grid is not None:
            c = export_mod.resize_grid(c, grid, progress=part())
        if mesh is not None:
            export_mod.export_mesh(c, mesh, faces=faces, error=error, atlas=atlas, progress=part())
            written.append(mesh)
        for t in textures:
            written += export_mod.export_texture(c, t, progress=part())
    return c, written


def _kb(p: Path) -> str:
    return f"{p.stat().st_size / 1024:,.0f} KB"


def _beside(mesh: Path, atlas: int | None) -> list[Path]:
    """The MTL and PNG an atlased OBJ writes beside itself; the PNG beside a USD layer."""
    suffix = mesh.suffix.lower()
    if atlas is None or suffix not in (".obj", ".usd", ".usda", ".usdc"):
        return []
    if suffix != ".obj":
        return [mesh.with_suffix(".png")]
    return [mesh.with_suffix(".mtl"), mesh.with_suffix(".png")]


def _mesh_summary(mesh: Path, faces: int | None, error: float | None) -> str:
    import trimesh

    from ..export import USD_SUFFIXES, usd_faces

    if mesh.suffix.lower() in USD_SUFFIXES:
        n = usd_faces(mesh)
    else:
        loaded = trimesh.load(mesh, force="mesh", process=False)
        assert isinstance(loaded, trimesh.Trimesh)  # force="mesh"
        n = len(loaded.faces)
    if faces is not None:
        budget = f"budget --faces {faces}"
    elif error is not None:
        budget = f"budget --error {error:g} voxel" + (
            " (default)" if error == DEFAULT_ERROR else ""
        )
    else:
        budget = "full resolution (--error 0)"
    return f"mesh: {n:,} triangles, {budget}"
