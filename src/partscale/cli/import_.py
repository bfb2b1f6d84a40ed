"""``partscale import``: a coloured mesh or an SDF grid -> ``.csdf.npz``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ..csdf import SUFFIX, save
from ..orient import off_square_message, square_note
from . import _common

if TYPE_CHECKING:
    from ..csdf import CSDF
    from ..thickness import ThinFeatures


def import_(
    input: Annotated[
        Path,
        typer.Argument(
            metavar="IN",
            help="Mesh (.glb, .gltf, .obj+.mtl, .ply) or SDF grid (.npy, .npz, AutoSDF .h5).",
        ),
    ],
    output: _common.CsdfOut,
    res: _common.Res = 128,
    pad: Annotated[
        int | None,
        typer.Option(
            "--pad",
            metavar="N",
            help="Empty voxels around the object, >= 3 (the band of exact distances).",
            show_default="5",
        ),
    ] = None,
    iso: Annotated[
        float | None,
        typer.Option(
            "--iso",
            metavar="LEVEL",
            help="Surface level of an SDF grid.",
            show_default="0; AutoSDF .h5: 0.02",
        ),
    ] = None,
    color: Annotated[
        Path | None,
        typer.Option(
            "--color",
            metavar="FILE",
            help="Colour: for an SDF grid, an (X, Y, Z, 3) .npy volume, sRGB: integers 0..255, "
            "or floats in [0, 1] (max <= 1.001) or 0..255 (max > 2); other ranges are refused.",
        ),
    ] = None,
    up: Annotated[
        str,
        typer.Option(
            "--up",
            metavar="AXIS",
            help="The mesh's up axis: y (glTF), z (CAD, Blender), -y, -z, x, -x.",
        ),
    ] = "y",
    scale: Annotated[
        float | None,
        typer.Option("--scale", metavar="FACTOR", help="Multiply the mesh's coordinates by this."),
    ] = None,
    units: Annotated[
        str | None,
        typer.Option(
            "--units",
            metavar="UNIT",
            help="The mesh's length unit, converted to metres: mm, cm, m or in.",
            show_default="the file's own (glTF: m)",
        ),
    ] = None,
    square: Annotated[
        bool,
        typer.Option(
            "--square",
            help=_common.SQUARE_HELP + ": zones are planes square to the axes.",
        ),
    ] = False,
) -> None:
    """Import a coloured mesh or an SDF grid as a coloured SDF (.csdf.npz).

    Meshes may be open assemblies: sign comes from the generalized winding number, open sheets
    are thickened, distances are exact near the surface and colours come from the textures.
    """
    _common.check_output(output, suffixes=(SUFFIX,), what="a CSDF file")
    from .. import ingest  # numba, scipy, trimesh: only when importing, not for every command

    with _common.progress_bar(f"import {input.name}") as progress:
        c = ingest.load(
            input,
            res=res,
            pad=pad,
            iso=iso,
            colors=color,
            up=up,
            scale=scale,
            units=units,
            square=square,
            progress=progress,
        )
    thin = _write_and_check(c, output)
    _common.done(f"wrote {output}: {' x '.join(map(str, c.shape))} voxels of {c.voxel_size:.4g} m")
    placed = c.meta["history"][0]
    if "turned_deg" in placed:
        _common.stderr.print(square_note(placed["turned_deg"]), highlight=False, soft_wrap=True)
    elif "off_square_deg" in placed:
        typer.echo(f"warning: {off_square_message(placed['off_square_deg'])}", err=True)
    below = thin.imported.get("below_one_voxel_triangles", 0)
    if thin.below_one_solid or thin.below_one_gap or below:
        typer.echo(
            f"below one voxel: {below} triangles of closed pieces (thickened), "
            f"{thin.below_one_solid} voxels of solid and {thin.below_one_gap} of gap"
        )
    msg = thin.message(c.voxel_size, c.meta.get("units", "m"))
    if msg:
        typer.echo(f"warning: thin features: {msg}")


def _write_and_check(c: CSDF, output: Path) -> ThinFeatures:
    """Write ``c`` (in this thread: an interrupt stops it) and find its thin features on a
    thread beside it: the write's deflate runs on a pool and releases the GIL, the thin-feature
    sweep is a parallel kernel that releases it too, so the two share the cores instead of
    waiting on each other.
    """
    from concurrent.futures import ThreadPoolExecutor

    from .._workers import launch_numba_threads
    from ..thickness import thin_features  # numba: only when importing, not for every command

    launch_numba_threads()  # from this (the main) thread, not the pool's
    with ThreadPoolExecutor(1) as pool:
        thin = pool.submit(thin_features, c)
        save(c, output)
        return thin.result()
