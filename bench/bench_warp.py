"""Zones beyond planes across an axis, timed beside a planar edit of the same object in the run.

For each object (imported at ``--res``, 128 by default): a radial zone grown by 20 % of the
outline's radius (:func:`partscale.edit.apply_radial`, about its found frame), an oblique zone
stretched along a diagonal (:func:`partscale.edit.apply_oblique`), and, as the baseline, a
stretch across x over the same share of the object (:func:`partscale.edit.apply_edit`); and
for flights, finding their steps (:func:`partscale.zones.find_screws`) and adding one
(:func:`partscale.edit.apply_screw`); for an analytic spiral stair (14 treads turning 30
degrees and rising 0.18, a column, a handrail; 128 voxels tall) and the real objects, finding a
helix (:func:`partscale.zones.find_helices`) beside finding diagonal steps on the same object,
and adding one step along it (:func:`partscale.edit.apply_helix`); for analytic star bases (a
column with 4 and 5 arms, 128 voxels across) and the real objects, finding a ring of elements
about the vertical (:func:`partscale.zones.find_rotations`) and adding one element
(:func:`partscale.edit.apply_rotation`), beside a planar edit of the same object. Targets: a
radial or oblique edit within 2x the planar edit's time; finding steps, a helix or a ring <= 5 s
per object at 128 on 2 cores. Median of ``--repeat``; the radial and oblique rows also print the
voxels each edit re-evaluated and the time per re-evaluated voxel against the planar edit's
(a warp that moves more of the object, like splayed legs in an annulus, re-evaluates more).

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_warp.py [--res 128] [--repeat 3]
[--only round,flights,helix,rotation]``
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

import numpy as np
from _timing import timed

from partscale import shapes
from partscale.csdf import CSDF
from partscale.edit import (
    Edit,
    ObliqueZone,
    apply_edit,
    apply_helix,
    apply_oblique,
    apply_radial,
    apply_rotation,
    apply_screw,
)
from partscale.ingest import load
from partscale.zones import find_helices, find_radial, find_rotations, find_screws

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("PARTSCALE_DATA", ROOT.parent / "shared" / "data"))
ROUND = ["kenney/tableRound.glb", "kenney/lampRoundFloor.glb", "sweethome3d/stool.obj"]
FLIGHTS = ["kenney/stairsOpenSingle.glb", "kenney/stairs.glb", "sweethome3d/staircase.obj"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--only", default="round,flights,helix,rotation", help="sections, comma-separated"
    )
    args = ap.parse_args()
    if not DATA.is_dir():
        raise SystemExit(f"needs the test objects in {DATA} (set PARTSCALE_DATA)")
    sections = {"round": round_rows, "flights": flight_rows, "helix": helix_rows}
    sections["rotation"] = rotation_rows
    for name in args.only.split(","):
        if name not in sections:
            raise SystemExit(f"--only: expected names of {', '.join(sections)}, got {name!r}")
        sections[name](args)


def _reevaluated(c: CSDF) -> int:
    """Voxels the last edit of ``c`` re-evaluated."""
    return int(c.meta["history"][-1].get("reevaluated_voxels", 0))


def _planar(c: CSDF) -> Edit:
    """The baseline: a stretch across x, the solid's 30 %..70 % slab made 60 % of its length."""
    sb = c.surface_bounds()
    lo, hi = float(sb[0, 0]), float(sb[1, 0])
    return Edit("x", lo + 0.3 * (hi - lo), lo + 0.7 * (hi - lo), lo + 0.9 * (hi - lo))


def round_rows(args) -> None:
    """Radial and oblique edits beside a planar one of the same object."""
    print(
        f"{'object':32s} {'planar s':>9s} {'radial s':>9s} {'oblique s':>10s}  ratio  "
        "per voxel  re-evaluated voxels (planar, radial, oblique)"
    )
    for rel in ROUND:
        c = load(DATA / rel, res=args.res)
        frame = find_radial(c)
        t_plane, p_out = timed(lambda c=c: apply_edit(c, _planar(c)), args.repeat)
        t_rad, n_rad = float("nan"), 0
        if frame is not None:
            zone = frame.zone(0.3 * frame.radius, 0.9 * frame.radius, 1.1 * frame.radius)
            t_rad, r_out = timed(lambda c=c, z=zone: apply_radial(c, z), args.repeat)
            n_rad = _reevaluated(r_out)
        n = np.array([1.0, 0.0, 1.0]) / np.sqrt(2)
        pts = c.origin + np.argwhere(c.sdf < 0) * c.voxel_size
        s = pts @ n
        s0, s1 = float(np.quantile(s, 0.3)), float(np.quantile(s, 0.7))
        ob = ObliqueZone((float(n[0]), float(n[1]), float(n[2])), s0, s1, s1 + 0.5 * (s1 - s0))
        t_obl, o_out = timed(lambda c=c, z=ob: apply_oblique(c, z), args.repeat)
        ratio = max(t_rad, t_obl) / t_plane
        n_plane, n_obl = _reevaluated(p_out), _reevaluated(o_out)
        per_voxel = max(t_rad / max(n_rad, 1), t_obl / max(n_obl, 1)) / (t_plane / max(n_plane, 1))
        print(
            f"{rel:32s} {t_plane:9.3f} {t_rad:9.3f} {t_obl:10.3f}  {ratio:.1f}x   "
            f"{per_voxel:7.1f}x  {n_plane}, {n_rad}, {n_obl}"
        )


def flight_rows(args) -> None:
    """Finding a flight's steps and adding one."""
    print(f"\n{'flight':32s} {'find steps s':>12s} {'+1 step s':>10s}  step (going, rise)")
    for rel in FLIGHTS:
        c = load(DATA / rel, res=args.res)
        t_find, found = timed(lambda c=c: find_screws(c), 1)
        if not found:
            print(f"{rel:32s} {t_find:12.2f} {'-':>10s}  none found")
            continue
        s = found[0]
        one_more = s.zone(1)
        t_add, _ = timed(lambda c=c, z=one_more: apply_screw(c, z), args.repeat)
        print(f"{rel:32s} {t_find:12.2f} {t_add:10.3f}  ({s.going:.3f}, {s.rise:.3f})")


def helix_rows(args) -> None:
    """Finding a helix (beside finding steps on the same object) and adding a step."""
    print(f"\n{'helix':32s} {'find helix s':>12s} {'find steps s':>12s} {'+1 step s':>10s}  found")
    objects = [("analytic spiral stair", spiral(args.res))]
    objects += [(rel, load(DATA / rel, res=args.res)) for rel in ROUND + FLIGHTS]
    for name, c in objects:
        t_find, found = timed(lambda c=c: find_helices(c), 1)
        t_steps, _ = timed(lambda c=c: find_screws(c), 1)
        if not found:
            print(f"{name:32s} {t_find:12.2f} {t_steps:12.2f} {'-':>10s}  none")
            continue
        hx = found[0]
        one_more = hx.zone(1)
        t_add, _ = timed(lambda c=c, z=one_more: apply_helix(c, z), args.repeat)
        print(
            f"{name:32s} {t_find:12.2f} {t_steps:12.2f} {t_add:10.3f}  {hx.angle:.2f} deg, "
            f"rise {hx.rise:.4f}, axis ({hx.center[0]:.4f}, {hx.center[1]:.4f})"
        )


def rotation_rows(args) -> None:
    """Finding a ring of elements about the vertical and adding one, beside a planar edit."""
    print(f"\n{'rotation':32s} {'find ring s':>11s} {'+1 elem s':>10s} {'planar s':>9s}  found")
    objects = [(f"analytic star base, {k} arms", star(k, args.res)) for k in (4, 5)]
    objects += [(rel, load(DATA / rel, res=args.res)) for rel in [*ROUND, "kenney/table.glb"]]
    for name, c in objects:
        t_find, found = timed(lambda c=c: find_rotations(c), 1)
        t_plane, _ = timed(lambda c=c: apply_edit(c, _planar(c)), args.repeat)
        if not found:
            print(f"{name:32s} {t_find:11.2f} {'-':>10s} {t_plane:9.3f}  none")
            continue
        rot = found[0]
        one_more = rot.zone(1)
        t_add, _ = timed(lambda c=c, z=one_more: apply_rotation(c, z), args.repeat)
        print(
            f"{name:32s} {t_find:11.2f} {t_add:10.3f} {t_plane:9.3f}  {rot.count} every "
            f"{rot.angle:.2f} deg, {'closed' if rot.closed else 'open'}, axis "
            f"({rot.center[0]:.4f}, {rot.center[1]:.4f})"
        )


def star(k: int, res: int) -> CSDF:
    """A star base about the y axis, ``res`` voxels across: a column of radius 0.05 and 0.5
    tall, with ``k`` arms 0.35 long, 0.05 wide and thick, the first along x."""

    def sdf(p):
        q = np.stack([np.hypot(p[:, 0], p[:, 2]) - 0.05, np.abs(p[:, 1] - 0.25) - 0.25], 1)
        d = np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)
        for m in range(k):
            t = math.radians(-m * 360 / k)
            local = p.copy()
            local[:, 0] = math.cos(t) * p[:, 0] - math.sin(t) * p[:, 2]
            local[:, 2] = math.sin(t) * p[:, 0] + math.cos(t) * p[:, 2]
            d = np.minimum(d, shapes.box_sdf(local, (0, 0.05, -0.025), (0.35, 0.1, 0.025)))
        return d

    b = np.array([[-0.36, 0, -0.36], [0.36, 0.5, 0.36]])
    return shapes.grid(sdf, b, voxel_size=0.72 / res, source="star base")


def spiral(res: int) -> CSDF:
    """A spiral stair about the y axis, ``res`` voxels tall: 14 treads 4 cm thick, 0.6 long and
    0.22 wide, each turned 30 degrees from x toward z and raised 0.18 from the one below, on a
    column of radius 0.08, with a handrail 0.8 above the treads (a tube about the helix)."""
    from scipy.spatial import cKDTree

    n, angle, rise, radius = 14, 30.0, 0.18, 0.6
    top = n * rise + 0.1

    def sdf(p):
        q = np.stack([np.hypot(p[:, 0], p[:, 2]) - 0.08, np.abs(p[:, 1] - top / 2) - top / 2], 1)
        d = np.minimum(q.max(1), 0) + np.linalg.norm(np.maximum(q, 0), axis=1)
        for k in range(n):
            t = math.radians(-k * angle)
            local = p.copy()
            local[:, 0] = math.cos(t) * p[:, 0] - math.sin(t) * p[:, 2]
            local[:, 2] = math.sin(t) * p[:, 0] + math.cos(t) * p[:, 2]
            y = rise * (k + 1) + 0.01
            d = np.minimum(d, shapes.box_sdf(local, (0, y - 0.04, -0.11), (radius, y, 0.11)))
        a = np.radians(np.linspace(0, (n - 1) * angle, int((n - 1) * angle * 2) + 1))
        rail = np.stack(
            [0.55 * np.cos(a), rise * (1 + a / math.radians(angle)) + 0.8, 0.55 * np.sin(a)], 1
        )
        return np.minimum(d, cKDTree(rail).query(p)[0] - 0.025)

    height = top + 0.85
    b = np.array([[-radius, 0, -radius], [radius, height, radius]])
    return shapes.grid(sdf, b, voxel_size=height / res, source="spiral stair")


if __name__ == "__main__":
    main()
