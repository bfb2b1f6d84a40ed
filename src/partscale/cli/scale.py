"""``partscale scale``: stretch, tile or globally scale a zone of a CSDF (or apply a recipe)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .. import csdf as csdf_mod
from ..errors import InputError
from . import _common

# mesh in and mesh out: the mesh route (partscale.meshedit), edits applied to the source mesh
_MESH_IN = (".glb", ".gltf", ".obj", ".ply")
_MESH_OUT = (".glb", ".obj", ".ply")


def scale(
    src: Annotated[
        Path,
        typer.Argument(
            metavar="IN",
            help="Input .csdf.npz file, or a mesh (.glb, .gltf, .obj, .ply) for the mesh route.",
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "-o",
            "--output",
            help="Output .csdf.npz file, or a mesh (.glb, .obj, .ply) when IN is one: the edit is applied to the source mesh itself.",
        ),
    ],
    axis: Annotated[str | None, typer.Option("--axis", help="x, y or z.")] = None,
    zone: Annotated[
        tuple[str, str] | None,
        typer.Option(
            "--zone", help="START END of the zone, in object units or with % of the extent."
        ),
    ] = None,
    to: Annotated[str | None, typer.Option("--to", help="DEST: where END goes.")] = None,
    mode: Annotated[
        str | None, typer.Option("--mode", help="stretch, tile or global (default stretch).")
    ] = None,
    recipe: Annotated[
        Path | None,
        typer.Option("--recipe", help="A recipe JSON file (instead of --axis/--zone/--to)."),
    ] = None,
) -> None:
    """Resize a zone between two planes: stretch it, tile it, or scale the whole object."""
    # The edit stage pulls in numba, scipy and scikit-image: load it only when a command runs.
    from ..edit import AXES, MODES, Edit, Recipe, apply_recipe
    from ..edit.recipe import parse_position

    mesh_route = src.suffix.lower() in _MESH_IN and output.suffix.lower() in _MESH_OUT
    if not mesh_route:
        _common.check_output(output, suffixes=(csdf_mod.SUFFIX,), what="a CSDF file")
    if recipe is not None:
        given = [
            n
            for n, v in (("--axis", axis), ("--zone", zone), ("--to", to), ("--mode", mode))
            if v is not None
        ]
        if given:
            raise InputError(
                f"--recipe: expected alone (modes are in the recipe), got it with {', '.join(given)}"
            )
        rec = Recipe.load(recipe)
    else:
        missing = [n for n, v in (("--axis", axis), ("--zone", zone), ("--to", to)) if v is None]
        if missing:
            raise InputError(
                f"scale: expected --axis, --zone and --to (or --recipe), missing {', '.join(missing)}"
            )
        if axis.lower() not in AXES:
            raise InputError(f"--axis: expected one of x, y, z, got {axis!r}")
        mode = "stretch" if mode is None else mode
        if mode.lower() not in MODES:
            raise InputError(f"--mode: expected one of {', '.join(MODES)}, got {mode!r}")
        rec = Recipe(
            (
                Edit(
                    axis=axis.lower(),
                    start=parse_position(zone[0], "--zone START"),
                    end=parse_position(zone[1], "--zone END"),
                    dest=parse_position(to, "--to"),
                    mode=mode.lower(),
                ),
            )
        )
    if mesh_route:
        return _scale_mesh(src, output, rec)
    c = csdf_mod.load(src)
    with _common.progress_bar("scale") as bar:
        out = apply_recipe(c, rec, progress=bar)
    csdf_mod.save(out, output)
    _common.done(f"wrote {output} ({' x '.join(map(str, out.shape))} voxels)")


def _scale_mesh(src: Path, output: Path, rec) -> None:
    from ..meshedit import edit_mesh_file

    result = edit_mesh_file(src, output, rec)
    for seam in result.seams:
        if not seam.ok:
            typer.echo(f"warning: {seam.message()}", err=True)
    _common.done(
        f"wrote {', '.join(map(str, result.written))} (mesh route: {result.faces_in} -> "
        f"{result.faces_out} triangles)"
    )
