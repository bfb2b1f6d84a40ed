"""From a decomposition to voxel labels: nearest surface point, connectivity, convex merging.

Every method ends with labels on the marching-cubes faces; these functions turn them into the
CSDF's ``parts`` grid the same way for all methods, so methods differ only in where they cut.
"""

from __future__ import annotations

import heapq

import numba
import numpy as np
from scipy import ndimage
from scipy.spatial import ConvexHull, QhullError, cKDTree

from .._workers import thread_map, worker_pool
from ..color import palette
from ..csdf import BAND_VOXELS, CSDF
from .concavity import (
    Patch,
    UnionCosts,
    decimate,
    surface_samples,
    touching_pairs,
    union_concavity,
    vertex_voxels,
)
from .fast import absorb_slivers

_FULL = np.ones((3, 3, 3), bool)  # 26-connectivity


def voxels_from_faces(
    csdf: CSDF, mesh, face_labels: np.ndarray, *, inside: np.ndarray | None = None
) -> np.ndarray:
    """(X, Y, Z) int32 labels: the label of the nearest surface point, -1 beyond
    :data:`partscale.csdf.BAND_VOXELS`.

    Parameters
    ----------
    csdf : CSDF
    mesh : trimesh.Trimesh
        ``to_mesh(csdf)``; its face centroids stand for the surface (faces are < 1 voxel).
    face_labels : (F,) int
        Part of each face, >= 0.
    inside : (X, Y, Z) int, optional
        Labels of the inside voxels (``sdf <= 0``) when the method knows them; only the voxels
        outside then take the nearest surface point's.
    """
    centres = csdf.world_to_index(mesh.triangles_center)
    near = csdf.sdf < BAND_VOXELS * csdf.voxel_size
    labels = np.full(csdf.shape, -1, np.int32)
    if inside is not None:
        solid = csdf.sdf <= 0
        labels[solid] = inside[solid]
        near &= ~solid
    ijk = np.argwhere(near)
    _, nearest = cKDTree(centres).query(ijk, workers=-1)
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


def join_specks(csdf: CSDF, labels: np.ndarray, min_inside: int) -> tuple[np.ndarray, int]:
    """Parts with fewer than ``min_inside`` inside voxels joined to the part they touch most, or
    the nearest one when they touch none.

    On a rough surface such a part is a bump of relief the cuts isolated, or a crumb of the band
    the relief cut off (a few outside voxels at its edge), not something a user can act on.

    Returns
    -------
    (X, Y, Z) int32 labels, renumbered; the number of parts joined.
    """
    n = int(labels.max()) + 1
    lab = np.asarray(labels, np.int32) + 1  # absorb_slivers' convention: 0 is none
    solid = csdf.sdf <= 0
    lab = absorb_slivers(lab, n, min_inside, size=np.bincount(lab[solid], minlength=n + 1))
    # what is left is touching nothing: the nearest voxel of a part that is no speck, looked
    # for in the speck's box grown by the band (a crumb lies within it of the surface)
    count = np.bincount(lab.ravel(), minlength=n + 1)
    inside = np.bincount(lab[solid], minlength=n + 1)
    speck = (count > 0) & (inside < min_inside)
    speck[0] = False
    if speck.sum() < (count[1:] > 0).sum():  # else there is nothing to join them to
        for c, sl in enumerate(ndimage.find_objects(lab), start=1):
            if sl is None or not speck[c]:
                continue
            grown = tuple(
                slice(max(x.start - 2 * BAND_VOXELS, 0), min(x.stop + 2 * BAND_VOXELS, dim))
                for x, dim in zip(sl, lab.shape, strict=True)
            )
            box = lab[grown]
            other = (box > 0) & ~speck[box]
            if not other.any():
                continue
            _d, near = ndimage.distance_transform_edt(~other, return_indices=True)
            here = box == c
            box[here] = box[tuple(ix[here] for ix in near)]
    out = renumber(lab - 1)
    return out, n - (int(out.max()) + 1)


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


_AHEAD = 16
"""Stale merge costs refreshed ahead of their turn, in parallel, by :func:`merge_convex`."""


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
    samples = surface_samples(csdf, labels, mesh=mesh)
    chunks = [decimate(samples[p], 1.0) if p in samples else np.empty((0, 3)) for p in range(n)]
    start = np.concatenate([[0], np.cumsum([len(c) for c in chunks])]).astype(np.int64)
    points = np.concatenate(chunks)
    has = {p for p in range(n) if start[p + 1] > start[p]}  # parts with a surface patch
    neighbours: dict[int, set[int]] = {p: set() for p in range(n)}
    pairs = sorted(touching_pairs(csdf, labels, mesh=mesh))
    for p, q in pairs:
        neighbours[p].add(q)
        neighbours[q].add(p)
    # above the tolerance the exact value only orders merges forced by max_parts
    limit = tolerance if max_parts is None else np.inf
    with worker_pool(UnionCosts, points, start, csdf.sdf / csdf.voxel_size, limit) as run:
        parent = _merge_greedy(run.map, n, has, neighbours, pairs, tolerance, max_parts)
    lut = np.append(parent, -1).astype(np.int32)
    return renumber(lut[labels])


def _merge_greedy(run, n, has, neighbours, pairs, tolerance, max_parts) -> np.ndarray:
    """:func:`merge_convex`'s loop over parts ``0..n-1``; ``has``: those with a patch.

    ``run`` computes :class:`UnionCosts` tasks (in worker processes). Returns (n,) int64: the
    part each part ended in.
    """
    atoms = {p: [p] for p in range(n)}
    version = dict.fromkeys(range(n), 0)
    has = set(has)
    hull = dict(zip(sorted(has), run([("hull", p) for p in sorted(has)]), strict=True))

    def costs(keys: list) -> dict:
        """{(p, q, vp, vq): (concavity of the union of p and q, its hull)}; a part without a
        patch adds nothing, and two of them cost nothing.
        """
        sides = [
            [((r, v), atoms[r], hull[r]) for r, v in ((p, vp), (q, vq)) if r in has]
            for p, q, vp, vq in keys
        ]
        todo = [i for i, side in enumerate(sides) if side]
        out = dict.fromkeys(keys, (0.0, None))
        out.update(
            zip([keys[i] for i in todo], run([("union", sides[i]) for i in todo]), strict=True)
        )
        return out

    # Costs are computed side by side where they are independent; the merges happen in the
    # order of computing them one at a time, so the parts do not depend on timing.
    known = costs([(p, q, 0, 0) for p, q in pairs])
    heap = [(known[p, q, 0, 0][0], p, q, 0, 0) for p, q in pairs]
    heapq.heapify(heap)
    alive = set(range(n))
    parent = np.arange(n)
    while heap:
        cost, p, q, vp, vq = heapq.heappop(heap)
        if p not in alive or q not in alive:
            continue
        if cost > tolerance and (max_parts is None or len(alive) <= max_parts):
            # every queued cost is at least this one; refreshing a stale one rarely lowers it
            break
        key = (p, q, version[p], version[q])
        if (vp, vq) != key[2:]:
            # Lazy update: a part grew since this cost was computed. Growing rarely makes a
            # union more convex, so the old cost orders the queue and is refreshed only here,
            # together with the next few stale ones (their costs wait in ``known``).
            if key not in known:
                ahead = [key]
                for _c, a, b, va, vb in heapq.nsmallest(_AHEAD, heap):
                    k = (a, b, version[a], version[b])
                    if a in alive and b in alive and (va, vb) != k[2:] and k not in known:
                        ahead.append(k)
                known.update(costs(list(dict.fromkeys(ahead))))
            heapq.heappush(heap, (known[key][0], p, q, *key[2:]))
            continue
        if q in has:
            hull[p] = known[key][1] if p in has else hull[q]
            has.add(p)
            has.discard(q)
        atoms[p] = atoms[p] + atoms.pop(q)
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
    return parent


def _part_graph(csdf: CSDF, mesh, labels: np.ndarray):
    """What the merges after :func:`merge_convex` start from.

    Returns a writeable int32 copy of ``labels``; each marching-cubes vertex's voxel ``ijk``
    (V, 3), position ``pts`` (V, 3) in voxel units and label ``vlab`` (V,); and the touching
    parts ``nbrs`` {part: set of parts}.
    """
    out = np.asarray(labels, dtype=np.int32).copy()
    ijk = vertex_voxels(csdf, mesh)
    pts = csdf.world_to_index(mesh.vertices)
    vlab = out[ijk[:, 0], ijk[:, 1], ijk[:, 2]]
    nbrs: dict[int, set[int]] = {}
    for p, q in touching_pairs(csdf, out, mesh=mesh):
        nbrs.setdefault(p, set()).add(q)
        nbrs.setdefault(q, set()).add(p)
    return out, ijk, pts, vlab, nbrs


def merge_across_junctions(
    csdf: CSDF, mesh, labels: np.ndarray, *, tolerance: float, min_voxels: int = 32
) -> np.ndarray:
    """Join two parts that a third one separates, where the third only crosses their hull.

    At a T-junction of boards (a shelf meeting a side panel) the panel is cut above and below the
    shelf, and the slice of panel between the cuts may join the shelf as well as the panel
    pieces; once it went to the shelf, the panel pieces no longer touch and
    :func:`merge_convex` keeps them apart. Here two parts ``a``, ``b`` that do not touch but
    both touch a part ``s`` become one, together with ``s``'s voxels inside the convex hull of
    their surface, when that union and what is left of ``s`` are each convex within
    ``tolerance`` voxels and ``s`` stays in one piece.

    Parameters
    ----------
    labels : (X, Y, Z) int
        Parts 0..P-1, -1 where none.
    tolerance : float
        Voxels of concavity the union and what is left of ``s`` may each have.
    min_voxels : int
        :func:`make_connected`'s, for the pieces the merges leave.

    Returns
    -------
    (X, Y, Z) int32 labels, renumbered.
    """
    j = _Junctions(csdf, mesh, labels, tolerance)
    j.prefetch()
    tried: set[tuple[int, int, int]] = set()
    todo = sorted(j.nbrs)
    while todo:
        s = todo.pop(0)
        if s not in j.nbrs:
            continue
        a = j.first_merge(s, tried)
        if a is not None:
            todo.extend(sorted({s, a} | j.nbrs[a]))
    return make_connected(j.out, min_voxels=min_voxels)


class _Junctions:
    """The parts :func:`merge_across_junctions` merges, and what it knows of them.

    Attributes
    ----------
    out : (X, Y, Z) int32
        The labels, merged in place.
    ijk, pts : (V, 3)
        Each marching-cubes vertex's voxel and position (voxel units).
    nbrs : dict of int to set of int
        The touching parts.
    verts : dict of int to (n,) int
        Each part's vertices (indices into ``ijk``, ``pts``).
    box : dict of int to (2, 3) int
        Each part's voxel box: first corner, one past the last.
    patches : dict of int to Patch
        Each part's surface patch, made when first needed, dropped when the part changes.
    gen, cheap : dict
        How many times each part changed, and the pair tests made per generation.
    """

    def __init__(self, csdf: CSDF, mesh, labels: np.ndarray, tolerance: float) -> None:
        self.out, self.ijk, self.pts, vlab, self.nbrs = _part_graph(csdf, mesh, labels)
        self.sdf = csdf.sdf / csdf.voxel_size
        self.inside = csdf.sdf <= 0
        self.tolerance = tolerance
        order = np.argsort(vlab, kind="stable")
        uniq, starts = np.unique(vlab[order], return_index=True)
        self.verts = {
            int(p): order[i:j]
            for p, i, j in zip(uniq, starts, [*starts[1:], len(order)], strict=True)
            if p >= 0
        }
        self.box = {
            p: np.array([[x.start for x in sl], [x.stop for x in sl]])
            for p, sl in enumerate(ndimage.find_objects(self.out + 1))
            if sl is not None
        }
        self.patches: dict[int, Patch] = {}
        self.gen: dict[int, int] = {}
        self.cheap: dict[tuple[int, int, int, int], bool] = {}

    def patch_of(self, p: int) -> Patch | None:
        """Part ``p``'s surface patch (None with fewer than 4 vertices)."""
        if len(self.verts.get(p, ())) < 4:
            return None
        return Patch(decimate(self.pts[self.verts[p]], 1.0))

    def patch(self, p: int) -> Patch | None:
        """:meth:`patch_of`, kept until the part changes."""
        if p not in self.patches:
            made = self.patch_of(p)
            if made is None:
                return None
            self.patches[p] = made
        return self.patches[p]

    def convex(self, group: list[Patch]) -> bool:
        """Whether the union of ``group`` is convex within the tolerance."""
        cost = union_concavity(group, sdf=self.sdf, spacing=1.0, limit=self.tolerance)
        return cost <= self.tolerance

    def pair_convex(self, a: int, b: int, pa: Patch, pb: Patch) -> bool:
        """:meth:`convex` of parts ``a`` and ``b``, kept until either changes."""
        key = (a, b, self.gen.get(a, 0), self.gen.get(b, 0))
        if key not in self.cheap:
            self.cheap[key] = self.convex([pa, pb])
        return self.cheap[key]

    def thickness(self, s: int) -> int:
        """The slice of a board that ``s`` took at the junction is no thicker than ``s``: its
        box's least side, and a voxel each side.
        """
        return (self.box[s][1] - self.box[s][0]).min() + 2

    def gap(self, a: int, b: int) -> int:
        """The voxels between the boxes of ``a`` and ``b`` (their largest gap along an axis)."""
        box = self.box
        return np.maximum(box[a][0] - box[b][1], box[b][0] - box[a][1]).max()

    def prefetch(self) -> None:
        """The cheap test (are ``a`` and ``b`` convex together?) for every pair the first pass
        will meet, computed side by side beforehand (a merge makes its parts' answers stale).
        """
        first: set[tuple[int, int]] = set()
        for s in self.nbrs:
            thick = self.thickness(s)
            around = sorted(self.nbrs[s])
            for i, a in enumerate(around):
                for b in around[i + 1 :]:
                    if b not in self.nbrs[a] and self.gap(a, b) <= thick:
                        first.add((a, b))
        first_list = sorted(first)
        needed = sorted({p for ab in first_list for p in ab} - set(self.patches))
        for p, made in zip(needed, thread_map(self.patch_of, needed), strict=True):
            if made is not None:
                self.patches[p] = made
        testable = [(a, b) for a, b in first_list if a in self.patches and b in self.patches]
        tests = thread_map(
            lambda ab: self.convex([self.patches[ab[0]], self.patches[ab[1]]]), testable
        )
        self.cheap = {(a, b, 0, 0): v for (a, b), v in zip(testable, tests, strict=True)}

    def first_merge(self, s: int, tried: set[tuple[int, int, int]]) -> int | None:
        """Merge the first pair of parts around ``s`` that :meth:`try_merge` allows (not
        ``tried`` before, not touching, close); the part they became, or None.
        """
        thick = self.thickness(s)
        around = sorted(self.nbrs[s])
        for i, a in enumerate(around):
            for b in around[i + 1 :]:
                if b in self.nbrs[a] or (s, a, b) in tried:
                    continue
                tried.add((s, a, b))
                if self.gap(a, b) <= thick and self.try_merge(s, a, b):
                    return a
        return None

    def try_merge(self, s: int, a: int, b: int) -> bool:
        """Merge ``a``, ``b`` and ``s``'s voxels in their hull where the union and what is left
        of ``s`` are each convex and ``s`` stays one piece; whether it did.
        """
        pa, pb = self.patch(a), self.patch(b)
        # s's slice between them is solid, so it leaves their union's concavity alone
        # (hull points inside the solid do not count): a cheap test first
        if pa is None or pb is None or not self.pair_convex(a, b, pa, pb):
            return False
        moved = self.hull_slice(s, a, b, pa, pb)
        if moved is None:
            return False
        mine = self.verts[s]
        local = self.ijk[mine] - self.box[s][0]
        goes = moved[local[:, 0], local[:, 1], local[:, 2]]
        group = [pa, pb]
        if goes.sum() >= 4:
            group.append(Patch(decimate(self.pts[mine[goes]], 1.0)))
        if not self.convex(group):
            return False
        if (~goes).sum() >= 4 and not self.convex([Patch(decimate(self.pts[mine[~goes]], 1.0))]):
            return False
        self.merge(s, a, b, moved, goes)
        return True

    def hull_slice(self, s: int, a: int, b: int, pa: Patch, pb: Patch) -> np.ndarray | None:
        """(box of ``s``) bool: ``s``'s voxels strictly inside the hull of ``a`` and ``b``;
        None where there are none, all of ``s``, or what is left of ``s`` falls apart.
        """
        box = self.box
        try:
            eq = ConvexHull(np.concatenate([pa.hull_points, pb.hull_points])).equations
        except (QhullError, ValueError):
            return None
        sl = tuple(slice(lo, hi) for lo, hi in box[s].T)
        here = self.out[sl] == s
        # only s's voxels in the box around a and b can lie in their hull
        lo = np.maximum(np.minimum(box[a][0], box[b][0]) - 1, box[s][0]) - box[s][0]
        hi = np.minimum(np.maximum(box[a][1], box[b][1]) + 1, box[s][1]) - box[s][0]
        if (hi <= lo).any():
            return None
        near = tuple(slice(x, y) for x, y in zip(lo, hi, strict=True))
        own = np.argwhere(here[near]) + lo
        # strictly inside: a margin took the voxels of s just beside the board's face
        # (half a voxel out), and the board's hull then bulged over its whole face
        move = _in_hull((own + box[s][0]).astype(np.float64), eq, 0.0)
        if not move.any() or move.sum() == here.sum():
            return None
        moved = np.zeros(here.shape, bool)
        moved[tuple(own[move].T)] = True
        _, pieces = ndimage.label(here & ~moved & self.inside[sl], structure=_FULL)
        return None if pieces > 1 else moved

    def merge(self, s: int, a: int, b: int, moved: np.ndarray, goes: np.ndarray) -> None:
        """``b`` and ``s``'s ``moved`` voxels (its vertices ``goes``) become ``a``."""
        box, out, nbrs = self.box, self.out, self.nbrs
        sl = tuple(slice(lo, hi) for lo, hi in box[s].T)
        out[sl][moved] = a
        sb = tuple(slice(lo, hi) for lo, hi in box[b].T)
        out[sb][out[sb] == b] = a
        mine = self.verts[s]
        self.verts[a] = np.concatenate([self.verts[a], self.verts.pop(b), mine[goes]])
        self.verts[s] = mine[~goes]
        box[a] = np.array([np.minimum(box[a][0], box[b][0]), np.maximum(box[a][1], box[b][1])])
        for p in (a, b, s):
            self.patches.pop(p, None)
            self.gen[p] = self.gen.get(p, 0) + 1
        for r in nbrs.pop(b):
            nbrs[r].discard(b)
            if r != a:
                nbrs[r].add(a)
                nbrs[a].add(r)


def merge_planar_groups(
    csdf: CSDF,
    mesh,
    labels: np.ndarray,
    *,
    tolerance: float,
    thickness: float = 4.0,
    min_group: int = 4,
) -> np.ndarray:
    """Join each group of at least ``min_group`` touching parts lying in one thin slab (a board's
    plane) into one part, when their union is convex within ``tolerance`` voxels.

    A railing (stringer, balusters, handrail) or a row of slats is many thin pieces in one
    plane: pairwise merging stops at the first two (a baluster on a long stringer leaves a
    wide triangle of air in their hull), yet the whole comb is nearly convex, its gaps being
    narrow. Groups are grown through touching parts from a part at most ``thickness`` voxels
    thick along a grid axis, taking the parts inside that slab (one voxel of slack) only.

    Parameters
    ----------
    labels : (X, Y, Z) int
        Parts 0..P-1, -1 where none.
    tolerance : float
        Voxels of concavity the union of a group may have.
    thickness : float
        Voxels: how thick the part a group grows from may be.
    min_group : int
        Fewest parts a group holds.

    Returns
    -------
    (X, Y, Z) int32 labels, renumbered.
    """
    out, _ijk, pts, vlab, nbrs = _part_graph(csdf, mesh, labels)
    sdf = csdf.sdf / csdf.voxel_size
    # extents of the parts' inside voxels (labels reach BAND_VOXELS voxels into the air too)
    box = {
        p: np.array([[x.start for x in sl], [x.stop - 1 for x in sl]])
        for p, sl in enumerate(ndimage.find_objects(np.where(csdf.sdf <= 0, out + 1, 0)))
        if sl is not None
    }
    patches = {p: Patch(decimate(pts[vlab == p], 1.0)) for p in box if (vlab == p).sum() >= 4}
    seen: set[frozenset] = set()
    merged: dict[int, int] = {}
    for ax in range(3):
        for p in sorted(box, key=lambda p: -(box[p][1] - box[p][0]).prod()):
            if p in merged:
                continue
            lo, hi = box[p][0][ax], box[p][1][ax]
            if hi - lo + 1 > thickness:
                continue
            members = {
                q
                for q in box
                if q not in merged and box[q][0][ax] >= lo - 1 and box[q][1][ax] <= hi + 1
            }
            group, front = {p}, [p]
            while front:
                r = front.pop()
                for q in nbrs.get(r, ()):
                    if q in members and q not in group:
                        group.add(q)
                        front.append(q)
            key = frozenset(group)
            if len(group) < min_group or key in seen or not all(q in patches for q in group):
                continue
            seen.add(key)
            c = union_concavity([patches[q] for q in group], sdf=sdf, spacing=1.0, limit=tolerance)
            if c <= tolerance:
                for q in group:
                    merged[q] = p
    lut = np.arange(int(out.max()) + 2, dtype=np.int32)
    for q, p in merged.items():
        lut[q] = p
    lut[-1] = -1
    return renumber(lut[out])


@numba.njit(cache=True, nogil=True)
def _in_hull(pts: np.ndarray, eq: np.ndarray, margin: float) -> np.ndarray:  # pragma: no cover
    # (N,) bool: within ``margin`` of the hull with facet planes ``eq`` (n . x + d <= 0 inside);
    # a point is dropped at its first facet farther than the margin (most points are outside)
    out = np.ones(pts.shape[0], np.bool_)
    for i in range(pts.shape[0]):
        for j in range(eq.shape[0]):
            if (
                pts[i, 0] * eq[j, 0] + pts[i, 1] * eq[j, 1] + pts[i, 2] * eq[j, 2] + eq[j, 3]
                > margin
            ):
                out[i] = False
                break
    return out


def parts_info(csdf: CSDF, mesh, labels: np.ndarray) -> list[dict]:
    """Per-part facts: index, labelled voxel count, world bbox of the part's surface patch,
    world volume of the patch's convex hull, display colour.
    """
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
