"""Fit to size: zones and modes chosen per axis so the object reaches a target extent.

Per axis (see :func:`fit`): where a repeat is found, tile one period (a whole number of voxels,
so the copies are exact shifts of its layers) with the number of copies
that brings the length closest to the target (to shrink, remove whole periods: a zone of them
tiled to its start, 0 copies, so the rest keep their thickness and spacing), and absorb the remainder (less than half a period)
by stretching constant slabs outside that period, so spacing is kept and the length is exact
(a board or panel keeps its thickness: spans and long uniform runs first, then the copies within
a tolerance; the notes say when only a thin slab could take it);
with no repeat, stretch the largest constant slab (a growth beyond doubling it shared by every
constant slab of similar length, each the same fraction), planes a few voxels in from the slab's
ends, where the surface changes least from layer to layer; global scaling only where neither
exists. All positions are on the input
object (recipe coordinates), so the tile and the stretch on one axis are drawn on the original.
Every change is snapped to whole voxels up front, so the result's extent is the target to half
a voxel.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from .._options import keyword_options
from ..csdf import CSDF
from ..edit import (
    CountEdit,
    Edit,
    HelixZone,
    ObliqueZone,
    RadialZone,
    Recipe,
    RotationZone,
    ScrewZone,
    parse_size,
    tile_count,
)
from ..errors import InputError
from ..progress import ProgressCallback, resolve
from .elements import AxisElements, count_zone, element_phrase, find_elements
from .elements import length_text as _fmt
from .features import Feature, axis_features, feature_spans, whole_copies
from .helix import find_helices
from .profile import SCAN_LAYERS, STEP, Profile, calm_runs, from_scan, profile
from .radial import find_radial, radial_zones
from .rotation import Rotation, find_rotations
from .screw import find_screws
from .suggest import (
    AXES,
    SHIFT_STEP,
    Candidate,
    axis_candidates,
    best_phase,
    join_islands,
    join_jump,
    plane_cost,
)

#: A tile's joins between copies may jump this much (voxels, :func:`~.suggest.join_jump`) more
#: than the cleanest join within reach before its planes give way to a cleaner pair: the
#: evaluation's line for a good seam.
JOIN_TOL = 0.1
#: fit --size takes whole elements (of a group that need not be equal) where the change is
#: within this share of one element of a whole number of them.
ELEMENT_TOLERANCE = 0.25
#: A count zone whose planes' cross-sections differ by more than this gets a note.
MATCH_SEAM = 0.15
#: A curved outline: beyond a slab the outline shrinks by more than this many voxels ...
CURVE_VOXELS = 1.5
#: ... and never by more than this many from one layer to the next (no step: a leg, a board),
#: looking at least this many voxels beyond it.
CURVE_STEP = 3
CURVE_REACH = 8
#: Levels (voxel rows across the axis) that must show the curve: a rim, not a speck.
CURVE_LEVELS = 3
#: Largest relative change of the tiled copies accepted instead of stretching a gap inside the
#: repeat (which would make one spacing uneven).
COPY_TOLERANCE = 0.05
#: A slab shrinks to no less than this many voxels.
MIN_SLAB_VOXELS = 2
#: A stretched slab's planes are moved this many voxels in from its ends (the stage blends two
#: voxels either side of a plane; the seam measure looks 2.5 either side).
INSET_VOXELS = 3
#: ...where the slab keeps at least this many voxels between them.
MIN_INSET_VOXELS = 4
#: Planes whose surrounding layers change within this much (mean sdf change per layer near the
#: surface, in voxels) of the calmest place in the slab count as calm as it: far below the
#: half-voxel steps the seam measure reports.
CALM_TOL = 0.05
#: ...among the layer pairs within this many voxels of the plane: the stage blends two voxels
#: either side, and a seam shows in the sdf's step across five layers centred on the plane
#: against the trend one layer beyond them (3.5 voxels, rounded up to whole layer pairs).
CALM_VOXELS = 4
#: How far (voxels) a tile zone's start may move from the detector's to sit at a whole-voxel
#: period's best planes.
PHASE_VOXELS = 1.0
#: Growth beyond this fraction of the largest slab's length is spread over more slabs.
MAX_STRETCH = 1.0
#: A shrink beyond this fraction of the largest slab's length is spread over every slab of
#: comparable length (:data:`SPREAD_FRACTION`), each the same fraction of its length.
MAX_SHRINK = 0.5
#: Slabs shorter than this fraction of the largest one take no share of a growth (or shrink).
SPREAD_FRACTION = 0.5
#: ...nor slabs shorter than this many voxels.
MIN_SPREAD_VOXELS = 10


def _disjoint(c: Candidate, zone: tuple[float, float] | None) -> bool:
    return zone is None or c.zone[1] <= zone[0] or c.zone[0] >= zone[1]


def layer_change(csdf: CSDF, axis: int) -> np.ndarray:
    """(N - 1,) float64: mean ``|sdf[i + 1] - sdf[i]|`` (voxels) over voxels within one voxel of
    the surface on layer ``i`` or ``i + 1`` along ``axis``; 0 where no surface is near.

    A slab of constant occupancy can still change near its ends (the sdf of a leg feels the seat
    a few voxels away): a stretch plane there changes that gradient at the plane, a seam.
    """
    h = csdf.voxel_size
    s = np.moveaxis(csdf.sdf, axis, 0)
    near = np.abs(s) <= h
    either = near[:-1] | near[1:]
    d = np.abs(s[1:].astype(np.float32) - s[:-1].astype(np.float32)) / np.float32(h)
    n = either.sum(axis=(1, 2))
    return np.where(n > 0, (d * either).sum(axis=(1, 2)) / np.maximum(n, 1), 0.0)


def _inset(
    c: Candidate, h: float, change: np.ndarray | None = None, first: float = 0.0
) -> tuple[float, float]:
    """A slab's zone moved at least :data:`INSET_VOXELS` in from each end where it stays long
    enough: planes right at the slab's ends lie on the feature that bounds it (a leg's face), where
    a stretch's blend shows as a seam.

    With ``change`` (:func:`layer_change` along the axis; ``first``: the world coordinate of its
    layer 0), each plane goes on to the whole-voxel position nearest its end, in its half of the
    slab, whose layers within :data:`CALM_VOXELS` either side change least (within
    :data:`CALM_TOL`): a gradient still fading out there (a leg near the seat) is changed by
    the stretch's blend and shows as a seam.
    """
    a, b = c.zone
    n = INSET_VOXELS * h
    if (b - a) - 2 * n < MIN_INSET_VOXELS * h:
        return a, b
    if change is None or change.size == 0:
        return a + n, b - n
    w = CALM_VOXELS
    m = int(np.floor(((b - a) / h - MIN_INSET_VOXELS) / 2))  # steps in, each plane's half
    steps = np.arange(INSET_VOXELS, max(INSET_VOXELS, m) + 1)
    # the layer pairs within w voxels of a plane y: 2 w of them, from ceil(i - w) (i: y's index)
    wins = np.lib.stride_tricks.sliding_window_view(np.pad(change, (0, 2 * w)), 2 * w)

    def cost(y: np.ndarray) -> np.ndarray:  # the largest change among them
        lo = np.ceil((y - first) / h - w - 1e-6).astype(np.int64)
        return wins[np.clip(lo, 0, change.size - 1)].max(axis=1)

    out = []
    for y in (a + steps * h, b - steps * h):
        cy = cost(y)
        out.append(float(y[np.flatnonzero(cy <= cy.min() + CALM_TOL)[0]]))
    return out[0], out[1]


def _fill(need: float, weights: list[float], rooms: list[float]) -> list[float]:
    """Shares of ``need`` in proportion to ``weights``, none above its room: what a full slab
    cannot give goes to the others, again in proportion (sums to less than ``need`` only where
    every room is used).
    """
    give = [0.0] * len(weights)
    free = [i for i, r in enumerate(rooms) if r > 0]
    left = need
    while free and left > 1e-12:
        total = sum(weights[i] for i in free)
        full = [i for i in free if left * weights[i] / total >= rooms[i] - give[i]]
        if not full:
            for i in free:
                give[i] += left * weights[i] / total
            break
        for i in full:
            left -= rooms[i] - give[i]
            give[i] = rooms[i]
        free = [i for i in free if i not in full]
    return give


def _stretch_edits(
    slabs: list[Candidate],
    change: float,
    h: float,
    axis: str,
    layers: tuple[np.ndarray, float] | None = None,
    spread_voxels: int = MIN_SPREAD_VOXELS,
    even_growth: bool = False,
) -> tuple[list[Edit], float]:
    """Stretch edits absorbing ``change`` (whole voxels) over ``slabs``, and what is left.

    Growing, the change is spread over the largest slab and, where it alone would more than
    double (:data:`MAX_STRETCH`), the next largest of those at least :data:`SPREAD_FRACTION` of
    its length and :data:`MIN_SPREAD_VOXELS` long, in proportion to their length: no slab is
    stretched out of shape to absorb it alone, and no thin slab (a leg's width) is stretched at
    all. Shrinking mirrors that: where the largest slab alone would lose more than
    :data:`MAX_SHRINK` of its length, every slab of those sizes gives up the same fraction of
    its length (a sideboard's three bays narrow alike; none is crushed to a sliver), as far as
    each can down to :data:`MIN_SLAB_VOXELS` (lengths here: the slabs' own, not their planes',
    which calm insets may move far in), through the calmest planes where they have the room
    together: one whose planes leave it too little gives what it can, the others the rest in
    the same proportion (:func:`_fill`). Where they cannot, or the shrink is smaller, the
    largest slabs take it, as many as can give it up, each in proportion to what it can give.
    Planes: the calm insets of :func:`_inset` (with ``layers``), else the plain ones, else the
    slabs' ends; shrinking, the first of those needing the fewest slabs. ``layers``:
    :func:`layer_change` and the world coordinate of its layer 0, for :func:`_inset`.
    ``spread_voxels``: the shortest slab that takes a share (0 among thin slabs, where each is a
    feature's thickness: two door panels either side of their knobs grow alike, not one).
    ``even_growth``: a growth goes to every one of ``slabs`` (the caller chose them:
    :func:`_even_growth`), each the same fraction of its length, largest first.
    """
    if not slabs or change == 0:
        return [], change
    options = _plane_options(slabs, h, layers)
    full = [c.zone[1] - c.zone[0] for c in slabs]
    best, even = _even_plan(options, full, change, h, spread_voxels, even_growth)
    options = [sorted(z, key=lambda z: z[0] - z[1]) for z in options]  # largest first
    if best is not None:
        zones, room, n = best
    elif change < 0:
        zones, room, n = _fewest_slabs(options, change, h)
    else:
        zones, room = options[0], []
        n = _growth_count(zones, change, h, spread_voxels)
    chosen = zones[:n]
    weights = even or ([z[1] - z[0] for z in chosen] if change > 0 else room[:n])
    return _shares(chosen, weights, room, change, h, axis)


#: Stretch planes, the room each slab has to shrink (whole voxels), how many of them take it
_Plan = tuple[list[tuple[float, float]], list[float], int]


def _rooms(zones: list[tuple[float, float]], h: float) -> list[float]:
    """What each zone can give up, in whole voxels, down to :data:`MIN_SLAB_VOXELS`."""
    return [max(0.0, round(((z[1] - z[0]) - MIN_SLAB_VOXELS * h) / h) * h) for z in zones]


def _plane_options(
    slabs: list[Candidate], h: float, layers: tuple[np.ndarray, float] | None
) -> list[list[tuple[float, float]]]:
    """Each slab's planes, in the order tried: the calm insets of :func:`_inset` (with
    ``layers``), the plain insets, the slabs' ends.
    """
    options = [[_inset(c, h) for c in slabs], [c.zone for c in slabs]]
    if layers is not None:
        options.insert(0, [_inset(c, h, *layers) for c in slabs])
    return options


def _peers(full: list[float], spread_voxels: int, h: float) -> list[int]:
    """The slabs (indices, largest first) of length comparable to the largest: at least
    :data:`SPREAD_FRACTION` of it and ``spread_voxels`` long.
    """
    return sorted(
        (i for i, f in enumerate(full) if f >= max(spread_voxels * h, SPREAD_FRACTION * max(full))),
        key=lambda i: -full[i],
    )


def _even_plan(
    options: list[list[tuple[float, float]]],
    full: list[float],
    change: float,
    h: float,
    spread_voxels: int,
    even_growth: bool,
) -> tuple[_Plan | None, list[float]]:
    """Where the change is spread evenly: the plan and each chosen slab's share; else
    ``(None, [])``.

    A shrink the largest slab could give only by losing more than :data:`MAX_SHRINK` of its
    length: every peer (:func:`_peers`) gives the same fraction of its full length, through the
    first planes where together they have the room (:func:`_fill`). ``even_growth``: every slab
    grows by the same fraction of its full length (a flight's treads all deepen), largest first.
    """
    peer = _peers(full, spread_voxels, h)
    if change < 0 and len(peer) > 1 and -change > MAX_SHRINK * max(full):
        for zones in options:
            ps = [zones[i] for i in peer]
            give = _fill(-change, [full[i] for i in peer], _rooms(ps, h))
            if -change <= sum(give) + h / 2:
                return (ps, _rooms(ps, h), len(ps)), give
    if change > 0 and even_growth:
        order = sorted(range(len(full)), key=lambda i: -full[i])
        return ([options[0][i] for i in order], [], len(order)), [full[i] for i in order]
    return None, []


def _fewest_slabs(options: list[list[tuple[float, float]]], change: float, h: float) -> _Plan:
    """A shrink (``change < 0``) through the planes that need the fewest slabs (each slab adds
    two seams, which calmer planes do not pay for), the calmest among those (``options``:
    largest slab first in each); every slab's full length where none suffice.
    """
    best: _Plan | None = None
    for zones in options:
        room = _rooms(zones, h)
        n = 1
        while n < len(zones) and -change > sum(room[:n]) + h / 2:
            n += 1
        if -change <= sum(room[:n]) + h / 2 and (best is None or n < best[2]):
            best = (zones, room, n)
    if best is None:
        zones = options[-1]
        return zones, _rooms(zones, h), len(zones)
    return best


def _growth_count(zones: list[tuple[float, float]], change: float, h: float, spread: int) -> int:
    """How many of ``zones`` (largest first) a growth goes to: the largest, and the next ones
    while those so far would more than double (:data:`MAX_STRETCH`) and the next is a peer.
    """
    big = zones[0][1] - zones[0][0]
    n = 1
    while (
        n < len(zones)
        and change > MAX_STRETCH * sum(z[1] - z[0] for z in zones[:n])
        and zones[n][1] - zones[n][0] >= max(spread * h, SPREAD_FRACTION * big)
    ):
        n += 1
    return n


def _shares(
    chosen: list[tuple[float, float]],
    weights: list[float],
    room: list[float],
    change: float,
    h: float,
    axis: str,
) -> tuple[list[Edit], float]:
    """The stretch edits giving each zone of ``chosen`` its share of ``change`` by ``weights``
    (whole voxels; the last takes the rest; a shrink no more than its ``room``), and what is
    left.
    """
    total = sum(weights)
    edits, left = [], change
    n = len(chosen)
    for i, ((a, b), w) in enumerate(zip(chosen, weights, strict=True)):
        share = left if i == n - 1 else round(change * w / total / h) * h
        if change < 0:
            share = max(share, -room[i])
        if abs(share) > h / 2:
            edits.append(Edit(axis, a, b, b + share, "stretch"))
            left -= share
    return edits, left


def _drift_chains(slabs: list[Candidate], p: Profile) -> list[Candidate]:
    """``slabs`` with each chain of neighbouring layers whose step is calm (a calm run split
    where its section drifted: a splayed leg's length) joined into one slab.

    Shrinking the whole run at once keeps a drifting section straight (a splayed leg steeper
    along its whole length); each piece on its own would bend it at every plane between them
    (the stool at 60 % of its height: seven slabs, seam shape 2.85; one chain, 0.61). Slabs
    apart, or next to each other across a step in the section (a rung, a board's face), stay
    apart. Growth keeps the pieces: it goes to the fewest slabs anyway, and a grown chain
    draws the runs a vertical line cuts through a splayed leg out with it.
    """
    out: list[Candidate] = []
    for c in sorted(slabs, key=lambda c: c.zone[0]):
        end = round(float(p.index(out[-1].zone[1]))) if out else -2
        first = round(float(p.index(c.zone[0])))
        if first == end + 1 and p.distance(np.array(end), np.array(first)) < STEP:
            prev = out[-1]
            zone = (prev.zone[0], c.zone[1])
            out[-1] = replace(
                prev,
                zone=zone,
                region=zone,
                score=max(prev.score, c.score),
                reason=f"{prev.reason}; drifting on: {c.reason}",
            )
        else:
            out.append(c)
    return out


def outline_extents(csdf: CSDF, axis: int) -> np.ndarray:
    """(L, N) int64: the solid's extent (voxels, first to last solid voxel) along one of the two
    other axes, per level of the third (L rows: the levels of both), per layer along ``axis``;
    0 where a level of a layer holds no solid. A round column shows as a chord in the levels it
    spans, however large the top above it.
    """
    inside = np.moveaxis(np.asarray(csdf.sdf < 0), axis, 0)  # (N, U, V)
    rows = []
    for across in (1, 2):  # extent along U per level of V, then along V per level of U
        hit = np.moveaxis(inside, across, -1)  # (N, levels, M)
        any_ = hit.any(axis=-1)
        first = np.argmax(hit, axis=-1)
        last = hit.shape[-1] - 1 - np.argmax(hit[..., ::-1], axis=-1)
        rows.append(np.where(any_, last - first + 1, 0).T)  # (levels, N)
    return np.concatenate(rows, axis=0)


def on_curve(extents: np.ndarray, first: float, zone: tuple[float, float], h: float) -> bool:
    """Whether the slab ``zone`` (world units; ``first``: the world coordinate of layer 0)
    sits on a round or curved outline: in at least :data:`CURVE_LEVELS` levels
    (:func:`outline_extents`) the outline across the axis keeps shrinking on both sides without
    a step, by more than :data:`CURVE_VOXELS` within the slab's own length beyond it (at least
    :data:`CURVE_REACH`): a round top's middle, a round column or foot in the slab, not the span
    between a table's legs, which ends at a step. Stretching such a slab flattens the curve
    where it lies (a round top becomes a stadium, a round foot an oval).
    """
    n = extents.shape[1]
    a = round((zone[0] - first) / h)
    b = round((zone[1] - first) / h)
    reach = max(b - a, CURVE_REACH)
    both = np.ones(extents.shape[0], dtype=bool)
    for i, step in ((a, -1), (b, 1)):
        j = i + step * np.arange(reach + 1)
        j = j[(j >= 0) & (j < n)]
        if j.size < 2:
            return False
        run = extents[:, j].astype(np.float64)  # (L, K): from the slab's end outwards
        d = np.diff(run, axis=1)
        curved = (
            (run > 0).all(axis=1)  # the outline goes on (where it ends, the object does)
            & (np.abs(d).max(axis=1) <= CURVE_STEP)
            & (d <= 0).all(axis=1)
            & (run[:, 0] - run.min(axis=1) > CURVE_VOXELS)
        )
        both &= curved
    return int(np.count_nonzero(both)) >= CURVE_LEVELS


def _long(c: Candidate, h: float) -> bool:
    """Whether a slab is at least :data:`MIN_SPREAD_VOXELS` long: a span or a long uniform run,
    not a feature's thickness (a board, a panel, a leg's width).
    """
    return round((c.zone[1] - c.zone[0]) / h) >= MIN_SPREAD_VOXELS


def _outside(slabs: list[Candidate], h: float, tiled: _Tiled | None) -> list[Candidate]:
    """The slabs outside the whole repeat (all of them with no repeat): the first to take a
    remainder, as a gap inside the repeat would make one spacing uneven.

    A slab the repeat's region reaches into counts as outside when it is a period long or more
    (no gap between two copies is: it is a span), and none lies within reach of a tile plane:
    the two blends and the seams' looks (:data:`CALM_VOXELS` either side of each) overlap, and
    the pair shows as one larger step.
    """
    if tiled is None:
        return slabs
    reach = 2 * CALM_VOXELS * h
    return [
        c
        for c in slabs
        if _disjoint(c, tiled.zone)
        and (_disjoint(c, tiled.region) or c.zone[1] - c.zone[0] >= tiled.period - h / 2)
        and all(abs(x - y) >= reach for x in c.zone for y in tiled.zone)
    ]


def _thin_reason(tiled: bool, each: bool = False) -> str:
    """Why a thin slab takes a growth: nothing longer could; ``each``: for several of them,
    with what that changes.
    """
    copies = f" nor the copies (within {100 * COPY_TOLERANCE:.0f}%)" if tiled else ""
    why = f"no slab of {MIN_SPREAD_VOXELS} voxels or more{copies} could take it"
    return f"{why}: a feature's thickness changes in each" if each else why


def _thin_note(c: Candidate, h: float, tiled: bool, alone: bool = True) -> str:
    """The note's tail for a stretch of the thin slab ``c``: which feature changes thickness,
    and, ``alone`` (the only thin slab stretched), why; several share one note of the reason
    (:func:`_to_slabs`).
    """
    n = round((c.zone[1] - c.zone[0]) / h)
    if not alone:
        return f" (a thin slab, {n} voxels)"
    return f": a thin slab ({n} voxels, a feature's thickness changes), as {_thin_reason(tiled)}"


def _voxel_period(
    csdf: CSDF, p: Profile, t: Candidate, features: list[Feature]
) -> tuple[float, float]:
    """A tile candidate's ``(start, period)`` (world) with the period a whole number of voxels.

    Every edit moves content by whole voxels, so copies of a period that is not one are
    resampled and the content after them is moved by a rounded length: the copies' spacing and
    the spacing across the repeat's end drift apart by up to half a voxel. Of the two whole-voxel
    lengths either side of the measured period, the one whose shift carries the repeat onto
    itself best (mean layer distance over the repeat, :meth:`Profile.shifted_distance`); the
    start within :data:`PHASE_VOXELS` of the detector's where :func:`~.suggest.plane_cost` is
    lowest (:func:`~.suggest.best_phase`), among those whose joins cut off the least solid
    (:func:`~.suggest.join_islands`) and jump least (within :data:`JOIN_TOL` voxel of the
    cleanest: :func:`~.suggest.join_jump`, the seam shape the evaluation measures), of those
    that copy whole elements (the axis's local ``features``: :func:`~.features.whole_copies`)
    where any does. Copies of a whole-voxel period are exact shifts of the original's layers.
    """
    assert t.period is not None  # set for a tile
    h = p.voxel_size
    period = t.period / h
    lo, hi = (float(x) for x in p.index(np.array(t.region)))
    t0 = float(p.index(t.zone[0]))
    best = None
    for n in sorted({int(np.floor(period)), int(np.ceil(period))}):
        i = np.arange(int(np.ceil(lo)), int(np.floor(hi - n)) + 1)
        if n < 2 or i.size == 0:
            continue
        err = float(p.shifted_distance(i, float(n)).mean())
        if best is None or err < best[0]:
            best = (err, n)
    if best is None:
        return float(t.zone[0]), float(t.period)
    n = best[1]
    a = max(lo, t0 - PHASE_VOXELS)
    b = min(hi, t0 + PHASE_VOXELS + n)
    if b - a < n:
        return float(t.zone[0]), float(t.period)
    starts = np.arange(a, b - n + 1e-9, SHIFT_STEP)
    whole = np.array([whole_copies(features, float(x), float(n), lo, hi) for x in starts])
    if whole.any():  # (the detector's start copies whole elements: so do some near it)
        starts = starts[whole]
    cut = np.array([join_islands(csdf, p.axis, float(x), float(n)) for x in starts])
    ok = cut <= cut.min()
    ok &= _clean_joins(csdf, p.axis, starts, float(n), ok)
    # the lowest-cost start among those, nearest the detector's
    runs = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    pieces = [(starts[runs[k]], starts[runs[k + 1] - 1]) for k in range(0, len(runs), 2)]
    picks = np.array([best_phase(p, float(n), x0, x1 + n, near=t0) for x0, x1 in pieces])
    # (the middle of a run may fall between the starts measured: measured again)
    cost = np.where(_clean_joins(csdf, p.axis, picks, float(n)), 0.0, np.inf)
    s = picks[int(np.argmin(cost + plane_cost(p, float(n), picks)))]
    return float(p.world(s)), n * h


def _clean_joins(
    csdf: CSDF, axis: int, starts: np.ndarray, period: float, among: np.ndarray | None = None
) -> np.ndarray:
    """(K,) bool: the ``starts`` (of those ``among``) whose join between tile copies jumps
    least (:func:`~.suggest.join_jump`), within :data:`JOIN_TOL` voxel of the least.
    """
    among = np.ones(len(starts), bool) if among is None else among
    jump = np.array(
        [
            join_jump(csdf, axis, float(x), period) if m else np.inf
            for x, m in zip(starts, among, strict=True)
        ]
    )
    return among & (jump <= jump.min() + JOIN_TOL)


@dataclass(frozen=True)
class _Axis:
    """What the remainder's stretches and notes need of one axis: its name (``'x'``...), the
    object's units, the surface's min and max along it (notes give positions from the min), the
    voxel size, :func:`layer_change` along it with the world coordinate of its layer 0 (for :func:`_inset`)
    and the zones of the slabs joined by :func:`_drift_chains` (notes name them).
    """

    name: str
    units: str | None
    lo: float
    hi: float
    h: float
    layers: tuple[np.ndarray, float]
    chained: frozenset[tuple[float, float]] = frozenset()


@dataclass(frozen=True)
class _Tiled:
    """Whole periods tiled (``k > 0`` more) or removed (``-k``) on one axis: the tile edit, the
    repeat's region, the tiled zone, the (whole-voxel) period, the length it adds (whole voxels,
    negative for a removal) and the copies that stand after it (world ``(a, b)``): the tiled
    zone's copies, or, after a removal (0 copies cannot take a length), the longer run of copies
    left beside the removed periods.
    """

    edit: Edit
    k: int
    region: tuple[float, float]
    zone: tuple[float, float]
    period: float
    grow: float
    copies: tuple[float, float]

    @property
    def removed(self) -> bool:
        """Whether periods were removed (0 copies of a zone of them)."""
        return self.k < 0


def _periods(
    csdf: CSDF,
    prof: Profile,
    t: Candidate,
    change: float,
    ax: tuple[str, str | None, float],
    features: list[Feature],
    pieces: bool = False,
) -> tuple[_Tiled, str] | None:
    """Tile whole periods of the repeat ``t`` (the number of copies that brings the length
    closest to ``change``), or remove whole periods (a zone of them tiled to its start, 0 copies,
    so the rest keep their thickness and spacing), and the note; None where no whole period fits
    the change (less than half a period). ``ax``: the axis's name, the object's units and the
    surface's min along it; ``features``: the axis's local features; ``pieces``: the note counts
    pieces of a row, one a period (``fit --add``), not periods.
    """
    assert t.period is not None and t.count is not None  # set for a tile
    name, units, lo = ax
    h = csdf.voxel_size
    start, period = _voxel_period(csdf, prof, t, features)
    k = int(np.floor(change / period + 0.5))
    k = max(k, 1 - t.count)  # cannot remove more periods than the repeat holds
    if k == 0:
        return None
    s = start
    grow = round(k * period / h) * h
    if k > 0:  # one period, 1 + k copies
        e = s + period
        edit = Edit(name, s, e, e + grow, "tile")
        copies = (float(edit.start), float(edit.dest))
    else:  # -k periods removed: 0 copies (tile to the zone's start)
        # whole periods earlier (the same phase: the same plane cost) until it fits in the
        # repeat, then clamped there
        back = max(0, int(np.ceil((s - k * period - t.region[1]) / period - 1e-9)))
        s = max(t.region[0], s - back * period)
        e = s - k * period
        edit = Edit(name, s, e, s, "tile")
        copies = max((t.region[0], s), (e, t.region[1]), key=lambda z: z[1] - z[0])
    if pieces:
        lead = f"{name}: {'add' if k > 0 else 'remove'} {abs(k)} piece(s), a period of "
    else:
        lead = (f"{name}: tile {k} more" if k > 0 else f"{name}: remove {-k}") + " period(s) of "
    note = (
        lead
        + f"{_fmt(period, units)} ({t.reason}), zone {_fmt(s - lo, units)}..{_fmt(e - lo, units)} "
        f"from the {name} min" + ("" if k > 0 else " (tile to its start: 0 copies)")
    )
    return _Tiled(edit, k, t.region, (s, e), period, grow, copies), note


def _element_periods(
    csdf: CSDF,
    prof: Profile,
    found: AxisElements,
    change: float,
    ax_name: str,
    units: str | None,
    lo: float,
) -> tuple[_Tiled, str] | None:
    """Whole elements of the axis's repeat group added (``k > 0``: a zone of one element and
    its separator tiled to ``1 + k`` copies) or removed (a zone of ``-k`` of them tiled to its
    start), ``k`` the whole number of typical elements nearest ``change``, and the note; None
    where the change is not within :data:`ELEMENT_TOLERANCE` of a whole number of elements
    (other than 0) or nothing repeats.
    """
    g = found.best
    if g is None:
        return None
    first = count_zone(csdf, found, 1, prof=prof)
    k = int(np.floor(change / first.length + 0.5))
    k = max(k, 1 - len(g.members))  # one element stays
    # whole elements only where the target is near a whole number of them (a table 30 %
    # deeper is a deeper top, not a third bay of legs)
    if k == 0 or abs(change - k * first.length) > ELEMENT_TOLERANCE * first.length:
        return None
    z = first if k > 0 else count_zone(csdf, found, -k, prof=prof)
    region = (found.elements[g.members[0]].start, found.elements[g.members[-1]].end)
    if k > 0:
        edit = Edit(ax_name, z.start, z.end, z.start + (1 + k) * z.length, "tile")
        grow = k * z.length
        copies = (z.start, z.start + (1 + k) * z.length)
    else:
        edit = Edit(ax_name, z.start, z.end, z.start, "tile")
        grow = -z.length
        copies = max((region[0], z.start), (z.end, region[1]), key=lambda r: r[1] - r[0])
    note = (
        (f"{ax_name}: add {k} element(s)" if k > 0 else f"{ax_name}: remove {-k} element(s)")
        + f" ({element_phrase(found, units)}), zone {_fmt(z.start - lo, units)}..{_fmt(z.end - lo, units)}"
        f" from the {ax_name} min"
        + (f" tiled to {1 + k} copies" if k > 0 else " (tile to its start: 0 copies)")
    )
    return _Tiled(edit, k, region, (z.start, z.end), first.length, grow, copies), note


def _add_steps(
    csdf: CSDF, axis: int, n: int, in_all: bool = False
) -> tuple[list[Edit | ScrewZone | HelixZone | RotationZone], list[str]] | None:
    """``n`` more (or ``-n`` fewer) steps of a flight that repeats diagonally
    (:func:`~partscale.zones.screw.find_screws`) with a part along ``axis``, or, up (y), of a
    spiral stair (:func:`~partscale.zones.helix.find_helices`) where no flight is found, or
    elements of a ring about the vertical (:func:`~partscale.zones.rotation.find_rotations`)
    where neither is; and the note; None where there is none. ``in_all``: ``n`` is the count
    wanted in all (:func:`add_axis`).
    """
    name = AXES[axis]
    units = csdf.meta.get("units")
    for sc in find_screws(csdf):
        if abs(sc.step[axis]) < csdf.voxel_size / 2:
            continue
        n, verb = _stair_change(name, n, sc.count, in_all, "flight")
        note = (
            f"{name}: {verb} step(s) of the flight along {sc.axis} (each {_fmt(sc.going, units)} "
            f"going, {_fmt(sc.rise, units)} rise; {sc.count} steps, {100 * sc.support:.0f}% of "
            f"the surface repeats), cut across {sc.axis} at {_fmt(sc.cut, units)}: what lies "
            "beyond moves by the step(s)"
        )
        return [sc.zone(n)], [note]
    if axis != 1:
        return None
    for hx in find_helices(csdf):
        n, verb = _stair_change(name, n, hx.count, in_all, "spiral stair")
        note = (
            f"{name}: {verb} step(s) of the spiral stair (each turns {hx.angle:.1f} degrees about "
            f"the vertical through {_fmt(hx.center[0], units)}, {_fmt(hx.center[1], units)} and "
            f"rises {_fmt(hx.rise, units)}; {hx.count} steps, {100 * hx.support:.0f}% of the "
            f"surface repeats), cut at the level {_fmt(hx.cut, units)}: what lies above turns "
            "and rises by the step(s)"
        )
        return [hx.zone(n)], [note]
    for rot in find_rotations(csdf):
        n = _change(name, n, rot.count, in_all)
        return _add_turned(rot, name, n, _verb(n), units)
    return None


def _add_periods(
    csdf: CSDF, axis: int, n: int, in_all: bool
) -> tuple[list[Edit | ScrewZone | HelixZone | RotationZone], list[str]] | None:
    """``n`` more (or ``-n`` fewer) periods of a row of pieces too short to be elements each
    (slats, fins, balusters: :data:`~partscale.zones.elements.MIN_SHARE`) where the whole
    cross-section repeats along ``axis`` (the best tile of :func:`axis_candidates`), as
    :func:`fit` tiles whole periods; and the note; None where nothing repeats.
    """
    prof = profile(csdf, axis)
    feats = axis_features(csdf, axis, calm_runs(prof))
    tiles = [c for c in axis_candidates(csdf, axis, prof=prof, features=feats) if c.kind == "tile"]
    if not tiles:
        return None
    t = tiles[0]
    assert t.count is not None and t.period is not None  # set for a tile
    name, units = AXES[axis], csdf.meta.get("units")
    n = _change(name, n, t.count, in_all)
    if -n >= t.count:
        raise InputError(
            f"add {name}: expected to remove at most {t.count - 1} of the {t.count} repeats, "
            f"got {-n}"
        )
    lo = float(csdf.surface_bounds()[0, axis])
    done = _periods(csdf, prof, t, n * t.period, (name, units, lo), feats, pieces=True)
    if done is None:
        return None
    tiled, note = done
    return [tiled.edit], [note]


def _change(name: str, n: int, count: int, in_all: bool) -> int:
    """The elements to add (negative: remove) for ``n`` more, or (``in_all``) ``n`` in all of
    ``count``; refused (one line) where that is no change or leaves none.
    """
    if not in_all:
        return n
    if n < 1:
        raise InputError(f"add {name}: expected at least 1 element in all, got {n}")
    if n == count:
        raise InputError(
            f"add {name}: expected a count other than the current one ({count}), got {n} in all"
        )
    return n - count


def _add_turned(
    rot: Rotation, name: str, n: int, verb: str, units: str | None
) -> tuple[list[Edit | ScrewZone | HelixZone | RotationZone], list[str]]:
    """``n`` more (or ``-n`` fewer) elements of a ring or arc about the vertical, and the note;
    refused (one line) where that would leave none or make the elements overlap.
    """
    what = "ring" if rot.closed else "arc"
    if n < 0 and -n >= rot.count:
        raise InputError(
            f"add {name}: expected to remove at most {rot.count - 1} of the {what}'s "
            f"{rot.count} elements, got {-n}"
        )
    if rot.closed and rot.width >= 180.0 / (rot.count + n):
        raise InputError(
            f"add {name}: expected at most {_most_on_ring(rot) - rot.count} more elements on the "
            f"ring (each is {2 * rot.width:.0f} degrees wide), got {n}"
        )
    spacing = (
        f"spaced evenly every {360 / (rot.count + n):.1f} degrees"
        if rot.closed
        else f"the arc {'continued' if n > 0 else 'cut short'} by {abs(rot.angle):.1f} degrees each"
    )
    note = (
        f"{name}: {verb} element(s) of the {'closed ring' if rot.closed else 'open arc'} about "
        f"the vertical through {_fmt(rot.center[0], units)}, {_fmt(rot.center[1], units)} "
        f"({rot.count} elements {abs(rot.angle):.1f} degrees apart, {100 * rot.support:.0f}% of "
        f"the surface repeats; the hub within {_fmt(rot.hub, units)} stays): "
        f"{rot.count + n} {spacing}"
    )
    return [rot.zone(n)], [note]


def _most_on_ring(rot: Rotation) -> int:
    """Most elements the ring holds without two overlapping."""
    return max(rot.count, math.ceil(180.0 / rot.width) - 1) if rot.width > 0 else 360


def _stair_change(name: str, n: int, count: int, in_all: bool, what: str) -> tuple[int, str]:
    """The steps to add (negative: remove) of a stair of ``count`` (:func:`_change`) and the
    note's verb; refused (one line) where that would remove all of them.
    """
    n = _change(name, n, count, in_all)
    if n < 0 and -n >= count:
        raise InputError(
            f"add {name}: expected to remove at most {count - 1} of the {what}'s {count} "
            f"steps, got {-n}"
        )
    return n, _verb(n)


def _verb(n: int) -> str:
    """``add n`` or ``remove -n``: how a note says a change of ``n`` elements or steps."""
    return f"add {n}" if n > 0 else f"remove {-n}"


def add_axis(
    csdf: CSDF, axis: int, n: int, *, in_all: bool = False
) -> tuple[list[Edit | ScrewZone | HelixZone | RotationZone], list[str]]:
    """Edits adding ``n`` elements of the repeat group along ``axis`` (``-n``: removing).

    Edits (recipe coordinates) adding ``n`` elements (removing ``-n``) of the repeat group
    along ``axis`` (:func:`~partscale.zones.elements.find_elements`), and the note: a zone of
    whole elements and their separators (:func:`~partscale.zones.elements.count_zone`) tiled
    to ``1 + n`` copies, or to its start. With no such group, steps of a flight that repeats
    diagonally with a part along ``axis``, or up, of a spiral stair (:func:`_add_steps`: one more
    step up), or up, of a ring of elements about the vertical (the arms of a star base: one more
    arm, the ring spaced evenly again).

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : int
        0, 1 or 2: the axis to add along.
    n : int
        Elements to add (negative: remove); with ``in_all``, the elements wanted in all.
    in_all : bool
        ``n`` is the count in all (``scale --copies N``): the change is ``n`` less the count of
        whichever repeat is used (the group's elements, the flight's or spiral's steps, the
        ring's elements).

    Returns
    -------
    (list of Edit, ScrewZone, HelixZone or RotationZone, list of str)
        The edits and one line saying what they do.

    Raises
    ------
    InputError
        ``n`` is 0, nothing repeats along the axis, or ``-n`` is not below the group's count.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> edits, why = zones.add_axis(bookcase, 1, 1)
    >>> edits[0].mode, why[0].split(",")[0]
    ('tile', 'y: add 1 element(s) (3 alike elements')
    """
    name = AXES[axis]
    if n == 0 and not in_all:
        raise InputError(f"add {name}: expected a number of elements other than 0, got 0")
    found = find_elements(csdf, axis)
    if found.best is None:
        steps = _add_steps(csdf, axis, n, in_all)
        if steps is None:
            steps = _add_periods(csdf, axis, n, in_all)
        if steps is not None:
            return steps
        raise InputError(
            f"add {name}: expected repeated elements along {name} (seats, doors, shelf rows, "
            f"drawers, steps), found none; resize by length instead (a size, or a zone by hand)"
        )
    n = _change(name, n, len(found.best.members), in_all)
    z = count_zone(csdf, found, 1 if n > 0 else -n)
    units = csdf.meta.get("units")
    lo = found.lo
    where = f"zone {_fmt(z.start - lo, units)}..{_fmt(z.end - lo, units)} from the {name} min"
    if n > 0:
        edit = Edit(name, z.start, z.end, z.start + (1 + n) * z.length, "tile")
        note = (
            f"{name}: add {n} element(s) ({element_phrase(found, units)}), {where} tiled to "
            f"{1 + n} copies"
        )
    else:
        edit = Edit(name, z.start, z.end, z.start, "tile")
        note = f"{name}: remove {-n} element(s) ({element_phrase(found, units)}), {where} cut out"
    if z.seam > MATCH_SEAM:
        note += (
            f"; its planes' cross-sections differ by {z.seam:.2f}, the copies' joins are blended"
        )
    return [edit], [note]


def _to_slabs(
    tier: list[Candidate],
    left: float,
    ax: _Axis,
    tiled: _Tiled | None,
    thin: bool,
    spread: int | None = None,
    even_growth: bool = False,
) -> tuple[list[Edit], list[str], float]:
    """Stretch edits over the slabs ``tier`` taking ``left`` (:func:`_stretch_edits`), a note
    each, and what is left; ``thin``: the notes say a feature's thickness changes.
    ``spread``: the shortest slab taking a share (default: 0 when ``thin``, else
    :data:`MIN_SPREAD_VOXELS`); ``even_growth``: see :func:`_stretch_edits`.
    """
    if spread is None:
        spread = 0 if thin else MIN_SPREAD_VOXELS
    st, left = _stretch_edits(tier, left, ax.h, ax.name, ax.layers, spread, even_growth)
    notes = []
    for ed in st:
        a, b = float(ed.start), float(ed.end)
        # the slab the planes lie in: a chain of drift-split slabs (_drift_chains) is named so
        home = next(c for c in tier if c.zone[0] - ax.h / 2 <= a and b <= c.zone[1] + ax.h / 2)
        what = "the drifting run of slabs" if home.zone in ax.chained else "the constant slab"
        notes.append(
            f"{ax.name}: stretch {what} {_fmt(a - ax.lo, ax.units)}.."
            f"{_fmt(b - ax.lo, ax.units)} from the {ax.name} min by "
            f"{_fmt(float(ed.dest) - b, ax.units)}"
            + (" (the remainder after whole periods)" if tiled else "")
            + (_thin_note(home, ax.h, tiled is not None, alone=len(st) == 1) if thin else "")
        )
    if thin and len(st) > 1 and not even_growth:  # (an even growth's own first note says it)
        notes.insert(
            0,
            f"{ax.name}: {len(st)} thin slabs take it, as "
            f"{_thin_reason(tiled is not None, each=True)}",
        )
    return st, notes, left


def _to_long_outside(
    slabs: list[Candidate], left: float, ax: _Axis, tiled: _Tiled | None
) -> tuple[list[Edit], list[str], float]:
    """The remainder to slabs at least :data:`MIN_SPREAD_VOXELS` long (:func:`_long`) outside
    the repeat (:func:`_outside`): the first choice, as a feature keeps its thickness and the
    copies their spacing.
    """
    outside = _outside(slabs, ax.h, tiled)
    tier = [c for c in outside if _long(c, ax.h)]
    shared = _even_growth(tier, outside, left, ax, tiled, thin=False)
    return shared or _to_slabs(tier, left, ax, tiled, thin=False)


def _even_growth(
    tier: list[Candidate],
    slabs: list[Candidate],
    left: float,
    ax: _Axis,
    tiled: _Tiled | None,
    thin: bool,
) -> tuple[list[Edit], list[str], float] | None:
    """Where the largest slab of ``tier`` would more than double taking ``left``: the slabs of
    ``slabs`` of comparable length share the growth, each the same fraction of its length
    (:func:`_to_slabs`), with a note first; else None.

    Comparable: at least :data:`SPREAD_FRACTION` of that largest, whatever their voxel count (a
    flight's treads at 128 are under :data:`MIN_SPREAD_VOXELS`). Not a thin slab at either end
    of the object (its outer part: a leg, a side panel), nor the pieces of a drifting run (a
    splayed leg: every plane through it bends it; growth goes to the fewest of those).
    """
    big = max((c.zone[1] - c.zone[0] for c in tier), default=0.0)
    if not tier or left <= MAX_STRETCH * big:
        return None
    ends = (ax.lo + 2 * ax.h, ax.hi - 2 * ax.h)  # a slab's zone starts past the end's layer
    peers = [
        c
        for c in slabs
        if c.zone[1] - c.zone[0] >= SPREAD_FRACTION * big
        and (_long(c, ax.h) or ends[0] < c.zone[0] < c.zone[1] < ends[1])
        and not any(a - ax.h / 2 <= c.zone[0] and c.zone[1] <= b + ax.h / 2 for a, b in ax.chained)
    ]
    if len(peers) < 2:
        return None
    st, notes, rest = _to_slabs(peers, left, ax, tiled, thin=thin, spread=0, even_growth=True)
    if len(st) > 1:
        notes.insert(
            0,
            f"{ax.name}: {len(st)} {'thin ' if thin else ''}constant slabs of comparable length "
            f"share the growth, each the same fraction of its length (the largest alone would "
            f"more than double"
            + (f"; {_thin_reason(tiled is not None, each=True)})" if thin else ")"),
        )
    return st, notes, rest


def _copies_within(left: float, tiled: _Tiled) -> bool:
    """Whether the copies take the remainder (:func:`_to_copies`) before any slab inside the
    repeat or any thin slab: their length changes within :data:`COPY_TOLERANCE` (one uneven gap
    is worse than copies a little off).
    """
    a, b = tiled.copies
    return abs(left) <= COPY_TOLERANCE * (b - a)


def _to_long_inside(
    slabs: list[Candidate], left: float, ax: _Axis, tiled: _Tiled
) -> tuple[list[Edit], list[str], float]:
    """The remainder to long slabs (:func:`_long`) inside the repeat's region but off the tiled
    zone (one spacing gets uneven): after the copies within :data:`COPY_TOLERANCE`.
    """
    outside = _outside(slabs, ax.h, tiled)
    tier = [c for c in slabs if _disjoint(c, tiled.zone) and c not in outside and _long(c, ax.h)]
    return _to_slabs(tier, left, ax, tiled, thin=False)


def _to_thin(
    slabs: list[Candidate], left: float, ax: _Axis, tiled: _Tiled | None
) -> tuple[list[Edit], list[str], float]:
    """The remainder to thin slabs outside the repeat (:func:`_outside`; shorter than
    :data:`MIN_SPREAD_VOXELS`: a feature's thickness), last of the slabs; the notes say which
    feature changes (:func:`_thin_note`). A thin slab inside the repeat never takes it: a feature
    of one copy and one spacing would change. A growth the largest would take only by more than
    doubling is shared by those of comparable length, each the same fraction (:func:`_even_growth`:
    a flight's treads all deepen), else it goes to the fewest. Nor do thin slabs take a growth
    that would more than double one of them (:data:`MAX_STRETCH`): nothing is taken then.
    """
    tier = [c for c in _outside(slabs, ax.h, tiled) if not _long(c, ax.h)]

    def doubles(st: list[Edit]) -> bool:
        # a growth that more than doubles a feature's thickness (a stair's tread, a ring of a
        # post) makes a lump of it: the copies or global scaling do better
        return any(
            float(e.dest) - float(e.end) > MAX_STRETCH * (float(e.end) - float(e.start)) + ax.h / 2
            for e in st
        )

    # a flight of thin treads with no long slab: all of them deepen alike where they can
    shared = _even_growth(tier, tier, left, ax, tiled, thin=True)
    if shared is not None and not doubles(shared[0]):
        return shared
    st, notes, rest = _to_slabs(tier, left, ax, tiled, thin=True)
    if doubles(st):
        return [], [], left
    return st, notes, rest


def _to_copies(
    edits: list[Edit], left: float, ax: _Axis, tiled: _Tiled, within: bool
) -> tuple[list[Edit], str] | None:
    """The copies absorb what no slab took (their spacing changes): the tile edit's copies get
    ``left`` more length, or, where periods were removed, the copies left beside them are
    stretched by it (None where that would leave them under :data:`MIN_SLAB_VOXELS`: global
    scaling is left). ``edits``: the tile edit first, then the stretches made; ``within``: taken
    within :data:`COPY_TOLERANCE` before the slabs inside the repeat and the thin ones.
    """
    it = "the rest" if len(edits) > 1 else "it"
    if tiled.removed:
        a, b = tiled.copies
        if b - a + min(left, 0.0) < MIN_SLAB_VOXELS * ax.h:
            return None
        note = (
            f"{ax.name}: no constant slab outside the tiled zone could take {it}: the "
            f"copies left {_fmt(a - ax.lo, ax.units)}..{_fmt(b - ax.lo, ax.units)} from the "
            f"{ax.name} min absorb {_fmt(left, ax.units)} (each {100 * left / (b - a):+.1f}%)"
        )
        return [*edits, Edit(ax.name, a, b, b + left, "stretch")], note
    t0 = edits[0]
    dest = float(t0.dest) + left
    n = tile_count(float(t0.end) - float(t0.start), dest - float(t0.start))
    pct = 100 * left / (dest - float(t0.start))
    note = (
        f"{ax.name}: no constant slab "
        + (
            f"of {MIN_SPREAD_VOXELS} voxels or more outside the tiled zone could take "
            f"{it} (a thinner one is a feature's thickness)"
            if within
            else f"outside the tiled zone could take {it}"
        )
        + f": its {n} copies absorb {_fmt(left, ax.units)} (each {pct:+.1f}%)"
    )
    return [Edit(ax.name, t0.start, t0.end, dest, "tile"), *edits[1:]], note


def fit_axis(
    csdf: CSDF, axis: int, target: float, *, allow_deform: bool = False
) -> tuple[list[Edit], list[str]]:
    """Edits (recipe coordinates) bringing the extent along ``axis`` to ``target``, and why.

    Whole periods first (:func:`_periods`; with no equal period, whole elements of a repeat
    group: :func:`_element_periods`), then what they leave (less than half a period, or the
    whole change with no repeat) in this order until it is taken: long slabs outside the
    repeat, the copies within :data:`COPY_TOLERANCE`, long slabs inside the repeat, the copies
    whatever their change. Slabs on a round or curved outline (:func:`on_curve`) take nothing.
    What is left then is refused (:class:`~partscale.errors.InputError`, naming the
    alternatives) unless ``allow_deform``: then thin slabs take it (a feature's thickness
    changes; a note says so) and global scaling is the last resort.
    A shrink takes each chain of drift-split slabs as one (:func:`_drift_chains`). The slabs are
    cut around the axis's local features (knobs, handles, motifs); a note says where the
    stretches lie beside them (:func:`_feature_note`).

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : int
        0, 1 or 2: the axis fitted.
    target : float
        The extent wanted along the axis (object units).
    allow_deform : bool
        Let thin slabs or global scaling take what nothing else can, instead of refusing.

    Returns
    -------
    (list of Edit, list of str)
        The edits (recipe coordinates) and one line per choice.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> edits, why = zones.fit_axis(bookcase, 1, 1.5)  # 30 cm taller: one more shelf row
    >>> [(e.mode, round(e.dest - e.end, 3)) for e in edits]
    [('tile', 0.3)]
    """
    name, units, lo, hi, change = _axis_change(csdf, axis, target)
    if change == 0:
        return [], [f"{name}: kept ({_fmt(hi - lo, units)}, target within half a voxel)"]
    prof = profile(csdf, axis)
    feats = axis_features(csdf, axis, calm_runs(prof))
    edits, why = _fit_axis(csdf, axis, target, prof, feats, allow_deform)
    return edits, why + _feature_note(edits, feats, prof, (name, units, lo)) + _snap_note(
        name, units, change, target - (hi - lo), csdf.voxel_size
    )


def _snap_note(name: str, units: str | None, change: float, asked: float, h: float) -> list[str]:
    """The line saying the change along an axis was snapped to whole voxels (``h``), where it
    differs from the one ``asked``: a size asked is not quietly met only to half a voxel.
    """
    if abs(change - asked) <= 1e-6 * h:
        return []
    return [
        f"{name}: {'+' if change > 0 else ''}{_fmt(change, units)} of the "
        f"{'+' if asked > 0 else ''}{_fmt(asked, units)} asked: edits move whole voxels of "
        f"{_fmt(h, units)}"
    ]


def _axis_change(
    csdf: CSDF, axis: int, target: float
) -> tuple[str, str | None, float, float, float]:
    """Where :func:`fit_axis` starts from: the axis's name, the object's units, the surface's
    extent ``(lo, hi)`` along ``axis``, and the change reaching ``target``, in whole voxels
    (every edit moves content by voxels).
    """
    sb = csdf.surface_bounds()
    lo, hi = float(sb[0, axis]), float(sb[1, axis])
    h = csdf.voxel_size
    return AXES[axis], csdf.meta.get("units"), lo, hi, round((target - (hi - lo)) / h) * h


def _feature_note(
    edits: list[Edit], features: list[Feature], p: Profile, ax: tuple[str, str | None, float]
) -> list[str]:
    """A line where ``edits`` stretch along an axis (``ax``: its name, the object's units, the
    surface's min along it) with local ``features`` (on its profile ``p``): where the stretched
    zones lie and the features they keep clear of (positions from the axis's min, as the other
    notes give them); and a line for those a stretched zone holds all the same (the copies
    absorbing a remainder, global scaling: stretched out of shape).
    """
    name, units, lo = ax
    zones = [(float(e.start), float(e.end)) for e in edits if e.mode in ("stretch", "global")]
    if not zones or not features:
        return []
    h = p.voxel_size

    def where(xs: list[tuple[float, float]]) -> str:
        shown = ", ".join(f"{_fmt(a - lo, units)}..{_fmt(b - lo, units)}" for a, b in xs[:6])
        return shown + (f" and {len(xs) - 6} more" if len(xs) > 6 else "")

    # a feature's extent: half a layer past its first and last
    spans = [
        (float(p.world(a)) - h / 2, float(p.world(b)) + h / 2) for a, b in feature_spans(features)
    ]
    held = [x for x in spans if any(x[0] < z1 and z0 < x[1] for z0, z1 in zones)]
    clear = [x for x in spans if x not in held]
    what = "local feature{} (knobs, handles, hinges, colour motifs)"
    lines = []
    if clear:
        lines.append(
            f"{name}: stretched zone{'s' if len(zones) > 1 else ''} {where(zones)} from the "
            f"{name} min placed to keep clear of {len(clear)} "
            f"{what.format('s' if len(clear) > 1 else '')} at {where(clear)}, which keep "
            f"their shape"
        )
    if held:
        lines.append(
            f"{name}: {len(held)} {what.format('s' if len(held) > 1 else '')} at "
            f"{where(held)} from the {name} min lie in a stretched zone, stretched out of "
            f"shape with it"
        )
    return lines


def _fit_axis(
    csdf: CSDF,
    axis: int,
    target: float,
    prof: Profile,
    feats: list[Feature],
    allow_deform: bool = False,
) -> tuple[list[Edit], list[str]]:
    """:func:`fit_axis` on the axis's profile ``prof`` and local features ``feats``, but the
    features' note: whole periods (:func:`_whole_periods`), then the remainder absorbed by
    slabs or the copies (:func:`_absorb`), else refused or scaled globally
    (:func:`_last_resort`).
    """
    name, units, lo, hi, change = _axis_change(csdf, axis, target)
    h = csdf.voxel_size
    cands = axis_candidates(csdf, axis, prof=prof, features=feats)
    scan = from_scan(csdf)
    # a completed scan's repeats are taken only when asked for (add_axis): its noise makes
    # elements of a plain body (a bin's, a table's top)
    tiles = [] if scan else [c for c in cands if c.kind == "tile"]
    slabs = [c for c in cands if c.kind == "stretch"]
    # a shrink is spread over many slabs: a drifting run shrinks whole, not at each piece
    chains = _drift_chains(slabs, prof)
    if cands:
        _check_shrinkable(tiles, chains, target, hi - lo, h, (name, units))
    tiled, edits, why = (
        (None, [], []) if scan else _whole_periods(csdf, axis, prof, tiles, change, feats)
    )
    left = change if tiled is None else change - tiled.grow
    if abs(left) <= h / 2:
        return edits, why
    first = float(csdf.axis_coords(axis)[0])
    layers = (layer_change(csdf, axis), first)
    ax = _Axis(name, units, lo, hi, h, layers, frozenset(c.zone for c in chains if c not in slabs))
    slabs, curved = _takers(csdf, axis, slabs, chains, left, allow_deform)
    done, left = _absorb(slabs, left, ax, tiled, allow_deform, edits, why)
    if done is not None:
        return done
    if not allow_deform:
        raise InputError(_refusal(name, target, left, units, slabs, curved, h, tiled is not None))
    return _last_resort(ax, change, slabs)


def _check_shrinkable(
    tiles: list[Candidate],
    chains: list[Candidate],
    target: float,
    extent: float,
    h: float,
    ax: tuple[str, str | None],
) -> None:
    """Refuse a ``target`` below what cannot shrink: the extent less every slab (``chains``)
    down to its minimum, or the removable periods of the best tile if those give more.
    """
    name, units = ax
    shrinkable = sum(max(0.0, c.zone[1] - c.zone[0] - MIN_SLAB_VOXELS * h) for c in chains)
    if tiles:
        assert tiles[0].count is not None and tiles[0].period is not None  # set for a tile
        shrinkable = max(shrinkable, (tiles[0].count - 1) * tiles[0].period)
    if target < extent - shrinkable - h / 2:
        raise InputError(
            f"size {name}: expected at least {_fmt(extent - shrinkable, units)} (the rigid "
            f"parts' total: what no slab or repeat can give up), got {_fmt(target, units)}"
        )


def _whole_periods(
    csdf: CSDF,
    axis: int,
    prof: Profile,
    tiles: list[Candidate],
    change: float,
    feats: list[Feature],
) -> tuple[_Tiled | None, list[Edit], list[str]]:
    """Whole periods of the best tile (:func:`_periods`), or with no equal period whole
    elements of a repeat that need not be equal (:func:`_element_periods`: mirrored doors,
    cushions of unequal width): what was tiled (None: nothing), its edit and note.
    """
    name, units = AXES[axis], csdf.meta.get("units")
    lo = float(csdf.surface_bounds()[0, axis])
    if tiles:
        done = _periods(csdf, prof, tiles[0], change, (name, units, lo), feats)
    else:
        elements = find_elements(csdf, axis, prof=prof)
        done = _element_periods(csdf, prof, elements, change, name, units, lo)
    if done is None:
        return None, [], []
    tiled, note = done
    return tiled, [tiled.edit], [note]


def _takers(
    csdf: CSDF,
    axis: int,
    slabs: list[Candidate],
    chains: list[Candidate],
    left: float,
    allow_deform: bool,
) -> tuple[list[Candidate], list[Candidate]]:
    """The slabs that may take the remainder ``left``, and those left out as curved.

    A shrink takes each drift chain whole (``chains``). Without ``allow_deform`` a growth
    leaves out long slabs on a round or curved outline (:func:`on_curve`): growth there
    flattens it (a round top becomes a stadium).
    """
    if left < 0:
        slabs = chains
    curved: list[Candidate] = []
    if not allow_deform and left > 0:
        h = csdf.voxel_size
        first = float(csdf.axis_coords(axis)[0])
        ext = outline_extents(csdf, axis)
        curved = [c for c in slabs if on_curve(ext, first, c.zone, h)]
        slabs = [c for c in slabs if c not in curved or not _long(c, h)]
    return slabs, curved


def _absorb(
    slabs: list[Candidate],
    left: float,
    ax: _Axis,
    tiled: _Tiled | None,
    allow_deform: bool,
    edits: list[Edit],
    why: list[str],
) -> tuple[tuple[list[Edit], list[str]] | None, float]:
    """The remainder ``left`` taken in order until it is gone: long slabs outside the repeat,
    long slabs inside it (unless the copies take it within :data:`COPY_TOLERANCE`), thin slabs
    (``allow_deform``), the copies. Returns the edits and notes (after ``edits``, ``why``) where
    it was all taken, else None; and what is left.
    """
    h = ax.h
    st, notes, left = _to_long_outside(slabs, left, ax, tiled)
    edits, why = edits + st, why + notes
    if abs(left) <= h / 2:
        return (edits, why), left
    within = tiled is not None and _copies_within(left, tiled)
    if tiled is not None and not within:
        st, notes, left = _to_long_inside(slabs, left, ax, tiled)
        edits, why = edits + st, why + notes
        if abs(left) <= h / 2:
            return (edits, why), left
    if not within and allow_deform:
        st, notes, left = _to_thin(slabs, left, ax, tiled)
        edits, why = edits + st, why + notes
        if abs(left) <= h / 2:
            return (edits, why), left
    taken = None if tiled is None else _to_copies(edits, left, ax, tiled, within)
    if taken is not None:
        return (taken[0], [*why, taken[1]]), left
    return None, left


def _last_resort(ax: _Axis, change: float, slabs: list[Candidate]) -> tuple[list[Edit], list[str]]:
    """Global scaling of the whole ``change`` along the axis, with the note saying why."""
    thin = (
        " (thin slabs would more than double)"
        if change > 0 and any(not _long(c, ax.h) for c in slabs)
        else ""
    )
    return [Edit(ax.name, ax.lo, ax.hi, ax.hi + change, "global")], [
        f"{ax.name}: GLOBAL scaling (last resort): no repeated element and no slab of "
        f"constant cross-section along {ax.name} could take {_fmt(change, ax.units)}{thin}"
    ]


def _refusal(
    name: str,
    target: float,
    left: float,
    units: str | None,
    slabs: list[Candidate],
    curved: list[Candidate],
    h: float,
    tiled: bool,
) -> str:
    """The one line refusing a fit that only a deformation would reach, with the alternatives."""
    if curved:
        why = "the outline is round or curved there (stretching flattens it)"
    elif any(not _long(c, h) for c in slabs):
        why = (
            f"only slabs thinner than {MIN_SPREAD_VOXELS} voxels could take it (a feature's "
            "thickness would change)"
        )
    else:
        why = "no slab of constant cross-section could take it"
    after = " after whole elements" if tiled else ""
    return (
        f"size {name}: expected a part-aware way to reach {_fmt(target, units)}, got none: "
        f"{_fmt(abs(left), units)} to {'grow' if left > 0 else 'shrink'}{after} and {why}; "
        f"alternatives: allow_deform (CLI --allow-deform: thin slabs, else global scaling along "
        f"{name}), scale --mode global along {name}, a zone of your own (scale --zone), or "
        f"whole elements (fit --add)"
    )


@keyword_options
def fit(
    csdf: CSDF,
    size: Sequence[str | float] | None = None,
    *,
    add: Mapping[str, int] | None = None,
    allow_deform: bool = False,
    progress: ProgressCallback | None = None,
) -> tuple[Recipe, list[str]]:
    """The recipe that resizes ``csdf`` to ``size`` along x, y, z, and why it was chosen.

    Parameters
    ----------
    csdf : CSDF
        The object.
    size : 3 specs, optional
        Per axis: ``'='`` (unchanged), an absolute length (``2.1``, ``'210cm'``,
        ``'2100mm'``; bare numbers in object units), a change (``'+20cm'``, ``'-5cm'``) or a
        percentage of the current extent (``'120%'``). Default: unchanged.
    add : mapping of axis to int, optional
        Elements to add (``{'x': 1}``: one more seat) or remove (``{'x': -1}``) on an axis
        (:func:`add_axis`); that axis's size must then be ``'='``.
    allow_deform : bool
        Where no zone reaches a size without deforming what should keep its shape (a round
        outline, only thin slabs), stretch thin slabs or scale globally (with a note) instead
        of refusing.

    Returns
    -------
    (Recipe, list of str)
        The recipe (positions on ``csdf``, world units; apply with
        :func:`partscale.edit.apply_recipe`) and one line per choice made. An axis already
        within half a voxel of its target gets no edit.

    Raises
    ------
    InputError
        A size that is not positive, unknown units, a target below what the rigid parts
        alone measure, a target only a deformation reaches (unless ``allow_deform``), an axis
        given both a size and a count, or a count no repeat group allows.

    Examples
    --------
    >>> from partscale import data, edit, ingest, zones
    >>> table = ingest.load(data.table(), res=64)
    >>> recipe, why = zones.fit(table, ["3m", "=", "120%"])
    >>> longer = edit.apply_recipe(table, recipe)
    >>> round(float(longer.surface_bounds()[1, 0] - longer.surface_bounds()[0, 0]), 1)
    3.0
    """
    report = resolve(progress)
    add = _check_add(add)
    size, targets = _targets(csdf, size)
    edits: list[Edit | RadialZone | ScrewZone | HelixZone | RotationZone] = []
    why: list[str] = []
    radial = _radial_fit(csdf, targets, add, allow_deform)
    if radial is not None:
        edits.append(radial[0])
        why.append(radial[1])
    moved: set[int] = set()  # axes a count edit's diagonal steps move too
    # counts first: the steps of a flight move along two axes
    for k, a in enumerate(sorted(range(3), key=lambda a: AXES[a] not in add)):
        report(k / 3, f"axis {AXES[a]}")
        if radial is not None and a != 1:
            continue  # x and z: the radial zone
        if a in moved:
            _check_unchanged(csdf, a, targets[a], "size", "the steps added move along", size[a])
            continue
        if AXES[a] in add:
            _check_unchanged(csdf, a, targets[a], "add", "the count decides", size[a])
            e, w = add_axis(csdf, a, add[AXES[a]])
            moved |= _moved_axes(e, a)
        else:
            planar, w = _size_axis(csdf, a, targets[a], allow_deform)
            e = list(planar)
        edits += e
        why += w
    report(1.0, "done")
    if not edits:
        raise InputError("size: expected a change on some axis, got the current size")
    planar = [e for e in edits if isinstance(e, Edit)]
    return Recipe(tuple(edits)), why + _off_square(csdf, planar) + _scan_note(csdf, size)


def _scan_note(csdf: CSDF, size: Sequence[str | float]) -> list[str]:
    """The line saying how a completed scan's sizes were fitted (where one was asked for)."""
    if not from_scan(csdf) or all(str(v).strip() == "=" for v in size):
        return []
    return [
        f"a completed scan: its cross-sections compared over {SCAN_LAYERS} layers (its surface "
        "carries the sensor's noise), sizes reached by stretching, its elements repeated only "
        "when asked for (--add)"
    ]


def _targets(
    csdf: CSDF, size: Sequence[str | float] | None
) -> tuple[Sequence[str | float], list[float]]:
    """``size`` (three ``'='`` where None) checked, and the extent it asks for per axis
    (:func:`partscale.edit.parse_size` on the current extent).
    """
    if size is None:
        size = ["="] * 3
    if isinstance(size, str) or len(size) != 3:
        raise InputError(f"size: expected three values (x y z), got {size!r}")
    units = csdf.meta.get("units")
    sb = csdf.surface_bounds()
    targets = [
        parse_size(v, extent=float(sb[1, a] - sb[0, a]), units=units, what=f"size {AXES[a]}")
        for a, v in enumerate(size)
    ]
    return size, targets


def _check_unchanged(
    csdf: CSDF, axis: int, target: float, what: str, because: str, given: str | float
) -> None:
    """Refuse a size along ``axis`` other than the current extent (within half a voxel): a
    count decides it, or steps added along another axis move along it too.
    """
    sb = csdf.surface_bounds()
    if abs(target - float(sb[1, axis] - sb[0, axis])) <= csdf.voxel_size / 2:
        return
    name = AXES[axis]
    if what == "size":
        raise InputError(f"size {name}: expected = ({because} {name} too), got {given}")
    raise InputError(
        f"add {name}: expected the size along {name} unchanged (=), as {because} it, "
        f"got size {name} {given}"
    )


def _moved_axes(edits: Sequence[object], axis: int) -> set[int]:
    """The axes other than ``axis`` that count edits' steps move along: a flight's diagonal
    step, a helix's or a ring's turn (x and z).
    """
    return {
        b
        for z in edits
        if isinstance(z, ScrewZone | HelixZone | RotationZone)
        for b in range(3)
        if b != axis and (isinstance(z, HelixZone | RotationZone) or abs(z.step[b]) > 0)
    }


def _size_axis(
    csdf: CSDF, axis: int, target: float, allow_deform: bool
) -> tuple[list[Edit], list[str]]:
    """:func:`fit_axis`, a refusal on an object whose walls run off the axes naming that cure
    too.
    """
    try:
        planar, why = fit_axis(csdf, axis, target, allow_deform=allow_deform)
        return list(planar), why
    except InputError as exc:
        turn = _off_square(csdf, [Edit(AXES[axis], 0.0, 1.0, 1.0)])
        if not turn or "part-aware" not in str(exc):
            raise
        raise InputError(f"{exc}; {turn[0]}") from None


def resolve_counts(csdf: CSDF, recipe: Recipe) -> tuple[Recipe, list[str]]:
    """Resolve a recipe's counts on an object into the zone edits that make them.

    Each count (:class:`~partscale.edit.CountEdit`: ``{"axis": "x", "copies": "+1"}``) is
    replaced by the zone edits :func:`add_axis` makes on ``csdf`` (whole elements, or a flight's
    steps); other edits stay as they are.

    Parameters
    ----------
    csdf : CSDF
        The object the recipe applies to.
    recipe : Recipe

    Returns
    -------
    (Recipe, list of str)
        The recipe with zone edits only, and a note per count resolved.

    Raises
    ------
    InputError
        A count no repeat along its axis allows (as :func:`add_axis`).

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.edit import Recipe
    >>> from partscale.zones import resolve_counts
    >>> boards = [((0, y, 0), (0.6, y + 0.02, 0.3)) for y in (0.0, 0.3, 0.6, 0.9)]
    >>> boards += [((0, 0, 0), (0.02, 0.92, 0.3)), ((0.58, 0, 0), (0.6, 0.92, 0.3))]
    >>> shelf = shapes.grid(lambda p: shapes.boxes_sdf(p, boards), [(0, 0, 0), (0.6, 0.92, 0.3)], voxel_size=0.02)
    >>> done, notes = resolve_counts(shelf, Recipe.parse({"edits": [{"axis": "y", "copies": "+1"}]}))
    >>> done.edits[0].mode
    'tile'
    """
    out: list[
        Edit | RadialZone | ScrewZone | HelixZone | RotationZone | ObliqueZone | CountEdit
    ] = []
    notes: list[str] = []
    for e in recipe.edits:
        if isinstance(e, CountEdit):
            made, why = add_axis(csdf, AXES.index(e.axis), e.copies)
            out += made
            notes += why
        else:
            out.append(e)
    return Recipe(tuple(out)), notes


def _radial_fit(
    csdf: CSDF, targets: list[float], add: dict[str, int], allow_deform: bool
) -> tuple[RadialZone, str] | None:
    """Where x and z grow (or shrink) by the same factor and a zone across x or z cannot take
    it part-aware (a round or polygonal outline in plan), the radial zone that can: the
    longest annulus of constant radial section (:func:`~partscale.zones.radial.radial_zones`)
    about the vertical, grown so the outline scales by the factor; else None.
    """
    sb = csdf.surface_bounds()
    ext = sb[1] - sb[0]
    h = csdf.voxel_size
    fx, fz = targets[0] / ext[0], targets[2] / ext[2]
    if "x" in add or "z" in add or abs(fx - 1) * ext[0] <= h / 2:
        return None
    if abs(fx - fz) * max(ext[0], ext[2]) > h:  # not the same factor, within a voxel
        return None
    try:
        for a in (0, 2):
            fit_axis(csdf, a, targets[a], allow_deform=allow_deform)
        return None  # planes across x and z take it
    except InputError:
        pass
    frame = find_radial(csdf, "y")
    zones = [] if frame is None else radial_zones(csdf, frame)
    if frame is None or not zones:
        return None
    r0, r1 = zones[0]
    grow = (fx - 1) * frame.radius
    if r1 + grow <= r0 + h:
        return None
    units = csdf.meta.get("units")
    shape = "round" if frame.sides == 0 else f"a regular {frame.sides}-sided polygon"
    note = (
        f"x, z: radial zone {_fmt(r0, units)}..{_fmt(r1, units)} from the vertical axis through "
        f"the centre (the outline in plan is {shape}) grows by {_fmt(grow, units)}: what lies "
        f"inside it (a column, a foot) and outside it (a rim) keeps its size"
    )
    return frame.zone(r0, r1, r1 + grow), note


def _check_add(add: Mapping[str, int] | None) -> dict[str, int]:
    """``add`` validated: axis names to non-zero whole numbers."""
    if add is None:
        return {}
    if not isinstance(add, Mapping):
        raise InputError(f"add: expected a mapping of axis to a count, got {add!r}")
    out = {}
    for k, v in add.items():
        name = str(k).lower()
        if name not in AXES:
            raise InputError(f"add: expected an axis x, y or z, got {k!r}")
        if isinstance(v, bool) or not isinstance(v, int | np.integer):
            raise InputError(f"add {name}: expected a whole number of elements, got {v!r}")
        if v == 0:
            raise InputError(f"add {name}: expected a number of elements other than 0, got 0")
        out[name] = int(v)
    return out


def _off_square(csdf: CSDF, edits: list[Edit]) -> list[str]:
    """A note where x or z changes and the object's walls run off x and z
    (:func:`partscale.orient.csdf_turn`): its slabs along them are not constant (fit falls back
    to thin slabs or global scaling), and the cure.
    """
    from ..orient import WALL_AXES, csdf_turn, off_square_message

    if not any(e.axis in WALL_AXES for e in edits):
        return []

    turn = csdf_turn(csdf)
    return [] if turn is None else [off_square_message(turn, csdf)]
