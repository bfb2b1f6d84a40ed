"""``partscale suggest``: zones found in the object itself (repeats to tile, slabs to stretch)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ..errors import InputError
from . import _common

if TYPE_CHECKING:
    from ..zones import AxisElements, Helix, RadialFrame, Rotation, Screw


def suggest(
    src: Annotated[
        Path,
        typer.Argument(
            metavar="IN",
            help="A .csdf.npz file, or a mesh (.glb, .gltf, .obj, .ply) imported at 128 first, "
            "as fit finds a mesh's zones.",
        ),
    ],
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
    from ..zones import suggest as suggest_zones

    if axis is not None and axis.lower() not in ("x", "y", "z"):
        raise InputError(f"--axis: expected one of x, y, z, got {axis!r}")
    if png is not None:
        _common.check_output(png, suffixes=(".png",), what="an image file")
    c = _common.csdf_or_mesh(src)  # a mesh as fit reads it: its CSDF at the import's default
    ax = axis.lower() if axis is not None else None
    cands = suggest_zones(c, ax)
    _warn_off_square(c, ax)
    found = _findings(c, ax)
    if as_json:
        typer.echo(json.dumps(_json_doc(cands, found), indent=2))
    else:
        for line in _text_lines(cands, found, ax, c.meta.get("units") or ""):
            typer.echo(line)
    if png is not None:
        from ..render import save_png

        save_png(_figure(c, cands, ax), png)
        _common.done(f"wrote {png}")


def _warn_off_square(c, ax: str | None) -> None:
    """An object turned about up has no constant slab along x or z: say so, with the cure."""
    from ..orient import WALL_AXES, csdf_turn, off_square_message

    turn = csdf_turn(c) if ax is None or ax in WALL_AXES else None
    if turn is not None:
        typer.echo(f"warning: {off_square_message(turn, c)}", err=True)


@dataclass(frozen=True)
class Findings:
    """What ``suggest`` finds besides the candidates, on ``ax`` (None: every axis).

    Attributes
    ----------
    elements : dict of str to AxisElements
        Per axis: its elements (:func:`partscale.zones.find_elements`).
    steps, helices, turns : list
        Flights of steps (:func:`~partscale.zones.find_screws`, those along ``ax``), spiral
        stairs where no flight is found, elements turned about the vertical where neither is.
    frame : RadialFrame or None
        A round or polygonal plan (every axis only).
    """

    elements: dict[str, AxisElements]
    steps: list[Screw]
    helices: list[Helix]
    turns: list[Rotation]
    frame: RadialFrame | None


def _findings(c, ax: str | None) -> Findings:
    """The elements, steps, helices, rotations and plan of ``c`` along ``ax``."""
    from ..zones import AXES, find_elements, find_helices, find_radial, find_rotations, find_screws

    found = {a: find_elements(c, a) for a in ([ax] if ax else list(AXES))}
    steps = find_screws(c) if ax is None or ax in ("x", "y", "z") else []
    steps = [sc for sc in steps if ax is None or abs(sc.step[AXES.index(ax)]) > 0]
    # a spiral stair: where no flight is found, up
    helices = find_helices(c) if not steps and ax in (None, "y") else []
    # elements about the vertical (a star base's arms): where no stair is found
    turns = find_rotations(c) if not steps and not helices and ax in (None, "y") else []
    frame = find_radial(c, "y") if ax is None else None
    return Findings(found, steps, helices, turns, frame)


def _json_doc(cands, found: Findings) -> dict:
    """``--json``: the candidates best first, the elements per axis, steps, helices, rotations
    and the round plan."""
    doc = {
        "candidates": [x.to_json() for x in cands],
        "elements": {a: f.to_json() for a, f in found.elements.items()},
        "steps": [sc.to_json() for sc in found.steps],
        "helix": [hx.to_json() for hx in found.helices],
        "rotation": [rt.to_json() for rt in found.turns],
    }
    frame = found.frame
    if frame is not None:
        doc["radial"] = {
            "center": list(frame.center),
            "sides": frame.sides,
            "phase": frame.phase,
            "radius": frame.radius,
        }
    return doc


def _text_lines(cands, found: Findings, ax: str | None, units: str) -> list[str]:
    """The text report: elements, steps, helices, rotations, the plan, the axes without a
    candidate, then the candidates ranked."""
    return [
        *_element_lines(found, units),
        *_repeat_lines(found, units),
        *_missing_lines(cands, ax),
        *_candidate_lines(cands, units),
    ]


def _element_lines(found: Findings, units: str) -> list[str]:
    """A line per axis's elements, but an axis a flight, helix or rotation steps along that
    has no element group."""
    from ..zones import AXES

    stepped = {AXES[k] for sc in found.steps for k in range(3) if abs(sc.step[k]) > 0}
    stepped |= {"y"} if found.helices or found.turns else set()
    return [
        _elements_line(f, units)
        for f in found.elements.values()
        if f.best is not None or f.axis not in stepped
    ]


def _repeat_lines(found: Findings, units: str) -> list[str]:
    """A line per flight of steps, spiral stair and ring of turned elements, and the plan."""
    lines = [
        f"steps: a flight along {sc.axis}, {sc.count} steps of {sc.going:.4g} going and "
        f"{sc.rise:.4g} rise {units} ({100 * sc.support:.0f}% of the surface repeats; "
        "fit --add y 1 adds one)"
        for sc in found.steps
    ]
    lines += [
        f"helix: a spiral stair, {hx.count} steps each turning {hx.angle:.1f} degrees "
        f"about the vertical through {hx.center[0]:.3f}, {hx.center[1]:.3f} and rising "
        f"{hx.rise:.4g} {units} ({100 * hx.support:.0f}% of the surface repeats; "
        "fit --add y 1 adds one)"
        for hx in found.helices
    ]
    lines += [
        f"rotation: {rt.count} elements, {'a closed ring' if rt.closed else 'an open arc'}, "
        f"each turned {rt.angle:.1f} degrees "
        f"about the vertical through {rt.center[0]:.3f}, {rt.center[1]:.3f} {units} "
        f"({100 * rt.support:.0f}% of the surface repeats; fit --add y 1 adds one)"
        for rt in found.turns
    ]
    frame = found.frame
    if frame is not None:
        shape = "round" if frame.sides == 0 else f"a regular {frame.sides}-sided polygon"
        lines.append(
            f"plan: {shape} about the vertical through {frame.center[0]:.4g}, "
            f"{frame.center[1]:.4g} {units} (scale --radial grows it)"
        )
    return lines


def _missing_lines(cands, ax: str | None) -> list[str]:
    """A line per axis with no candidate, or no tile candidate."""
    from ..zones import AXES

    lines = []
    for a in [ax] if ax else list(AXES):
        mine = [x for x in cands if x.axis == a]
        if not mine:
            lines.append(f"{a}: no candidate (no repeated element, no constant slab)")
        elif not any(x.kind == "tile" for x in mine):
            lines.append(f"{a}: no repeated element (no tile candidate)")
    return lines


def _candidate_lines(cands, units: str) -> list[str]:
    """The candidates ranked, one line each."""
    lines = []
    for i, x in enumerate(cands, start=1):
        extra = f" period {x.period:.4g} x {x.count}" if x.kind == "tile" else ""
        lines.append(
            f"{i:2d}. {x.axis} {x.kind:7s} zone {x.zone[0]:.4g} {x.zone[1]:.4g} {units}"
            f"{extra}  score {x.score:.2f}  {x.reason}"
        )
    return lines


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
