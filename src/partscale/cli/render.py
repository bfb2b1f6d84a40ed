"""``partscale render``: a picture of a CSDF, sphere-traced from the SDF on the CPU."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..errors import InputError
from ._common import CsdfIn, check_output, done, progress_bar


def render(
    path: CsdfIn,
    output: Annotated[Path, typer.Option("-o", "--output", help="Image to write (.png).")],
    view: Annotated[str, typer.Option("--view", help="Camera: front, side, top or iso.")] = "iso",
    size: Annotated[int, typer.Option("--size", help="Image width and height in pixels.")] = 512,
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
) -> None:
    """Render a CSDF to a PNG (sphere tracing of the SDF, its colours, simple shading)."""
    # heavy modules (numba, trimesh, scikit-image) load only when this command runs
    from .. import render as render_mod
    from ..csdf import load

    check_output(output, suffixes=(".png",), what="an image file")
    if view not in render_mod.VIEWS:
        raise InputError(f"--view: expected one of {', '.join(render_mod.VIEWS)}, got {view!r}")
    if not output.parent.is_dir():
        raise InputError(
            f"{output}: expected an existing output folder, got none at {output.parent}"
        )
    c = load(path)
    if completion:
        from ..complete import completion_colors

        c = c.replace(rgb=completion_colors(c))
    with progress_bar("render") as bar:
        image = render_mod.render(
            c, view=view, size=size, parts=parts, scale_bar=scale_bar, progress=bar
        )
        render_mod.save_png(image, output)
    done(f"wrote {output} ({size} x {size}, {view} view)")
