"""Part-aware selective scaling of a CSDF: stretch, tile or global, then re-evaluation.

An edit names an axis, a zone ``[START, END]`` and a destination ``DEST`` for END (see
:mod:`partscale.edit.recipe`). Content before START is unchanged, ``[START, END]`` becomes
``[START, DEST]`` and content beyond END is translated by ``DEST - END``. The grid grows or shrinks
along the axis with the object and the voxel size never changes. The shift ``DEST - END`` is
snapped to a whole number of voxels (so the length is exact to half a voxel), which makes content
outside the zone an exact copy of the original voxels.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._memory import check_memory
from .._options import keyword_options
from ..csdf import BAND_VOXELS, CSDF
from ..errors import InputError
from ..progress import ProgressCallback, resolve, scaled
from ._recompute import recompute_mask
from .parts import renumber_copies, unlabel_far, update_parts_info
from .recipe import (
    AXES,
    CountEdit,
    Edit,
    HelixZone,
    ObliqueZone,
    RadialZone,
    Recipe,
    RotationZone,
    ScrewZone,
    forward_coordinate,
    source_coordinate,
    tile_count,
)
from .reevaluate import reevaluate_arrays
from .resample import Plan, apply_plan, empty_layers, lerp_layers, make_plan
from .resolved import BYTES_PER_VOXEL, ResolvedEdit, resolve_edit
from .warp import apply_warp, moved_axes, warp_grid


def _as_edit(edit: Edit | dict[str, Any]) -> Edit:
    if isinstance(edit, Edit):
        return Edit.parse(edit.to_json())
    return Edit.parse(edit)


def _plan(csdf: CSDF, r: ResolvedEdit, *, blend: bool = True) -> Plan:
    ax = r.axis
    return make_plan(
        mode=r.mode,
        n_out=csdf.shape[ax] + r.shift_voxels(csdf.voxel_size),
        origin=float(csdf.origin[ax]),
        h=csdf.voxel_size,
        start=r.start,
        end=r.end,
        dest=r.dest,
        lo=r.lo,
        hi=r.hi,
        blend=blend,
    )


@dataclass(frozen=True)
class _Edited:
    """The arrays an edit made (world axis order) and what its history records about them."""

    sdf: np.ndarray
    rgb: np.ndarray
    parts: np.ndarray
    scale: float
    #: new part index -> (original index, copy number), for tiled copies of inner parts
    copy_of: dict[int, tuple[int, int]] = field(default_factory=dict)
    #: voxels re-evaluated; None for the naive baseline (no re-evaluation)
    reevaluated: int | None = None
    #: voxels of cut slivers the tile seams left out, per zone plane ("start", "end")
    slivers: dict[str, int] = field(default_factory=dict)


def _edit_arrays(
    csdf: CSDF, r: ResolvedEdit, *, naive: bool = False, band: float = BAND_VOXELS
) -> _Edited:
    """Resample (and unless ``naive``, re-evaluate)."""
    ax, mode = r.axis, r.mode
    h = csdf.voxel_size
    plan = _plan(csdf, r, blend=not naive)
    src_sdf = np.moveaxis(csdf.sdf, ax, 0)
    src_rgb = np.moveaxis(csdf.rgb, ax, 0)
    src_parts = np.moveaxis(csdf.parts, ax, 0)
    copy_of: dict[int, tuple[int, int]] = {}
    reevaluated = None
    slivers: dict[str, int] = {}
    if naive:
        m = len(plan.xa)
        out_sdf, out_rgb, out_parts = (
            lerp_layers(a, x, empty_layers((m, *a.shape[1:]), a.dtype, ax))
            for a, x in (
                (src_sdf, plan.xa),
                (src_rgb, plan.xa),
                # nearest source layer: integer positions are copies
                (src_parts, np.clip(np.rint(plan.xa), 0, src_parts.shape[0] - 1)),
            )
        )
    else:
        # the part-aware modes keep elements thinner than the compression or lying at a seam;
        # global stays the plain baseline scaling
        out_sdf, out_rgb, out_parts, slivers = apply_plan(
            src_sdf,
            src_rgb,
            src_parts,
            plan,
            keep_thin=None if mode == "global" else h,
            axis=ax,
        )
        if mode == "tile":
            o = float(csdf.origin[ax])
            copy_of = renumber_copies(
                src_sdf,
                src_parts,
                out_parts,
                plan,
                i_start=(r.start - o) / h,
                i_end=(r.end - o) / h,
            )
            _cap_seam_layers(out_sdf, plan, np.float32(band * h))
        y = float(csdf.origin[ax]) + np.arange(out_sdf.shape[0]) * h
        mask, j0 = recompute_mask(
            src_sdf,
            out_sdf,
            plan,
            mode=mode,
            y=y,
            start=r.start,
            end=r.end,
            dest=r.dest,
            h=h,
            band=band,
        )
        eff_band = (band + 1.0) * max(1.0, 1.0 / plan.scale)
        # parts are labelled up to the band outside the surface (as the segment stage does):
        # voxels re-evaluation changed lose theirs beyond it (the only ones the mask could move;
        # the copied layers outside the zone keep their labels as they are, like their distances)
        far = np.float32(BAND_VOXELS * h)
        reevaluated = reevaluate_arrays(
            out_sdf, out_rgb, out_parts, h, mask, band=eff_band, row0=j0, far=float(far)
        )
        # the slab (between START and the new END, seams inside it) is one run of layers: a view
        layers = np.flatnonzero(plan.in_slab | (plan.beta > 0))
        if layers.size:
            slab = slice(int(layers[0]), int(layers[-1]) + 1)
            unlabel_far(out_sdf, out_parts, far, slab, ax)
    sdf, rgb, parts = (np.moveaxis(a, 0, ax) for a in (out_sdf, out_rgb, out_parts))
    # written in world order and nothing else holds them: read-only, the CSDF takes them as
    # they are instead of copying (no full copy beyond the output)
    for a in (sdf, rgb, parts):
        a.flags.writeable = False
    return _Edited(
        sdf,
        rgb,
        parts,
        plan.scale,
        copy_of,
        reevaluated,
        slivers,
    )


def _history_entry(csdf: CSDF, edit: Edit, r: ResolvedEdit, done: _Edited, op: str) -> dict:
    entry = {
        "op": op,
        "edit": {
            "axis": AXES[r.axis],
            "zone": [r.start, r.end],
            "to": r.given_dest,
            "mode": edit.mode,
        },
        "given": edit.to_json(),
        "shift_voxels": r.shift_voxels(csdf.voxel_size),
        "to_snapped": r.dest,
        "scale": done.scale,
    }
    if edit.mode == "tile":
        entry["copies"] = r.n_copies
    if done.reevaluated is not None:
        entry["reevaluated_voxels"] = int(done.reevaluated)
    if done.slivers:
        # a zone plane cut an element: its sliver is not repeated at the inner seams
        entry["slivers_left_out"] = dict(done.slivers)
    return entry


@keyword_options
def _cap_seam_layers(sdf: np.ndarray, plan: Plan, cap: np.float32) -> None:
    """Cap ``|sdf|`` (axis-first, in place) at ``cap`` in a tile's seam blend layers.

    A blend of two copies' distances is no distance: where one copy is far outside and the other
    near its surface (or inside), the blend can exceed the band while the surface it makes lies a
    voxel away; re-evaluation, which recomputes only voxels within the band, would leave such a
    value (3 voxels too far, 2 % of a radiator's seam band at 256). Capped, they are recomputed;
    one that finds no surface within the band keeps the cap, a bound that keeps the sign, as
    beyond the band everywhere.
    """
    rows = np.flatnonzero(plan.beta > 0)
    if rows.size:
        sdf[rows] = np.clip(sdf[rows], -cap, cap)


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
    ``tile`` blends the copies across each internal seam; an element on one side of a seam only
    (a thin shelf next to a zone plane) is kept whole in its copy rather than faded, while the
    sliver a plane cuts off a board that goes on past it is left out at the inner seams (the
    board stays whole once, beside the copies; the history's ``slivers_left_out`` counts its
    voxels per plane), and ``stretch`` or ``tile`` compressing a slab keeps
    elements (and gaps) thinner than the compression, each on at least one voxel (see
    :func:`~partscale.edit.resample.apply_plan`). :func:`naive_edit` concatenates without
    blending and resamples linearly.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import apply_edit
    >>> longer = apply_edit(bar, {"axis": "x", "zone": [0.3, 0.6], "to": 0.8})
    >>> bar.shape, longer.shape, round(float(longer.surface_bounds()[1, 0]), 3)
    ((27, 11, 11), (31, 11, 11), 1.2)
    """
    return _apply_edit(csdf, edit, progress=progress)


def _apply_edit(
    csdf: CSDF,
    edit: Edit | dict[str, Any],
    *,
    progress: ProgressCallback | None = None,
    record: dict[str, Any] | None = None,
    given: Edit | None = None,
) -> CSDF:
    report = resolve(progress)
    edit = _as_edit(edit)
    r = resolve_edit(csdf, edit, given=given)
    report(0.05, f"{edit.mode} along {edit.axis}")
    done = _edit_arrays(csdf, r)
    report(0.9, "recording")
    meta = dict(csdf.meta)  # the history is shared (read-only); only parts_info changes here
    if isinstance(meta.get("parts_info"), list):
        # update_parts_info replaces keys and never changes a value in place: shallow copies of
        # the entries leave the input's untouched (the new CSDF copies its meta anyway)
        meta["parts_info"] = [dict(x) if isinstance(x, dict) else x for x in meta["parts_info"]]
        update_parts_info(meta, done.parts, r, done.scale, done.copy_of)
    entry = _history_entry(csdf, edit, r, done, "scale")
    if edit.mode == "global":  # what its plane map needs (recipe coordinates)
        entry.update(lo=r.lo, hi=r.hi)
    entry.update(record or {})
    # the arrays are the edit's own, made from a valid CSDF: not scanned again
    out = csdf.with_trusted_history(entry, sdf=done.sdf, rgb=done.rgb, parts=done.parts, meta=meta)
    report(1.0, "done")
    return out


def _carried(
    e: Edit, bounds: np.ndarray, applied: list[tuple[int, dict[str, Any]]]
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """``e``'s (start, end, dest) on the recipe's input, and carried through the ``applied``
    edits before it on the same axis (recipe coordinates); the destination keeps its change.
    """
    ax = e.axis_index
    s, en, d = e.resolve(float(bounds[0, ax]), float(bounds[1, ax]))
    planes = np.array([s, en], dtype=np.float64)
    for a, kw in applied:
        if a == ax:
            planes = forward_coordinate(planes, **kw)
    s2, e2 = float(planes[0]), float(planes[1])
    # a destination at the start stays there exactly (tile: 0 copies, the zone removed)
    return (s, en, d), (s2, e2, s2 if d == s else e2 + (d - en))


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

    Parameters
    ----------
    csdf : CSDF
        The object.
    recipe : Recipe, dict or list
        A :class:`Recipe`, its JSON form, or a list of edits.
    progress : callable(fraction, message), optional
        Called as the work goes on.

    Returns
    -------
    CSDF
        The object after the last edit.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.edit import apply_recipe
    >>> table = ingest.load(data.table(), res=64)
    >>> recipe = {"version": 1, "edits": [
    ...     {"axis": "x", "zone": ["35%", "65%"], "to": "105%"},
    ...     {"axis": "y", "zone": ["20%", "80%"], "to": "90%"},
    ... ]}
    >>> longer = apply_recipe(table, recipe)
    >>> [e["op"] for e in longer.meta["history"]]
    ['import', 'scale', 'scale']
    """
    if not isinstance(recipe, Recipe):
        recipe = Recipe.parse(recipe, units=csdf.meta.get("units"))
    n = len(recipe.edits)
    if n > 1:
        # refused before its first edits are computed (a single edit's own check, which names
        # it, comes before any work anyway)
        check_recipe_memory(csdf, recipe, what=f"a recipe of {n} edits")
    check_mixed(recipe)
    for i, e in enumerate(recipe.edits):
        if isinstance(e, CountEdit):
            raise InputError(
                f"edits[{i}]: expected zone edits, got a count ({e.copies:+d} along {e.axis}) "
                "unresolved; resolve it on the object first (partscale.zones.resolve_counts)"
            )
    bounds = csdf.surface_bounds() if n else None
    applied: list[tuple[int, dict[str, Any]]] = []  # (axis, forward-map arguments)
    out = csdf
    for i, e in enumerate(recipe.edits):
        if isinstance(e, CountEdit):  # refused above
            continue
        if not isinstance(e, Edit):  # a radial or oblique zone, steps: positions as given
            report = scaled(progress, i / n, (i + 1) / n)
            report(0.0, type(e).__name__)
            out = apply_warp(out, e, record={"given": e.to_json(), "recipe_step": i})
            continue
        ax = e.axis_index
        assert bounds is not None  # computed whenever there are edits
        (s, en, d), (s2, e2, d2) = _carried(e, bounds, applied)
        step = Edit(e.axis, s2, e2, d2, e.mode)
        record = {
            "given": e.to_json(),
            "input": {"zone": [s, en], "to": d},
            "recipe_step": i,
        }
        # the user's text is echoed in messages only where nothing carried its positions (after
        # an edit on the same axis, 10% of the input is elsewhere on this object)
        given = None if any(a == ax for a, _ in applied) else e
        out = _apply_edit(
            out, step, progress=scaled(progress, i / n, (i + 1) / n), record=record, given=given
        )
        h = out.meta["history"][-1]
        kw = {"mode": e.mode, "start": s2, "end": e2, "dest": h["to_snapped"]}
        if h.get("copies") == 0:  # a removed zone's start snapped with its destination
            kw["start"] = h["to_snapped"]
        if e.mode == "global":
            kw.update(lo=h["lo"], hi=h["hi"])
        applied.append((ax, kw))
    return out


def check_mixed(recipe: Recipe) -> None:
    """Refuse (one line) a recipe holding a radial or oblique zone and a zone across an axis that
    zone moves content along: the one's positions could not be carried through the other.
    """
    warps = [(i, e) for i, e in enumerate(recipe.edits) if not isinstance(e, Edit | CountEdit)]
    for i, w in warps:
        for j, e in enumerate(recipe.edits):
            if isinstance(e, Edit) and e.axis_index in moved_axes(w):
                kind = {
                    RadialZone: "radial",
                    ScrewZone: "step",
                    HelixZone: "helix",
                    RotationZone: "rotation",
                }.get(type(w), "oblique")
                raise InputError(
                    f"edits[{j}]: expected no zone along {e.axis} in a recipe with the {kind} "
                    f"zone edits[{i}] (it moves content along {e.axis}), got one; apply them "
                    "as two recipes"
                )


def check_recipe_memory(csdf: CSDF, recipe: Recipe | dict[str, Any] | list, *, what: str) -> None:
    """Refuse a recipe whose result would not fit in memory, before any work.

    Refuse (:class:`~partscale.errors.MemoryLimitError`) a recipe whose result
    (:func:`recipe_shape`) would not fit in memory, saying what it would need; ``what`` names
    the request in the message.

    Parameters
    ----------
    csdf : CSDF
        The object.
    recipe : Recipe, dict or list
        The recipe to check.
    what : str
        The request, as the message names it.

    Returns
    -------
    None
        Raises :class:`~partscale.errors.MemoryLimitError` where the result would not fit.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import check_recipe_memory
    >>> check_recipe_memory(bar, [{"axis": "x", "zone": [0.3, 0.6], "to": 0.8}], what="a longer bar")
    """
    check_memory(recipe_shape(csdf, recipe), BYTES_PER_VOXEL, what=what)


def recipe_shape(csdf: CSDF, recipe: Recipe | dict[str, Any] | list) -> tuple[int, int, int]:
    """(X, Y, Z) grid shape :func:`apply_recipe` would give, without computing anything.

    Each edit grows its axis by ``round((DEST - END) / voxel_size)`` voxels, its planes carried
    through the earlier edits as :func:`apply_recipe` carries them; for ``global`` the solid's
    extent is the input's carried the same way. A shift within rounding of half a voxel can come
    out one voxel apart from the edit's own: compare the result again when the limit is exact.
    Positions are not validated here (the edit does that); the shape never drops below 1.

    Parameters
    ----------
    csdf : CSDF
        The object.
    recipe : Recipe, dict or list
        The recipe.

    Returns
    -------
    (int, int, int)
        The grid shape of the result.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import recipe_shape
    >>> bar.shape, recipe_shape(bar, [{"axis": "x", "zone": [0.3, 0.6], "to": 0.8}])
    ((27, 11, 11), (31, 11, 11))
    """
    if not isinstance(recipe, Recipe):
        recipe = Recipe.parse(recipe, units=csdf.meta.get("units"))
    h = csdf.voxel_size
    shape = list(csdf.shape)
    bounds = csdf.surface_bounds()
    extent = [[float(bounds[0, a]), float(bounds[1, a])] for a in range(3)]
    applied: list[tuple[int, dict[str, Any]]] = []
    origin = np.asarray(csdf.origin, dtype=np.float64)
    for e in recipe.edits:
        if isinstance(e, CountEdit):
            raise InputError(
                f"recipe: expected zone edits, got a count ({e.copies:+d} along {e.axis}) "
                "unresolved (partscale.zones.resolve_counts)"
            )
        if not isinstance(e, Edit):
            origin, grown = warp_grid(origin, tuple(shape), h, e)
            shape = list(grown)
            continue
        ax = e.axis_index
        (_, _, d), (s2, e2, d2) = _carried(e, bounds, applied)
        if not np.isfinite((d2 - e2) / h):
            raise InputError(f"to: expected a finite position, got {d}")
        shift = round((d2 - e2) / h)
        shape[ax] = max(1, shape[ax] + shift)
        kw: dict[str, Any] = {"mode": e.mode, "start": s2, "end": e2, "dest": e2 + shift * h}
        if e.mode == "tile" and d2 == s2:  # removed: the start snaps with the destination
            kw["start"] = kw["dest"]
        lo, hi = extent[ax]
        if e.mode == "global":
            kw.update(lo=lo, hi=hi)
        if (
            e.mode != "global"
            and hi - lo > 0
            and e2 > s2
            and (kw["dest"] > s2 or kw["dest"] == kw["start"])
        ):
            extent[ax] = [float(v) for v in forward_coordinate(np.array([lo, hi]), **kw)]
        elif e.mode == "global" and hi > lo:
            extent[ax] = [lo, hi + shift * h]
        applied.append((ax, kw))
    return (shape[0], shape[1], shape[2])


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
    """Edit one zone: ``apply_edit(csdf, {"axis": axis, "zone": zone, "to": to, "mode": mode})``.

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : {'x', 'y', 'z'}
        The axis the zone lies along.
    zone : (start, end)
        The zone's planes: floats in the object's units or strings like ``'30%'``.
    to : float or str
        Where ``end`` goes.
    mode : {'stretch', 'tile', 'global'}
        How the zone changes.
    progress : callable(fraction, message), optional
        Called as the work goes on.

    Returns
    -------
    CSDF
        The edited object (see :func:`apply_edit`).

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.edit import scale
    >>> table = ingest.load(data.table(), res=64)
    >>> longer = scale(table, axis="x", zone=("35%", "65%"), to="105%")
    >>> longer.shape[0] > table.shape[0]
    True
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

    Parameters
    ----------
    csdf : CSDF
        The object.
    edit : Edit or dict
        One zone edit, as :func:`apply_edit` takes it.

    Returns
    -------
    CSDF
        The naive result: same grid as :func:`apply_edit`'s, distances not re-evaluated.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import apply_edit, naive_edit
    >>> edit = {"axis": "x", "zone": [0.3, 0.6], "to": 0.8}
    >>> naive_edit(bar, edit).shape == apply_edit(bar, edit).shape
    True
    """
    edit = _as_edit(edit)
    r = resolve_edit(csdf, edit)
    done = _edit_arrays(csdf, r, naive=True)
    return csdf.with_trusted_history(
        _history_entry(csdf, edit, r, done, "naive_scale"),
        sdf=done.sdf,
        rgb=done.rgb,
        parts=done.parts,
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

    Parameters
    ----------
    csdf : CSDF
        An edited object.
    after : CSDF, optional
        An earlier state of it: only the edits made since are taken.

    Returns
    -------
    Recipe
        The recipe, positions in world units on the original.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import apply_edit, recipe_from_history
    >>> longer = apply_edit(bar, {"axis": "x", "zone": [0.3, 0.6], "to": 0.8})
    >>> recipe_from_history(longer).to_json()
    {'version': 1, 'edits': [{'axis': 'x', 'zone': [0.3, 0.6], 'to': 0.8, 'mode': 'stretch'}]}
    """
    hist = csdf.meta.get("history", [])
    if after is not None:
        hist = hist[len(after.meta.get("history", [])) :]
    entries = [
        h
        for h in hist
        if isinstance(h, dict)
        and h.get("op") in ("scale", "radial", "oblique", "screw", "helix", "rotation")
    ]
    if not entries:
        raise InputError("history: expected at least one scale edit, got none")
    edits: list[Edit | RadialZone | ObliqueZone | ScrewZone | HelixZone | RotationZone] = []
    earlier: list[tuple[int, dict[str, Any]]] = []  # all edits before the current run
    run: list[tuple[int, dict[str, Any]]] = []  # edits of the current run
    for h in entries:
        if h["op"] == "radial":
            edits.append(RadialZone.parse({k: h[k] for k in ("radial", "zone", "to")}))
            continue
        if h["op"] == "oblique":
            edits.append(ObliqueZone.parse({k: h[k] for k in ("normal", "zone", "to")}))
            continue
        if h["op"] == "screw":
            edits.append(ScrewZone.parse({k: h[k] for k in ("screw", "copies")}))
            continue
        if h["op"] == "helix":
            edits.append(HelixZone.parse({k: h[k] for k in ("helix", "copies")}))
            continue
        if h["op"] == "rotation":
            edits.append(RotationZone.parse({k: h[k] for k in ("rotation", "copies")}))
            continue
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
    "apply_edit",
    "apply_recipe",
    "check_recipe_memory",
    "naive_edit",
    "recipe_from_history",
    "recipe_shape",
    "scale",
]
