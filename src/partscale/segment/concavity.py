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

import numba
import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree

from ..csdf import CSDF
from ..surface import to_mesh


def hull_concavity(
    points: np.ndarray,
    *,
    spacing: float = 1.0,
    sdf: np.ndarray | None = None,
    limit: float = np.inf,
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
    limit : float
        Stop early, returning a value above ``limit``, once the answer is known to exceed it.

    Returns
    -------
    float
        Concavity in the units of ``points``; 0 for fewer than 4 points or a flat set.

    Examples
    --------
    Two walls 10 long meeting at a right angle: their hull's diagonal face is 5 from the
    nearest wall point (the hull bridges the gap between them).

    >>> import numpy as np
    >>> from partscale import segment
    >>> u, z = np.meshgrid(np.linspace(0, 10, 41), np.linspace(0, 4, 17))
    >>> wall_x = np.stack([u.ravel(), 0 * u.ravel(), z.ravel()], axis=1)
    >>> wall_y = wall_x[:, [1, 0, 2]]
    >>> round(segment.hull_concavity(np.concatenate([wall_x, wall_y]), spacing=0.5), 2)
    5.0
    """
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < 4:
        return 0.0
    try:
        hull = ConvexHull(pts)
    except (QhullError, ValueError):
        return 0.0  # flat or degenerate: no volume, nothing concave
    return _to_hull(hull, pts, [pts], lambda: [cKDTree(pts)], spacing, sdf, limit)


def _to_hull(hull, corners, point_sets, trees, spacing, sdf, limit) -> float:
    """The two directions of the Hausdorff distance between ``point_sets`` and ``hull`` (the
    hull of ``corners``); ``trees()`` gives KD-trees of the point sets, only when needed.
    """
    eq = np.ascontiguousarray(hull.equations)  # (F, 4): n . x + d <= 0 inside, |n| = 1
    inward = max(_deepest_index(p, eq, 0.0)[1] for p in point_sets)
    if inward > limit:
        return inward
    samples = _hull_samples(corners[hull.simplices], spacing, sdf, limit)
    if not len(samples):
        return inward
    # beyond the limit the exact distance does not matter: the trees stop searching there
    bound = limit * 1.001 + 1e-9 if np.isfinite(limit) else np.inf
    dist = np.full(len(samples), np.inf)
    for tree in trees():
        np.minimum(dist, tree.query(samples, distance_upper_bound=bound)[0], out=dist)
    return max(inward, float(dist.max()))


def deepest_point(pts: np.ndarray, eq: np.ndarray) -> tuple[int, float]:
    """Index of the point of ``pts`` (N, 3) deepest inside the hull with facet planes ``eq``
    (n . x + d <= 0 inside, |n| = 1), and its depth.
    """
    return _deepest_index(np.ascontiguousarray(pts, np.float64), np.ascontiguousarray(eq), -np.inf)


@numba.njit(cache=True, nogil=True)
def _deepest_index(pts, eq, floor):  # pragma: no cover - compiled
    # Distance of a point inside a convex hull to its boundary = its smallest facet-plane
    # depth; the answer is the point with the largest such distance above ``floor`` (index 0
    # and ``floor`` when none). A point stops being scanned as soon as one facet is closer
    # than the best so far (most points lie on the hull).
    best, arg = floor, 0
    for i in range(pts.shape[0]):
        m = np.inf
        for j in range(eq.shape[0]):
            d = -(pts[i, 0] * eq[j, 0] + pts[i, 1] * eq[j, 1] + pts[i, 2] * eq[j, 2] + eq[j, 3])
            if d < m:
                m = d
                if m <= best:
                    break
        if m > best:
            best, arg = m, i
    return arg, best


#: Most lattice steps per triangle edge (a hull triangle longer than this many spacings gets
#: its samples farther apart).
_LATTICE_MAX = 256


def _hull_samples(
    tri: np.ndarray, spacing: float, sdf: np.ndarray | None, limit: float = np.inf
) -> np.ndarray:
    """(M, 3) points covering triangles ``tri`` (T, 3, 3), at most ``spacing`` apart, keeping
    only those more than one voxel outside the solid (nearest voxel of ``sdf``, in voxels) when
    ``sdf`` is given.

    A barycentric lattice with ``ceil(longest edge / spacing)`` steps per edge (at most
    ``_LATTICE_MAX``), so long thin triangles (common on hulls) are covered along their length
    too.

    With a finite ``limit``, triangles whose every point is within ``limit`` of a corner (a
    triangle of diameter D lies within D / sqrt(3) of its nearest corner, equality for the
    equilateral one) are left out: their corners are samples of the patch, so no point on them
    can be farther than ``limit`` from it.
    """
    skip = limit * np.sqrt(3.0) if np.isfinite(limit) else -1.0
    return _outside_lattice(
        np.ascontiguousarray(tri, dtype=np.float64),
        float(spacing),
        _NO_SDF if sdf is None else sdf,
        float(skip),
    )


_NO_SDF = np.full((1, 1, 1), np.inf, np.float32)  # every sample is "outside"


@numba.njit(cache=True, nogil=True)
def _outside_lattice(tri, spacing, sdf, skip):  # pragma: no cover - compiled
    # the lattice of _hull_samples, generated and filtered in one pass (no (M, 3) temporary)
    n = 0
    ks = np.empty(tri.shape[0], np.int64)
    for t in range(tri.shape[0]):
        e = 0.0
        for u, v in ((0, 1), (0, 2), (1, 2)):
            d = np.sqrt(
                (tri[t, v, 0] - tri[t, u, 0]) ** 2
                + (tri[t, v, 1] - tri[t, u, 1]) ** 2
                + (tri[t, v, 2] - tri[t, u, 2]) ** 2
            )
            e = max(e, d)
        k = min(max(int(np.ceil(e / spacing)), 1), _LATTICE_MAX)
        if e <= skip:
            k = 0
        ks[t] = k
        n += (k + 1) * (k + 2) // 2
    out = np.empty((n, 3), np.float64)
    m = 0
    for t in range(tri.shape[0]):
        k = ks[t]
        if k == 0:
            continue
        for i in range(k + 1):
            for j in range(k + 1 - i):
                fi, fj = i / k, j / k
                # scalars, not a small array per sample: no allocation in the innermost loop
                x = (
                    tri[t, 0, 0]
                    + fi * (tri[t, 1, 0] - tri[t, 0, 0])
                    + fj * (tri[t, 2, 0] - tri[t, 0, 0])
                )
                y = (
                    tri[t, 0, 1]
                    + fi * (tri[t, 1, 1] - tri[t, 0, 1])
                    + fj * (tri[t, 2, 1] - tri[t, 0, 1])
                )
                z = (
                    tri[t, 0, 2]
                    + fi * (tri[t, 1, 2] - tri[t, 0, 2])
                    + fj * (tri[t, 2, 2] - tri[t, 0, 2])
                )
                ii = min(max(int(np.rint(x)), 0), sdf.shape[0] - 1)
                jj = min(max(int(np.rint(y)), 0), sdf.shape[1] - 1)
                kk = min(max(int(np.rint(z)), 0), sdf.shape[2] - 1)
                if sdf[ii, jj, kk] > 1.0:
                    out[m, 0] = x
                    out[m, 1] = y
                    out[m, 2] = z
                    m += 1
    return out[:m]


def decimate(points: np.ndarray, cell: float) -> np.ndarray:
    """(M, 3): one of ``points`` per occupied cube of edge ``cell`` (first in input order)."""
    return points[decimate_index(points, cell)]


def decimate_index(points: np.ndarray, cell: float) -> np.ndarray:
    """(M,) intp, increasing: the indices of :func:`decimate`'s points in ``points``."""
    q = np.floor(points / cell).astype(np.int64)
    q -= q.min(axis=0)
    k = (q[:, 0] * (q[:, 1].max() + 1) + q[:, 1]) * (q[:, 2].max() + 1) + q[:, 2]
    _, first = np.unique(k, return_index=True)
    return np.sort(first)


class Patch:
    """A part's surface samples with their hull vertices and a KD-tree, so the concavity of a
    union of patches costs a hull of a few hundred points instead of all samples.

    Parameters
    ----------
    points : (N, 3) float64
        Surface samples, voxel units.
    """

    def __init__(self, points: np.ndarray):
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.tree = cKDTree(self.points)
        self.hull_points = self.points[_hull_vertices(self.points, np.arange(len(self.points)))]


def union_concavity(
    patches: list[Patch],
    *,
    sdf: np.ndarray | None = None,
    spacing: float = 1.0,
    limit: float = np.inf,
) -> float:
    """:func:`hull_concavity` of the union of ``patches``' samples, from their parts.

    Stops early, returning a value above ``limit``, once the answer is known to exceed it.
    """
    corners = np.concatenate([p.hull_points for p in patches])
    cost, _ = _hull_cost(
        corners, [p.points for p in patches], lambda: [p.tree for p in patches], spacing, sdf, limit
    )
    return cost


def _hull_cost(corners, samples, trees, spacing, sdf, limit) -> tuple[float, ConvexHull | None]:
    """:func:`_to_hull` of the samples to the hull of ``corners``, and that hull; (0, None)
    where the corners span no volume (flat: nothing concave).
    """
    if len(corners) < 4:
        return 0.0, None
    try:
        hull = ConvexHull(corners)
    except (QhullError, ValueError):
        return 0.0, None
    return _to_hull(hull, corners, samples, trees, spacing, sdf, limit), hull


class UnionCosts:
    """Concavity of unions of parts' patches, computed where the patches are not objects but
    index lists, so that worker processes can share them (see :func:`labels.merge_convex`).

    A part is a list of *atoms* (the parts it started as, whose samples never change) and the
    indices of its hull vertices; a union's hull is the hull of both parts' hull vertices.

    Parameters
    ----------
    points : (N, 3) float64
        Every atom's surface samples, atom after atom (voxel units).
    start : (A + 1,) int64
        Atom ``a``'s samples are ``points[start[a]:start[a + 1]]``.
    sdf : (X, Y, Z) float
        Signed distance in voxels.
    limit : float
        As :func:`union_concavity`'s.

    Called with ``("hull", a)``: (H,) int64, atom ``a``'s hull vertices (thinned as
    :class:`Patch`'s). With ``("union", parts)``, ``parts`` a list of (key, atoms,
    hull) (a key names a part's current state, e.g. (part, version)): the concavity of the
    parts' union and the union's hull vertices, thinned (the hull of the merged part).
    """

    _KEEP = 256  # parts whose samples and KD-tree stay cached

    def __init__(self, points: np.ndarray, start: np.ndarray, sdf: np.ndarray, limit: float):
        self.points, self.start, self.sdf, self.limit = points, start, sdf, limit
        self._cache: dict = {}

    def __call__(self, task: tuple):
        """Run one ``("hull", a)`` or ``("union", parts)`` task (see the class)."""
        if task[0] == "hull":
            a = task[1]
            return _hull_vertices(self.points, np.arange(self.start[a], self.start[a + 1]))
        parts = [self._part(key, atoms) for key, atoms, _ in task[1]]
        idx = np.concatenate([h for _, _, h in task[1]])
        cost, hull = _hull_cost(
            self.points[idx],
            [pts for pts, _ in parts],
            lambda: [tree for _, tree in parts],
            1.0,
            self.sdf,
            self.limit,
        )
        return cost, _thin(self.points, idx if hull is None else idx[hull.vertices])

    def _part(self, key, atoms):
        got = self._cache.get(key)
        if got is None:
            pts = np.concatenate([self.points[self.start[a] : self.start[a + 1]] for a in atoms])
            got = self._cache[key] = (pts, cKDTree(pts))
            if len(self._cache) > self._KEEP:
                del self._cache[next(iter(self._cache))]  # the oldest: parts only grow
        return got


def _hull_vertices(points: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """(H,) int64: the indices of ``idx`` whose points are hull vertices, thinned."""
    try:
        idx = idx[ConvexHull(points[idx]).vertices]
    except (QhullError, ValueError):
        pass
    return _thin(points, idx)


def _thin(points: np.ndarray, idx: np.ndarray) -> np.ndarray:
    # a curved patch has most of its samples on its hull: one per 1.5-voxel cell moves the hull
    # by a fraction of a voxel and keeps union hulls cheap
    return idx[decimate_index(points[idx], 1.5)] if len(idx) > 200 else idx


def vertex_labels(csdf: CSDF, labels: np.ndarray, mesh) -> np.ndarray:
    """(V,) int: each marching-cubes vertex takes the label of the inside end of its grid edge.

    A vertex lies on the edge between an inside and an outside voxel; the inside voxel's label
    is the reliable one (voxels in the air between two close pieces may belong to either).
    """
    ijk = vertex_voxels(csdf, mesh)
    return np.asarray(labels)[ijk[:, 0], ijk[:, 1], ijk[:, 2]]


def vertex_voxels(csdf: CSDF, mesh) -> np.ndarray:
    """(V, 3) intp: the inside end of each marching-cubes vertex's grid edge (its voxel)."""
    v = csdf.world_to_index(mesh.vertices)
    lo = np.floor(v + 1e-6).astype(np.intp)
    hi = np.ceil(v - 1e-6).astype(np.intp)
    for a in range(3):
        np.clip(lo[:, a], 0, csdf.shape[a] - 1, out=lo[:, a])
        np.clip(hi[:, a], 0, csdf.shape[a] - 1, out=hi[:, a])
    s_lo = csdf.sdf[lo[:, 0], lo[:, 1], lo[:, 2]]
    s_hi = csdf.sdf[hi[:, 0], hi[:, 1], hi[:, 2]]
    return np.where((s_lo <= s_hi)[:, None], lo, hi)


def surface_samples(csdf: CSDF, labels: np.ndarray, *, mesh=None) -> dict[int, np.ndarray]:
    """Each part's patch of the surface: part -> (N, 3) float64 points in voxel-index units.

    Marching-cubes vertices (labelled by :func:`vertex_labels`) and face centroids (labelled by
    the majority of their vertices), samples about half a voxel apart.
    """
    if mesh is None:
        mesh = to_mesh(csdf)
    vlab = vertex_labels(csdf, labels, mesh)
    f = vlab[mesh.faces]
    flab = np.where((f[:, 1] == f[:, 2]) & (f[:, 0] != f[:, 1]), f[:, 1], f[:, 0])
    idx = csdf.world_to_index(np.concatenate([mesh.vertices, mesh.triangles_center]))
    lab = np.concatenate([vlab, flab])
    out: dict[int, np.ndarray] = {}
    order = np.argsort(lab, kind="stable")
    uniq, start = np.unique(lab[order], return_index=True)
    for p, s, e in zip(uniq, start, [*start[1:], len(order)], strict=True):
        if p >= 0:
            out[int(p)] = idx[order[s:e]]
    return out


def touching_pairs(csdf: CSDF, labels: np.ndarray, *, mesh=None) -> set[tuple[int, int]]:
    """Pairs (p, q), p < q, of parts that meet: on the surface (a marching-cubes edge between
    their patches) or inside the solid (face-adjacent inside voxels).
    """
    labels = np.asarray(labels)
    if mesh is None:
        mesh = to_mesh(csdf)
    vlab = vertex_labels(csdf, labels, mesh).astype(np.int64)
    e = vlab[mesh.edges_unique]
    keys = [np.minimum(e[:, 0], e[:, 1]) * 65536 + np.maximum(e[:, 0], e[:, 1])]
    keys[0] = keys[0][(e[:, 0] != e[:, 1]) & (e.min(axis=1) >= 0)]
    inside = csdf.sdf <= 0
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
    mesh : trimesh.Trimesh, optional
        The object's marching-cubes surface, if already made (:func:`partscale.surface.to_mesh`).

    Returns
    -------
    (P,) float64
        Part ``p``'s concavity at index ``p``; 0 for a part with no surface.

    Examples
    --------
    Each bar of a row is convex:

    >>> from partscale import segment, shapes
    >>> row, _ = shapes.bars(2, width=0.2, gap=0.1, height=0.5, depth=0.3, voxel_size=0.05)
    >>> bool((segment.part_concavities(segment.segment(row)) < 0.5).all())
    True
    """
    labels = np.asarray(csdf.parts if parts is None else parts)
    n = int(labels.max()) + 1 if labels.size and labels.max() >= 0 else 0
    pts = surface_samples(csdf, labels, mesh=mesh)
    sdf = csdf.sdf / csdf.voxel_size
    return np.array([hull_concavity(pts[p], sdf=sdf) if p in pts else 0.0 for p in range(n)])


def concavity(csdf: CSDF, part_index: int) -> float:
    """Concavity of one part of a segmented CSDF, in voxels.

    Parameters
    ----------
    csdf : CSDF
        A segmented CSDF (:func:`segment`).
    part_index : int
        The part, ``0 .. csdf.n_parts - 1``.

    Returns
    -------
    float
        How far the part's surface is from its convex hull (see the module's definition).

    Raises
    ------
    IndexError
        When ``part_index`` is not a part of ``csdf``.

    Examples
    --------
    >>> from partscale import segment, shapes
    >>> box = segment.segment(shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1))
    >>> round(segment.concavity(box, 0), 3)
    0.0
    """
    if not 0 <= part_index < csdf.n_parts:
        raise IndexError(f"part_index: expected 0..{csdf.n_parts - 1}, got {part_index}")
    pts = surface_samples(csdf, csdf.parts)
    if part_index not in pts:
        return 0.0
    return hull_concavity(pts[part_index], sdf=csdf.sdf / csdf.voxel_size)
