"""``partscale segment``: split an object into nearly convex parts (kept in its .csdf.npz)."""

from __future__ import annotations

from typing import Annotated

import typer

from .._options import count
from ..csdf import SUFFIX, load, save
from ..errors import InputError
from . import _common


def segment(
    path: _common.CsdfIn,
    output: _common.CsdfOut,
    method: Annotated[
        str,
        typer.Option(
            "--method",
            metavar="METHOD",
            help="How to segment: fast (voxel creases) or coacd (the reference, slow).",
        ),
    ] = "fast",  # segment.DEFAULT_METHOD (importing it here would slow every command's start)
    threshold: Annotated[
        float,
        typer.Option(
            "--threshold",
            metavar="FRACTION",
            help="Concavity allowed in a part, relative to size, in (0, 1].",
        ),
    ] = 0.05,
    max_parts: Annotated[
        int | None, typer.Option("--max-parts", metavar="N", help="At most this many parts.")
    ] = None,
    seed: Annotated[
        int, typer.Option("--seed", metavar="N", help="Random seed (same seed, same parts).")
    ] = 0,
    noise: Annotated[
        str,
        typer.Option(
            "--noise",
            metavar="VOXELS",
            help="The surface's relief RMS in voxels, or auto: measured. A rough surface (a "
            "completed scan's) widens the concavity tolerances by its peak-to-valley and joins "
            "specks of relief to their neighbours; 0 segments it as if smooth.",
        ),
    ] = "auto",
    no_cache: Annotated[
        bool,
        typer.Option(
            "--no-cache",
            help="Neither read nor store the cache. The cache lives in $PARTSCALE_CACHE/segment, "
            "else ~/.cache/partscale/segment, and holds at most 1 GiB (PARTSCALE_CACHE_MAX "
            "bytes; least recently used entries go first); a damaged entry is discarded and "
            "recomputed.",
        ),
    ] = False,
) -> None:
    """Split the object into nearly convex parts; every voxel gets its part's index."""
    from ..segment import check_method, describe_noise
    from ..segment import segment as run

    # options are checked before the (possibly long) work, and before anything is written
    check_method(method, what="--method")
    if not 0 < threshold <= 1:
        raise InputError(f"--threshold: expected a number in (0, 1], got {threshold}")
    if max_parts is not None:
        count(max_parts, "--max-parts")
    relief = _noise(noise)
    _common.check_output(output, suffixes=(SUFFIX,), what="a CSDF file")
    c = load(path)
    with _common.progress_bar(f"segment ({method})") as bar:
        out = run(
            c,
            method=method,
            threshold=threshold,
            max_parts=max_parts,
            seed=seed,
            noise=relief,
            cache=not no_cache,
            progress=bar,
        )
    for line in describe_noise(out.meta["history"][-1]):
        _common.stderr.print(line, highlight=False, soft_wrap=True)
    save(out, output)
    _common.done(f"wrote {output}: {out.n_parts} parts ({method})")


def _noise(text: str) -> float | None:
    """``--noise``: None for auto (measured), else a number of voxels >= 0."""
    if text.strip().lower() == "auto":
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value >= 0 and value < float("inf")):
        raise InputError(f"--noise: expected auto or a number >= 0 (voxels), got {text!r}")
    return value
