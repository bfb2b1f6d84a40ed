"""Coloured mesh -> CSDF: exact distances in a narrow band, robust sign, colour from the texture.

Method (what makes it robust on real assemblies of open and intersecting pieces)
---------------------------------------------------------------------------------
0. Two-sided faces. A triangle stored once per winding (exporters make faces two-sided that
   way) cancels in the winding number: where both its sides are outside and such faces close
   up a body, one copy of each is kept, wound as its neighbours are, so that the body is solid
   as a viewer shows it (:mod:`partscale.ingest._two_sided`).
1. Classification. Each triangle is classified by libigl's generalized winding number ``w``
   just in front of it. Crossing an oriented triangle against its normal raises ``w`` by
   exactly 1, so the front value ``lo`` (the lower side) says nearly all: ``|lo| <= 1/4``
   (outside on one side, inside on the other): a *boundary* of the solid, kept exactly;
   ``lo >= 3/4``: *buried* inside another piece, ignored; anything else (``lo`` fractional or
   below -1/4): an *open sheet* (cloth, a single-sided board). A boundary whose copy with the
   other winding lies on it reads the same behind it (``w`` steps by less than 1/2 across
   it, not by 1): an open sheet.
   Triangles longer than ``SUBDIVIDE`` voxels are also probed towards their corners; where
   the probes disagree (a board partly buried in another) they are split into pieces of
   ``SUBDIVIDE_MIXED`` voxels classified one by one.
   Above ``PROBE_RES`` voxels the classification keeps a ``PROBE_RES`` grid's scale: a
   piece's class is the same at every finer resolution.
2. Thin pieces. Open sheets, and closed pieces thinner than the grid can hold (shelves, back
   panels: inward ray to the next boundary shorter than ``2 t``), become solids of thickness
   ``2 t``, ``t = sqrt(3)/2`` voxel, so their inside voxels stay 6-connected and marching cubes
   has no holes. Thicker closed pieces keep their surface exactly (no offset).
3. Exact unsigned distances to boundary and to sheet pieces within a band of ``BAND_VOXELS``
   voxels (:data:`partscale.csdf.BAND_VOXELS`; numba, slabs along x in parallel, no races).
4. Sign: a voxel with no surface within one voxel has the sign of all its 6-neighbours, so the
   6-connected components of such voxels (the far field included; sheets and buried faces
   block them as much as boundaries, so a cushion with an open seam still encloses its inside
   and a buried face uncovered along a strip leaks nothing) share one sign, read
   from ``w > 1/2`` at a few voxels per component (at all of them when those disagree). The
   voxels left (inside boards a few voxels thick, in narrow gaps) are grouped by steps that
   cross no surface (``dist(p) + dist(q) > h``): enclosed groups take ``w`` at their three
   voxels farthest from the surface where those agree; the others are tested one by one.
5. ``sdf = min(signed boundary distance, sheet distance - offset)`` in the band; beyond it, the
   distance to the nearest surface of the nearest band voxel (a Euclidean feature transform).
6. Colour of a voxel = source colour at its nearest surface point (texture through the UVs),
   carried beyond the band by the same feature transform.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import cc3d
import numpy as np

from .._memory import check_memory
from .._options import MAX_RES, MIN_RES, check_res, keyword_options  # noqa: F401
from .._workers import launch_numba_threads
from ..csdf import BAND_VOXELS, CSDF, make
from ..errors import InputError, shown
from ..progress import ProgressCallback, resolve
from . import _distance, _far_field, _labels, _shading, _sign, _two_sided
from .mesh import ColoredMesh

SUBDIVIDE = 4.0  # triangles longer than this many probe voxels are also probed near their corners
SUBDIVIDE_MIXED = 2.0  # piece size (probe voxels) where a triangle is partly buried
PROBE_RES = 128
"""Finest grid the classification follows: at a finer ``--res`` its probes keep the offsets
and the spacing of a ``PROBE_RES`` grid, so every piece gets the class it gets there (a
property of the mesh, the same at every finer resolution, at a query count that does not grow
with the grid)."""
SLAB = 2  # x-layers per parallel work item
RANDOM_CHUNK = 1 << 20  # random draws per chunk when sampling the far field's components
BYTES_PER_VOXEL = 64  # peak working set of from_mesh per voxel (39-46 measured, temporaries too)
MAX_PAD = 4096
"""Largest ``--pad`` (same reason as :data:`MAX_RES`)."""


def check_pad(pad: int | None, what: str) -> int:
    """Validate ``--pad`` (an int in [BAND_VOXELS, :data:`MAX_PAD`]; None: the default)."""
    if pad is None:
        return BAND_VOXELS + 2
    if isinstance(pad, bool) or not isinstance(pad, int | np.integer):
        raise InputError(f"{what}: expected an integer pad, got {shown(pad)}", params=("pad",))
    pad = int(pad)
    if not BAND_VOXELS <= pad <= MAX_PAD:
        raise InputError(
            f"{what}: expected pad in [{BAND_VOXELS}, {MAX_PAD}] (at least the exact band), "
            f"got {shown(pad, 24)}",
            params=("pad",),
        )
    return pad


def grid_for_bounds(lo, hi, res: int, pad: int):
    """Cubic grid with ``res`` voxels along the longest side of ``[lo, hi]`` plus ``pad`` each side.

    Returns origin (3,) float64, voxel size h, shape (3,) int. The box is centred in the grid.
    """
    lo = np.asarray(lo, np.float64)
    hi = np.asarray(hi, np.float64)
    ext = hi - lo
    h = float(ext.max()) / res
    n = np.ceil(ext / h - 1e-9).astype(np.int64) + 1 + 2 * pad
    centre = (lo + hi) / 2
    origin = centre - (n - 1) / 2 * h
    return origin, h, n


CLASS_CUTS = (-0.25, 0.25, 0.75)
"""Winding-number values where a triangle's class changes (see :func:`classify_pieces`)."""
MAX_UNSURE_SHARE = 0.05
"""Largest share of a group of two-sided faces' area whose probes read a part of a whole
number (slivers along an open face's edge): more, and the group keeps every copy."""
INSIDE_CUTS = (0.5,)
"""Inside where ``w > 1/2``."""
STEP_CUT = 0.5
"""A face across which ``w`` steps by less than this bounds nothing (:func:`_bounding_nothing`)."""
FAST_ACCURACY = 1.5
"""libigl's ``accuracy_scale`` (its default is 2) for a first, cheaper pass: about half the
time; its values differed from the default's by at most 0.03 on the test objects."""
FULL_ACCURACY = 2.0
MARGIN = 0.1
"""First-pass values this close to a cut are recomputed at libigl's default accuracy, so every
decision is the one the default accuracy takes (the margin is over 3x the first pass's error)."""


class _Winding:
    """Generalized winding number of the mesh (V, F) at query points, (Q, 3) -> (Q,) float64.

    libigl's fast winding number with its hierarchy built once (on the first query) and
    reused by every later call: the plain ``igl.fast_winding_number`` rebuilds it per call
    (~40 ms+ each, and an import makes up to ~15 calls). Callers say which ``cuts`` they
    compare the values with: a cheaper pass decides everything farther than ``MARGIN`` from
    a cut, and only the rest is computed at libigl's default accuracy.
    """

    def __init__(self, V: np.ndarray, F: np.ndarray):
        self.V = V
        self.F = F
        self._bvh: Any = None  # igl.FastWindingNumberBVH once built (igl is untyped)

    def __call__(self, Q: np.ndarray, cuts: tuple[float, ...]) -> np.ndarray:
        import igl

        if len(Q) == 0:
            return np.zeros(0)
        if self._bvh is None:
            self._bvh = igl.FastWindingNumberBVH()
            self._bvh.init(self.V, self.F)
        Q = np.ascontiguousarray(Q, dtype=np.float64)
        w = self._bvh.winding_number(Q, FAST_ACCURACY)
        near = np.abs(w[:, None] - np.asarray(cuts)[None, :]).min(axis=1) < MARGIN
        if near.any():
            w[near] = self._bvh.winding_number(np.ascontiguousarray(Q[near]), FULL_ACCURACY)
        return w


def _class_of(lo: np.ndarray) -> np.ndarray:
    out = np.full(len(lo), 2, np.int8)
    out[(lo >= CLASS_CUTS[0]) & (lo <= CLASS_CUTS[1])] = 0
    out[lo >= CLASS_CUTS[2]] = 1
    return out


def probe_size(h: float, res: int) -> float:
    """Voxel size the classification probes follow at ``--res`` (see :data:`PROBE_RES`)."""
    return h * max(1.0, res / PROBE_RES)


def classify_pieces(wn: _Winding, h: float):
    """Distance primitives and their class (0 boundary, 1 buried, 2 open sheet, -1 degenerate).

    Lengths are in voxels of size ``h``, the probe voxel (:func:`probe_size`). Probes lie
    ``0.05 h`` in front of the surface. Every triangle is classified at its centroid;
    triangles longer than ``SUBDIVIDE`` also at three points towards their corners, and where
    those disagree (a board partly buried in another) they are bisected, and the halves
    probed again, down to pieces of ``SUBDIVIDE_MIXED`` near the curves where pieces intersect
    (surfaces are exact except within about a probe voxel of those curves). A triangle
    classified buried may still be uncovered along a strip the probes missed; the sign flood
    is blocked by buried faces too, so such a strip leaks nothing. Winding-number queries next
    to the surface are the expensive part of the import, so only as many as needed are made,
    as many at any resolution above ``PROBE_RES`` as at ``PROBE_RES``.

    Returns prim (P, 3, 3) float64, parent (P,) int64 (source triangle), corner_bary (P, 3, 3)
    (barycentrics of each primitive corner in its source triangle), cls (P,) int8 and front
    (P,) float64, ``w`` at the probe in front of each primitive's centroid (nan: degenerate).
    """
    tris = wn.V[wn.F]
    n_tri = len(tris)
    eps = 0.05 * h
    e1 = tris[:, 1] - tris[:, 0]
    e2 = tris[:, 2] - tris[:, 0]
    nrm = np.cross(e1, e2)
    ln = np.linalg.norm(nrm, axis=1)
    ok = ln > 1e-14 * max(1.0, float(np.abs(tris).max())) ** 2
    unit = np.zeros_like(nrm)
    unit[ok] = nrm[ok] / ln[ok, None]
    edge = np.stack(
        [np.linalg.norm(tris[:, (i + 1) % 3] - tris[:, i], axis=1) for i in range(3)], 1
    )
    big = np.nonzero(ok & (edge.max(axis=1) > SUBDIVIDE * h))[0]
    okid = np.nonzero(ok)[0]
    corner_w = np.array([[4, 1, 1], [1, 4, 1], [1, 1, 4]], np.float64) / 6
    probes = [tris[okid].mean(axis=1) + eps * unit[okid]]
    for cw in corner_w:
        probes.append(np.einsum("c,ncd->nd", cw, tris[big]) + eps * unit[big])
    w = wn(np.concatenate(probes), CLASS_CUTS)
    cls = np.full(n_tri, -1, np.int8)
    cls[okid] = _class_of(w[: len(okid)])
    w_tri = np.full(n_tri, np.nan)
    w_tri[okid] = w[: len(okid)]
    corner_cls = _class_of(w[len(okid) :]).reshape(3, -1)
    mixed = big[(corner_cls != cls[big]).any(axis=0)]
    whole = np.ones(n_tri, bool)
    whole[mixed] = False
    wid = np.nonzero(whole)[0]
    prim = [tris[wid]]
    parent = [wid]
    bary = [np.broadcast_to(np.eye(3), (len(wid), 3, 3))]
    pcls = [cls[wid]]
    front = [w_tri[wid]]
    # refine only where the probes disagree: bisect, probe the halves, keep what agrees (a
    # sliver of another class between the probes can be missed: surfaces may be off by up to
    # about a voxel right at the curves where pieces intersect)
    t = tris[mixed]
    par = mixed
    b = np.broadcast_to(np.eye(3), (len(mixed), 3, 3))
    while len(t):
        t, b, par = _bisect(t, b, par)
        longest = np.max([np.linalg.norm(t[:, (i + 1) % 3] - t[:, i], axis=1) for i in range(3)], 0)
        big_piece = longest > SUBDIVIDE_MIXED * h
        n = unit[par] * eps
        q = [t.mean(axis=1) + n]
        q += [np.einsum("c,ncd->nd", cw, t[big_piece]) + n[big_piece] for cw in corner_w]
        w = wn(np.concatenate(q), CLASS_CUTS)
        c = _class_of(w[: len(t)])
        cc = _class_of(w[len(t) :]).reshape(len(corner_w), -1)
        done = ~big_piece
        done[big_piece] = (cc == c[big_piece]).all(axis=0)
        prim.append(t[done])
        parent.append(par[done])
        bary.append(b[done])
        pcls.append(c[done])
        front.append(w[: len(t)][done])
        t, b, par = t[~done], b[~done], par[~done]
    return (
        np.concatenate(prim),
        np.concatenate(parent),
        np.concatenate(bary),
        np.concatenate(pcls),
        np.concatenate(front),
    )


def _bisect(t, b, par):
    """Split each triangle (and its corner barycentrics) in two at its longest edge."""
    e = np.stack([np.linalg.norm(t[:, (i + 1) % 3] - t[:, i], axis=1) for i in range(3)], 1)
    roll = (np.arange(3)[None, :] + e.argmax(axis=1)[:, None]) % 3
    rows = np.arange(len(t))[:, None]
    t, b = t[rows, roll], b[rows, roll]
    mt = (t[:, 0] + t[:, 1]) / 2
    mb = (b[:, 0] + b[:, 1]) / 2
    t2 = np.concatenate([np.stack([t[:, 0], mt, t[:, 2]], 1), np.stack([mt, t[:, 1], t[:, 2]], 1)])
    b2 = np.concatenate([np.stack([b[:, 0], mb, b[:, 2]], 1), np.stack([mb, b[:, 1], b[:, 2]], 1)])
    return t2, b2, np.concatenate([par, par])


def _thickness(tris, start: float) -> np.ndarray:
    """(T,) distance from each boundary triangle's centroid, inwards, to the next boundary.

    Only boundary triangles are hit (buried faces are inside the solid, not across it); inf
    where the ray leaves. Rays start ``start`` behind the face, so coincident duplicate faces
    do not count.
    """
    import trimesh

    if len(tris) == 0:
        return np.zeros(0)
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    origins = tris.mean(axis=1) - start * n
    mesh = trimesh.Trimesh(
        tris.reshape(-1, 3), np.arange(3 * len(tris)).reshape(-1, 3), process=False
    )
    loc, ray, _tri = mesh.ray.intersects_location(origins, -n, multiple_hits=False)
    out = np.full(len(tris), np.inf)
    out[ray] = np.linalg.norm(loc - origins[ray], axis=1) + start
    return out


def _band(tris, origin, h, shape, radius):
    """Distance band (float32, inf outside) and nearest triangle ids (int32, -1)."""
    if len(tris) == 0:
        return np.full(tuple(shape), np.inf, np.float32), np.full(tuple(shape), -1, np.int32)
    dist = np.empty(tuple(shape), np.float32)  # initialised by the kernel, slab by slab
    tid = np.empty(tuple(shape), np.int32)
    ptr, lst = _distance.slab_lists(tris, origin, h, radius, int(shape[0]), SLAB)
    _distance.band_distance(
        tris, ptr, lst, SLAB, origin, h, radius, dist, tid, fresh=True, finish_root=True
    )
    return dist, tid


def _component_signs(wn, d, dist, free, in_sheet, h, origin):
    """(X, Y, Z) int8 sign (+1 outside, -1 inside) of the boundary distance.

    ``d``: distance to the nearest boundary or buried face. ``free``: voxels with no surface
    (boundary, buried or sheet) within one voxel. ``in_sheet``: voxels inside a thickened
    sheet or thin piece; they are solid whatever the boundary's sign, so those that would
    need a query of their own (inside thin boards) are set inside directly. ``dist``: distance
    to the nearest boundary, buried or sheet face (neighbours whose ``dist`` sum to more than
    a voxel have no surface between them). The rest are winding-number queries, three per
    enclosed group of such neighbours where those three agree.
    """
    shape = d.shape
    # flood the voxels > 2 voxels from any surface: a gap narrower than 4 voxels in an open
    # assembly cannot connect an inside to the outside; the ring between 1 and 2 voxels takes
    # the sign of its flooded neighbours
    core = free & (d > 2 * h)
    # cc3d numbers components as scipy's ndimage.label does (raster order of their first
    # voxel, 6-connected), about 3-4x faster on a 256^3 grid (191 -> ~60 ms on SheenChair)
    labels, n_comp = cc3d.connected_components(core, connectivity=6, return_N=True)
    labels = labels.view(np.int32) if labels.dtype == np.uint32 else labels.astype(np.int32)
    sign = np.zeros(shape, np.int8)
    if n_comp:
        # per component: its 5 voxels farthest from the surface plus a random 1 in 4000 (up to
        # 200); the majority decides, so free space that reaches into an open container (a
        # drawer, a bookcase) stays air even where the winding number there exceeds 1/2
        size, pick = _labels.label_stats(labels, d, n_comp, 5)
        extra = np.minimum(size // 4000, 200)
        rand = [np.zeros(0, np.int64)]
        if extra.any():
            # the same draws as one rng.random(number of labelled voxels), in chunks
            rng = np.random.default_rng(0)
            left, start, seen = int(size[1:].sum()), 0, 0
            while left:
                chunk = rng.random(min(left, RANDOM_CHUNK))
                got, start = _labels.random_picks(labels, start, seen, chunk, size, extra)
                rand.append(got)
                seen += len(chunk)
                left -= len(chunk)
        samples = np.concatenate([pick, *rand])
        pts = origin + np.stack(np.unravel_index(samples, shape), axis=1) * h
        w = wn(pts, INSIDE_CUTS)
        inside = w > INSIDE_CUTS[0]
        comp = labels.ravel()[samples]
        n_in = np.bincount(comp, weights=inside, minlength=n_comp + 1)
        n_all = np.bincount(comp, minlength=n_comp + 1)
        comp_sign = np.where(n_in * 2 > n_all, -1, 1).astype(np.int8)
        comp_sign[0] = 0
        _labels.paint_labels(labels, comp_sign, sign)
    del labels
    # the ring, then voxels near the boundary, take the sign of signed 6-neighbours that agree
    # (ring voxels pass the sign on among themselves: each has d > h); all of these lie
    # within two voxels of the surface, so they are listed and visited one by one
    todo = _sign.spread_signs(sign, np.flatnonzero(free & ~core), 8)
    del core
    # ring voxels still unsigned (in narrow gaps, inside boards) are signed with the
    # undecided near ones below
    left = _sign.sign_near(sign, free, in_sheet, np.flatnonzero(~free))
    # the rest: groups joined by surface-free steps. Those enclosed (inside boards 2-4 voxels
    # thick, most of them) take the sign of a few samples where those agree
    flat = np.sort(np.concatenate([left, todo]))
    root, touch = _sign.clear_components(flat, sign, in_sheet, dist, h)
    # groups that reach a signed voxel are queried voxel by voxel: next to open sheets the
    # winding number can pass 1/2 away from any surface (inside an open cup's walls)
    seeded = touch[root].any(axis=1)
    queries = flat[seeded]
    flat, root = flat[~seeded], root[~seeded]
    # enclosed groups: 3 voxels each (the farthest from the surface); where those disagree,
    # all of the group's voxels
    if len(flat) == 0:
        _query_signs(wn, sign, queries, h, origin)
        return sign
    order = np.lexsort((-dist.ravel()[flat], root))
    r_sorted = root[order]
    first = np.r_[True, r_sorted[1:] != r_sorted[:-1]]
    run_start = np.maximum.accumulate(np.where(first, np.arange(len(order)), 0))
    pick = order[np.arange(len(order)) - run_start < 3]
    w_pick = wn(origin + np.stack(np.unravel_index(flat[pick], shape), axis=1) * h, INSIDE_CUTS)
    n_in = np.bincount(root[pick], weights=w_pick > INSIDE_CUTS[0], minlength=len(touch))
    n_all = np.bincount(root[pick], minlength=len(touch))
    agree = (n_in == 0) | (n_in == n_all)
    ok = agree[root]
    sign.ravel()[flat[ok]] = np.where(n_in[root[ok]] > 0, -1, 1)
    _query_signs(wn, sign, np.concatenate([queries, flat[~ok]]), h, origin)
    return sign


def _query_signs(wn, sign, flat_idx, h, origin):
    """Set ``sign`` at the flat voxel indices from the winding number (inside where w > 1/2)."""
    if len(flat_idx):
        pts = origin + np.stack(np.unravel_index(flat_idx, sign.shape), axis=1) * h
        w = wn(pts, INSIDE_CUTS)
        sign.ravel()[flat_idx] = np.where(w > INSIDE_CUTS[0], -1, 1)


def _fill_bubbles(sdf: np.ndarray, sign: np.ndarray, h: float) -> int:
    """Fill (in place) enclosed outside pockets thinner than a voxel; returns voxels filled.

    Two closed pieces that touch leave a crevice of air between them that the winding number
    rightly calls outside. Thinner than a voxel, it is caught by a voxel centre here and there,
    and each one caught is a closed bubble inside the solid: more of them the finer the grid
    (none at 128, dozens at 256 on SheenChair), each a spurious surface piece. Pockets whose
    voxels all lie within half a voxel of the surface and that reach no farther outside voxel
    (nor the grid's border) take the inside sign; their distances to the triangles are kept.
    Real cavities reach deeper than half a voxel and stay.
    """
    fill = _sign.shell_pockets(sdf, np.float32(0.5 * h))
    sdf.ravel()[fill] *= -1
    sign.ravel()[fill] = -1
    return len(fill)


@dataclass
class _Pieces:
    """The mesh's distance primitives (see :func:`classify_pieces`) and their classes.

    ``sub`` (P, 3, 3) float64, ``parent`` (P,) int64, ``corner_bary`` (P, 3, 3), ``cls`` (P,)
    int8; ``boundary`` and ``sheet`` (int64) index the boundary and open-sheet primitives.
    """

    sub: np.ndarray
    parent: np.ndarray
    corner_bary: np.ndarray
    cls: np.ndarray
    boundary: np.ndarray
    sheet: np.ndarray


@dataclass
class _Thin:
    """The closed pieces thickened into sheets: ``thin`` primitive ids, ``offset`` (P,)
    float64 half-thickness of every sheet primitive, and what import records about them.
    """

    thin: np.ndarray
    offset: np.ndarray
    n_open: int
    n_thin: int
    record: dict


def _place(mesh: ColoredMesh, name: str, res: int, pad: int):
    """The mesh as (V, F) float64 / int64 and its grid: origin, h, shape (tuple of int)."""
    V = np.ascontiguousarray(mesh.vertices, np.float64)
    F = np.ascontiguousarray(mesh.faces, np.int64)
    if len(F) == 0:
        raise InputError(f"{name}: expected a mesh with triangles, got none")
    used = V[np.unique(F)]
    lo, hi = used.min(axis=0), used.max(axis=0)
    if not (hi - lo).max() > 0:
        raise InputError(f"{name}: expected a mesh with non-zero extent, got a point")
    origin, h, shape = grid_for_bounds(lo, hi, res, pad)
    check_memory(
        tuple(int(s) for s in shape), BYTES_PER_VOXEL, what=f"{name} at res {res}", params=("res",)
    )
    return V, F, origin, h, tuple(int(s) for s in shape)


def _one_of_two_sided(V: np.ndarray, F: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """The faces the import uses: ``kept`` (F',) int64 ids, one copy of each two-sided face
    where that closes a body, and ``twin`` (F',) int64 the opposite copy of those still
    stored with both windings (-1: none). Such copies cancel in ``w``: a surface of no body,
    which :func:`classify_pieces` alone would read as a boundary with outside on both sides.

    A two-sided face (see :mod:`partscale.ingest._two_sided`) is a triangle stored as often
    with one winding as with the other, the same whole ``w`` on both sides (``0.05 h`` off,
    as the classification probes; within ``CLASS_CUTS[1]`` of 0, 1, 2, ...: outside, or
    inside another solid), in a closed group of them (see the module). The copies kept
    must read as a boundary: a group of them with ``w < CLASS_CUTS[0]`` in front of a copy
    is wound the wrong way round, and is turned over; where that does not help either, it
    keeps every copy (as imports did before; checked again, up to 3 times, as that changes
    the others' ``w``). A face whose probe reads a part of a whole (a sliver along an open
    face's edge, where a wall was cut beside a one-sided back) follows its group where such
    faces hold at most ``MAX_UNSURE_SHARE`` of the group's area; else the group keeps every
    copy. A mesh with none keeps every face.
    """
    pairs = _two_sided.opposite_pairs(V, F)
    fwd = pairs.fwd
    if len(fwd) == 0:
        return np.arange(len(F)), np.full(len(F), -1, np.int64)
    tris = V[F[fwd]]
    nrm = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    ln = np.linalg.norm(nrm, axis=1)
    ok = ln > 1e-14 * max(1.0, float(np.abs(tris).max())) ** 2
    probe = tris[ok].mean(axis=1) + 0.05 * h * nrm[ok] / ln[ok, None]
    two = ~ok  # no area: it joins up the faces around it whichever copy is kept
    w = _Winding(V, F)(probe, CLASS_CUTS)
    whole = np.abs(w - np.round(w)) <= CLASS_CUTS[1]
    two[ok] = w >= CLASS_CUTS[0]
    # a sliver along the edge of an open face (a wall's strip cut at a plane beside a one-sided
    # back) reads a part of a whole at its probe: it follows its group, where most of the
    # group's area reads whole
    unsure = np.zeros(len(fwd), bool)
    unsure[ok] = ~whole
    choice, group = _two_sided.keep_one(pairs, two)
    linked = group >= 0
    if linked.any():
        area = np.zeros(len(fwd))
        area[ok] = ln[ok]
        total = np.bincount(group[linked], area[linked])
        share = np.bincount(group[linked], (area * unsure)[linked]) / np.maximum(total, 1e-300)
        choice[linked & (share[np.maximum(group, 0)] > MAX_UNSURE_SHARE)] = 0
    for step in range(4):
        on = np.flatnonzero((choice != 0) & ok)
        if len(on) == 0:
            break
        keep = _two_sided.kept(pairs, choice)
        face = np.where(choice[on] > 0, fwd[on], pairs.rev[on])
        t = V[F[face]]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        w = _Winding(V, F[keep])(t.mean(axis=1) + 0.05 * h * n / ln[on, None], CLASS_CUTS)
        bad = np.isin(group, group[on][w < CLASS_CUTS[0]])
        if not bad.any():
            break
        choice[bad] = -choice[bad] if step == 0 else 0
    keep = np.flatnonzero(_two_sided.kept(pairs, choice))
    g = np.maximum(pairs.pair[keep], 0)
    both = (pairs.pair[keep] >= 0) & (choice[g] == 0)
    # each copy's twin: the first copy of the other winding (a copy winds as its pair's
    # fwd copy where its corners are theirs turned round)
    a, b = pairs.W[keep], pairs.W[pairs.fwd[g]]
    same = (a == b).all(1) | (a == np.roll(b, 1, 1)).all(1) | (a == np.roll(b, 2, 1)).all(1)
    return keep, np.where(both, np.where(same, pairs.rev[g], pairs.fwd[g]), -1)


def _classify(wn: _Winding, name: str, h: float, res: int) -> _Pieces:
    """Step 1: the pieces and their classes; refuses a mesh with no surface left."""
    sub, parent, corner_bary, cls, front = classify_pieces(wn, probe_size(h, res))
    cls[_bounding_nothing(wn, sub, cls, front, probe_size(h, res))] = 2
    boundary = np.nonzero(cls == 0)[0]
    sheet = np.nonzero(cls == 2)[0]
    if len(boundary) + len(sheet) == 0:
        raise InputError(f"{name}: expected a surface, got only degenerate or buried triangles")
    return _Pieces(sub, parent, corner_bary, cls, boundary, sheet)


def _bounding_nothing(
    wn: _Winding, sub: np.ndarray, cls: np.ndarray, front: np.ndarray, h: float
) -> np.ndarray:
    """(B,) int64 the pieces classified boundary (``cls`` 0; ``sub`` (P, 3, 3) float64) across
    which ``w`` does not step: less than 1/2 higher a probe ``0.05 h`` behind their centroid
    than in front of it (``front`` (P,) float64, the classification's probe).

    Crossing a face against its normal raises ``w`` by 1. A face whose copy with the other
    winding lies on it (a two-sided face left as it is, or copies triangulated differently, as
    Sweet Home's chair's side panels are) cancels that step: it reads outside on both sides,
    bounds nothing, and was lost. It is an open sheet, as a one-sided panel is.
    """
    on = np.flatnonzero(cls == 0)
    t = sub[on]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    behind = wn(t.mean(axis=1) - 0.05 * h * n, INSIDE_CUTS)
    return on[behind - front[on] < STEP_CUT]


def _boundary_band(pieces: _Pieces, origin, h: float, shape):
    """Steps 2-3 (boundary): the boundary's band (d_b float32, id_b int32) and the thin pieces.

    The boundary's band needs only the classes: its numba kernel (no GIL) runs on a thread of
    its own while this one casts the thickness rays (serial, embree).
    """
    boundary, sheet, parent = pieces.boundary, pieces.sheet, pieces.parent
    thick = math.sqrt(3) / 2 * h
    tris_b = np.ascontiguousarray(pieces.sub[boundary])
    launch_numba_threads()  # from this thread, not the pool's (see the function)
    with ThreadPoolExecutor(1) as pool:
        band_b = pool.submit(_band, tris_b, origin, h, shape, BAND_VOXELS * h)
        # closed pieces thinner than the grid can hold (shelves, back panels) would vanish or
        # get holes: their faces also join the sheets, offset so that the piece is 2t thick
        offset = np.zeros(len(pieces.sub))
        offset[sheet] = thick
        thickness = _thickness(tris_b, 0.01 * h)
        d_b, id_b = band_b.result()
    thin = boundary[thickness < 2 * thick]
    offset[thin] = thick - thickness[thickness < 2 * thick] / 2
    # what import reports (``partscale info`` too): how thin the thickened pieces really are
    t_thin = thickness[thickness < 2 * thick] / h
    record = {}
    if t_thin.size:
        record = {
            "thin_piece_thickness_voxels": {
                "min": round(float(t_thin.min()), 3),
                "median": round(float(np.median(t_thin)), 3),
            },
            "below_one_voxel_triangles": len(np.unique(parent[boundary[thickness < h]])),
        }
    n_open = len(np.unique(parent[sheet]))
    n_thin = len(np.unique(parent[thin]))
    return d_b, id_b, _Thin(thin, offset, n_open, n_thin, record)


def _signs(wn: _Winding, pieces: _Pieces, d_b, f_s, id_s, sheet, offset, origin, h):
    """Step 4: (X, Y, Z) int8 sign of the boundary distance; ``f_s`` becomes, in place, the
    thickened sheets' distance (see :func:`partscale.ingest._sign.sign_inputs`).

    Buried faces block the flood and the clear steps too: a face classified buried over its
    whole area can be uncovered along a strip its probes missed (a board whose cover ends
    short of its edge), a hole in the surface that the flood would leak through once the
    strip is wider than its 4 voxels (at 256 on painted_wooden_cabinet, not at 128). Near a
    truly buried face both sides are inside, so blocking there changes no sign.
    """
    d_u = d_b
    buried = np.nonzero(pieces.cls == 1)[0]
    if len(buried):
        # min(d_b, distance to buried faces within 2 voxels), in one copy of d_b
        d_u = d_b.copy()
        tris_u = np.ascontiguousarray(pieces.sub[buried])
        ptr, lst = _distance.slab_lists(tris_u, origin, h, 2 * h, d_b.shape[0], SLAB)
        no_ids = np.empty((1, 1, 1), np.int32)
        _distance.band_distance(tris_u, ptr, lst, SLAB, origin, h, 2 * h, d_u, no_ids, root=True)
    # the thickened sheets block the flood (not ``free``) as much as boundaries do (a cushion
    # whose cloth has an open seam still encloses its inside); at 2t thick they leave no
    # 6-connected tunnel. ``dist``: to the nearest boundary, buried or (unthickened) sheet
    # face: steps between voxels whose distances sum to more than a voxel cross no surface
    in_sheet, free, dist = _sign.sign_inputs(d_u, f_s, id_s, sheet, offset, h)
    return _component_signs(wn, d_u, dist, free, in_sheet, h, origin)


def _compose_band(sign, d_b, id_b, boundary, f_s, id_s, sheet, h: float):
    """Step 5 in the band: ``sdf`` float32, ``win`` int32 (nearest primitive) and ``band`` bool.

    sdf = min(signed boundary distance (+-inf beyond the band), thickened sheet distance);
    values within 1e-3 voxel of 0 are moved to +-1e-3 voxel: a surface exactly through a
    voxel centre (axis-aligned models) would give marching cubes degenerate triangles. The
    band: ``|sdf| <= BAND_VOXELS h``, compared in float32 (as numpy compares a float32 grid
    with a Python float).
    """
    shape = sign.shape
    sdf = np.empty(shape, np.float32)
    win = np.empty(shape, np.int32)  # primitive ids: far fewer than 2**31
    band = np.empty(shape, np.bool_)
    tiny = np.float32(1e-3 * h)
    band_lim = np.float32(BAND_VOXELS * h)
    _distance.compose(sign, d_b, id_b, boundary, f_s, id_s, sheet, tiny, sdf, win, band_lim, band)
    return sdf, win, band


def _band_colour(mesh: ColoredMesh, name: str, pieces: _Pieces, twin, win, band, origin, h, report):
    """Step 6 in the band: (X, Y, Z, 3) uint8 sRGB, set at the band voxels only. ``twin``
    (F,) int64: each face's opposite copy where both are used (-1: none): a voxel behind
    such a face takes the colour of the copy facing it (:func:`_facing`).
    """
    shape = band.shape
    band_idx = np.flatnonzero(band)
    if len(band_idx) == 0:
        raise InputError(f"{name}: expected a surface inside the grid, got none")
    w_b = win.ravel()[band_idx].astype(np.int64)
    bary = _distance.voxel_closest(band_idx, np.array(shape), origin, h, pieces.sub, w_b)
    report(0.75, "colour from the texture")
    pbary = _shading.corner_mix(w_b, bary, pieces.corner_bary)
    face = pieces.parent[w_b]
    if (twin >= 0).any():
        centres = origin + np.stack(np.unravel_index(band_idx, shape), axis=1) * h
        face, pbary = _facing(mesh, twin, face, pbary, centres)
    rgb = np.empty((*shape, 3), np.uint8)
    rgb.reshape(-1, 3)[band_idx] = mesh.color_at(face, pbary)
    return rgb


def _facing(mesh: ColoredMesh, twin, face, bary, points):
    """The copy of a two-sided face that faces each point: ``face`` (N,) int64 and ``bary``
    (N, 3) float64 the closest point's barycentrics in it, turned to the opposite copy
    ``twin[face]`` (and that point's barycentrics in it) where ``points`` (N, 3) lie behind
    ``face``. A two-sided face's copies may carry different colours (a drawer front: wood
    outside, white inside); nearest by distance alone, they tie.
    """
    V = np.asarray(mesh.vertices, np.float64)
    F = np.asarray(mesh.faces, np.int64)
    on = np.flatnonzero(twin[face] >= 0)
    tri = V[F[face[on]]]
    q = np.einsum("nc,ncd->nd", bary[on], tri)
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    back = np.einsum("nd,nd->n", points[on] - q, nrm) < 0
    behind = on[back]
    face, bary = face.copy(), bary.copy()
    if len(behind):
        other = twin[face[behind]]
        _, bary[behind] = _distance.closest_points(q[back], V[F[other]], np.arange(len(other)))
        face[behind] = other
    return face, bary


@keyword_options
def from_mesh(
    mesh: ColoredMesh,
    *,
    res: int = 128,
    pad: int | None = None,
    progress: ProgressCallback | None = None,
) -> CSDF:
    """Coloured signed distance field of a (possibly open, self-intersecting) coloured mesh.

    The steps are the module's method, in its order.

    Parameters
    ----------
    mesh : ColoredMesh
        From :func:`partscale.ingest.load_mesh`.
    res : int
        Voxels along the object's longest side (>= 16); voxels are cubic.
    pad : int, optional
        Empty voxels between the object's bounding box and the grid border (default
        ``BAND_VOXELS + 2``; at least ``BAND_VOXELS``).
    progress : callable(fraction, message), optional

    Returns
    -------
    CSDF
        ``sdf`` (X, Y, Z) float32 exact within ``BAND_VOXELS`` voxels of the surface, negative
        inside; ``rgb`` (X, Y, Z, 3) uint8 sRGB of the nearest surface point.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> table = ingest.from_mesh(ingest.load_mesh(data.table()), res=64)
    >>> table.shape
    (75, 36, 46)
    """
    report = resolve(progress)
    name = mesh.source or "mesh"
    res = check_res(res, name)
    pad = check_pad(pad, name)
    V, F, origin, h, shape = _place(mesh, name, res, pad)
    report(0.0, "classifying pieces")
    kept, twin = _one_of_two_sided(V, F, probe_size(h, res))
    wn = _Winding(V, F[kept])
    pieces = _classify(wn, name, h, res)
    pieces.parent = kept[pieces.parent]
    report(0.15, "exact distances near the surface")
    d_b, id_b, thin = _boundary_band(pieces, origin, h, shape)
    sheet = np.concatenate([pieces.sheet, thin.thin])
    report(0.3, "thickening open sheets")
    f_s, id_s = _band(
        np.ascontiguousarray(pieces.sub[sheet]), origin, h, shape, (BAND_VOXELS + 1) * h
    )
    report(0.45, "inside/outside")
    sign = _signs(wn, pieces, d_b, f_s, id_s, sheet, thin.offset, origin, h)
    sdf, win, band = _compose_band(sign, d_b, id_b, pieces.boundary, f_s, id_s, sheet, h)
    del d_b, id_b, f_s, id_s
    n_bubbles = _fill_bubbles(sdf, sign, h)  # flips signs only: the band stays
    report(0.65, "distances beyond the band")
    twin_of = np.full(len(F), -1, np.int64)
    twin_of[kept] = twin
    rgb = _band_colour(mesh, name, pieces, twin_of, win, band, origin, h, report)
    if not band.all():
        report(0.8, "distances beyond the band")
        # beyond the band a distance is at least the band's: the floor guards the feature
        # transform's rare non-nearest picks from pulling values inside the band
        floor = BAND_VOXELS * h
        _far_field.far_field(band, origin, h, pieces.sub, win, thin.offset, sign, floor, sdf, rgb)
    report(1.0, "done")
    meta = _import_meta(mesh, res, pad, len(F), thin, n_bubbles, len(F) - len(kept))
    return make(sdf, rgb, None, origin, h, meta)


def _import_meta(
    mesh: ColoredMesh, res: int, pad: int, n_faces: int, thin: _Thin, n_bubbles: int, n_two: int
):
    """The CSDF's meta: what import did, as ``partscale info`` shows it."""
    return {
        "source": mesh.source,
        "units": "m",
        "history": [
            {
                "op": "import",
                "source": mesh.source,
                "res": res,
                "pad": pad,
                "triangles": n_faces,
                "open_sheet_triangles": thin.n_open,
                "thin_piece_triangles": thin.n_thin,
                "sheet_half_thickness_voxels": round(math.sqrt(3) / 2, 4),
                **thin.record,
                "filled_bubble_voxels": n_bubbles,
                **({"two_sided_copies_dropped": n_two} if n_two else {}),
                "band_voxels": BAND_VOXELS,
                **({"notes": list(mesh.notes)} if mesh.notes else {}),
            }
        ],
    }
