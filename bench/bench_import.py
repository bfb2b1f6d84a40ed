"""Benchmark: ``partscale import`` at --res 128 vs libigl's winding-number signed distance.

For every object in ../shared/data/{kenney, polyhaven, khronos}: our import (mesh already read,
the numba kernels already compiled) timed as the median of 3 runs, its peak memory (peak of
traced numpy/Python allocations, and the process's max RSS, in a fresh subprocess per object),
and, in the same subprocess on the same grid, libigl's
``igl.signed_distance(P, V, F, sign_type=FAST_WINDING_NUMBER)`` over every voxel centre
(one run). Accuracy columns compare the two fields: median |difference| in the 3-voxel band
(voxels) and sign agreement more than two voxels from the surface (our thickened sheets and
dropped buried faces differ from libigl's raw field by design on open assemblies).

Usage::

    PYTHONPATH=src python bench/bench_import.py [--res 128] [--igl all|subset|none] [--only NAME]

``--igl subset`` (default) runs libigl on SheenChair, the Poly Haven objects and four Kenney
objects only (libigl takes seconds to minutes per object on 2 cores); the table says where
libigl was not run.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("PARTSCALE_DATA", ROOT.parent / "shared" / "data"))
IGL_SUBSET = {"table.glb", "chair.glb", "bedBunk.glb", "bookcaseOpen.glb", "SheenChair.glb"}


def objects() -> list[Path]:
    out = sorted((DATA / "kenney").glob("*.glb"))
    out += sorted((DATA / "polyhaven").glob("*/*.gltf"))
    out += sorted((DATA / "khronos").glob("*.glb"))
    return out


def one(path: Path, res: int, run_igl: bool) -> dict:
    """Measure one object in this (fresh) process; returns a JSON-able dict."""
    import numpy as np

    from partscale import ingest

    mesh = ingest.load_mesh(path)
    ingest.from_mesh(mesh, res=32)  # load the compiled kernels (numba cache) outside the timing
    times = []
    tracemalloc.start()
    for _ in range(3):
        tracemalloc.reset_peak()
        t = time.perf_counter()
        c = ingest.from_mesh(mesh, res=res)
        times.append(time.perf_counter() - t)
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    out = {
        "name": f"{path.parent.name}/{path.name}",
        "triangles": int(mesh.n_faces),
        "shape": list(c.shape),
        "median_s": statistics.median(times),
        "times": times,
        "traced_peak": traced,
        "max_rss": rss,
    }
    if run_igl:
        import igl

        h = c.voxel_size
        idx = np.stack(np.meshgrid(*[np.arange(s) for s in c.shape], indexing="ij"), -1)
        P = c.index_to_world(idx.reshape(-1, 3))
        V = np.ascontiguousarray(mesh.vertices)
        F = np.ascontiguousarray(mesh.faces)
        t = time.perf_counter()
        S = igl.signed_distance(P, V, F, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER)[0]
        out["igl_s"] = time.perf_counter() - t
        ours = c.sdf.ravel().astype(np.float64)
        band = np.abs(S) < 3 * h
        out["band_diff_p50"] = float(np.median(np.abs(ours[band] - S[band])) / h)
        far = np.abs(S) > 2 * h
        out["sign_agree"] = float(np.mean((ours[far] < 0) == (S[far] < 0)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--igl", choices=("all", "subset", "none"), default="subset")
    ap.add_argument("--only", default=None, help="run only objects whose name contains this")
    ap.add_argument("--one", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--with-igl", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(Path(args.one), args.res, args.with_igl)))
        return
    if not DATA.exists():
        sys.exit(f"test objects not found under {DATA} (set PARTSCALE_DATA)")
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    rows = []
    print(
        f"import at --res {args.res}: median of 3 runs; libigl signed_distance (fast winding "
        f"number sign) on the same grid, 1 run ({args.igl})",
        flush=True,
    )
    head = (
        f"{'object':42s} {'tris':>6s} {'grid':>13s} {'ours s':>7s} {'traced':>8s} {'maxRSS':>8s}"
        f" {'libigl s':>8s} {'speed-up':>8s} {'band d50':>8s} {'sign %':>7s}"
    )
    print(head)
    print("-" * len(head), flush=True)
    for path in objects():
        if args.only and args.only not in str(path):
            continue
        run_igl = args.igl == "all" or (args.igl == "subset" and path.name in IGL_SUBSET)
        if path.parent.parent.name == "polyhaven" and args.igl == "subset":
            run_igl = True
        cmd = [sys.executable, __file__, "--one", str(path), "--res", str(args.res)]
        if run_igl:
            cmd.append("--with-igl")
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if proc.returncode != 0:
            print(f"{path.name}: failed\n{proc.stderr}")
            continue
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        rows.append(r)
        grid = "x".join(map(str, r["shape"]))
        mib = 1 << 20
        igl_cols = (
            f" {r['igl_s']:8.2f} {r['igl_s'] / r['median_s']:7.1f}x {r['band_diff_p50']:8.3f}"
            f" {100 * r['sign_agree']:7.2f}"
            if "igl_s" in r
            else f" {'not run':>8s} {'':>8s} {'':>8s} {'':>7s}"
        )
        print(
            f"{r['name']:42s} {r['triangles']:6d} {grid:>13s} {r['median_s']:7.2f}"
            f" {r['traced_peak'] / mib:6.0f}Mi {r['max_rss'] / mib:6.0f}Mi{igl_cols}",
            flush=True,
        )
    if rows:
        tot = sum(r["median_s"] for r in rows)
        with_igl = [r for r in rows if "igl_s" in r]
        print("-" * len(head))
        print(f"{len(rows)} objects, total import {tot:.1f} s")
        if with_igl:
            sp = [r["igl_s"] / r["median_s"] for r in with_igl]
            print(
                f"libigl on {len(with_igl)} objects: speed-up median {statistics.median(sp):.1f}x, "
                f"min {min(sp):.1f}x"
            )


if __name__ == "__main__":
    main()
