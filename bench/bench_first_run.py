"""The first ``partscale import`` after a fresh install: cold (nothing compiled) beside warm.

Each run is a fresh subprocess, as a user's command is. numba's cache is pointed at a new empty
folder (``NUMBA_CACHE_DIR``), so "cold" compiles every kernel the import needs, as on a machine
that never ran partscale; "warm" is the same command again, loading them. Then the ahead-of-time
route: ``python -m partscale.warmup`` (what ``./dev.sh setup`` runs after installing) into another
empty folder, and the first import after it, and the demo's other commands, each with the number
of kernels it still had to compile (0: the warm-up covered it).

    .venv/bin/python bench/bench_first_run.py [--res 128] [--no-warmup]

The target: the first import of the demo object after a fresh install within 10 s on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: Runs the CLI in-process with a counter of the partscale kernels numba compiles (printed last
#: on stderr as ``compiled: N``).
RUNNER = """
import sys
from partscale.warmup import _count_compiles
names = _count_compiles()
from partscale.cli import main
sys.argv = ["partscale", *sys.argv[1:]]
try:
    main()
finally:
    sys.stderr.write(f"compiled: {len(set(names))}\\n")
"""


def run(args: list[str], cache: Path, cwd: Path) -> tuple[float, int]:
    """(wall seconds, kernels compiled) of ``partscale ARGS`` in a fresh process."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    t = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", RUNNER, *args], cwd=cwd, env=env, capture_output=True, text=True
    )
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise SystemExit(f"partscale {' '.join(args)} failed:\n{proc.stderr}")
    compiled = int(proc.stderr.strip().splitlines()[-1].split()[-1])
    return wall, compiled


def warmup(cache: Path) -> float:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "partscale.warmup"], env=env, check=True)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--no-warmup", action="store_true", help="only cold and warm")
    a = ap.parse_args()
    from partscale import data

    table = str(data.table())
    rows: list[tuple[str, float, int]] = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        imp = ["import", table, "-o", "t.csdf.npz", "--res", str(a.res)]
        cold_cache = root / "cache-cold"
        cold_cache.mkdir()
        rows.append(("first import, empty cache (cold)", *run(imp, cold_cache, root)))
        rows.append(("same import again (warm)", *run(imp, cold_cache, root)))
        if not a.no_warmup:
            ahead = root / "cache-ahead"
            ahead.mkdir()
            rows.append(("python -m partscale.warmup, empty cache", warmup(ahead), -1))
            rows.append(("first import after the warm-up", *run(imp, ahead, root)))
            demo = [
                ["segment", "t.csdf.npz", "-o", "t.csdf.npz"],
                ["info", "t.csdf.npz"],
                "scale t.csdf.npz -o l.csdf.npz --axis x --zone 35% 65% --to 105%".split(),
                ["render", "t.csdf.npz", "-o", "t.png"],
                ["render", "t.csdf.npz", "-o", "p.png", "--parts"],
                ["export", "l.csdf.npz", "--mesh", "l.glb"],
            ]
            for args in demo:
                rows.append((f"then partscale {args[0]} (demo)", *run(args, ahead, root)))
    cpus = os.cpu_count()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"first run of partscale, --res {a.res}, {cpus} cores, load {load:.1f} at the end")
    print(f"{'what':<44} {'wall s':>7} {'kernels compiled':>17}")
    for what, wall, n in rows:
        print(f"{what:<44} {wall:7.1f} {'' if n < 0 else n:>17}")
    cold, warm = rows[0][1], rows[1][1]
    print(f"cold / warm: {cold / warm:.1f}x; target: first import <= 10 s")


if __name__ == "__main__":
    main()
