"""``import partscale`` (the lazy top level) beside the imports the eager top level made.

Each row is the median wall time of ``--repeat`` fresh interpreters running one statement, and
the heavy libraries it left in ``sys.modules``:

- ``python -c pass``: the interpreter alone;
- the eager set: what ``import partscale`` imported before its names loaded on first use (the
  numba cache folder, the CSDF type and file, the errors, the memory helpers; numpy with them);
- ``import partscale``: the lazy top level;
- ``import partscale; partscale.fit``: the first use of a stage (zones, which loads numba,
  scipy and trimesh).

Run: ``.venv/bin/python bench/bench_import_time.py [--repeat 15]``
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

HEAVY = ("numpy", "numba", "scipy", "trimesh", "skimage")
ROWS = {
    "interpreter (pass)": "pass",
    "eager set (before)": "import partscale._jit, partscale.csdf, partscale.errors, partscale._memory",
    "import partscale": "import partscale",
    "partscale.fit (first use)": "import partscale; partscale.fit",
}


def run(code: str) -> tuple[float, list[str]]:
    """Wall seconds of a fresh interpreter running ``code``, and the heavy modules it loaded."""
    probe = (
        f"{code}\nimport sys, json; print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    )
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return time.perf_counter() - t, json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    print(f"{'statement':28} {'median s':>9}  heavy modules loaded")
    for label, code in ROWS.items():
        times, loaded = [], []
        for _ in range(args.repeat):
            dt, loaded = run(code)
            times.append(dt)
        print(f"{label:28} {statistics.median(times):9.3f}  {', '.join(loaded) or '-'}")


if __name__ == "__main__":
    main()
