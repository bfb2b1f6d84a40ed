"""``partscale eval``: the evaluation suite (every edit in every mode, figures and tables)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ._common import done, error_line, progress_bar


def eval_suite(
    suite: Annotated[Path, typer.Argument(help="Suite JSON file (e.g. eval/suite.json).")],
    out: Annotated[Path, typer.Option("-o", "--out", help="Output folder (created).")],
    res: Annotated[
        int | None,
        typer.Option(
            "--res",
            help="Import resolution, voxels along the longest side (default: the suite's, 128).",
        ),
    ] = None,
    only: Annotated[str | None, typer.Option("--only", help="Run only this object.")] = None,
    segment: Annotated[
        str | None,
        typer.Option(
            "--segment",
            help="Segment each object first with this method (fast or coacd; cached) and add a "
            "row coloured by part to the figures. Off by default.",
        ),
    ] = None,
    data: Annotated[
        Path | None,
        typer.Option(
            "--data", help="Folder of the test objects (default: PARTSCALE_DATA or ../shared/data)."
        ),
    ] = None,
) -> None:
    """Run each suite edit as global, stretch, tile and the naive baseline; measure and draw.

    Writes NAME.png per object, contact_sheet.png, metrics.csv, metrics.md and summary.md.

    Exit code 0 when every entry ran; 1 when some could not (each listed on stderr and in
    summary.md, the others still ran); 2 for a bad suite file or option.
    """
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
