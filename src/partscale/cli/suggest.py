"""``partscale suggest``: zones found in the object itself (repeats to tile, slabs to stretch)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from ..errors import InputError
from . import _common


def suggest(
    src: Annotated[Path, typer.Argument(metavar="IN", help="A .csdf.npz file.")],
    axis: Annotated[
        str | None,
        typer.Option("--axis", metavar="AXIS", help="The axis: x, y or z.", show_default="all"),
    ] = None,
    as_json: Annotated[
        bool,
        typer.Option(
            "--json", help="Print JSON instead of text (for scripts): a list, best first."
        ),
    ] = False,
    png: Annotated[
        Path | None,
        typer.Option(
            "--png", metavar="FILE", help="Also draw the object with the candidate bands (.png)."
        ),
    ] = None,
) -> None:
    """Suggest zones: one period of a repeated element (tile) and slabs of constant cross-section
    (stretch), ranked best first, with zone planes in object units."""
    from ..csdf import load
    from ..orient import WALL_AXES, csdf_turn, off_square_message
    from ..zones import AXES
    from ..zones import suggest as suggest_zones

    if axis is not None and axis.lower() not in ("x", "y", "z"):
        raise InputError(f"--axis: expected one of x, y, z, got {axis!r}")
    if png is not None:
        _common.check_output(png, suffixes=(".png",), what="an image file")
    c = load(src)
    ax = axis.lower() if axis is not None else None
    cands = suggest_zones(c, ax)
    # an object turned about up has no constant slab along x or z: say so, with the cure
    turn = csdf_turn(c) if ax is None or ax in WALL_AXES else None
    if ax is not None and not cands:
        raise InputError(
            f"--axis {ax}: expected a zone candidate, got none (no repeated element and no slab "
            "of constant cross-section along it"
            + (f"; {off_square_message(turn, c)})" if turn is not None else ")")
        )
    if turn is not None:
        typer.echo(f"warning: {off_square_message(turn, c)}", err=True)
    units = c.meta.get("units") or ""
    if as_json:
        typer.echo(json.dumps([x.to_json() for x in cands], indent=2))
    else:
        for a in [ax] if ax else list(AXES):
            mine = [x for x in cands if x.axis == a]
            if not mine:
                typer.echo(f"{a}: no candidate (no repeated element, no constant slab)")
            elif not any(x.kind == "tile" for x in mine):
                typer.echo(f"{a}: no repeated element (no tile candidate)")
        for i, x in enumerate(cands, start=1):
            extra = f" period {x.period:.4g} x {x.count}" if x.kind == "tile" else ""
            typer.echo(
                f"{i:2d}. {x.axis} {x.kind:7s} zone {x.zone[0]:.4g} {x.zone[1]:.4g} {units}"
                f"{extra}  score {x.score:.2f}  {x.reason}"
            )
    if png is not None:
        from ..render import save_png

        save_png(_figure(c, cands, ax), png)
        _common.done(f"wrote {png}")


#: Band colours (sRGB) per kind, and the most bands drawn (the best, numbered by rank).
COLOURS = {"tile": (0, 114, 178), "stretch": (0, 158, 115)}
MAX_BANDS = 6


def _figure(c, cands, axis):
    """The ``--png`` picture: the best candidates as bands on the view showing ``axis`` (side for
    z, else front)."""
    from ..render import render_bands
    from ..zones import AXES

    bands = [
        (AXES.index(x.axis), x.zone[0], x.zone[1], f"{rank} {x.kind}", COLOURS[x.kind])
        for rank, x in enumerate(cands[:MAX_BANDS], start=1)
    ]
    try:
        return render_bands(c, bands, view="side" if axis == "z" else "front")
    except InputError as e:
        raise InputError(f"--png: {e}") from None
