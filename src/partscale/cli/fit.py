"""``partscale fit``: the object resized to a target extent, zones and modes chosen for it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from ..csdf import SUFFIX, load
from . import _common
from .scale import (
    SQUARE_OPTION,
    check_usd,
    csdf_fallback,
    output_option,
    remesh_note,
    scale_mesh,
    write_edited,
)


def _whole_count(value: tuple[str, str]) -> tuple[str, str]:
    """``--add``'s N: a whole number of elements (negative removes)."""
    from ..errors import InputError

    try:
        int(value[1])
    except ValueError:
        raise InputError(
            f"--add: expected AXIS N, N a whole number of elements (-N removes), got {value[1]!r}"
        ) from None
    return value


def fit(
    src: Annotated[
        Path, typer.Argument(metavar="IN", help="A .csdf.npz file, or a mesh (mesh route).")
    ],
    output: Annotated[Path, output_option("for a mesh IN.")],
    size: Annotated[
        tuple[str, str, str] | None,
        typer.Option(
            "--size", metavar="X Y Z", help=_common.SIZE_HELP, callback=_common.check_size
        ),
    ] = None,
    add: Annotated[
        tuple[str, str] | None,
        typer.Option(
            "--add",
            metavar="AXIS N",
            callback=_common.spaced("--add", "AXIS N", _whole_count),
            help="Add N elements (seats, doors, shelf rows, steps) along AXIS; -N removes N. "
            "With y, also the elements of a ring about the vertical (a star base's arms, chairs "
            "about a round table), spaced evenly again.",
        ),
    ] = None,
    allow_deform: Annotated[
        bool,
        typer.Option("--allow-deform", help=_common.ALLOW_DEFORM_HELP + "."),
    ] = False,
    recipe_out: Annotated[
        Path | None,
        typer.Option("--recipe-out", metavar="FILE", help="Write the recipe applied (JSON)."),
    ] = None,
    square: Annotated[bool, SQUARE_OPTION] = False,
) -> None:
    """Resize to a target size or by whole elements: tile whole periods or elements (seats,
    doors, shelf rows), absorb the rest in a slab of constant cross-section; says what it chose,
    and refuses (exit 2) where only a deformation would reach the size. A mesh is edited on the
    mesh route; where the zones chosen are steps or a ring, or the copies' seams cannot be
    welded, through its CSDF instead, written remeshed (and said).
    """
    from ..meshedit import check_route, check_square, is_mesh_route

    mesh_route = is_mesh_route(src, output)
    if not mesh_route:
        _common.check_output(output, suffixes=(SUFFIX,), what="a CSDF file")
    check_square(square, mesh_route, src, output)  # its own line for a mesh -> CSDF --square
    check_route(src, output)
    check_usd(output)
    if recipe_out is not None:
        _common.check_output(recipe_out, suffixes=(".json",), what="a recipe JSON file")
    c = _object(src, mesh_route, square)
    if size is None and add is None:
        from ..errors import InputError

        raise InputError("fit: expected --size X Y Z or --add AXIS N, got neither")
    recipe, remesh, fallback = _plan(c, mesh_route, size, add, allow_deform)
    from .._files import staged_writes

    if mesh_route and not remesh:
        with staged_writes():  # the mesh and its recipe: both, or neither
            if scale_mesh(src, output, recipe, square=square, csdf=fallback):
                _write_recipe(recipe, recipe_out)
                return
    # a CSDF; or on a mesh, steps, a ring or seams that cannot be welded: through its CSDF
    _apply_and_save(c, recipe, output, recipe_out, remesh=mesh_route)


def _object(src: Path, mesh_route: bool, square: bool):
    """The CSDF zones are found on: the file's, or on the mesh route the mesh's (turned as the
    mesh route will turn it; the recipe is then applied to the mesh itself)."""
    if not mesh_route:
        return load(src)
    from ..meshedit import edit_target

    return edit_target(src, zones=True, square=square)


def _plan(c, mesh_route: bool, size, add, allow_deform: bool):
    """The recipe :func:`partscale.zones.fit` chooses, checked up front, and why (stderr);
    whether a mesh is edited through its CSDF (steps or a ring: :func:`.scale.remesh_note`);
    and on the mesh route, the CSDF it falls back to where seams cannot be welded (None where
    that would not fit in memory: :func:`.scale.csdf_fallback`)."""
    from ..zones import fit as fit_zones

    recipe, why = fit_zones(
        c,
        list(size) if size is not None else None,
        add=None if add is None else {add[0]: int(add[1])},
        allow_deform=allow_deform,
    )
    note = remesh_note(c, recipe) if mesh_route else None
    what = f"fit to {' x '.join(size)}" if size is not None else f"fit --add {add[0]} {add[1]}"
    _preflight(c, recipe, mesh_route and note is None, what)
    for line in [*why, *([note] if note else [])]:  # one line each, unwrapped
        _common.stderr.print(line, highlight=False, soft_wrap=True)
    on_mesh = mesh_route and note is None
    fallback = csdf_fallback(c, recipe, what=what) if on_mesh else None
    return recipe, note is not None, fallback


def _apply_and_save(c, recipe, output: Path, recipe_out: Path | None, *, remesh: bool) -> None:
    """The CSDF route: ``recipe`` applied with a progress bar, what changed said, the object
    (or with ``remesh``, its surface as a mesh) and its recipe written (both, or neither)."""
    from .._files import staged_writes
    from ..edit import apply_recipe, describe_changes

    with _common.progress_bar("fit") as bar:
        out = apply_recipe(c, recipe, progress=bar)
    for line in describe_changes(out.meta.get("history", [])[-len(recipe.edits) :], out):
        _common.stderr.print(line, highlight=False, soft_wrap=True)
    with staged_writes():  # the object and its recipe: both, or neither
        write_edited(out, output, remesh=remesh)
        _write_recipe(recipe, recipe_out)
    sb = out.surface_bounds()
    ext = " x ".join(f"{v:.4g}" for v in sb[1] - sb[0])
    _common.done(f"wrote {output} (solid {ext} {out.meta.get('units') or ''})")


def _preflight(c, recipe, on_mesh: bool, what: str) -> None:
    """What applying the recipe checks up front, done before the plan is printed: a plan is
    never shown and then refused (a size too large for memory, a recipe its own schema or the
    mixing rule refuses). ``on_mesh``: applied to the mesh itself, whose route checks its
    copies' memory as it makes them."""
    from ..edit import Recipe, check_recipe_memory

    Recipe.parse(recipe.to_json(), units=c.meta.get("units"))  # what --recipe-out writes reads back
    if on_mesh:
        return
    check_recipe_memory(c, recipe, what=what)


def _write_recipe(recipe, path: Path | None) -> None:
    """--recipe-out: the recipe fit applied, as JSON (written whole or not at all)."""
    if path is None:
        return
    from .._files import atomic_path

    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(recipe.to_json(), indent=2) + "\n")
    _common.done(f"wrote {path}")
