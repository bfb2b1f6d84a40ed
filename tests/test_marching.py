"""The re-evaluation's marching cubes (partscale._marching): scikit-image's surface, crack-free
where faces are ambiguous, and without the GIL."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from skimage import measure

from partscale import _marching


def closed_mesh(tri: np.ndarray) -> trimesh.Trimesh:
    """The triangles (F, 9) as one mesh, corners shared where they coincide."""
    m = trimesh.Trimesh(tri[:, :9].reshape(-1, 3), np.arange(3 * len(tri)).reshape(-1, 3))
    m.merge_vertices(digits_vertex=9)
    return m


def edge_uses(m: trimesh.Trimesh) -> np.ndarray:
    _, counts = np.unique(m.edges_sorted, axis=0, return_counts=True)
    return counts


def test_sphere_matches_scikit_image():
    """A sphere of radius 9.3 voxels: the vertices are scikit-image's (the same linear zero
    crossings), the surface is closed, and its area is scikit-image's within 0.1 % (the
    polygons are the same; only the diagonals of four-sided ones may differ) and the sphere's
    within 1 %."""
    x, y, z = np.mgrid[:24, :23, :25].astype(np.float32)
    v = np.sqrt((x - 11.2) ** 2 + (y - 11.4) ** 2 + (z - 12.1) ** 2) - 9.3
    tri = _marching.march(v)
    ref_v, ref_f, _, _ = measure.marching_cubes(v, 0.0, allow_degenerate=True)
    ours = closed_mesh(tri)
    assert set(edge_uses(ours).tolist()) == {2}
    assert len(tri) == len(ref_f)
    assert len(ours.vertices) == len(ref_v)
    gap, _ = trimesh.proximity.ProximityQuery(trimesh.Trimesh(ref_v, ref_f)).vertex(ours.vertices)
    assert gap.max() <= 1e-5  # float32 rounding of scikit-image's vertices
    ref_area = trimesh.Trimesh(ref_v, ref_f).area
    assert abs(ours.area - ref_area) <= 1e-3 * ref_area
    assert abs(ours.area - 4 * np.pi * 9.3**2) <= 0.01 * 4 * np.pi * 9.3**2


@pytest.mark.parametrize("seed", [0, 1])
def test_ambiguous_faces_leave_no_crack(seed):
    """White noise inside a box of positive values: most cells are ambiguous somewhere, and the
    two cells of every face must join their segments there (every edge of the surface is used
    exactly twice). Without the face decider shared by both cells, cracks appear."""
    rng = np.random.default_rng(seed)
    v = np.ones((14, 13, 12), np.float32)
    v[1:-1, 1:-1, 1:-1] = rng.normal(size=(12, 11, 10))
    tri = _marching.march(v)
    _table, _means, ambiguous = _marching._tables()
    assert np.count_nonzero(ambiguous) > 0
    uses = edge_uses(closed_mesh(tri))
    assert len(tri) > 1000
    assert set(uses.tolist()) == {2}


def test_extra_columns_and_empty_field():
    """``width`` adds columns after the nine corners; a field without a sign change has no
    triangle."""
    x = np.mgrid[:5, :5, :5][0].astype(np.float32) - 2.5
    tri = _marching.march(x, width=17)
    assert tri.shape == (2 * 4 * 4, 17)
    assert np.allclose(tri[:, 0:9:3], 2.5)
    assert _marching.march(np.ones((4, 4, 4), np.float32)).shape == (0, 9)


def test_smallest_volumes():
    """One cell with one corner inside: one triangle, at the linear crossings of its three edges
    (value 0 at a quarter of the way from -1 to 3); a volume thinner than two samples along an
    axis has no cell, whatever its signs."""
    v = np.full((2, 2, 2), 3.0, np.float32)
    v[0, 0, 0] = -1.0
    tri = _marching.march(v)
    assert tri.shape == (1, 9)
    got = sorted(map(tuple, np.round(tri.reshape(3, 3), 6).tolist()))
    assert got == [(0.0, 0.0, 0.25), (0.0, 0.25, 0.0), (0.25, 0.0, 0.0)]
    rng = np.random.default_rng(0)
    for shape in [(1, 6, 5), (6, 1, 5), (6, 5, 1), (6, 5, 0)]:
        assert _marching.march(rng.normal(size=shape).astype(np.float32)).shape == (0, 9)


def test_releases_the_gil():
    """The boxes of one edit are solved side by side: the kernel must not hold the GIL."""
    assert _marching._march.targetoptions["nogil"] is True
