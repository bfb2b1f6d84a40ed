"""Zone candidates found in the object itself: repeated elements (tile) and constant slabs (stretch).

Repetition (in the spirit of Bokeloh et al.'s symmetry-based repetition detection, on the voxel
grid instead of a clean mesh): along an axis, layer ``i`` and the layer ``s`` voxels beyond it are
compared for every shift ``s`` (quarter-voxel steps, interpolated layers) by the soft Jaccard
distance of their cross-sections (:mod:`.profile`). A *repeat* at shift ``s`` is a run of
consecutive layers that all match the layer ``s`` beyond (distance below :data:`MATCH`), whose
content within one period is not constant (some pair of layers less than ``s`` apart differs by
at least :data:`CONTRAST`, so a constant slab, which matches itself at every shift, is no
repeat), covering at least :data:`MIN_COUNT` periods, or two periods matched strongly (mean
distance below :data:`STRONG`; a pair of drawers, but not a table's two legs, whose run covers
only the legs). The period is the shift of least mean distance near it; multiples of a period
(which match as well) are dropped. The zone is one period whose planes lie where the cost
``area / max area + distance(plane, plane + period)`` is lowest, in the middle of that low run:
in the gaps between elements, or where the cross-sections at both planes match.

Bounded repeats (:func:`find_bounded_repeats`, a second, weaker detector for copies that do not
match layer for layer: soft cushions, mirrored drawers): repeated elements are separated by
boundaries, a board or divider (a local maximum of the cross-section area) or a gap or groove (a
local minimum), each changing the area by at least :data:`PROMINENCE` of the largest cross-section.
A chain of boundaries of one kind delimits at least two elements that are copies: equally wide,
equally spaced (within :data:`BOUND_TOL`), each boundary narrower than half an element (a
boundary is thinner than what it separates; a cushion's broad crown is no boundary), each with
a shape of its own (no constant slab: the equal spans between a symmetric frame's supports, a
table's legs and centre stretcher, are the space between boundaries, not elements; boards
repeated over constant spans are the full match's), their coarse cross-sections alike, shifted
or mirrored (a drawer's handle sits on the mirrored side), in all but a tenth of the layers
(:data:`QUANTILE`), and the layers at the two planes of one period match (:data:`MATCH`), so
the copies join seamlessly. The period is the shift carrying
one element onto the next; the zone runs from one element's start to the next's (one element
and one interior boundary). Such a candidate scores :data:`BOUNDED_WEIGHT` of a full match.

Constant slabs: maximal runs of layers whose neighbour-to-neighbour distance stays below
:data:`STEP` (:func:`calm_runs`) and whose ends differ by less than :data:`DRIFT`, cut around
the local features (a knob, a handle, a colour motif: :func:`~.features.axis_features`) that the
whole-section distance cannot see; stretching them resamples equal layers, so nothing is
distorted. Where the CSDF is segmented, a slab's planes are moved to the
nearest plane between parts (a part's bounding box end) within a voxel, and its reason names them;
a row of at least :data:`MIN_COUNT` equal parts at a constant pitch (:func:`_part_repeats`) is a
repeat in itself, read from the segmentation's part boxes alone.

A period is only real where its copies repeat whole elements: every tile candidate's zone copies
whole elements (:func:`~.features.whole_copies`: no plane through a local feature, none in the
zone that the periods beside it lack, as a handle on one door of two), moved by whole periods,
or for a full match to the best phase, where it would not; else it is dropped (:func:`_whole`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace
from typing import Literal, NamedTuple

import numpy as np
from scipy import ndimage
from scipy.signal import find_peaks

from .._options import keyword_options
from ..csdf import BAND_VOXELS, CSDF
from ..edit import AXES, SEAM_VOXELS
from ..progress import ProgressCallback, resolve
from .features import Feature, axis_features, feature_spans, whole_copies
from .profile import MIN_SLAB, Profile, _axis_index, _runs, _solid_layers, calm_runs, profile

#: Two layers match when their soft Jaccard distance is below this.
MATCH = 0.15
#: A repeat's mean distance below this is a strong match (enough for two periods).
STRONG = 0.05
#: The content of one period must hold two layers at least this far apart.
CONTRAST = 0.35
#: Share of a repeat's layers whose one-period window must hold that contrast.
VARIED = 0.9
#: Fewest periods a repeat must cover (two are enough with a strong match).
MIN_COUNT = 3
#: How far (voxels) a copy may sit from its place in a strict period and still match.
JITTER = 0.5
#: Shift step of the period search, voxels.
SHIFT_STEP = 0.25
#: Constant slab: neighbouring layers closer than :data:`STEP` (see :func:`calm_runs`), its two
#: ends closer than DRIFT.
DRIFT = 0.06
#: :data:`DRIFT` on a completed scan (:attr:`Profile.scan`): the distance from a constant run's
#: first layer to its others does not grow there but stays at the scan's noise, 0.03-0.08 once
#: averaged (a bookcase's shelves 0.03, a pedal bin's body 0.07), where a mesh's is 0.
SCAN_DRIFT = 0.12


def drift_limit(p: Profile) -> float:
    """The drift (:data:`DRIFT`, on a scan :data:`SCAN_DRIFT`) within which a slab's layers are
    one constant section.
    """
    return SCAN_DRIFT if p.scan else DRIFT


#: A boundary between elements changes the cross-section area by this share of the largest one.
PROMINENCE = 0.05
#: Copies of one element, voxelised at different phases, differ in width and spacing this much.
BOUND_TOL = 1.0
#: Share of an element's layers that must match its copy (the rest: knobs, seams, wear).
QUANTILE = 0.9
#: Score of a bounded repeat relative to a full cross-section match.
BOUNDED_WEIGHT = 0.5
#: A tile join's jump compares layers this many apart, centred on the join (:func:`join_jump`):
#: wider than the scaling stage's blend, which spreads a jump without removing it.
SEAM_WINDOW = 5
#: Layers either side of a zone that :func:`join_jump` tiles with it: the seam window and its
#: trend layers, the blend and the re-evaluation's reach.
JOIN_MARGIN = 10


@dataclass(frozen=True)
class Candidate:
    """A suggested zone.

    Parameters
    ----------
    axis : {'x', 'y', 'z'}
        The axis.
    kind : {'tile', 'stretch'}
        Repeat one period, or stretch a slab of constant cross-section.
    zone : (float, float)
        World ``(start, end)`` along the axis; for ``tile`` exactly one period long.
    period : float or None
        Tile: the period (world units); None for stretch.
    count : int or None
        Tile: how many whole periods the repeat covers; None for stretch.
    score : float
        0..1, higher is better; comparable across kinds and axes.
    reason : str
        One line: what was found.
    region : (float, float)
        World extent of the repeat (tile) or the slab (stretch).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> best = zones.suggest(bookcase, "y")[0]
    >>> best.kind, best.period, best.count
    ('tile', 0.295, 4)
    """

    axis: str
    kind: Literal["tile", "stretch"]
    zone: tuple[float, float]
    period: float | None
    count: int | None
    score: float
    reason: str
    region: tuple[float, float]

    def to_json(self) -> dict:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        d = {
            "axis": self.axis,
            "kind": self.kind,
            "zone": [self.zone[0], self.zone[1]],
            "score": round(self.score, 4),
            "reason": self.reason,
            "region": [self.region[0], self.region[1]],
        }
        if self.kind == "tile":
            d["period"] = self.period
            d["count"] = self.count
        return d


@dataclass(frozen=True)
class _Repeat:
    shift: float  # period, voxels
    first: int  # first layer of the matching run
    last: int  # last layer of the matching run
    err: float  # mean distance over the run at the refined period
    count: int

    @property
    def span(self) -> tuple[float, float]:
        return float(self.first), float(self.last) + self.shift


def find_repeats(p: Profile) -> list[_Repeat]:
    """Every repeat of ``p`` (see module docstring), fundamental periods only, best first."""
    i0, i1 = _solid_layers(p)
    n_solid = i1 - i0 + 1
    if n_solid < 6:
        return []
    dist = p.distance(np.arange(p.n)[:, None], np.arange(p.n)[None, :])
    layers = np.arange(i0, i1 + 1)
    shifts = np.arange(2.0, n_solid / 2 + SHIFT_STEP, SHIFT_STEP)
    err = p.shifted_distance(layers[None, :], shifts[:, None])  # (S, N)
    # repeats drift by up to JITTER between copies (hand-placed shelves): a layer matches if a
    # layer within JITTER of the shifted position does
    w = round(JITTER / SHIFT_STEP)
    loose = ndimage.minimum_filter1d(err, 2 * w + 1, axis=0, mode="nearest")
    found: list[_Repeat] = []
    for si, s in enumerate(shifts):
        e = loose[si]
        # the shifted layer must lie within the solid too
        ok = (e < MATCH) & (layers + s <= i1 + 0.5)
        for a, b in _runs(ok):
            run_len = b - a + 1
            if run_len + s < 2 * s - 1e-9:  # fewer than two periods
                continue
            first, last = layers[a], layers[b]
            # content within every period must vary (each window of one period from a layer of
            # the run holds a layer far from it): a constant slab matches itself at every shift,
            # and one with a feature at its end is no repeat either
            sub = dist[first : last + 1, first : min(last + int(np.ceil(s)), p.n)]
            off = np.arange(sub.shape[1])[None, :] - np.arange(sub.shape[0])[:, None]
            varied = np.where((off > 0) & (off < s), sub, 0.0).max(axis=1) >= CONTRAST
            if varied.mean() < VARIED:
                continue
            # the period: the shift near s of least mean (exact) distance over the run
            near = np.flatnonzero(np.abs(shifts - s) <= JITTER + 1e-9)
            best = near[np.argmin(err[near, a : b + 1].mean(axis=1))]
            found.append(
                _Repeat(float(shifts[best]), int(first), int(last), float(e[a : b + 1].mean()), 0)
            )
    if not found:
        return []
    # refine: for each (run, shift) keep the shift of least mean error among near-equal ones
    # longest well-matched repeats first: a short run at a near-equal shift must not hide one
    found.sort(key=lambda r: -(r.last - r.first + 1 + r.shift) * (1 - r.err / MATCH))
    kept: list[_Repeat] = []
    for r in found:
        if any(abs(r.shift - q.shift) <= 1.0 and _overlap(r, q) > 0.5 for q in kept):
            continue
        count = int(np.floor((r.last - r.first + 1 + r.shift) / r.shift + 0.25))
        strong = r.err < STRONG
        if count < MIN_COUNT and not (count >= 2 and strong):
            continue
        kept.append(_Repeat(r.shift, r.first, r.last, r.err, count))
    # drop multiples of a kept period over the same region (they match too)
    out: list[_Repeat] = []
    for r in sorted(kept, key=lambda r: r.shift):
        if any(
            _overlap(r, q) > 0.5 and abs(r.shift / q.shift - round(r.shift / q.shift)) * q.shift < 1
            for q in out
        ):
            continue
        out.append(r)
    return out


def _overlap(a: _Repeat, b: _Repeat) -> float:
    lo = max(a.span[0], b.span[0])
    hi = min(a.span[1], b.span[1])
    return max(0.0, hi - lo) / max(1e-9, min(a.span[1] - a.span[0], b.span[1] - b.span[0]))


@dataclass(frozen=True)
class BoundedRepeat:
    """Elements repeated between boundaries along a profile's axis (:func:`find_bounded_repeats`).

    Parameters
    ----------
    period : float
        The shift carrying one element onto the next, in voxels.
    elements : tuple of (float, float)
        Each element's ``(start, end)`` as layer indices (:meth:`Profile.world` gives world).
    err : float
        Mean coarse cross-section distance between consecutive elements.
    mirrored : bool
        Whether consecutive elements match mirrored (drawers with handles facing a divider).
    kind : {1, -1}
        The boundaries: ``1`` boards or dividers, ``-1`` gaps or grooves.
    start : float
        The zone's start (layer index): one element and one interior boundary from there.

    Examples
    --------
    >>> from partscale.zones import BoundedRepeat
    >>> drawers = BoundedRepeat(period=30.0, elements=((2, 30), (32, 60)), err=0.01, mirrored=False, kind=-1, start=1.0)
    >>> len(drawers.elements), drawers.kind  # two elements between grooves
    (2, -1)
    """

    period: float
    elements: tuple[tuple[float, float], ...]
    err: float
    mirrored: bool
    kind: int
    start: float


def _boundaries(p: Profile) -> list[tuple[int, float, float, float]]:
    """``(kind, lo, hi, cut)`` of every boundary inside the solid: ``kind`` +1 for a local
    maximum of the area (a board: faces ``lo``..``hi`` at half prominence, where elements end),
    -1 for a minimum (a gap or groove: elements meet at its deepest point ``cut``).
    """
    a = p.area / max(float(p.area.max()), 1e-9)
    i0, i1 = _solid_layers(p)
    out = []
    for kind in (1, -1):
        peaks, props = find_peaks(kind * a, prominence=PROMINENCE, width=0, rel_height=0.5)
        inner = (peaks > i0) & (peaks < i1)
        for i, lo, hi in zip(
            peaks[inner], props["left_ips"][inner], props["right_ips"][inner], strict=True
        ):
            y0, y1, y2 = a[i - 1], a[i], a[i + 1]
            den = y0 - 2 * y1 + y2
            cut = i + float(np.clip(0.5 * (y0 - y2) / den, -0.5, 0.5)) if abs(den) > 1e-12 else i
            out.append((kind, float(lo), float(hi), float(cut)))
    return out


def _element_distance(p: Profile, e: tuple[float, float], f: tuple[float, float], mirror: bool):
    """(K,) coarse distances between element ``e``'s layers and the matching layers of ``f``."""
    i = np.arange(int(np.ceil(e[0])), int(np.floor(e[1])) + 1)
    t = (i - e[0]) / max(e[1] - e[0], 1e-9)
    x = f[1] - t * (f[1] - f[0]) if mirror else f[0] + t * (f[1] - f[0])
    return p.shifted_distance(i, x - i, coarse=True)


def find_bounded_repeats(p: Profile, csdf: CSDF | None = None) -> list[BoundedRepeat]:
    """Every bounded repeat of a profile (see module docstring), best first.

    Parameters
    ----------
    p : Profile
        The cross-sections along an axis.
    csdf : CSDF, optional
        The object ``p`` is the profile of, to keep the zone's planes off thin features (see
        :func:`join_islands`).

    Returns
    -------
    list of BoundedRepeat
        Elements repeated between boundaries (drawers between dividers, doors between grooves).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> zones.find_bounded_repeats(zones.profile(bookcase, "y"), bookcase)  # shelves: a plain repeat
    []
    """
    i0, i1 = _solid_layers(p)
    n_solid = i1 - i0 + 1
    found: list[tuple[int, list[tuple[float, float]]]] = []
    bounds = _boundaries(p)
    for kind in (1, -1):
        b = sorted((x for x in bounds if x[0] == kind), key=lambda x: x[1])
        # a separator: one gap, or a run of consecutive boards (a divider of two faces); at most
        # a quarter of the solid (narrower than half an element, two elements at least)
        seps = [
            (j, k, b[j][1], b[k][2], b[j][3], b[k][3])
            for j in range(len(b))
            for k in range(j, len(b) if kind == 1 else j + 1)
            if b[k][2] - b[j][1] <= n_solid / 4
        ]

        def ends(sep, kind=kind):  # (where an element before it ends, after it starts)
            return (sep[2], sep[3]) if kind == 1 else (sep[4], sep[5])

        after: dict[int, list] = {}
        for si, sa in enumerate(seps):
            for sj, sb in enumerate(seps):
                if sb[0] > sa[1]:
                    e = (ends(sa)[1], ends(sb)[0])
                    # an element of under two layers has no shape to compare
                    if e[1] - e[0] >= 2 and max(sa[3] - sa[2], sb[3] - sb[2]) <= (e[1] - e[0]) / 2:
                        after.setdefault(si, []).append((e, sj))

        def chains(chain, last, after=after):
            grown = False
            for e, nxt in after.get(last, []):
                first = chain[0]
                if abs((e[1] - e[0]) - (first[1] - first[0])) > BOUND_TOL:
                    continue
                if (
                    len(chain) >= 2
                    and abs((e[0] - chain[-1][0]) - (chain[1][0] - first[0])) > BOUND_TOL
                ):
                    continue
                grown = True
                yield from chains([*chain, e], nxt)
            if not grown and len(chain) >= 2:
                yield chain

        found += [(kind, c) for si in after for e, nxt in after[si] for c in chains([e], nxt)]
    # longest chains first; sub-chains and multiples of a kept chain's period over it add nothing
    found.sort(key=lambda c: -len(c[1]))
    out: list[BoundedRepeat] = []
    for kind, chain in found:
        period = chain[1][0] - chain[0][0]
        if any(
            chain[0][0] >= q.elements[0][0] - BOUND_TOL
            and chain[-1][1] <= q.elements[-1][1] + BOUND_TOL
            and abs(period - round(period / q.period) * q.period) <= BOUND_TOL
            for q in out
        ):
            continue
        r = _check_chain(p, chain, kind, csdf)
        if r is not None:
            out.append(r)
    out.sort(key=lambda r: (-len(r.elements), r.err))
    return out


def _check_chain(
    p: Profile, chain: list[tuple[float, float]], kind: int, csdf: CSDF | None = None
) -> BoundedRepeat | None:
    """The chain as a bounded repeat if its elements are copies joining seamlessly, else None.

    The zone starts at an element's start or end: with ``csdf``, those whose joins between
    copies cut off the fewest solid voxels (:func:`join_islands`), then the lowest
    :func:`plane_cost`.
    """
    for e in chain:  # an element has a shape of its own: no constant slab (see module)
        i = np.arange(int(np.ceil(e[0])), int(np.floor(e[1])) + 1)
        if p.distance(i[:, None], i[None, :]).max(initial=0.0) < drift_limit(p):
            return None
    errs, mirrored = [], False
    for e, f in itertools.pairwise(chain):
        best = None
        for mirror in (False, True):
            d = _element_distance(p, e, f, mirror)
            if d.size and np.quantile(d, QUANTILE) <= MATCH and (best is None or d.mean() < best):
                best, m = float(d.mean()), mirror
        if best is None:
            return None
        errs.append(best)
        mirrored |= m
    shifts = [f[0] - e[0] for e, f in itertools.pairwise(chain)]
    shifts += [f[1] - e[1] for e, f in itertools.pairwise(chain)]
    period = float(np.mean(shifts))
    # the planes: an element's start (or end) and the next's, where the layers match best
    starts = np.array([e[0] for e in chain[:-1]] + [e[1] for e in chain[:-1]])
    k = np.round(starts).astype(np.int64)
    seam = p.shifted_distance(k, starts + period - k)
    if seam.min() > MATCH:
        return None
    cost = np.where(seam <= MATCH, plane_cost(p, period, starts), np.inf)
    if csdf is not None:
        ok = np.isfinite(cost)
        cut = np.array(
            [
                join_islands(csdf, p.axis, t, period) if o else 0
                for t, o in zip(starts, ok, strict=True)
            ]
        )
        cost = np.where(ok & (cut > cut[ok].min()), np.inf, cost)
    good = np.flatnonzero(cost <= cost.min() + 0.03)
    mid = (chain[0][0] + chain[-1][1] - period) / 2
    start = float(starts[good[np.argmin(np.abs(starts[good] - mid))]])
    return BoundedRepeat(period, tuple(chain), float(np.mean(errs)), mirrored, kind, start)


def join_islands(csdf: CSDF, axis: int, start: float, period: float) -> int:
    """Solid voxels a join between tile copies of ``[start, start + period]`` (layer indices
    along ``axis``) cuts off: in the join's cross-fade (:data:`~partscale.edit.SEAM_VOXELS`
    either side, the left copy's layers past ``start + period`` weighed against the right
    copy's past ``start``, sampled at the output's layers) and one layer beyond, the solid of
    face-connected components touching neither end layer, less that of the same window in the
    object on either plane whose components are apart even across edges and corners (its own
    small parts).

    A thin feature (a one-voxel strip) that ends within the cross-fade fades into the other
    copy's air there; what is left attached only along an edge or corner is fragile (the
    interpolated field decides whether the surface keeps it): a loose fragment, an extra piece
    at every join, which no cross-section measure of the profile notices (a few voxels of a
    large section).
    """
    s = np.moveaxis(csdf.sdf, axis, 0)
    n = s.shape[0]
    reach = int(np.ceil(SEAM_VOXELS)) + 1
    ys = start + period
    j = np.arange(int(np.ceil(ys - reach)), int(np.floor(ys + reach)) + 1)

    def layers(x: np.ndarray) -> np.ndarray:  # sdf at continuous layer indices x (clamped)
        x = np.clip(x, 0.0, n - 1.0)
        i = np.floor(x).astype(np.int64)
        f = (x - i).astype(np.float32)[:, None, None]
        return (1 - f) * s[i] + f * s[np.minimum(i + 1, n - 1)]

    o = j - ys
    right = np.clip(o / (2 * SEAM_VOXELS) + 0.5, 0.0, 1.0).astype(np.float32)[:, None, None]
    joined = (1 - right) * layers(ys + o) + right * layers(start + o)

    def loose(win: np.ndarray, structure: np.ndarray | None = None) -> int:
        lab, k = ndimage.label(win < 0, structure=structure)
        if k == 0:
            return 0
        ends = np.union1d(lab[0], lab[-1])
        size = np.bincount(lab.ravel(), minlength=k + 1)
        size[ends] = 0
        return int(size[1:].sum())

    # the object's own small parts: apart even across edges and corners
    full = np.ones((3, 3, 3), bool)
    own = max(loose(layers(start + o), full), loose(layers(ys + o), full))
    return max(0, loose(joined) - own)


def layer_step(
    before: np.ndarray,
    first: np.ndarray,
    last: np.ndarray,
    after: np.ndarray,
    h: float,
    window: int = SEAM_WINDOW,
) -> np.ndarray:
    """The shape step between two layers of distances ``window`` layers apart, per voxel.

    Parameters
    ----------
    before, first, last, after : (..., M, N) float32 arrays
        Signed distances (negative inside) of the layer before the pair, the pair's two layers
        (``first`` and ``last``, ``window`` layers apart) and the layer after it; any leading
        axes are broadcast (a stack of pairs).
    h : float
        The voxel size.
    window : int, optional
        Layers between ``first`` and ``last``; :data:`SEAM_WINDOW` by default.

    Returns
    -------
    (..., M, N) float32 array
        ``|(last - first) - trend| / h``, clipped at ``2 * BAND_VOXELS``, the trend being what
        the one-layer steps just outside the pair predict over the pair,
        ``window * ((first - before) + (after - last)) / 2``: zero for a surface that
        changes linearly (a slanted leg), the full step for a discontinuity however it was
        blended within the pair. The seam measure of fit and of the evaluation.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.zones import layer_step
    >>> ramp = [np.full((2, 2), v, np.float32) for v in (0.0, 0.1, 0.6, 0.7)]
    >>> round(float(layer_step(*ramp, h=0.1).max()), 4)  # a linear field: no step
    0.0
    >>> jump = [np.full((2, 2), v, np.float32) for v in (0.0, 0.1, 0.68, 0.78)]
    >>> round(float(layer_step(*jump, h=0.1).max()), 4)  # 0.08 more than the trend
    0.8
    """
    trend = window * ((first - before) + (after - last)) / 2
    return np.minimum(np.abs((last - first) - trend) / h, 2 * BAND_VOXELS)


def _window_step(f: np.ndarray, h: float) -> float:
    """The shape step across a window of layers ``f`` (``SEAM_WINDOW + 3`` of them: one before
    the pair compared, the pair :data:`SEAM_WINDOW` apart, one after): the mean
    :func:`layer_step` over the voxels within a voxel of the surface on either layer of the
    pair; NaN with fewer than 3 such voxels.
    """
    k = SEAM_WINDOW
    f = f.astype(np.float32)
    f0, fk = f[1], f[k + 1]
    step = layer_step(f[0], f0, fk, f[k + 2], h)
    either = (np.abs(f0) <= h) | (np.abs(fk) <= h)
    if either.sum() < 3:
        return math.nan
    return float(step[either].mean())


def _seam_step(s: np.ndarray, y: float, h: float) -> float:
    """The largest :func:`_window_step` of ``s`` (layers first) among the windows centred on
    layer index ``y`` and one layer either side (a plane on a layer still shows its largest
    jump); NaN where none measures (the windows clamped to the layers there are).
    """
    k = SEAM_WINDOW
    first = math.floor(y) - (k - 1) // 2
    steps = [
        _window_step(s[np.clip(np.arange(i - 1, i + k + 2), 0, len(s) - 1)], h)
        for i in (first - 1, first, first + 1)
    ]
    finite = [x for x in steps if math.isfinite(x)]
    return max(finite) if finite else math.nan


def join_jump(csdf: CSDF, axis: int, start: float, period: float) -> float:
    """The shape jump (voxels) a join between tile copies of ``[start, start + period]``
    (layer indices along ``axis``, the period whole) adds to the object's own at the zone's
    planes: what the evaluation's seam shape measures at that join.

    The zone is tiled once more by the edit stage itself (:func:`partscale.edit.apply_edit`:
    its seam blend and re-evaluation), on the layers from :data:`JOIN_MARGIN` before the zone
    to as many after it (the join sees no further); the join's step (:func:`_seam_step`) less
    the larger of the object's own steps at the two planes (a board lying at a plane steps
    there in the object too), at least 0; 0 where no surface crosses the join. Planes where the
    cross-section is the same either side of the join (both in a gap, or in a constant
    stretch) join all but cleanly (the stage's blend leaves a little); one mid-cushion and the
    other on its rounded edge jump.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.zones.suggest import join_jump
    >>> bookcase = shapes.bookcase(height=1.22)  # a shelf every 15 layers, from layer 3
    >>> round(join_jump(bookcase, 1, 10.5, 15.0), 2)  # one row, air to air
    0.14
    >>> round(join_jump(bookcase, 1, 18.0, 7.0), 2)  # a shelf's underside joined to air
    3.13
    """
    from ..edit import Edit, apply_edit

    h = csdf.voxel_size
    n = csdf.shape[axis]
    i0 = max(0, math.floor(start) - JOIN_MARGIN)
    i1 = min(n, math.ceil(start + period) + JOIN_MARGIN + 1)
    crop: list[slice] = [slice(None)] * 3
    crop[axis] = slice(i0, i1)
    box = tuple(crop)
    origin = csdf.origin.copy()
    origin[axis] += i0 * h
    part = csdf.replace(sdf=csdf.sdf[box], rgb=csdf.rgb[box], parts=csdf.parts[box], origin=origin)
    s = float(origin[axis] + (start - i0) * h)
    e = s + period * h
    tiled = apply_edit(part, Edit(AXES[axis], s, e, e + period * h, "tile"))
    joined = np.moveaxis(tiled.sdf, axis, 0)
    jump = _seam_step(joined, (e - tiled.origin[axis]) / h, h)
    if not math.isfinite(jump):
        return 0.0
    layers = np.moveaxis(csdf.sdf, axis, 0)
    own = [_seam_step(layers, y, h) for y in (start, start + period)]
    return max(0.0, jump - max((x for x in own if math.isfinite(x)), default=0.0))


def plane_cost(p: Profile, period: float, starts: np.ndarray) -> np.ndarray:
    """(K,) cost of a tile zone ``[t, t + period]`` (layer indices ``starts``): low in gaps and
    where the two planes' cross-sections match.
    """
    amax = max(float(p.area.max()), 1e-9)
    area = np.interp(starts, np.arange(p.n), p.area) / amax
    area2 = np.interp(starts + period, np.arange(p.n), p.area) / amax
    k = np.floor(starts).astype(np.int64)
    f = starts - k
    # distance between the layers at t and t + period, both interpolated (via the nearer layer)
    base = np.where(f < 0.5, k, np.minimum(k + 1, p.n - 1))
    d = p.shifted_distance(base, period + starts - base)
    return 0.5 * (area + area2) + d


def best_phase(p: Profile, period: float, lo: float, hi: float, near: float | None = None) -> float:
    """Start (layer index) of the best one-period zone inside ``[lo, hi]`` (layer indices).

    The lowest-cost run of starts (quarter-voxel steps) nearest ``near`` (default: the middle of
    the range), and the middle of that run.
    """
    starts = np.arange(lo, hi - period + 1e-9, SHIFT_STEP)
    if starts.size == 0:
        return lo
    return _best_of(p, period, starts, (lo + hi - period) / 2 if near is None else near)


def whole_phase(
    p: Profile,
    period: float,
    lo: float,
    hi: float,
    features: list[Feature],
    near: float | None = None,
) -> float | None:
    """:func:`best_phase` among the starts whose zone copies whole elements
    (:func:`~.features.whole_copies` of the axis's local ``features``); None where none does.
    """
    starts = np.arange(lo, hi - period + 1e-9, SHIFT_STEP)
    starts = starts[[whole_copies(features, x, period, lo, hi) for x in starts]]
    if starts.size == 0:
        return None
    return _best_of(p, period, starts, (lo + hi - period) / 2 if near is None else near)


def _best_of(p: Profile, period: float, starts: np.ndarray, near: float) -> float:
    """The middle of the run of lowest-cost ``starts`` (ascending) nearest ``near``."""
    cost = plane_cost(p, period, starts)
    good = cost <= cost.min() + 0.03
    runs = _split_at_gaps(good, starts)
    mids = (starts[runs[:, 0]] + starts[runs[:, 1]]) / 2
    best = runs[np.argmin(np.abs(mids - near))]
    return float((starts[best[0]] + starts[best[1]]) / 2)


def _split_at_gaps(good: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(R, 2) ``[first, last]`` indices of the runs of ``good`` starts that follow each other
    one :data:`SHIFT_STEP` apart.
    """
    apart = np.concatenate([[True], np.diff(starts) > SHIFT_STEP * 1.5])
    edges = np.flatnonzero(apart)
    out = []
    for a, b in zip(edges, [*edges[1:], len(starts)], strict=True):
        out += [[a + r0, a + r1] for r0, r1 in _runs(good[a:b])]
    return np.asarray(out, dtype=np.int64).reshape(-1, 2)


def _whole(c: Candidate, p: Profile, features: list[Feature], free: bool) -> Candidate | None:
    """The tile candidate ``c`` with its zone moved, where it would not copy whole elements
    (:func:`~.features.whole_copies`), by whole periods inside its region (the nearest such
    zone: another element like it), else, with ``free`` (a full cross-section match, whose
    phase is chosen by :func:`best_phase`), to the best phase that does; None where none does
    (a period through a handle or a mullion is no period).
    """
    assert c.period is not None and c.count is not None  # a tile candidate has both
    if not features:
        return c
    period = c.period / p.voxel_size
    lo, hi = (float(x) for x in p.index(np.array(c.region)))
    t = float(p.index(c.zone[0]))
    k = np.arange(-c.count - 1, c.count + 2)
    k = k[np.argsort(np.abs(k), kind="stable")]
    slack = BOUND_TOL
    for x in t + k * period:
        if (
            lo - slack <= x
            and x + period <= hi + slack
            and whole_copies(features, x, period, lo, hi)
        ):
            return _moved(c, p, x)
    if free and (x := whole_phase(p, period, lo, hi, features, near=t)) is not None:
        return _moved(c, p, x)
    return None


def _moved(c: Candidate, p: Profile, start: float) -> Candidate:
    """``c`` with its zone starting at layer index ``start``."""
    s = float(p.world(start))
    assert c.period is not None  # a tile candidate has one
    return replace(c, zone=(s, s + c.period))


class Slab(NamedTuple):
    """A constant slab: layers ``first..last`` (inclusive), the largest distance of a layer from
    the first (``drift``), and whether a local feature bounds it (``at_feature``).
    """

    first: int
    last: int
    drift: float
    at_feature: bool = False


def constant_slabs(
    p: Profile, csdf: CSDF | None = None, features: list[Feature] | None = None
) -> list[Slab]:
    """Layer runs of constant, non-empty cross-section (see module).

    ``csdf``: the object ``p`` was taken from; each calm run is then also cut around its local
    features (``features``, default :func:`~.features.axis_features` of the calm runs) before
    it is split where it drifts.
    """
    runs = calm_runs(p)
    feats: list[Feature] = []
    if csdf is not None:
        feats = axis_features(csdf, p.axis, runs) if features is None else features
        runs = [piece for a, b in runs for piece in _beside_features(a, b, feats)]
    spans = feature_spans(feats)
    out = []
    for first, last in runs:
        # split where the drift from the slab's start exceeds the limit (a slowly changing
        # section)
        while last - first + 1 >= MIN_SLAB:
            drift = p.distance(np.full(last - first + 1, first), np.arange(first, last + 1))
            over = np.flatnonzero(drift >= drift_limit(p))
            end = int(over[0] - 1 + first) if over.size else last
            if end - first + 1 >= MIN_SLAB:
                beside = any(first - 2 <= b < first or end < a <= end + 2 for a, b in spans)
                out.append(Slab(first, end, float(drift[: end - first + 1].max()), beside))
            first = end + 1
    return out


def _beside_features(first: int, last: int, features: list[Feature]) -> list[tuple[int, int]]:
    """The runs of layers ``first..last`` (inclusive) that hold no part of ``features``, at
    least :data:`MIN_SLAB` long.
    """
    keep = np.ones(last - first + 1, dtype=bool)
    for a, b in feature_spans(features):
        if a <= last and first <= b:
            keep[max(a, first) - first : min(b, last) - first + 1] = False
    return [(first + int(r0), first + int(r1)) for r0, r1 in _runs(keep) if r1 - r0 + 1 >= MIN_SLAB]


def _part_planes(csdf: CSDF, axis: int) -> np.ndarray:
    info = csdf.meta.get("parts_info")
    if not isinstance(info, list):
        return np.zeros(0)
    ends = []
    for x in info:
        box = x.get("bbox") if isinstance(x, dict) else None
        if box is not None:
            ends += [float(box[0][axis]), float(box[1][axis])]
    return np.unique(np.asarray(ends, dtype=np.float64))


def _part_repeats(csdf: CSDF, axis: int) -> list[tuple[float, list[tuple[float, float]]]]:
    """``(pitch, [(lo, hi), ...])`` (world units) of every row of repeated parts along ``axis``.

    A row: at least :data:`MIN_COUNT` parts of the segmentation (``meta['parts_info']`` boxes)
    with the same size along every axis and the same place across ``axis`` (within
    :data:`BOUND_TOL` voxels), at a constant pitch along it: copies of one part. Two equal
    parts are no row (any symmetric object has mirrored pairs: a table's legs).
    """
    info = csdf.meta.get("parts_info")
    if not isinstance(info, list):
        return []
    boxes = np.array(
        [x["bbox"] for x in info if isinstance(x, dict) and np.shape(x.get("bbox", ())) == (2, 3)],
        dtype=np.float64,
    ).reshape(-1, 2, 3)
    if len(boxes) < MIN_COUNT:
        return []
    tol = BOUND_TOL * csdf.voxel_size
    other = [a for a in range(3) if a != axis]
    # size along all axes and place across the axis: one key per part
    key = np.concatenate([boxes[:, 1] - boxes[:, 0], boxes[:, 0, other]], axis=1)
    close = (np.abs(key[:, None, :] - key[None, :, :]) <= tol).all(axis=2)
    out, used = [], np.zeros(len(boxes), bool)
    for i in range(len(boxes)):
        if used[i]:
            continue
        group = np.flatnonzero(close[i] & ~used)
        used[group] = True
        lo = np.sort(boxes[group, 0, axis])
        if len(lo) < MIN_COUNT:
            continue
        step = np.diff(lo)
        if step.min() > tol and np.ptp(step) <= tol:
            size = float(np.median(key[group, axis]))
            out.append((float(step.mean()), [(float(a), float(a) + size) for a in lo]))
    return out


def _tile(
    axis: str, start: float, period: float, count: int, score: float, reason: str, region
) -> Candidate:
    """A tile candidate whose zone is one ``period`` from ``start`` (world units)."""
    start = float(start)
    return Candidate(
        axis=axis,
        kind="tile",
        zone=(start, start + float(period)),
        period=float(period),
        count=count,
        score=float(np.clip(score, 0, 1)),
        reason=reason,
        region=(float(region[0]), float(region[1])),
    )


def axis_candidates(
    csdf: CSDF,
    axis: str | int,
    *,
    prof: Profile | None = None,
    features: list[Feature] | None = None,
) -> list[Candidate]:
    """Zone candidates along one axis, best first (see :func:`suggest`).

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : {'x', 'y', 'z'} or {0, 1, 2}
        The axis the zones are sought along.
    prof : Profile, optional
        The axis's :func:`~partscale.zones.profile` if the caller has it.
    features : list of Feature, optional
        The axis's local features (:func:`~.features.axis_features` of :func:`calm_runs`) where
        the caller has them.

    Returns
    -------
    list of Candidate
        Best first; none where the axis has neither a repeat nor a constant slab.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> [c.kind for c in zones.axis_candidates(bookcase, "y")][:2]
    ['tile', 'stretch']
    """
    ax = _axis_index(axis)
    p = prof if prof is not None else profile(csdf, ax)
    feats = axis_features(csdf, ax, calm_runs(p)) if features is None else features
    repeats = find_repeats(p)
    out = _repeat_tiles(p, repeats)
    out += _bounded_tiles(p, csdf, repeats)
    out += _part_row_tiles(p, csdf, out)
    # a period is only real where its copies repeat whole elements
    out = [
        w for c in out if (w := _whole(c, p, feats, free="repeats of a" in c.reason)) is not None
    ]
    out += _slab_candidates(p, csdf, feats)
    out.sort(key=lambda c: -c.score)
    return out


def _extent(p: Profile) -> float:
    """The extent along the profile's axis, at least a voxel: what scores and reasons refer to."""
    return max(p.hi - p.lo, p.voxel_size)


def _repeat_tiles(p: Profile, repeats: list[_Repeat]) -> list[Candidate]:
    """A tile candidate per repeat of the whole cross-section (:func:`find_repeats`), planes at
    its best phase; more repeats and more of the extent covered score higher.
    """
    h, extent, name = p.voxel_size, _extent(p), AXES[p.axis]
    out = []
    for r in repeats:
        a, b = r.span
        t = best_phase(p, r.shift, a, b)
        period = r.shift * h
        cover = min(1.0, (b - a) * h / extent)
        # more repeats are stronger evidence: 2 -> 0.67, 3 -> 0.75, 8 -> 0.89
        score = (1 - r.err / MATCH) * (0.5 + 0.5 * cover) * (1 - 1 / (r.count + 1))
        reason = (
            f"{r.count} repeats of a {period:.4g} period ({100 * period / extent:.1f}% of "
            f"the extent), cross-sections match to {r.err:.3f}"
        )
        out.append(
            _tile(name, p.world(t), period, r.count, score, reason, (p.world(a), p.world(b)))
        )
    return out


def _bounded_tiles(p: Profile, csdf: CSDF, repeats: list[_Repeat]) -> list[Candidate]:
    """A tile candidate per run of elements between boards or gaps
    (:func:`find_bounded_repeats`) whose period (or a multiple of it, over it) the whole
    cross-section's ``repeats`` did not find already; weighted by :data:`BOUNDED_WEIGHT`.
    """
    h, extent, name = p.voxel_size, _extent(p), AXES[p.axis]
    out = []
    for br in find_bounded_repeats(p, csdf):
        # a period the full match found already (or a multiple of it, over it) adds nothing
        if any(
            abs(br.period - round(br.period / q.shift) * q.shift) <= BOUND_TOL
            and min(br.elements[-1][1], q.span[1]) > max(br.elements[0][0], q.span[0])
            for q in repeats
        ):
            continue
        a, b = br.elements[0][0], br.elements[-1][1]
        period = br.period * h
        count = len(br.elements)
        cover = min(1.0, (b - a) * h / extent)
        score = BOUNDED_WEIGHT * (1 - br.err / MATCH) * (0.5 + 0.5 * cover) * (1 - 1 / (count + 1))
        what = "boards or dividers" if br.kind == 1 else "gaps or grooves"
        reason = (
            f"{count} elements between {what}, a {period:.4g} period "
            f"({100 * period / extent:.1f}% of the extent), coarse cross-sections match "
            f"{'mirrored ' if br.mirrored else ''}to {br.err:.3f}"
        )
        region = (p.world(a), p.world(b))
        out.append(_tile(name, p.world(br.start), period, count, score, reason, region))
    return out


def _part_row_tiles(p: Profile, csdf: CSDF, tiles: list[Candidate]) -> list[Candidate]:
    """A tile candidate per row of equal parts of the segmentation (:func:`_part_repeats`)
    whose pitch (or a multiple of it, over it) none of ``tiles`` has; planes halfway across
    the gaps around the middle part.
    """
    h, extent, name = p.voxel_size, _extent(p), AXES[p.axis]
    found = [
        (c.period / h, p.index(c.region[0]), p.index(c.region[1]))
        for c in tiles
        if c.period is not None  # every candidate so far is a tile, with a period
    ]
    out = []
    for pitch, parts in _part_repeats(csdf, p.axis):
        step = pitch / h
        a, b = float(p.index(parts[0][0])), float(p.index(parts[-1][1]))
        if any(
            abs(step - max(1, round(step / q)) * q) <= BOUND_TOL and min(b, qb) > max(a, qa)
            for q, qa, qb in found
        ):
            continue
        # the region: from halfway across the gap before the first part to past the last
        gap = step - (parts[0][1] - parts[0][0]) / h
        a0, b0 = max(a - gap / 2, 0.0), min(b + gap / 2, p.n - 1.0)
        # planes halfway across the gaps around the middle part
        count = len(parts)
        t = float(p.index(parts[(count - 1) // 2][0])) - gap / 2
        score = (0.5 + 0.5 * min(1.0, (b - a) * h / extent)) * (1 - 1 / (count + 1))
        reason = (
            f"{count} equal parts of the segmentation at a {pitch:.4g} pitch "
            f"({100 * pitch / extent:.1f}% of the extent)"
        )
        out.append(_tile(name, p.world(t), pitch, count, score, reason, (p.world(a0), p.world(b0))))
    return out


def _slab_candidates(p: Profile, csdf: CSDF, feats: list[Feature]) -> list[Candidate]:
    """A stretch candidate per slab of constant cross-section (:func:`constant_slabs`) at least
    two voxels long, its planes moved to a boundary between parts within a voxel
    (:func:`_at_part_planes`); less drift and more length score higher.
    """
    h, extent, name = p.voxel_size, _extent(p), AXES[p.axis]
    planes = _part_planes(csdf, p.axis)
    out = []
    for first, last, drift, at_feature in constant_slabs(p, csdf, feats):
        s, e, why = _at_part_planes(float(p.world(first)), float(p.world(last)), planes, h)
        if e - s < 2 * h:
            continue
        length = (e - s) / extent
        score = (1 - drift / drift_limit(p)) * min(1.0, 0.3 + length)
        out.append(
            Candidate(
                axis=name,
                kind="stretch",
                zone=(s, e),
                period=None,
                count=None,
                score=float(np.clip(score, 0, 1)),
                reason=(
                    f"constant cross-section over {e - s:.4g} ({100 * length:.1f}% of the extent), "
                    f"drift {drift:.3f}{why}"
                    + (", next to a local feature (a knob, a handle)" if at_feature else "")
                ),
                region=(s, e),
            )
        )
    return out


def _at_part_planes(s: float, e: float, planes: np.ndarray, h: float) -> tuple[float, float, str]:
    """A slab's planes ``s``, ``e`` (world) each moved onto the nearest of ``planes`` (part
    boundaries) within a voxel, where it stays inside the slab; the reason's words if any moved.
    """
    why = ""
    if not planes.size:
        return s, e, why
    # prefer a plane between parts within a voxel, if still inside the slab
    for which, v in (("start", s), ("end", e)):
        j = np.argmin(np.abs(planes - v))
        if abs(planes[j] - v) <= h and s - h <= planes[j] <= e + h:
            if which == "start":
                s = max(s, float(planes[j]))
            else:
                e = min(e, float(planes[j]))
            why = ", planes at part boundaries"
    return s, e, why


@keyword_options
def suggest(
    csdf: CSDF, axis: str | int | None = None, *, progress: ProgressCallback | None = None
) -> list[Candidate]:
    """Zone candidates of ``csdf``, ranked best first.

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : {'x', 'y', 'z'} or None
        One axis, or all three.
    progress : callable(fraction, message), optional
        Called as the work goes on.

    Returns
    -------
    list of Candidate
        ``tile`` (one period of a repeated element, planes in the gaps) and ``stretch`` (a slab
        of constant cross-section); an axis without either gives none.

    Examples
    --------
    >>> from partscale import data, ingest, zones
    >>> table = ingest.load(data.table(), res=64)
    >>> best = zones.suggest(table, "x")[0]
    >>> best.kind, best.axis
    ('stretch', 'x')
    """
    report = resolve(progress)
    axes = [_axis_index(axis)] if axis is not None else [0, 1, 2]
    out: list[Candidate] = []
    for n, ax in enumerate(axes):
        report(n / len(axes), f"axis {AXES[ax]}")
        out += axis_candidates(csdf, ax)
    report(1.0, "done")
    out.sort(key=lambda c: -c.score)
    return out
