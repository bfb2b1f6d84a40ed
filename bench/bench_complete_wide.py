"""Wide virtual-scan benchmark of partscale.complete: every object, many views, the raw scan beside.

Every complete object of ../shared/data (furniture of all kinds, not only chairs) is scaled to
its real size, scanned virtually from several views (yaw all round, pitch 0 to 45 degrees, near
and far, with and without a floor, the sensor's noise and holes of
:func:`partscale.evaluate.virtual_scan`), completed at 128 voxels, and scored against
its own import's exterior (F-score at 1 % of the diagonal; ``--truth mesh``: the mesh's whole
surface, a closed cabinet's inside included, which no view reaches). The raw scan's own import (its points, as
``bench_complete.py`` scores it) is the baseline in the same run. Printed: one line a scan,
per-class and overall medians of F@1 %, and the share of scans where the completion beats the
raw scan (by 0.05 or more), matches it, loses to it (by more than 0.01), or fails (no object
found in the scan, or no completion: counted in the shares, not in the medians); the objects the
method was tuned on (``bench_complete.py``'s list) are marked ``*`` and the headline is over the
others.

    .venv/bin/python bench/bench_complete_wide.py --quick      # 6 objects, one view each
    .venv/bin/python bench/bench_complete_wide.py --views 1    # every object, one view each
    .venv/bin/python bench/bench_complete_wide.py              # every object, 6 single views + 2 triples
    .venv/bin/python bench/bench_complete_wide.py --views 1 --triples 0 --world-yaw 30 --upright

The scan's world is the object's own frame (its walls along the axes) unless ``--world-yaw``
turns it, as a real camera's frame is; the completion, written in that world's frame by default,
is then voxelized askew to the object (``--upright``: in its own upright frame).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from partscale import ingest
from partscale.complete import api, complete
from partscale.errors import InputError, PartscaleWarning
from partscale.evaluate import completion, virtual

DATA = Path(
    os.environ.get("PARTSCALE_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)
TUNED = {
    "kenney/chair.glb",
    "kenney/chairCushion.glb",
    "kenney/chairDesk.glb",
    "kenney/chairModernFrameCushion.glb",
    "khronos/SheenChair.glb",
    "sweethome3d/chair.obj",
    "sweethome3d/stool.obj",
    "polyhaven/painted_wooden_stool/painted_wooden_stool_1k.gltf",
    "kenney/table.glb",
    "kenney/tableCross.glb",
    "kenney/loungeSofa.glb",
    "kenney/loungeDesignSofa.glb",
}
"""The objects the completion was built and tuned with (bench_complete.py's list)."""
KENNEY_SCALE = 0.7
"""Metres per Kenney unit: the kit is drawn large (its chair 1.36 units tall, its table 0.95);
0.7 makes the chair 0.95 m and the table 0.66 m."""
SCALE = {
    # Sweet Home 3D files stored in other units: the catalogue height (cm) / the file's height
    "sweethome3d/chair.obj": 0.90 / 9.025,
    "sweethome3d/bedsideTable.obj": 0.50 / 5.02,
    "sweethome3d/squareTable.obj": 0.74 / 1.30,
}
"""Metres per unit of the files not in metres (the rest of Sweet Home 3D, Poly Haven and Khronos
are)."""
CLASSES = [
    ("bedside", "cabinet"),
    ("cabinet", "cabinet"),
    ("stool", "stool"),
    ("chair", "chair"),
    ("bench", "sofa"),
    ("sofa", "sofa"),
    ("bed", "bed"),
    ("table", "table"),
    ("desk", "table"),
    ("book", "shelf"),
    ("shel", "shelf"),
    ("drawer", "cabinet"),
    ("dresser", "cabinet"),
    ("tvunit", "cabinet"),
    ("radiator", "cabinet"),
    ("stair", "stairs"),
    ("railing", "stairs"),
]
"""(word in the file's name, class): the first that matches; otherwise "other"."""
QUICK = [
    "kenney/chair.glb",
    "kenney/bookcaseOpenLow.glb",
    "kenney/trashcan.glb",
    "sweethome3d/chair2.obj",
    "sweethome3d/table.obj",
    "polyhaven/wooden_table_02/wooden_table_02_1k.gltf",
]
"""--quick: a tuned chair and five objects of other classes the method was not tuned on."""
PITCHES = (0.0, 15.0, 30.0, 45.0)
BEATS, LOSES = 0.05, 0.01


def objects() -> list[str]:
    """Paths (under DATA) of every complete object: meshes, not the scans."""
    out = []
    for pat in ("kenney/*.glb", "khronos/*.glb", "polyhaven/*/*.gltf", "sweethome3d/*.obj"):
        out += sorted(str(p.relative_to(DATA)) for p in DATA.glob(pat))
    return out


def class_of(rel: str) -> str:
    name = Path(rel).stem.lower()
    return next((c for w, c in CLASSES if w in name), "other")


def scale_of(rel: str) -> float:
    if rel in SCALE:
        return SCALE[rel]
    return KENNEY_SCALE if rel.startswith("kenney/") else 1.0


def views_of(i: int, n_single: int, n_triple: int) -> list[dict]:
    """The scans of object ``i``: yaw all round (offset per object), pitch cycling 0-45 degrees,
    near and far, a floor in two of three."""
    out = []
    for k in range(n_single):
        yaw = (k * 360.0 / max(n_single, 1) + 23.0 * i) % 360.0
        out.append(
            dict(
                azimuths=(yaw,),
                elevation=PITCHES[(i + k) % len(PITCHES)],
                distance=(1.0, 1.5)[k % 2],
                floor=(i + k) % 3 != 2,
            )
        )
    for k in range(n_triple):
        yaw = (60.0 * k + 37.0 * i) % 360.0
        out.append(
            dict(
                azimuths=(yaw, yaw + 120.0, yaw + 240.0),
                elevation=PITCHES[(i + k + 1) % len(PITCHES)],
                distance=1.0,
                floor=True,
            )
        )
    return out


def turned(deg: float) -> np.ndarray:
    """(4, 4) float64: a turn by ``deg`` degrees about y (up)."""
    a = np.radians(deg)
    R = np.eye(4)
    R[:3, :3] = [[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]]
    return R


def in_object_frame(c, P: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Surface samples ``P`` (N, 3) of a completion ``c`` (grid frame) in the object's frame:
    through the grid's frame in the scan's world (``to_input_frame``) and the world's turn ``R``
    undone."""
    T = np.asarray(c.meta["completion"]["to_input_frame"], np.float64)
    return (P @ T[:3, :3].T + T[:3, 3]) @ R[:3, :3]


def run_one(
    rel: str, i: int, n_single: int, n_triple: int, res: int, world_yaw: float = 0.0,
    upright: bool = False, truth: str = "exterior",
) -> list[dict]:  # fmt: skip
    mesh = ingest.load_mesh(DATA / rel)
    s = scale_of(rel)
    if s != 1.0:
        mesh = dataclasses.replace(mesh, vertices=np.asarray(mesh.vertices) * s)
    gt = ingest.from_mesh(mesh, res=128)
    if truth == "exterior":
        gt = completion.exterior(gt)  # a closed carcass's inside is no surface a view reaches
    tau = completion.f_tau(gt)
    G, _ = completion.surface_samples(gt, tau=tau)
    rows = []
    for v in views_of(i, n_single, n_triple):
        row = dict(rel=rel, cls=class_of(rel), tuned=rel in TUNED, n=len(v["azimuths"]), **v)
        try:
            frames = virtual.virtual_scan(mesh, **v)
        except ValueError as exc:  # the virtual sensor: out of its range
            print(f"  {Path(rel).stem:30s} not scanned: {exc}", flush=True)
            continue
        # the scan's world: the object's own frame, or turned about up (a camera's frame)
        R = turned(world_yaw)
        frames = [dataclasses.replace(f, pose=R @ f.pose) for f in frames]
        try:
            ob = api.observe(frames)
        except InputError as exc:  # no object found: neither import nor completion has one
            print(f"  {Path(rel).stem:30s} no object found in the scan: {exc}", flush=True)
            rows.append({**row, "raw": np.nan, "full": np.nan, "kept": "failed", "struts": 0})
            continue
        row["raw"] = completion.chamfer_fscore(ob.points @ R[:3, :3], G, tau)["fscore"]
        t = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", PartscaleWarning)
                c = complete(frames, res=res, upright=upright)
        except InputError as exc:
            print(f"  {Path(rel).stem:30s} completion failed: {exc}", flush=True)
            row.update(full=np.nan, kept="failed", seconds=time.perf_counter() - t, struts=0)
            rows.append(row)
            continue
        row["seconds"] = time.perf_counter() - t
        P, _ = completion.surface_samples(c, tau=tau)
        row["full"] = completion.chamfer_fscore(in_object_frame(c, P, R), G, tau)["fscore"]
        m = c.meta["completion"]
        row["kept"], row["struts"] = m["guard"]["kept"], len(m["struts"])
        rows.append(row)
        mark = "*" if row["tuned"] else " "
        print(
            f"{mark} {Path(rel).stem:30s} {row['cls']:8s} {row['n']}v yaw {v['azimuths'][0]:5.0f} "
            f"pitch {v['elevation']:4.0f} dist {v['distance']:.1f} floor {int(v['floor'])} | F@1% "
            f"raw {row['raw']:.3f} full {row['full']:.3f} ({row['kept']}, {row['struts']} struts)"
            f" | {row['seconds']:.1f} s",
            flush=True,
        )
    return rows


def verdict(r: dict) -> str:
    if not (np.isfinite(r["full"]) and np.isfinite(r["raw"])):
        return "fails"
    d = r["full"] - r["raw"]
    return "beats" if d >= BEATS else "loses" if d < -LOSES else "matches"


def summary(all_rows: list[dict], title: str) -> None:
    """One line: medians over the scans that completed; the shares over all, failures too."""
    if not all_rows:
        return
    rows = [r for r in all_rows if verdict(r) != "fails"]
    med = lambda xs: float(np.median(xs)) if xs else float("nan")  # noqa: E731
    v = [verdict(r) for r in all_rows]
    share = {k: v.count(k) / len(v) for k in ("beats", "matches", "loses", "fails")}
    times = [r["seconds"] for r in all_rows if "seconds" in r]
    print(
        f"{title:34s} {len(all_rows):4d} scans | median F@1% raw "
        f"{med([r['raw'] for r in rows]):.3f} full {med([r['full'] for r in rows]):.3f} | "
        f"beats {share['beats']:4.0%} matches {share['matches']:4.0%} loses "
        f"{share['loses']:4.0%} fails {share['fails']:4.0%} | time median {med(times):.1f} s "
        f"max {max(times, default=float('nan')):.1f} s"
    )


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="six objects, one view each")
    ap.add_argument("--views", type=int, default=6, help="single views per object")
    ap.add_argument("--triples", type=int, default=2, help="three-view scans per object")
    ap.add_argument("--only", default=None, help="only objects whose path contains this")
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument(
        "--world-yaw",
        type=float,
        default=0.0,
        help="turn the scan's world this many degrees about up: a camera's frame, not the "
        "object's own (its axes then lie askew to the object's walls)",
    )
    ap.add_argument("--upright", action="store_true", help="complete with upright=True")
    ap.add_argument(
        "--truth",
        choices=("exterior", "mesh"),
        default="exterior",
        help="score against the object's exterior (sealed cavities, such as a closed "
        "cabinet's inside, filled: what a sensor can see from any view) or against the "
        "mesh's whole surface",
    )
    args = ap.parse_args()
    print(f"truth: the object's {args.truth} surface")
    objs = QUICK if args.quick else objects()
    n_single, n_triple = (1, 0) if args.quick else (args.views, args.triples)
    if args.only:
        objs = [o for o in objs if args.only in o]
    rows: list[dict] = []
    for i, rel in enumerate(objs):
        if not (DATA / rel).exists():
            print(f"skip {rel}: missing")
            continue
        rows += run_one(
            rel, i, n_single, n_triple, args.res, args.world_yaw, args.upright, args.truth
        )
    for n in (1, 3):
        rn = [r for r in rows if r["n"] == n]
        if not rn:
            continue
        print(f"--- {n} view(s) ---")
        for cls in sorted({r["cls"] for r in rn}):
            summary([r for r in rn if r["cls"] == cls], f"  class {cls}")
        summary([r for r in rn if r["tuned"]], "  tuned objects (*)")
        summary([r for r in rn if not r["tuned"]], "  HEADLINE: objects not tuned on")
        summary(rn, "  all objects")
        kept = [r["kept"] for r in rn]
        print(
            f"  guard kept the observed scan on {kept.count('observed')}/{len(kept)}, "
            f"no object found or completion failed on {kept.count('failed')} (in the shares as "
            "fails, not in the medians)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
