"""Edit cost at 128 on every object of ``eval/suite.json`` (issue 15: ≤ 100 ms each), beside a plain
vectorised resample of the same edit in the same run.

Each object is imported at ``--res`` and segmented ``fast`` (as ``partscale eval --segment``
does; the segment cache makes reruns cheap); its edit runs in stretch and tile with
:func:`partscale.edit.apply_edit` (re-evaluation included) and with
:func:`partscale.edit.naive_edit` (no re-evaluation, no seam blend): median wall and CPU ms of
``--repeat`` after one warm-up. A recipe entry runs its recipe; ``sweethome3d/electricRadiator``
rides along with a stretch/tile of x 25 %–75 % to 125 %.

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_edit_suite.py [--repeat 3] [--only NAME]``
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from dataclasses import replace
from functools import partial
from pathlib import Path

from _timing import timed_cpu

from partscale import ingest, reuse_freed_memory
from partscale.edit import Edit, apply_edit, apply_recipe, naive_edit
from partscale.evaluate import load_suite
from partscale.segment import segment

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
RADIATOR = ("radiator", "sweethome3d/electricRadiator.obj")
RADIATOR_EDIT = Edit.parse({"axis": "x", "zone": ["25%", "75%"], "to": "125%"})
TARGET_MS = 100.0


def times(fn: Callable[[], object], repeat: int) -> tuple[float, float]:
    """(median wall ms, median CPU ms) of ``repeat`` calls after one warm-up."""
    fn()
    wall, cpu = timed_cpu(fn, repeat)
    return 1e3 * wall, 1e3 * cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--only", default="", help="run only entries whose name contains this")
    args = ap.parse_args()
    # as the CLI does (partscale.cli.main): freed grids' pages are reused, not faulted in anew
    print(f"freed memory reused (glibc): {'yes' if reuse_freed_memory() else 'no'}")
    suite = load_suite(ROOT / "eval" / "suite.json")
    jobs = [(e.name, e.path, e.edit, e.recipe) for e in suite.entries]
    jobs.append((*RADIATOR, RADIATOR_EDIT, None))
    print(
        f"edit at --res {args.res}, median of {args.repeat} after a warm-up; "
        f"load average {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores"
    )
    print(
        f"{'object':24s} {'mode':8s} {'grid':>12s} {'ours ms':>8s} {'cpu ms':>7s} "
        f"{'naive ms':>9s} {'ours/naive':>10s} {'<= 100 ms':>9s}"
    )
    worst = 0.0
    for name, path, edit, recipe in jobs:
        if args.only not in name:
            continue
        c = segment(ingest.load(DATA / path, res=args.res), method="fast", cache=True)
        grid = "x".join(map(str, c.shape))
        if recipe is not None:
            ours = times(partial(apply_recipe, c, recipe), args.repeat)
            print(f"{name:24s} {'recipe':8s} {grid:>12s} {ours[0]:8.1f} {ours[1]:7.1f}")
            worst = max(worst, ours[0])
            continue
        assert edit is not None  # an entry has an edit or a recipe
        for mode in ("stretch", "tile"):
            e = replace(edit, mode=mode)
            ours = times(partial(apply_edit, c, e), args.repeat)
            naive = times(partial(naive_edit, c, e), args.repeat)
            ok = "yes" if ours[0] <= TARGET_MS else "no"
            print(
                f"{name:24s} {mode:8s} {grid:>12s} {ours[0]:8.1f} {ours[1]:7.1f} "
                f"{naive[0]:9.1f} {ours[0] / naive[0]:10.2f} {ok:>9s}"
            )
            worst = max(worst, ours[0])
    print(f"slowest edit: {worst:.1f} ms (target <= {TARGET_MS:.0f} ms)")


if __name__ == "__main__":
    main()
