"""Zone suggestion and fit-to-size timings on the evaluation suite, beside a hand-given edit.

For every object of ``eval/suite.json`` (imported at ``--res``, 128 by default): the time of
:func:`partscale.zones.suggest` per axis, of :func:`partscale.zones.fit` to the suite's target
length including the edits (:func:`partscale.edit.apply_recipe`), and, as the baseline in the
same run, of the suite's own hand-given edit (:func:`partscale.edit.apply_edit`, stretch).
Targets (issue 13): suggest <= 0.3 s per axis, fit <= 2 s per object including the edit.

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_zones.py [--res 128]``
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from partscale.edit import Edit, apply_edit, apply_recipe
from partscale.ingest import load
from partscale.zones import fit, suggest

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=128)
    args = ap.parse_args()
    suite = json.loads((ROOT / "eval" / "suite.json").read_text())
    print(
        f"{'object':24s} {'shape':>14s} {'suggest x/y/z s':>20s} {'fit+edit s':>10s} "
        f"{'hand edit s':>11s}  chosen"
    )
    worst_suggest = worst_fit = 0.0
    for o in suite["objects"]:
        if "edit" not in o:  # a recipe entry: no single target length to fit
            continue
        c = load(DATA / o["path"], res=args.res)
        per_axis = []
        for a in "xyz":
            t = time.perf_counter()
            suggest(c, a)
            per_axis.append(time.perf_counter() - t)
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
            f"{'/'.join(f'{v:.2f}' for v in per_axis):>20s} {t_fit:10.2f} {t_hand:11.2f}  {chosen}"
        )
    print(
        f"worst suggest per axis {worst_suggest:.2f} s (target <= 0.3); "
        f"worst fit+edit {worst_fit:.2f} s (target <= 2)"
    )


if __name__ == "__main__":
    main()
