"""Concavity of a part: how far its surface is from its convex hull, in voxels.

The measure is a Hausdorff distance between the part's share of the object's surface (its
*patch*) and the boundary of the patch's convex hull (CoACD's concavity without its volume
term): the larger of

- the deepest patch point inside the hull (a dent, a notch, an inner corner), and
- the hull point outside the solid farthest from the patch (the hull bridging a gap).

Hull points inside the solid are where the part was cut from its neighbours: a flat cut is on
the hull and is not a concavity, so they are left out. Measuring the patch, not the part's voxels,
keeps the measure independent of how interior voxels are labelled (by nearest surface point,
their borders bend near creases). Everything is in voxel-index units (voxel centres at integers),
so distances are in voxels.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree

from ..csdf import CSDF
from ..surface import sample_nearest, to_mesh


def hull_concavity(
    points: np.ndarray, *, spacing: float = 1.0, sdf: np.ndarray | None = None
) -> float:
    """Hausdorff distance between sampled surface points and their convex hull's boundary.

    Parameters
    ----------
    points : (N, 3) float64
        Surface samples (voxel units), about ``spacing`` apart or closer.
    spacing : float
        Sampling step on the hull's facets for the hull-to-points direction.
    sdf : (X, Y, Z) float, optional
        Signed distance in voxels; when given, only hull samples more than one voxel outside
        the solid count in the hull-to-points direction (hull points inside are cut faces).

    Returns
    -------
    float
        Concavity in the units of ``points``; 0 for fewer than 4 points or a flat set.
    """
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < 4:
        return 0.0
    try:
        hull = ConvexHull(pts)
    except (QhullError, ValueError):
        return 0.0  # flat or degenerate: no volume, nothing concave
    eq = hull.equations  # (F, 4): n . x + d <= 0 inside, |n| = 1
    # Distance of an inside point to a convex hull's boundary = its smallest facet-plane depth.
    depth = np.empty(len(pts))
    step = max(1, 4_000_000 // max(len(eq), 1))
    for s in range(0, len(pts), step):
        d = -(pts[s : s + step] @ eq[:, :3].T + eq[:, 3])
        depth[s : s + step] = d.min(axis=1)
    inward = float(max(depth.max(), 0.0))
    samples = _sample_triangles(pts[hull.simplices], spacing)
    if sdf is not None:
        samples = samples[sample_nearest(sdf, samples) > 1.0]
        if not len(samples):
            return inward
    dist, _ = cKDTree(pts).query(samples, workers=-1)
    return max(inward, float(dist.max()))


def _sample_triangles(tri: np.ndarray, spacing: float) -> np.ndarray:
    """(M, 3) points covering triangles ``tri`` (T, 3, 3) about ``spacing`` apart (deterministic)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    edge = np.maximum(
        np.linalg.norm(b - a, axis=1),
        np.maximum(np.linalg.norm(c - a, axis=1), np.linalg.norm(c - b, axis=1)),
    )
    n = np.clip(np.ceil(edge / spacing).astype(np.int64), 1, 400)
    out = [tri.mean(axis=1)]
    for k in np.unique(n):
        sel = n == k
        # barycentric lattice with k steps per edge
        i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
        m = (i + j) <= k
        u = (i[m] / k)[None, :, None]
        v = (j[m] / k)[None, :, None]
        aa, bb, cc = a[sel][:, None], b[sel][:, None], c[sel][:, None]
        out.append((aa + u * (bb - aa) + v * (cc - aa)).reshape(-1, 3))
    return np.concatenate(out)


def surface_samples(csdf: CSDF, labels: np.ndarray, *, mesh=None) -> dict[int, np.ndarray]:
    """dict part -> (N, 3) float64: the part's patch of the surface, in voxel-index units.

    Marching-cubes vertices and face centroids (samples about half a voxel apart), each given
    the label of its nearest voxel.
    """
    if mesh is None:
        mesh = to_mesh(csdf)
    idx = csdf.world_to_index(np.concatenate([mesh.vertices, mesh.triangles_center]))
    lab = sample_nearest(np.asarray(labels), idx)
    out: dict[int, np.ndarray] = {}
    order = np.argsort(lab, kind="stable")
    uniq, start = np.unique(lab[order], return_index=True)
    for p, s, e in zip(uniq, start, [*start[1:], len(order)], strict=True):
        if p >= 0:
            out[int(p)] = idx[order[s:e]]
    return out


def touching_pairs(csdf: CSDF, labels: np.ndarray, *, mesh=None) -> set[tuple[int, int]]:
    """Pairs (p, q), p < q, of parts that meet: on the surface (a marching-cubes edge between
    their patches) or inside the solid (face-adjacent inside voxels)."""
    labels = np.asarray(labels)
    if mesh is None:
        mesh = to_mesh(csdf)
    vlab = sample_nearest(labels, csdf.world_to_index(mesh.vertices)).astype(np.int64)
    e = vlab[mesh.edges_unique]
    keys = [np.minimum(e[:, 0], e[:, 1]) * 65536 + np.maximum(e[:, 0], e[:, 1])]
    keys[0] = keys[0][(e[:, 0] != e[:, 1]) & (e.min(axis=1) >= 0)]
    inside = csdf.sdf < 0
    for ax in range(3):
        a = [slice(None)] * 3
        b = [slice(None)] * 3
        a[ax] = slice(0, -1)
        b[ax] = slice(1, None)
        la, lb = labels[tuple(a)], labels[tuple(b)]
        cut = inside[tuple(a)] & inside[tuple(b)] & (la != lb) & (la >= 0) & (lb >= 0)
        pa, pb = la[cut].astype(np.int64), lb[cut].astype(np.int64)
        keys.append(np.minimum(pa, pb) * 65536 + np.maximum(pa, pb))
    return {(int(k) // 65536, int(k) % 65536) for k in np.unique(np.concatenate(keys))}


def part_concavities(csdf: CSDF, parts: np.ndarray | None = None, *, mesh=None) -> np.ndarray:
    """(P,) float64: concavity of every part in voxels (see the module's definition).

    Parameters
    ----------
    csdf : CSDF
        A segmented CSDF (or any CSDF with ``parts`` given separately).
    parts : (X, Y, Z) int, optional
        Labels to measure instead of ``csdf.parts``.
    """
    labels = np.asarray(csdf.parts if parts is None else parts)
    n = int(labels.max()) + 1 if labels.size and labels.max() >= 0 else 0
    pts = surface_samples(csdf, labels, mesh=mesh)
    sdf = csdf.sdf / csdf.voxel_size
    return np.array([hull_concavity(pts[p], sdf=sdf) if p in pts else 0.0 for p in range(n)])


def concavity(csdf: CSDF, part_index: int) -> float:
    """Concavity of one part of a segmented CSDF, in voxels.

    Raises :class:`IndexError` when ``part_index`` is not a part of ``csdf``.
    """
    if not 0 <= part_index < csdf.n_parts:
        raise IndexError(f"part_index: expected 0..{csdf.n_parts - 1}, got {part_index}")
    pts = surface_samples(csdf, csdf.parts)
    if part_index not in pts:
        return 0.0
    return hull_concavity(pts[part_index], sdf=csdf.sdf / csdf.voxel_size)
