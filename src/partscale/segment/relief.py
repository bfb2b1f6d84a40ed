"""Surface relief: how rough an object's surface is at the scale of a few voxels.

A scanned and completed object carries the sensor's noise as bumps and dents a voxel or two
deep all over its surface. The concavity a part's hull measures then is its true concavity plus
the relief's peak-to-valley, so a tolerance meant for clean geometry cuts every bumpy board into
dozens of pieces (a completed Kenney chair: 152 parts where the clean one has 10).

The relief is measured where it cannot be confused with shape: around sampled surface points,
a quadric height field is fitted to the surface within :data:`RADIUS` voxels on the same side
(normals within 73 degrees, so a thin board's two faces and an edge's two sides are apart), and
the RMS of what the quadric leaves is the local relief. Curvature, tubes and fillets are what a
quadric fits; bumps a few voxels across are what it cannot. The median over the surface ignores
edges and corners (a small share of any surface).

Measured on 17 clean imports of ``../shared/data`` at 128 voxels and on 16 completions of
partial scans (virtual and real TUM scans), one run, 2026-12-02 (median RMS, voxels): clean
0.00-0.12 (the coat rack's thin turned pole and the Sweet Home staircase the highest), completed
0.18-0.36. :data:`CLEAN_RELIEF` sits between the two: marching cubes' own faceting.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..csdf import CSDF
from ..surface import to_mesh

RADIUS = 3.0
"""Neighbourhood radius (voxels) of one fit: bumps up to about twice this across are relief."""
CLEAN_RELIEF = 0.15
"""Relief RMS (voxels) of clean geometry: marching cubes of an exact distance field leaves up to
0.12 on the clean objects measured; above this the surface carries noise."""
PEAK_TO_VALLEY = 16.0
"""Peak-to-valley of the relief a hull sees over a part, in units of the measured RMS. For
independent Gaussian samples it would be 8 (the expected range of ~3,000, a part's surface at one
sample per voxel: 2 sqrt(2 ln 3000)); but bumps are correlated over a few voxels and the quadric
absorbs part of each, so the RMS reads low. Calibrated where the truth is known: completions of
one- and three-view virtual scans of six objects (``bench/bench_complete.py``'s sensor) against
the clean objects they were scanned from, 2026-12-02: with 16 they segment into 0.7-2.4x the
clean part counts (median 0.9x), with 8 into 1.0-4.3x (median 1.9x), with 20 a median 0.8x."""
_SAMPLES = 6000
_NEIGHBOURS = 48
_SAME_SIDE = 0.3  # cosine: neighbours whose normal is within 73 degrees


def surface_relief(vertices: np.ndarray, normals: np.ndarray, voxel_size: float) -> float:
    """Median relief RMS of a surface, in voxels.

    Parameters
    ----------
    vertices, normals : (V, 3) float
        The surface's vertices (world units) and unit normals.
    voxel_size : float
        World units per voxel.

    Returns
    -------
    float
        The median over up to 6,000 evenly spread vertices of the RMS residual of a quadric
        height field fitted to the same-side surface within :data:`RADIUS` voxels; 0 for a
        surface too small to measure.

    Examples
    --------
    A sphere's marching cubes is clean geometry (below :data:`CLEAN_RELIEF`), the same surface
    with bumps a voxel deep is not:

    >>> import numpy as np
    >>> from partscale import segment, shapes
    >>> from partscale.surface import to_mesh
    >>> mesh = to_mesh(shapes.sphere((0, 0, 0), 0.5, voxel_size=0.02))
    >>> v, n = mesh.vertices, mesh.vertex_normals
    >>> segment.surface_relief(v, n, 0.02) < 0.15
    True
    >>> bumps = 0.02 * np.random.default_rng(0).normal(0, 0.5, (len(v), 1)) * n
    >>> segment.surface_relief(v + bumps, n, 0.02) > 0.15
    True
    """
    V = np.asarray(vertices, np.float64) / voxel_size
    N = np.asarray(normals, np.float64)
    if len(V) < _NEIGHBOURS:
        return 0.0
    idx = np.arange(0, len(V), max(1, len(V) // _SAMPLES))
    dist, nb = cKDTree(V).query(V[idx], k=_NEIGHBOURS, distance_upper_bound=RADIUS)
    found = np.isfinite(dist)
    nb = np.where(found, nb, 0)
    n = N[idx]
    # a vertex whose faces cancel has no normal (length 0): it is no sample
    use = (
        found
        & (np.einsum("skj,sj->sk", N[nb], n) > _SAME_SIDE)
        & (np.linalg.norm(n, axis=1) > 0.5)[:, None]
    )
    # a tangent frame (a, b, n) per sample: the fit is a height field over (a, b)
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    a = np.cross(n, helper)
    a /= np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-12)
    b = np.cross(n, a)
    rel = V[nb] - V[idx][:, None]
    u, v, h = (np.einsum("skj,sj->sk", rel, e) for e in (a, b, n))
    basis = np.stack([u * u, u * v, v * v, u, v, np.ones_like(u)], axis=-1)
    w = use[..., None] * basis
    gram = np.einsum("ski,skj->sij", w, w) + 1e-6 * np.eye(6)
    coef = np.linalg.solve(gram, np.einsum("ski,sk->si", w, h * use)[..., None])[..., 0]
    resid = (h - np.einsum("ski,si->sk", basis, coef)) * use
    count = use.sum(axis=1)
    enough = count >= 12  # 6 unknowns: at least twice as many points
    if not enough.any():
        return 0.0
    rms = np.sqrt((resid[enough] ** 2).sum(axis=1) / count[enough])
    return float(np.median(rms))


def relief_of(csdf: CSDF) -> float:
    """Relief of the object's surface (its marching cubes), in voxels.

    Parameters
    ----------
    csdf : CSDF
        The object (its colours are not read).

    Returns
    -------
    float
        :func:`surface_relief` of its zero level.

    Examples
    --------
    >>> from partscale import segment, shapes
    >>> ball = shapes.sphere((0, 0, 0), 0.5, voxel_size=0.05)
    >>> segment.relief_of(ball) < segment.relief.CLEAN_RELIEF
    True
    """
    mesh = to_mesh(csdf, attributes=False)
    return surface_relief(mesh.vertices, mesh.vertex_normals, csdf.voxel_size)


def noise_tolerance(relief: float) -> float:
    """Concavity (voxels) the surface's noise adds to what a part's hull measures.

    Parameters
    ----------
    relief : float
        The surface's relief RMS in voxels (:func:`surface_relief`).

    Returns
    -------
    float
        :data:`PEAK_TO_VALLEY` times the relief beyond clean geometry's (added in quadrature,
        so a surface at or below :data:`CLEAN_RELIEF` adds nothing).

    Examples
    --------
    >>> from partscale import segment
    >>> segment.noise_tolerance(0.1), round(segment.noise_tolerance(0.25), 2)
    (0.0, 3.2)
    """
    noise = np.sqrt(max(relief * relief - CLEAN_RELIEF * CLEAN_RELIEF, 0.0))
    return float(PEAK_TO_VALLEY * noise)
