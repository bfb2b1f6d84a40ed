"""Part bookkeeping of an edit: tiled copies of inner parts get new indices, and
``meta['parts_info']`` (the segment stage's part facts) follows the edit.

Arrays are axis-first (N, A, B): the edit axis is axis 0.
"""

from __future__ import annotations

import copy as _copy
import math
from typing import Any

import numba as nb
import numpy as np

from ..color import palette_colour
from ..errors import InputError
from .resample import Plan, _rows
from .resolved import ResolvedEdit


def inner_parts(sdf: np.ndarray, parts: np.ndarray, i_start: float, i_end: float) -> np.ndarray:
    """Part indices whose inside voxels all lie strictly between layers ``i_start``, ``i_end``.

    Arrays are axis-first (N, A, B).
    """
    n = sdf.shape[0]
    # the layers strictly between the planes; a part is inner when it is inside there and
    # nowhere else (one pass over each side, no per-part extremes over the whole grid)
    lo = max(0, math.floor(i_start) + 1) if math.isfinite(i_start) else 0
    hi = min(n, math.ceil(i_end)) if math.isfinite(i_end) else n
    if lo >= hi:
        return np.zeros(0, np.int64)
    within = part_counts(parts[lo:hi], sdf[lo:hi])
    if not within.any():
        return np.zeros(0, np.int64)
    keep = within > 0
    for side in (slice(0, lo), slice(hi, n)):
        out = part_counts(parts[side], sdf[side])[: keep.size]
        keep[: out.size] &= out == 0
    return np.flatnonzero(keep)


def part_counts(parts: np.ndarray, sdf: np.ndarray | None = None) -> np.ndarray:
    """(P,) int64 voxels of each part index ``p >= 0`` (P: the largest found + 1), only those
    inside (``sdf <= 0``) when ``sdf`` is given; ``parts`` int16, ``sdf`` float32 of its shape.

    One pass in memory order (any view: the count does not depend on the order), in parallel.
    """
    # axes by decreasing stride: the inner loop walks memory (axis-first views are transposed)
    order = np.argsort([-abs(x) for x in parts.strides], kind="stable")
    p = parts.transpose(order)
    if p.size == 0:
        return np.zeros(0, np.int64)
    if sdf is None:
        return _count_labels(p, p, False, nb.get_num_threads())
    return _count_labels(p, sdf.transpose(order), True, nb.get_num_threads())


@nb.njit(cache=True, parallel=True)
def _count_labels(parts, sdf, inside_only, chunks):
    """:func:`part_counts` over ``chunks`` spans of axis 0 side by side (integer sums: the
    same counts whatever the number of chunks).
    """
    n0 = parts.shape[0]
    chunks = max(1, min(chunks, n0))
    hist = np.zeros((chunks, 32768), np.int64)  # every int16 label >= 0
    for c in nb.prange(chunks):
        for i in range(c * n0 // chunks, (c + 1) * n0 // chunks):
            for j in range(parts.shape[1]):
                for k in range(parts.shape[2]):
                    q = parts[i, j, k]
                    if q >= 0 and (not inside_only or sdf[i, j, k] <= 0):
                        hist[c, q] += 1
    total = np.zeros(32768, np.int64)
    top = -1
    for q in range(32768):
        for c in range(chunks):
            total[q] += hist[c, q]
        if total[q]:
            top = q
    return total[: top + 1]


def unlabel_far(
    sdf: np.ndarray, parts: np.ndarray, far: np.float32, layers: slice, axis: int
) -> None:
    """Part -1 (in place) where ``sdf > far`` in the output ``layers`` (a slice along axis 0).

    ``sdf``, ``parts`` (N, A, B) are axis-first; as views of C-ordered arrays in world order
    (the edit axis at ``axis``, what :func:`~partscale.edit.resample.empty_layers` makes) one
    parallel pass does it, else numpy.
    """
    s3, p3 = _rows(sdf, axis), _rows(parts, axis)
    if not np.may_share_memory(p3, parts):  # a copy: write through numpy instead
        np.copyto(parts[layers], np.int16(-1), where=sdf[layers] > far)
        return
    j0, j1, _ = layers.indices(sdf.shape[0])
    _unlabel_rows(s3, p3, np.float32(far), j0, max(j1, j0))


@nb.njit(cache=True, parallel=True)
def _unlabel_rows(sdf, parts, far, j0, j1):
    """parts[p, j, q] = -1 where sdf[p, j, q] > far, layers ``j0 <= j < j1`` of (P, N, Q)
    views; rows in parallel (unsigned indices: the inner loop vectorises).
    """
    nj = j1 - j0
    for t in nb.prange(sdf.shape[0] * nj):
        p = np.uint64(t // nj)
        j = np.uint64(j0 + t % nj)
        for q in range(np.uint64(0), np.uint64(sdf.shape[2])):
            if sdf[p, j, q] > far:
                parts[p, j, q] = -1


def update_parts_info(
    meta: dict[str, Any],
    parts: np.ndarray,
    r: ResolvedEdit,
    scale: float,
    copy_of: dict[int, tuple[int, int]],
) -> None:
    """Carry ``meta['parts_info']`` (the segment stage's part facts) through an edit.

    ``voxels`` is recounted; ``bbox`` (world box of the part's surface patch) is mapped along the
    axis by the edit itself; ``hull_volume`` is scaled with parts lying wholly inside the zone (all
    parts in global mode); other keys are kept. Each new (copied) part gets a copy of its
    original's entry with ``index`` and ``copy_of`` set, and its own display ``color`` (that
    of its new index), so copies are told apart wherever parts are drawn.
    """
    info = meta.get("parts_info")
    if not isinstance(info, list):
        return
    ax, s, e, d, mode = r.axis, r.start, r.end, r.dest, r.mode
    shift = d - e
    n_copies = r.n_copies if mode == "tile" else 1
    period = (d - s) / n_copies if n_copies else 0.0  # 0 copies: the zone collapses onto s
    lo = r.lo

    def forward(x: float, copy: int) -> float:
        if mode == "global":
            return lo + (x - lo) * scale
        if x < s:
            return x
        if x > e:
            return x + shift
        if n_copies == 0:  # a removed zone: what lay in it meets the join
            return s
        return s + copy * period + (x - s) * scale

    counts = part_counts(parts)
    n = counts.size
    by_index = {int(x.get("index", -1)): x for x in info if isinstance(x, dict)}
    # entries are changed by replacing their keys, never in place: shallow copies keep the
    # originals' facts for the copies made from them
    originals = {p: dict(x) for p, x in by_index.items()}
    for p in range(n):
        src, m = copy_of.get(p, (p, 0))
        base = originals.get(src)
        if base is None:
            continue
        entry = by_index.get(p)
        if entry is None:
            entry = _copy.deepcopy(base)
            entry["index"] = p
            entry["copy_of"] = src
            entry["color"] = palette_colour(p)
            info.append(entry)
        entry["voxels"] = int(counts[p]) if p < len(counts) else 0
        box = base.get("bbox")
        inner = box is not None and s < box[0][ax] and box[1][ax] < e
        if box is not None:
            new_box = _copy.deepcopy(box)
            # a part crossing the zone runs through every copy: its end lies in the last one
            last = m if inner else n_copies - 1
            new_box[0][ax] = forward(box[0][ax], m)
            new_box[1][ax] = forward(box[1][ax], last)
            entry["bbox"] = new_box
        if "hull_volume" in base and (inner or mode == "global"):
            entry["hull_volume"] = base["hull_volume"] * scale
    info.sort(key=lambda x: x.get("index", -1))


def renumber_copies(
    src_sdf: np.ndarray,
    src_parts: np.ndarray,
    out_parts: np.ndarray,
    plan: Plan,
    *,
    i_start: float,
    i_end: float,
) -> dict[int, tuple[int, int]]:
    """Give copies ``m >= 1`` of the parts lying wholly inside the zone new indices (in place).

    New indices follow the existing ones: copy ``m`` of inner part ``p`` (rank ``r`` among the
    ``q`` inner parts) becomes ``P + (m - 1) q + r``. Parts that cross the zone's planes run
    continuously through every copy and keep their index. Returns ``{new: (original, m)}``.
    """
    inner = inner_parts(src_sdf, src_parts, i_start, i_end)
    n_copies = int(plan.copy.max()) + 1
    if inner.size == 0 or n_copies < 2:
        return {}
    base = part_counts(src_parts).size  # the largest index + 1
    q = inner.size
    if base + (n_copies - 1) * q - 1 > np.iinfo(np.int16).max:
        raise InputError(
            f"tile: expected at most {np.iinfo(np.int16).max + 1} parts, got "
            f"{base + (n_copies - 1) * q}"
        )
    copy_of: dict[int, tuple[int, int]] = {}
    for m in range(1, n_copies):
        layers = np.flatnonzero(plan.in_slab & (plan.copy == m))
        if layers.size == 0:
            continue
        lut = np.arange(-1, base, dtype=np.int64)  # lut[p + 1] = p
        new = base + (m - 1) * q + np.arange(q)
        lut[inner + 1] = new
        for p, nw in zip(inner.tolist(), new.tolist(), strict=True):
            copy_of[nw] = (p, m)
        _relabel(out_parts, layers, lut)
    return copy_of


@nb.njit(cache=True, parallel=True)
def _relabel(parts, layers, lut):
    """``parts[j] = lut[parts[j] + 1]`` in place for the ``layers`` j of ``parts`` (N, A, B)."""
    for t in nb.prange(layers.size):
        j = layers[t]
        for a in range(parts.shape[1]):
            for b in range(parts.shape[2]):
                parts[j, a, b] = lut[parts[j, a, b] + 1]
