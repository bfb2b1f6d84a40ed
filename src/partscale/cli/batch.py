"""``partscale batch``: the pipeline over many objects (a thin layer over partscale.batch.run)."""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from . import _common

if TYPE_CHECKING:
    from ..batch import BatchResult

OPTIONAL_VALUES = {
    "--segment": ("fast", ("fast", "coacd")),
    "--render": ("iso", ("iso", "front", "side", "top")),
}
"""Options whose value may be left out (typer has no such options): the default, and the values
(:data:`partscale.segment.METHODS` and :data:`partscale.render.VIEWS`, written out so that
reading the command line imports neither stage)."""


def optional_values(argv: list[str]) -> list[str]:
    """``batch ... --segment [METHOD]``: supply the default where no value follows.

    The next word is the option's value only when it is one of its values, so
    ``batch --segment data/ -o out`` segments with ``fast`` and reads ``data/`` as an input.
    Other commands' arguments are returned unchanged.
    """
    words = [a for a in argv if not a.startswith("-")]
    if not words or words[0] != "batch":
        return argv
    out: list[str] = []
    for i, a in enumerate(argv):
        out.append(a)
        if a in OPTIONAL_VALUES:
            default, values = OPTIONAL_VALUES[a]
            nxt = argv[i + 1] if i + 1 < len(argv) else None
            if nxt is None or nxt.lower() not in values:
                out[-1] = f"{a}={default}"
    return out


def _duration(seconds: float) -> str:
    m, s = divmod(seconds, 60)
    return f"{int(m)}m{s:04.1f}s" if m else f"{s:.1f}s"


@contextlib.contextmanager
def _batch_bar():
    """One bar for the whole batch on stderr: objects done, rate, ETA (hidden without a tty)."""
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    with Progress(
        TextColumn("[bold]batch"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[rate]}"),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        TimeElapsedColumn(),
        TextColumn("{task.fields[last]}"),
        console=_common.stderr,
        transient=True,
        disable=not _common.stderr.is_terminal,
    ) as bar:
        task = bar.add_task("batch", total=None, rate="", last="")
        state: dict[str, int] = {}

        def callback(fraction: float, message: str) -> None:
            step, _, said = message.partition(": ")
            if step == "plan":  # "plan: N to run, M already done"
                state["total"] = int(said.split()[0])
                bar.update(task, total=max(state["total"], 1), last=message)
                return
            if "total" not in state:  # the steps before the plan
                bar.update(task, last=message)
                return
            done = round(fraction * state["total"])
            speed = bar.tasks[0].speed
            rate = f"{speed * 60:.1f}/min" if speed else ""
            bar.update(task, completed=done, rate=rate, last=message)

        yield callback


def batch(
    inputs: Annotated[
        list[Path],
        typer.Argument(
            metavar="INPUTS",
            help="Files, folders (searched recursively by extension) or manifests (.csv with a "
            "'path' column, .jsonl with a 'path' key; other columns: name, res, square, segment, "
            "recipe, size, allow_deform, export, render).",
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "-o",
            "--output",
            metavar="DIR",
            help="Where to write: a folder, one subfolder per object and status.csv.",
        ),
    ],
    res: _common.Res = 128,
    square: Annotated[
        bool,
        typer.Option("--square", help=_common.SQUARE_HELP + ": each mesh of the batch."),
    ] = False,
    segment: Annotated[
        str | None,
        typer.Option(
            "--segment",
            metavar="[METHOD]",
            help="Segment each object first: fast (--segment alone) or coacd.",
        ),
    ] = None,
    recipe: Annotated[
        Path | None,
        typer.Option("--recipe", metavar="FILE", help="A recipe JSON to apply: to every object."),
    ] = None,
    size: Annotated[
        tuple[str, str, str] | None,
        typer.Option(
            "--size", metavar="X Y Z", help=_common.SIZE_HELP, callback=_common.check_size
        ),
    ] = None,
    allow_deform: Annotated[
        bool,
        typer.Option("--allow-deform", help=_common.ALLOW_DEFORM_HELP + ": each object's."),
    ] = False,
    export: Annotated[
        str,
        typer.Option(
            "--export",
            metavar="FORMATS",
            help="Outputs per object, comma-separated: csdf, glb, ply, obj, raw, png, nrrd "
            "('none' for a render only).",
        ),
    ] = "csdf",
    render: Annotated[
        str | None,
        typer.Option(
            "--render",
            metavar="[VIEW]",
            help="Also render a 512x512 PNG: iso (--render alone), front, side or top.",
        ),
    ] = None,
    engine: Annotated[
        str, typer.Option("--engine", metavar="ENGINE", help="local (process pool) or ray.")
    ] = "local",
    address: Annotated[
        str | None,
        typer.Option(
            "--address",
            metavar="ADDRESS",
            help="Ray cluster to join.",
            show_default="a local instance",
        ),
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option("--workers", metavar="N", help="Objects at once.", show_default="the cores"),
    ] = None,
    timeout: Annotated[
        float | None,
        typer.Option("--timeout", metavar="SECONDS", help="Seconds one object may take."),
    ] = None,
    memory: Annotated[
        str | None,
        typer.Option(
            "--memory",
            metavar="SIZE",
            help="Memory one worker may use, e.g. 4GiB.",
            show_default="the machine's, shared out",
        ),
    ] = None,
    retries: Annotated[
        int,
        typer.Option("--retries", metavar="N", help="Ray: retries of a task whose worker died."),
    ] = 1,
    rank: Annotated[
        int, typer.Option("--rank", metavar="N", help="This shard's index (Slurm arrays).")
    ] = 0,
    world_size: Annotated[
        int, typer.Option("--world-size", metavar="N", help="Number of shards.")
    ] = 1,
    retry_failed: Annotated[
        bool, typer.Option("--retry-failed", help="Rerun objects that failed before.")
    ] = False,
) -> None:
    """Run the pipeline on many objects: resumable (OUTDIR/status.csv), on all cores or Ray."""
    from ..batch import run

    with _batch_bar() as bar:
        r = run(
            inputs,
            output,
            res=res,
            square=square,
            segment=segment,
            recipe=recipe,
            fit=list(size) if size else None,
            allow_deform=allow_deform,
            export=export,
            render=render,
            engine=engine.lower(),
            workers=workers,
            timeout=timeout,
            memory=memory,
            address=address,
            retries=retries,
            rank=rank,
            world_size=world_size,
            retry_failed=retry_failed,
            progress=bar,
        )
    # unwrapped lines (rich would wrap long paths at the terminal width)
    sys.stderr.write("".join(line + "\n" for line in summary(r)))
    sys.stderr.flush()
    code = exit_code(r)
    if code:
        raise typer.Exit(code)


def summary(r: BatchResult) -> list[str]:
    """What the batch says when it ends: counts, the slowest objects, one line per failure."""
    counts = f"{len(r.done)} done, {len(r.failed)} failed, {len(r.skipped)} skipped (already done)"
    if r.not_retried:
        counts += f", {len(r.not_retried)} failed before (not retried: --retry-failed)"
    if r.interrupted:
        counts += f", {len(r.interrupted)} interrupted"
    lines = [f"batch: {counts} in {_duration(r.seconds)}; status: {r.status}"]
    if r.slowest:
        lines.append("slowest: " + ", ".join(f"{n} {s:.1f} s" for n, s in r.slowest[:5]))
    lines += [
        f"failed: {name}: {' '.join(error.split())}" for name, error in [*r.failed, *r.not_retried]
    ]
    return lines


def exit_code(r: BatchResult) -> int:
    """130 when interrupted, 1 when an object failed (now or before), else 0."""
    return 130 if r.interrupted else 0 if r.ok else 1
