"""``partscale render``: a picture of a CSDF, sphere-traced from the SDF on the CPU."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .._options import choice, count
from ..errors import InputError
from . import _common
from ._common import check_output, csdf_or_mesh, done, progress_bar

MESH_RES = 256
"""Voxels along a mesh's longest side when it is imported to be drawn: finer than the default
import (128), so thin boards and small details show."""


def render(
    path: Annotated[
        Path,
        typer.Argument(
            metavar="IN",
            help="A .csdf.npz file, or a mesh (.glb, .gltf, .obj, .ply) with its colours or "
            "textures.",
        ),
    ],
    output: Annotated[
        Path,
        typer.Option("-o", "--output", metavar="OUT", help="Where to write: a .png image."),
    ],
    view: Annotated[
        str, typer.Option("--view", metavar="VIEW", help="Camera: front, side, top or iso.")
    ] = "iso",
    pixels: Annotated[
        int, typer.Option("--pixels", metavar="N", help="Image width and height in pixels.")
    ] = 512,
    parts: Annotated[
        bool, typer.Option("--parts", help="Colour by part (needs a segmented CSDF).")
    ] = False,
    completion: Annotated[
        bool,
        typer.Option(
            "--completion",
            help="Colour a completed scan by kind: observed blue, mirrored amber, guessed red.",
        ),
    ] = False,
    scale_bar: Annotated[
        bool, typer.Option("--scale-bar", help="Draw a labelled scale bar.")
    ] = False,
    res: Annotated[
        int,
        typer.Option(
            "--res",
            metavar="N",
            help=_common.RES_HELP + " A mesh IN is imported at this resolution first.",
        ),
    ] = MESH_RES,
) -> None:
    """Render a CSDF or a mesh to a PNG (sphere tracing of the SDF, its colours, simple shading).

    A mesh (what the mesh route writes, or any other) is imported first, as partscale import
    does, so its picture is drawn exactly as a CSDF's.
    """
    # heavy modules (numba, trimesh, scikit-image) load only when this command runs
    from .. import render as render_mod

    check_output(output, suffixes=(".png",), what="an image file")
    view = choice(view, "--view", render_mod.VIEWS)
    pixels = count(pixels, "--pixels", lo=render_mod.MIN_SIZE, hi=render_mod.MAX_SIZE)
    if not output.parent.is_dir():
        raise InputError(
            f"{output}: expected an existing output folder, got none at {output.parent}"
        )
    c = csdf_or_mesh(path, res)
    if parts and c.n_parts == 0:
        raise InputError(
            f"--parts: expected a segmented CSDF (partscale segment), got no parts in {path.name}"
        )
    if completion:
        from ..complete import completion_colors

        c = c.replace(rgb=completion_colors(c))
    with progress_bar("render") as bar:
        image = render_mod.render(
            c, view=view, size=pixels, parts=parts, scale_bar=scale_bar, progress=bar
        )
        render_mod.save_png(image, output)
    done(f"wrote {output} ({pixels} x {pixels}, {view} view)")
