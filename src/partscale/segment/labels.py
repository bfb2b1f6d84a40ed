"""From a decomposition to voxel labels: nearest surface point, connectivity, convex merging.

Every method ends with labels on the marching-cubes faces; these functions turn them into the
CSDF's ``parts`` grid the same way for all methods, so methods differ only in where they cut.
"""

from __future__ import annotations

import heapq

import numpy as np
from scipy import ndimage
from scipy.spatial import ConvexHull, QhullError, cKDTree

from .._util import palette_colour
from ..csdf import CSDF
from .concavity import Patch, decimate, surface_samples, touching_pairs, union_concavity

BAND = 3.0
"""Voxels up to this many voxels outside the surface get a part; farther ones stay -1."""

_FULL = np.ones((3, 3, 3), bool)  # 26-connectivity


def voxels_from_faces(csdf: CSDF, mesh, face_labels: np.ndarray) -> np.ndarray:
    """(X, Y, Z) int32 labels: the label of the nearest surface point, -1 beyond :data:`BAND`.

    Parameters
    ----------
    csdf : CSDF
    mesh : trimesh.Trimesh
        ``to_mesh(csdf)``; its face centroids stand for the surface (faces are < 1 voxel).
    face_labels : (F,) int
        Part of each face, >= 0.
    """
    centres = csdf.world_to_index(mesh.triangles_center)
    near = csdf.sdf < BAND * csdf.voxel_size
    ijk = np.argwhere(near)
    _, nearest = cKDTree(centres).query(ijk, workers=-1)
    labels = np.full(csdf.shape, -1, np.int32)
    labels[near] = np.asarray(face_labels)[nearest]
    return labels


def faces_from_voxels(csdf: CSDF, mesh, labels: np.ndarray) -> np.ndarray:
    """(F,) int32: each face takes the label of the nearest labelled voxel to its centroid."""
    known = labels >= 0
    _, idx = ndimage.distance_transform_edt(~known, return_indices=True)
    ijk = np.rint(csdf.world_to_index(mesh.triangles_center)).astype(np.intp)
    for a in range(3):
        np.clip(ijk[:, a], 0, csdf.shape[a] - 1, out=ijk[:, a])
    src = idx[:, ijk[:, 0], ijk[:, 1], ijk[:, 2]]
    return labels[src[0], src[1], src[2]].astype(np.int32)


def make_connected(labels: np.ndarray, *, min_voxels: int = 32) -> np.ndarray:
    """Make every part 26-connected.

    A part's largest connected piece keeps its label; another piece becomes a part of its own
    when it has at least ``min_voxels`` voxels or touches no other part, and otherwise joins the
    part it touches most.

    Parameters
    ----------
    labels : (X, Y, Z) int
        -1 where none.

    Returns
    -------
    (X, Y, Z) int32, parts numbered 0..P-1 (not yet ordered).
    """
    out = np.asarray(labels, dtype=np.int32).copy()
    orphans = np.zeros(out.shape, bool)
    next_label = int(out.max()) + 1
    for part, sl in enumerate(ndimage.find_objects(out + 1)):
        if sl is None:
            continue
        mine = out[sl] == part
        comp, n = ndimage.label(mine, structure=_FULL)
        if n <= 1:
            continue
        sizes = np.bincount(comp.ravel())[1:]
        keep = int(np.argmax(sizes)) + 1
        for c in range(1, n + 1):
            if c == keep:
                continue
            region = comp == c
            if sizes[c - 1] >= min_voxels:
                out[sl][region] = next_label
                next_label += 1
            else:
                orphans[sl] |= region
    if orphans.any():
        out[orphans] = -1
        comp, n = ndimage.label(orphans, structure=_FULL)
        for c, sl in enumerate(ndimage.find_objects(comp), start=1):
            grown = tuple(
                slice(max(s.start - 1, 0), min(s.stop + 1, dim))
                for s, dim in zip(sl, out.shape, strict=True)
            )
            region = comp[grown] == c
            ring = ndimage.binary_dilation(region, _FULL) & ~region
            around = out[grown][ring]
            around = around[around >= 0]
            if around.size:
                out[grown][region] = np.bincount(around).argmax()
            else:
                out[grown][region] = next_label
                next_label += 1
    return renumber(out)


def renumber(labels: np.ndarray) -> np.ndarray:
    """(X, Y, Z) int32: parts renumbered 0..P-1, largest first (ties: first voxel in C order)."""
    flat = labels.ravel()
    uniq, first, counts = np.unique(flat, return_index=True, return_counts=True)
    keep = uniq >= 0
    uniq, first, counts = uniq[keep], first[keep], counts[keep]
    order = np.lexsort((first, -counts))
    lut = np.full(int(uniq.max()) + 2 if uniq.size else 1, -1, np.int32)
    lut[uniq[order]] = np.arange(len(order), dtype=np.int32)
    return lut[labels]  # labels == -1 picks lut[-1] == -1


def merge_convex(
    csdf: CSDF,
    mesh,
    labels: np.ndarray,
    *,
    tolerance: float,
    max_parts: int | None = None,
) -> np.ndarray:
    """Greedily merge touching parts while their union stays nearly convex.

    Pairs that meet on the surface or inside the solid are merged cheapest first (concavity of
    the union's surface patch, in voxels) while that concavity is at most ``tolerance``; beyond
    it, merging goes on only while there are more than ``max_parts`` parts. Parts of separate
    pieces (they only meet in the air between them) are never merged.

    Returns
    -------
    (X, Y, Z) int32 labels, renumbered.
    """
    n = int(labels.max()) + 1
    if n <= 1:
        return renumber(labels)
    # one sample per voxel is enough to decide merges at a tolerance of a voxel or more
    patch = {
        p: Patch(decimate(v, 1.0)) for p, v in surface_samples(csdf, labels, mesh=mesh).items()
    }
    sdf = csdf.sdf / csdf.voxel_size
    neighbours: dict[int, set[int]] = {p: set() for p in range(n)}
    pairs = sorted(touching_pairs(csdf, labels, mesh=mesh))
    for p, q in pairs:
        neighbours[p].add(q)
        neighbours[q].add(p)

    def union_cost(p: int, q: int) -> float:
        both = [patch[r] for r in (p, q) if r in patch]
        if not both:
            return 0.0
        # above the tolerance the exact value only orders merges forced by max_parts
        limit = tolerance if max_parts is None else np.inf
        return union_concavity(both, sdf=sdf, spacing=2.0, limit=limit)

    alive = set(range(n))
    version = dict.fromkeys(range(n), 0)
    heap = [(union_cost(p, q), p, q, 0, 0) for p, q in pairs]
    heapq.heapify(heap)
    parent = np.arange(n)
    while heap:
        cost, p, q, vp, vq = heapq.heappop(heap)
        if p not in alive or q not in alive:
            continue
        if version[p] != vp or version[q] != vq:
            # Lazy update: a part grew since this cost was computed. Growing rarely makes a
            # union more convex, so the old cost orders the queue and is refreshed only here.
            heapq.heappush(heap, (union_cost(p, q), p, q, version[p], version[q]))
            continue
        if cost > tolerance and (max_parts is None or len(alive) <= max_parts):
            break
        if q in patch:
            patch[p] = patch[p].merged(patch.pop(q)) if p in patch else patch.pop(q)
        for r in neighbours.pop(q):
            if r != p:
                neighbours[r].discard(q)
                neighbours[r].add(p)
                neighbours[p].add(r)
                a, b = min(p, r), max(p, r)
                # a pair new to p: queue it (with q's old cost as its first estimate)
                heapq.heappush(heap, (cost, a, b, -1, -1))
        neighbours[p].discard(q)
        alive.discard(q)
        parent[parent == q] = p
        version[p] += 1
    lut = np.append(parent, -1).astype(np.int32)
    return renumber(lut[labels])


def palette(n: int) -> list[list[int]]:
    """``n`` distinct sRGB display colours, :func:`palette_colour` of 0..n-1."""
    return [palette_colour(i) for i in range(n)]


def parts_info(csdf: CSDF, mesh, labels: np.ndarray) -> list[dict]:
    """Per-part facts: index, labelled voxel count, world bbox of the part's surface patch,
    world volume of the patch's convex hull, display colour."""
    n = int(labels.max()) + 1 if labels.max() >= 0 else 0
    counts = np.bincount(labels[labels >= 0].ravel(), minlength=n)
    patch = surface_samples(csdf, labels, mesh=mesh)
    colours = palette(n)
    info = []
    for p in range(n):
        pts = patch.get(p)
        if pts is None or len(pts) == 0:  # no surface sample: use its voxels
            pts = np.argwhere(labels == p).astype(np.float64)
        world = csdf.index_to_world(pts)
        try:
            vol = float(ConvexHull(pts).volume) * csdf.voxel_size**3
        except (QhullError, ValueError):
            vol = 0.0
        info.append(
            {
                "index": p,
                "voxels": int(counts[p]),
                "bbox": [world.min(axis=0).tolist(), world.max(axis=0).tolist()],
                "hull_volume": vol,
                "color": colours[p],
            }
        )
    return info
