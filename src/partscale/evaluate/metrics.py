"""Measured quality of one edit: the original CSDF ``a`` against the edited CSDF ``b``.

Every metric compares ``b`` with what the edit promised (the :class:`~partscale.edit.ResolvedEdit`
that :func:`partscale.edit.resolve_edit` gives, with the mode that produced ``b``; several of
them as :class:`Zones` for a multi-edit recipe): content before the zone stays put, content after
it moves by ``dest - end``, the zone ``[start, end]`` becomes ``[start, dest]``. Geometric errors
are in voxels (``voxel_size`` of ``a``; edits keep it), so they read the same at any resolution;
colour steps are Euclidean distances of 8-bit sRGB triples (0 .. 441). With several zones each
metric is taken over all of them (the worst edited axis).

Conventions: the edit axis coordinate of a world point is ``y``; "outside" means before ``start``
or after the zone's end (``end`` in ``a``, ``dest`` in ``b``), kept :data:`MARGIN` voxels away from
the zone's planes where seams are blended; "inside" is the zone, the same margin in from its
planes.

The metrics (each a function below, gathered by :func:`evaluate`):

- ``length_err``: |solid extent of ``b`` along the axis - target extent|.
- ``rigid_err``: 99th percentile of the distance between the surface outside the zone before and
  after (each surface point moved by the edit's translation, distance to the other surface; both
  ways).
- ``prop_out`` / ``prop_in``: proportion error. The local thickness of the solid along the edit
  axis is the length of every solid run (chord) on the voxel-centre lines along it, ends at the
  sdf's linear zero crossings (sub-voxel; exact on faces, up to a voxel short on lines grazing an
  edge, which the trimmed quantiles below absorb): the thickness of shelves, balusters, legs in
  the direction the edit changes. Runs wholly outside (inside) the zone are pooled (inside
  ``b``, the runs whose source through their tile copy lies inside: like with like at the
  joins); the error is the normalised 1-Wasserstein distance between the before and after
  distributions (mean absolute difference of their 5..95 % quantiles over the mean before). Elements kept: 0;
  scaled by ``f``: ``|f - 1|``. (Across the axis a one-axis edit changes no thickness.)
- ``spacing_err``: spacing of repeated elements. On lines along the edit axis where ``a`` has
  three solid runs evenly spaced (two consecutive pitches within :data:`PERIOD_TOLERANCE`: lines
  through repeated elements), the pitches (centre-to-centre distances of consecutive runs) with
  at least one of their two runs centred in the zone are compared with the pitches on the same
  lines of ``b`` touching the new zone likewise, with the same normalised Wasserstein distance.
  Pitches with a run cut by a zone plane (or a join between copies) are left out: that element
  is meant to change (a seat stretched between two arms). NaN where ``a`` has no such lines (no
  repeated elements along the axis).
- ``sdf_err_mean`` / ``sdf_err_p99``: ``|sdf|`` against the true distance to ``b``'s own surface
  (its marching-cubes mesh, exact point-triangle distances) in a band of
  :data:`~partscale.csdf.BAND_VOXELS` voxels, within the new zone and as many voxels either side
  (the whole object for ``global``).
  Marching cubes chamfers sharp edges, so an exact field scores up to ~0.5 voxel at p99 on a box;
  the mean is the figure to compare.
- ``watertight`` and ``pieces``: of the marching-cubes surface (connected components of faces);
  ``pieces_expected``: the original's, plus for ``tile`` one more per copy of each piece lying
  wholly in the zone.
- ``seam_color`` / ``seam_shape``: the jump across each seam plane (the zone's two planes in
  ``b``, plus the joins between tile copies): the mean colour (sdf) difference between two voxel
  slices :data:`SEAM_WINDOW` apart centred on the plane (so a blended seam still counts in
  full; for the sdf, less the trend just outside, see :func:`slice_steps`), near the surface,
  minus the same jump in ``a`` at the corresponding plane (for a join between copies, which
  continues both zone planes at once, the larger of ``a``'s jumps there), clipped at 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import edt
import igl
import numpy as np
import trimesh

from ..csdf import BAND_VOXELS, CSDF
from ..edit import Edit, ResolvedEdit, recipe_from_history, resolve_edit
from ..errors import InputError
from ..surface import to_mesh
from ..zones import SEAM_WINDOW, layer_step

#: Two consecutive pitches on a line within this fraction of each other mark repeated elements.
PERIOD_TOLERANCE = 0.15
#: Voxels kept between the zone's planes and the regions called outside/inside.
MARGIN = 1.0
#: Fewest samples a distribution needs before it is compared (a handful of stray runs, e.g. a
#: bump a voxel high, would otherwise decide a region's error).
MIN_SAMPLES = 20
#: Most surface points / band voxels measured per comparison (a fixed-seed random subset).
MAX_POINTS = 150_000

_QUANTILES = np.linspace(0.05, 0.95, 19)


@dataclass(frozen=True)
class Zone:
    """One zone of an edit: the edit as resolved on the original, and where it lies in the result.

    Attributes
    ----------
    edit : ResolvedEdit
        The edit on the original (:func:`partscale.edit.resolve_edit`; ``dest`` snapped to whole
        voxels as the stage does), with the mode that produced the result.
    before : float
        How far the zone moved in the result: the growth of the other zones on its axis that
        lie before it (0 for a single edit).

    Examples
    --------
    >>> from partscale import edit, evaluate, shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> zone = evaluate.Zone(edit.resolve_edit(bar, edit.Edit("x", 0.3, 0.6, 0.8)), before=0.1)
    >>> zone.start, zone.end, round(zone.new_start, 3), round(zone.new_end, 3), zone.mode
    (0.3, 0.6, 0.4, 0.9, 'stretch')
    """

    edit: ResolvedEdit
    before: float = 0.0

    axis = property(lambda self: self.edit.axis, doc="0, 1, 2 for x, y, z.")
    start = property(lambda self: self.edit.start, doc="Zone start in the original.")
    end = property(lambda self: self.edit.end, doc="Zone end in the original.")
    lo = property(lambda self: self.edit.lo, doc="The original solid's extent along the axis.")
    hi = property(lambda self: self.edit.hi, doc="The original solid's extent along the axis.")
    mode = property(lambda self: self.edit.mode, doc="``stretch``, ``tile`` or ``global``.")
    n_copies = property(lambda self: self.edit.n_copies, doc="Copies a ``tile`` makes.")

    @property
    def new_start(self) -> float:
        """The zone's start in the result."""
        return self.edit.start + self.before

    @property
    def new_end(self) -> float:
        """The zone's end in the result."""
        return self.edit.dest + self.before

    @property
    def offset(self) -> float:
        """Translation of the content just beyond the zone."""
        return self.new_end - self.end

    def joins(self) -> list[float]:
        """Result-frame planes between tile copies (none for other modes)."""
        return [y + self.before for y, source in self.edit.seams() if source is None]

    def source_interval(self, y0: np.ndarray, y1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Map result-frame intervals inside the zone to the original (NaN: crosses a join)."""
        y0 = np.asarray(y0, dtype=np.float64)
        y1 = np.asarray(y1, dtype=np.float64)
        n = self.n_copies if self.mode == "tile" else 1
        if n == 0:  # a removed zone: nothing of the result lies in it
            return np.full(y0.shape, np.nan), np.full(y1.shape, np.nan)
        step = (self.new_end - self.new_start) / n
        scale = step / (self.end - self.start)
        k = np.clip(np.floor((y0 - self.new_start) / step), 0, n - 1)
        base = self.new_start + k * step
        s0 = self.start + (y0 - base) / scale
        s1 = self.start + (y1 - base) / scale
        crosses = y1 > base + step
        return np.where(crosses, np.nan, s0), np.where(crosses, np.nan, s1)


@dataclass(frozen=True)
class Zones:
    """Every zone of an edit (one or several, on one or several axes), non-overlapping per axis.

    Built from one :class:`~partscale.edit.ResolvedEdit` (:meth:`of`), from edits given on one
    original (:meth:`placed`) or from a result's history (:func:`zones_from_history`); every
    metric accepts either.

    Attributes
    ----------
    zones : tuple of Zone
        The zones, each placed where it lies in the result.

    Examples
    --------
    Two stretches along x: the second zone lies 0.2 further on in the result.

    >>> from partscale import edit, evaluate, shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> edits = [edit.resolve_edit(bar, edit.Edit("x", a, b, b + 0.2)) for a, b in ((0.1, 0.3), (0.6, 0.8))]
    >>> zones = evaluate.Zones.placed(edits)
    >>> [(z.start, round(z.new_start, 3)) for z in zones.on(0)], round(zones.target_length(0), 3)
    ([(0.1, 0.1), (0.6, 0.8)], 1.4)
    """

    zones: tuple[Zone, ...]

    @classmethod
    def of(cls, geo: ResolvedEdit | Zones) -> Zones:
        """``geo`` itself if it is :class:`Zones`, else the one zone of the edit ``geo``."""
        if isinstance(geo, Zones):
            return geo
        return cls((Zone(geo),))

    @classmethod
    def placed(cls, edits: list[ResolvedEdit] | tuple[ResolvedEdit, ...]) -> Zones:
        """Zones of edits given on one original (recipe coordinates), each moved in the result
        by the growth of the zones before it on its axis. Raises :class:`InputError` for zones
        that overlap on one axis and for ``global`` among several edits.
        """
        if len(edits) > 1 and any(r.mode == "global" for r in edits):
            raise InputError(
                f"edits: expected a global edit alone, got one among {len(edits)} edits"
            )
        out = []
        for r in edits:
            same = [q for q in edits if q.axis == r.axis and q is not r]
            for q in same:
                if r.start < q.end and r.end > q.start:
                    raise InputError(
                        f"edits: expected zones that do not overlap, got [{r.start:.6g}, "
                        f"{r.end:.6g}] and [{q.start:.6g}, {q.end:.6g}] along {r.axis_name}"
                    )
            out.append(Zone(r, sum(q.shift for q in same if q.end <= r.start)))
        return cls(tuple(out))

    @property
    def axes(self) -> list[int]:
        """The axes (0, 1, 2) with a zone, in order."""
        return sorted({z.axis for z in self.zones})

    def on(self, axis: int) -> list[Zone]:
        """The zones on ``axis``, by start."""
        return sorted((z for z in self.zones if z.axis == axis), key=lambda z: z.start)

    def target_length(self, axis: int) -> float:
        """The solid's length along ``axis`` the edits ask for (world units)."""
        zs = self.on(axis)
        return zs[0].hi - zs[0].lo + sum(z.edit.shift for z in zs)

    def offset(self, axis: int, y: np.ndarray, *, result: bool = False) -> np.ndarray:
        """Translation of original-frame points ``y`` (result-frame with ``result``) outside
        the zones on ``axis``: the offset of the last zone ending before each point.
        """
        y = np.asarray(y, dtype=np.float64)
        out = np.zeros_like(y)
        for z in self.on(axis):
            out = np.where(y >= (z.new_end if result else z.end), z.offset, out)
        return out

    def outside(self, axis: int, y: np.ndarray, margin: float, *, result: bool = False):
        """Points of ``y`` more than ``margin`` outside every zone on ``axis``."""
        keep = np.ones(np.shape(y), bool)
        for z in self.on(axis):
            lo, hi = (z.new_start, z.new_end) if result else (z.start, z.end)
            keep &= (y < lo - margin) | (y > hi + margin)
        return keep

    def seams(self, axis: int) -> list[tuple[float, float | None, Zone]]:
        """Seam planes in the result along ``axis``: (plane, original plane or None for a join
        between tile copies, its zone).
        """
        return [(y + z.before, source, z) for z in self.on(axis) for y, source in z.edit.seams()]


def zones_from_history(edited: CSDF, original: CSDF) -> Zones:
    """The zones of the scale edits ``edited``'s history records since ``original``.

    The edits are read back on the original (:func:`partscale.edit.recipe_from_history`:
    recipe coordinates, however many runs made them) and resolved there, each with the
    destination the stage snapped it to.

    Parameters
    ----------
    edited : CSDF
        An edit result of ``original`` (its history continues the original's).
    original : CSDF
        The object before the edits.

    Returns
    -------
    Zones
        One zone per scale edit, in the original's frame.

    Raises
    ------
    partscale.errors.InputError
        Without a scale edit, for zones that overlap on one axis (a zone drawn inside an earlier
        one's result) and for ``global`` among several edits.

    Examples
    --------
    >>> from partscale import edit, evaluate, shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> longer = edit.apply_edit(bar, {"axis": "x", "zone": [0.3, 0.6], "to": 0.8})
    >>> [(z.axis, z.start, z.end, z.new_end) for z in evaluate.zones_from_history(longer, bar).zones]
    [(0, 0.3, 0.6, 0.8)]
    """
    recipe = recipe_from_history(edited, after=original)
    hist = edited.meta.get("history", [])[len(original.meta.get("history", [])) :]
    applied = [h for h in hist if isinstance(h, dict) and h.get("op") == "scale"]
    resolved = []
    planar = [e for e in recipe.edits if isinstance(e, Edit)]
    for e, h in zip(planar, applied, strict=True):
        s, en, _ = e.resolve(0.0, 1.0)
        # the shift the stage performed (snapped on the object it applied to)
        shift = float(h["to_snapped"]) - float(h["edit"]["zone"][1])
        resolved.append(resolve_edit(original, Edit(e.axis, s, en, en + shift, e.mode)))
    return Zones.placed(resolved)


# -- solid runs along grid lines ------------------------------------------------------------


@dataclass(frozen=True)
class Runs:
    """The solid's runs (chords) on the voxel-centre lines along one axis.

    Attributes
    ----------
    axis : int
    line : (R,) int64
        Index of the line in the grid with ``axis`` moved last (C order of the other two axes).
    perp : (R, 2) float64
        World coordinates of the line along the other two axes, in increasing axis order.
    start, end : (R,) float64
        World coordinates of the run's ends along ``axis`` (sub-voxel zero crossings).
    """

    axis: int
    line: np.ndarray
    perp: np.ndarray
    start: np.ndarray
    end: np.ndarray

    @property
    def length(self) -> np.ndarray:
        """(R,) float64: each run's length."""
        return self.end - self.start

    @property
    def centre(self) -> np.ndarray:
        """(R,) float64: each run's middle."""
        return (self.start + self.end) / 2


def runs(csdf: CSDF, axis: int) -> Runs:
    """All solid runs of ``csdf`` along ``axis`` (``sdf <= 0`` is solid), sorted by line."""
    s = np.moveaxis(csdf.sdf, axis, -1)
    shape = s.shape
    flat = s.reshape(-1, shape[-1])
    n = shape[-1]
    inside = flat <= 0
    pad = np.zeros((inside.shape[0], 1), bool)
    edges = np.diff(np.concatenate([pad, inside, pad], axis=1).view(np.int8), axis=1)
    line, i0 = np.nonzero(edges == 1)  # first solid voxel
    line_e, i1 = np.nonzero(edges == -1)  # one past the last solid voxel
    del line_e  # row-major order pairs starts and ends on the same line
    last = i1 - 1

    def crossing(before: np.ndarray, after: np.ndarray, valid: np.ndarray) -> np.ndarray:
        # linear zero crossing between voxel `before` and its neighbour `after`
        b = np.where(valid, before, 0)
        a = np.where(valid, after, 0)
        v0 = flat[line, b].astype(np.float64)
        v1 = flat[line, a].astype(np.float64)
        denom = np.where(v0 != v1, v0 - v1, 1.0)
        return b + np.clip(v0 / denom, 0.0, 1.0)

    has_before = i0 > 0
    start = np.where(has_before, crossing(i0 - 1, i0, has_before), i0 - 0.5)
    has_after = i1 < n
    end = np.where(has_after, crossing(last, i1, has_after), last + 0.5)
    h = csdf.voxel_size
    others = [a for a in range(3) if a != axis]
    j, k = np.divmod(line, shape[1])
    perp = np.stack(
        [csdf.origin[others[0]] + j * h, csdf.origin[others[1]] + k * h], axis=1
    ).astype(np.float64)
    o = csdf.origin[axis]
    return Runs(axis, line.astype(np.int64), perp, o + start * h, o + end * h)


def _in_region(r: Runs, region_axis: int, lo: float, hi: float) -> np.ndarray:
    """Runs wholly within ``[lo, hi]`` along ``region_axis``."""
    if r.axis == region_axis:
        return (r.start >= lo) & (r.end <= hi)
    others = [a for a in range(3) if a != r.axis]
    y = r.perp[:, others.index(region_axis)]
    return (y >= lo) & (y <= hi)


def thickness(
    csdf: CSDF,
    axis: int,
    *,
    region_axis: int | None = None,
    region: tuple[float, float] = (-math.inf, math.inf),
) -> np.ndarray:
    """(R,) float64: lengths of the solid runs along ``axis`` lying wholly in ``region``.

    ``region`` is a world interval along ``region_axis`` (default ``axis``).
    """
    r = runs(csdf, axis)
    ra = axis if region_axis is None else region_axis
    return r.length[_in_region(r, ra, *region)]


def distribution_error(before: np.ndarray, after: np.ndarray) -> float:
    """Normalised 1-Wasserstein distance between two samples of a positive quantity.

    Mean absolute difference of their 5..95 % quantiles divided by the mean of ``before``'s; 0 for
    equal distributions, ``|f - 1|`` when every value is scaled by ``f``. NaN when either sample has
    fewer than :data:`MIN_SAMPLES` values.
    """
    before = np.asarray(before, dtype=np.float64)
    after = np.asarray(after, dtype=np.float64)
    if len(before) < MIN_SAMPLES or len(after) < MIN_SAMPLES:
        return math.nan
    qa = np.quantile(before, _QUANTILES)
    qb = np.quantile(after, _QUANTILES)
    return float(np.mean(np.abs(qb - qa)) / max(float(np.mean(qa)), 1e-12))


# -- the metrics ------------------------------------------------------------------------------


def length_error(b: CSDF, geo: ResolvedEdit | Zones) -> float:
    """|extent of ``b``'s solid - target extent| along each edited axis, in voxels (the worst)."""
    zs = Zones.of(geo)
    bb = b.surface_bounds()
    return max(abs(bb[1, ax] - bb[0, ax] - zs.target_length(ax)) / b.voxel_size for ax in zs.axes)


def _runs_on(runs_a: Runs | list[Runs] | None, a: CSDF, axis: int) -> Runs:
    if isinstance(runs_a, Runs):
        return runs_a if runs_a.axis == axis else runs(a, axis)
    return runs_a[axis] if runs_a is not None else runs(a, axis)


def _worst(values: list[float]) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return max(finite) if finite else math.nan


def _crosses(r: Runs, planes: list[float]) -> np.ndarray:
    out = np.zeros(len(r.start), bool)
    for y in planes:
        out |= (r.start < y) & (r.end > y)
    return out


def _inside_a(r: Runs, zs: list[Zone], m: float) -> np.ndarray:
    keep = np.zeros(len(r.start), bool)
    for z in zs:
        keep |= (r.start >= z.start + m) & (r.end <= z.end - m)
    return keep


def _inside_b(r: Runs, zs: list[Zone], m: float) -> np.ndarray:
    """Runs of the result whose source (through their own tile copy) lies where
    :func:`_inside_a` takes the original's: a copy's elements near its ends are the original's
    elements near the zone's planes, left out there too (like with like).
    """
    keep = np.zeros(len(r.start), bool)
    for z in zs:
        within = (r.start >= z.new_start) & (r.end <= z.new_end)
        s0, s1 = z.source_interval(r.start, r.end)
        with np.errstate(invalid="ignore"):
            keep |= within & (s0 >= z.start + m) & (s1 <= z.end - m)
    return keep


def proportion_error(
    a: CSDF, b: CSDF, geo: ResolvedEdit | Zones, *, runs_a: Runs | list[Runs] | None = None
) -> dict[str, float]:
    """``{'out': e, 'in': e}``: thickness distribution error along each edited axis per region
    (the worst axis).

    Runs across the edit axis are left out: a one-axis edit cannot change a cross-section's
    set of thicknesses, only how many lines see each, which says nothing about proportions.
    "out": runs more than :data:`MARGIN` outside every zone. "in": runs of ``a`` wholly in a
    zone, the margin in from its planes, against the runs of ``b`` whose source (mapped through
    their tile copy) lies there too: a copy's elements touching the joins are the original's
    elements touching the zone's planes, which neither side counts; runs crossing a join are
    left out (their pieces crossed the zone's planes in ``a``). NaN where a region has fewer
    than :data:`MIN_SAMPLES` runs on either side.
    """
    zs = Zones.of(geo)
    m = MARGIN * a.voxel_size
    errs: dict[str, list[float]] = {"out": [], "in": []}
    for ax in zs.axes:
        on = zs.on(ax)
        ra = _runs_on(runs_a, a, ax)
        rb = runs(b, ax)
        joins = [y for z in on for y in z.joins()]
        out_a = zs.outside(ax, ra.start, m) & zs.outside(ax, ra.end, m)
        # wholly on one side of every zone: both ends outside and the same offset
        out_a &= zs.offset(ax, ra.start) == zs.offset(ax, ra.end)
        out_b = zs.outside(ax, rb.start, m, result=True) & zs.outside(ax, rb.end, m, result=True)
        out_b &= zs.offset(ax, rb.start, result=True) == zs.offset(ax, rb.end, result=True)
        errs["out"].append(distribution_error(ra.length[out_a], rb.length[out_b]))
        in_a = _inside_a(ra, on, m)
        in_b = _inside_b(rb, on, m) & ~_crosses(rb, joins)
        errs["in"].append(distribution_error(ra.length[in_a], rb.length[in_b]))
    return {k: _worst(v) for k, v in errs.items()}


def _pitches(r: Runs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Consecutive run pairs on each line: (line, first centre, second centre)."""
    c = r.centre
    same = r.line[1:] == r.line[:-1]
    return r.line[:-1][same], c[:-1][same], c[1:][same]


def _pitch_runs(r: Runs) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the two runs of each pitch of :func:`_pitches`."""
    same = np.nonzero(r.line[1:] == r.line[:-1])[0]
    return same, same + 1


def pitches(csdf: CSDF, axis: int) -> np.ndarray:
    """(P,) float64: centre-to-centre distances of consecutive solid runs on lines along ``axis``."""
    _, c0, c1 = _pitches(runs(csdf, axis))
    return c1 - c0


def _line_keys(r: Runs, h: float) -> np.ndarray:
    # lines matched across grids by their world position (edits keep the voxel size and move
    # nothing across the edit axis), rounded to the voxel
    return np.rint(r.perp / h).astype(np.int64) @ np.array([1 << 32, 1], np.int64)


def spacing_error(
    a: CSDF, b: CSDF, geo: ResolvedEdit | Zones, *, runs_a: Runs | list[Runs] | None = None
) -> float:
    """Pitch distribution error of repeated elements across the zones (see module docstring);
    the worst edited axis.

    Pitches with a run crossing a zone's plane (or, in ``b``, a join between tile copies) are
    left out: that element is cut by the edit and meant to change length (a seat spanning the
    zone between two arms grows, and so do its pitches to them), not a repeated element moved.
    """
    zs = Zones.of(geo)
    return _worst([_spacing_on(a, b, zs, ax, _runs_on(runs_a, a, ax)) for ax in zs.axes])


def _spacing_on(a: CSDF, b: CSDF, zs: Zones, ax: int, ra: Runs) -> float:
    on = zs.on(ax)
    rb = runs(b, ax)
    h = a.voxel_size
    la, ca0, ca1 = _pitches(ra)
    # lines through repeated elements: two consecutive pitches equal within PERIOD_TOLERANCE
    # (three elements evenly spaced), not merely three solids (rung, slanted leg, seat)
    pa = ca1 - ca0
    pair = (la[1:] == la[:-1]) & (
        np.abs(pa[1:] - pa[:-1]) <= PERIOD_TOLERANCE * np.maximum(pa[1:], pa[:-1])
    )
    repeated_lines = np.unique(la[1:][pair])
    if len(repeated_lines) == 0:
        return math.nan

    def touches(c0: np.ndarray, c1: np.ndarray, result: bool) -> np.ndarray:
        # an element of the pair lies in a zone: pitches spanning a whole zone (a rung and a
        # seat on either side of stretched legs) are meant to grow
        out = np.zeros(len(c0), bool)
        for z in on:
            lo, hi = (z.new_start, z.new_end) if result else (z.start, z.end)
            out |= ((c0 >= lo) & (c0 <= hi)) | ((c1 >= lo) & (c1 <= hi))
        return out

    planes_a = [p for z in on for p in (z.start, z.end)]
    planes_b = [p for z in on for p in (z.new_start, z.new_end, *z.joins())]
    i0, i1 = _pitch_runs(ra)
    cut_a = _crosses(ra, planes_a)
    keep_a = np.isin(la, repeated_lines) & touches(ca0, ca1, False) & ~(cut_a[i0] | cut_a[i1])
    if not keep_a.any():
        return math.nan
    keys_a = _line_keys(ra, h)
    # key of each repeated line of a, looked up through one of its runs
    first_run = np.searchsorted(ra.line, repeated_lines)
    wanted = keys_a[first_run]
    lb, cb0, cb1 = _pitches(rb)
    j0, j1 = _pitch_runs(rb)
    cut_b = _crosses(rb, planes_b)
    keys_b = _line_keys(rb, h)
    first_b = np.searchsorted(rb.line, lb)
    keep_b = np.isin(keys_b[first_b], wanted) & touches(cb0, cb1, True) & ~(cut_b[j0] | cut_b[j1])
    return distribution_error((ca1 - ca0)[keep_a], (cb1 - cb0)[keep_b])


def _subset(points: np.ndarray, n: int = MAX_POINTS) -> np.ndarray:
    if len(points) <= n:
        return points
    rng = np.random.default_rng(0)
    return points[rng.choice(len(points), n, replace=False)]


def _distance_to_mesh(points: np.ndarray, mesh: trimesh.Trimesh) -> np.ndarray:
    if len(points) == 0:
        return np.zeros(0)
    d2, _, _ = igl.point_mesh_squared_distance(
        np.ascontiguousarray(points, dtype=np.float64),
        np.ascontiguousarray(mesh.vertices, dtype=np.float64),
        np.ascontiguousarray(mesh.faces, dtype=np.int64),
    )
    return np.sqrt(np.maximum(d2, 0.0))


def rigidity_error(
    mesh_a: trimesh.Trimesh,
    mesh_b: trimesh.Trimesh,
    geo: ResolvedEdit | Zones,
    voxel_size: float,
) -> float:
    """99th percentile of the surface displacement outside every zone, in voxels (both ways).

    Each surface point more than :data:`MARGIN` outside every zone (on every edited axis) is
    moved by the edit's translation there and its distance to the other surface taken. Not the
    maximum: marching cubes cuts a sharp edge differently when the grid's phase against it
    changes (a translation by a fraction of a voxel), by up to half a voxel, on a thin set of
    vertices along edges.
    """
    zs = Zones.of(geo)
    m = MARGIN * voxel_size

    def rigid(v: np.ndarray, result: bool) -> np.ndarray:
        keep = np.ones(len(v), bool)
        for ax in zs.axes:
            keep &= zs.outside(ax, v[:, ax], m, result=result)
        p = _subset(v[keep].copy())
        sign = -1.0 if result else 1.0
        for ax in zs.axes:
            p[:, ax] += sign * zs.offset(ax, p[:, ax], result=result)
        return p

    pa = rigid(mesh_a.vertices, False)
    pb = rigid(mesh_b.vertices, True)
    d = np.concatenate([_distance_to_mesh(pa, mesh_b), _distance_to_mesh(pb, mesh_a)])
    return float(np.quantile(d, 0.99)) / voxel_size if len(d) else math.nan


def _shell(sdf: np.ndarray) -> np.ndarray:
    """Voxels whose sign differs from a face neighbour's (the surface's voxel shell)."""
    inside = sdf <= 0
    shell = np.zeros_like(inside)
    for ax in range(3):
        d = np.diff(inside, axis=ax)
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[ax] = slice(None, -1)
        hi[ax] = slice(1, None)
        shell[tuple(lo)] |= d
        shell[tuple(hi)] |= d
    return shell


def distance_error(
    b: CSDF,
    mesh_b: trimesh.Trimesh,
    *,
    axis: int | None = None,
    region: tuple[float, float] | None = None,
    regions: list[tuple[int, float, float]] | None = None,
) -> tuple[float, float]:
    """(mean, p99) of ``| |sdf| - true distance |`` in voxels, over the band of ``BAND_VOXELS`` voxels.

    The true distance is to ``b``'s own zero level (its marching-cubes mesh), so the surface is
    taken as given and only the stored distances are judged. ``region``: only band voxels whose
    coordinate along ``axis`` lies in this world interval (where an edit changed the field);
    ``regions``: several such ``(axis, lo, hi)``, band voxels in any of them.
    """
    h = b.voxel_size
    shell = _shell(b.sdf)
    # as uint8: edt takes a bool array on a slower path, with the same result
    near = edt.edt((~shell).view(np.uint8), parallel=1) <= BAND_VOXELS + 1.5
    idx = np.argwhere(near)
    if region is not None and axis is not None:
        y = b.origin[axis] + idx[:, axis] * h
        idx = idx[(y >= region[0]) & (y <= region[1])]
    if regions is not None:
        keep = np.zeros(len(idx), bool)
        for ax, lo, hi in regions:
            y = b.origin[ax] + idx[:, ax] * h
            keep |= (y >= lo) & (y <= hi)
        idx = idx[keep]
    idx = _subset(idx)
    pts = b.index_to_world(idx)
    true = _distance_to_mesh(pts, mesh_b)
    stored = np.abs(b.sdf[idx[:, 0], idx[:, 1], idx[:, 2]].astype(np.float64))
    keep = true <= BAND_VOXELS * h
    if not keep.any():
        return math.nan, math.nan
    err = np.abs(stored[keep] - true[keep]) / h
    return float(err.mean()), float(np.quantile(err, 0.99))


def _components(mesh: trimesh.Trimesh) -> list[np.ndarray]:
    return trimesh.graph.connected_components(
        mesh.face_adjacency, nodes=np.arange(len(mesh.faces)), min_len=1
    )


def topology(mesh: trimesh.Trimesh) -> tuple[bool, int]:
    """(watertight, number of face-connected pieces) of a surface mesh."""
    return bool(mesh.is_watertight), len(_components(mesh))


def slice_steps(
    csdf: CSDF, axis: int, *, window: int = SEAM_WINDOW
) -> tuple[np.ndarray, np.ndarray]:
    """Colour and shape jumps between voxel slices ``window`` apart along ``axis``.

    Returns
    -------
    color : (N,) float64
        At ``i``: mean sRGB distance between slices ``i`` and ``i + k`` (``k = window``) over
        voxels within one voxel of the surface on both; NaN where fewer than 3 such voxels.
    shape : (N,) float64
        At ``i``: mean ``sdf`` change from slice ``i`` to ``i + k`` less the trend the one-voxel
        differences just outside the pair predict, ``|(f[i+k] - f[i]) - k (f[i] - f[i-1] +
        f[i+k+1] - f[i+k]) / 2|``, in voxels (clipped at ``2 * BAND_VOXELS``), over voxels within one
        voxel of the surface on slice ``i`` or ``i + k``: zero for a surface that changes
        linearly (a slanted leg), the full step for a discontinuity however it was blended
        within the pair.
    """
    h = csdf.voxel_size
    k = window
    s = np.moveaxis(csdf.sdf, axis, 0)
    c = np.moveaxis(csdf.rgb, axis, 0)
    n = s.shape[0]
    color = np.full(n, np.nan)
    shape = np.full(n, np.nan)
    if n < k + 3:
        return color, shape
    i = np.arange(1, n - k - 1)
    near = np.abs(s) <= h
    both = near[i] & near[i + k]
    either = near[i] | near[i + k]
    dc = np.linalg.norm(c[i + k].astype(np.float32) - c[i].astype(np.float32), axis=-1)
    f = s.astype(np.float32)
    js = layer_step(f[i - 1], f[i], f[i + k], f[i + k + 1], h, k)
    n_both = both.sum(axis=(1, 2))
    n_either = either.sum(axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        color[i] = np.where(n_both >= 3, (dc * both).sum(axis=(1, 2)) / n_both, np.nan)
        shape[i] = np.where(n_either >= 3, (js * either).sum(axis=(1, 2)) / n_either, np.nan)
    return color, shape


def _step_at(
    steps: np.ndarray, csdf: CSDF, axis: int, y: float, window: int = SEAM_WINDOW
) -> float:
    # the pair of slices centred on y and one pair either side: a plane on a voxel centre still
    # shows its largest jump
    i = math.floor((y - csdf.origin[axis]) / csdf.voxel_size) - (window - 1) // 2
    near = steps[max(i - 1, 0) : max(i + 2, 0)]
    near = near[np.isfinite(near)]
    return float(near.max()) if len(near) else math.nan


def seam_jumps(
    a: CSDF, b: CSDF, geo: ResolvedEdit | Zones, *, steps_a: tuple | dict | None = None
) -> tuple[float, float]:
    """(colour jump in sRGB levels, shape jump in voxels): the worst seam of ``b``.

    Each seam's step minus the step ``a`` has at the plane it continues, clipped at 0. A join
    between tile copies continues both zone planes at once (copy ``m``'s end meets copy
    ``m + 1``'s start), so it is measured against the larger of ``a``'s steps at the two: a
    board lying at a zone plane shows at every join, as in the original. NaN when no seam has
    surface on both sides. ``steps_a``: :func:`slice_steps` of ``a`` (for one axis, or a dict
    axis -> steps).
    """
    zs = Zones.of(geo)
    jc, js = [], []
    for ax in zs.axes:
        if isinstance(steps_a, dict):
            col_a, shp_a = steps_a[ax] if ax in steps_a else slice_steps(a, ax)
        elif steps_a is not None and len(zs.axes) == 1:
            col_a, shp_a = steps_a
        else:
            col_a, shp_a = slice_steps(a, ax)
        col_b, shp_b = slice_steps(b, ax)
        med_c, med_s = (
            float(np.nanmedian(x)) if np.isfinite(x).any() else math.nan for x in (col_a, shp_a)
        )

        def at_a(y: float, steps: np.ndarray, med: float, ax: int = ax) -> float:
            v = _step_at(steps, a, ax, y)
            return v if math.isfinite(v) else med

        for yb, ya, z in zs.seams(ax):
            cb, sb = _step_at(col_b, b, ax, yb), _step_at(shp_b, b, ax, yb)
            planes = (z.start, z.end) if ya is None else (ya,)
            ca = max(at_a(p, col_a, med_c) for p in planes)
            sa = max(at_a(p, shp_a, med_s) for p in planes)
            if math.isfinite(cb):
                jc.append(max(0.0, cb - ca))
            if math.isfinite(sb):
                js.append(max(0.0, sb - sa))
    return (max(jc) if jc else math.nan, max(js) if js else math.nan)


# -- all together -----------------------------------------------------------------------------


class Reference:
    """What :func:`evaluate` needs of the original, computed once per object.

    Parameters
    ----------
    csdf : CSDF
        The original object.

    Attributes
    ----------
    csdf : CSDF
        The original.
    mesh : trimesh.Trimesh
        Its marching-cubes surface.
    runs : list
        Solid runs along grid lines, per axis.
    pieces : int
        Connected surfaces of the mesh.
    watertight : bool
        Whether the mesh is closed.

    Examples
    --------
    >>> from partscale import evaluate, shapes
    >>> ref = evaluate.Reference(shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05))
    >>> ref.pieces, ref.watertight
    (1, True)
    """

    def __init__(self, csdf: CSDF):
        self.csdf = csdf
        self.mesh = to_mesh(csdf)
        self.runs = [runs(csdf, ax) for ax in range(3)]
        self._steps: dict[int, tuple] = {}
        comps = _components(self.mesh)
        self.watertight, self.pieces = bool(self.mesh.is_watertight), len(comps)
        v = self.mesh.vertices
        # (P, 2, 3): each piece's bounding box, to count the pieces a tile copies
        self._piece_bounds = np.array(
            [
                [
                    v[self.mesh.faces[f]].reshape(-1, 3).min(0),
                    v[self.mesh.faces[f]].reshape(-1, 3).max(0),
                ]
                for f in comps
            ]
        ).reshape(-1, 2, 3)

    def expected_pieces(self, geo: ResolvedEdit | Zones) -> int:
        """Pieces the edit should leave: each tile copy repeats the pieces wholly in its zone."""
        n = self.pieces
        for z in Zones.of(geo).zones:
            if z.mode == "tile":
                lo, hi = self._piece_bounds[:, 0, z.axis], self._piece_bounds[:, 1, z.axis]
                n += (z.n_copies - 1) * int(((lo > z.start) & (hi < z.end)).sum())
        return n

    def steps(self, axis: int) -> tuple[np.ndarray, np.ndarray]:
        """:func:`slice_steps` of the original along ``axis``, computed once."""
        if axis not in self._steps:
            self._steps[axis] = slice_steps(self.csdf, axis)
        return self._steps[axis]


METRICS = (
    "length_err",
    "rigid_err",
    "prop_out",
    "prop_in",
    "spacing_err",
    "sdf_err_mean",
    "sdf_err_p99",
    "watertight",
    "pieces",
    "pieces_expected",
    "seam_color",
    "seam_shape",
)


def evaluate(
    ref: Reference | CSDF, b: CSDF, geo: ResolvedEdit | Zones
) -> dict[str, float | int | bool]:
    """Every metric of one edit result ``b`` against the original (see module docstring).

    Parameters
    ----------
    ref : Reference or CSDF
        The original (a :class:`Reference` reuses its mesh and runs across modes).
    b : CSDF
        The edited object; same voxel size as the original.
    geo : ResolvedEdit or Zones
        The edit as resolved on the original, with the mode that produced ``b``; a
        :class:`Zones` for several zones (a multi-edit recipe, :func:`zones_from_history`).

    Returns
    -------
    dict
        Metric name -> value: ``length_err``, ``rigid_err`` (voxels), ``prop_out``,
        ``prop_in``, ``spacing_err`` (relative; NaN where not measurable), ``sdf_err_mean``,
        ``sdf_err_p99`` (voxels), ``watertight``, ``pieces``, ``pieces_expected``,
        ``seam_color`` (sRGB levels) and ``seam_shape`` (voxels). Lower is better.

    Examples
    --------
    The stage's stretch against the naive one on a row of three posts: both give the length
    asked for, but only the stage re-evaluates the distance field in the zone.

    >>> from partscale import edit, evaluate, shapes
    >>> posts, _ = shapes.bars(3, width=0.1, gap=0.2, height=0.3, depth=0.1, voxel_size=0.02)
    >>> change = {"axis": "x", "zone": [0.25, 0.45], "to": 0.65}
    >>> zone = edit.resolve_edit(posts, edit.Edit.parse(change))
    >>> ref = evaluate.Reference(posts)
    >>> staged = evaluate.evaluate(ref, edit.apply_edit(posts, change), zone)
    >>> naive = evaluate.evaluate(ref, edit.naive_edit(posts, change), zone)
    >>> float(staged["length_err"]), float(naive["length_err"]), staged["pieces"]
    (0.0, 0.0, 3)
    >>> staged["sdf_err_mean"] < 0.02 < 0.05 < naive["sdf_err_mean"]
    True
    """
    if not isinstance(ref, Reference):
        ref = Reference(ref)
    a = ref.csdf
    if not math.isclose(a.voxel_size, b.voxel_size, rel_tol=1e-6):
        raise InputError(
            f"edited CSDF: expected the original's voxel size {a.voxel_size:.6g}, "
            f"got {b.voxel_size:.6g}"
        )
    zs = Zones.of(geo)
    mesh_b = to_mesh(b)
    prop = proportion_error(a, b, zs, runs_a=ref.runs)
    watertight, pieces = topology(mesh_b)
    sdf_mean, sdf_p99 = distance_error(b, mesh_b, regions=_changed(zs, a.voxel_size, True))
    seam_c, seam_s = seam_jumps(a, b, zs, steps_a={ax: ref.steps(ax) for ax in zs.axes})
    return {
        "length_err": length_error(b, zs),
        "rigid_err": rigidity_error(ref.mesh, mesh_b, zs, a.voxel_size),
        "prop_out": prop["out"],
        "prop_in": prop["in"],
        "spacing_err": spacing_error(a, b, zs, runs_a=ref.runs),
        "sdf_err_mean": sdf_mean,
        "sdf_err_p99": sdf_p99,
        "watertight": watertight,
        "pieces": pieces,
        "pieces_expected": ref.expected_pieces(zs),
        "seam_color": seam_c,
        "seam_shape": seam_s,
    }


def _changed(zs: Zones, h: float, result: bool) -> list[tuple[int, float, float]] | None:
    """Where the edit changed the field: each zone and :data:`~partscale.csdf.BAND_VOXELS` voxels either side (None:
    everywhere, for ``global``).
    """
    if any(z.mode == "global" for z in zs.zones):
        return None
    band = BAND_VOXELS * h
    return [
        (
            z.axis,
            (z.new_start if result else z.start) - band,
            (z.new_end if result else z.end) + band,
        )
        for z in zs.zones
    ]


def evaluate_original(
    ref: Reference, geo: ResolvedEdit | Zones | None = None
) -> dict[str, float | int | bool]:
    """The metrics that apply to the unedited object (its stored distances and topology).

    With ``geo``, distances are judged in the zones (and a band around them) only, as
    :func:`evaluate` does for a stretch or tile.
    """
    regions = None if geo is None else _changed(Zones.of(geo), ref.csdf.voxel_size, False)
    mean, p99 = distance_error(ref.csdf, ref.mesh, regions=regions)
    return {
        "sdf_err_mean": mean,
        "sdf_err_p99": p99,
        "watertight": ref.watertight,
        "pieces": ref.pieces,
    }
