"""Resampling along the edit axis: the slab's new voxels read from the old grid.

Everything here works on arrays with the edit axis moved first, ``(N, A, B)``; one output layer
``j`` along the axis reads source layers by a *plan*: a continuous source index ``xa[j]`` and,
inside a tile seam's blend window, a second one ``xb[j]`` with weight ``beta[j]`` (< 0.5, so the
first is always the dominant one). Layers whose source index is an integer are copied exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from .recipe import source_coordinate, tile_count

#: Half-width of a tile seam's blend window, in output voxels.
SEAM_VOXELS = 2.0


@dataclass(frozen=True)
class Plan:
    """Per output layer ``j`` (N',): where it reads from along the axis.

    Attributes
    ----------
    xa : (N',) float64
        Continuous source index of the dominant sample.
    xb : (N',) float64
        Continuous source index of the blended sample (tile seams), ``nan`` elsewhere.
    beta : (N',) float64
        Weight of ``xb`` in ``[0, 0.5]``, 0 outside seams.
    copy : (N',) int64
        Tile copy the layer belongs to (0 outside the slab and in stretch/global).
    in_slab : (N',) bool
        Output layers between the start plane and the new end plane.
    scale : float
        Local stretch factor of the slab (new length / old length; per copy for tile).
    """

    xa: np.ndarray
    xb: np.ndarray
    beta: np.ndarray
    copy: np.ndarray
    in_slab: np.ndarray
    scale: float


def make_plan(
    *,
    mode: str,
    n_out: int,
    origin: float,
    h: float,
    start: float,
    end: float,
    dest: float,
    lo: float,
    hi: float,
    seam_voxels: float = SEAM_VOXELS,
    blend: bool = True,
) -> Plan:
    """Build the sampling plan of an edit along one axis (world positions, ``dest`` snapped).

    For ``tile`` with ``blend``, each internal seam cross-fades the two copies' continuations
    (left copy read past END, right copy read before START) over ``seam_voxels`` output voxels
    either side, so the field stays continuous across the seam (METHOD.md step 6). The blend
    alone would fade a feature thinner than that window which exists on one side of the seam
    only (a shelf just inside a zone plane) or close a gap of about a voxel; :func:`apply_plan`
    with ``keep_thin`` keeps those whole in the copy they belong to, and leaves out the sliver a
    plane cuts off a board that goes on past it (what :func:`~partscale.edit.apply_edit`
    does). Planes in the gaps
    between repeated elements, or through the middle of one, still give the smoothest seams (both
    continuations agree and the blend changes nothing); ``blend=False`` (what
    :func:`~partscale.edit.naive_edit` uses) concatenates the copies without blending, leaving a
    step in the field at each seam. A tile with 0 copies (``dest == start``) has no slab and no
    blend: the layers before START and those after END are copied as they were, joined at START.
    """
    y = origin + np.arange(n_out) * h
    x = source_coordinate(y, mode=mode, start=start, end=end, dest=dest, lo=lo, hi=hi)
    xa = (x - origin) / h
    shift_vox = round((dest - end) / h)
    # Outside the slab the map is a whole-voxel translation: snap to exact integers so those
    # layers are copies (rigidity), immune to rounding in the map.
    removed = mode == "tile" and tile_count(end - start, dest - start) == 0
    before = y < start
    after = y >= start if removed else y > dest  # 0 copies: the sides join at START, no slab
    if mode != "global":
        j = np.arange(n_out, dtype=np.float64)
        xa = np.where(before, j, xa)
        xa = np.where(after, j - shift_vox, xa)
    in_slab = ~before & ~after
    xb = np.full(n_out, np.nan)
    beta = np.zeros(n_out)
    copy = np.zeros(n_out, np.int64)
    length, target = end - start, dest - start
    if mode == "global":
        scale = (hi - lo + dest - end) / (hi - lo)
        in_slab = np.ones(n_out, bool)
    elif mode == "stretch":
        scale = target / length
    elif removed:
        scale = 1.0  # no slab: both sides are copied as they were
    else:
        n = tile_count(length, target)
        period = target / n
        scale = period / length
        u = (y - start) / period
        copy = np.where(in_slab, np.clip(np.floor(u), 0, n - 1), 0).astype(np.int64)
        if blend and n > 1:
            w = min(seam_voxels * h, period / 2)
            for m in range(1, n):
                ys = start + m * period
                near = np.abs(y - ys) < w
                # left copy continued past END, right copy continued before START
                x_left = (end + (y - ys) / scale - origin) / h
                x_right = (start + (y - ys) / scale - origin) / h
                ramp = np.clip((y - ys) / (2 * w) + 0.5, 0.0, 1.0)  # weight of the right copy
                left = near & (y < ys)
                right = near & (y >= ys)
                xa = np.where(left, x_left, xa)
                xb = np.where(left, x_right, xb)
                beta = np.where(left, ramp, beta)
                xa = np.where(right, x_right, xa)
                xb = np.where(right, x_left, xb)
                beta = np.where(right, 1.0 - ramp, beta)
    return Plan(xa=xa, xb=xb, beta=beta, copy=copy, in_slab=in_slab, scale=float(scale))


def _split(x: np.ndarray, n_src: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Integer neighbours and weight of continuous indices, clamped to the grid."""
    x = np.clip(x, 0.0, n_src - 1.0)
    i0 = np.floor(x).astype(np.int64)
    w = x - i0
    i1 = np.minimum(i0 + 1, n_src - 1)
    return i0, i1, w


@nb.njit(cache=True, parallel=True)
def _lerp_into(src, i0, i1, w, out, lo, hi, js):
    """out[:, j] = src[:, i0[j]] (w[j] == 0) or the float32 blend of src[:, i0[j]] and
    src[:, i1[j]], for the output layers ``js``.

    src (P, N, Q), out (P, M, Q), both C-contiguous: the edit axis in the middle, so the inner
    loop runs over contiguous memory. Rows ``(p, j)`` are independent and run in parallel. For
    an integer ``out`` the blend is rounded half to even and clipped to [lo, hi].
    """
    nq = src.shape[2]
    nj = js.shape[0]
    integer = lo < hi
    for t in nb.prange(src.shape[0] * nj):
        p = t // nj
        j = js[t % nj]
        a0, a1 = i0[j], i1[j]
        if w[j] == 0:
            for q in range(nq):
                out[p, j, q] = src[p, a0, q]
            continue
        w1 = np.float32(w[j])
        w0 = np.float32(1.0) - w1
        if integer:
            for q in range(nq):
                v = np.float32(src[p, a0, q]) * w0 + np.float32(src[p, a1, q]) * w1
                out[p, j, q] = min(max(np.rint(v), lo), hi)
        else:
            for q in range(nq):
                out[p, j, q] = np.float32(src[p, a0, q]) * w0 + np.float32(src[p, a1, q]) * w1


#: Runs of at least this many consecutive copied layers are copied as blocks (numpy's strided
#: copy, at memory speed), not layer by layer through the kernel.
_BLOCK_LAYERS = 4


def _copy_runs(src: np.ndarray, i0: np.ndarray, w: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Copy the runs of output layers that read consecutive source layers exactly (``w == 0``,
    ``i0`` rising by one: the rigid content before and after the slab) as blocks; returns the
    output layers left for the kernel (int64).
    """
    m = len(i0)
    exact = w == 0
    # a run continues where the next layer is exact and reads the next source layer
    cont = exact[1:] & exact[:-1] & (np.diff(i0) == 1)
    starts = np.flatnonzero(exact & ~np.concatenate(([False], cont)))
    done = np.zeros(m, bool)
    if starts.size:
        ends = np.flatnonzero(exact & ~np.concatenate((cont, [False]))) + 1
        for j0, j1 in zip(starts.tolist(), ends.tolist(), strict=True):
            if j1 - j0 >= _BLOCK_LAYERS:
                s0 = int(i0[j0])
                out[j0:j1] = src[s0 : s0 + (j1 - j0)]
                done[j0:j1] = True
    return np.flatnonzero(~done).astype(np.int64)


def _middle(a: np.ndarray) -> np.ndarray | None:
    """Axis-first ``a`` (N, ...) as a (P, N, Q) view of the C-contiguous world array it was
    moved from (the edit axis in the middle), or None when it is no such view.
    """
    for ax in range(min(a.ndim, 3)):
        world = np.moveaxis(a, 0, ax)
        if world.flags.c_contiguous:
            p = int(np.prod(world.shape[:ax], dtype=np.int64))
            return world.reshape(p, a.shape[0], -1)
    return None


def _alike(*views: np.ndarray | None) -> bool:
    """Whether :func:`_middle` views all exist and agree across the edit axis (P and Q)."""
    if any(v is None for v in views):
        return False
    return len({(v.shape[0], v.shape[2]) for v in views if v is not None}) == 1


def _lerp_rest(src, i0, i1, w32, out, lo, hi):
    """Rigid runs as block copies, the remaining layers through :func:`_lerp_into`."""
    js = _copy_runs(src, i0, w32, out)
    if js.size == 0:
        return
    s3, o3 = _middle(src), _middle(out)
    if not _alike(s3, o3):
        # any other strides: through contiguous axis-first copies
        s3 = np.ascontiguousarray(src).reshape(1, src.shape[0], -1)
        o3 = np.empty((1, out.shape[0], s3.shape[2]), out.dtype)
        _lerp_into(s3, i0, i1, w32, o3, lo, hi, js)
        out[js] = o3.reshape(out.shape)[js]
        return
    _lerp_into(s3, i0, i1, w32, o3, lo, hi, js)


def empty_layers(shape: tuple[int, ...], dtype, axis: int) -> np.ndarray:
    """Uninitialised axis-first array ``shape`` (N, A, B[, C]): a view of a C-ordered array in
    world order (the edit axis at ``axis``), so the result needs no transposing copy.
    """
    world = list(shape)
    n = world.pop(0)
    world.insert(axis, n)
    return np.moveaxis(np.empty(world, dtype), axis, 0)


def lerp_layers(src: np.ndarray, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Linear interpolation of layers of ``src`` (N, A, B[, C]) at continuous indices ``x`` (M,).

    Returns (M, ...) of ``src``'s dtype (integers rounded half to even, computed in float32),
    written into ``out`` when given (any strides, e.g. :func:`empty_layers`); layers at integer
    ``x`` are exact copies.
    """
    i0, i1, w = _split(x, src.shape[0])
    if out is None:
        out = np.empty((len(x), *src.shape[1:]), src.dtype)
    if np.issubdtype(src.dtype, np.integer):
        info = np.iinfo(src.dtype)
        lo, hi = float(info.min), float(info.max)
    else:
        lo = hi = 0.0
    _lerp_rest(src, i0, i1, w.astype(np.float32), out, lo, hi)
    return out


def crisp_parts(
    parts: np.ndarray, sdf: np.ndarray, x: np.ndarray, out: np.ndarray | None = None
) -> np.ndarray:
    """Part labels at continuous indices ``x``: no blended labels (into ``out`` when given).

    Between source layers ``i0`` and ``i0 + 1`` with different labels, the boundary is placed where
    the part change is closest to the surface: at the linear zero crossing of the sdf when the
    surface passes between them, else half-way (nearest source voxel).
    """
    i0, i1, w = _split(x, parts.shape[0])
    if out is None:
        out = parts[i0]
    else:  # copies of the nearer-below layer (weight 0), into any strides
        _lerp_rest(parts, i0, i0, np.zeros(len(i0), np.float32), out, 0.0, 0.0)
    frac = np.flatnonzero(w != 0)
    if frac.size == 0:
        return out
    p3, s3, o3 = _middle(parts), _middle(sdf), _middle(out)
    if not _alike(p3, s3, o3):  # any other strides: contiguous copies
        p3 = np.ascontiguousarray(parts).reshape(1, parts.shape[0], -1)
        s3 = np.ascontiguousarray(sdf).reshape(1, sdf.shape[0], -1)
        o3 = np.ascontiguousarray(out).reshape(1, out.shape[0], -1)
        _crisp_into(p3, s3, i0, i1, w.astype(np.float32), frac, o3)
        out[frac] = o3.reshape(out.shape)[frac]
        return out
    _crisp_into(p3, s3, i0, i1, w.astype(np.float32), frac, o3)
    return out


@nb.njit(cache=True, inline="always")
def _label_switch(a, b):
    """float32 blend weight from sample ``a`` towards ``b`` (float32 distances) at which the
    second sample's part takes over: where the surface crosses between them, else halfway.

    Asked only where the two labels differ: float32 is exact enough to place a boundary.
    """
    if (a <= 0) != (b <= 0):
        aa, ab = abs(a), abs(b)
        return aa / max(aa + ab, np.float32(1e-30))
    return np.float32(0.5)


@nb.njit(cache=True, parallel=True)
def _crisp_into(parts, sdf, i0, i1, w, js, out):
    """For output layers ``js`` (holding ``parts[:, i0[j]]``): take ``parts[:, i1[j]]`` where it
    differs and ``w[j]`` reaches the boundary (the sdf's linear zero crossing between the two
    layers when the surface passes between them, else half-way).

    parts, sdf (P, N, Q) and out (P, M, Q), C-contiguous; rows (p, j) run in parallel.
    """
    nq = parts.shape[2]
    nj = js.shape[0]
    for t in nb.prange(parts.shape[0] * nj):
        p = t // nj
        j = js[t % nj]
        a0, a1 = i0[j], i1[j]
        wj = w[j]
        for q in range(nq):
            p0 = out[p, j, q]
            p1 = parts[p, a1, q]
            if p0 == p1:
                continue
            if wj >= _label_switch(sdf[p, a0, q], sdf[p, a1, q]):
                out[p, j, q] = p1


#: Rows (in world order, across the edit axis) shorter than this get their rigid runs as block
#: copies before :func:`_resample_cols` (:func:`apply_plan`).
_SHORT_ROW = 32

#: Columns per parallel task of :func:`_resample_cols` (the task also spans one row of P).
_COL_BLOCK = 256


def _rows(a: np.ndarray, axis: int) -> np.ndarray:
    """Axis-first ``a`` (N, ...) as (P, N, Q): its array in world order (the edit axis at
    ``axis``), C-ordered (copied only where it is not), the axes before ``axis`` merged into P
    and those after it (colour included) into Q. A view of ``a`` when no copy was needed (as for
    :func:`empty_layers`).
    """
    world = np.ascontiguousarray(np.moveaxis(a, 0, axis))
    p = int(np.prod(world.shape[:axis], dtype=np.int64))
    return world.reshape(p, a.shape[0], -1)


@nb.njit(cache=True, parallel=True)
def _resample_cols(
    src,
    src_rgb,
    src_parts,
    i0,
    i1,
    w,
    frac,
    done,
    xa,
    pair,
    write,
    seam_of,
    out,
    out_rgb,
    out_parts,
    was,
):
    """Resample (P, N, Q) views (rgb (P, N, CQ)), C-contiguous, into (P, M, Q) ones: columns
    ``(p, q)`` in parallel blocks, layers in order, the inner loop over contiguous ``q``.
    Layers with ``done[j]`` are already written (block copies) and only read here.

    Output layer ``j`` reads source layers ``i0[j]``, ``i1[j]`` with weight ``w[j]`` (float32):
    copies where it is 0, else the float32 blend (rgb rounded half to even, clipped to 0..255);
    parts are ``src_parts[i0[j]]``, or where ``frac[j]`` and the label at ``i1[j]`` differs,
    that label once ``w[j]`` reaches the boundary (the sdf's linear zero crossing between the
    two layers when the surface passes between them, else half-way). Layer ``j`` with
    ``seam_of[j] = k >= 0`` is saved to ``was[k]`` as resampled.

    Then, for each pair ``j - 1, j`` with ``pair[j - 1]`` (once layer ``j`` is resampled, so a
    pair sees what the one before it wrote, as a pass over the finished layers would), the
    source layers strictly between ``xa[j - 1]`` and ``xa[j]`` are read column by column: where
    both output samples are outside (``> 0``) but one of those layers is inside, a solid
    thinner than the compression was skipped; the output layer nearer to its deepest sample (and
    ``write``-able) takes that sample's distance, colour and part. Skipped gaps (both inside, a
    layer between outside) likewise take the largest.
    """
    # indices are unsigned: with no negative index to wrap around, the loops over q vectorise
    m, nq = out.shape[1], out.shape[2]
    n_src = src.shape[1]
    nc = np.uint64(src_rgb.shape[2] // max(nq, 1))
    nblk = (nq + _COL_BLOCK - 1) // _COL_BLOCK
    for task in nb.prange(src.shape[0] * nblk):
        p = np.uint64(task // nblk)
        blk = task % nblk
        qa = np.uint64(blk * _COL_BLOCK)
        qe = np.uint64(min(blk * _COL_BLOCK + _COL_BLOCK, nq))
        nw = qe - qa
        sign = np.empty(nw, src.dtype)  # per column of a pair, see _skipped_samples
        best = np.empty(nw, src.dtype)
        sb = np.empty(nw, np.int64)
        for j in range(m):
            ju = np.uint64(j)
            if not done[j]:
                a0, a1 = np.uint64(i0[j]), np.uint64(i1[j])
                _blend_layer(src, src_rgb, out, out_rgb, p, ju, a0, a1, w[j], qa, qe, nc)
                for q in range(qa, qe):
                    out_parts[p, ju, q] = src_parts[p, a0, q]
                if frac[j]:
                    _switch_labels(src, src_parts, out_parts, p, ju, a0, a1, w[j], qa, qe)
            if seam_of[j] >= 0:
                k = np.uint64(seam_of[j])
                for q in range(qa, qe):
                    was[k, p, q] = out[p, ju, q]
            if j == 0 or not pair[j - 1]:
                continue
            r0 = max(int(np.floor(xa[j - 1])) + 1, 0)
            r1 = min(int(np.ceil(xa[j])) - 1, n_src - 1)
            if r1 >= r0:
                _skipped_samples(
                    src, src_rgb, src_parts, xa, write, p, j, r0, r1, qa, qe, nc, sign, best, sb,
                    out, out_rgb, out_parts,
                )  # fmt: skip


@nb.njit(cache=True)
def _blend_layer(src, src_rgb, out, out_rgb, p, ju, a0, a1, wj, qa, qe, nc):
    """:func:`_resample_cols`' layer ``ju`` of row ``p``, columns ``qa ... qe - 1``: a copy of
    source layer ``a0`` where ``wj`` is 0, else the float32 blend of ``a0`` and ``a1`` (rgb
    rounded half to even, clipped to 0..255).
    """
    ca, ce = qa * nc, qe * nc
    if wj == 0:
        for q in range(qa, qe):
            out[p, ju, q] = src[p, a0, q]
        for q in range(ca, ce):
            out_rgb[p, ju, q] = src_rgb[p, a0, q]
        return
    w1 = np.float32(wj)
    w0 = np.float32(1.0) - w1
    for q in range(qa, qe):
        out[p, ju, q] = np.float32(src[p, a0, q]) * w0 + np.float32(src[p, a1, q]) * w1
    for q in range(ca, ce):
        v = np.float32(src_rgb[p, a0, q]) * w0 + np.float32(src_rgb[p, a1, q]) * w1
        # float32 bounds: float64 ones cost a conversion per value and keep the loop from
        # vectorising (same results, ~2x faster alone)
        out_rgb[p, ju, q] = min(max(np.rint(v), np.float32(0.0)), np.float32(255.0))


@nb.njit(cache=True)
def _switch_labels(src, src_parts, out_parts, p, ju, a0, a1, wj, qa, qe):
    """:func:`_resample_cols`' parts of layer ``ju`` (row ``p``, columns ``qa ... qe - 1``)
    between source layers ``a0`` and ``a1``: the label at ``a1`` where it differs, once ``wj``
    reaches the boundary (:func:`_label_switch`).
    """
    for q in range(qa, qe):
        label = src_parts[p, a1, q]
        if out_parts[p, ju, q] == label:
            continue
        if wj >= _label_switch(src[p, a0, q], src[p, a1, q]):
            out_parts[p, ju, q] = label


@nb.njit(cache=True)
def _skipped_samples(
    src, src_rgb, src_parts, xa, write, p, j, r0, r1, qa, qe, nc, sign, best, sb, out,
    out_rgb, out_parts,
):  # fmt: skip
    """:func:`_resample_cols`' pair of output layers ``j - 1, j`` (row ``p``, columns ``qa ...
    qe - 1``): source layers ``r0 ... r1`` lie strictly between them; where a solid (or a gap)
    among them was skipped, the output layer nearer to its deepest sample (and ``write``-able)
    takes that sample. ``sign``, ``best``, ``sb`` (``qe - qa``,): scratch.
    """
    jp = j - 1
    jpu, ju = np.uint64(jp), np.uint64(j)
    for q in range(qa, qe):
        # both outside: a skipped solid is sought (the least sample, below 0), both inside: a
        # skipped gap (the largest, above 0); as ``sign * v > sign * best`` (an exact
        # negation), one comparison that vectorises
        solid = out[p, jpu, q] > 0
        sign[q - qa] = 0.0 if solid != (out[p, ju, q] > 0) else (-1.0 if solid else 1.0)
        best[q - qa] = 0
        sb[q - qa] = -1
    # the deepest sample in source order (the first of equals), column by column
    for r in range(r0, r1 + 1):
        ru = np.uint64(r)
        for q in range(qa, qe):
            v = src[p, ru, q]
            better = sign[q - qa] * v > sign[q - qa] * best[q - qa]
            best[q - qa] = v if better else best[q - qa]
            sb[q - qa] = r if better else sb[q - qa]
    for q in range(qa, qe):
        r = sb[q - qa]
        if r < 0:
            continue
        t = jp if r - xa[jp] <= xa[j] - r else j
        if not write[t]:
            t = 2 * jp + 1 - t
            if not write[t]:
                continue
        tu, ru = np.uint64(t), np.uint64(r)
        out[p, tu, q] = best[q - qa]
        for c in range(q * nc, (q + 1) * nc):
            out_rgb[p, tu, c] = src_rgb[p, ru, c]
        out_parts[p, tu, q] = src_parts[p, ru, q]


def cut_slivers(
    plan: Plan, seam: np.ndarray, dominant: np.ndarray, other: np.ndarray, out_sdf: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The slivers of elements cut by a zone plane at the tile seams: two (S, A, B) bool masks.

    ``seam`` (S,) are the blend layers of ``plan`` (``beta > 0``), ``dominant`` and ``other``
    (S, A, B) their samples of the layer's own copy and of the other copy, ``out_sdf``
    (N', A, B) the resampled layers (next to a blend window: its copy read on). Each copy, read
    up to its own plane (the left copy up to END, the right one from START), shows in each
    column a run of solid touching the seam. The run is a *cut sliver* when the
    copy's continuation past that plane (the ``other`` sample of the nearest layer across the
    seam) has the same sign, so the element goes on beyond the plane, and the run ends within
    the blend window on its own side or on the layer next to it. The element it belongs to lies
    beyond the plane and appears once, next to the last (first) copy; repeated at each internal
    seam its sliver would be a loose fragment (or a notch). An element lying wholly inside the
    copy (a thin shelf just inside a plane) has no continuation past the plane: no sliver.

    Runs of gap are never slivers: filling a cut gap with the other copy's solid closes it, and
    where the zone's planes lie in the gaps between repeated elements (a radiator's sections)
    at different depths, the two cut gaps that meet at an inner seam were filled in all but a
    few columns, sealing the gap's openings into enclosed air the original has not. A gap left
    whole costs at most a thin groove at the seam, and closes no cavity.

    Returns
    -------
    drop : (S, A, B) bool
        A sliver's voxels where the other copy has the opposite sign: :func:`apply_plan` gives
        them the other copy's sample where the blend would keep the sliver's side, so the
        sliver is left out the same way at every internal seam.
    hold : (S, A, B) bool
        Voxels across the seam from a sliver where the element's continuation (the other copy)
        has the sign of the sliver and the own copy the other: there the blend keeps the own
        sample where it would flip it.
    """
    drop = np.zeros(dominant.shape, bool)
    hold = np.zeros(dominant.shape, bool)
    inside, inside_other = dominant <= 0, other <= 0
    # an internal seam's layers: a run reading the left copy (near END, so xa > xb), then,
    # consecutive, a run reading the right copy
    left = plan.xa[seam] > plan.xb[seam]
    first = np.ones(seam.size, bool)
    first[1:] = (left[1:] != left[:-1]) | (np.diff(seam) != 1)
    edges = np.append(np.flatnonzero(first), seam.size)
    for a0, a1, b1 in zip(edges[:-2], edges[1:-1], edges[2:], strict=True):
        j0, j1 = seam[a0] - 1, seam[b1 - 1] + 1
        if not left[a0] or left[a1] or seam[a1] != seam[a1 - 1] + 1:
            continue
        if j0 < 0 or j1 >= out_sdf.shape[0]:
            continue
        # this seam's layers only (views): its windows, counted from the left one's first
        sw = slice(a0, b1)
        lw, rw = slice(0, a1 - a0), slice(a1 - a0, b1 - a0)
        seam_drop, seam_hold = drop[sw], hold[sw]
        for solid in (True,):  # solid runs only: a gap filled could seal a cavity
            mine = inside[sw] if solid else ~inside[sw]
            theirs = inside_other[sw] if solid else ~inside_other[sw]
            # per side: its layers from the seam outwards, the copy's continuation past its own
            # plane (the other side's nearest layer), the layer next to the window
            for win, across, run, cont, beyond in (
                (
                    lw,
                    rw,
                    _run(mine[lw][::-1])[::-1],
                    theirs[rw.start],
                    out_sdf[j0],
                ),
                (
                    rw,
                    lw,
                    _run(mine[rw]),
                    theirs[rw.start - 1],
                    out_sdf[j1],
                ),
            ):
                near, whole = (run[-1], run[0]) if win is lw else (run[0], run[-1])
                col = near & cont & ~(whole & ((beyond <= 0) == solid))
                if not col.any():
                    continue
                seam_drop[win] |= run & col & ~theirs[win]
                seam_hold[across] |= col & ~mine[across] & theirs[across]
    return drop, hold


def _run(m: np.ndarray) -> np.ndarray:
    """(L, A, B) bool: where ``m`` (L, A, B) bool holds on every layer from the first to this
    one (``np.logical_and.accumulate`` along the layers, which numpy runs 3-6x slower than one
    search for each column's first miss).
    """
    miss = ~m
    first = np.where(miss.any(axis=0), miss.argmax(axis=0), len(m))
    return np.arange(len(m))[:, None, None] < first


def apply_plan(
    sdf: np.ndarray,
    rgb: np.ndarray,
    parts: np.ndarray,
    plan: Plan,
    *,
    keep_thin: float | None = None,
    axis: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, int]]:
    """Resample axis-first arrays ``(N, A, B)`` by ``plan`` into new ``(N', A, B)`` arrays.

    Returns ``(sdf, rgb, parts, left_out)``: the new arrays, and the voxels of cut slivers left
    out per zone plane (``{"start": n, "end": n}``, only where ``n > 0``; see below), for the
    edit's history.

    The new arrays are axis-first views of C-ordered arrays in world order with the edit axis
    at ``axis`` (:func:`empty_layers`): moved back, they are the result as it is stored.

    ``keep_thin`` (a distance, world units; e.g. one voxel), when given, keeps elements that the
    linear resampling would lose:

    - in the slab, a solid (or gap) lying between two consecutive output samples, thinner than
      the spacing of the samples in the source (a compressed slab skips source layers), is put
      back on the output sample nearer to it with its source distance, colour and part, so it
      keeps at least one voxel instead of vanishing (an element thinner than the compression
      survives it);
    - in a tile seam's blend, where the blend flips the side of the dominant copy (its layer's
      own) against a blended sample more than ``keep_thin`` away on the other side, the dominant
      sample is kept: a thin shelf or sliver on one side of the seam stays whole in its copy
      instead of fading into the other copy's air (or a thin gap into its solid). Where both
      copies have surface within ``keep_thin`` of each other the blend is as before;
    - but where a zone plane cuts a solid element (a board straddling END or START), the sliver
      the plane cuts off is left out at every internal seam (:func:`cut_slivers`; never a cut
      gap, whose filling could seal a cavity): the element
      stays whole once, beyond the last copy (before the first), and no copy gets a loose
      fragment of it (counted in ``left_out``).
    """
    m = len(plan.xa)
    out_sdf, out_rgb, out_parts = (
        empty_layers((m, *a.shape[1:]), a.dtype, axis) for a in (sdf, rgb, parts)
    )
    # (P, N, Q) views in world order (rgb (P, N, 3Q)), the outputs' written in place
    s3, c3, p3, o3, oc3, op3 = (
        _rows(a, axis) for a in (sdf, rgb, parts, out_sdf, out_rgb, out_parts)
    )
    left_out: dict[str, int] = {}
    seam = np.flatnonzero(plan.beta > 0)
    # consecutive layers reading one continuous stretch of the source (the dominant samples;
    # a tile seam's jump from one copy's continuation to the other's is no pair)
    pair = np.zeros(m, bool)
    if keep_thin is not None:
        pair[:-1] = (plan.in_slab[:-1] | plan.in_slab[1:]) & (np.diff(plan.xa) > 0)
    i0, i1, w = _split(plan.xa, sdf.shape[0])
    seam_of = np.full(m, -1, np.int64)
    seam_of[seam] = np.arange(seam.size)
    was = np.empty((seam.size, s3.shape[0], s3.shape[2]), np.float32)
    done = np.zeros(m, bool)
    if s3.shape[2] < _SHORT_ROW:
        # rows across the axis too short for the kernel's inner loops (the edit axis last in
        # world order): the rigid runs as block copies, contiguous along the axis
        for a, o in ((sdf, out_sdf), (rgb, out_rgb), (parts, out_parts)):
            left = _copy_runs(a, i0, w, o)
        done[:] = True
        done[left] = False
    # one pass writes every output voxel (but block copies): resampled, thin elements kept
    _resample_cols(
        s3,
        c3,
        p3,
        i0,
        i1,
        w.astype(np.float32),
        w != 0,
        done,
        plan.xa,
        pair,
        plan.in_slab,
        seam_of,
        o3,
        oc3,
        op3,
        was,
    )
    if seam.size:
        views = (s3, c3, o3, oc3)
        left_out = _blend_seams(
            sdf, parts, out_sdf, out_parts, views, plan, seam, pair, was, keep_thin
        )
    return out_sdf, out_rgb, out_parts, left_out


def _blend_seams(
    sdf: np.ndarray,
    parts: np.ndarray,
    out_sdf: np.ndarray,
    out_parts: np.ndarray,
    views: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    plan: Plan,
    seam: np.ndarray,
    pair: np.ndarray,
    was: np.ndarray,
    keep_thin: float | None,
) -> dict[str, int]:
    """:func:`apply_plan`'s tile seams, in place: output layers ``seam`` (as resampled, in
    ``was``) blended between their dominant and other copy, cut slivers left out where
    ``keep_thin`` is given. ``sdf``, ``parts``, ``out_sdf``, ``out_parts``: axis-first;
    ``views``: the (P, N, Q) row views of the source sdf and rgb and the output's (see
    :func:`apply_plan`). Returns ``left_out``.
    """
    # the seam layers' dominant and other samples (the dominant as kept thin where it was)
    s3, c3, o3, oc3 = views
    left_out: dict[str, int] = {}
    a0, a1, wa = _split(plan.xa[seam], sdf.shape[0])
    b0, b1, wb = _split(plan.xb[seam], sdf.shape[0])
    wa, wb = wa.astype(np.float32), wb.astype(np.float32)
    kept = bool(pair.any())
    dominant, other = (np.empty_like(was) for _ in range(2))
    layers = (seam, a0, a1, wa, b0, b1, wb)  # each seam layer's output layer and sources
    _seam_samples(s3, o3, layers, was, kept, dominant, other)
    shape = (seam.size, *sdf.shape[1:])
    thin = keep_thin is not None
    if thin:
        drop, hold = cut_slivers(plan, seam, dominant.reshape(shape), other.reshape(shape), out_sdf)
        drop, hold = drop.reshape(was.shape), hold.reshape(was.shape)
    else:
        drop = hold = np.zeros(was.shape, bool)
    far = np.float32(keep_thin if thin else 0.0)
    beta = plan.beta[seam].astype(np.float32)
    _seam_blend(c3, o3, oc3, layers, beta, dominant, other, was, kept, thin, far, drop, hold)
    if drop.any():
        # a cut sliver is left out: the other copy's part (its sample and colour are in)
        drop = drop.reshape(shape)
        own = out_parts[seam]
        out_parts[seam] = np.where(drop, crisp_parts(parts, sdf, plan.xb[seam]), own)
        # a left window's layers read their copy up to END
        at_end = (plan.xa[seam] > plan.xb[seam])[:, None, None]
        for plane, n in (("start", (drop & ~at_end).sum()), ("end", (drop & at_end).sum())):
            if n:
                left_out[plane] = int(n)
    return left_out


@nb.njit(cache=True, parallel=True)
def _seam_samples(src, out, layers, was, kept, dominant, other):
    """For seam layer ``k`` (output layer ``seam[k]``), (P, Q) float32 each: ``other[k]``, the
    float32 blend of ``src`` layers ``b0[k]``, ``b1[k]`` by ``wb[k]`` (no exact copy at weight
    0: the arithmetic of the vectorised blend it replaces); ``dominant[k]`` likewise at ``a0``,
    ``a1``, ``wa``, or the output's value where ``kept`` and :func:`_resample_cols` kept a thin
    element there (it differs from ``was``). ``layers``: ``(seam, a0, a1, wa, b0, b1, wb)``, (S,)
    each, the layer indices as int64 and the weights as float32. src (P, N, Q), out (P, M, Q);
    rows in parallel.
    """
    seam, a0, a1, wa, b0, b1, wb = layers
    ns, nq = seam.shape[0], src.shape[2]
    for t in nb.prange(ns * src.shape[0]):
        k = t // src.shape[0]
        p = t % src.shape[0]
        o, wk = out[p, seam[k]], was[k, p]
        d, e = dominant[k, p], other[k, p]
        sa0, sa1, sb0, sb1 = src[p, a0[k]], src[p, a1[k]], src[p, b0[k]], src[p, b1[k]]
        w1 = wa[k]
        w0 = np.float32(1.0) - w1
        for q in range(nq):
            d[q] = np.float32(sa0[q]) * w0 + np.float32(sa1[q]) * w1
        if kept:
            for q in range(nq):
                if o[q] != wk[q]:
                    d[q] = o[q]
        w1 = wb[k]
        w0 = np.float32(1.0) - w1
        for q in range(nq):
            e[q] = np.float32(sb0[q]) * w0 + np.float32(sb1[q]) * w1


@nb.njit(cache=True, parallel=True)
def _seam_blend(
    src_rgb, out, out_rgb, layers, beta, dominant, other, was, kept, thin, far, drop, hold
):
    """Blend the seam layers (in place): :func:`apply_plan`'s rule per voxel, float32.

    ``src_rgb`` (P, N, 3Q), ``out`` (P, M, Q), ``out_rgb`` (P, M, 3Q); ``dominant``, ``other``,
    ``was``, ``drop``, ``hold`` (S, P, Q) per seam layer ``k`` (output layer ``seam[k]``, blend
    weight ``beta[k]``; ``layers`` and the rgb read as :func:`_seam_samples` reads the sdf).
    With ``thin`` (``keep_thin`` given, ``far`` its value), ``drop`` is narrowed to where a cut
    sliver is left out (the other copy's sample and colour). Rows in parallel.
    """
    seam, a0, a1, wa, b0, b1, wb = layers
    ns, nq = seam.shape[0], out.shape[2]
    n_c = src_rgb.shape[2] // max(nq, 1)
    for t in nb.prange(ns * out.shape[0]):
        k = t // out.shape[0]
        p = t % out.shape[0]
        j = seam[k]
        o, oc, wk = out[p, j], out_rgb[p, j], was[k, p]
        d, e, dr, hd = dominant[k, p], other[k, p], drop[k, p], hold[k, p]
        ca0, ca1, cb0, cb1 = (
            src_rgb[p, a0[k]],
            src_rgb[p, a1[k]],
            src_rgb[p, b0[k]],
            src_rgb[p, b1[k]],
        )
        bt = beta[k]
        b0_ = np.float32(1.0) - bt
        va = wa[k]
        va0 = np.float32(1.0) - va
        vb = wb[k]
        vb0 = np.float32(1.0) - vb
        for q in range(nq):
            dq, eq = d[q], e[q]
            blended = dq * b0_ + eq * bt
            keep = False
            own = kept and o[q] != wk[q]  # a thin element kept: its colour too
            gone = False
            if thin:
                flip = (dq <= 0) != (blended <= 0)
                keep = flip and ((dq <= 0 and eq > far) or (dq > 0 and eq < -far))
                # only where the blend alone would not do it: the sliver keeps its side (kept,
                # or no flip), the element's continuation flips the own sample
                gone = dr[q] and (keep or not flip)
                dr[q] = gone
                keep = (keep or (hd[q] and flip)) and not gone
            if keep:
                blended = dq
            elif gone:
                blended = eq
            o[q] = blended
            for c in range(q * n_c, (q + 1) * n_c):
                cb = np.float32(cb0[c]) * vb0 + np.float32(cb1[c]) * vb
                if gone:
                    v = cb
                elif keep or own:
                    continue  # the resampled colour stays
                else:
                    v = (np.float32(ca0[c]) * va0 + np.float32(ca1[c]) * va) * b0_ + cb * bt
                oc[c] = min(max(np.rint(v), np.float32(0.0)), np.float32(255.0))
