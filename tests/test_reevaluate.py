"""Re-evaluation of a long run of target layers in pieces: the same on any machine, and as exact as
one box against exact distances to the marching-cubes surface; faces on the grid nodes
(degenerate triangles) re-evaluate to the exact distances; colours and parts come from the
nearest surface point."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest
import trimesh
from skimage import measure

from partscale import _workers, shapes
from partscale.edit import naive_edit, reevaluate

# the module, not the function ``partscale.edit.reevaluate`` of the same name
REEVAL = sys.modules["partscale.edit.reevaluate"]


@pytest.fixture(scope="module")
def stretched():
    """A ball stretched naively (distances scaled along y): 57 layers of targets along x."""
    ball = shapes.sphere((0.0, 0.0, 0.0), 0.5, voxel_size=0.02)
    return naive_edit(ball, {"axis": "y", "zone": [-0.2, 0.1], "to": 0.373})


def pieces_of(c, monkeypatch):
    """(re-evaluated c, the layer spans of the pieces it was solved in)."""
    spans = []
    solve = REEVAL._solve_box

    def spy(*args):
        spans.append(args[5])
        return solve(*args)

    with monkeypatch.context() as m:
        m.setattr(REEVAL, "_solve_box", spy)
        # short pieces: more cuts than the default, on a small grid
        m.setattr(REEVAL, "_PIECE_LAYERS", min(REEVAL._PIECE_LAYERS, 24))
        out = reevaluate(c)
    return out, sorted(spans)


def test_pieces_depend_on_the_layers_not_the_cores(stretched, monkeypatch):
    results = []
    for cores in (1, 4):
        with monkeypatch.context() as m:
            m.setattr(os, "cpu_count", lambda cores=cores: cores)
            m.setattr(_workers, "_POOL", None)  # a pool of this many threads
            results.append(pieces_of(stretched, monkeypatch))
    (serial, spans), (threaded, spans4) = results
    assert len(spans) >= 3 and spans == spans4, (spans, spans4)
    for name in ("sdf", "rgb", "parts"):
        assert np.array_equal(getattr(serial, name), getattr(threaded, name)), name


def test_pieces_are_as_exact_as_one_box(stretched, monkeypatch):
    """Against exact point-to-triangle distances (trimesh) to the marching-cubes surface of the
    whole field, on a fixed sample of the band: the pieces' max and p99 errors are within 0.005
    voxel of one box's (their paths differ where the sweeps start; neither is exact, both stay
    within 0.05 voxel)."""
    split, spans = pieces_of(stretched, monkeypatch)
    assert len(spans) >= 3, spans
    with monkeypatch.context() as m:
        m.setattr(REEVAL, "_pieces", lambda runs: runs)
        one, one_span = pieces_of(stretched, monkeypatch)
    assert len(one_span) == 1
    h = stretched.voxel_size
    v, f, _, _ = measure.marching_cubes(
        np.array(stretched.sdf, np.float32), 0.0, allow_degenerate=False
    )
    surface = trimesh.Trimesh(v, f, process=False)
    band = np.argwhere(np.abs(stretched.sdf) <= 3 * h)
    sample = band[np.random.default_rng(0).choice(len(band), 3000, replace=False)]
    _, exact, _ = trimesh.proximity.closest_point(surface, sample.astype(np.float64))
    err = {}
    for name, c in (("pieces", split), ("one box", one)):
        got = np.abs(c.sdf[tuple(sample.T)].astype(np.float64)) / h
        err[name] = np.abs(got - exact)
    stats = {k: (e.max(), np.percentile(e, 99)) for k, e in err.items()}
    assert stats["pieces"][0] <= stats["one box"][0] + 0.005, stats
    assert stats["pieces"][1] <= stats["one box"][1] + 0.005, stats
    assert stats["pieces"][0] <= 0.05, stats
    # the pieces did change some values (else this test would compare a thing with itself)
    assert not np.array_equal(split.sdf, one.sdf)


def test_faces_on_the_grid_nodes_are_exact():
    """A box whose faces lie on grid nodes: the field is 0 there and marching cubes makes
    degenerate triangles (kept: they are points and segments of the surface). Distances scaled
    by 1.7, as a naive stretch scales them, come back to the box's exact distances (float32
    rounding only) across the band."""
    h = 0.125
    box = shapes.box((0.0, 0.0, 0.0), (2.0, 1.5, 1.0), voxel_size=h)
    sdf = np.array(box.sdf, np.float32)
    v, f, _, _ = measure.marching_cubes(sdf, 0.0, allow_degenerate=True)
    area = np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    assert (area == 0).sum() >= 100  # the case this test is about
    out = reevaluate(box.replace(sdf=sdf * np.float32(1.7)))
    # the voxels still within the band after scaling (beyond it reevaluate leaves values be)
    band = np.abs(sdf) * 1.7 <= 3 * h
    err = np.abs(out.sdf[band].astype(np.float64) - sdf[band]) / h
    assert err.max() <= 1e-5, err.max()


def test_colours_and_parts_come_from_the_nearest_surface_point():
    """Above a box's top face (at 5.3 voxels, between two layers), every re-evaluated voxel takes
    the colour of the face, trilinear in a red ramp along z (60 + 12 per voxel: 123.6 there,
    where the voxels' own ramp reads 132 and 144), and the part of the solid just below it (the
    left and right halves are parts 1 and 2)."""
    h = 0.1
    lo, hi = (0.0, 0.0, 0.0), (1.2, 0.8, 0.53)
    c = shapes.grid(
        lambda p: shapes.box_sdf(p, lo, hi),
        (lo, hi),
        voxel_size=h,
        color=lambda p: np.stack(
            [np.rint(60 + 12 * p[:, 2] / h), np.full(len(p), 90), np.full(len(p), 30)], axis=1
        ),
    )
    x, y, z = (c.origin[a] + np.arange(c.shape[a]) * h for a in range(3))
    X, Y, Z = np.meshgrid(x, y, z, indexing="ij")
    parts = np.where(X < 0.6, 1, 2).astype(np.int16)
    sdf = np.array(c.sdf, np.float32)
    out = reevaluate(c.replace(sdf=sdf * np.float32(1.5), parts=parts))
    above = (
        (Z > hi[2])
        & (sdf * 1.5 <= 3 * h)  # still within the band after scaling
        & (X > lo[0] + h / 2)
        & (X < hi[0] - h / 2)
        & (Y > lo[1] + h / 2)
        & (Y < hi[1] - h / 2)
    )
    assert above.sum() >= 2 * 11 * 7
    red = out.rgb[..., 0][above].astype(int)
    assert np.abs(red - 123.6).max() <= 1, np.unique(red)
    assert (out.rgb[..., 1:][above] == (90, 30)).all()
    assert (out.parts[above] == parts[above]).all()
