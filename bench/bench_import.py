"""Benchmark: ``partscale import`` at --res 128 vs libigl's winding-number signed distance.

For every object in ../shared/data/{kenney, polyhaven, khronos} and Sweet Home 3D's radiator: our import (mesh already read,
the numba kernels already compiled) timed as the median of 3 runs, its peak memory (peak of
traced numpy/Python allocations in a fourth, untimed run, and the process's max RSS after the
timed runs, in a fresh subprocess per object),
and, in the same subprocess on the same grid, libigl's
``igl.signed_distance(P, V, F, sign_type=FAST_WINDING_NUMBER)`` over every voxel centre
(one run). Accuracy columns compare the two fields: median |difference| in the 3-voxel band
(voxels) and sign agreement more than two voxels from the surface (our thickened sheets and
dropped buried faces differ from libigl's raw field by design on open assemblies). Then the
surface's pieces (marching cubes components), closed internal voids, and the p99 band distance
error against exact point-to-triangle distances where the nearest triangle is a plain closed
surface (sheets and thin pieces are thickened by design). Every resolution given (default 128
and 256) runs per object, side by side, with the growth from the first; the load average is
printed: on a shared machine compare ratios measured in the same run.

Usage::

    PYTHONPATH=src python bench/bench_import.py [--res 128 256] [--igl all|subset|none] [--only NAME]
    PYTHONPATH=src python bench/bench_import.py --stages [--res 256] [--only SheenChair] [--runs 2]

``--stages``: per stage of the import (as its progress reports them), wall seconds, CPU seconds
(every thread; the calling thread's share beside them) and CPU over wall (how many cores the
stage kept busy), ``--runs`` runs per object after a warm-up; then the whole ``partscale
import`` command (reading the mesh, the import, writing the file) run as users run it, in a
fresh interpreter, phase by phase (start-up imports, read and import, write with the
thin-feature check), its CPU over wall; then, unless ``--igl none``, libigl's signed distance
on the same grid and the speed-up over the import and over the whole command, in the same run.
On a shared machine the load average printed says how far wall figures can be trusted: CPU
seconds are robust, shares are not.

``--igl subset`` (default) runs libigl on SheenChair, the Poly Haven objects and four Kenney
objects only (libigl takes seconds to minutes per object on 2 cores); the table says where
libigl was not run.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
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
    out += [p for p in [DATA / "sweethome3d" / "electricRadiator.obj"] if p.exists()]
    return out


def band_p99(c, mesh, n: int = 100_000) -> float | None:
    """p99 of ``| |sdf| - d |`` in voxels over band voxels (up to ``n``, sampled) whose nearest
    triangle is a plain closed-surface one (not an open sheet or a thin piece, which the import
    thickens by design) and whose nearest surface stays that triangle once those pieces are
    thickened (next to a thin fin the fin's thickened face is nearer, by design: such voxels
    measured the thickening, not the distances); ``d``: exact point-to-triangle distance
    (libigl). None without libigl."""
    try:
        import igl
    except ImportError:
        return None
    import math

    import numpy as np

    from partscale.ingest import mesh_sdf as ms  # the import's own classification, for the bench

    h = c.voxel_size
    V = np.ascontiguousarray(mesh.vertices, np.float64)
    F = np.ascontiguousarray(mesh.faces, np.int64)
    band = np.argwhere(np.abs(c.sdf) <= 3 * h)
    rng = np.random.default_rng(0)
    band = band[rng.choice(len(band), min(len(band), n), replace=False)]
    d2, fi, _ = igl.point_mesh_squared_distance(c.index_to_world(band), V, F)
    res = c.meta["history"][0]["res"]
    sub, parent, _, cls, _ = ms.classify_pieces(ms._Winding(V, F), ms.probe_size(h, res))
    boundary = np.nonzero(cls == 0)[0]
    sheet = np.nonzero(cls == 2)[0]
    thick = math.sqrt(3) / 2 * h  # the import's half-thickness of thickened pieces
    t = ms._thickness(sub[boundary], 0.01 * h)
    thin = boundary[t < 2 * thick]
    plain = np.zeros(len(F), bool)
    plain[parent[boundary]] = True
    plain[parent[sheet]] = False
    plain[parent[thin]] = False
    keep = plain[fi]
    # the thickened pieces' surfaces, offset as the import offsets them
    pieces = np.concatenate([sheet, thin])
    if len(pieces):
        offset = np.concatenate([np.full(len(sheet), thick), thick - t[t < 2 * thick] / 2])
        tris = sub[pieces].reshape(-1, 3)
        d2t, ft, _ = igl.point_mesh_squared_distance(
            c.index_to_world(band), tris, np.arange(len(tris)).reshape(-1, 3)
        )
        keep &= np.sqrt(d2t) - offset[ft] >= np.sqrt(d2)
    err = np.abs(np.abs(c.sdf[tuple(band[keep].T)]) - np.sqrt(d2[keep])) / h
    return float(np.quantile(err, 0.99))


def one(path: Path, res: int, run_igl: bool) -> dict:
    """Measure one object in this (fresh) process; returns a JSON-able dict."""
    import numpy as np

    from partscale import ingest

    mesh = ingest.load_mesh(path)
    ingest.from_mesh(mesh, res=32)  # load the compiled kernels (numba cache) outside the timing
    times = []
    for _ in range(3):
        t = time.perf_counter()
        c = ingest.from_mesh(mesh, res=res)
        times.append(time.perf_counter() - t)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    # tracing slows allocations down: peak memory is measured in a fourth, untimed run
    tracemalloc.start()
    ingest.from_mesh(mesh, res=res)
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    from scipy import ndimage

    from partscale.evaluate import metrics

    lab, n_out = ndimage.label(c.sdf > 0)
    border = set()
    for ax in range(3):
        border |= set(np.unique(np.take(lab, [0, -1], axis=ax)).tolist())
    del lab
    out = {
        "pieces": metrics.topology(metrics.to_mesh(c))[1],
        "voids": n_out - len(border - {0}),
        "band_p99": band_p99(c, mesh),
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


def thread_cpu() -> dict[int, float]:
    """CPU seconds (user + system) of each live thread of this process, by thread id."""
    tick = os.sysconf("SC_CLK_TCK")
    out = {}
    for task in Path("/proc/self/task").iterdir():
        try:
            fields = (task / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # the thread ended meanwhile
        out[int(task.name)] = (int(fields[11]) + int(fields[12])) / tick
    return out


def bound_wall(before: dict[int, float], after: dict[int, float], cpu: float) -> float:
    """Estimated wall seconds of a span's work on this machine's cores, idle: its busiest
    thread's CPU (the threads that ended within it counted as one), or its CPU over the cores.

    A load-robust view of how parallel the work is, where wall figures are not. Within a span
    it is the least wall the work needs, so the busy share it gives is an upper estimate, the
    closer the finer the spans; it errs the other way where threads ended within the span
    (counted as one) or where a loaded machine left work on one thread that idle cores would
    have shared.
    """
    deltas = [after[t] - before.get(t, 0.0) for t in after]
    ended = cpu - sum(deltas)
    return max(max(deltas, default=0.0), ended, cpu / (os.cpu_count() or 1))


def stages(path: Path, res: int, runs: int) -> float:
    """Per-stage wall, CPU and CPU/wall of the import of ``path``; returns the median wall."""
    from partscale import ingest

    mesh = ingest.load_mesh(path)
    ingest.from_mesh(mesh, res=32)  # load the compiled kernels outside the timing
    walls = []
    for rep in range(runs):
        marks = [(time.perf_counter(), time.process_time(), thread_cpu(), "start")]

        def mark(_f: float, msg: str, m: list = marks) -> None:
            m.append((time.perf_counter(), time.process_time(), thread_cpu(), msg))

        ingest.from_mesh(mesh, res=res, progress=mark)
        marks.append((time.perf_counter(), time.process_time(), thread_cpu(), "end"))
        bound = report(marks)
        w, c = marks[-1][0] - marks[0][0], marks[-1][1] - marks[0][1]
        walls.append(w)
        print(
            f"{path.name} at {res}, run {rep + 1}: wall {w:.2f} s, CPU {c:.2f} s, busy "
            f"{c / w:.2f} of {os.cpu_count()} cores; on idle cores about "
            f"{c / bound:.2f} (load average {os.getloadavg()[0]:.1f})",
            flush=True,
        )
    return statistics.median(walls)


def report(marks: list) -> float:
    """Print each span between ``marks`` (wall, CPU, threads' CPU, label); returns the sum of
    their :func:`bound_wall`."""
    total = 0.0
    for (w0, c0, t0, what), (w1, c1, t1, _) in itertools.pairwise(marks):
        bound = bound_wall(t0, t1, c1 - c0)
        total += bound
        if w1 - w0 >= 0.01:
            print(
                f"  {what:44s} wall {w1 - w0:6.2f} s  CPU {c1 - c0:6.2f} s  "
                f"busy {(c1 - c0) / (w1 - w0):4.2f}  idle-core est. {bound:5.2f} s"
            )
    return total


#: Runs ``partscale import`` as the command does (its ``main``), in a fresh interpreter, and
#: prints the wall, CPU and threads' CPU seconds of its phases as JSON: start-up (the
#: interpreter, the command-line interface and the ingest package), each stage the import
#: reports (reading the mesh loads trimesh, classifying loads libigl), writing the file beside
#: the thin-feature check, and the rest.
_PHASES = """
import json, os, sys, time
sys.path.insert(0, sys.argv.pop(1))
from bench_import import thread_cpu
def now():
    return time.perf_counter(), time.process_time(), thread_cpu()
# the interpreter's own start, from the process's start time (clock ticks after boot)
with open("/proc/self/stat") as f:
    start_ticks = int(f.read().rsplit(")", 1)[1].split()[19])
with open("/proc/uptime") as f:
    up = float(f.read().split()[0])
start = time.perf_counter() - (up - start_ticks / os.sysconf("SC_CLK_TCK"))
marks = [("start", start, 0.0, {})]
import partscale.cli
from partscale import ingest
cmd = sys.modules["partscale.cli.import_"]  # the module (the package names the command so)
marks.append(("start-up: interpreter, cli, ingest", *now()))
load, write = ingest.load, cmd._write_and_check
def timed_load(*a, **k):
    shown = k["progress"]
    last = ["import: its input checks"]
    def progress(f, msg):  # each stage the import reports ends at the next one's start
        marks.append((last[0], *now()))
        last[0] = "import: " + msg
        shown(f, msg)
    out = load(*a, **{**k, "progress": progress})
    marks.append((last[0], *now()))
    return out
def timed_write(*a, **k):
    out = write(*a, **k)
    marks.append(("write and thin-feature check", *now()))
    return out
ingest.load, cmd._write_and_check = timed_load, timed_write
sys.argv = ["partscale", "import", *sys.argv[1:]]
try:
    partscale.cli.main()
except SystemExit:
    pass
marks.append(("messages and exit", *now()))
print(json.dumps([(w, c, {int(k): v for k, v in t.items()}, m) for m, w, c, t in marks]), file=sys.stderr)
"""


def command(path: Path, res: int, runs: int) -> list[float]:
    """The whole ``partscale import`` (read, import, write) as users run it, phase by phase."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    walls = []
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(runs):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            out = Path(tmp) / "o.csdf.npz"
            cmd = [sys.executable, "-c", _PHASES, str(Path(__file__).parent), str(path)]
            cmd += ["--res", str(res), "-o", str(out)]
            proc = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
            w = time.perf_counter() - t
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            c = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            marks = json.loads(proc.stderr.strip().splitlines()[-1])
            # each mark names the phase that ends there; report() wants the one that starts
            bound = report([(*a[:3], b[3]) for a, b in itertools.pairwise(marks)] + marks[-1:])
            # the interpreter's exit (module teardown, the libraries' exit handlers) on one thread
            exit_cpu = c - marks[-1][1]
            exit_wall = w - (marks[-1][0] - marks[0][0])
            bound += exit_cpu
            print(
                f"  {'interpreter exit':44s} wall {exit_wall:6.2f} s  CPU {exit_cpu:6.2f} s  "
                f"busy {exit_cpu / exit_wall:4.2f}  idle-core est. {exit_cpu:5.2f} s"
            )
            walls.append(w)
            print(
                f"partscale import --res {res}, run {rep + 1}: wall {w:.2f} s, CPU {c:.2f} s, "
                f"busy {c / w:.2f} of {os.cpu_count()} cores (target >= 1.4 of 2); on idle "
                f"cores about {c / bound:.2f} (load average {os.getloadavg()[0]:.1f})",
                flush=True,
            )
    return walls


def igl_seconds(path: Path, res: int) -> float:
    """libigl's ``signed_distance`` (fast winding number sign) over the import's grid, one run."""
    import igl
    import numpy as np

    from partscale import ingest

    mesh = ingest.load_mesh(path)
    c = ingest.from_mesh(mesh, res=res)
    idx = np.stack(np.meshgrid(*[np.arange(s) for s in c.shape], indexing="ij"), -1)
    P = c.index_to_world(idx.reshape(-1, 3))
    V, F = np.ascontiguousarray(mesh.vertices), np.ascontiguousarray(mesh.faces)
    t = time.perf_counter()
    igl.signed_distance(P, V, F, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER)
    return time.perf_counter() - t


def stages_and_command(path: Path, res: int, runs: int, run_igl: bool) -> None:
    """``--stages``: the library's stages, the whole command, and libigl in the same run."""
    ours = stages(path, res, runs)
    walls = command(path, res, runs)
    if run_igl:
        ig = igl_seconds(path, res)
        print(
            f"libigl signed_distance at {res}: {ig:.2f} s; speed-up {ig / ours:.1f}x over the "
            f"import (median {ours:.2f} s), {ig / max(walls):.1f}-{ig / min(walls):.1f}x over the "
            f"whole command ({min(walls):.2f}-{max(walls):.2f} s); load average "
            f"{os.getloadavg()[0]:.1f}",
            flush=True,
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, nargs="+", default=[128, 256])
    ap.add_argument("--igl", choices=("all", "subset", "none"), default="subset")
    ap.add_argument("--only", default=None, help="run only objects whose name contains this")
    ap.add_argument("--one", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--with-igl", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--stages", action="store_true", help="per-stage CPU over wall")
    ap.add_argument("--runs", type=int, default=2, help="runs of each (--stages)")
    args = ap.parse_args()
    if args.stages:
        for path in objects():
            if path.stem == (args.only or "SheenChair") or (args.only and args.only in str(path)):
                stages_and_command(path, args.res[-1], args.runs, args.igl != "none")
        return
    if args.one:
        print(json.dumps(one(Path(args.one), args.res[0], args.with_igl)))
        return
    if not DATA.exists():
        sys.exit(f"test objects not found under {DATA} (set PARTSCALE_DATA)")
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + os.pathsep + env.get("PYTHONPATH", "")
    rows = []
    load = os.getloadavg()
    print(
        f"import at --res {' and '.join(map(str, args.res))}: median of 3 runs; libigl "
        f"signed_distance (fast winding number sign) on the same grid, 1 run ({args.igl}); "
        f"load average {load[0]:.1f} {load[1]:.1f} {load[2]:.1f} on {os.cpu_count()} cores",
        flush=True,
    )
    head = (
        f"{'object':42s} {'res':>4s} {'tris':>6s} {'grid':>13s} {'ours s':>7s} {'traced':>8s}"
        f" {'maxRSS':>8s} {'libigl s':>8s} {'speed-up':>8s} {'band d50':>8s} {'sign %':>7s}"
        f" {'pieces':>6s} {'voids':>5s} {'p99 tri':>7s}"
    )
    print(head)
    print("-" * len(head), flush=True)
    for path in objects():
        if args.only and args.only not in str(path):
            continue
        run_igl = args.igl == "all" or (args.igl == "subset" and path.name in IGL_SUBSET)
        if path.parent.parent.name == "polyhaven" and args.igl == "subset":
            run_igl = True
        for res in args.res:
            cmd = [sys.executable, __file__, "--one", str(path), "--res", str(res)]
            if run_igl:
                cmd.append("--with-igl")
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
            if proc.returncode != 0:
                print(f"{path.name}: failed\n{proc.stderr}")
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            r["res"] = res
            rows.append(r)
            grid = "x".join(map(str, r["shape"]))
            mib = 1 << 20
            igl_cols = (
                f" {r['igl_s']:8.2f} {r['igl_s'] / r['median_s']:7.1f}x {r['band_diff_p50']:8.3f}"
                f" {100 * r['sign_agree']:7.2f}"
                if "igl_s" in r
                else f" {'not run':>8s} {'':>8s} {'':>8s} {'':>7s}"
            )
            p99 = "" if r.get("band_p99") is None else f"{r['band_p99']:7.3f}"
            print(
                f"{r['name']:42s} {res:4d} {r['triangles']:6d} {grid:>13s} {r['median_s']:7.2f}"
                f" {r['traced_peak'] / mib:6.0f}Mi {r['max_rss'] / mib:6.0f}Mi{igl_cols}"
                f" {r['pieces']:6d} {r['voids']:5d} {p99:>7s}",
                flush=True,
            )
    if len(args.res) > 1:
        r0 = args.res[0]
        base = {r["name"]: r for r in rows if r["res"] == r0}
        print(f"growth from res {r0}: import time, libigl time, pieces (same for closed objects)")
        for r in rows:
            b = base.get(r["name"])
            if r["res"] == r0 or b is None:
                continue
            ig = f"{r['igl_s'] / b['igl_s']:6.2f}" if "igl_s" in r and "igl_s" in b else "      "
            print(
                f"{r['name']:42s} {r['res']:4d} ours x{r['median_s'] / b['median_s']:.2f} "
                f"libigl x{ig} pieces {b['pieces']} -> {r['pieces']}"
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
