"""Virtual-scan benchmark of partscale.complete (issue 17).

Each complete object of ../shared/data is scanned virtually (trimesh ray casting, Kinect-like
noise and holes, a floor) from one and from three viewpoints, completed, and scored against its
own import at the same resolution: CD-L1 (x 10^3 of the bounding-box diagonal) and F-score at
tau = 1 % of the diagonal, for the raw scan (its points), a plain mirror baseline (the points
and their image in the best vertical plane by voting, no free-space test) and the full method,
in one run; the colour error on Kenney objects (flat material colours); and the time of a
completion beside a plain ``import`` of the same partial scan (its points as a range mesh).

    .venv/bin/python bench/bench_complete.py [--quick] [--only SUBSTRING]

Objects are scanned and scored at their real size (the virtual sensor is metric; a file in
other units is scaled by its row's metres per unit).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

from partscale import ingest
from partscale.complete import api, symmetry
from partscale.errors import InputError
from partscale.evaluate import completion, virtual

DATA = Path(
    os.environ.get("PARTSCALE_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)
OBJECTS = [
    ("kenney/chair.glb", "chair", 1.0),
    ("kenney/chairCushion.glb", "chair", 1.0),
    ("kenney/chairDesk.glb", "chair", 1.0),
    ("kenney/chairModernFrameCushion.glb", "chair", 1.0),
    ("khronos/SheenChair.glb", "chair", 1.0),
    # stored in decimetres: 9 units tall, 90 cm in the Sweet Home 3D catalogue (its README)
    ("sweethome3d/chair.obj", "chair", 0.1),
    ("sweethome3d/stool.obj", "stool", 1.0),
    ("polyhaven/painted_wooden_stool/painted_wooden_stool_1k.gltf", "stool", 1.0),
    ("kenney/table.glb", "table", 1.0),
    ("kenney/tableCross.glb", "table", 1.0),
    ("kenney/loungeSofa.glb", "sofa", 1.0),
    ("kenney/loungeDesignSofa.glb", "sofa", 1.0),
]
"""(path under ../shared/data, category, metres per unit of the file): the virtual sensor and
the completion are metric, so every object is scanned and scored at its real size."""


def mirror_baseline(ob) -> np.ndarray:
    """Observed points plus their image in the strongest vertical plane (no free-space test)."""
    U, Uinv = ob.U, np.linalg.inv(ob.U)
    Qu = trimesh.transform_points(ob.points, U)
    ext = Qu.max(axis=0) - Qu.min(axis=0)
    cell = 1.5 * float(ext.max()) / 128
    planes = symmetry.mirror_planes(
        Qu, ob.colors, lambda p: np.zeros(len(p), bool), cell, max_planes=1
    )
    if not planes:
        return ob.points
    return np.concatenate([ob.points, trimesh.transform_points(planes[0].apply(Qu), Uinv)])


def import_time(points: np.ndarray) -> float:
    """Seconds of a plain import of the partial scan as a range mesh (its points, ball-pivot-free:
    each point a tiny triangle, the cheapest mesh that holds them)."""
    import trimesh

    from partscale.ingest import from_trimesh

    e = 0.002
    dx, dy = np.array([e, 0, 0]), np.array([0, e, 0])
    tri = np.stack([points, points + dx, points + dy], axis=1)
    mesh = trimesh.Trimesh(
        tri.reshape(-1, 3), np.arange(3 * len(points)).reshape(-1, 3), process=False
    )
    t = time.perf_counter()
    ingest.from_mesh(from_trimesh(mesh), res=128)
    return time.perf_counter() - t


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="three objects only")
    ap.add_argument("--skip", type=int, default=0, help="leave out the first SKIP objects")
    ap.add_argument("--only", default=None, help="only objects whose path contains this")
    args = ap.parse_args()
    objs = OBJECTS[:3] if args.quick else OBJECTS[args.skip :]
    if args.only:
        objs = [o for o in objs if args.only in o[0]]
    rows = []
    for rel, cat, unit in objs:
        path = DATA / rel
        if not path.exists():
            print(f"skip {rel}: missing")
            continue
        mesh = ingest.load_mesh(path)
        if unit != 1.0:  # the truth and the scan both at the real size
            mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * unit)
        gt = completion.exterior(ingest.from_mesh(mesh, res=128))  # what a view can reach
        tau = completion.f_tau(gt)
        G, Gc = completion.surface_samples(gt, tau=tau)
        diag = tau / completion.F_TAU
        for views in (1, 3):
            frames = virtual.virtual_scan(mesh, views)
            try:
                ob = api.observe(frames)
            except InputError as exc:  # reported, and the run goes on with the next object
                print(f"{Path(rel).stem:28s} {views}v  failed: {exc}", flush=True)
                continue
            raw = completion.chamfer_fscore(ob.points, G, tau)
            mir = completion.chamfer_fscore(mirror_baseline(ob), G, tau)
            t = time.perf_counter()
            c = api.complete(frames, res=128)
            t_c = time.perf_counter() - t
            P, Pc = completion.surface_samples(c, tau=tau)
            full = completion.chamfer_fscore(P, G, tau)
            col = (
                completion.colour_error(P, Pc, G, Gc, tau)
                if rel.startswith("kenney/")
                else float("nan")
            )
            t_i = import_time(ob.points)
            rows.append((rel, cat, views, raw, mir, full, col, t_c, t_i))
            print(
                f"{Path(rel).stem:28s} {views}v  F@1% raw {raw['fscore']:.3f} mirror {mir['fscore']:.3f} "
                f"full {full['fscore']:.3f} | CD-L1x1e3/diag raw {1e3 * raw['cd_l1'] / diag:.1f} "
                f"mirror {1e3 * mir['cd_l1'] / diag:.1f} full {1e3 * full['cd_l1'] / diag:.1f} | "
                f"colour {col:.1f}/255 | complete {t_c:.2f} s, import {t_i:.2f} s",
                flush=True,
            )
    for views in (1, 3):
        r = [x for x in rows if x[2] == views]
        if not r:
            continue
        chairs = [x for x in r if x[1] == "chair"]
        med = lambda xs: float(np.median(xs)) if xs else float("nan")  # noqa: E731
        print(
            f"{views} view(s): median F@1% raw {med([x[3]['fscore'] for x in r]):.3f} mirror "
            f"{med([x[4]['fscore'] for x in r]):.3f} full {med([x[5]['fscore'] for x in r]):.3f}; "
            f"chairs full {med([x[5]['fscore'] for x in chairs]):.3f}; full >= raw on "
            f"{sum(x[5]['fscore'] >= x[3]['fscore'] for x in r)}/{len(r)}; time median "
            f"{med([x[7] for x in r]):.2f} s (import {med([x[8] for x in r]):.2f} s)"
        )
    cols = [x[6] for x in rows if np.isfinite(x[6])]
    if cols:
        print(
            f"colour error on flat-colour objects: mean {np.mean(cols):.1f}/255, max {np.max(cols):.1f}/255"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
