"""Local features of a slab: what a whole-section comparison cannot see.

A knob, a handle, a hinge, a keyhole or a printed motif is a few voxels of a cross-section of
thousands: the soft Jaccard distance between layers (:mod:`.profile`) barely moves across it, so
a "constant" slab may hold one, and stretching the slab squashes it into an oval or smears it
into a bar. Here each voxel is compared with its own column along the axis instead
(:func:`run_features`), in shape and in colour; constant slabs are cut around what is found
(:func:`.suggest.constant_slabs`), tile planes are kept off it (:func:`.suggest.axis_candidates`)
and a user's stretch zone that holds one is named (:func:`local_features`,
:func:`feature_notes`).

The rule (:func:`run_features`), and the figures behind it (objects imported at 128 voxels along
their longest side; sizes below scale with the grid):

- **Shape.** A bump or dip of a column stands more than half a voxel of occupancy out of its
  column on both sides; a feature is a connected set of them whose surface moves by more than
  :data:`FEATURE_HEIGHT` (one voxel) somewhere, at least :data:`FEATURE_VOXELS` (2) voxels. A
  knob two voxels across moves it by 1.07-2.0 voxels (cube, cylinder and sphere knobs at twelve
  random sub-voxel offsets each: the sphere's worst case 1.07), while what is not a feature
  stays below one voxel: the wear of worn wood at most 0.98 (polyhaven's worn bookshelf, whose
  wear is sub-voxel: its occupancy peaks at 0.66), and on the Kenney, Sweet Home 3D and Khronos
  objects the other bumps in constant slabs (seams, grooves, faceting) 0.53-0.89 (one of 0.95
  along a drawer's handle). The 27-voxel floor this replaces missed every knob under about
  three voxels across (27 voxels).
- **Colour.** On columns along one face (within a voxel of the surface throughout, one face
  nearest: at edges and corners the colour of the nearest of two faces flickers), a motif
  stands more than :data:`COLOUR_CONTRAST` (40 of 255) out of its column on both sides in some
  sRGB channel, at least two voxels wide along its face: a hinge or a handle of another colour,
  a printed dot, a keyhole.
- **Noise.** The threshold follows the surface's own noise: a feature must also exceed
  :data:`NOISE_MARGIN` (2) times what the run's strongest :data:`NOISE_SHARE` (2 %) of surface
  voxels reach (their wear, grain or scanner noise), in shape and in colour alike. The object's
  relief (:func:`partscale.segment.relief_of`) is no such measure here: it is a median over the
  whole surface, 0.000 on the worn bookshelf (its wear covers under 2 % of it), and costs
  0.1-0.6 s where this costs a quantile of values already at hand. Figures: a box with a
  2-voxel knob, its distances given smooth noise of 0.1-0.6 voxel RMS (relief 0.04-0.22), three
  seeds each: with the margin at 1 its constant runs held up to 15 noise features, at 1.5 up to
  4, at 2 none in the 15 copies, the knob found to 0.2 voxel of noise (beyond, the noise merges
  with it, as a scan does). In colour, the strongest 2 % of a calm run's face voxels change not
  at all on 32 of 46 flat-coloured catalogue models (Kenney, Sweet Home 3D, Khronos), by up to
  87 levels on the rest (trims, a sink's basin), and by 43-141 on the seven textured Poly Haven
  models (worn paint, wood grain): their wear does not cut slabs, their hardware still does.
  Worn or scanned surfaces are not cut into crumbs: the worn bookshelf has no feature on any
  axis (its slabs are those of the 27-voxel floor), the calm runs of four completed TUM scans
  (relief 0.29-0.35) none in shape.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from scipy import ndimage

from ..csdf import BAND_VOXELS, CSDF
from ..edit import Edit, Recipe, edit_label, unit_suffix
from .profile import _axis_index, calm_runs, profile

#: Voxels along the object's longest side at which the sizes below are given (an import at
#: ``--res 128``); they scale with it, so a feature is the same share of the object at every
#: resolution.
REFERENCE_VOXELS = 128
#: A shape feature moves the surface by more than this many voxels (at 128) somewhere.
FEATURE_HEIGHT = 1.0
#: Fewest voxels (at 128) of a feature: a knob 2 voxels across.
FEATURE_VOXELS = 2
#: A colour motif differs from its column on both sides by more than this in some sRGB channel
#: (of 255).
COLOUR_CONTRAST = 40.0
#: Least slope (voxels per voxel) of the distances across the axis at a column along one face;
#: a unit slope is one face nearest (0.71 where two at right angles are as near).
SINGLE_FACE = 0.9
#: Layers a calm run is extended by either side to find its features (:func:`axis_features`).
EXTEND = 3
#: The share of a run's surface voxels whose detail is its finish: the strongest this share of
#: the surface reaches (its wear, grain or noise), which a feature must exceed ...
NOISE_SHARE = 0.02
#: ... by this factor.
NOISE_MARGIN = 2.0


@dataclass(frozen=True)
class Feature:
    """A local feature of a run of layers along an axis (:func:`run_features`).

    Parameters
    ----------
    first, last : int
        Its layers along the axis (inclusive).
    kind : {'shape', 'colour'}
        Found in the solid (a knob, a handle, a keyhole) or in the colour alone (a motif).
    across : ((int, int), (int, int))
        Its extent across the axis: inclusive index ranges along the other two axes, in order.
    voxels : int
        How many voxels it holds.
    calm : bool
        Whether it lies at least in part in a calm run (:func:`axis_features`): not wholly in
        the layers past one, where the section changes (a board, a door's edge) and a colour
        found may be that structure's own.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> door = shapes.door()
    >>> zones.axis_features(door, 0, [(4, 82)])[0].kind
    'shape'
    """

    first: int
    last: int
    kind: Literal["shape", "colour"]
    across: tuple[tuple[int, int], tuple[int, int]]
    voxels: int
    calm: bool = True


def _envelope_excess(x: np.ndarray) -> np.ndarray:
    """(L, K) how far each value of the columns ``x`` (L, K) stands above the lowest value
    before it and the lowest after it, or below the highest before and the highest after
    (whichever is more): a bump or a dip of the column, 0 on a monotone run.
    """
    lo = np.maximum(np.minimum.accumulate(x, axis=0), np.minimum.accumulate(x[::-1], axis=0)[::-1])
    hi = np.minimum(np.maximum.accumulate(x, axis=0), np.maximum.accumulate(x[::-1], axis=0)[::-1])
    return np.maximum(x - lo, hi - x)


def _noise(values: np.ndarray, n_surface: int) -> float:
    """The value the strongest :data:`NOISE_SHARE` of ``n_surface`` surface voxels reach, given
    ``values`` (the measure at those of them that can reach any; the rest count as 0).
    """
    k = int(NOISE_SHARE * n_surface)
    if k < 1 or values.size < k:
        return 0.0
    return float(np.partition(values.ravel(), values.size - k)[values.size - k])


@dataclass(frozen=True)
class _Run:
    """What the two detectors share of layers ``first..`` along an axis: their distances ``d``
    (L, A, B, world units, the axis first: a view of the grid), the voxel size ``h``, their
    least distance per column ``low`` (A, B), the section's solid extent across the axis (two
    ``(lo, hi)`` index ranges: no feature spans it both ways) and the least voxels of a
    feature.
    """

    first: int
    d: np.ndarray
    h: np.float32
    low: np.ndarray
    section: tuple[tuple[int, int], tuple[int, int]]
    vmin: int


def _components(
    run: _Run,
    bump: np.ndarray,
    sharp: np.ndarray,
    peak: np.ndarray,
    threshold: float,
    cols: tuple[np.ndarray, np.ndarray],
    kind: Literal["shape", "colour"],
    offset: int,
) -> list[Feature]:
    """The features among the connected (26-neighbour) sets of ``bump`` voxels (L, K: the run's
    layers from ``offset`` by columns ``cols``): at least ``run.vmin`` voxels, local (at most
    half as long as the run inside its end layers, and short of the section's extent one way
    across), holding a ``sharp`` voxel and one whose ``peak`` exceeds ``threshold``; a colour
    motif at least two voxels wide along its face (:func:`_face_width`).
    """
    hit = bump.any(axis=0)
    if not hit.any():
        return []
    # label in the box of the columns that hold bumps, scattered back to their places
    j, k = cols[0][hit], cols[1][hit]
    ja, ka = int(j.min()), int(k.min())
    grid = np.zeros((bump.shape[0], int(j.max()) - ja + 1, int(k.max()) - ka + 1), dtype=bool)
    grid[:, j - ja, k - ka] = bump[:, hit]
    lab, n = ndimage.label(grid, structure=np.ones((3, 3, 3)))
    # each component's voxels: (layer, column in the bump columns), grouped by label
    li, ci = np.nonzero(bump[:, hit])
    at = lab[li, j[ci] - ja, k[ci] - ka]
    order = np.argsort(at, kind="stable")
    li, ci, at = li[order], ci[order], at[order]
    bounds = np.searchsorted(at, np.arange(1, n + 2))
    wide = [(hi - lo + 1) / 2 for lo, hi in run.section]
    out = []
    for label in range(1, n + 1):
        sel = slice(bounds[label - 1], bounds[label])
        ls, cs = li[sel], ci[sel]
        if ls.size < run.vmin or not sharp[:, hit][ls, cs].any():
            continue
        if peak[:, hit][ls, cs].max() <= threshold:
            continue
        a, b = j[cs], k[cs]
        across = ((int(a.min()), int(a.max())), (int(b.min()), int(b.max())))
        # a board or a band around the object spans the section both ways: structure
        spans = all(hi - lo + 1 >= w for (lo, hi), w in zip(across, wide, strict=True))
        narrow = kind == "colour" and _face_width(run, ls + offset, a, b) < 2
        short = 2 * (int(ls.max()) - int(ls.min()) + 1) <= len(run.d) - 2
        if short and not (spans or narrow):
            out.append(
                Feature(
                    run.first + offset + int(ls.min()),
                    run.first + offset + int(ls.max()),
                    kind,
                    across,
                    int(ls.size),
                )
            )
    return out


def _face_width(run: _Run, layer: np.ndarray, a: np.ndarray, b: np.ndarray) -> int:
    """Width (voxels) across the axis along its face of the colour motif whose voxels are at
    ``(layer, a, b)`` in ``run``: its extent across the axis in the direction its face runs
    (the other direction across is the face's normal, through the voxels within a voxel of
    it).
    """
    d = run.d
    grad = [
        np.abs(d[layer, np.minimum(a + 1, d.shape[1] - 1), b] - d[layer, np.maximum(a - 1, 0), b]),
        np.abs(d[layer, a, np.minimum(b + 1, d.shape[2] - 1)] - d[layer, a, np.maximum(b - 1, 0)]),
    ]
    along = b if grad[0].sum() > grad[1].sum() else a  # the normal is the steeper direction
    return int(along.max() - along.min()) + 1


def _shape_features(run: _Run, high: np.ndarray, height: float) -> list[Feature]:
    """The shape features of ``run`` (see :func:`run_features`); ``high`` (A, B): its greatest
    distance per column.
    """
    # only a column whose occupancy changes by half a voxel or more along the run can hold a
    # bump: most columns of a slab never do, so the rest of the work is on those alone
    occ_hi = np.clip(0.5 - run.low / run.h, 0.0, 1.0)
    j, k = np.nonzero(occ_hi - np.clip(0.5 - high / run.h, 0.0, 1.0) >= 0.5)
    cols = (j, k)
    if j.size == 0:
        return []
    s = np.clip(run.d[:, j, k] / run.h, -BAND_VOXELS, BAND_VOXELS)  # (L, K) voxels
    occ = np.clip(0.5 - s, 0.0, 1.0)
    steep = np.abs(np.diff(occ, axis=0)) >= 0.5
    sharp = np.zeros(occ.shape, dtype=bool)
    sharp[:-1] |= steep
    sharp[1:] |= steep
    # the run's two end layers may hold the edge of the next section (a side panel starting):
    # against them, a groove running the whole run would look like a dip, so they are no
    # reference; the layers next to them are also compared with the run's inside alone (a
    # knob's flank that the run begins or ends with, whose other side lies past it)
    inside, flank = _inside(occ), _flanks(occ)
    bump = (inside >= 0.5) | (flank >= 0.5)
    if not bump.any():
        return []
    # how far the surface moved there (unclipped distances: a bump a voxel or more high),
    # against the noise of each test: an envelope's, and one value's against another
    surface = np.abs(s) <= 1.0
    n_layer = int(np.count_nonzero(np.abs(run.d[len(run.d) // 2]) <= run.h))
    score = np.zeros(s.shape)
    for moved, rows in ((_inside(-s), len(s) - 2), (_flanks(-s), 2 * (EXTEND - 1))):
        # the run's surface voxels: its cross-sections barely change, so its middle layer's
        # times its layers
        noise = _noise(moved[surface & (moved > 0)], rows * n_layer)
        score = np.maximum(score, moved / max(height, NOISE_MARGIN * noise))
    return _components(run, bump, sharp, score, 1.0, cols, "shape", 0)


def _inside(x: np.ndarray) -> np.ndarray:
    """(L, K) :func:`_envelope_excess` of the columns ``x`` (L, K: a run's layers by columns)
    but their two end values (0 there).
    """
    out = np.zeros_like(x)
    out[1:-1] = _envelope_excess(x[1:-1])
    return out


def _flanks(x: np.ndarray) -> np.ndarray:
    """(L, K) how far each value of the columns ``x`` (L, K) next to their end values, within
    :data:`EXTEND` of them, stands from the value just inside those (0 elsewhere, and where the
    run is too short to have an inside).
    """
    out = np.zeros_like(x)
    e = EXTEND
    if len(x) > 2 * e + 1:
        out[1:e] = np.abs(x[1:e] - x[e])
        out[-e:-1] = np.abs(x[-e:-1] - x[-e - 1])
    return out


def _colour_features(run: _Run, rgb_grid: np.ndarray) -> list[Feature]:
    """The colour motifs of ``run`` (see :func:`run_features`); ``rgb_grid`` (L, A, B, 3):
    its colours.
    """
    # columns along a face: within a voxel of the surface at every inner layer, with such a
    # column either side along one direction across (at an edge, the colour of the nearest of
    # two faces flickers)
    middle = run.d[len(run.d) // 2] / run.h
    mid = np.nonzero(np.abs(middle) <= 1.0)
    on = (np.abs(run.d[1:-1, mid[0], mid[1]]) <= run.h).all(axis=0)
    grid = np.zeros((middle.shape[0] + 2, middle.shape[1] + 2), dtype=bool)
    grid[mid[0][on] + 1, mid[1][on] + 1] = True
    strip = (grid[:-2, 1:-1] & grid[2:, 1:-1]) | (grid[1:-1, :-2] & grid[1:-1, 2:])
    # ... and one face nearest: where two are (a corner), the distances' slope across the axis
    # drops below 1 (its central differences straddle the kink)
    one = np.pad((np.hypot(*np.gradient(middle)) >= SINGLE_FACE) | (middle < 0), 1)
    one = one[1:-1, 1:-1] & one[:-2, 1:-1] & one[2:, 1:-1] & one[1:-1, :-2] & one[1:-1, 2:]
    face = on & strip[mid] & one[mid]
    if not face.any():
        return []
    n_face = (len(run.d) - 2) * int(np.count_nonzero(face))
    rgb = rgb_grid[:, mid[0][face], mid[1][face]]
    # only a column whose colour spans more than the least threshold's share of the noise can
    # reach it (the rest stay below it, and below what sets the noise's level there)
    span = (rgb.max(axis=0).astype(np.int16) - rgb.min(axis=0)).max(axis=1)
    keep = span > COLOUR_CONTRAST / NOISE_MARGIN
    if not keep.any():
        return []
    cols = (mid[0][face][keep], mid[1][face][keep])
    rgb = rgb[:, keep].astype(np.float32)  # (L, K, 3)
    inner = rgb[1:-1]
    dev = np.max([_envelope_excess(inner[..., c]) for c in range(3)], axis=0)  # (L - 2, K)
    threshold = max(COLOUR_CONTRAST, NOISE_MARGIN * _noise(dev, n_face))
    bump = dev > threshold
    if not bump.any():
        return []
    jump = np.abs(np.diff(rgb, axis=0)).max(axis=2) > threshold
    sharp = jump[:-1] | jump[1:]
    return _components(run, bump, sharp, dev, threshold, cols, "colour", 1)


def _section(low: np.ndarray) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """The solid's extent across the axis (index ranges) of columns whose least distance is
    ``low`` (A, B); None for no solid.
    """
    a, b = np.nonzero(low <= 0)
    if a.size == 0:
        return None
    return ((int(a.min()), int(a.max())), (int(b.min()), int(b.max())))


def run_features(csdf: CSDF, axis: int, first: int, last: int, *, reach: int = 0) -> list[Feature]:
    """The local features of layers ``first..last`` (inclusive) along ``axis`` (0, 1, 2), in
    order of their first layer (see the module docstring for the rule and its figures).

    Each voxel is compared with its own column along the axis, inside the run. In shape, a
    voxel is in a bump when its occupancy stands more than half a voxel above the lowest
    before it and the lowest after it (a protrusion) or below the highest on both sides (a
    dip, a hole); in colour, a voxel within a voxel of a face is in a motif when some channel
    stands above or below its column on both sides in the same way by more than the colour
    threshold. A feature is a connected (26-neighbour) set of such voxels that is

    - at least :data:`FEATURE_VOXELS` voxels (at 128),
    - local: it spans at most half the run (a cushion's crown or a bowed board spans the run,
      and stretching it along the run keeps its look) and not the solid's whole section both
      ways across the axis (a board, a band around the object: structure, not hardware),
    - sharp-edged: somewhere its occupancy changes by more than half a voxel (its colour by
      more than the threshold) from one layer to the next (a surface steeper than about 27
      degrees to the axis: a knob's or a handle's flank, not a gentle bulge), and
    - above the run's noise: the surface moves more than :data:`FEATURE_HEIGHT` voxels (at
      128) there (a colour more than :data:`COLOUR_CONTRAST`), and more than
      :data:`NOISE_MARGIN` times what the run's strongest :data:`NOISE_SHARE` of surface voxels
      reach (the finish of a worn, grained or scanned surface).

    A column that changes once (a splayed leg, an apron's curve, a bevel, one colour meeting
    another) is drift, which the whole-section test bounds. The run's two end layers are no
    reference: a feature in them is not found. ``reach``: colour motifs are sought over that
    many more layers either side (see :func:`axis_features`).
    """
    if last - first < 2:
        return []
    n = csdf.shape[axis]
    h = np.float32(csdf.voxel_size)
    sb = csdf.surface_bounds()
    scale = float((sb[1] - sb[0]).max()) / csdf.voxel_size / REFERENCE_VOXELS
    vmin = max(2, round(FEATURE_VOXELS * scale**3))
    a, b = max(0, first - reach), min(n - 1, last + reach)
    # one copy of the layers, the axis first (a layer of the grid along y or z is strided)
    window = np.ascontiguousarray(np.moveaxis(csdf.sdf, axis, 0)[a : b + 1])
    d = window[first - a : last - a + 1]
    low, high = d.min(axis=0), d.max(axis=0)
    section = _section(low)
    if section is None:
        return []
    found = _shape_features(_Run(first, d, h, low, section, vmin), high, FEATURE_HEIGHT * scale)
    if (a, b) != (first, last):
        low = np.minimum(low, window.min(axis=0))
        section = _section(low)
        assert section is not None  # (it holds the run's solid)
    run = _Run(a, window, h, low, section, vmin)
    found += _colour_features(run, np.moveaxis(csdf.rgb, axis, 0)[a : b + 1])
    return sorted(found, key=lambda f: (f.first, f.last))


def axis_features(csdf: CSDF, axis: int, runs: list[tuple[int, int]]) -> list[Feature]:
    """The local features along ``axis`` of the given runs of layers.

    The local features along ``axis`` (0, 1, 2) of the runs of layers ``runs`` (inclusive
    ``(first, last)``: the calm runs of :func:`.profile.calm_runs`), in order of their first
    layer.

    Colour motifs are sought over each run extended by :data:`EXTEND` layers either side: one in
    its end layer, or just past it (a hinge or a handle at a door's edge, which itself ends the
    run), has a reference beyond it then; columns along a face there are still a face. Shapes are
    not: beyond the run, the columns cross the structure that ended it (a leg, a board), whose
    rise from a column would stand out as a bump. One found from two runs is kept once.

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : int
        0, 1 or 2: the axis the runs lie along.
    runs : list of (int, int)
        Runs of layers, inclusive ``(first, last)``.

    Returns
    -------
    list of Feature
        In order of their first layer.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> door = shapes.door()
    >>> [(f.first, f.last, f.kind) for f in zones.axis_features(door, 0, [(4, 82)])]
    [(65, 71, 'shape')]
    """
    found: list[Feature] = []
    for a, b in runs:
        for f in run_features(csdf, axis, a, b, reach=EXTEND):
            f = replace(f, calm=f.first <= b and a <= f.last)
            same = [i for i, g in enumerate(found) if _alike(f, g) and _overlaps(f, g)]
            if not same:
                found.append(f)
            else:  # the fuller view of it, calm if found so once
                g = found[same[0]]
                found[same[0]] = replace(max(f, g, key=lambda x: x.voxels), calm=f.calm or g.calm)
    return sorted(found, key=lambda f: (f.first, f.last))


def feature_spans(features: list[Feature]) -> list[tuple[int, int]]:
    """``(first, last)`` layer spans of ``features``, those that share layers (a pair of knobs
    side by side) joined into one, in order.
    """
    out: list[tuple[int, int]] = []
    for f in sorted(features, key=lambda f: f.first):
        if out and f.first <= out[-1][1] + 1:
            out[-1] = (out[-1][0], max(out[-1][1], f.last))
        else:
            out.append((f.first, f.last))
    return out


def _overlaps(f: Feature, g: Feature) -> bool:
    """Whether ``f`` and ``g`` share layers and, within a voxel, a place across the axis."""
    return (
        f.first <= g.last
        and g.first <= f.last
        and all(
            a[0] <= b[1] + 1 and b[0] <= a[1] + 1 for a, b in zip(f.across, g.across, strict=True)
        )
    )


def _alike(f: Feature, g: Feature) -> bool:
    """Whether ``g`` could be a copy of ``f`` along the axis: the same kind, as long within a
    voxel (a quarter for a long one) and at the same place across the axis within a voxel.
    """
    lf, lg = f.last - f.first, g.last - g.first
    return (
        f.kind == g.kind
        and abs(lf - lg) <= max(1.0, 0.25 * max(lf, lg))
        and all(
            abs(a[0] - b[0]) <= 1 and abs(a[1] - b[1]) <= 1
            for a, b in zip(f.across, g.across, strict=True)
        )
    )


def cut_features(features: list[Feature], plane: float) -> list[Feature]:
    """The features a plane at continuous layer index ``plane`` passes through (each occupies
    half a layer past its first and last).
    """
    return [f for f in features if f.first - 0.5 < plane < f.last + 0.5]


def whole_copies(
    features: list[Feature], start: float, period: float, lo: float, hi: float
) -> bool:
    """Whether tiling a zone of a repeat copies whole elements.

    Whether tiling the zone ``[start, start + period]`` (continuous layer indices) of a
    repeat over ``[lo, hi]`` copies whole elements.

    Neither plane may pass through a local feature (the copies would join a knob's halves to
    whatever the other plane cuts), and each feature of a calm run inside the zone must have
    one alike (:func:`_alike`: a translated or a mirrored copy) in the period before or after
    it within the repeat: a handle on one door of two, inside a zone of one pane, is no part
    of the period, and tiling it would double it.

    Parameters
    ----------
    features : list of Feature
        The axis's local features (:func:`axis_features`).
    start : float
        The zone's first plane (continuous layer index).
    period : float
        The zone's length, layers.
    lo, hi : float
        The repeat's extent, layers.

    Returns
    -------
    bool
        True where the copies would be whole elements.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> door = shapes.door()
    >>> knob = zones.axis_features(door, 0, [(4, 82)])
    >>> zones.whole_copies(knob, 10.0, 20.0, 4.0, 82.0), zones.whole_copies(knob, 60.0, 10.0, 4.0, 82.0)
    (True, False)
    """
    end = start + period
    if cut_features(features, start) or cut_features(features, end):
        return False
    near = [(max(lo, start - period) - 1, start), (end, min(hi, end + period) + 1)]
    return all(
        any(
            g is not f and _alike(f, g) and any(a <= g.first and g.last <= b for a, b in near)
            for g in features
        )
        for f in features
        if f.calm and start <= f.first and f.last <= end
    )


def local_features(
    csdf: CSDF, axis: str | int, zone: tuple[float, float]
) -> list[tuple[float, float]]:
    """The local features (a knob, a handle, a motif) that stretching ``zone`` would deform.

    World ``(start, end)`` extents along ``axis`` (x, y, z or 0, 1, 2) of the local features (a
    knob, a handle, a hinge, a keyhole, a colour motif: :func:`run_features`) between the
    planes of ``zone`` (world units), even in part: what stretching that zone would stretch out
    of shape. Empty for a zone of constant section.

    Those of the axis's calm runs (:func:`axis_features`, where the slabs :mod:`.suggest`
    offers are cut) and those of the zone's own layers.

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : {'x', 'y', 'z'} or {0, 1, 2}
        The axis ``zone`` lies along.
    zone : (float, float)
        The zone's planes, world units.

    Returns
    -------
    list of (float, float)
        World extents of the features along the axis.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> door = shapes.door()
    >>> [(round(a, 3), round(b, 3)) for a, b in zones.local_features(door, "x", (0.5, 0.75))]
    [(0.615, 0.685)]
    >>> zones.local_features(door, "x", (0.1, 0.4))
    []
    """
    ax = _axis_index(axis)
    h = csdf.voxel_size
    o = float(csdf.origin[ax])
    first = max(int(np.ceil((zone[0] - o) / h - 1e-6)), 0)
    last = min(int(np.floor((zone[1] - o) / h + 1e-6)), csdf.shape[ax] - 1)
    if last - first < 2:
        return []
    found = axis_features(csdf, ax, calm_runs(profile(csdf, ax))) + run_features(
        csdf, ax, first, last
    )
    inside = [f for f in found if f.first <= last and first <= f.last]
    # each reaches half a layer past its first and last
    return [(o + (a - 0.5) * h, o + (b + 0.5) * h) for a, b in feature_spans(inside)]


def feature_notes(csdf: CSDF, recipe: Recipe) -> list[str]:
    """One line per stretch edit of ``recipe`` whose zone holds a local feature (:func:`local_features`).

    Such a feature is stretched with the zone, out of shape. Zones are read on ``csdf``, the
    recipe's input (recipe coordinates).

    Parameters
    ----------
    csdf : CSDF
        The recipe's input.
    recipe : Recipe
        The edits.

    Returns
    -------
    list of str
        The notes.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> door = shapes.door()
    >>> from partscale.edit import Edit, Recipe
    >>> print(zones.feature_notes(door, Recipe((Edit("x", 0.5, 0.75, 0.9),)))[0][:66])
    the stretch zone 0.5..0.75 m along x holds 1 local feature (a knob
    """
    sb = csdf.surface_bounds()
    units = csdf.meta.get("units")
    u = unit_suffix(units)
    lines = []
    for i, e in enumerate(recipe.edits):
        if not isinstance(e, Edit) or e.mode != "stretch":
            continue
        ax = e.axis_index
        s, en, _ = e.resolve(float(sb[0, ax]), float(sb[1, ax]))
        found = local_features(csdf, ax, (s, en))
        if not found:
            continue
        where = ", ".join(f"{a:.4g}..{b:.4g}" for a, b in found)
        lines.append(
            f"{edit_label(i, len(recipe.edits))}the stretch zone "
            f"{s:.4g}..{en:.4g}{u} along {e.axis} holds {len(found)} local feature"
            f"{'s' if len(found) > 1 else ''} (a knob, a handle, a motif) at {where}{u}, stretched out "
            f"of shape with it; --snap (the editor's snapping) moves the zone into a constant slab"
        )
    return lines
