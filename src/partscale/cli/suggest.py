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
            "--json",
            help="Print JSON instead of text (for scripts): the candidates best first, and per "
            "axis the elements, separators and repeat groups; steps (straight or a helix), "
            "elements turned about the vertical and a round plan.",
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
    (stretch), ranked best first, with zone planes in object units; and the elements along each
    axis (seats, doors, shelf rows) that fit --add counts.

    Example: partscale suggest sofa.csdf.npz --axis x
    """
    from ..csdf import load
    from ..orient import WALL_AXES, csdf_turn, off_square_message
    from ..zones import (
        AXES,
        find_elements,
        find_helices,
        find_radial,
        find_rotations,
        find_screws,
    )
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
    if turn is not None:
        typer.echo(f"warning: {off_square_message(turn, c)}", err=True)
    units = c.meta.get("units") or ""
    found = {a: find_elements(c, a) for a in ([ax] if ax else list(AXES))}
    steps = find_screws(c) if ax is None or ax in ("x", "y", "z") else []
    steps = [sc for sc in steps if ax is None or abs(sc.step[AXES.index(ax)]) > 0]
    # a spiral stair: where no flight is found, up
    helices = find_helices(c) if not steps and ax in (None, "y") else []
    # elements about the vertical (a star base's arms): where no stair is found
    turns = find_rotations(c) if not steps and not helices and ax in (None, "y") else []
    frame = find_radial(c, "y") if ax is None else None
    if as_json:
        doc = {
            "candidates": [x.to_json() for x in cands],
            "elements": {a: f.to_json() for a, f in found.items()},
            "steps": [sc.to_json() for sc in steps],
            "helix": [hx.to_json() for hx in helices],
            "rotation": [rt.to_json() for rt in turns],
        }
        if frame is not None:
            doc["radial"] = {
                "center": list(frame.center),
                "sides": frame.sides,
                "phase": frame.phase,
                "radius": frame.radius,
            }
        typer.echo(json.dumps(doc, indent=2))
    else:
        stepped = {AXES[k] for sc in steps for k in range(3) if abs(sc.step[k]) > 0}
        stepped |= {"y"} if helices or turns else set()
        for f in found.values():
            if f.best is not None or f.axis not in stepped:
                typer.echo(_elements_line(f, units))
        for sc in steps:
            typer.echo(
                f"steps: a flight along {sc.axis}, {sc.count} steps of {sc.going:.4g} going and "
                f"{sc.rise:.4g} rise {units} ({100 * sc.support:.0f}% of the surface repeats; "
                "fit --add y 1 adds one)"
            )
        for hx in helices:
            typer.echo(
                f"helix: a spiral stair, {hx.count} steps each turning {hx.angle:.1f} degrees "
                f"about the vertical through {hx.center[0]:.3f}, {hx.center[1]:.3f} and rising "
                f"{hx.rise:.4g} {units} ({100 * hx.support:.0f}% of the surface repeats; "
                "fit --add y 1 adds one)"
            )
        for rt in turns:
            ring = "a closed ring" if rt.closed else "an open arc"
            typer.echo(
                f"rotation: {rt.count} elements, {ring}, each turned {rt.angle:.1f} degrees "
                f"about the vertical through {rt.center[0]:.3f}, {rt.center[1]:.3f} {units} "
                f"({100 * rt.support:.0f}% of the surface repeats; fit --add y 1 adds one)"
            )
        if frame is not None:
            shape = "round" if frame.sides == 0 else f"a regular {frame.sides}-sided polygon"
            typer.echo(
                f"plan: {shape} about the vertical through {frame.center[0]:.4g}, "
                f"{frame.center[1]:.4g} {units} (scale --radial grows it)"
            )
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


def _elements_line(found, units: str) -> str:
    """One line on the elements along an axis: the best group's, positions from the axis min."""
    from ..zones import element_phrase

    g = found.best
    if g is None:
        return f"{found.axis}: no repeated element (fit --add {found.axis} N has nothing to count)"
    spans = ", ".join(
        f"{found.elements[i].start - found.lo:.3g}..{found.elements[i].end - found.lo:.3g}"
        for i in g.members
    )
    return (
        f"{found.axis}: {element_phrase(found)} at {spans} {units} from the {found.axis} min "
        f"(fit --add {found.axis} 1 adds one)"
    )


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
