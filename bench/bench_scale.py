"""Edit timings at 128 and 256 voxels, side by side: stretch and tile with re-evaluation, beside
two baselines, and how each grows from one resolution to the next.

- ours: :func:`partscale.edit.apply_edit` (resampling, seams, re-evaluation of the band, parts);
- (a) naive: per-column linear resampling of the slab without re-evaluation, a Python loop over
  the columns with ``np.interp`` per column for distance and colour (what the authors' public
  prototype does), checked against :func:`partscale.edit.naive_edit` in the same run;
- (b) a full-grid Euclidean distance transform (``edt``, inside and outside) of the edited grid:
  what recomputing every distance from the voxelised solid would cost (and it is only exact to
  the voxel, not to the sub-voxel surface).

Peak memory is ``tracemalloc``'s peak (numpy buffers are traced) during one edit, against the
size of the output grid (sdf + rgb + parts, 9 bytes a voxel).

The machine's load average is printed with the figures: on a shared machine absolute times
swing, ratios measured in the same run (ours / naive_edit, 256 / 128) hold better.

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_scale.py [--repeat 10] [--res 128 256]
[--no-loop]``
"""

from __future__ import annotations

import argparse
import os
import tracemalloc
from pathlib import Path

import edt
import numpy as np
from _timing import timed, timed_cpu

from partscale import reuse_freed_memory, shapes
from partscale.edit import Edit, apply_edit, naive_edit, resolve_edit, tile_count

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def cube(c, res: int):
    """Pad a CSDF to ``res`` voxels on every axis (the paper's cubic grid) with its border values.

    The padding is far outside the band (the import leaves >= 5 empty voxels around the object),
    so no edit reads it as surface; it only makes the grid, and the baselines' work, 128^3.
    """
    pad = [(0, 0)] * 3
    for a in range(3):
        extra = max(res - c.shape[a], 0)
        pad[a] = (extra // 2, extra - extra // 2)
    origin = c.origin - np.array([p[0] for p in pad]) * c.voxel_size
    return c.replace(
        sdf=np.pad(c.sdf, pad, mode="edge"),
        rgb=np.pad(c.rgb, [*pad, (0, 0)], mode="edge"),
        parts=np.pad(c.parts, pad, mode="edge"),
        origin=origin,
    )


def load_object(res: int):
    """bookcaseOpen imported at ``res`` (or an analytic stand-in when import or data is absent)."""
    path = DATA / "kenney" / "bookcaseOpen.glb"
    try:
        from partscale import ingest

        if path.exists():
            c = ingest.load(path, res=res)
            return cube(c, res), f"kenney/bookcaseOpen.glb at res {res}, padded to {res}^3"
    except ImportError:
        pass
    h = 2.55 / res
    Box = tuple[tuple[float, float, float], tuple[float, float, float]]
    boxes: list[Box] = [((0, 0, 0), (0.05, 2.55, 0.7)), ((1.1, 0, 0), (1.15, 2.55, 0.7))]
    boxes += [((0.05, y, 0), (1.1, y + 0.087, 0.7)) for y in (0.29, 0.986, 1.682, 2.378)]
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes), ((0, 0, 0), (1.15, 2.55, 0.7)), voxel_size=h
    )
    return cube(c, res), f"analytic bookcase stand-in at res {res} (import stage absent)"


def naive_loop(csdf, edit):
    """Baseline (a): per-column np.interp of sdf and rgb, Python loop over the columns."""
    r = resolve_edit(csdf, type(edit).parse(edit.to_json()) if hasattr(edit, "to_json") else edit)
    ax = r.axis
    h = csdf.voxel_size
    o = float(csdf.origin[ax])
    n_out = csdf.shape[ax] + r.shift_voxels(h)
    y = o + np.arange(n_out) * h
    s, e, d = r.start, r.end, r.dest
    shift = d - e
    if edit.mode == "tile":
        n = tile_count(e - s, d - s)
        u = (y - s) / ((d - s) / n)
        x = np.where(
            y < s, y, np.where(y > d, y - shift, s + (u - np.minimum(np.floor(u), n - 1)) * (e - s))
        )
    else:
        x = np.where(y < s, y, np.where(y > d, y - shift, s + (y - s) * (e - s) / (d - s)))
    xs = o + np.arange(csdf.shape[ax]) * h
    src_sdf = np.moveaxis(csdf.sdf, ax, -1)
    src_rgb = np.moveaxis(csdf.rgb, ax, -2)
    A, B = src_sdf.shape[:2]
    out_sdf = np.empty((A, B, n_out), np.float32)
    out_rgb = np.empty((A, B, n_out, 3), np.uint8)
    for a in range(A):
        for b in range(B):
            out_sdf[a, b] = np.interp(x, xs, src_sdf[a, b])
            for c in range(3):
                out_rgb[a, b, :, c] = np.rint(np.interp(x, xs, src_rgb[a, b, :, c]))
    return np.moveaxis(out_sdf, -1, ax), np.moveaxis(out_rgb, -2, ax)


def full_edt(csdf):
    """Baseline (b): signed distance of the whole grid from its voxelised solid (two EDTs)."""
    inside = csdf.sdf <= 0
    h = csdf.voxel_size
    out = edt.edt(~inside, anisotropy=(h, h, h), parallel=2)
    ins = edt.edt(inside, anisotropy=(h, h, h), parallel=2)
    return np.where(inside, -ins, out).astype(np.float32)


def cases_at(res: int):
    """The edit cases at one resolution: bookcase stretch and tile, table stretched +40%."""
    c, what = load_object(res)
    lo, hi = c.surface_bounds()[:, 1]
    period = 0.696 * (hi - lo) / 2.552  # one shelf period of bookcaseOpen
    s = lo + 0.33 / 2.552 * (hi - lo)
    cases = [
        ("stretch", c, {"axis": "y", "zone": [s, s + period], "to": s + 1.6 * period}),
        ("tile", c, {"axis": "y", "zone": [s, s + period], "to": s + 3 * period, "mode": "tile"}),
    ]
    print(f"res {res}: {what}, grid {' x '.join(map(str, c.shape))}")
    table = DATA / "kenney" / "table.glb"
    try:
        from partscale import ingest

        if table.exists():
            t = cube(ingest.load(table, res=res), res)
            tlo, thi = t.surface_bounds()[:, 0]
            edit = {"axis": "x", "zone": [-0.6, 0.6], "to": 0.6 + 0.4 * (thi - tlo)}
            cases.append(("table+40%", t, edit))
            print(f"res {res}: table+40%: kenney/table.glb, padded, stretched between legs")
    except ImportError:
        pass
    return cases


def measure(c, e, repeat: int, *, loop: bool) -> dict:
    """Timings (seconds) and peak memory of one edit case."""
    edit = Edit.parse(e)
    apply_edit(c, edit)  # warm (numba cache load)
    t_ours, t_cpu = timed_cpu(lambda: apply_edit(c, edit), repeat)
    out = apply_edit(c, edit)
    vec = naive_edit(c, edit)
    t_loop = float("nan")
    if loop:
        t_loop, _ = timed(lambda: naive_loop(c, edit), max(1, min(repeat, 3)))
        loop_sdf, _ = naive_loop(c, edit)
        agree = np.abs(loop_sdf - vec.sdf).max()
        assert agree < 1e-4 * c.voxel_size, agree  # the loop is the same baseline
    t_vec, _ = timed(lambda: naive_edit(c, edit), repeat)
    t_edt, _ = timed(lambda: full_edt(out), repeat)
    tracemalloc.start()
    apply_edit(c, edit)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {
        "ours": t_ours,
        "cpu": t_cpu,
        "reeval": out.meta["history"][-1]["reevaluated_voxels"],
        "loop": t_loop,
        "vec": t_vec,
        "edt": t_edt,
        "peak": peak,
        "grid": int(np.prod(out.shape)) * 9,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument(
        "--res", type=int, nargs="+", default=[128, 256], help="resolutions, side by side"
    )
    ap.add_argument("--no-loop", action="store_true", help="skip baseline (a), the slow loop")
    args = ap.parse_args()
    # as the CLI does (partscale.cli.main): freed grids' pages are reused, not faulted in anew
    print(f"freed memory reused (glibc): {'yes' if reuse_freed_memory() else 'no'}")
    rows: dict[tuple[str, int], dict] = {}
    for res in args.res:
        for name, c, e in cases_at(res):
            rows[name, res] = measure(c, e, args.repeat, loop=not args.no_loop)
    load = os.getloadavg()
    print(
        f"median of {args.repeat} ((a) of 3); load average {load[0]:.1f} {load[1]:.1f} "
        f"{load[2]:.1f} on {os.cpu_count()} cores: compare ratios measured in one run"
    )
    print(
        f"{'edit':9} {'res':>4} {'ours ms':>9} {'ours cpu ms':>12} {'reeval vox':>11} "
        f"{'(a) naive loop ms':>18} {'naive_edit ms':>14} {'ours/naive':>11} "
        f"{'(b) full EDT ms':>16} {'peak MiB':>9} {'peak/grid':>10}"
    )
    for (name, res), m in rows.items():
        print(
            f"{name:9} {res:4d} {m['ours'] * 1e3:9.1f} {m['cpu'] * 1e3:12.1f} {m['reeval']:11d} "
            f"{m['loop'] * 1e3:18.1f} {m['vec'] * 1e3:14.1f} {m['ours'] / m['vec']:11.2f} "
            f"{m['edt'] * 1e3:16.1f} {m['peak'] / 2**20:9.1f} {m['peak'] / m['grid']:10.2f}"
        )
    if len(args.res) > 1:
        r0 = args.res[0]
        print(f"growth from res {r0} (voxels x{(args.res[-1] / r0) ** 3:.0f} per step to the last)")
        print(
            f"{'edit':9} {'res':>4} {'ours':>7} {'naive_edit':>11} {'full EDT':>9} {'reeval vox':>11}"
        )
        for (name, res), m in rows.items():
            if res == r0 or (name, r0) not in rows:
                continue
            b = rows[name, r0]
            print(
                f"{name:9} {res:4d} {m['ours'] / b['ours']:7.2f} {m['vec'] / b['vec']:11.2f} "
                f"{m['edt'] / b['edt']:9.2f} {m['reeval'] / max(b['reeval'], 1):11.2f}"
            )


if __name__ == "__main__":
    main()
