"""Zone suggestion and fit-to-size timings on the evaluation suite, beside a hand-given edit.

For every object of ``eval/suite.json`` (imported at ``--res``, 128 by default): the time of
:func:`partscale.zones.suggest` per axis, of :func:`partscale.zones.fit` to the suite's target
length including the edits (:func:`partscale.edit.apply_recipe`), and, as the baselines in the
same run, of the suite's own hand-given edit (:func:`partscale.edit.apply_edit`, stretch) and of
the candidates without the local features (:func:`partscale.zones.axis_candidates` given none:
the path before knobs, handles and colour motifs were sought, less its old 27-voxel detector,
which cost about 4 ms an axis). Each time is the least of three runs.
Targets (issue 13): suggest <= 0.3 s per axis, fit <= 2 s per object including the edit.

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_zones.py [--res 128]``
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

from partscale.edit import Edit, apply_edit, apply_recipe
from partscale.ingest import load
from partscale.zones import axis_candidates, fit, suggest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("PARTSCALE_DATA", ROOT.parent / "shared" / "data"))


def _least(fn, runs: int = 3) -> float:
    """The least wall time (s) of ``runs`` calls of ``fn``."""
    best = float("inf")
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=128)
    args = ap.parse_args()
    suite = json.loads((ROOT / "eval" / "suite.json").read_text())
    print(
        f"{'object':24s} {'shape':>14s} {'suggest x/y/z s':>20s} {'no features s':>20s} "
        f"{'fit+edit s':>10s} {'hand edit s':>11s}  chosen"
    )
    worst_suggest = worst_fit = 0.0
    for o in suite["objects"]:
        if "edit" not in o:  # a recipe entry: no single target length to fit
            continue
        c = load(DATA / o["path"], res=args.res)
        per_axis = [_least(lambda a=a, c=c: suggest(c, a)) for a in "xyz"]
        plain = [_least(lambda a=a, c=c: axis_candidates(c, a, features=[])) for a in "xyz"]
        edit = Edit.parse({**o["edit"], "mode": o["edit"].get("mode", "stretch")})
        ax = edit.axis_index
        sb = c.surface_bounds()
        lo, hi = float(sb[0, ax]), float(sb[1, ax])
        _, e, d = edit.resolve(lo, hi)
        size = ["=", "=", "="]
        size[ax] = repr(hi - lo + d - e)
        t = time.perf_counter()
        recipe, _ = fit(c, size)
        apply_recipe(c, recipe)
        t_fit = time.perf_counter() - t
        t = time.perf_counter()
        apply_edit(c, edit)
        t_hand = time.perf_counter() - t
        worst_suggest = max(worst_suggest, *per_axis)
        worst_fit = max(worst_fit, t_fit)
        chosen = "+".join(x.mode for x in recipe.edits)
        print(
            f"{o['name']:24s} {'x'.join(map(str, c.shape)):>14s} "
            f"{'/'.join(f'{v:.3f}' for v in per_axis):>20s} "
            f"{'/'.join(f'{v:.3f}' for v in plain):>20s} {t_fit:10.2f} {t_hand:11.2f}  {chosen}"
        )
    print(
        f"worst suggest per axis {worst_suggest:.2f} s (target <= 0.3); "
        f"worst fit+edit {worst_fit:.2f} s (target <= 2)"
    )


if __name__ == "__main__":
    main()
