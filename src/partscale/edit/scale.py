"""Part-aware selective scaling of a CSDF: stretch, tile or global, then re-evaluation.

An edit names an axis, a zone ``[START, END]`` and a destination ``DEST`` for END (see
:mod:`partscale.edit.recipe`). Content before START is unchanged, ``[START, END]`` becomes
``[START, DEST]`` and content beyond END is translated by ``DEST - END``. The grid grows or shrinks
along the axis with the object and the voxel size never changes. The shift ``DEST - END`` is
snapped to a whole number of voxels (so the length is exact to half a voxel), which makes content
outside the zone an exact copy of the original voxels.
"""

from __future__ import annotations

import copy as _copy
import math
from typing import Any

import numpy as np
from scipy import ndimage

from .._util import check_memory, keyword_options, palette_colour
from ..csdf import CSDF
from ..errors import InputError
from ..progress import ProgressCallback, resolve, scaled
from .recipe import AXES, MODES, Edit, Recipe, forward_coordinate, source_coordinate, tile_count
from .reevaluate import BAND_VOXELS, reevaluate_arrays
from .resample import SEAM_VOXELS, Plan, apply_plan, lerp_layers, make_plan

#: Peak working bytes per output voxel of an edit (output arrays, float temporaries, masks).
BYTES_PER_VOXEL = 64  # 48, plus up to 16 where every voxel is re-evaluated (index, old value, flag)

#: An axial slope of the source distance below this counts as "nearest surface point lateral".
_LATERAL = 0.05

#: A slab scaled by less than this relative amount counts as rigid (error <= 1% of |distance|,
#: 0.04 voxel at the band's edge): tiles of whole periods are copies, not stretches.
_RIGID = 0.01


def _as_edit(edit: Edit | dict[str, Any]) -> Edit:
    if isinstance(edit, Edit):
        return Edit.parse(edit.to_json())
    return Edit.parse(edit)


def _fmt(v: float) -> str:
    return f"{v:.6g}"


def resolve_edit(csdf: CSDF, edit: Edit) -> dict[str, Any]:
    """Validate ``edit`` against ``csdf`` and resolve it to world units.

    Returns a dict with ``axis`` (int), ``start``, ``end``, ``dest`` (as given, resolved),
    ``dest_snapped``, ``shift`` (whole voxels), ``lo``, ``hi`` (solid extent along the axis) and
    ``shape`` (the output grid's shape). Raises :class:`InputError` on bad input.
    """
    ax = edit.axis_index
    h = csdf.voxel_size
    sb = csdf.surface_bounds()
    lo, hi = float(sb[0, ax]), float(sb[1, ax])
    s, e, d = edit.resolve(lo, hi)
    if not all(map(math.isfinite, (s, e, d, (d - e) / h))):
        raise InputError(
            f"zone, to: expected finite positions, got zone [{_fmt(s)}, {_fmt(e)}], to {_fmt(d)}"
        )
    name = AXES[ax]
    if not s < e:
        raise InputError(f"zone: expected start < end, got start {_fmt(s)} >= end {_fmt(e)}")
    if not d > s:
        raise InputError(f"to: expected DEST > START {_fmt(s)}, got {_fmt(d)}")
    tol = h / 2
    if s < lo - tol or e > hi + tol:
        raise InputError(
            f"zone: expected inside the solid's extent [{_fmt(lo)}, {_fmt(hi)}] along {name}, "
            f"got [{_fmt(s)}, {_fmt(e)}]"
        )
    if e - s < 2 * h:
        raise InputError(
            f"zone: expected at least two voxels thick ({_fmt(2 * h)}), got {_fmt(e - s)}"
        )
    shift = round((d - e) / h)
    d_snap = e + shift * h
    if d_snap - s < h:
        raise InputError(
            f"to: expected DEST at least one voxel ({_fmt(h)}) beyond START {_fmt(s)}, "
            f"got {_fmt(d)}"
        )
    shape = list(csdf.shape)
    shape[ax] += shift
    check_memory(tuple(shape), BYTES_PER_VOXEL, what=f"scale along {name} to {_fmt(d)}")
    return {
        "axis": ax,
        "start": s,
        "end": e,
        "dest": d,
        "dest_snapped": d_snap,
        "shift": shift,
        "lo": lo,
        "hi": hi,
        "shape": tuple(shape),
    }


def _plan(csdf: CSDF, r: dict[str, Any], mode: str, *, blend: bool = True) -> Plan:
    ax = r["axis"]
    return make_plan(
        mode=mode,
        n_out=r["shape"][ax],
        origin=float(csdf.origin[ax]),
        h=csdf.voxel_size,
        start=r["start"],
        end=r["end"],
        dest=r["dest_snapped"],
        lo=r["lo"],
        hi=r["hi"],
        blend=blend,
    )


def _inner_parts(sdf: np.ndarray, parts: np.ndarray, i_start: float, i_end: float) -> np.ndarray:
    """Part indices whose inside voxels all lie strictly between layers ``i_start``, ``i_end``.

    Arrays are axis-first (N, A, B).
    """
    n_parts = int(parts.max()) + 1 if parts.size else 0
    if n_parts <= 0:
        return np.zeros(0, np.int64)
    inside = (sdf <= 0) & (parts >= 0)
    layer = np.broadcast_to(np.arange(sdf.shape[0])[:, None, None], sdf.shape)
    labels = np.where(inside, parts.astype(np.int64) + 1, 0)
    idx = np.arange(1, n_parts + 1)
    present = ndimage.sum_labels(np.ones(sdf.shape), labels, idx) > 0
    mn = np.asarray(ndimage.minimum(layer, labels, idx), float)
    mx = np.asarray(ndimage.maximum(layer, labels, idx), float)
    keep = present & (mn > i_start) & (mx < i_end)
    return np.flatnonzero(keep)


def _update_parts_info(
    meta: dict[str, Any],
    parts: np.ndarray,
    r: dict[str, Any],
    mode: str,
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
    ax, s, e, d = r["axis"], r["start"], r["end"], r["dest_snapped"]
    shift = d - e
    n_copies = tile_count(e - s, d - s) if mode == "tile" else 1
    period = (d - s) / n_copies
    lo = r["lo"]

    def forward(x: float, copy: int) -> float:
        if mode == "global":
            return lo + (x - lo) * scale
        if x < s:
            return x
        if x > e:
            return x + shift
        return s + copy * period + (x - s) * scale

    n = int(parts.max()) + 1 if parts.size and parts.max() >= 0 else 0
    counts = np.bincount(parts[parts >= 0].ravel(), minlength=n)
    by_index = {int(x.get("index", -1)): x for x in info if isinstance(x, dict)}
    originals = {p: _copy.deepcopy(x) for p, x in by_index.items()}
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


def _recompute_mask(
    src_sdf: np.ndarray,
    out_sdf: np.ndarray,
    plan: Plan,
    *,
    mode: str,
    y: np.ndarray,
    start: float,
    end: float,
    dest: float,
    h: float,
    band: float,
) -> np.ndarray:
    """Voxels (axis-first, output grid) whose distance could have changed and must be recomputed.

    The paper's rule: voxels whose old |distance| exceeds their distance to the zone's planes, plus
    the resampled slab. Among those, a voxel keeps its resampled value when that value is provably
    still the distance: the slab grows (scale >= 1, so the inverse map is 1-Lipschitz and old
    distances are lower bounds) and its nearest surface point lies square to the axis (axial slope
    of the source distance ~ 0), so its distance is carried over unchanged; or, in a tile copy at
    scale ~1, the ball of its distance lies within its copy (a pure translation).
    """
    lim = (band + 1.0) * h * max(1.0, 1.0 / plan.scale)
    mask = np.zeros(out_sdf.shape, np.uint8)
    n_copies = int(plan.copy.max()) + 1
    if mode == "tile" and abs(plan.scale - 1.0) <= _RIGID:
        # Copies at scale ~1 are translations of the slab, and the first and last copy continue
        # the content before and after the zone exactly: a voxel's neighbourhood is unchanged
        # unless the ball of its distance reaches an internal seam (or it lies in a blend).
        period = (dest - start) / n_copies
        seams = start + period * np.arange(1, n_copies)
        if seams.size == 0:
            return mask
        to_seam = np.abs(y[:, None] - seams[None, :]).min(axis=1)
        reach = np.maximum(to_seam - SEAM_VOXELS * h, 0.0).astype(np.float32)
        rows = np.flatnonzero(reach <= lim)
        a = np.abs(out_sdf[rows])
        mask[rows] = (a <= lim) & (a >= reach[rows, None, None])
        return mask
    if mode == "global":
        j0, j1 = 0, out_sdf.shape[0]
        affected = np.abs(out_sdf) <= lim
    else:
        # distance of each output layer to the zone (0 inside the slab), one voxel of slack;
        # layers farther from the zone than the band cannot be affected
        gap = np.where(y < start, start - y, np.where(y > dest, y - dest, 0.0))
        gap = np.maximum(gap - h, 0.0).astype(np.float32)
        rows = np.flatnonzero(gap <= lim)
        j0, j1 = int(rows[0]), int(rows[-1]) + 1
        a = np.abs(out_sdf[j0:j1])
        affected = (a <= lim) & (a >= gap[j0:j1, None, None])
    cand = np.nonzero(affected)
    cand = (cand[0] + j0, cand[1], cand[2])
    n_src = src_sdf.shape[0]
    xa = plan.xa[cand[0]]
    xc = np.clip(xa, 0, n_src - 1)
    i0 = np.floor(xc).astype(np.int64)
    i1 = np.minimum(i0 + 1, n_src - 1)
    slope = np.zeros(len(xa), np.float32)
    for i in (i0, i1):
        up = np.minimum(i + 1, n_src - 1)
        dn = np.maximum(i - 1, 0)
        g = (src_sdf[up, cand[1], cand[2]] - src_sdf[dn, cand[1], cand[2]]) / np.maximum(
            (up - dn) * h, h
        )
        np.maximum(slope, np.abs(g), out=slope)
    keep = slope <= _LATERAL
    if plan.scale < 1.0 - _RIGID:
        # A shrinking slab can bring surface closer: everything affected is recomputed. Outside
        # the slab, a voxel whose nearest point is square to the axis still has that point, so
        # its old distance caps the new one (code 2): the exact value wherever nothing came
        # closer, immune to the facets' chamfer of sharp edges.
        code = np.where(keep & ~plan.in_slab[cand[0]], 2, 1).astype(np.uint8)
        mask[cand] = code
        return mask
    if mode == "tile":
        # Copies are not one monotone map: a slab voxel keeps its value only if the ball of its
        # distance stays inside its own copy (and it is not in a seam blend). Voxels outside the
        # slab see every copy farther than its source, so the growth argument holds for them.
        n_copies = int(plan.copy.max()) + 1
        period = (dest - start) / n_copies
        yy = y[cand[0]]
        c = plan.copy[cand[0]]
        room = np.minimum(yy - (start + c * period), start + (c + 1) * period - yy)
        inside = plan.in_slab[cand[0]]
        # a copy at scale ~1 is a translation: inside that ball nothing else changed
        rigid = abs(plan.scale - 1.0) <= _RIGID
        ok_in = (plan.beta[cand[0]] == 0) & (np.abs(out_sdf[cand]) < room) & (keep | rigid)
        keep = np.where(inside, ok_in, keep)
    sel = ~keep
    mask[cand[0][sel], cand[1][sel], cand[2][sel]] = 1
    return mask


def _renumber_copies(
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
    inner = _inner_parts(src_sdf, src_parts, i_start, i_end)
    n_copies = int(plan.copy.max()) + 1
    if inner.size == 0 or n_copies < 2:
        return {}
    base = int(src_parts.max()) + 1
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
        block = out_parts[layers]
        out_parts[layers] = lut[block.astype(np.int64) + 1].astype(np.int16)
    return copy_of


def _edit_arrays(
    csdf: CSDF, r: dict[str, Any], mode: str, *, naive: bool = False, band: float = BAND_VOXELS
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """Resample (and unless ``naive``, re-evaluate); returns arrays in world axis order."""
    ax = r["axis"]
    h = csdf.voxel_size
    plan = _plan(csdf, r, mode, blend=not naive)
    src_sdf = np.moveaxis(csdf.sdf, ax, 0)
    src_rgb = np.moveaxis(csdf.rgb, ax, 0)
    src_parts = np.moveaxis(csdf.parts, ax, 0)
    extra: dict[str, Any] = {"scale": plan.scale}
    if naive:
        out_sdf = lerp_layers(src_sdf, plan.xa)
        out_rgb = lerp_layers(src_rgb, plan.xa)
        ix = np.clip(np.rint(plan.xa), 0, src_parts.shape[0] - 1).astype(np.int64)
        out_parts = src_parts[ix]
    else:
        out_sdf, out_rgb, out_parts = apply_plan(src_sdf, src_rgb, src_parts, plan)
        if mode == "tile":
            o = float(csdf.origin[ax])
            extra["copy_of"] = _renumber_copies(
                src_sdf,
                src_parts,
                out_parts,
                plan,
                i_start=(r["start"] - o) / h,
                i_end=(r["end"] - o) / h,
            )
        y = float(csdf.origin[ax]) + np.arange(out_sdf.shape[0]) * h
        mask = _recompute_mask(
            src_sdf,
            out_sdf,
            plan,
            mode=mode,
            y=y,
            start=r["start"],
            end=r["end"],
            dest=r["dest_snapped"],
            h=h,
            band=band,
        )
        eff_band = (band + 1.0) * max(1.0, 1.0 / plan.scale)
        # what re-evaluation may change, as resampled: to tell the voxels it did change
        todo = np.flatnonzero(mask)
        sdf_was, parts_was = out_sdf.ravel()[todo], out_parts.ravel()[todo]
        extra["reevaluated"] = reevaluate_arrays(
            out_sdf, out_rgb, out_parts, h, mask, band=eff_band
        )
        # parts are labelled up to the band outside the surface (as the segment stage does):
        # voxels the edit resampled or recomputed lose theirs beyond it; the copied layers
        # outside the zone keep their labels as they are, like their distances
        far = np.float32(BAND_VOXELS * h)
        flat_sdf, flat_parts = out_sdf.ravel(), out_parts.ravel()
        moved = (flat_sdf[todo] != sdf_was) | (flat_parts[todo] != parts_was)
        flat_parts[todo[moved & (flat_sdf[todo] > far)]] = -1
        layers = plan.in_slab | (plan.beta > 0)
        slab_parts = out_parts[layers]
        slab_parts[out_sdf[layers] > far] = -1
        out_parts[layers] = slab_parts
    back = (np.moveaxis(out_sdf, 0, ax), np.moveaxis(out_rgb, 0, ax), np.moveaxis(out_parts, 0, ax))
    return (*back, extra)


def _history_entry(edit: Edit, r: dict[str, Any], extra: dict[str, Any], op: str) -> dict:
    entry = {
        "op": op,
        "edit": {
            "axis": AXES[r["axis"]],
            "zone": [r["start"], r["end"]],
            "to": r["dest"],
            "mode": edit.mode,
        },
        "given": edit.to_json(),
        "shift_voxels": int(r["shift"]),
        "to_snapped": r["dest_snapped"],
        "scale": extra["scale"],
    }
    if edit.mode == "tile":
        entry["copies"] = tile_count(r["end"] - r["start"], r["dest_snapped"] - r["start"])
    if "reevaluated" in extra:
        entry["reevaluated_voxels"] = int(extra["reevaluated"])
    return entry


@keyword_options
def apply_edit(
    csdf: CSDF, edit: Edit | dict[str, Any], *, progress: ProgressCallback | None = None
) -> CSDF:
    """Apply one zone edit (stretch, tile or global) with re-evaluation.

    Parameters
    ----------
    csdf : CSDF
        The object; positions of ``edit`` in ``%`` refer to its solid's extent along the axis.
    edit : Edit or dict
        See :mod:`partscale.edit.recipe` (JSON form accepted).

    Returns
    -------
    CSDF
        New grid, longer or shorter along the axis by ``round((DEST - END) / voxel_size)`` voxels,
        same origin and voxel size. Outside the zone the voxels are exact copies (translated beyond
        it); within ``BAND_VOXELS`` of the surface every recomputed distance is the distance to
        the edited surface as the grid represents it (exact for flat surface; see
        :mod:`partscale.edit` for sharp edges and corners). ``meta['history']`` gains the edit
        in world units (and as given).

    Notes
    -----
    ``tile`` blends the copies across each internal seam; thin features on one side of a seam
    only (the sliver a zone plane leaves where it cuts a board) fade there. Put the zone's
    planes in the gaps between repeated elements or through the middle of one (see
    :func:`~partscale.edit.resample.make_plan`); :func:`naive_edit` concatenates without
    blending.
    """
    return _apply_edit(csdf, edit, progress=progress)


def _apply_edit(
    csdf: CSDF,
    edit: Edit | dict[str, Any],
    *,
    progress: ProgressCallback | None = None,
    record: dict[str, Any] | None = None,
) -> CSDF:
    report = resolve(progress)
    edit = _as_edit(edit)
    r = resolve_edit(csdf, edit)
    report(0.05, f"{edit.mode} along {edit.axis}")
    sdf, rgb, parts, extra = _edit_arrays(csdf, r, edit.mode)
    report(0.9, "recording")
    meta = _copy.deepcopy(csdf.meta)
    if isinstance(meta.get("parts_info"), list):
        _update_parts_info(meta, parts, r, edit.mode, extra["scale"], extra.get("copy_of", {}))
    entry = _history_entry(edit, r, extra, "scale")
    if edit.mode == "global":  # what its plane map needs (recipe coordinates)
        entry.update(lo=r["lo"], hi=r["hi"])
    entry.update(record or {})
    out = csdf.with_history(entry, sdf=sdf, rgb=rgb, parts=parts, meta=meta)
    report(1.0, "done")
    return out


@keyword_options
def apply_recipe(
    csdf: CSDF,
    recipe: Recipe | dict[str, Any] | list,
    *,
    progress: ProgressCallback | None = None,
) -> CSDF:
    """Apply every edit of ``recipe`` in order, each to the previous result.

    All positions refer to ``csdf`` as given (see :mod:`partscale.edit.recipe`): edit ``k``'s
    planes are carried through the edits before it on the same axis
    (:func:`~partscale.edit.forward_coordinate`) and its destination keeps its change. Each
    history entry records the edit as applied (``edit``, world units on the object it applied
    to), as given (``given``), and on the recipe's input (``input``, world units) with its
    place in the recipe (``recipe_step``).
    """
    if not isinstance(recipe, Recipe):
        recipe = Recipe.parse(recipe)
    n = len(recipe.edits)
    bounds = csdf.surface_bounds() if n else None
    applied: list[tuple[int, dict[str, Any]]] = []  # (axis, forward-map arguments)
    out = csdf
    for i, e in enumerate(recipe.edits):
        ax = e.axis_index
        s, en, d = e.resolve(float(bounds[0, ax]), float(bounds[1, ax]))
        planes = np.array([s, en], dtype=np.float64)
        for a, kw in applied:
            if a == ax:
                planes = forward_coordinate(planes, **kw)
        s2, e2 = float(planes[0]), float(planes[1])
        d2 = e2 + (d - en)
        step = Edit(e.axis, s2, e2, d2, e.mode)
        record = {
            "given": e.to_json(),
            "input": {"zone": [s, en], "to": d},
            "recipe_step": i,
        }
        out = _apply_edit(out, step, progress=scaled(progress, i / n, (i + 1) / n), record=record)
        h = out.meta["history"][-1]
        kw = {"mode": e.mode, "start": s2, "end": e2, "dest": h["to_snapped"]}
        if e.mode == "global":
            kw.update(lo=h["lo"], hi=h["hi"])
        applied.append((ax, kw))
    return out


@keyword_options
def scale(
    csdf: CSDF,
    *,
    axis: str,
    zone: tuple[float | str, float | str],
    to: float | str,
    mode: str = "stretch",
    progress: ProgressCallback | None = None,
) -> CSDF:
    """Convenience: ``apply_edit(csdf, {"axis": axis, "zone": zone, "to": to, "mode": mode})``.

    Positions are floats in the object's units or strings like ``'30%'``.
    """
    e = Edit.parse({"axis": axis, "zone": zone, "to": to, "mode": mode})
    return apply_edit(csdf, e, progress=progress)


def naive_edit(csdf: CSDF, edit: Edit | dict[str, Any]) -> CSDF:
    """BASELINE, not for use: the edit as the authors' public prototype does it.

    Per-column linear resampling of the slab (sdf and colour; parts by nearest source voxel),
    plain concatenation of the copies for ``tile`` (no seam blending, no new part indices), and
    NO re-evaluation: stretched distances stay stretched. Same grid, snapping and validation as
    :func:`apply_edit`, so the two compare voxel for voxel. The evaluation and the benchmark
    measure :func:`apply_edit` against it.
    """
    edit = _as_edit(edit)
    r = resolve_edit(csdf, edit)
    sdf, rgb, parts, extra = _edit_arrays(csdf, r, edit.mode, naive=True)
    return csdf.with_history(
        _history_entry(edit, r, extra, "naive_scale"), sdf=sdf, rgb=rgb, parts=parts
    )


def _preimage(y: float, kw: dict[str, Any]) -> float:
    """A source position whose plane lands exactly on ``y`` after the edit ``kw`` (or nearest)."""
    if kw["mode"] == "global":
        lo, hi = kw["lo"], kw["hi"]
        x = lo + (y - lo) / ((hi - lo + kw["dest"] - kw["end"]) / (hi - lo))
    elif y <= kw["start"]:
        return y
    elif y >= kw["dest"]:
        x = y - (kw["dest"] - kw["end"])
    else:  # inside the zone: through the first copy's (or the stretch's) scale
        x = float(source_coordinate(np.array([y]), **{**kw, "mode": "stretch"})[0])
        if kw["mode"] == "tile":
            n = tile_count(kw["end"] - kw["start"], kw["dest"] - kw["start"])
            x = kw["start"] + (x - kw["start"]) * n
    # floating point: a neighbour within a few ulps that maps back exactly, so replay is exact
    cand, lo_c, hi_c = [x], x, x
    for _ in range(8):
        lo_c, hi_c = float(np.nextafter(lo_c, -np.inf)), float(np.nextafter(hi_c, np.inf))
        cand += [lo_c, hi_c]
    for c in cand:
        if float(forward_coordinate(np.array([c]), **kw)[0]) == y:
            return c
    return x


def recipe_from_history(csdf: CSDF, *, after: CSDF | None = None) -> Recipe:
    """The recipe of the scale edits recorded in ``csdf.meta['history']`` (world units).

    ``apply_recipe(original, recipe_from_history(result, after=original))`` reproduces ``result``
    bit for bit. ``after``: skip the history entries ``after`` already had. Positions are on the
    original (recipe coordinates, see :mod:`partscale.edit.recipe`): edits recorded by separate
    runs are carried back through the earlier ones (exactly wherever floating point allows).
    """
    hist = csdf.meta.get("history", [])
    if after is not None:
        hist = hist[len(after.meta.get("history", [])) :]
    entries = [h for h in hist if isinstance(h, dict) and h.get("op") == "scale"]
    if not entries:
        raise InputError("history: expected at least one scale edit, got none")
    edits: list[Edit] = []
    earlier: list[tuple[int, dict[str, Any]]] = []  # all edits before the current run
    run: list[tuple[int, dict[str, Any]]] = []  # edits of the current run
    for h in entries:
        applied = Edit.parse(h["edit"])
        ax = applied.axis_index
        if h.get("recipe_step", 0) == 0:
            earlier += run
            run = []
        if "input" in h:
            s, e = h["input"]["zone"]
            d = h["input"]["to"]
        else:  # recorded on the object it applied to (a single edit)
            s, e, d = applied.resolve(0.0, 1.0)
        # from this run's input back to the original, through every earlier run's edits
        for a, kw in reversed(earlier):
            if a == ax:
                s0, e0 = _preimage(s, kw), _preimage(e, kw)
                d = e0 + (d - e)
                s, e = s0, e0
        edits.append(Edit(applied.axis, s, e, d, applied.mode))
        kw = {
            "mode": applied.mode,
            "start": float(h["edit"]["zone"][0]),
            "end": float(h["edit"]["zone"][1]),
            "dest": float(h["to_snapped"]),
        }
        if applied.mode == "global":
            kw.update(lo=float(h.get("lo", 0.0)), hi=float(h.get("hi", 1.0)))
        run.append((ax, kw))
    return Recipe(tuple(edits))


__all__ = [
    "BAND_VOXELS",
    "MODES",
    "apply_edit",
    "apply_recipe",
    "naive_edit",
    "recipe_from_history",
    "resolve_edit",
    "scale",
]
