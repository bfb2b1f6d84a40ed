"""Benchmark: what ``partscale info``, ``import`` and every stage that meshes or files a grid
pay besides the edit, at 128 and 256 voxels, each beside a baseline in the same process.

- thin features (:func:`partscale.thickness.thin_features`, one parallel sweep) beside the
  same rule as whole-grid vectorised numpy passes (a float32 run length per axis and side, a
  3x3x3 maximum filter: how it was measured before), with the two results compared;
- the surface mesh (:func:`partscale.surface.to_mesh`: marching cubes, colours, parts,
  orientation) beside skimage's marching cubes alone (its floor), and the relief that
  ``info`` and ``segment`` measure on it;
- writing and reading the ``.csdf.npz`` (:func:`partscale.save`, :func:`partscale.load`)
  beside numpy's ``savez_compressed`` and ``np.load`` of the same arrays, with the file sizes.

Median of ``--repeat`` runs after a warm-up (numba's cached kernels loaded)::

    .venv/bin/python bench/bench_surface.py [--res 128 256] [--repeat 3] [--object PATH]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
from _timing import timed
from scipy import ndimage
from skimage import measure

from partscale import ingest, load, save
from partscale.segment import relief_of
from partscale.surface import to_mesh
from partscale.thickness import THIN_VOXELS, thin_features

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("PARTSCALE_DATA", ROOT.parent / "shared" / "data"))


def thin_vectorised(sdf: np.ndarray, h: float, limit: float = THIN_VOXELS) -> tuple[int, int]:
    """Baseline: (thin solid, thin gap) voxels by the rule of :mod:`partscale.thickness` as
    whole-grid numpy passes."""
    s = np.asarray(sdf, np.float32)
    h32 = np.float32(h)
    counts = []
    for inside in (True, False):
        t = np.full(s.shape, np.inf, np.float32)
        for ax in range(3):
            a = np.moveaxis(s, ax, 0)
            out = np.moveaxis(t, ax, 0)
            side = (a <= 0) if inside else (a > 0)
            aa = np.abs(a) / h32
            n = a.shape[0]
            c, p, q = slice(1, n - 1), slice(0, n - 2), slice(2, n)
            one = side[c] & ~side[p] & ~side[q]
            out[c] = np.where(
                one, np.minimum(out[c], np.maximum(2 - aa[p] - aa[q], 2 * aa[c])), out[c]
            )
            c0, c1, p, q = slice(1, n - 2), slice(2, n - 1), slice(0, n - 3), slice(3, n)
            two = side[c0] & side[c1] & ~side[p] & ~side[q]
            r = np.maximum(3 - aa[p] - aa[q], np.float32(1.0))
            out[c0] = np.where(two, np.minimum(out[c0], r), out[c0])
            out[c1] = np.where(two, np.minimum(out[c1], r), out[c1])
        thin = (t < limit) & (np.abs(s) > np.float32(0.01) * h32) & (s <= 0 if inside else s > 0)
        depth = np.where(s <= 0, -s, 0) if inside else np.where(s > 0, s, 0)
        thin &= ~(ndimage.maximum_filter(depth, size=3, mode="nearest") >= limit / 2 * h32)
        counts.append(int(thin.sum()))
    return counts[0], counts[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, nargs="+", default=[128, 256])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--object", default=str(DATA / "khronos" / "SheenChair.glb"))
    args = ap.parse_args()
    path = Path(args.object)
    if not path.exists():
        print(f"skip: {path} missing")
        return 0
    print(f"{path.name}, median of {args.repeat}; load average {os.getloadavg()[0]:.1f}")
    print(f"{'res':>4} {'stage':14} {'partscale s':>12} {'baseline s':>11}  baseline / notes")
    tmp = Path(tempfile.mkdtemp())
    for res in args.res:
        c = ingest.load(path, res=res)
        h = c.voxel_size
        thin_features(c)
        t, tf = timed(lambda c=c: thin_features(c), args.repeat)
        tb, base = timed(lambda c=c, h=h: thin_vectorised(c.sdf, h), args.repeat)
        same = (tf.solid_voxels, tf.gap_voxels) == base
        print(
            f"{res:>4} {'thin features':14} {t:12.3f} {tb:11.3f}  vectorised passes; same counts: {same}"
        )
        t, m = timed(lambda c=c: to_mesh(c), args.repeat)
        padded = np.pad(c.sdf, 1, mode="constant", constant_values=float(c.sdf.max()))
        tb, _ = timed(lambda p=padded: measure.marching_cubes(p, 0.0), args.repeat)
        print(
            f"{res:>4} {'to_mesh':14} {t:12.3f} {tb:11.3f}  skimage marching cubes alone; {len(m.faces)} faces"
        )
        t, _ = timed(lambda c=c: relief_of(c), args.repeat)
        print(f"{res:>4} {'relief':14} {t:12.3f} {'':>11}  (to_mesh included)")
        ours, theirs = tmp / f"c{res}.csdf.npz", tmp / f"n{res}.npz"
        arrays = {"sdf": c.sdf, "rgb": c.rgb, "parts": c.parts}
        t, _ = timed(lambda c=c, p=ours: save(c, p), args.repeat)
        tb, _ = timed(lambda a=arrays, p=theirs: np.savez_compressed(p, **a), args.repeat)
        size = f"{ours.stat().st_size / 2**20:.1f} MB vs {theirs.stat().st_size / 2**20:.1f} MB"
        print(f"{res:>4} {'save':14} {t:12.3f} {tb:11.3f}  np.savez_compressed; {size}")
        t, _ = timed(lambda p=ours: load(p), args.repeat)
        tb, _ = timed(lambda p=theirs: {k: v for k, v in np.load(p).items()}, args.repeat)
        print(f"{res:>4} {'load':14} {t:12.3f} {tb:11.3f}  np.load of numpy's file (no checks)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
