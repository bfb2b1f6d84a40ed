"""The fast method: cut the voxel solid at its concave creases, then merge convex neighbours.

Furniture is mostly boards, legs and panels meeting at creases. Where a board meets a leg, the
solid's cross-section area along some axis jumps from one slice to the next (a leg's section to
a tabletop's). A region that is not yet convex (concavity above the tolerance) is cut at every
such jump along x, y and z at once, and its pieces (connected components of the cells between
cuts) are treated the same way, recursively. A concave region without such a jump (a bend, a
curved shell, a board turned off the grid axes) is cut once by a plane through its deepest
concavity, oriented along a grid or principal axis, whichever leaves the least concave pieces.

The pieces label the inside voxels exactly (only voxels outside the surface take their nearest
surface point's part), so a part's boundary is the cut itself and does not bleed across a
crease. Cutting at all creases at once over-segments on purpose (a side panel is chopped at
every shelf); three merges then join pieces back:

1. :func:`labels.merge_convex`: touching pieces, least concave union first, while the union is
   convex within the tolerance (restores whole legs and slabs);
2. :func:`labels.merge_across_junctions`: at a T-junction the slice of panel beside a shelf may
   have joined the shelf, leaving the panel pieces above and below apart; they join, with the
   slice, when both results stay convex (a bookcase side becomes one part again);
3. :func:`labels.merge_planar_groups`: four or more touching thin parts in one grid-aligned slab
   (a railing: stringer, balusters, handrail) whose union is convex within CoACD's own threshold
   in voxels (``group_scale``), which pairwise merging cannot reach (a baluster with the
   stringer leaves a wide triangle of air in their hull, the whole comb only narrow gaps).

The tolerance is CoACD's threshold read in voxels, ``threshold * scale * L`` for the object's
largest extent ``L`` in voxels (CoACD normalises the mesh to [-1, 1], so ``scale`` = 0.5 is its
own reading); ``scale`` = 0.3 (2.1 voxels at 128) cuts and merges finer than CoACD, whose parts
on these objects measure 0.8-3.3 voxels. On a rough surface (a completed scan's) every
tolerance grows by the relief's peak-to-valley (:mod:`partscale.segment.relief`); on clean
geometry by nothing.

Pieces are cut, and merge costs computed, in forked worker processes (one per core; threads
gained only 1.3x here, the hull and sampling code holds the GIL between compiled calls); results
are numbered and merged in the order one process would, so the parts do not depend on timing or
on the number of cores. Slivers a plane cut leaves at a curved shell's rim (under
``min_voxels``) join the piece they touch most instead of becoming parts to merge back.

Measured against CoACD at its defaults in one run (``bench/bench_segment.py``, the 9 objects at
128 voxels, 2026-11-22, 2-core x86-64; wall seconds, fast a median of 3, CPU in brackets
including worker processes)::

    object                  CoACD wall (cpu) parts  max  | fast wall (cpu) parts  max  | match
    kenney/table               15.4 (24.5)     8   1.99  |  0.8 (1.1)     8   0.52 | yes
    kenney/chair               18.1 (26.8)    12   1.95  |  0.6 (0.8)    10   0.57 | yes
    kenney/bookcaseOpen        18.3 (30.2)     8   1.53  |  0.9 (1.4)    11   1.22 | yes
    kenney/stairsOpen           8.8 (13.2)    11   0.75  |  0.4 (0.5)    11   0.75 | yes
    khronos/SheenChair         63.9 (103)     28   3.26  |  4.3 (6.6)    34   2.85 | yes
    sweethome3d/table          18.1 (23.1)    10   3.06  |  2.4 (2.6)     9   0.34 | yes
    sweethome3d/chair          10.9 (14.9)     9   1.06  |  0.7 (0.9)     9   0.75 | yes
    sweethome3d/bookcase       28.5 (45.7)    10   1.07  |  0.9 (1.2)    10   0.73 | yes
    sweethome3d/staircase      25.3 (35.3)    19   3.15  |  2.0 (2.9)    26   2.87 | yes

Max concavity no worse and at most 1.5x the parts on 9 of 9, every object within 5 s; median
0.9 s against 18 s (19x). So this is the default method
(:data:`partscale.segment.DEFAULT_METHOD`). The curved SheenChair (331 pieces before merging)
is the slowest, most of it in ``merge_convex``. Merges
test a union at the measure's own 1-voxel spacing: at 2 voxels a narrow air pocket under a
curved cushion went unseen and a merged part measured 5.2. Junction merges move only voxels
strictly inside the joined boards' hull; with half a voxel of slack the Sweet Home bookcase's
rounded shelf creases went to the panel and measured 1.075 against CoACD's 1.072.

Tried and dropped: labelling faces by the pieces' convex hulls as CoACD's are (parts leaked
more); giving pieces under 8-64 voxels to a neighbour before merging (about 20% faster on the
SheenChair, but the Kenney bookcase then merges to 1.53 voxels, just above CoACD's 1.5323);
only the deepest-point depth, or coarser samples, to choose planes (SheenChair parts 5-7
voxels concave); a larger tolerance (the Sweet Home chair merges a slat with a post at 2.8
voxels against CoACD's 1.06); a second merge up to the largest concavity already present
(little effect: 51 to 48 parts on the staircase).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from scipy.spatial import ConvexHull, QhullError

from .._options import count
from .._workers import worker_pool
from ..csdf import CSDF
from ..errors import InputError
from ..progress import ProgressCallback, resolve
from .concavity import decimate, deepest_point, hull_concavity

PARAMS = {
    "jump": 0.3,
    "min_jump": 0.05,
    "scale": 0.3,
    "max_depth": 16,
    "min_voxels": 27,
    "group_scale": 0.5,
    "thin": 4,
    "min_group": 4,
}
"""Options of the fast method.

jump : a cut where the section area changes by at least this fraction between two slices;
min_jump : ... and by at least this fraction of the region's largest section;
scale : concavity tolerance = ``threshold * scale * largest extent`` (voxels);
max_depth : recursion limit; min_voxels : smaller pieces are not split further;
group_scale : tolerance of a group merge (:func:`labels.merge_planar_groups`), as ``scale``;
thin : most voxels thick a slab of grouped parts is; min_group : fewest parts in such a group.
"""

_FULL = np.ones((3, 3, 3), bool)


def check_params(params: dict) -> dict:
    """Validate the fast method's options; returns them with defaults filled in."""
    out = dict(PARAMS)
    out.update(params)
    for name in ("jump", "min_jump"):
        v = float(out[name])
        if not 0 < v < 1:
            raise InputError(f"{name}: expected a number in (0, 1), got {out[name]!r}")
        out[name] = v
    for name in ("scale", "group_scale"):
        if not float(out[name]) > 0:
            raise InputError(f"{name}: expected a number > 0, got {out[name]!r}")
        out[name] = float(out[name])
    for name in ("max_depth", "min_voxels", "thin", "min_group"):
        out[name] = count(out[name], name)
    return out


def tolerance(csdf: CSDF, threshold: float, params: dict) -> float:
    """Concavity tolerance in voxels: ``threshold * scale *`` the solid's largest extent."""
    inside = np.argwhere(csdf.sdf <= 0)
    extent = float((inside.max(axis=0) - inside.min(axis=0) + 1).max())
    return threshold * params["scale"] * extent


def _region_concavity(mask: np.ndarray, limit: float = np.inf) -> float:
    """Concavity (voxels) of a voxel region, from the centres of its boundary voxels (one per
    2-voxel cell: enough to tell a region above the tolerance, which is 2 voxels or more).
    """
    return hull_concavity(decimate(_boundary(mask), 2.0), spacing=2.0, limit=limit)


def _boundary(mask: np.ndarray) -> np.ndarray:
    """(N, 3) float64: centres of the region's boundary voxels; a region one voxel thick
    (a slice cut from a curved shell) gets its two faces instead, so that its hull has volume
    and a bend within the slice counts.
    """
    interior = ndimage.binary_erosion(mask, border_value=0)
    pts = np.argwhere(mask & ~interior).astype(np.float64)
    for a in range(3):
        if mask.shape[a] == 1:
            pts = np.concatenate([pts, pts])
            pts[: len(pts) // 2, a] -= 0.5
            pts[len(pts) // 2 :, a] += 0.5
    return pts


def _cuts(mask: np.ndarray, jump: float, min_jump: float) -> list[np.ndarray]:
    """Per axis, indices t such that the region is cut between slices t and t + 1."""
    out = []
    for ax in range(3):
        other = tuple(a for a in range(3) if a != ax)
        area = mask.sum(axis=other).astype(np.float64)
        lo, hi = np.minimum(area[:-1], area[1:]), np.maximum(area[:-1], area[1:])
        rel = 1.0 - lo / np.maximum(hi, 1.0)
        big = (hi - lo) >= min_jump * area.max()
        # a crease is a step: the change between these two slices is at least twice the
        # change next to it (a rounded end changes area over many slices instead)
        side = np.maximum(np.pad(rel[:-1], (1, 0)), np.pad(rel[1:], (0, 1)))
        out.append(np.nonzero((rel >= jump) & big & (rel >= 2 * side))[0])
    return out


def _deepest_point(pts: np.ndarray) -> tuple[np.ndarray, float]:
    """The point of ``pts`` (N, 3) deepest inside their convex hull, and its depth."""
    try:
        hull = ConvexHull(pts)
    except (QhullError, ValueError):
        return pts.mean(axis=0), 0.0
    i, depth = deepest_point(pts, hull.equations)
    return pts[i], float(depth)


def _plane_pieces(mask: np.ndarray, min_size: int = 0) -> list[tuple[np.ndarray, tuple]]:
    """Split a concave region by the best plane through its deepest concavity.

    The deepest boundary voxel inside the region's convex hull sits in the crease or bend that
    makes the region concave. Planes through it, normal to each axis and to each principal
    axis of the region, are tried; the one whose pieces have the least worst concavity wins.
    Unlike a cut across a whole grid slice, a tilted plane splits a curved shell across its
    bend instead of peeling it slice by slice.
    """
    pts = _boundary(mask)
    if len(pts) < 8:
        return []
    centre, _ = _deepest_point(pts)
    vox = np.argwhere(mask).astype(np.float64)
    vox_pca = vox[:: len(vox) // 20000 + 1]
    _, _, axes = np.linalg.svd(vox_pca - vox_pca.mean(axis=0), full_matrices=False)
    normals = np.concatenate([np.eye(3), axes])
    # score each plane on the boundary voxels alone (a flat cut face adds nothing concave),
    # thinned to one per 2-voxel cell: the score only ranks the planes
    few = decimate(pts, 3.0) if len(pts) > 1000 else pts
    best_score, best_n = np.inf, None
    for n in normals:
        below = (few - centre) @ n <= 0
        cut = (vox_pca - centre) @ n <= 0  # the voxels, not the boundary, must be split
        if min(below.sum(), (~below).sum()) < 4 or cut.all() or not cut.any():
            continue
        # a plane can only win with both sides below the best score so far
        score = hull_concavity(few[below], spacing=3.0, limit=best_score)
        if score < best_score:
            score = max(score, hull_concavity(few[~below], spacing=3.0, limit=best_score))
        if score < best_score:
            best_score, best_n = score, n
    if best_n is None:
        return []
    i, j, k = np.ogrid[: mask.shape[0], : mask.shape[1], : mask.shape[2]]
    side = best_n[0] * (i - centre[0]) + best_n[1] * (j - centre[1]) + best_n[2] * (k - centre[2])
    lab = np.zeros(mask.shape, np.int32)
    n = 0
    for h in (mask & (side <= 0), mask & (side > 0)):
        comp, m = ndimage.label(h, structure=_FULL)
        lab[comp > 0] = comp[comp > 0] + n
        n += m
    lab = absorb_slivers(lab, n, min_size)
    pieces = []
    for sl_i, sl in enumerate(ndimage.find_objects(lab), start=1):
        if sl is not None:
            pieces.append((lab[sl] == sl_i, tuple(x.start for x in sl)))
    return pieces


def absorb_slivers(
    lab: np.ndarray, n: int, min_size: int, *, size: np.ndarray | None = None
) -> np.ndarray:
    """Join each labelled piece smaller than ``min_size`` voxels to the piece it touches most.

    A plane across a curved shell leaves slivers at its rim; as parts of their own they would
    only be merged back later, at a far higher cost. A sliver touching no piece stays.

    Parameters
    ----------
    lab : (X, Y, Z) int
        Labels ``1..n`` (0: none); changed in place.
    n : int
        The largest label.
    min_size : int
        Pieces with fewer voxels (or less ``size``) are joined.
    size : (n + 1,) int, optional
        Each label's size if not its voxel count (e.g. inside voxels only); a joined piece adds
        its size to its new one.

    Returns
    -------
    (X, Y, Z) int
        ``lab`` itself (changed), for chaining.

    Examples
    --------
    Two pieces of 27 voxels and a one-voxel sliver on the second one's face:

    >>> import numpy as np
    >>> from partscale import segment
    >>> lab = np.zeros((6, 3, 3), np.int64)
    >>> lab[:3], lab[3:], lab[3, 1, 1] = 1, 2, 3
    >>> np.bincount(segment.absorb_slivers(lab, 3, min_size=5).ravel()).tolist()
    [0, 27, 27]
    """
    if n < 2 or min_size <= 1:
        return lab
    count = np.bincount(lab.ravel(), minlength=n + 1)
    present = count > 0
    size = count if size is None else np.array(size, np.int64)
    order = np.argsort(size[1:], kind="stable") + 1
    small = [c for c in order if present[c] and size[c] < min_size]
    for c in small:
        if not present[c] or size[c] >= min_size:
            continue
        sl = ndimage.find_objects((lab == c).astype(np.int8))[0]
        grown = tuple(slice(max(x.start - 1, 0), x.stop + 1) for x in sl)
        here = lab[grown] == c
        ring = ndimage.binary_dilation(here) & ~here
        touch = lab[grown][ring]
        touch = touch[(touch > 0) & (touch != c)]
        if touch.size == 0:
            continue
        counts = np.bincount(touch, minlength=n + 1)
        best = int(np.argmax(counts))
        lab[grown][here] = best
        size[best] += size[c]
        present[c] = False
    return lab


def _split(mask: np.ndarray, cuts: list[np.ndarray]) -> list[tuple[np.ndarray, tuple]]:
    """Connected pieces of ``mask`` in the cells between cuts, as (sub-mask, offset)."""
    edges = [
        np.concatenate([[0], np.asarray(c, np.int64) + 1, [mask.shape[a]]])
        for a, c in enumerate(cuts)
    ]
    pieces = []
    for x0, x1 in zip(edges[0][:-1], edges[0][1:], strict=True):
        for y0, y1 in zip(edges[1][:-1], edges[1][1:], strict=True):
            for z0, z1 in zip(edges[2][:-1], edges[2][1:], strict=True):
                cell = mask[x0:x1, y0:y1, z0:z1]
                if not cell.any():
                    continue
                comp, _ = ndimage.label(cell, structure=_FULL)
                for c, sl in enumerate(ndimage.find_objects(comp), start=1):
                    sub = comp[sl] == c
                    off = (x0 + sl[0].start, y0 + sl[1].start, z0 + sl[2].start)
                    pieces.append((sub, off))
    return pieces


class _Cutter:
    """Cuts one region: ``(mask, depth)`` -> ``(final, pieces)``; final when the region is small,
    deep or convex enough, else ``pieces`` is a list of (sub-mask, offset).
    """

    def __init__(self, params: dict, tau: float):
        self.params, self.tau = params, tau

    def __call__(self, item: tuple[np.ndarray, int]) -> tuple[bool, list]:
        mask, depth = item
        params = self.params
        if (
            int(mask.sum()) < params["min_voxels"]
            or depth >= params["max_depth"]
            or _region_concavity(mask, limit=self.tau) <= self.tau
        ):
            return True, []
        cuts = _cuts(mask, params["jump"], params["min_jump"])
        pieces = (
            _split(mask, cuts)
            if any(len(c) for c in cuts)
            else _plane_pieces(mask, params["min_voxels"])
        )
        return len(pieces) <= 1, pieces


def atoms(
    csdf: CSDF,
    *,
    threshold: float,
    params: dict,
    floor: float = 2.0,
    noise: float = 0.0,
    progress: ProgressCallback | None = None,
) -> np.ndarray:
    """(X, Y, Z) int32: inside voxels cut into pieces at concave creases, -1 outside.

    Pieces are not yet merged: see the module's description. ``floor`` (voxels) is the least
    tolerance: below it, concavity measured on voxels is sampling noise. ``noise`` (voxels) is
    added to the tolerance: the concavity a rough surface's relief adds
    (:func:`partscale.segment.relief.noise_tolerance`).
    """
    report = resolve(progress)
    tau = max(tolerance(csdf, threshold, params), floor) + noise
    inside = csdf.sdf <= 0
    comp, _ = ndimage.label(inside, structure=_FULL)
    roots = [
        (comp[sl] == c, tuple(s.start for s in sl), 0)
        for c, sl in enumerate(ndimage.find_objects(comp), start=1)
    ]

    # Regions are independent: each is cut (in a worker process) as soon as its parent is.
    # Pieces are then numbered in the depth-first order of a one-at-a-time recursion, so the
    # result does not depend on timing.
    total = float(inside.sum())
    done = 0.0
    children: dict[int, list[int]] = {}
    items = list(roots)
    with worker_pool(_Cutter, params, tau) as workers:
        pending = {workers.submit((m, d)): i for i, (m, _o, d) in enumerate(items)}
        while pending:
            i = pending.pop((got := workers.next_done())[0])
            final, pieces = got[1]
            mask, off, depth = items[i]
            if final:
                done += int(mask.sum())
            else:
                children[i] = []
                for sub, o in pieces:
                    items.append((sub, (off[0] + o[0], off[1] + o[1], off[2] + o[2]), depth + 1))
                    children[i].append(len(items) - 1)
                    pending[workers.submit((sub, depth + 1))] = len(items) - 1
            report(done / total, f"cutting at creases ({len(items)} regions)")
    out = np.full(csdf.shape, -1, np.int32)
    n = 0
    stack = list(range(len(roots)))
    while stack:
        i = stack.pop()
        if i in children:
            stack.extend(children[i])
            continue
        mask, off, _depth = items[i]
        view = out[
            off[0] : off[0] + mask.shape[0],
            off[1] : off[1] + mask.shape[1],
            off[2] : off[2] + mask.shape[2],
        ]
        view[mask] = n
        n += 1
    report(1.0, f"cutting at creases ({n} pieces)")
    return out
