"""Thin features: measured on analytic slabs, warned about by ``partscale info``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from partscale import shapes
from partscale.csdf import save
from partscale.thickness import thin_features

H = 0.02


def slabs(thickness: float, n: int = 4):
    """``n`` slabs ``thickness`` voxels thick across x, every ten voxels, 0.3 x 0.2 m."""
    p = 10 * H
    boxes = [((m * p + 0.3 * H, 0, 0), (m * p + (0.3 + thickness) * H, 0.3, 0.2)) for m in range(n)]
    bounds = np.array([[0, 0, 0], [(n - 1) * p + (thickness + 1.3) * H, 0.3, 0.2]])
    return shapes.grid(lambda q: shapes.boxes_sdf(q, boxes), bounds, voxel_size=H)


@pytest.mark.parametrize("thickness", [0.9, 1.3])
def test_thin_slabs_are_measured_and_a_finer_resolution_named(thickness):
    t = thin_features(slabs(thickness))
    assert t.worth_warning and t.gap_voxels == 0
    # the slabs' inside voxels, all of them: one or two layers of 16 x 11 per slab
    assert t.solid_voxels >= 4 * 14 * 9
    assert abs(t.typical - thickness) <= 0.05
    assert (t.below_one_solid > 0) == (thickness < 1)
    # the named resolution holds the slabs at >= 1.5 voxels
    assert t.needed_resolution * thickness / t.resolution >= 1.5


def test_thick_bodies_and_their_rims_are_not_thin():
    for c in (
        slabs(4.0),
        shapes.sphere((0, 0, 0), 0.3, voxel_size=H),
        shapes.box((0, 0, 0), (0.31, 0.23, 0.17), voxel_size=H),
    ):
        t = thin_features(c)
        assert not t.worth_warning and t.message(H) is None, t


def test_a_thin_gap_is_a_feature_too():
    # two blocks 0.8 voxel apart, a voxel centre in the slit between them
    boxes = [((0, 0, 0), (0.2 + 0.6 * H, 0.3, 0.2)), ((0.2 + 1.4 * H, 0, 0), (0.4, 0.3, 0.2))]
    c = shapes.grid(
        lambda q: shapes.boxes_sdf(q, boxes), ((0, 0, 0), (0.4, 0.3, 0.2)), voxel_size=H
    )
    t = thin_features(c)
    assert t.worth_warning and t.below_one_gap > 0 and t.solid_voxels == 0
    assert abs(t.typical - 0.8) <= 0.05


def test_info_warns_about_thin_features(tmp_path, cli):
    thin = save(slabs(0.9), tmp_path / "thin.csdf.npz")
    thick = save(slabs(4.0), tmp_path / "thick.csdf.npz")
    out = cli("info", thin, check=True).stdout
    assert "warning:     thin features" in out and "--res " in out, out
    clean = cli("info", thick, check=True).stdout
    assert "warning" not in clean
    assert "relief:" in clean and "(smooth)" in clean  # a clean grid is no scan
    s = json.loads(cli("info", thin, "--json", check=True).stdout)["thin_features"]
    assert s["below_one_voxel"]["solid"] > 0 and s["needed_resolution"] > s["resolution"]


def test_import_records_pieces_thinner_than_a_voxel_and_info_names_a_resolution():
    """A board 0.6 voxel thick (res 40 over 1 m: voxels of 2.5 cm, board 1.5 cm; its 4 broad
    triangles are thin, the edges are not): the import
    thickens it to hold it, records how thin it was, and the warning names a finer grid."""
    trimesh = pytest.importorskip("trimesh")
    from partscale import ingest

    board = trimesh.creation.box(bounds=[[0, 0, 0], [1.0, 0.015, 0.5]])
    c = ingest.from_mesh(ingest.from_trimesh(board), res=40)
    rec = c.meta["history"][0]
    assert rec["thin_piece_triangles"] == 4 and rec["below_one_voxel_triangles"] >= 2
    assert abs(rec["thin_piece_thickness_voxels"]["median"] - 0.6) <= 0.02
    t = thin_features(c)
    assert t.worth_warning and "thickened at import" in t.message(c.voxel_size)
    # 1.5 voxels across the 1.5 cm board: voxels of 1 cm, 100 along the metre
    assert t.needed_resolution >= 100


def _reference(s: np.ndarray, h: float, limit: float) -> tuple[list[int], float]:
    """The rule of :func:`thin_features` read voxel by voxel in plain Python: counts (solid,
    gap, below one solid, below one gap, surface) and the median thickness."""
    n = s.shape
    inside = s <= 0
    a = np.abs(s) / np.float32(h)
    counts, thick = [0] * 5, []
    for v in np.ndindex(*n):
        nbr = [tuple(v[b] + d * (b == ax) for b in range(3)) for ax in range(3) for d in (-1, 1)]
        if any(all(0 <= u[b] < n[b] for b in range(3)) and inside[u] != inside[v] for u in nbr):
            counts[4] += 1
        if not a[v] > 0.01:
            continue
        t = np.inf
        for ax in range(3):
            for lo, hi in ((v[ax], v[ax]), (v[ax] - 1, v[ax]), (v[ax], v[ax] + 1)):
                if lo < 1 or hi > n[ax] - 2:
                    continue

                def at(q, ax=ax, v=v):
                    return tuple(q if b == ax else v[b] for b in range(3))

                run = [inside[at(q)] == inside[v] for q in range(lo, hi + 1)]
                ends = [inside[at(lo - 1)] != inside[v], inside[at(hi + 1)] != inside[v]]
                if all(run) and all(ends):
                    out = np.float32(2 + hi - lo) - a[at(lo - 1)] - a[at(hi + 1)]
                    t = min(t, max(out, 2 * a[v] if hi == lo else 1.0))
        box = tuple(slice(max(x - 1, 0), x + 2) for x in v)
        near = s[box][inside[box] == inside[v]]
        if t < limit and not (np.abs(near) >= limit / 2 * np.float32(h)).any():
            side = 0 if inside[v] else 1
            counts[side] += 1
            counts[2 + side] += int(t < 1)
            thick.append(t)
    return counts, float(np.median(thick)) if thick else np.nan


def test_the_sweep_reads_the_rule_voxel_by_voxel():
    """Slabs 0.7-1.6 voxels thick, a slit between two blocks and noise, on a 24 x 18 x 14 grid:
    the parallel sweep counts what a plain per-voxel reading of the rule counts."""
    rng = np.random.default_rng(3)
    boxes = [
        ((0.1 * H + m * 5 * H, 0, 0), ((0.1 + 0.7 + 0.3 * m) * H + m * 5 * H, 0.3, 0.2))
        for m in range(4)
    ]
    boxes += [((0.36, 0, 0), (0.4, 0.3, 0.2)), ((0.4 + 0.8 * H, 0, 0), (0.46, 0.3, 0.2))]
    c = shapes.grid(
        lambda q: shapes.boxes_sdf(q, boxes), ((0, 0, 0), (0.46, 0.34, 0.26)), voxel_size=H
    )
    s = (c.sdf + rng.normal(0, 0.2 * H, c.sdf.shape)).astype(np.float32)
    c = c.replace(sdf=s)
    t = thin_features(c)
    counts, median = _reference(s, H, 1.5)
    assert counts[0] > 0 and counts[1] > 0
    assert [
        t.solid_voxels,
        t.gap_voxels,
        t.below_one_solid,
        t.below_one_gap,
        t.surface_voxels,
    ] == counts
    assert t.typical == pytest.approx(median, abs=1e-6)


def test_every_command_starts_without_numba_until_thin_features_runs():
    """Reading the command-line interface (``info`` and ``import`` read this module) loads none
    of numba, trimesh and scipy; the first ``thin_features`` call loads numba."""
    import subprocess
    import sys

    probe = (
        "import json, sys\n"
        "import partscale.cli, partscale.thickness\n"
        "heavy = ('numba', 'trimesh', 'scipy')\n"
        "before = [m for m in heavy if m in sys.modules]\n"
        "from partscale import shapes\n"
        "partscale.thickness.thin_features(shapes.box((0, 0, 0), (0.2, 0.2, 0.2), voxel_size=0.05))\n"
        "print(json.dumps([before, 'numba' in sys.modules]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=300
    )
    before, after = json.loads(out.stdout.splitlines()[-1])
    assert before == [] and after
