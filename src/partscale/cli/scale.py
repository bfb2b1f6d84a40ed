"""``partscale scale``: stretch, tile or globally scale a zone of a CSDF (or apply a recipe)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..csdf import SUFFIX, load, save
from ..errors import InputError
from . import _common

SQUARE_OPTION = typer.Option(
    "--square",
    help=_common.SQUARE_HELP + ": the mesh route edits it turned so (zones are planes square to "
    "the walls; positions refer to the turned mesh), then turns it back.",
)

# the options of ``scale`` (the command's signature names them)
In = Annotated[
    Path,
    typer.Argument(
        metavar="IN",
        help="A .csdf.npz file, or a mesh (.glb, .gltf, .obj, .ply) for the mesh route.",
    ),
]


def output_option(when: str) -> typer.models.OptionInfo:
    """``-o/--output``: a CSDF, or a mesh ``when`` (the end of its help) IN is one."""
    return typer.Option(
        "-o",
        "--output",
        metavar="OUT",
        help="Where to write: a .csdf.npz file, or a mesh (.glb, .obj, .ply; .usd, .usda, .usdc, "
        ".usdz with partscale\\[usd]) " + when,
    )


Out = Annotated[
    Path, output_option("when IN is one (the edit is applied to the source mesh itself).")
]
Axis = Annotated[str | None, typer.Option("--axis", metavar="AXIS", help="The axis: x, y or z.")]
Zone = Annotated[
    tuple[str, str] | None,
    typer.Option(
        "--zone",
        metavar="START END",
        callback=_common.spaced("--zone", "START END"),
        help="The zone's planes: object units, with a unit (30cm, 300mm, 0.3m, 12in) or % "
        "of the extent (0% at its min). Omitted with --copies: whole elements (seats, "
        "doors, shelf rows, steps) of the repeat found along --axis (y: also the arms of a "
        "ring about the vertical).",
    ),
]
To = Annotated[
    str | None,
    typer.Option("--to", metavar="DEST", help="Where END goes: a position, as START and END are."),
]
By = Annotated[
    str | None,
    typer.Option(
        "--by",
        metavar="LENGTH",
        help="Instead of --to: the change in length, e.g. +20cm, -5cm or 8in (no %).",
    ),
]
Copies = Annotated[
    str | None,
    typer.Option(
        "--copies",
        metavar="N",
        help="Instead of --to (tile): +N more copies, or N in all; with no --zone, +N / -N "
        "elements (or N in all) of the repeat found along --axis.",
    ),
]
Snap = Annotated[
    bool,
    typer.Option(
        "--snap", help="Move the planes to the nearest good position for the mode (says so)."
    ),
]
Mode = Annotated[
    str | None,
    typer.Option(
        "--mode",
        metavar="MODE",
        help="stretch, tile or global.",
        show_default="stretch; tile with --copies",
    ),
]
RecipeIn = Annotated[
    Path | None,
    typer.Option(
        "--recipe",
        metavar="FILE",
        help="A recipe JSON to apply: instead of --axis, --zone and --to.",
    ),
]
Radial = Annotated[
    bool,
    typer.Option(
        "--radial",
        help="A radial zone about the vertical (y) axis: --zone R0 R1 are radii (% of the "
        "outline's radius, or lengths), --to / --by the new outer radius.",
    ),
]
Center = Annotated[
    tuple[str, str] | None,
    typer.Option(
        "--center",
        metavar="X Z",
        help="With --radial: the axis' position.",
        show_default="found",
        callback=_common.spaced("--center", "X Z"),
    ),
]
Sides = Annotated[
    int | None,
    typer.Option(
        "--sides",
        metavar="N",
        help="With --radial: 0 for a round outline, N for a regular N-gon.",
        show_default="found",
    ),
]
Span = Annotated[
    tuple[str, str] | None,
    typer.Option(
        "--span",
        metavar="LO HI",
        callback=_common.spaced("--span", "LO HI"),
        help="With --radial: only the levels between LO and HI along y (a lamp's base).",
    ),
]
Normal = Annotated[
    tuple[float, float, float] | None,
    typer.Option(
        "--normal",
        metavar="NX NY NZ",
        help="An oblique zone square to this direction: --zone S0 S1 and --to along it "
        "(lengths from the origin, or % of the extent along it).",
    ),
]


def scale(
    src: In,
    output: Out,
    axis: Axis = None,
    zone: Zone = None,
    to: To = None,
    by: By = None,
    copies: Copies = None,
    snap: Snap = False,
    mode: Mode = None,
    recipe: RecipeIn = None,
    square: Annotated[bool, SQUARE_OPTION] = False,
    radial: Radial = False,
    center: Center = None,
    sides: Sides = None,
    span: Span = None,
    normal: Normal = None,
) -> None:
    """Resize a zone between two planes: stretch it, tile it, or scale the whole object; or a
    radial zone (an annulus about the vertical) or an oblique one (planes square to any
    direction).
    """
    from ..meshedit import check_route, check_square, is_mesh_route

    mesh_route = is_mesh_route(src, output)
    if not mesh_route:
        _common.check_output(output, suffixes=(SUFFIX,), what="a CSDF file")
    check_square(square, mesh_route, src, output)  # its own line for a mesh -> CSDF --square
    check_route(src, output)
    check_usd(output)
    dest_given = _given(("--to", to), ("--by", by), ("--copies", copies))
    if radial or normal is not None:
        _check_warp_route(radial, mesh_route)
        rec, c = _warp_recipe(
            src, radial, normal, axis, zone, to, by, copies, mode, snap, recipe, center, sides, span
        )
        return _apply_and_save(c, rec, output)
    warp_opts = _given(("--center", center), ("--sides", sides), ("--span", span), truthy=False)
    if warp_opts:
        raise InputError(
            f"{', '.join(n for n, _ in warp_opts)}: expected with --radial, got it without"
        )
    moves = None
    if recipe is not None:
        _check_recipe_alone(axis, zone, mode, dest_given, snap)
        c, rec = _recipe_file(src, recipe, mesh_route, square)
    elif zone is None and copies is not None and axis is not None:
        c, rec = _element_recipe(src, mesh_route, axis, copies, mode, snap, square, dest_given)
        if mesh_route:
            if remesh_note(c, rec) is None:
                fallback = csdf_fallback(c, rec, what=f"scale --copies {copies}")
                if scale_mesh(src, output, rec, square=square, csdf=fallback) or fallback is None:
                    return
            # steps, a ring, or seams that cannot be welded: through the mesh's CSDF
            return _apply_and_save(c, rec, output, remesh=True)
    else:
        c, rec, moves = _zone_recipe(
            src,
            mesh_route,
            square,
            axis,
            zone,
            mode,
            dest_given,
            to=to,
            by=by,
            copies=copies,
            snap=snap,
        )
    if mesh_route:
        scale_mesh(src, output, rec, square=square)
        return
    assert c is not None  # loaded unless mesh_route
    _apply_and_save(c, rec, output, moves)


def _given(*pairs: tuple[str, object], truthy: bool = True) -> list[tuple[str, object]]:
    """The ``(name, value)`` pairs given: a value that is truthy (``truthy``) or not None."""
    return [(n, v) for n, v in pairs if (v if truthy else v is not None)]


def _check_warp_route(radial: bool, mesh_route: bool) -> None:
    """``--radial`` and ``--normal`` edit a CSDF: the mesh route cuts across x, y or z only."""
    if mesh_route:
        raise InputError(
            f"{'--radial' if radial else '--normal'}: expected a CSDF (the mesh route cuts at "
            "planes across x, y or z only; import the mesh first), got a mesh"
        )


def _check_recipe_alone(axis, zone, mode, dest_given, snap: bool) -> None:
    """``--recipe`` comes alone: its edits name their own axes, zones and modes."""
    given = [
        n
        for n, v in (("--axis", axis), ("--zone", zone), ("--mode", mode), *dest_given)
        if v is not None
    ] + (["--snap"] if snap else [])
    if given:
        raise InputError(
            f"--recipe: expected alone (modes are in the recipe), got it with {', '.join(given)}"
        )


def _recipe_file(src: Path, recipe: Path, mesh_route: bool, square: bool):
    """``--recipe``: the CSDF (None on the mesh route) and the recipe read for it, its counts
    resolved."""
    from ..edit import Recipe

    c = None if mesh_route else load(src)
    # positions with a unit ("30cm") in the object's units: a mesh route's are metres
    rec = Recipe.load(recipe, units="m" if c is None else c.meta.get("units"))
    return c, _resolved_counts(src, c, rec, square)


def _check_zone_options(axis, zone, mode, dest_given, copies) -> tuple[str, str]:
    """The plain zone edit's options checked: ``(axis, mode)`` in lower case, the mode
    defaulted (tile with ``--copies``, else stretch)."""
    from ..edit import AXES, MODES

    missing = [n for n, v in (("--axis", axis), ("--zone", zone)) if v is None]
    if not dest_given:
        missing.append("--to (or --by, --copies)")
    if missing:
        raise InputError(
            f"scale: expected --axis, --zone and --to (or --recipe), missing {', '.join(missing)}"
        )
    if len(dest_given) > 1:
        raise InputError(
            "scale: expected one of --to, --by, --copies, got "
            + ", ".join(n for n, _ in dest_given)
        )
    assert axis is not None  # in `missing` otherwise
    if axis.lower() not in AXES:
        raise InputError(f"--axis: expected one of x, y, z, got {axis!r}")
    if mode is None:
        mode = "tile" if copies is not None else "stretch"
    if mode.lower() not in MODES:
        raise InputError(f"--mode: expected one of {', '.join(MODES)}, got {mode!r}")
    if copies is not None and mode.lower() != "tile":
        raise InputError(f"--copies: expected --mode tile, got --mode {mode}")
    return axis.lower(), mode.lower()


def _zone_recipe(src, mesh_route, square, axis, zone, mode, dest_given, *, to, by, copies, snap):
    """The plain zone edit (``--axis --zone --to``/``--by``/``--copies``): what it resolves
    against, its one-edit recipe, and the snap's moves (None without ``--snap``)."""
    from ..edit import Recipe

    axis, mode = _check_zone_options(axis, zone, mode, dest_given, copies)
    c = _object(src, mesh_route, snap, square)
    edit = _edit(c, axis, zone, mode, to=to, by=by, copies=copies)
    moves = None
    if snap:
        from ..zones import describe_moves
        from ..zones import snap as snap_edit

        total = None if copies is None else _copies_total(copies)
        edit, moves = snap_edit(c, edit, copies=total)
        _common.stderr.print(
            describe_moves(moves, c.meta.get("units")), highlight=False, soft_wrap=True
        )
    return c, Recipe((edit,)), moves


def _resolved_counts(src: Path, c, rec, square: bool):
    """``rec`` with its counts (``{"axis": "x", "copies": "+1"}``) made zone edits on the
    object (:func:`partscale.zones.resolve_counts`; for the mesh route on its CSDF), what they
    became printed."""
    from ..edit import CountEdit

    if not any(isinstance(e, CountEdit) for e in rec.edits):
        return rec
    from ..zones import resolve_counts

    obj = c if c is not None else _object(src, True, True, square)
    rec, notes = resolve_counts(obj, rec)
    for line in notes:
        _common.stderr.print(line, highlight=False, soft_wrap=True)
    return rec


def _apply_and_save(c, rec, output: Path, moves=None, *, remesh: bool = False) -> None:
    """Apply ``rec`` to ``c`` with a progress bar, say what changed, write ``output`` (with
    ``remesh``, as a mesh: :func:`write_edited`)."""
    from ..edit import apply_recipe, describe_changes
    from ..zones import feature_notes

    with _common.progress_bar("scale") as bar:
        out = apply_recipe(c, rec, progress=bar)
    if moves is not None:
        from ..zones import record_snap

        out = record_snap(out, moves)
    entries = out.meta.get("history", [])[-len(rec.edits) :]
    for line in describe_changes(entries, out) + feature_notes(c, rec):
        _common.stderr.print(line, highlight=False, soft_wrap=True)
    write_edited(out, output, remesh=remesh)
    grid = f"{' x '.join(map(str, out.shape))} voxels"
    _common.done(f"wrote {output} ({'remeshed from ' * remesh}{grid})")


def _warp_recipe(
    src, radial, normal, axis, zone, to, by, copies, mode, snap, recipe, center, sides, span
):
    """The one-edit recipe of ``--radial`` or ``--normal`` (a :class:`RadialZone` about the
    vertical, or an :class:`ObliqueZone`), and the CSDF it applies to."""
    from ..edit import ObliqueZone, Recipe, parse_length

    name = "--radial" if radial else "--normal"
    clash = [
        n
        for n, v in (
            ("--axis", axis),
            ("--copies", copies),
            ("--recipe", recipe),
            ("--snap", snap or None),
            ("--normal" if radial else "--radial", normal if radial else (radial or None)),
        )
        if v is not None
    ]
    if mode is not None and mode.lower() != "stretch":
        clash.append(f"--mode {mode}")
    if clash:
        raise InputError(
            f"{name}: expected --zone and --to or --by with it, got {', '.join(clash)}"
        )
    if normal is not None and (center is not None or sides is not None or span is not None):
        raise InputError("--normal: expected no --center, --sides or --span (those are --radial's)")
    if zone is None or (to is None) == (by is None):
        raise InputError(f"{name}: expected --zone START END and one of --to or --by")
    c = load(src)
    units = c.meta.get("units")
    if radial:
        return _radial_recipe(c, zone, to, by, center, sides, span), c
    import numpy as np

    n = np.asarray(normal, dtype=np.float64)
    if not np.isfinite(n).all() or np.linalg.norm(n) < 1e-9:
        raise InputError(f"--normal: expected a non-zero direction NX NY NZ, got {list(normal)}")
    n = n / np.linalg.norm(n)
    # the solid's extent along the normal: what % refers to
    inside = np.argwhere(c.sdf < 0)
    proj = (c.origin + inside * c.voxel_size) @ n
    lo, hi = float(proj.min()), float(proj.max())
    s0, s1 = (
        _along(v, lo, hi, units, f"--zone {w}") for v, w in zip(zone, ("START", "END"), strict=True)
    )
    dest = (
        _along(to, lo, hi, units, "--to")
        if to is not None
        else s1 + parse_length(by, units=units, what="--by")
    )
    return Recipe((ObliqueZone((float(n[0]), float(n[1]), float(n[2])), s0, s1, dest),)), c


def _along(value: str, lo: float, hi: float, units, what: str) -> float:
    """A position given as a length (object units, or with a unit) or % of ``lo..hi``."""
    from ..edit import parse_position

    p = parse_position(value, what, units)
    if isinstance(p, str):  # a percentage
        return lo + float(p.rstrip("%")) / 100 * (hi - lo)
    return p


def _radial_recipe(c, zone, to, by, center, sides, span):
    """``--radial``: the zone's frame found (or given), radii as % of its outline or lengths."""
    from ..edit import Recipe, parse_length, radial_extent
    from ..zones import find_radial

    units = c.meta.get("units")
    frame = find_radial(c, "y")
    if frame is None and (center is None or sides is None):
        raise InputError(
            "--radial: expected a round or regular-polygon outline seen from above, found none; "
            "give --center X Z and --sides N (0: round)"
        )
    cx, cz = frame.center if frame is not None else (0.0, 0.0)
    if center is not None:
        cx, cz = (_along(v, 0.0, 0.0, units, "--center") for v in center)
    k = frame.sides if sides is None and frame is not None else int(sides or 0)
    phase = frame.phase if frame is not None and k == frame.sides else 0.0
    from ..edit import RadialZone

    probe = RadialZone("y", (cx, cz), 0.0, 1.0, 2.0, k, phase)
    rmax = radial_extent(c, probe)
    r0, r1 = (
        _along(v, 0.0, rmax, units, f"--zone {w}") for v, w in zip(zone, ("R0", "R1"), strict=True)
    )
    dest = (
        _along(to, 0.0, rmax, units, "--to")
        if to is not None
        else r1 + parse_length(by, units=units, what="--by")
    )
    lim = None
    if span is not None:
        sb = c.surface_bounds()
        y0, y1 = (_along(v, float(sb[0, 1]), float(sb[1, 1]), units, "--span") for v in span)
        lim = (y0, y1)
    return Recipe((RadialZone("y", (cx, cz), r0, r1, dest, k, phase, lim),))


def check_usd(output: Path) -> None:
    """A USD output needs the optional usd-core: one line naming the extra, before any work."""
    from ..export import require_usd

    require_usd(output)


def _object(src: Path, mesh_route: bool, snap: bool, square: bool = False):
    """What the options resolve against: the CSDF, or for the mesh route the mesh's frame (its
    CSDF at the default resolution where --snap needs zones), turned square with ``square``."""
    if not mesh_route:
        return load(src)
    from ..meshedit import edit_target

    return edit_target(src, zones=snap, square=square)


def remesh_note(c, rec) -> str | None:
    """The line saying a mesh's edit goes through its CSDF ``c`` (``rec`` has a zone the mesh
    route cannot cut: steps, a ring), or None where the mesh route applies ``rec``; refused
    where ``c`` was turned square (the remeshed result would stay turned)."""
    from ..meshedit import off_plane_zones

    kinds = off_plane_zones(rec)
    if not kinds:
        return None
    turned = _turned(c)
    if turned:
        raise InputError(
            f"--square: expected a turn of 0 with a {kinds[0]} zone on the mesh route (its CSDF "
            f"is remeshed, and would stay turned), got {turned:g} degrees; import with --square "
            "and edit the CSDF"
        )
    zones = " and ".join(sorted(set(kinds)))
    return _remesh_line(
        c, f"the mesh route cuts only at planes across x, y or z, not a {zones} zone"
    )


def _turned(c) -> float:
    """Degrees ``--square`` turned the mesh's CSDF ``c`` by (0.0: not turned)."""
    return float((c.meta.get("history") or [{}])[0].get("turned_deg") or 0.0)


def _remesh_line(c, why: str) -> str:
    """The note that the edit goes through the mesh's CSDF ``c`` (imported for its zones), and
    ``why``."""
    res = (c.meta.get("history") or [{}])[0].get("res")
    return (
        f"note: {why}: the edit is applied to the mesh's CSDF (imported at --res {res}) and the "
        "result remeshed (vertex colours, not its UVs and materials; for a finer grid: "
        "partscale import --res 256, then edit and export)"
    )


def write_edited(out, output: Path, *, remesh: bool) -> None:
    """``out`` written to ``output``: the CSDF, or with ``remesh`` its surface as a coloured
    mesh (:func:`partscale.export.export_mesh` at export's default budget), with progress."""
    if not remesh:
        save(out, output)
        return
    from ..export import export_mesh
    from .export import DEFAULT_ERROR

    with _common.progress_bar("remesh") as bar:
        export_mesh(out, output, error=DEFAULT_ERROR, progress=bar)


def csdf_fallback(c, rec, *, what: str):
    """``c``, the mesh's CSDF a mesh route edit falls back to where the copies' seams cannot be
    welded, where ``rec`` applied to it fits in memory; else None, the line saying so printed:
    the mesh route then writes its seams as they are (checked before any work, so a plan is
    never followed by a refusal after the mesh was cut)."""
    from ..edit import check_recipe_memory
    from ..errors import MemoryLimitError

    try:
        check_recipe_memory(c, rec, what=what)
    except MemoryLimitError as exc:
        _common.stderr.print(
            f"note: seams that cannot be welded would go through the mesh's CSDF, too large "
            f"here ({exc}): they are written as they are",
            highlight=False,
            soft_wrap=True,
        )
        return None
    return c


def scale_mesh(src: Path, output: Path, rec, *, square: bool = False, csdf=None) -> bool:
    """The mesh route: ``rec`` applied to the mesh ``src``, written to ``output``, what it did
    said on stderr (:func:`partscale.meshedit.report_lines`). Given the mesh's ``csdf`` (zones
    the tool chose, not the user), nothing is written where a tile seam cannot be welded, and
    the note says the edit goes through that CSDF: returns whether the mesh was written."""
    from ..meshedit import edit_mesh_file, report_lines

    welded_only = csdf is not None and not _turned(csdf)  # turned: a remesh would stay turned
    result = edit_mesh_file(src, output, rec, square=square, welded_only=welded_only)
    if not result.written:
        bad = [seam for seam in result.seams if not seam.ok]
        gaps = sum(seam.unmatched for seam in bad)
        total = sum(seam.unmatched + seam.welded for seam in bad)
        why = (
            f"the copies' seams cannot be welded on the mesh ({gaps} of {total} vertices "
            "without a partner: the cross-sections at the zone's planes differ)"
        )
        _common.stderr.print(_remesh_line(csdf, why), highlight=False, soft_wrap=True)
        return False
    lines, done = report_lines(result)
    for kind, line in lines:
        if kind == "warning":
            typer.echo(f"warning: {line}", err=True)
        else:
            _common.stderr.print(line, highlight=False, soft_wrap=True)
    _common.done(done)
    return True


def _edit(c, axis: str, zone, mode: str, *, to, by, copies):
    """The edit from the designer's options: positions with units, --by or --copies."""
    from ..edit import Edit, parse_length, parse_position

    units = c.meta.get("units")
    start = parse_position(zone[0], "--zone START", units)
    end = parse_position(zone[1], "--zone END", units)
    if to is not None:
        return Edit(axis, start, end, parse_position(to, "--to", units), mode)
    # --by and --copies need END (and START) in object units
    ax = AXES_INDEX[axis]
    sb = c.surface_bounds()
    s, e, _ = Edit(axis, start, end, end, mode).resolve(float(sb[0, ax]), float(sb[1, ax]))
    if by is not None:
        return Edit(axis, start, end, e + parse_length(by, units=units, what="--by"), mode)
    return Edit(axis, start, end, s + _copies_total(copies) * (e - s), mode)


def _element_recipe(src: Path, mesh_route: bool, axis: str, copies: str, mode, snap, square, given):
    """``--copies`` with no ``--zone``: whole elements added or removed along ``axis``
    (:func:`partscale.zones.elements.find_elements`), the choice printed; returns the CSDF
    they were found on (a mesh's, on the mesh route) and the recipe."""
    from ..edit import AXES, Recipe
    from ..zones import add_axis

    if axis.lower() not in AXES:
        raise InputError(f"--axis: expected one of x, y, z, got {axis!r}")
    others = [n for n, v in given if n != "--copies"]
    if others or snap or (mode is not None and mode.lower() != "tile"):
        extra = ", ".join(
            [
                *others,
                *(["--snap"] if snap else []),
                *([f"--mode {mode}"] if mode and mode.lower() != "tile" else []),
            ]
        )
        raise InputError(
            f"--copies with no --zone: expected it alone (whole elements), got {extra}"
        )
    c = _object(src, mesh_route, True, square)
    ax = AXES.index(axis.lower())
    text = copies.strip()
    try:
        n = int(text)
    except ValueError:
        raise InputError(
            f"--copies: expected +N or -N (elements more or fewer), or N in all, got {copies!r}"
        ) from None
    # N in all: the change is N less the count of the repeat add_axis uses (elements, steps,
    # a ring's elements)
    edits, notes = add_axis(c, ax, n, in_all=not text.startswith(("+", "-")))
    rec = Recipe(tuple(edits))
    note = remesh_note(c, rec) if mesh_route else None
    for line in [*notes, *([note] if note else [])]:
        _common.stderr.print(line, highlight=False, soft_wrap=True)
    return c, rec


def _copies_total(copies: str) -> int:
    """The number of copies in all that ``--copies`` asks for (``+N``: N more than the one)."""
    text = copies.strip()
    try:
        n = int(text)
    except ValueError:
        raise InputError(
            f"--copies: expected +N (more copies) or N (in all), got {copies!r}"
        ) from None
    total = 1 + n if text.startswith(("+", "-")) else n
    if total < 1:
        raise InputError(f"--copies: expected at least one copy in all, got {copies!r}")
    return total


AXES_INDEX = {"x": 0, "y": 1, "z": 2}
