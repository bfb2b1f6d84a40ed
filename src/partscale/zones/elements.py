"""Elements: the object along one axis as a designer counts it (seats, doors, shelves, steps).

Along an axis an object reads as a row of *elements* (a seat cushion, a door, a drawer, a
compartment, a step) and the *separators* between them (a gap or groove, a board or divider, an
armrest, a mullion). An element is the unit a designer adds or removes ("one more seat"); a zone
cut from element to element, one element and one separator long, tiled, adds exactly that.

How they are found (:func:`find_elements`), from the CSDF's geometry and colour together:

1. **Separator candidates** (:func:`_candidates`). Two signals, each read at every layer pair:

   - *What a viewer sees change* (:func:`edge_score`). The object is looked at from the four
     sides square to the axis (a depth image each: the first surface along each ray, with its
     colour). Between layers ``i`` and ``i + 1`` a pixel is an edge where the surface appears or
     disappears, where its depth *jumps* (the change differs by more than :data:`DEPTH_JUMP`
     voxels from the mean change of the layer pairs either side: a step, a groove's wall, a
     board's face, not the even slope of a curved outline), or where its colour changes by more
     than :data:`COLOUR_JUMP` (a painted line, a gap's shadow). A layer pair's score is the
     largest share, over the four views, of that view's visible pixels that are edges.
     Layer pairs scoring at least :data:`EDGE_SCORE` form separator candidates (runs of them,
     a layer apart at most). A knob or a handle is a small share of a view (its own height of
     a door's); a groove between two doors, a board's face, the gap between two cushions run
     across most of what is seen there.
   - *Boards and gaps in the cross-section area* (:func:`partscale.zones.suggest._boundaries`):
     a local maximum of the solid's area (a shelf, a divider hidden behind a face) or minimum
     (a gap) changing it by :data:`~partscale.zones.suggest.PROMINENCE` of the largest.

2. **Elements and groups** (:func:`_chains`). An element candidate is the span between two
   separator candidates, at least :data:`MIN_ELEMENT` layers, each separator narrower than half
   of it. Two neighbouring elements (sharing the separator between them) are *alike* when their
   coarse cross-sections, compared along their lengths normalised to [0, 1] (so a small length
   change does not matter), differ by less than :data:`~partscale.zones.suggest.MATCH` in all
   but a tenth of the layers and hold as much solid (within :data:`AREA_CHANGE`: a flight's next
   tread is a step up, not a copy), as they are or mirrored (a left door with its knob on the right,
   a right door with its knob on the left), and their lengths differ by at most
   :data:`LENGTH_CHANGE` (any amount for calm elements, whose cross-section barely changes
   along them: compartments of unequal height between shelves). Colour is not compared: copies
   in another finish are still copies. A *group* is a chain of at least two neighbouring
   elements, each alike the next and the first. Elements are not required to be equally spaced
   or identical.

3. **The group a designer means** (:func:`_best_chains`): the chains covering most of the
   object, with most elements, best matched; then others that do not overlap it. A chain is
   no group where its elements hold a separator clearly stronger than those between them
   (:data:`STRONGER`: rows of elements each), or where it spans less of the solid than
   :data:`MIN_COVER_PAIR` (two elements) or :data:`MIN_COVER` (three or more): two alike
   layers of a sofa's height (its base and its seat) are not what a designer counts. Nor are
   two mirrored halves reaching the object's ends across a board (:func:`_halves`: a trestle
   table's crossed legs, a staircase's middle stringer).

Every position is world units along the axis (``origin + index * voxel_size``); layer
``i``'s centre is at :meth:`partscale.csdf.CSDF.axis_coords` ``[i]``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage
from scipy.signal import find_peaks

from ..csdf import CSDF
from ..edit import AXES
from .profile import SCAN_LAYERS, Profile, _axis_index, from_scan, profile
from .suggest import MATCH, QUANTILE, SHIFT_STEP, _boundaries, _solid_layers, join_islands

#: A layer pair is a separator candidate where this share of the visible surface changes there.
EDGE_SCORE = 0.3
#: ...and stands out this much from the edge score either side (a peak, not a rough surface).
EDGE_PROMINENCE = 0.15
#: A depth change (voxels) that differs this much from its neighbours' is a jump, not a slope.
DEPTH_JUMP = 0.35
#: A colour change (largest of the three sRGB channels, 0..255) that makes an edge.
COLOUR_JUMP = 48
#: Widest board or gap read from the cross-section area, a share of the solid's length.
NARROW = 1 / 12
#: Fewest layers of an element ...
MIN_ELEMENT = 3
#: ... and least share of the solid's length (a rail's thickness is no element).
MIN_SHARE = 0.05
#: Largest relative length change between alike elements (unless both are calm).
LENGTH_CHANGE = 0.25
#: Largest relative change of the mean cross-section area between alike elements.
AREA_CHANGE = 0.06
#: An element is calm where no layer differs from its middle layer by more than this (soft
#: Jaccard distance of the coarse cross-sections): compartments, panels, a seat's straight run.
CALM = 0.1
#: Largest length ratio between alike calm elements (compartments 21 and 41 cm high are alike).
CALM_RATIO = 2.0
#: Where an element's two ends are compared (share of its length in from each end).
UNIT_ENDS = (0.05, 0.1)
#: Candidates within this edge score of a chain's separators count as strong as them.
STRENGTH_TOL = 0.05
#: A chain whose elements hold a candidate this much stronger than its weakest separator is
#: no group (a bunk bed's two halves, each holding its posts, separated by a rail).
STRONGER = 0.15
#: Separators as strong as a chain's own inside each of its elements that make each a row of
#: pieces rather than one element (two: a door's two grooves; three or more: a run of slats).
ROW = 3
#: Least share of the solid's length a group spans: two elements, or three or more.
MIN_COVER_PAIR = 0.6
MIN_COVER = 0.3
#: Layers within which a pair of mirrored halves reaches the solid's ends (:func:`_halves`).
HALF_ENDS = 1.0
#: Layers sampled along each element to compare two of them.
SAMPLES = 16
#: Most chains reported per axis.
MAX_GROUPS = 3
#: Most steps of the search for chains over every way of cutting the axis into elements (a few
#: hundred on furniture; a row of dozens of slats has exponentially many): past it the search
#: follows from each element only the neighbour that matches it best.
MAX_CHAIN_STEPS = 20_000


@dataclass(frozen=True)
class Separator:
    """What lies between two elements along an axis.

    Parameters
    ----------
    start, end : float
        World positions along the axis.
    kind : {'edge', 'board', 'gap'}
        ``'edge'`` (seen to change: a groove, a face, a painted line), ``'board'`` (the
        cross-section's area peaks: a shelf, a divider) or ``'gap'`` (it dips).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> zones.find_elements(bookcase, "y").separators[0].kind
    'edge'
    """

    start: float
    end: float
    kind: str

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {"start": self.start, "end": self.end, "kind": self.kind}


@dataclass(frozen=True)
class Element:
    """One element along an axis: a seat cushion, a door, a compartment between shelves.

    Parameters
    ----------
    start, end : float
        World positions along the axis.
    group : int or None
        The repeat group it belongs to (an index into :attr:`AxisElements.groups`), or None.
    mirrored : bool
        Whether it matches its group's first element only mirrored.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> zones.find_elements(bookcase, "y").elements[0].group
    0
    """

    start: float
    end: float
    group: int | None = None
    mirrored: bool = False

    @property
    def length(self) -> float:
        """``end - start``, world units."""
        return self.end - self.start

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {
            "start": self.start,
            "end": self.end,
            "length": self.length,
            "group": self.group,
            "mirrored": self.mirrored,
        }


@dataclass(frozen=True)
class Group:
    """Elements that repeat along an axis.

    Parameters
    ----------
    members : tuple of int
        Indices into :attr:`AxisElements.elements`, in order along the axis.
    separators : tuple of int
        The separators between them (indices into :attr:`AxisElements.separators`, one fewer).
    err : float
        Mean distance between neighbours' cross-sections (0..:data:`MATCH`).
    mirrored : bool
        Whether any pair matches only mirrored.
    typical : int
        The member a count edit copies or removes first (median length, nearest the middle).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> zones.find_elements(bookcase, "y").groups[0]
    Group(members=(0, 1, 2), separators=(0, 1), err=0.0, mirrored=False, typical=1)
    """

    members: tuple[int, ...]
    separators: tuple[int, ...]
    err: float
    mirrored: bool
    typical: int

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {
            "members": list(self.members),
            "separators": list(self.separators),
            "count": len(self.members),
            "err": round(self.err, 4),
            "mirrored": self.mirrored,
            "typical": self.typical,
        }


@dataclass(frozen=True)
class AxisElements:
    """The elements of an object along one axis (:func:`find_elements`).

    Parameters
    ----------
    axis : {'x', 'y', 'z'}
        The axis.
    elements : tuple of Element
        Ordered along the axis; each group's members, then the spans between the separators
        of the best group's row that belong to no group.
    separators : tuple of Separator
        Ordered along the axis.
    groups : tuple of Group
        Best first: :attr:`best` is the one a count edit uses.
    lo, hi, voxel_size : float
        The solid's extent along the axis (world units) and the object's voxel size, as its
        :class:`Profile` holds them.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> found = zones.find_elements(bookcase, "y")
    >>> len(found.elements), found.best.members
    (3, (0, 1, 2))
    """

    axis: str
    elements: tuple[Element, ...]
    separators: tuple[Separator, ...]
    groups: tuple[Group, ...]
    lo: float
    hi: float
    voxel_size: float

    @property
    def best(self) -> Group | None:
        """The most typical repeat group, or None where nothing repeats."""
        return self.groups[0] if self.groups else None

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {
            "axis": self.axis,
            "elements": [e.to_json() for e in self.elements],
            "separators": [s.to_json() for s in self.separators],
            "groups": [g.to_json() for g in self.groups],
        }


# -- 1. separator candidates ------------------------------------------------------------------


def _views(s: np.ndarray, rgb: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Depth images of the solid ``s`` ((N, U, V) float32 sdf in voxels, the axis first) seen
    from its four sides square to the axis: per view ``depth`` (N, W) float32 (voxels from the
    grid's side to the first zero crossing, linear between samples; NaN where no surface),
    ``colour`` (N, W, 3) int16 (sRGB of the first inside sample) and ``present`` (N, W) bool.
    """
    out = []
    for ax in (1, 2):
        for flip in (False, True):
            t = np.flip(s, axis=ax) if flip else s
            c = np.flip(rgb, axis=ax) if flip else rgb
            t = np.moveaxis(t, ax, -1)  # (N, W, D)
            inside = np.asarray(t < 0)
            present = np.asarray(inside.any(axis=-1))
            j = np.argmax(inside, axis=-1)
            jm = np.maximum(j - 1, 0)
            a = np.take_along_axis(t, jm[..., None], -1)[..., 0]
            b = np.take_along_axis(t, j[..., None], -1)[..., 0]
            frac = np.where((j > 0) & (a > b), a / np.maximum(a - b, 1e-6), 0.0)
            depth = np.where(present, jm + np.clip(frac, 0.0, 1.0), np.nan).astype(np.float32)
            cm = np.moveaxis(c, ax, -2)  # (N, W, D, 3)
            colour = np.take_along_axis(cm, j[..., None, None], -2)[..., 0, :].astype(np.int16)
            out.append((depth, colour, present))
    return out


def edge_score(csdf: CSDF, axis: int) -> np.ndarray:
    """(N - 1,) float64: for each layer pair ``(i, i + 1)`` along ``axis``, the largest share
    over the four side views of the visible pixels that change there (see module, step 1).
    """
    h = np.float32(csdf.voxel_size)
    s = np.moveaxis(csdf.sdf, axis, 0) / h
    rgb = np.moveaxis(csdf.rgb, axis, 0)
    if from_scan(csdf):
        # a completed scan's surface and colours averaged along the axis as its profile is
        # (profile.SCAN_LAYERS): its noise would be edges at every layer
        s = ndimage.uniform_filter1d(s, SCAN_LAYERS, axis=0, mode="nearest")
        rgb = ndimage.uniform_filter1d(rgb.astype(np.float32), SCAN_LAYERS, axis=0, mode="nearest")
    best = np.zeros(s.shape[0] - 1)
    for depth, colour, present in _views(s, rgb):
        both = present[1:] & present[:-1]
        either = present[1:] | present[:-1]
        d1 = np.nan_to_num(np.diff(depth, axis=0))
        trend = np.zeros_like(d1)
        trend[1:-1] = 0.5 * (d1[:-2] + d1[2:])
        jump = np.abs(d1 - trend) > DEPTH_JUMP
        dc = np.abs(np.diff(colour, axis=0)).max(axis=-1) > COLOUR_JUMP
        # a pixel appearing or vanishing beside one seen in both layers is an outline creeping
        # sideways (a slanted leg, a curve), not a face starting
        beside = np.zeros_like(both)
        beside[:, 1:] |= both[:, :-1]
        beside[:, :-1] |= both[:, 1:]
        edge = (either & ~both & ~beside) | (both & (jump | dc))
        share = edge.sum(axis=1) / np.maximum(either.sum(axis=1), 1)
        best = np.maximum(best, share)
    return best


@dataclass(frozen=True)
class _Cand:
    """A separator candidate in layer indices: the layers ``lo..hi`` it covers (continuous: an
    edge between layers i and i + 1 lies at i + 0.5), where the elements beside it end, and its
    ``strength``: the largest edge score in it (an area boundary alone: :data:`EDGE_SCORE`).
    """

    lo: float
    hi: float
    kind: str
    strength: float


def _candidates(csdf: CSDF, p: Profile) -> list[_Cand]:
    """Separator candidates (step 1 of the module), ordered, overlapping ones merged."""
    i0, i1 = _solid_layers(p)
    score = edge_score(csdf, p.axis)
    cands: list[_Cand] = []
    # peaks of the edge score, each over the run of pairs around it scoring at least half of it
    peaks, _ = find_peaks(
        np.concatenate([[0.0], score, [0.0]]), height=EDGE_SCORE, prominence=EDGE_PROMINENCE
    )
    for pk in peaks - 1:
        top = score[pk]
        lo = hi = pk
        while lo > 0 and score[lo - 1] >= top / 2 and pk - lo < 3:
            lo -= 1
        while hi < len(score) - 1 and score[hi + 1] >= top / 2 and hi - pk < 3:
            hi += 1
        cands.append(_Cand(float(lo) + 0.5, float(hi) + 0.5, "edge", float(top)))
    # narrow area boundaries: a board, a narrow dip (a cushion's broad crown is no board, a
    # plateau between two boards no gap: its middle is arbitrary)
    narrow = max(MIN_ELEMENT, (i1 - i0) * NARROW)
    for kind, lo, hi, cut in _boundaries(p):
        if hi - lo > narrow:
            continue
        if kind == 1:
            cands.append(_Cand(float(lo), float(hi), "board", EDGE_SCORE))
        else:
            cands.append(_Cand(float(cut), float(cut), "gap", EDGE_SCORE))
    cands.sort(key=lambda c: (c.lo, c.hi))
    merged: list[_Cand] = []
    boards: list[bool] = []  # whether each merged candidate holds a board
    for c in cands:
        board = c.kind == "board"
        # touching candidates are one separator (a board's two faces), but two boards are two
        # separators however close (a row of slats, narrow gaps between: no separator from
        # end to end)
        if merged and (
            c.lo <= merged[-1].hi or (c.lo <= merged[-1].hi + 1.0 and not (board and boards[-1]))
        ):
            m = merged[-1]
            both = m.kind if m.kind == c.kind else "edge"
            merged[-1] = _Cand(m.lo, max(m.hi, c.hi), both, max(m.strength, c.strength))
            boards[-1] = boards[-1] or board
        else:
            merged.append(c)
            boards.append(board)
    return merged


# -- 2. elements and chains -------------------------------------------------------------------


def _samples(e: tuple[float, float]) -> np.ndarray:
    """(SAMPLES,) layer positions spread over element ``e`` (layer indices), a layer in from
    each end (the separator's face is blended into the layer next to it).
    """
    a, b = e[0] + 1.0, e[1] - 1.0
    return a + (np.arange(SAMPLES) + 0.5) / SAMPLES * (b - a)


def _layer_distance(p: Profile, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Coarse distances between the (interpolated) layers at positions ``x`` and ``y``."""
    i = np.clip(np.round(x).astype(np.int64), 0, p.n - 1)
    return p.shifted_distance(i, y - i, coarse=True)


def _calm(p: Profile, e: tuple[float, float]) -> bool:
    """Whether element ``e``'s cross-section barely changes along it (:data:`CALM`)."""
    x = _samples(e)
    mid = np.full_like(x, (e[0] + e[1]) / 2)
    return bool(_layer_distance(p, mid, x).max() < CALM)


def _unit(p: Profile, e: tuple[float, float]) -> bool:
    """Whether element ``e`` begins and ends alike (module, step 2): some pair of layers at
    :data:`UNIT_ENDS` of its length in from either end matches (a door's two edges, a cushion's
    two rounded ends, a compartment), so half of a symmetric piece (from a side panel to the
    middle handle) is no element.
    """
    t = np.asarray(UNIT_ENDS)
    le = e[1] - e[0]
    d = _layer_distance(p, e[0] + t * le, e[1] - t * le)
    return bool(d.min() <= MATCH)


def _alike(p: Profile, e: tuple[float, float], f: tuple[float, float]) -> tuple[float, bool] | None:
    """``(err, mirrored)`` where elements ``e`` and ``f`` are alike (module, step 2), else None."""
    le, lf = e[1] - e[0], f[1] - f[0]
    ratio = max(le, lf) / max(min(le, lf), 1e-9)
    calm = _calm(p, e) and _calm(p, f)
    if ratio > (CALM_RATIO if calm else 1 + LENGTH_CHANGE):
        return None
    x = _samples(e)
    t = (x - e[0]) / le
    # as much solid in each (a flight's next tread is as deep but higher: a step, not a copy)
    ae = np.interp(x, np.arange(p.n), p.area).mean()
    af = np.interp(f[0] + t * lf, np.arange(p.n), p.area).mean()
    if abs(ae - af) > AREA_CHANGE * max(ae, af):
        return None
    best = None  # the same share of each element's length (mirrored: from its other end)
    for mirror in (False, True):
        y = f[1] - t * lf if mirror else f[0] + t * lf
        d = _layer_distance(p, x, y)
        if np.quantile(d, QUANTILE) <= MATCH and (best is None or d.mean() < best[0]):
            best = (float(d.mean()), mirror)
    return best


@dataclass(frozen=True)
class _Chain:
    elements: tuple[tuple[float, float], ...]  # layer indices
    seps: tuple[tuple[float, float], ...]  # layer indices, one fewer: what lies between them
    kinds: tuple[str, ...]  # each separator's kind
    err: float
    mirrored: tuple[bool, ...]  # each element against the first


_Key = tuple[int, int]  # an element: the candidates it runs from and to


def _chains(p: Profile, cands: list[_Cand]) -> list[_Chain]:
    """Every maximal chain of alike neighbouring elements between candidates (module, step 2).

    An element runs from the end of candidate ``a`` to the start of candidate ``b``; the next
    one from the end of a candidate ``c >= b`` on: the candidates ``b..c`` are the separator
    between them (a board's two faces, or a divider and the gaps beside it), narrower than
    half of either element. Where there are too many ways to cut the axis to try them all
    (:data:`MAX_CHAIN_STEPS`: a row of dozens of slats), elements holding a candidate as strong
    as their ends are left out (they are rows of elements each, see :func:`_best_chains`), and
    past that the search follows each element's best matched neighbour only.
    """
    i0, i1 = _solid_layers(p)
    shortest = max(MIN_ELEMENT, MIN_SHARE * (i1 - i0))
    elems: dict[_Key, tuple[float, float]] = {}
    for a, b in itertools.combinations(range(len(cands)), 2):
        e = (cands[a].hi, cands[b].lo)
        if e[1] - e[0] >= shortest and _unit(p, e):
            elems[(a, b)] = e
    try:
        return _ChainSearch(p, cands, elems).run()
    except _TooManyChains:
        pass
    plain = {k: e for k, e in elems.items() if _plain(cands, k)}
    try:
        return _ChainSearch(p, cands, plain).run()
    except _TooManyChains:
        return _ChainSearch(p, cands, plain, greedy=True).run()


def _plain(cands: list[_Cand], k: _Key) -> bool:
    """Whether element ``k`` holds no candidate within :data:`STRENGTH_TOL` of its weaker end."""
    weaker = min(cands[k[0]].strength, cands[k[1]].strength)
    return all(c.strength < weaker - STRENGTH_TOL for c in cands[k[0] + 1 : k[1]])


class _TooManyChains(Exception):
    """A chain search passed :data:`MAX_CHAIN_STEPS` (see :func:`_chains`)."""


class _ChainSearch:
    """The depth-first search of :func:`_chains` over the elements ``elems``: every maximal
    chain, or with ``greedy`` those that follow each element's best matched neighbour.
    Raises :class:`_TooManyChains` past :data:`MAX_CHAIN_STEPS` steps and comparisons, unless
    greedy.
    """

    def __init__(
        self,
        p: Profile,
        cands: list[_Cand],
        elems: dict[_Key, tuple[float, float]],
        *,
        greedy: bool = False,
    ):
        self.p, self.cands, self.elems, self.greedy = p, cands, elems, greedy
        self.after: dict[int, list[_Key]] = {}
        for k in elems:
            self.after.setdefault(k[0], []).append(k)
        self.alike: dict[tuple[_Key, _Key], tuple[float, bool] | None] = {}
        self.steps = 0
        self.out: list[_Chain] = []

    def run(self) -> list[_Chain]:
        for k in self.elems:
            self.grow([k], [], [False])
        return self.out

    def step(self) -> None:
        self.steps += 1
        if self.steps > MAX_CHAIN_STEPS and not self.greedy:
            raise _TooManyChains

    def match(self, k1: _Key, k2: _Key) -> tuple[float, bool] | None:
        if (k1, k2) not in self.alike:
            self.step()
            self.alike[(k1, k2)] = _alike(self.p, self.elems[k1], self.elems[k2])
        return self.alike[(k1, k2)]

    def successors(self, k: _Key) -> list[_Key]:
        e, cands = self.elems[k], self.cands
        out = []
        for c in range(k[1], len(cands)):
            sep = cands[c].hi - cands[k[1]].lo
            if sep > (e[1] - e[0]) / 2:
                break
            out += [
                f for f in self.after.get(c, []) if sep <= (self.elems[f][1] - self.elems[f][0]) / 2
            ]
        return out

    def nexts(self, chain: list[_Key]) -> list[tuple[_Key, tuple[float, bool], bool]]:
        """The elements that may follow ``chain``: each with its match to the last and whether
        it is mirrored against the first; in a greedy search only the best matched.
        """
        found = []
        for nxt in self.successors(chain[-1]):
            m_prev = self.match(chain[-1], nxt)
            m_first = self.match(chain[0], nxt) if len(chain) > 1 else m_prev
            if m_prev is not None and m_first is not None:
                found.append((nxt, m_prev, m_first[1]))
        if self.greedy and found:
            return [min(found, key=lambda f: f[1][0])]
        return found

    def grow(self, chain: list[_Key], errs: list[float], mirr: list[bool]) -> None:
        self.step()
        grown = False
        for nxt, m_prev, mirrored in self.nexts(chain):
            grown = True
            self.grow([*chain, nxt], [*errs, m_prev[0]], [*mirr, mirrored])
        if not grown and len(chain) >= 2:
            pairs = list(itertools.pairwise(chain))
            kinds = tuple(self.cands[k[1]].kind if k[1] == f[0] else "board" for k, f in pairs)
            self.out.append(
                _Chain(
                    tuple(self.elems[k] for k in chain),
                    tuple((self.cands[k[1]].lo, self.cands[f[0]].hi) for k, f in pairs),
                    kinds,
                    float(np.mean(errs)),
                    tuple(mirr),
                )
            )


def _strength(cands: list[_Cand], lo: float, hi: float) -> float:
    """The strongest candidate within ``lo..hi`` (layer indices): a separator's strength."""
    return max((k.strength for k in cands if lo - 1e-6 <= k.lo and k.hi <= hi + 1e-6), default=0.0)


def _best_chains(p: Profile, cands: list[_Cand], chains: list[_Chain]) -> list[_Chain]:
    """Chains best first (most of the solid covered, most elements, best matched), each
    overlapping none before it; at most :data:`MAX_GROUPS`.
    """
    i0, i1 = _solid_layers(p)
    solid = max(i1 - i0, 1)

    def score(c: _Chain) -> float:
        cover = (c.elements[-1][1] - c.elements[0][0]) / solid
        n = len(c.elements)
        # elements holding a candidate as strong as what separates them are several elements
        # each (two halves of three compartments each): the finer chain is what repeats
        sep = min(_strength(cands, a, b) for a, b in c.seps)
        inner = max(
            (
                k.strength
                for k in cands
                if any(a + 1 < k.lo and k.hi < b - 1 for a, b in c.elements)
            ),
            default=0.0,
        )
        if inner > sep + STRONGER:
            return 0.0  # clearly stronger separators inside: these are rows of elements each
        if _rows(cands, c, sep):
            return 0.0  # each a row of pieces parted as strongly: a run of slats, not two halves
        if cover < (MIN_COVER_PAIR if n == 2 else MIN_COVER):
            return 0.0  # a pair that is not most of the object: a sofa's base and seat
        if _halves(p, c, i0, i1):
            return 0.0  # one symmetric object's two halves about a board: nothing ends them
        coarse = 0.5 if inner >= sep - STRENGTH_TOL else 1.0
        return cover * (1 - 1 / n) * (1 - 0.5 * c.err / MATCH) * coarse

    kept: list[_Chain] = []
    for c in sorted(chains, key=score, reverse=True):
        if score(c) <= 0:
            break
        span = (c.elements[0][0], c.elements[-1][1])
        if any(span[0] < q.elements[-1][1] and q.elements[0][0] < span[1] for q in kept):
            continue
        kept.append(c)
        if len(kept) == MAX_GROUPS:
            break
    return kept


def _halves(p: Profile, c: _Chain, i0: int, i1: int) -> bool:
    """Whether ``c`` is the two mirrored halves of one object about a board in its middle (a
    trestle table's crossed legs and their stretcher, a staircase's middle stringer), not two
    elements: they reach the solid's first and last layers ``i0``, ``i1`` (within
    :data:`HALF_ENDS` layers), where elements are ended by something (an armrest, a side panel,
    a gap), and a board parts them; doors parted by a gap and overlaying the sides stay a
    pair. Halves whose cross-section barely changes along them (:func:`_calm`: a staircase's
    treads either side of its stringer) match as well mirrored as not, and count as mirrored.
    """
    return (
        len(c.elements) == 2
        and (c.mirrored[-1] or all(_calm(p, e) for e in c.elements))
        and c.kinds == ("board",)
        and c.elements[0][0] - i0 <= HALF_ENDS
        and i1 - c.elements[-1][1] <= HALF_ENDS
    )


def _rows(cands: list[_Cand], c: _Chain, sep: float) -> bool:
    """Whether every element of ``c`` holds :data:`ROW` or more candidates within
    :data:`STRENGTH_TOL` of its separators' strength ``sep``: each is a row of pieces itself
    (a dozen slats of a row of two dozen), too short to be elements on their own
    (:data:`MIN_SHARE`), not what a designer counts.
    """
    return all(
        sum(a + 1 < k.lo and k.hi < b - 1 and k.strength >= sep - STRENGTH_TOL for k in cands)
        >= ROW
        for a, b in c.elements
    )


def _typical(lengths: list[float]) -> int:
    """Index of the element of median length, the middle one among equals."""
    med = float(np.median(lengths))
    off = [abs(x - med) for x in lengths]
    close = [i for i, d in enumerate(off) if d <= min(off) + 0.5]
    mid = (len(lengths) - 1) / 2
    return min(close, key=lambda i: abs(i - mid))


def find_elements(csdf: CSDF, axis: str | int, *, prof: Profile | None = None) -> AxisElements:
    """The elements and separators of ``csdf`` along ``axis`` and the groups that repeat.

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : {'x', 'y', 'z'} or {0, 1, 2}
        The axis the elements lie along.
    prof : Profile, optional
        The axis's :func:`~partscale.zones.profile` if the caller has it.

    Returns
    -------
    AxisElements
        Positions in world units; :attr:`AxisElements.best` is the group a count edit uses
        (None where nothing repeats).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> found = zones.find_elements(bookcase, "y")
    >>> found.best is not None, zones.element_phrase(found)
    (True, '3 alike elements, 0.26 long')
    """
    ax = _axis_index(axis)
    p = prof if prof is not None else profile(csdf, ax)
    cands = _candidates(csdf, p)
    chains = _best_chains(p, cands, _chains(p, cands))
    return _describe(p, chains)


def _describe(p: Profile, chains: list[_Chain]) -> AxisElements:
    """The :class:`AxisElements` of the chosen chains: their elements and separators."""
    seps: list[Separator] = []
    elements: list[Element] = []
    groups: list[Group] = []
    for g, c in enumerate(chains):
        first = len(elements)
        for (a, b), m in zip(c.elements, c.mirrored, strict=True):
            elements.append(Element(float(p.world(a)), float(p.world(b)), g, m))
        members = tuple(range(first, len(elements)))
        s0 = len(seps)
        for (a, b), kind in zip(c.seps, c.kinds, strict=True):
            seps.append(Separator(float(p.world(a)), float(p.world(b)), kind))
        lengths = [b - a for a, b in c.elements]
        groups.append(
            Group(
                members=members,
                separators=tuple(range(s0, len(seps))),
                err=c.err,
                mirrored=any(c.mirrored),
                typical=members[_typical(lengths)],
            )
        )
    return AxisElements(
        axis=AXES[p.axis],
        elements=tuple(elements),
        separators=tuple(seps),
        groups=tuple(groups),
        lo=p.lo,
        hi=p.hi,
        voxel_size=p.voxel_size,
    )


# -- count edits: N more or fewer elements ------------------------------------------------------


@dataclass(frozen=True)
class CountZone:
    """A zone of whole elements with their separators, for a count edit (:func:`count_zone`).

    Parameters
    ----------
    start, end : float
        World positions of the zone's planes along the axis; ``end - start`` is a whole number
        of voxels, so tiled copies are exact shifts of the object's layers.
    members : tuple of int
        The elements (indices into :attr:`AxisElements.elements`) the zone holds, whole.
    seam : float
        Soft Jaccard distance between the cross-sections at the two planes (0: they match, so
        copies join seamlessly; at most :data:`~partscale.zones.suggest.MATCH` where possible).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> z = zones.count_zone(bookcase, zones.find_elements(bookcase, "y"), 1)
    >>> round(z.start, 3), round(z.end, 3), z.members, z.seam
    (0.624, 0.924, (1,), 0.0)
    """

    start: float
    end: float
    members: tuple[int, ...]
    seam: float

    @property
    def length(self) -> float:
        """``end - start``, world units."""
        return self.end - self.start


def _anchors(
    p: Profile, found: AxisElements, g: Group, j: int, m: int, inside: bool
) -> list[tuple[float, float, float, float]]:
    """``(start, end, cost, seam)`` (layer indices) of the zones holding the members
    ``j..j+m-1`` of ``g`` (positions in the group) and ``m`` separators: from a plane at member
    ``j``'s start (or in the separator before it) to the same place at member ``j + m``
    (forward), or from the end of member ``j - 1`` to that of member ``j + m - 1`` (backward),
    shifted alike by ``t`` (quarter voxels). ``inside``: the planes may also go up to halfway
    into the elements (else at most a voxel in: a plane through an element's middle joins the
    halves of two elements, mirrored ones back to front). Cost: the seam (distance between the
    planes' cross-sections) plus their cross-section area (low in gaps).
    """
    el = [(p.index(found.elements[i].start), p.index(found.elements[i].end)) for i in g.members]
    sep = [
        (p.index(found.separators[i].start), p.index(found.separators[i].end)) for i in g.separators
    ]
    c = len(el)
    pairs: list[tuple[float, float, float, float]] = []  # (a, b, t_lo, t_hi)
    if j + m <= c - 1:  # forward: member j's start to member j + m's start
        before = sep[j - 1][1] - sep[j - 1][0] if j > 0 else 0.0
        reach = min(el[j][1] - el[j][0], el[j + m][1] - el[j + m][0]) / 2
        pairs.append((el[j][0], el[j + m][0], -before, reach if inside else min(reach, 1.0)))
    if j >= 1:  # backward: member j - 1's end to member j + m - 1's end
        after = sep[j + m - 1][1] - sep[j + m - 1][0] if j + m - 1 < c - 1 else 0.0
        reach = min(el[j - 1][1] - el[j - 1][0], el[j + m - 1][1] - el[j + m - 1][0]) / 2
        pairs.append(
            (el[j - 1][1], el[j + m - 1][1], -reach if inside else -min(reach, 1.0), after)
        )
    amax = max(float(p.area.max()), 1e-9)
    out: list[tuple[float, float, float, float]] = []
    for a, b, t0, t1 in pairs:
        t = np.arange(t0, t1 + 1e-9, SHIFT_STEP)
        length = float(np.round(b - a))  # whole voxels
        starts = a + t
        base = np.clip(np.round(starts).astype(np.int64), 0, p.n - 1)
        seam = p.shifted_distance(base, starts + length - base)
        area = np.interp(starts, np.arange(p.n), p.area) / amax
        area2 = np.interp(starts + length, np.arange(p.n), p.area) / amax
        cost = seam + 0.5 * (area + area2)
        out += [
            (float(x), float(x + length), float(k), float(d))
            for x, k, d in zip(starts, cost, seam, strict=True)
        ]
    return out


def count_zone(
    csdf: CSDF, found: AxisElements, m: int, *, prof: Profile | None = None
) -> CountZone:
    """The zone of ``m`` whole elements and ``m`` separators that a count edit tiles or cuts out.

    The zone holding ``m`` whole elements of :attr:`AxisElements.best` and ``m`` separators,
    around its typical member, whose planes' cross-sections match best.

    Tiled to ``1 + n`` copies it adds ``n`` elements; tiled to its start (0 copies) it removes
    ``m``. Among the zones of least cost (:func:`_anchors`, within 0.03 of the lowest), those
    whose copies' joins cut off the least solid (:func:`~partscale.zones.suggest.join_islands`).

    Parameters
    ----------
    csdf : CSDF
        The object.
    found : AxisElements
        Its elements along the axis (:func:`find_elements`).
    m : int
        Whole elements the zone holds.
    prof : Profile, optional
        The axis's :func:`~partscale.zones.profile` if the caller has it.

    Returns
    -------
    CountZone
        The zone, world units.

    Raises
    ------
    InputError
        No repeat group along the axis, or ``m`` not below its element count (one stays).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> zone = zones.count_zone(bookcase, zones.find_elements(bookcase, "y"), 1)
    >>> zone.members
    (1,)
    """
    from ..errors import InputError

    g = found.best
    if g is None:
        raise InputError(
            f"elements along {found.axis}: expected a repeated element (a seat, a door, a shelf "
            f"row), found none along {found.axis}"
        )
    c = len(g.members)
    if not 1 <= m < c + (1 if m == 1 else 0):
        raise InputError(
            f"elements along {found.axis}: expected to remove at most {c - 1} of its {c} "
            f"elements (one stays), got {m}"
        )
    p = prof if prof is not None else profile(csdf, AXES.index(found.axis))
    typ = g.members.index(g.typical)
    lengths = [found.elements[i].length for i in g.members]
    # runs of m members holding the typical one, and any other run as long within a voxel (a
    # mirrored pair's other door): the zone of least cost among them
    runs = [
        j
        for j in range(c - m + 1)
        if j <= typ < j + m
        or abs(sum(lengths[j : j + m]) - sum(lengths[typ : typ + m])) <= found.voxel_size
    ]
    best: tuple[float, float, float, float] | None = None
    best_key: tuple[int, float] | None = None
    members: tuple[int, ...] = ()
    for j in runs:
        # planes in the separators where they match there, else halfway into the elements
        zones = _anchors(p, found, g, j, m, inside=False)
        if not zones or min(z[3] for z in zones) > MATCH:
            zones = _anchors(p, found, g, j, m, inside=True)
        if not zones:
            continue
        low = min(z[2] for z in zones)
        good = [z for z in zones if z[2] <= low + 0.03]
        for z in good:
            key = (join_islands(csdf, p.axis, z[0], z[1] - z[0]), z[2])
            if best_key is None or key < best_key:
                best, best_key, members = z, key, tuple(g.members[j : j + m])
    if best is not None:
        return CountZone(float(p.world(best[0])), float(p.world(best[1])), members, best[3])
    raise InputError(
        f"elements along {found.axis}: expected room for a zone of {m} whole element(s), got "
        f"none (the group's {c} elements leave no separator to cut at)"
    )


def length_text(x: float, units: str | None) -> str:
    """A length as the notes write it: centimetres under a metre where ``units`` is ``"m"``
    (``'26.0 cm'``, ``'1.200 m'``), else four figures in the object's units.
    """
    if units == "m":
        return f"{x * 100:.1f} cm" if abs(x) < 1 else f"{x:.3f} m"
    return f"{x:.4g}"


def element_phrase(found: AxisElements, units: str | None = None) -> str:
    """A few words on the best group: ``'2 alike elements, mirrored, 0.84..0.85 m long'``.

    Parameters
    ----------
    found : AxisElements
        The elements along an axis.
    units : str, optional
        The object's units: lengths as :func:`length_text` writes them (bare numbers where
        not given).

    Returns
    -------
    str
        The phrase (``'no repeated element'`` where nothing repeats).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> zones.element_phrase(zones.find_elements(bookcase, "y"))
    '3 alike elements, 0.26 long'
    >>> zones.element_phrase(zones.find_elements(bookcase, "y"), "m")
    '3 alike elements, 26.0 cm long'
    """
    g = found.best
    if g is None:
        return "no repeated element"
    lengths = [found.elements[i].length for i in g.members]
    lo, hi = min(lengths), max(lengths)
    if units is None:
        size = f"{lo:.3g}" if hi - lo < found.voxel_size else f"{lo:.3g}..{hi:.3g}"
    else:
        size = length_text(lo, units)
        size += "" if hi - lo < found.voxel_size else f"..{length_text(hi, units)}"
    return f"{len(g.members)} alike elements{', mirrored' if g.mirrored else ''}, {size} long"
