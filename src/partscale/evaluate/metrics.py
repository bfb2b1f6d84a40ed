"""Measured quality of one edit: the original CSDF ``a`` against the edited CSDF ``b``.

Every metric compares ``b`` with what the edit promised (the :class:`~partscale.edit.ResolvedEdit`
that :func:`partscale.edit.resolve_edit` gives, with the mode that produced ``b``): content before
the zone stays put, content after it moves by ``dest - end``, the zone ``[start, end]`` becomes
``[start, dest]``. Geometric errors are in voxels (``voxel_size`` of ``a``; edits keep it), so they
read the same at any resolution; colour steps are Euclidean distances of 8-bit sRGB triples
(0 .. 441).

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
  the direction the edit changes. Runs wholly outside (inside) the zone are pooled; the error is
  the normalised 1-Wasserstein distance between the before and after distributions (mean
  absolute difference of their 5..95 % quantiles over the mean before). Elements kept: 0;
  scaled by ``f``: ``|f - 1|``. (Across the axis a one-axis edit changes no thickness.)
- ``spacing_err``: spacing of repeated elements. On lines along the edit axis where ``a`` has
  three solid runs evenly spaced (two consecutive pitches within :data:`PERIOD_TOLERANCE`: lines
  through repeated elements), the pitches (centre-to-centre distances of consecutive runs) with
  at least one of their two runs centred in the zone are compared with the pitches on the same
  lines of ``b`` touching the new zone likewise, with the same normalised Wasserstein distance.
  NaN where ``a`` has no such lines (no repeated elements along the axis).
- ``sdf_err_mean`` / ``sdf_err_p99``: ``|sdf|`` against the true distance to ``b``'s own surface
  (its marching-cubes mesh, exact point-triangle distances) in a band of :data:`BAND_VOXELS` voxels,
  within the new zone and :data:`BAND_VOXELS` voxels either side (the whole object for ``global``).
  Marching cubes chamfers sharp edges, so an exact field scores up to ~0.5 voxel at p99 on a box;
  the mean is the figure to compare.
- ``watertight`` and ``pieces``: of the marching-cubes surface (connected components of faces);
  ``pieces_expected``: the original's, plus for ``tile`` one more per copy of each piece lying
  wholly in the zone.
- ``seam_color`` / ``seam_shape``: the jump across each seam plane (the zone's two planes in
  ``b``, plus the joins between tile copies): the mean colour (sdf) difference between two voxel
  slices :data:`SEAM_WINDOW` apart centred on the plane (so a blended seam still counts in
  full; for the sdf, less the trend just outside, see :func:`slice_steps`), near the surface,
  minus the same jump in ``a`` at the corresponding plane (for joins between copies, minus
  ``a``'s median), clipped at 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import edt
import igl
import numpy as np
import trimesh

from ..csdf import BAND_VOXELS, CSDF
from ..edit import ResolvedEdit
from ..errors import InputError
from ..surface import to_mesh

#: Two consecutive pitches on a line within this fraction of each other mark repeated elements.
PERIOD_TOLERANCE = 0.15
#: Voxels kept between the zone's planes and the regions called outside/inside.
MARGIN = 1.0
#: Fewest samples a distribution needs before it is compared (a handful of stray runs, e.g. a
#: bump a voxel high, would otherwise decide a region's error).
MIN_SAMPLES = 20
#: Seam jumps compare slices this many voxels apart, centred on the seam: wider than the scaling
#: stage's blend (2 voxels either side of a join), which spreads a jump without removing it.
SEAM_WINDOW = 5
#: Most surface points / band voxels measured per comparison (a fixed-seed random subset).
MAX_POINTS = 150_000

_QUANTILES = np.linspace(0.05, 0.95, 19)


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
        return self.end - self.start

    @property
    def centre(self) -> np.ndarray:
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


def length_error(b: CSDF, geo: ResolvedEdit) -> float:
    """|extent of ``b``'s solid along the axis - target extent|, in voxels."""
    bb = b.surface_bounds()
    got = bb[1, geo.axis] - bb[0, geo.axis]
    return abs(got - geo.target_length) / b.voxel_size


def _regions(geo: ResolvedEdit, h: float) -> dict[str, tuple[list, list]]:
    m = MARGIN * h
    inf = math.inf
    return {
        "out": (
            [(-inf, geo.start - m), (geo.end + m, inf)],
            [(-inf, geo.start - m), (geo.dest + m, inf)],
        ),
        "in": ([(geo.start + m, geo.end - m)], [(geo.start + m, geo.dest - m)]),
    }


def proportion_error(
    a: CSDF, b: CSDF, geo: ResolvedEdit, *, runs_a: Runs | None = None
) -> dict[str, float]:
    """``{'out': e, 'in': e}``: thickness distribution error along the edit axis per region.

    Runs across the edit axis are left out: a one-axis edit cannot change a cross-section's
    set of thicknesses, only how many lines see each, which says nothing about proportions.
    Runs of ``b`` crossing a join between tile copies are left out too: their pieces were runs
    crossing the zone's planes in ``a``, which no region holds. NaN where a region has fewer
    than :data:`MIN_SAMPLES` runs on either side.
    """
    ra = runs_a if runs_a is not None else runs(a, geo.axis)
    rb = runs(b, geo.axis)
    joins = [y for y, source in geo.seams() if source is None]
    clear = np.ones(len(rb.start), bool)
    for y in joins:
        clear &= ~((rb.start < y) & (rb.end > y))
    out: dict[str, float] = {}
    for name, (reg_a, reg_b) in _regions(geo, a.voxel_size).items():
        la = np.concatenate([ra.length[_in_region(ra, geo.axis, *r)] for r in reg_a])
        lb = np.concatenate([rb.length[_in_region(rb, geo.axis, *r) & clear] for r in reg_b])
        out[name] = distribution_error(la, lb)
    return out


def _pitches(r: Runs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Consecutive run pairs on each line: (line, first centre, second centre)."""
    c = r.centre
    same = r.line[1:] == r.line[:-1]
    return r.line[:-1][same], c[:-1][same], c[1:][same]


def pitches(csdf: CSDF, axis: int) -> np.ndarray:
    """(P,) float64: centre-to-centre distances of consecutive solid runs on lines along ``axis``."""
    _, c0, c1 = _pitches(runs(csdf, axis))
    return c1 - c0


def _line_keys(r: Runs, h: float) -> np.ndarray:
    # lines matched across grids by their world position (edits keep the voxel size and move
    # nothing across the edit axis), rounded to the voxel
    return np.rint(r.perp / h).astype(np.int64) @ np.array([1 << 32, 1], np.int64)


def spacing_error(a: CSDF, b: CSDF, geo: ResolvedEdit, *, runs_a: Runs | None = None) -> float:
    """Pitch distribution error of repeated elements across the zone (see module docstring)."""
    ra = runs_a if runs_a is not None else runs(a, geo.axis)
    rb = runs(b, geo.axis)
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

    def touches(c0: np.ndarray, c1: np.ndarray, hi: float) -> np.ndarray:
        # an element of the pair lies in the zone: pitches spanning the whole zone (a rung and
        # a seat on either side of stretched legs) are meant to grow
        return ((c0 >= geo.start) & (c0 <= hi)) | ((c1 >= geo.start) & (c1 <= hi))

    keep_a = np.isin(la, repeated_lines) & touches(ca0, ca1, geo.end)
    if not keep_a.any():
        return math.nan
    keys_a = _line_keys(ra, h)
    # key of each repeated line of a, looked up through one of its runs
    first_run = np.searchsorted(ra.line, repeated_lines)
    wanted = keys_a[first_run]
    lb, cb0, cb1 = _pitches(rb)
    keys_b = _line_keys(rb, h)
    first_b = np.searchsorted(rb.line, lb)
    keep_b = np.isin(keys_b[first_b], wanted) & touches(cb0, cb1, geo.dest)
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
    mesh_a: trimesh.Trimesh, mesh_b: trimesh.Trimesh, geo: ResolvedEdit, voxel_size: float
) -> float:
    """99th percentile of the surface displacement outside the zone, in voxels (both ways).

    Not the maximum: marching cubes cuts a sharp edge differently when the grid's phase against
    it changes (a translation by a fraction of a voxel), by up to half a voxel, on a thin set of
    vertices along edges.
    """
    m = MARGIN * voxel_size
    ax = geo.axis
    va = mesh_a.vertices
    ya = va[:, ax]
    pa = _subset(va[(ya < geo.start - m) | (ya > geo.end + m)].copy())
    pa[:, ax] = np.where(pa[:, ax] > geo.end, pa[:, ax] + geo.shift, pa[:, ax])
    vb = mesh_b.vertices
    yb = vb[:, ax]
    pb = _subset(vb[(yb < geo.start - m) | (yb > geo.dest + m)].copy())
    pb[:, ax] = np.where(pb[:, ax] > geo.dest, pb[:, ax] - geo.shift, pb[:, ax])
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
) -> tuple[float, float]:
    """(mean, p99) of ``| |sdf| - true distance |`` in voxels, over the band of
    ``BAND_VOXELS`` voxels.

    The true distance is to ``b``'s own zero level (its marching-cubes mesh), so the surface is
    taken as given and only the stored distances are judged. ``region``: only band voxels whose
    coordinate along ``axis`` lies in this world interval (where an edit changed the field).
    """
    h = b.voxel_size
    shell = _shell(b.sdf)
    near = edt.edt(~shell, parallel=1) <= BAND_VOXELS + 1.5
    idx = np.argwhere(near)
    if region is not None and axis is not None:
        y = b.origin[axis] + idx[:, axis] * h
        idx = idx[(y >= region[0]) & (y <= region[1])]
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
        f[i+k+1] - f[i+k]) / 2|``, in voxels (clipped at ``2 * BAND_VOXELS``), over voxels
        within one voxel of the surface on slice ``i`` or ``i + k``: zero for a surface that changes
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
    trend = k * ((f[i] - f[i - 1]) + (f[i + k + 1] - f[i + k])) / 2
    js = np.minimum(np.abs((f[i + k] - f[i]) - trend) / h, 2 * BAND_VOXELS)
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
    a: CSDF, b: CSDF, geo: ResolvedEdit, *, steps_a: tuple | None = None
) -> tuple[float, float]:
    """(colour jump in sRGB levels, shape jump in voxels): the worst seam of ``b``.

    Each seam's step minus the step ``a`` has at the plane it continues (its median step for the
    joins between tile copies), clipped at 0; NaN when no seam has surface on both sides.
    """
    ax = geo.axis
    col_a, shp_a = steps_a if steps_a is not None else slice_steps(a, ax)
    col_b, shp_b = slice_steps(b, ax)
    med_c, med_s = (
        float(np.nanmedian(x)) if np.isfinite(x).any() else math.nan for x in (col_a, shp_a)
    )
    jc, js = [], []
    for yb, ya in geo.seams():
        cb, sb = _step_at(col_b, b, ax, yb), _step_at(shp_b, b, ax, yb)
        if ya is None:
            ca, sa = med_c, med_s
        else:
            ca, sa = _step_at(col_a, a, ax, ya), _step_at(shp_a, a, ax, ya)
        ca = ca if math.isfinite(ca) else med_c
        sa = sa if math.isfinite(sa) else med_s
        if math.isfinite(cb):
            jc.append(max(0.0, cb - ca))
        if math.isfinite(sb):
            js.append(max(0.0, sb - sa))
    return (max(jc) if jc else math.nan, max(js) if js else math.nan)


# -- all together -----------------------------------------------------------------------------


class Reference:
    """What :func:`evaluate` needs of the original, computed once per object.

    Attributes: ``csdf``, ``mesh``, ``runs`` (per axis), ``steps`` (per axis, see
    :func:`slice_steps`), ``pieces``, ``watertight``.
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

    def expected_pieces(self, geo: ResolvedEdit) -> int:
        """Pieces the edit should leave: each tile copy repeats the pieces wholly in the zone."""
        if geo.mode != "tile":
            return self.pieces
        lo, hi = self._piece_bounds[:, 0, geo.axis], self._piece_bounds[:, 1, geo.axis]
        inside = int(((lo > geo.start) & (hi < geo.end)).sum())
        return self.pieces + (geo.n_copies - 1) * inside

    def steps(self, axis: int) -> tuple[np.ndarray, np.ndarray]:
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


def evaluate(ref: Reference | CSDF, b: CSDF, geo: ResolvedEdit) -> dict[str, float | int | bool]:
    """Every metric of one edit result ``b`` against the original (see module docstring).

    Parameters
    ----------
    ref : Reference or CSDF
        The original (a :class:`Reference` reuses its mesh and runs across modes).
    b : CSDF
        The edited object; same voxel size as the original.
    geo : ResolvedEdit
        The edit as resolved on the original, with the mode that produced ``b``.
    """
    if not isinstance(ref, Reference):
        ref = Reference(ref)
    a = ref.csdf
    if not math.isclose(a.voxel_size, b.voxel_size, rel_tol=1e-6):
        raise InputError(
            f"edited CSDF: expected the original's voxel size {a.voxel_size:.6g}, "
            f"got {b.voxel_size:.6g}"
        )
    mesh_b = to_mesh(b)
    prop = proportion_error(a, b, geo, runs_a=ref.runs[geo.axis])
    watertight, pieces = topology(mesh_b)
    band = BAND_VOXELS * a.voxel_size
    zone = None if geo.mode == "global" else (geo.start - band, geo.dest + band)
    sdf_mean, sdf_p99 = distance_error(b, mesh_b, axis=geo.axis, region=zone)
    seam_c, seam_s = seam_jumps(a, b, geo, steps_a=ref.steps(geo.axis))
    return {
        "length_err": length_error(b, geo),
        "rigid_err": rigidity_error(ref.mesh, mesh_b, geo, a.voxel_size),
        "prop_out": prop["out"],
        "prop_in": prop["in"],
        "spacing_err": spacing_error(a, b, geo, runs_a=ref.runs[geo.axis]),
        "sdf_err_mean": sdf_mean,
        "sdf_err_p99": sdf_p99,
        "watertight": watertight,
        "pieces": pieces,
        "pieces_expected": ref.expected_pieces(geo),
        "seam_color": seam_c,
        "seam_shape": seam_s,
    }


def evaluate_original(
    ref: Reference, geo: ResolvedEdit | None = None
) -> dict[str, float | int | bool]:
    """The metrics that apply to the unedited object (its stored distances and topology).

    With ``geo``, distances are judged in the zone (and a band around it) only, as
    :func:`evaluate` does for a stretch or tile.
    """
    band = BAND_VOXELS * ref.csdf.voxel_size
    zone = None if geo is None else (geo.start - band, geo.end + band)
    axis = None if geo is None else geo.axis
    mean, p99 = distance_error(ref.csdf, ref.mesh, axis=axis, region=zone)
    return {
        "sdf_err_mean": mean,
        "sdf_err_p99": p99,
        "watertight": ref.watertight,
        "pieces": ref.pieces,
    }
