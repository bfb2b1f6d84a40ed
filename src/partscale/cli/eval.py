"""``partscale eval``: the evaluation suite (every edit in every mode, figures and tables), or
one edit result scored against its original (``--original A --edited B`` or ``--recipe R``)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from . import _common
from ._common import done, error_line, progress_bar


def eval_suite(
    suite: Annotated[
        Path | None,
        typer.Argument(metavar="SUITE", help="Suite JSON file (e.g. eval/suite.json)."),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(
            "-o", "--output", metavar="DIR", help="Where to write: a folder (created; suite only)."
        ),
    ] = None,
    original: Annotated[
        Path | None,
        typer.Option("--original", metavar="FILE", help="Score one edit: the original .csdf.npz."),
    ] = None,
    edited: Annotated[
        Path | None,
        typer.Option(
            "--edited",
            metavar="FILE",
            help="The edited .csdf.npz (its zones read from its history; several edits, "
            "several zones).",
        ),
    ] = None,
    recipe: Annotated[
        Path | None,
        typer.Option(
            "--recipe",
            metavar="FILE",
            help="A recipe JSON to apply: to --original, then scored.",
        ),
    ] = None,
    as_json: Annotated[
        bool,
        typer.Option("--json", help="Print JSON instead of text (for scripts); with --original."),
    ] = False,
    res: Annotated[
        int | None,
        typer.Option(
            "--res", metavar="N", help=_common.RES_HELP, show_default="the suite's, else 128"
        ),
    ] = None,
    only: Annotated[
        str | None, typer.Option("--only", metavar="NAME", help="Run only this object.")
    ] = None,
    segment: Annotated[
        str | None,
        typer.Option(
            "--segment",
            metavar="METHOD",
            help="Segment each object first: fast or coacd (cached); the figures gain a row "
            "coloured by part.",
        ),
    ] = None,
    data: Annotated[
        Path | None,
        typer.Option(
            "--data",
            metavar="DIR",
            help="Folder of the suite's objects.",
            show_default="$PARTSCALE_DATA, else the suite's data key",
        ),
    ] = None,
) -> None:
    """Run each suite edit as global, stretch, tile and the naive baseline; measure and draw.
    Or score one result: --original A.csdf.npz with --edited B.csdf.npz or --recipe R.json.

    Suite: writes NAME.png per object, contact_sheet.png, metrics.csv, metrics.md and
    summary.md. Exit code 0 when every entry ran; 1 when some could not (each listed on stderr
    and in summary.md, the others still ran); 2 for a bad suite file or option. One edit: prints
    the metrics (exit 0, also when some fail their threshold: listed under "fails").
    """
    if original is not None or edited is not None or recipe is not None:
        _score_one(suite, out, original, edited, recipe, as_json)
        return
    from ..errors import InputError

    if suite is None or out is None:
        raise InputError(
            "eval: expected SUITE -o OUT, or --original A with --edited B or --recipe R; got "
            + ("no -o" if suite is not None else "no suite")
        )
    with progress_bar("eval") as bar:
        from ..evaluate import run_suite  # heavy (trimesh, libigl): load only when run

        result = run_suite(suite, out, res=res, only=only, data=data, segment=segment, progress=bar)
    for msg in result.failures:
        error_line(msg)
    n = len(result.objects)
    names = ", ".join(p.name for p in result.files.values())
    done(
        f"evaluated {n - len(result.failures)} of {n} object(s) in {result.elapsed_s:.0f} s "
        f"at --res {result.res}: {out}/ {names}"
    )
    if result.failures:
        # SystemExit, not typer.Exit: the app runs with standalone_mode=False, where click
        # returns typer.Exit's code instead of exiting with it
        raise SystemExit(1)


def _score_one(
    suite: Path | None,
    out: Path | None,
    original: Path | None,
    edited: Path | None,
    recipe: Path | None,
    as_json: bool,
) -> None:
    import json
    import math

    from ..errors import InputError

    if suite is not None or out is not None:
        raise InputError("eval: expected a suite or --original, got both")
    if original is None:
        raise InputError("eval: --edited/--recipe: expected --original too, got none")
    if (edited is None) == (recipe is None):
        raise InputError(
            "eval --original: expected --edited or --recipe (one), got "
            + ("both" if edited is not None else "neither")
        )
    from ..csdf import load
    from ..edit import Recipe
    from ..evaluate import CRITERIA, score_edit

    a = load(original)
    if edited is not None:
        result = score_edit(a, load(edited))
    else:
        assert recipe is not None  # exactly one of --edited, --recipe (checked above)
        result = score_edit(a, recipe=Recipe.load(recipe))

    def clean(v):
        if isinstance(v, float) and not math.isfinite(v):
            return None
        return v

    if as_json:
        doc = {
            **result,
            "metrics": {k: clean(v) for k, v in result["metrics"].items()},
            "reference": {k: clean(v) for k, v in result["reference"].items()},
        }
        typer.echo(json.dumps(doc, indent=2))
        return
    for z in result["zones"]:
        copies = f", {z['copies']} copies" if "copies" in z else ""
        typer.echo(
            f"zone {z['axis']} [{z['zone'][0]:.6g}, {z['zone'][1]:.6g}] -> "
            f"[{z['new_zone'][0]:.6g}, {z['new_zone'][1]:.6g}] {z['mode']}{copies}"
        )
    m = result["metrics"]
    width = max(len(k) for k in m)
    for k, v in m.items():
        text = (
            "n/a"
            if isinstance(v, float) and math.isnan(v)
            else (f"{v:.3g}" if isinstance(v, float) else str(v))
        )
        what = CRITERIA[k][0] if k in CRITERIA else ""
        limit = f"  (fails above {CRITERIA[k][2]:g})" if k in CRITERIA else ""
        typer.echo(f"{k:<{width}}  {text:>8}  {what}{limit}")
    fails = result["failures"]
    typer.echo("fails: " + (", ".join(fails) if fails else "none"))
