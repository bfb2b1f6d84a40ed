"""Render and export timings on 128^3 grids, each beside a baseline run in the same process.

- render: the numba sphere tracer (512 x 512, every view) against a plain numpy tracer that marches
  all still-active rays at once with scipy's trilinear ``map_coordinates`` (the obvious vectorised
  implementation), on the same grid, same camera, same hit threshold.
- export: our GLB writer (linear COLOR_0, SDF normals) against trimesh's own GLB export of the
  same marching-cubes mesh (which writes sRGB bytes as COLOR_0); the textures; resampling.

Objects: an analytic sphere and a row of bars at 128 voxels along the longest side, plus real
objects from ../shared/data when the import stage is available.

Run: ``PYTHONPATH=src .venv/bin/python bench/render_export.py [--repeat 3]``
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from functools import partial
from pathlib import Path

import numpy as np
from _timing import timed
from scipy import ndimage

from partscale import export, render, shapes
from partscale.surface import to_mesh

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
REAL = ["kenney/chair.glb", "kenney/table.glb", "khronos/SheenChair.glb"]


def numpy_trace(csdf, view: str, size: int) -> np.ndarray:
    """Baseline: (size*size,) bool hit mask from a numpy sphere tracer of all rays at once."""
    cam = render.camera(view, csdf.surface_bounds(), size)
    h = csdf.voxel_size
    sdf = csdf.sdf.astype(np.float64) / h
    o = (cam.pixel_rays() - csdf.origin) / h
    d = -cam.back
    hi = np.asarray(csdf.shape, float) - 1
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (0 - o) / d, (hi - o) / d
    ta = np.where(np.isfinite(ta), ta, -np.inf)
    tb = np.where(np.isfinite(tb), tb, np.inf)
    t0 = np.minimum(ta, tb).max(axis=1)
    t1 = np.maximum(ta, tb).min(axis=1)
    active = np.nonzero(t0 <= t1)[0]
    t = t0.copy()
    hit = np.zeros(len(o), bool)
    for _ in range(render.MAX_STEPS):
        if len(active) == 0:
            break
        p = o[active] + t[active, None] * d
        v = ndimage.map_coordinates(sdf, p.T, order=1, mode="nearest")
        done = v < render.HIT_EPS
        hit[active[done]] = True
        t[active] += np.maximum(v, render.HIT_EPS)
        active = active[~done & (t[active] <= t1[active])]
    return hit


def objects():
    yield "sphere", shapes.sphere((0, 0, 0), 0.5, voxel_size=1.0 / 122)
    c, _ = shapes.bars(6, width=0.08, gap=0.1, height=0.6, depth=0.3, voxel_size=1.0 / 120)
    yield "6 bars", c
    try:
        from partscale.ingest import load as ingest_load
    except ImportError:
        print("(import stage not available: real objects skipped)", file=sys.stderr)
        return
    for rel in REAL:
        if (DATA / rel).exists():
            yield rel, ingest_load(DATA / rel, res=128)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    render.render(shapes.sphere((0, 0, 0), 0.3, voxel_size=0.05), size=32)  # JIT warm-up
    rows: list[tuple[str, str, str, float, str, float | None, float | None]] = []
    tmp = Path(tempfile.mkdtemp())
    for name, c in objects():
        grid = "x".join(map(str, c.shape))
        for view in render.VIEWS:
            t_ours, img = timed(partial(render.render, c, view=view, size=512), args.repeat)
            t_base, hit = timed(partial(numpy_trace, c, view, 512), 1)
            agree = float(((img != 255).any(-1).ravel() == hit).mean())
            rows.append((name, grid, f"render {view} 512²", t_ours, "numpy tracer", t_base, agree))
        t_glb, _ = timed(partial(export.export_mesh, c, tmp / "a.glb"), args.repeat)
        t_tm, _ = timed(partial(lambda c: to_mesh(c).export(tmp / "b.glb"), c), args.repeat)
        rows.append((name, grid, "export .glb", t_glb, "trimesh .glb", t_tm, None))
        for suf in (".raw", ".png", ".nrrd"):
            t, _ = timed(partial(export.export_texture, c, tmp / f"t{suf}"), args.repeat)
            rows.append((name, grid, f"export {suf}", t, "", None, None))
        for size in (64, 256):
            t, _ = timed(partial(export.resize_grid, c, size), args.repeat)
            rows.append((name, grid, f"resample -> {size}", t, "", None, None))
    print(
        f"{'object':<24} {'grid':<12} {'task':<20} {'ours s':>8}  {'baseline':<14} {'s':>8} {'x':>6} {'same px':>8}"
    )
    for name, grid, task, t, base, tb, same in rows:
        b = f"{tb:8.3f} {tb / t:6.1f}" if tb is not None else f"{'':8} {'':6}"
        a = f"{same:8.4f}" if same is not None else ""
        print(f"{name:<24} {grid:<12} {task:<20} {t:8.3f}  {base:<14} {b} {a}")


if __name__ == "__main__":
    main()
