"""Batch throughput and overhead: 1 worker vs 2, Ray beside local.

``--small`` (a dozen small objects; use --res 64): each repeat first runs the objects one after
another in this process on one thread (the baseline: the objects' own times), then the batch
with 1 and 2 workers; each run prints its start-up (until the first object starts), object
phase (first started to last finished) and end (the rest), the CPU busy share (CPU seconds of
the batch and its workers over wall seconds times cores), the overhead (wall minus the sum of
its object times over the cores, and against the baseline's), how far the object phase is
from that ideal share, and the CPU seconds the batch spends beside its objects' (robust to a
busy machine, where the wall figures are not); the end prints each figure's range over the
repeats. Without ``--small``, every object of the data:

Each object: import at --res, fast segmentation, a recipe edit (x zone 35%-65% stretched to
105%), GLB export and an iso render. A corrupt file and an object imported at a resolution no
worker's memory allows ride along and must be recorded failed while everything else completes.
Prints wall time, objects per minute, the 2-worker speed-up, Ray's start-up and per-object
overhead beside the local engine in the same run, and each worker's peak memory.

    .venv/bin/python bench/bench_batch.py [--small] [--res 128] [--no-ray] [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from partscale.batch import discover, read_status, run  # noqa: E402

DATA = Path(os.environ.get("PARTSCALE_DATA", ROOT.parent / "shared" / "data"))
RECIPE = {"version": 1, "edits": [{"axis": "x", "zone": ["35%", "65%"], "to": "105%"}]}


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)  # the workers, once reaped
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def phases(label: str, r, cpu: float, workers: int, base: float) -> tuple[float, ...]:
    """Start-up, object phase and end of a local run, its CPU busy share and its overhead, beside
    ``base``, the same objects' own times run one after another in this process.

    Wall figures are only as good as the machine is quiet; the CPU figures are not: ``cpu``
    is every CPU second the batch and its workers spent, ``objects_cpu_seconds`` what the
    objects' jobs spent, the rest is what the batch adds (imports, loading kernels, the pool).
    Returns (overhead, overhead against the baseline, start-up, object phase against the
    ideal, end, CPU busy share).
    """
    cores = os.cpu_count() or 1
    rows = read_status(r.outdir / "status.csv")
    work = sum(float(x["seconds"]) for x in rows.values() if x["seconds"])
    info = r.engine_info
    share = min(cores, workers)
    ideal = work / share
    start = r.seconds - info["objects_seconds"] - info["end_seconds"]
    busy = cpu / (r.seconds * cores)
    phase = info["objects_seconds"] / ideal - 1
    print(
        f"{label:<18} wall {r.seconds:5.2f} s = start-up {start:4.2f} + objects "
        f"{info['objects_seconds']:5.2f} + end {info['end_seconds']:4.2f}; CPU busy "
        f"{busy:4.0%} of {cores} cores; object times {work:5.2f} s / {share}"
        f" = {ideal:5.2f} s: overhead {r.seconds - ideal:+5.2f} s (target <= 1 s; against the "
        f"baseline's {base:5.2f} s / {share}: {r.seconds - base / share:+5.2f} s), object "
        f"phase {phase:+4.0%} (target within 10 %); CPU: "
        f"{cpu:5.2f} s, objects {info['objects_cpu_seconds']:5.2f} s, batch's own "
        f"{cpu - info['objects_cpu_seconds']:4.2f} s; load average {os.getloadavg()[0]:.1f}"
    )
    return (r.seconds - ideal, r.seconds - base / share, start, phase, info["end_seconds"], busy)


def in_process(objs: list[Path], res: int, tmp: Path) -> tuple[float, float]:
    """The baseline: each object's job run here, one after another on one thread, its kernels
    loaded first (a warm-up object); the sums of the objects' own wall and CPU seconds."""
    import numba

    from partscale.batch import job

    spec = job.batch_spec({"res": res, "segment": "fast", "export": "glb"})
    task = {"spec": spec, "outdir": str(tmp / "baseline")}
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        job.execute({**task, "name": "warm", "path": str(objs[0])})
        done = [job.execute({**task, "name": p.stem, "path": str(p)}) for p in objs]
    finally:
        numba.set_num_threads(before)
    return sum(d["seconds"] for d in done), sum(d["cpu_seconds"] for d in done)


def small(args) -> None:
    """A dozen small objects, 1 and 2 workers, phases printed beside the baseline (the same
    objects run one after another in this process); repeated ``args.repeat`` times, and the
    range of each figure over the repeats printed at the end."""
    objs = sorted((DATA / "kenney").glob("*.glb"), key=lambda p: p.stat().st_size)[:12]
    seen: dict[int, list[tuple[float, ...]]] = {w: [] for w in args.workers}
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        print(f"{len(objs)} small Kenney objects at --res {args.res}, fast segment, GLB export")
        for rep in range(args.repeat):
            base, base_cpu = in_process(objs, args.res, tmp / f"base-{rep}")
            print(
                f"baseline, in this process, one thread: object times {base:5.2f} s, "
                f"{base_cpu:5.2f} CPU seconds; load average {os.getloadavg()[0]:.1f}"
            )
            for workers in args.workers:
                out = tmp / f"w{workers}-{rep}"
                cpu = _cpu()
                r = run(objs, out, res=args.res, segment="fast", export="glb", workers=workers)
                label = f"local, {workers} worker{'s' * (workers > 1)}"
                seen[workers].append(phases(label, r, _cpu() - cpu, workers, base))
    for workers, figures in seen.items():
        cols = list(zip(*figures, strict=True))
        names = ("overhead s", "vs baseline s", "start-up s", "object phase", "end s", "CPU busy")
        text = ", ".join(
            f"{n} {min(c):+.2f}..{max(c):+.2f}"
            if n != "object phase" and n != "CPU busy"
            else f"{n} {min(c):+.0%}..{max(c):+.0%}"
            for n, c in zip(names, cols, strict=True)
        )
        print(f"{workers} worker(s) over {len(figures)} runs: {text}")


def one(label, manifest, outdir, recipe, res, **kw):
    r = run(
        [manifest],
        outdir,
        res=res,
        segment="fast",
        recipe=recipe,
        export="glb",
        render="iso",
        memory="3GiB",
        **kw,
    )
    if r.interrupted:
        sys.exit(130)
    rows = read_status(outdir / "status.csv")
    peaks = [float(x["peak_memory_mib"]) for x in rows.values() if x["peak_memory_mib"]]
    secs = [float(x["seconds"]) for x in rows.values() if x["seconds"]]
    n = len(r.done) + len(r.failed)
    print(
        f"{label:<22} {r.seconds:7.1f} s wall  {60 * n / r.seconds:6.1f} objects/min  "
        f"sum of object times {sum(secs):6.1f} s  done {len(r.done)} failed {len(r.failed)}  "
        f"peak per worker: median {statistics.median(peaks):.0f} MiB, max {max(peaks):.0f} MiB"
        + (f"  ray start-up {r.engine_info['startup_seconds']:.1f} s" if r.engine_info else "")
    )
    for name, err in r.failed:
        print(f"    failed: {name}: {err}")
    return r


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--no-ray", action="store_true")
    ap.add_argument("--small", action="store_true", help="a dozen small objects, phases")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    if args.small:
        small(args)
        return
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        recipe = tmp / "recipe.json"
        recipe.write_text(json.dumps(RECIPE))
        corrupt = tmp / "inputs" / "corrupt.glb"
        corrupt.parent.mkdir()
        corrupt.write_bytes(b"glTF" + bytes(range(256)) * 8)
        items = discover([DATA])
        rows: list[dict[str, str | int]] = [{"path": str(it.path), "name": it.name} for it in items]
        rows.append({"path": str(corrupt)})
        # 2048 voxels a side: far beyond the 3 GiB each worker may use
        rows.append({"path": str(DATA / "kenney" / "chair.glb"), "name": "too_large", "res": 2048})
        manifest = tmp / "all.jsonl"
        manifest.write_text("".join(json.dumps(r) + "\n" for r in rows))
        print(
            f"{len(rows)} inputs ({len(items)} objects of {DATA}, 2 that must fail), --res {args.res}"
        )
        r1 = one("local, 1 worker", manifest, tmp / "w1", recipe, args.res, workers=1)
        r2 = one("local, 2 workers", manifest, tmp / "w2", recipe, args.res, workers=2)
        print(f"speed-up 2 workers / 1 worker: {r1.seconds / r2.seconds:.2f}x (target >= 1.7x)")
        # One worker already runs numba's parallel stages on both cores, so the ratio above is
        # bounded by how serial one object is, not by the pool. What the pool itself gives: the
        # 2-worker run's objects each ran on one thread; their summed time is a 1-thread worker's
        # wall time, kept busy on two cores at once.
        one_thread = sum(
            float(x["seconds"])
            for x in read_status(tmp / "w2" / "status.csv").values()
            if x["seconds"]
        )
        print(
            f"2 workers / a 1-thread worker (sum of the 2-worker run's 1-thread object times, "
            f"{one_thread:.1f} s): {one_thread / r2.seconds:.2f}x of 2 cores"
        )
        if not args.no_ray:
            try:
                import ray  # noqa: F401
            except ImportError:
                print("ray not installed: pip install 'partscale[ray]'")
                return
            rr = one(
                "ray, 2 CPUs (local)",
                manifest,
                tmp / "ray",
                recipe,
                args.res,
                engine="ray",
                workers=2,
            )
            start = rr.engine_info["startup_seconds"]
            per = (rr.seconds - start - r2.seconds) / len(rows)
            print(
                f"ray overhead beside local 2 workers: start-up {start:.1f} s, {per * 1000:+.0f} ms per object"
            )


if __name__ == "__main__":
    main()
