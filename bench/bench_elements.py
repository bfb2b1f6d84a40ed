"""Finding elements and adding one, timed beside today's zone suggestions in the same run.

For every entry of ``eval/suite.json`` that states an element count (``"elements"``), imported
at ``--res`` (128 by default): the time of :func:`partscale.zones.find_elements` on its axis,
of :func:`partscale.zones.suggest` on the same axis (the baseline: what a user ran before), and
of ``fit --add AXIS 1`` in the library (:func:`partscale.zones.fit` with ``add``, then
:func:`partscale.edit.apply_recipe`: the whole command's work but reading and writing files).
Targets: elements <= 0.3 s per axis, fit --add <= 2 s including the edit. Best of ``--repeat``.

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_elements.py [--res 128] [--repeat 3]``
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from _timing import timed

from partscale.edit import apply_recipe
from partscale.ingest import load
from partscale.zones import find_elements, fit, suggest

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    suite = json.loads((ROOT / "eval" / "suite.json").read_text())
    entries = [o for o in suite["objects"] if "elements" in o]
    if not DATA.is_dir():
        raise SystemExit(f"needs the test objects in {DATA}")
    print(
        f"{'object':26s} {'axis':>4s} {'count':>5s} {'elements s':>10s} {'suggest s':>9s} "
        f"{'fit --add 1 s':>13s}"
    )
    worst_el = worst_add = 0.0
    for o in entries:
        axis = o["elements"]["axis"]
        c = load(DATA / o["path"], res=args.res)
        find_elements(c, axis)  # compile what numba compiles once, outside the timing
        t_el, found = timed(lambda c=c, axis=axis: find_elements(c, axis), args.repeat)
        t_sug, _ = timed(lambda c=c, axis=axis: suggest(c, axis), args.repeat)

        def add(c=c, axis=axis):
            recipe, _ = fit(c, None, add={axis: 1})
            return apply_recipe(c, recipe)

        t_add, _ = timed(add, args.repeat)
        n = len(found.best.members) if found.best is not None else 0
        worst_el, worst_add = max(worst_el, t_el), max(worst_add, t_add)
        print(f"{o['name']:26s} {axis:>4s} {n:5d} {t_el:10.3f} {t_sug:9.3f} {t_add:13.3f}")
    print(f"worst: elements {worst_el:.3f} s (target 0.3), fit --add {worst_add:.3f} s (target 2)")


if __name__ == "__main__":
    main()
