"""Symmetries of a partial scan, found by voting and kept only where the free space agrees.

Everything here works in the *upright* frame: y up, the floor at y = 0.

- Mirror planes are vertical (normal horizontal). Pairs of scan points at the same height and of
  similar colour each vote for the plane that swaps them (angle, offset); the strongest peaks are
  refined and scored by mirroring the whole scan: ``support`` is the fraction of mirrored points
  that land on the scan, ``violation`` the fraction that land where a camera saw through (free
  space). A plane is accepted when ``violation <= MAX_VIOLATION`` and ``support >= MIN_SUPPORT``,
  and applied at the heights where it holds; a plane held firmly there (``UNSEEN_SUPPORT``) is
  applied too at heights whose copies land only where no camera looked
  (:func:`_held_where_unseen`).
- Rotations: 4- and 5-fold about a vertical axis, for the lowest part of the object (the bases of
  swivel chairs and tables), the axis found by a coarse-to-fine search, accepted piece by piece
  (:func:`rotation_axis`) and applied only in the region of the pieces it holds for.
- Round objects (a bin, a lamp, a round table, a stool's round seat on its pedestal): level
  slabs whose points lie on an arc of one circle about one vertical axis, their faces turned
  out from it, make a turn of the whole (:func:`revolution`): a regular polygon's fold where
  the faces say so, else ``ROUND_FOLD`` steps round a circle.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numba
import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from .carve import lookup

MIN_SUPPORT = 0.3
#: Walls in plan (:func:`walls_direction`): this share of the upright faces' normals within this many
#: degrees of one direction or the one square to it. Unless the object spans as far along one
#: as along the other (within WALL_SQUARE_CELLS cells), no mirror plane within
#: WALL_DIAGONAL_DEG of their diagonal.
WALL_SHARE = 0.6
WALL_SPREAD_DEG = 5.0
WALL_DIAGONAL_DEG = 15.0
WALL_SQUARE_CELLS = 2.0
MAX_VIOLATION = 0.06
UNSEEN_SUPPORT = 0.9
"""Support of a mirror plane, over the heights where its copies land on the scan, from which it
is applied too at the heights where they land only where no camera looked (none where a camera
saw through): a table seen from one end, 45 degrees above, shows its top whole and the legs of
the near end; the far legs stand under the top, unseen, and the plane across its length, held
by the top, copies the near legs there."""
VIOLATION_WEIGHT = 4.0
SAMPLES = 1500
PAIRS = 60000
BASE_FRACTION = 0.3
"""Rotational symmetry is looked for, and applied, below this fraction of the object's height."""
SLABS = 8
REFINE_PEAKS = 3
"""Vote peaks whose neighbourhoods the plane search refines (the rest are scored once)."""
REFINE_NEIGHBOURS = 4
REFINE_SAMPLES = 3000
REFINE_FACING = 0.8
PLATEAU_STEPS = np.arange(-3.0, 3.001, 0.25)
"""Offsets (cells) about the refined plane at which its copies' landing in free space is read
(:func:`_centred_in_free`)."""
PLATEAU_SLACK = 0.001
"""Share of the copies by which a plane's landing in free space may exceed the least and still
be on the plateau of planes the free space allows."""
PLATEAU_FLAT = 0.02
"""Spread (cells) of the refinement's cost across that plateau below which the fit says nothing
of where on it the plane stands."""
PLATEAU_MIN_MOVE = 0.5
"""Cells by which the plateau's middle must lie off the refined plane for the plane to move."""
"""Cosine above which a mirrored point's normal and its counterpart's agree (same surface)."""
MIN_ROTATION_SUPPORT = 0.5
"""Share of a base piece's points with a rotated copy on the scan for the rotation to hold."""
MAX_ROTATION_VIOLATION = 0.25
"""Share of a base piece's rotated copies allowed where a camera saw through (each is then
dropped; the TUM chairs' star bases 0.14-0.17 at 5-fold, 0.40 at 4-fold)."""
MIN_ROTATION_COVER = 0.4
"""Share of the base's points in the pieces a rotation holds for, for it to be accepted."""
ROTATION_PIECE = 2.0
"""Cells: base points closer than about this are one piece."""
ROTATION_SAMPLES = 4000
ROTATION_CELLS_ACROSS = 40
"""The rotation's support tolerance is at most the footprint of what the base carries over
this (at --res 128 the grid's cell is finer already)."""
HUB_SHARE = 0.25
"""Share of the radius of a turning base's pieces (their farthest point from the axis) within
which they must reach the axis (their hub): a length of the base, not of the grid's cells (five
cells passed the TUM purple chair's two legs at --res 64, reaching 0.18 of their radius, and
failed them at --res 128, 0.20). A star base's legs start at its hub (0.02-0.20 of their
radius on the TUM chairs); a table's four legs, each a piece, stand near their radius."""
ARM_REACH = 6.0
"""Cells: the neighbourhood whose spread in plan gives a base point's direction (a leg is a few
cells wide and many long)."""
ARM_LINEARITY = 0.8
"""1 - minor/major variance of that neighbourhood above which the point lies on an arm."""
ARM_SAMPLES = 400
"""Arm points drawn to vote for the hub."""
ARM_TOLERANCE = 2.0
"""Cells from an arm's line within which an axis counts as on it."""
ARM_GAP_DEG = 15.0
"""Degrees about the hub without arm points that separate two arms."""
ARM_MIN_POINTS = 5
"""Arm points (of ``ARM_SAMPLES``) that make an arm."""
ARM_FOLD_DEG = 10.0
"""Degrees by which the angle between two arms may miss a multiple of a fold's step."""
MIN_RADIAL = 0.8
"""Mean |cosine| between the base's arms and the direction from the turn's axis above which
the arms radiate from it (a star's legs; a box's bottom edges run across it)."""
ARM_PARALLEL = 0.87
"""Arms whose lines meet must differ in direction: the mean resultant length of the voters'
doubled angles stays below this (two arms 30 degrees apart; parallel runners give 1)."""
ROTATION_SLACK_DEG = 4.0
"""Degrees a rotated copy may turn further to land on the scan (:func:`_copies_scored`)."""
MIN_COVER = 0.6
"""A symmetry must hold on slabs holding at least this fraction of the points."""
MAX_PLANE_TILT_DEG = 10.0
"""Degrees a vertical mirror plane may tilt across itself to fit the scan (:func:`tilted_plane`)."""


ROUND_SLABS = 12
"""Level slabs of the object's height tested for a round section (:func:`revolution`)."""
ROUND_MIN_POINTS = 40
ROUND_SPAN_DEG = 120.0
"""Degrees of arc a slab's points must span about their circle's centre: less does not place
the centre (a flat face fits a wide circle over a few degrees)."""
ROUND_RESIDUAL = 0.08
"""Median distance of a slab's points from their circle, as a share of its radius: a regular
octagon's faces lie within 0.04 of it, a hexagon's 0.06; two sides of a box at a corner 0.29."""
ROUND_FACING = 0.8
ROUND_FACING_SHARE = 0.8
"""Share of a round slab's side-facing points whose faces turn out from the axis (cosine at
least ``ROUND_FACING``): a ring of legs stands on a circle but faces every way."""
ROUND_MIN_RADIUS = 2.0
"""Cells: a slab's circle at least this wide places its centre (a pole's does not)."""
ROUND_AXIS = 0.1
"""Share of the radius (at least a cell) within which the round slabs' centres lie of the axis:
further, up is askew (a lamp's shade seen with up 6 degrees off, its centres drifting 5 cm over
25 cm of height)."""
ROUND_SHARE = 0.3
ROUND_HELD = 0.8
"""Shares of the object's points in its round slabs, and in those and the slabs within their
cylinder (a lid, a pole, a foot), for the whole to turn: a chair with a round seat does not."""
ROUND_POLYGON = 0.7
"""Concentration (:func:`_fold_of`) above which the faces' directions give a polygon's fold."""
ROUND_FOLD = 8
"""Steps of the turn round a circle: a view sees about a third of it, so copies 45 degrees apart
overlap each other and the scan."""
ROUND_SUPPORT = 0.15
ROUND_VIOLATION = 0.06
"""Shares of the round part's turned copies that must land on the scan (a view sees a third of
a round side or more, and the copies a step or two round overlap it: a bin 0.29, a round table
0.30; a bookcase's front seen level, whose slabs fitted wide circles, 0.01) and that may land
where a camera saw through."""


@dataclass(frozen=True)
class Symmetry:
    """A rigid map of the upright frame: ``p -> p @ A.T + b``; ``kind`` is "mirror" or "rotation"
    (then ``fold``); ``bands`` are the height intervals where it holds and is applied.
    """

    kind: str
    A: np.ndarray
    b: np.ndarray
    support: float
    violation: float
    fold: int = 0
    bands: tuple = ((-np.inf, np.inf),)
    params: dict = field(default_factory=dict)
    region: Callable[[np.ndarray], np.ndarray] | None = None

    def where(self, points: np.ndarray) -> np.ndarray:
        """(N,) bool: points at heights where this symmetry holds (and in its region)."""
        y = np.asarray(points)[:, 1]
        out = np.logical_or.reduce([(y >= a) & (y < b) for a, b in self.bands])
        if self.region is not None:
            out &= self.region(points)
        return out

    def apply(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) float64: ``points`` (N, 3) mapped by the symmetry, ``A p + b``."""
        return np.asarray(points) @ self.A.T + self.b


def _mirror(theta: float, d: float) -> tuple[np.ndarray, np.ndarray]:
    n = np.array([np.cos(theta), 0.0, np.sin(theta)])
    return np.eye(3) - 2 * np.outer(n, n), 2 * d * n


def _rotation(angle: float, cx: float, cz: float) -> tuple[np.ndarray, np.ndarray]:
    c, s = np.cos(angle), np.sin(angle)
    A = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    centre = np.array([cx, 0.0, cz])
    return A, centre - A @ centre


class _Scorer:
    """Support (landing on the scan) and violation (landing in free space) of mapped points."""

    def __init__(self, points: np.ndarray, free: Callable[[np.ndarray], np.ndarray], cell: float):
        self.free = free
        self.cell = cell
        self.lo = points.min(axis=0) - 2 * cell
        idx = np.floor((points - self.lo) / cell).astype(np.int64)
        self.shape = idx.max(axis=0) + 3
        occ = np.zeros(tuple(self.shape), bool)
        occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
        self.occ = ndimage.binary_dilation(occ, np.ones((3, 3, 3), bool))

    def __call__(self, mapped: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Map (K, M, 3) mapped points -> support (K, M) bool, violation (K, M) bool."""
        K, M, _ = mapped.shape
        flat = np.ascontiguousarray(mapped, np.float64).reshape(-1, 3)
        sup = np.empty(len(flat), bool)
        off = np.empty(len(flat), bool)
        lookup(flat, np.eye(3), np.zeros(3), self.lo, self.cell, self.occ, False, sup, off)
        vio = self.free(flat)
        return sup.reshape(K, M), vio.reshape(K, M)


def _slab_ids(y: np.ndarray, top: float) -> np.ndarray:
    return np.clip((y / max(top, 1e-12) * SLABS).astype(np.int64), 0, SLABS - 1)


def _slab_score(sup: np.ndarray, vio: np.ndarray, slab: np.ndarray):
    """Per candidate: score, accepted slabs (K, SLABS) bool, support and violation over them.

    A slab (a band of heights) takes the copy when its own violation is at most
    MAX_VIOLATION and its support at least MIN_SUPPORT: a swivel chair's base turns
    independently of its seat, so a plane can hold above the base and fail on it.
    """
    M = sup.shape[1]
    onehot = np.zeros((M, SLABS))
    onehot[np.arange(M), slab] = 1.0
    n = onehot.sum(axis=0)
    ns = sup.astype(np.float64) @ onehot
    nv = vio.astype(np.float64) @ onehot
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = (n > 0) & (nv <= MAX_VIOLATION * n) & (ns >= MIN_SUPPORT * n)
    covered = (n * ok).sum(axis=1) / M
    s_sup = (ns * ok).sum(axis=1) / np.maximum((n * ok).sum(axis=1), 1)
    s_vio = (nv * ok).sum(axis=1) / np.maximum((n * ok).sum(axis=1), 1)
    score = ((ns - VIOLATION_WEIGHT * nv) * ok).sum(axis=1) / M
    return score, ok, covered, s_sup, s_vio


def mirror_planes(
    points: np.ndarray,
    colors: np.ndarray,
    free: Callable[[np.ndarray], np.ndarray],
    cell: float,
    *,
    max_planes: int = 2,
    normals: np.ndarray | None = None,
    seed: int = 0,
) -> list[Symmetry]:
    """Accepted vertical mirror planes, strongest first (at most ``max_planes``, at least 30
    degrees apart).

    points : (N, 3) upright points of the object; colors : (N, 3) uint8; free : callable on
    (M, 3) upright points -> (M,) bool; cell : the support tolerance, world units; normals :
    (N, 3) unit normals of the points, optional: with them each plane is refined below the
    voting grid (:func:`_refine_plane`).
    """
    rng = np.random.default_rng(seed)
    P = np.asarray(points, np.float64)
    C = np.asarray(colors, np.int64)
    pick = rng.choice(len(P), min(len(P), SAMPLES), replace=False)
    S, SC = P[pick], C[pick]
    scorer = _Scorer(P, free, cell)
    top = float(P[:, 1].max())
    # walls in plan, and not square: no mirror plane across their diagonal (see _best_plane)
    walls = None if normals is None else walls_direction(np.asarray(normals, np.float64))
    if walls is not None and _square_in_plan(P, walls, cell):
        walls = None  # square: its diagonal may be a mirror plane as well as the walls' own
    found: list[Symmetry] = []
    pts, cols = S, SC
    for _ in range(max_planes):
        taken = [s.params["theta"] for s in found]
        best = _best_plane(pts, cols, scorer, cell, rng, taken, top, walls)
        if best is None:
            break
        if normals is not None:
            best = _refine_plane(best, P, np.asarray(normals, np.float64), cell, free)
            # the heights where it holds, judged again with the plane where it now is
            plane = np.array([[best.params["theta"], best.params["offset"]]])
            sup, vio = scorer(_mirror_all(pts, plane))
            _, ok, covered, s_sup, s_vio = _slab_score(sup, vio, _slab_ids(pts[:, 1], top))
            if covered[0] >= MIN_COVER:
                best = Symmetry(
                    best.kind,
                    best.A,
                    best.b,
                    float(s_sup[0]),
                    float(s_vio[0]),
                    bands=_bands(ok[0], top),
                    params={**best.params, "cover": float(covered[0])},
                )
        found.append(_held_where_unseen(best, pts, scorer, top))
        # the next plane votes with the mirrored copy too (a table: left-right, then front-back)
        pts = np.concatenate([pts, best.apply(pts)])
        cols = np.concatenate([cols, cols])
        if len(pts) > 2 * SAMPLES:
            keep = rng.choice(len(pts), 2 * SAMPLES, replace=False)
            pts, cols = pts[keep], cols[keep]
    return found


def _held_where_unseen(sym: Symmetry, pts: np.ndarray, scorer: _Scorer, top: float) -> Symmetry:
    """``sym`` applied too at the heights where no copy of ``pts`` (M, 3) lands where a camera
    saw through, below the highest it was accepted at, where it holds with ``UNSEEN_SUPPORT``
    or more (over the heights it was accepted at, whose copies land on the scan): a band of
    heights whose copies land only where no camera looked says nothing against it, and says
    nothing for it. ``params`` records the heights it is applied at for that reason
    (``unseen_bands``).
    """
    if sym.support < UNSEEN_SUPPORT:
        return sym
    sup, vio = scorer(sym.apply(pts)[None])
    slab = _slab_ids(pts[:, 1], top)
    n = np.bincount(slab, minlength=SLABS)
    nv = np.bincount(slab, weights=vio[0].astype(np.float64), minlength=SLABS)
    ns = np.bincount(slab, weights=sup[0].astype(np.float64), minlength=SLABS)
    ok = (n > 0) & (nv <= MAX_VIOLATION * n)
    # only under the highest height where the copies land on the scan: what a top hides under
    # it, not what rises above it (a chair's back, copied across the plane its legs and seat
    # hold front to back, stood over the seat's front edge)
    held = np.flatnonzero(ok & (ns >= MIN_SUPPORT * n))
    ok &= np.arange(SLABS) <= (held.max() if len(held) else -1)
    bands = _bands(ok, top)
    added = [b for b in bands if b not in sym.bands]
    if not added:
        return sym
    return replace(sym, bands=bands, params={**sym.params, "unseen_bands": added})


def walls_direction(normals: np.ndarray) -> float | None:
    """The direction (radians, modulo a right angle) of the object's walls in plan: where at
    least ``WALL_SHARE`` of its upright faces' normals (``normals`` (N, 3) unit, upright)
    turn within ``WALL_SPREAD_DEG`` of one direction or the one square to it, their mean
    direction there; else None (a round object, or faces turned every way).

    Examples
    --------
    >>> import numpy as np
    >>> a = np.radians(20.0)
    >>> n = np.array([[np.cos(a), 0, np.sin(a)], [-np.sin(a), 0, np.cos(a)]] * 50)
    >>> round(float(np.degrees(walls_direction(n))), 3)
    20.0
    """
    side = np.flatnonzero(np.abs(normals[:, 1]) < 0.3)
    if len(side) < 50:
        return None
    phi = np.degrees(np.arctan2(normals[side, 2], normals[side, 0])) % 90.0
    hist = np.bincount(np.floor(phi).astype(np.int64) % 90, minlength=90)
    spread = int(WALL_SPREAD_DEG)
    window = np.array(
        [hist[np.arange(j - spread, j + spread + 1) % 90].sum() for j in range(90)], np.float64
    )
    best = int(np.argmax(window))
    if window[best] < WALL_SHARE * len(side):
        return None
    # the window's first degree of several as full (faces all at 20 degrees: 15.5): the mean
    # of the faces in it, on the circle a quarter turn long (their angles times four)
    near = np.abs((phi - (best + 0.5) + 45.0) % 90.0 - 45.0) <= WALL_SPREAD_DEG
    return float(np.angle(np.exp(4j * np.radians(phi[near])).mean())) / 4.0


def _square_in_plan(P: np.ndarray, walls: float, cell: float) -> bool:
    """Whether points ``P`` (N, 3) upright span as far along the walls' one direction
    (``walls``, radians) as along the other, within ``WALL_SQUARE_CELLS`` cells: a square
    stool or table, whose diagonal maps one side onto the other (a cabinet 60 by 64 cm is no
    square: its diagonal would carry its side 4 cm past its front).
    """
    u = np.array([np.cos(walls), np.sin(walls)])
    X = P[:, [0, 2]]
    along = float(np.ptp(X @ u))
    across = float(np.ptp(X @ np.array([-u[1], u[0]])))
    return abs(along - across) <= WALL_SQUARE_CELLS * cell


def _diagonal(theta: np.ndarray, walls: float) -> np.ndarray:
    """(K,) bool: plane normals ``theta`` (radians) within ``WALL_DIAGONAL_DEG`` of the
    diagonal between the walls' two directions.
    """
    off = np.degrees(np.asarray(theta) - walls) % 90.0
    return np.abs(off - 45.0) <= WALL_DIAGONAL_DEG


def _best_plane(S, SC, scorer, cell, rng, taken, top, walls=None) -> Symmetry | None:
    n = len(S)
    i = rng.integers(0, n, PAIRS)
    j = rng.integers(0, n, PAIRS)
    dp = S[j] - S[i]
    horiz = np.hypot(dp[:, 0], dp[:, 2])
    ok = (np.abs(dp[:, 1]) < cell) & (horiz > 2 * cell)
    ok &= np.abs(SC[j] - SC[i]).sum(axis=1) < 90
    if ok.sum() < 20:
        return None
    theta = np.arctan2(dp[ok, 2], dp[ok, 0]) % np.pi
    nx, nz = np.cos(theta), np.sin(theta)
    mid = (S[i[ok]] + S[j[ok]]) / 2
    d = mid[:, 0] * nx + mid[:, 2] * nz
    d_lo, d_hi = d.min(), d.max()
    n_t, n_d = 90, max(2, int(np.ceil((d_hi - d_lo) / cell)) + 1)
    hist, _, _ = np.histogram2d(theta, d, bins=(n_t, n_d), range=((0, np.pi), (d_lo, d_hi + 1e-9)))
    hist = ndimage.gaussian_filter(hist, 1.0, mode=("wrap", "constant"))
    peaks = hist == ndimage.maximum_filter(hist, size=5, mode=("wrap", "constant"))
    order = np.argsort(hist[peaks])[::-1][:12]
    ti, di = np.nonzero(peaks)
    peaks = []
    for k in order:
        t0 = (ti[k] + 0.5) * np.pi / n_t
        d0 = d_lo + (di[k] + 0.5) * (d_hi - d_lo + 1e-9) / n_d
        if any(_angle_gap(t0, t) < np.radians(30) for t in taken):
            continue
        # a box seen from a corner: the plane on its diagonal maps the face seen on one side
        # onto the face seen on the other, and holds best (all it copies lands on the scan),
        # where planes along its walls copy half of it into unseen space. A mirror across the
        # diagonal swaps the walls' two directions: it holds only for an object as long along
        # one as along the other, which one with ``walls`` is not (see mirror_planes)
        if walls is not None and _diagonal(np.array([t0]), walls)[0]:
            continue
        peaks.append((t0, d0))
    if not peaks:
        return None
    slab = _slab_ids(S[:, 1], top)
    # coarse to fine: the peaks as voted, then a fine grid around the best few of them
    sup, vio = scorer(_mirror_all(S, np.array(peaks)))
    score = _slab_score(sup, vio, slab)[0]
    cands = [
        (t0 + dt, d0 + dd)
        for t0, d0 in (peaks[i] for i in np.argsort(score)[::-1][:REFINE_PEAKS])
        for dt in np.radians(np.arange(-3, 4, 1.0))
        for dd in np.arange(-2, 2.01, 0.5) * cell
    ]
    sup, vio = scorer(_mirror_all(S, np.array(cands)))
    score, ok, covered, s_sup, s_vio = _slab_score(sup, vio, slab)
    best = int(np.argmax(np.where(covered >= MIN_COVER, score, -np.inf)))
    if covered[best] < MIN_COVER:
        return None
    t, d = _canonical(*cands[best])
    A, b = _mirror(t, d)
    return Symmetry(
        "mirror",
        A,
        b,
        float(s_sup[best]),
        float(s_vio[best]),
        bands=_bands(ok[best], top),
        params={"theta": float(t), "offset": float(d), "cover": float(covered[best])},
    )


def _mirror_fit(sym, P: np.ndarray, N: np.ndarray, cell: float):
    """``cost(refl)``: for reflections ``x -> A x + b`` (a list of ``(A, b)``), how far each
    carries the points where ``sym`` holds (at most ``REFINE_SAMPLES`` of them, a fixed-seed
    sample; returned too, (M, 3)) from scan points ``P`` whose normals ``N`` face the same
    way: (K,) the mean nearest distance, capped at ``cell`` so points without a counterpart
    weigh alike everywhere. All the reflections' points are searched at once: one k-d search
    and one start of its two threads a step, not one per reflection (the search's own work is
    the same; on slow scans the refinement took 2.3 s of calls in turn, 1.9 s batched).
    """
    from scipy.spatial import cKDTree

    w = sym.where(P)
    X, XN = P[w], N[w]
    if len(X) > REFINE_SAMPLES:
        k = np.random.default_rng(1).choice(len(X), REFINE_SAMPLES, replace=False)
        X, XN = X[k], XN[k]
    tree = cKDTree(P)

    def cost(refl: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
        A = np.stack([a for a, _ in refl])  # (K, 3, 3)
        b = np.stack([v for _, v in refl])  # (K, 3)
        moved = np.einsum("kij,nj->kni", A, X) + b[:, None, :]
        dist, nn = tree.query(
            moved.reshape(-1, 3), k=REFINE_NEIGHBOURS, distance_upper_bound=cell, workers=2
        )
        ok = np.isfinite(dist)
        turned = np.einsum("kij,nj->kni", A, XN).reshape(-1, 3)
        facing = np.einsum("nj,nkj->nk", turned, N[np.where(ok, nn, 0)]) > REFINE_FACING
        capped = np.where(ok & facing, dist, cell).min(axis=1)
        return capped.reshape(len(refl), len(X)).mean(axis=1)

    return cost, X


def _refine_plane(
    sym: Symmetry, P: np.ndarray, N: np.ndarray, cell: float, free: Callable | None = None
) -> Symmetry:
    """The plane moved to where the scan's mirrored points lie closest to scan points facing
    the same way (the mean distance, capped at ``cell``, so points without a counterpart weigh
    alike everywhere), searched below the voting grid in offset, then angle, then offset, at the
    heights where the plane holds. The voting grid alone leaves the plane up to a cell and a
    degree off, and a copy a voxel off costs about as much as a missing one. With ``free``
    (upright points (M, 3) -> (M,) bool, the space the cameras saw through), then centred on
    the plateau the free space allows where the fit is flat across it (:func:`_centred_in_free`).
    """
    fit, X = _mirror_fit(sym, P, N, cell)

    t, d = sym.params["theta"], sym.params["offset"]
    # coarse to fine: offset (cells), angle (degrees), offset again
    for what, steps in (
        ("d", np.linspace(-1.5, 1.5, 31)),
        ("t", np.linspace(-2.0, 2.0, 17)),
        ("d", np.linspace(-0.3, 0.3, 13)),
        ("t", np.linspace(-0.3, 0.3, 7)),
    ):
        if what == "d":
            cands = [(t, d + x * cell) for x in steps]
        else:
            cands = [(t + np.radians(x), d) for x in steps]
        t, d = cands[int(np.argmin(fit([_mirror(*c) for c in cands])))]
    if free is not None:
        d = _centred_in_free(t, d, X, fit, free, cell)
    t, d = _canonical(t, d)
    A, b = _mirror(t, d)
    return Symmetry(
        sym.kind,
        A,
        b,
        sym.support,
        sym.violation,
        bands=sym.bands,
        params={**sym.params, "theta": float(t), "offset": float(d)},
    )


def _centred_in_free(
    t: float, d: float, X: np.ndarray, fit: Callable, free: Callable, cell: float
) -> float:
    """The offset of plane ``(t, d)`` moved to the middle of the plateau of offsets whose
    copies of ``X`` (M, 3) land in ``free`` space least (within ``PLATEAU_SLACK``), where ``d``
    lies on it, the plateau ends within ``PLATEAU_STEPS`` on both sides, the fit (``fit``, the
    cost of :func:`_mirror_fit`) spreads less than ``PLATEAU_FLAT`` cells across it and its
    middle lies ``PLATEAU_MIN_MOVE`` cells or more off ``d``; else ``d``.

    A box seen from a front corner: its front mirrored onto itself lands on itself wherever the
    plane stands within it, and only the copies of the front's ends tell, beyond its far end or
    past the seen side, where the cameras saw through: the plane stands midway between where
    they begin to. The fit, flat, left Sweet Home's kitchen cabinet's plane 1.5 cm off and its
    mirrored side with it (F@1% 0.720 from one view; centred, 0.873). From three views the
    copies land somewhere in free space at every offset (noise along the seen faces): no
    plateau, and the fit places the plane.
    """
    xs = PLATEAU_STEPS
    copies = _mirror_all(X, np.stack([np.full(len(xs), t), d + xs * cell], axis=1))
    vio = free(copies.reshape(-1, 3)).reshape(len(xs), len(X)).mean(axis=1)
    ok = vio <= vio.min() + PLATEAU_SLACK
    i0 = int(np.argmin(np.abs(xs)))
    if not ok[i0]:
        return d
    lo, hi = i0, i0
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    while hi < len(xs) - 1 and ok[hi + 1]:
        hi += 1
    mid = float(xs[lo] + xs[hi]) / 2
    if lo == 0 or hi == len(xs) - 1 or abs(mid) < PLATEAU_MIN_MOVE:
        return d
    spread = float(np.ptp(fit([_mirror(t, d + x * cell) for x in xs[lo : hi + 1]]))) / cell
    return d + mid * cell if spread < PLATEAU_FLAT else d


def tilted_plane(
    sym: Symmetry, points: np.ndarray, normals: np.ndarray, cell: float
) -> tuple[np.ndarray, float]:
    """The mirror plane ``sym`` (vertical) tilted across itself, by up to ``MAX_PLANE_TILT_DEG``,
    to where the scan's mirrored points lie closest to scan points facing the same way (the
    cost of :func:`_refine_plane`): a mirror plane contains up, so where up came from weaker
    evidence than a floor its tilt measures how far up is off across the plane.

    points, normals : (N, 3) upright points and their unit normals; cell : the support
    tolerance, world units. Returns the tilted plane's unit normal (3,) and offset (its points
    ``p`` have ``normal @ p == offset``), in the upright frame.
    """
    P, N = np.asarray(points, np.float64), np.asarray(normals, np.float64)
    fit, X = _mirror_fit(sym, P, N, cell)
    t0, d0 = sym.params["theta"], sym.params["offset"]
    n0 = np.array([np.cos(t0), 0.0, np.sin(t0)])
    pivot = float(np.median(X[:, 1]))  # tilted about the plane's line at the points' mid-height

    def plane(phi, d):
        n = np.cos(phi) * n0 + np.sin(phi) * np.array([0.0, 1.0, 0.0])
        return n, d0 * np.cos(phi) + pivot * np.sin(phi) + d

    def reflection(phi, d):
        n, off = plane(phi, d)
        return np.eye(3) - 2 * np.outer(n, n), 2 * off * n

    phi, d = 0.0, 0.0
    lim = np.radians(MAX_PLANE_TILT_DEG)
    for what, steps in (
        ("t", np.radians(np.linspace(-MAX_PLANE_TILT_DEG, MAX_PLANE_TILT_DEG, 41))),
        ("d", np.linspace(-1.5, 1.5, 13) * cell),
        ("t", np.radians(np.linspace(-1.0, 1.0, 9))),
        ("d", np.linspace(-0.3, 0.3, 7) * cell),
    ):
        if what == "t":
            cands = [(float(np.clip(phi + x, -lim, lim)), d) for x in steps]
        else:
            cands = [(phi, d + x) for x in steps]
        phi, d = cands[int(np.argmin(fit([reflection(*c) for c in cands])))]
    return plane(phi, d)


def _canonical(theta: float, offset: float) -> tuple[float, float]:
    """The same plane with its angle in [0, pi) (the normal turned over flips the offset)."""
    k = np.floor(theta / np.pi)
    return float(theta - k * np.pi), float(offset * (-1.0) ** k)


def _mirror_all(S: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """(K, M, 3): points S (M, 3) mirrored in each vertical plane (theta, offset) of (K, 2)."""
    n = np.stack([np.cos(planes[:, 0]), np.zeros(len(planes)), np.sin(planes[:, 0])], axis=1)
    dist = S @ n.T - planes[:, 1]  # (M, K) signed distances to each plane
    return S[None] - 2 * dist.T[:, :, None] * n[:, None, :]


def _bands(ok: np.ndarray, top: float) -> tuple:
    """Height intervals of the accepted slabs (the lowest reaches below the floor, the highest
    above the top, so every point of those slabs is inside).
    """
    edges = np.linspace(0, top, SLABS + 1)
    edges[0], edges[-1] = -np.inf, np.inf
    return tuple((float(edges[i]), float(edges[i + 1])) for i in np.flatnonzero(ok))


def _angle_gap(a: float, b: float) -> float:
    g = abs(a - b) % np.pi
    return min(g, np.pi - g)


def rotation_axis(
    points: np.ndarray,
    free: Callable[[np.ndarray], np.ndarray],
    cell: float,
    *,
    folds: tuple[int, ...] = (5, 4),
    seed: int = 0,
) -> Symmetry | None:
    """The best accepted k-fold rotation (k in ``folds``) of the object's base about a vertical
    axis, or None. Its ``A``/``b`` are the rotation by one step (``fold`` steps make the turn).

    points : (N, 3) upright points; free : callable on (M, 3) upright points -> (M,) bool;
    cell : the support tolerance, world units.

    The base is the points below ``BASE_FRACTION`` of the height, cut into pieces (points within
    ``ROTATION_PIECE`` cells are one piece: a star base is one piece, scraps of floor or clutter
    beside it are others). The axis is searched coarse to fine on all of them, then again on the
    pieces the rotation holds for: a piece holds when at least ``MIN_ROTATION_SUPPORT`` of its
    points have a copy landing on the scan (a leg seen in part finds the other legs) and at most
    ``MAX_ROTATION_VIOLATION`` of its copies land where a camera saw through. The rotation is
    accepted when those pieces hold ``MIN_ROTATION_COVER`` of the base's points and its axis
    lies under the rest of the object (within the 2-98 percentile box of the points above the
    base, where there are any), and the base is a star: its arms in plan (:class:`_Arms`, at
    the footprint's own scale) radiate from the axis (:meth:`_Arms.radial` at least
    ``MIN_RADIAL``). It applies only
    in their region (``Symmetry.region``: their cells turned through every step, so a copy of a
    scrap beside the base is never made).
    """
    rng = np.random.default_rng(seed)
    P = np.asarray(points, np.float64)
    top = P[:, 1].max()
    below = BASE_FRACTION * top
    base = P[P[:, 1] < below]
    if len(base) < 50:
        return None
    if len(base) > ROTATION_SAMPLES:
        base = base[rng.choice(len(base), ROTATION_SAMPLES, replace=False)]
    from .floor import clusters

    # a base turns under what it carries: the axis lies within the footprint of the rest
    above = P[P[:, 1] >= below][:, [0, 2]]
    if len(above) >= 50:
        foot_lo, foot_hi = np.percentile(above, 2, axis=0), np.percentile(above, 98, axis=0)
        # a coarse grid's cell would let a 4-fold turn of a five-star land on its legs
        across = float((foot_hi - foot_lo).max()) / ROTATION_CELLS_ACROSS
        cell, arm_cell = min(cell, across), across
    else:
        foot_lo, foot_hi = np.full(2, -np.inf), np.full(2, np.inf)
        arm_cell = cell
    # a base that turns is a star: arms whose lines meet at a hub on the axis. A box, a plinth
    # or a table's frame also lands on itself turned about its middle where a side is seen (a
    # 4-fold turn of a rectangle puts its long side on its short one), and turned copies of
    # those stood off the object in unseen space (the wide benchmark's cabinets, desks, sofas):
    # without arms, no turn is searched; with them, it must turn about where they radiate from
    arms = _Arms.of(base, arm_cell, np.random.default_rng(seed + 1))
    if arms is None:
        return None
    piece = clusters(base, ROTATION_PIECE * cell)
    scorer = _Scorer(base, free, cell)
    bounds = (foot_lo, foot_hi)
    found = []
    for k in folds:
        turn = _turn(base, piece, scorer, cell, k, rng, bounds)
        if turn is not None:
            found.append((k, *turn))
    if not found:
        return None
    radial = max(arms.radial(f[2]) for f in found)
    if radial < MIN_RADIAL:
        return None
    # a star's legs point at its hub, and the angles between them give its fold, however few
    # are seen and wherever the copies land: two straight legs map onto each other about any
    # point of their bisector, where a fold of the wrong count can land better
    fold = arms.fold(tuple(f[0] for f in found)) if len(found) > 1 else None
    if fold is not None:
        found = [f for f in found if f[0] == fold]
    best = None
    for k, score, centre, held, sup, vio in found:
        if best is None or score > best[0]:
            A, b = _rotation(2 * np.pi / k, *centre)
            region = _Region.around(base[held], centre, k, ROTATION_PIECE * cell)
            best = (
                score,
                Symmetry(
                    "rotation",
                    A,
                    b,
                    float(sup.any(axis=0).mean()),
                    float(vio.mean()),
                    fold=k,
                    bands=((-np.inf, float(below)),),
                    params={
                        "fold": k,
                        "axis_x": float(centre[0]),
                        "axis_z": float(centre[1]),
                        "cover": float(held.mean()),
                    },
                    region=region,
                ),
            )
    return None if best is None else best[1]


def _turn(base, piece, scorer, cell, k, rng, bounds):
    """(score, centre (2,), held (M,) bool, support, violation) of the k-fold turn of the base
    points (M, 3) about the axis the search places within ``bounds`` (lo, hi), or None where
    the rotation is refused.
    """
    foot_lo, foot_hi = bounds
    centre = _rotation_search(base, scorer, cell, k, rng, None, bounds)
    held = _pieces_held(base, piece, scorer, centre, k)
    if not held.any():
        return None
    # again on what the rotation holds for, from where the first search ended
    centre = _rotation_search(base[held], scorer, cell, k, rng, centre, bounds)
    held = _pieces_held(base, piece, scorer, centre, k)
    if held.mean() < MIN_ROTATION_COVER or not ((centre >= foot_lo) & (centre <= foot_hi)).all():
        return None
    # a turning base is one piece whose arms meet at a hub on the axis (four legs of a
    # table, each a piece of its own, are not)
    r = np.hypot(base[held, 0] - centre[0], base[held, 2] - centre[1])
    if r.min() > HUB_SHARE * r.max():
        return None
    # the axis placed by exact copies (the slack finds it, but copies are made exact)
    centre = _rotation_search(base[held], scorer, cell, k, rng, centre, bounds, slack=False)
    # the fold is chosen on exact copies: with the slack a 4-fold turn of a five-star
    # lands on legs often enough to look as good
    sup, vio = _copies_on(base[held], scorer, centre, k, slack=False)
    return float(held.mean() * (sup.mean() - VIOLATION_WEIGHT * vio.mean())), centre, held, sup, vio


@dataclass(frozen=True, eq=False)
class _Arms:
    """The base's arms seen from above: points (M, 2) (x, z) on elongated stretches and their
    directions (M, 2), and the hub (2,) where most of their lines meet.
    """

    X: np.ndarray
    d: np.ndarray
    cell: float
    hub: np.ndarray

    @classmethod
    def of(cls, base: np.ndarray, cell: float, rng) -> _Arms | None:
        """The arms of the base points (N, 3), or None where they do not meet from at least two
        directions (no elongated stretches, or parallel ones).
        """
        X = base[:, [0, 2]]
        pairs = cKDTree(X).query_pairs(ARM_REACH * cell, output_type="ndarray")
        # each point's neighbourhood covariance in plan, summed over the pairs (and itself)
        n, sums = _pair_sums(X, pairs)
        mx, mz = sums[0] / n, sums[1] / n
        a = sums[2] / n - mx * mx
        b = sums[3] / n - mx * mz
        c = sums[4] / n - mz * mz
        half = np.sqrt(np.maximum(((a - c) / 2) ** 2 + b * b, 0.0))
        major, minor = (a + c) / 2 + half, (a + c) / 2 - half
        on = (n >= 6) & (1.0 - minor / np.maximum(major, 1e-300) >= ARM_LINEARITY)
        if on.sum() < 20:  # a few stray points are no arm
            return None
        theta = 0.5 * np.arctan2(2 * b[on], a[on] - c[on])
        d = np.stack([np.cos(theta), np.sin(theta)], axis=1)
        X = X[on]
        if len(X) > ARM_SAMPLES:
            keep = rng.choice(len(X), ARM_SAMPLES, replace=False)
            X, d = X[keep], d[keep]
        # the hub: coarse over the base's footprint, then finer around the best
        lo, hi = X.min(axis=0), X.max(axis=0)
        axes = np.stack(
            np.meshgrid(*(np.arange(lo[q], hi[q] + cell, cell) for q in (0, 1)), indexing="ij"),
            axis=-1,
        ).reshape(-1, 2)
        hub = axes[int(np.argmax(_arm_votes(axes, X, d, cell).sum(axis=1)))]
        fine = np.arange(-4, 5) * cell / 4
        axes = hub + np.stack(np.meshgrid(fine, fine, indexing="ij"), axis=-1).reshape(-1, 2)
        v = _arm_votes(axes, X, d, cell)
        best = int(np.argmax(v.sum(axis=1)))
        # the voters must point along at least two directions (doubled angles: a line's
        # direction has no sign)
        dd = d[v[best]]
        if len(dd) == 0:
            return None
        twice = np.exp(2j * np.arctan2(dd[:, 1], dd[:, 0]))
        if abs(twice.mean()) > ARM_PARALLEL:
            return None
        return cls(X, d, cell, axes[best])

    def radial(self, centre: np.ndarray) -> float:
        """Mean |cosine| between the arm points' directions and their direction from ``centre``
        (2,) (x, z), over the points beyond ``ARM_REACH`` cells of it: 1 for arms radiating
        from it.
        """
        v = self.X - centre
        r = np.hypot(v[:, 0], v[:, 1])
        far = r >= ARM_REACH * self.cell
        if not far.any():
            return 0.0
        cos = (v[far, 0] * self.d[far, 0] + v[far, 1] * self.d[far, 1]) / r[far]
        return float(np.abs(cos).mean())

    def fold(self, folds: tuple[int, ...]) -> int | None:
        """The fold in ``folds`` whose step the angles between the arms about the hub are
        multiples of, within ``ARM_FOLD_DEG`` (each arm counts once, however much of it is
        seen), where exactly one fold fits; else None.
        """
        v = self.X - self.hub
        far = np.hypot(v[:, 0], v[:, 1]) >= ARM_REACH * self.cell
        phi = np.sort(np.degrees(np.arctan2(v[far, 1], v[far, 0])))
        if len(phi) < 2:
            return None
        # arms: runs of angles without a gap wider than ARM_GAP_DEG, round the circle
        gaps = np.diff(np.append(phi, phi[0] + 360.0))
        cuts = np.flatnonzero(gaps > ARM_GAP_DEG)
        if len(cuts) < 2:
            return None  # one arm (or a ring of points): no angle between arms
        # arm i runs from after cut i to cut i + 1; the last wraps past 180 degrees
        start = cuts + 1
        ends = np.append(cuts[1:], cuts[0] + len(phi))
        unwrapped = np.concatenate([phi, phi + 360.0])
        arm = [unwrapped[i : j + 1] for i, j in zip(start, ends, strict=True)]
        arm = [np.mean(a) for a in arm if len(a) >= ARM_MIN_POINTS]
        if len(arm) < 2:
            return None
        between = (np.array(arm)[:, None] - np.array(arm)[None])[np.triu_indices(len(arm), 1)]
        fits = []
        for k in folds:
            step = 360.0 / k
            off = np.abs(between - step * np.round(between / step))
            if off.max() <= ARM_FOLD_DEG:
                fits.append(k)
        return fits[0] if len(fits) == 1 else None


@numba.njit(cache=True)
def _pair_sums(X, pairs):
    """Each point's count of neighbours (itself included) and (5, M) sums over them of the
    offsets (dx, dz), dx^2, dx dz and dz^2 (offsets keep the sums well conditioned), for
    points X (M, 2) float64 and neighbour ``pairs`` (P, 2) int (i < j, each once).

    A pair adds to both its points: in the order ``np.bincount`` would add over every pair
    (i, j), then every (j, i), so the sums are the same bit for bit; each point is its own
    neighbour at offset zero, which counts but adds nothing. One pass over the pairs instead of
    a gathered (2P, 2) array of offsets (1.1 million pairs of a cabinet's walls seen from
    above: 0.2 s).
    """
    m = X.shape[0]
    n = np.ones(m)
    out = np.zeros((5, m))
    for way in range(2):
        for k in range(pairs.shape[0]):
            i, j = pairs[k, way], pairs[k, 1 - way]
            dx, dz = X[j, 0] - X[i, 0], X[j, 1] - X[i, 1]
            out[0, i] += dx
            out[1, i] += dz
            out[2, i] += dx * dx
            out[3, i] += dx * dz
            out[4, i] += dz * dz
            n[i] += 1.0
    return n, out


def _arm_votes(axes: np.ndarray, X: np.ndarray, d: np.ndarray, cell: float) -> np.ndarray:
    """(C, M) bool: the arm points X (M, 2) of direction d (M, 2) whose line passes within
    ``ARM_TOLERANCE`` cells of each axis (C, 2), from beyond their own neighbourhood.
    """
    v = axes[:, None, :] - X[None]
    along = np.abs(v[..., 0] * d[:, 0] + v[..., 1] * d[:, 1])
    across = np.abs(v[..., 1] * d[:, 0] - v[..., 0] * d[:, 1])
    return (across <= ARM_TOLERANCE * cell) & (along >= 2 * ARM_REACH * cell)


def _copies_on(X, scorer, centre, k, slack=True) -> tuple[np.ndarray, np.ndarray]:
    """(k-1, M) bool support and violation of the copies of X (M, 3) by the k-fold rotation
    about the vertical axis through ``centre`` (x, z).
    """
    sup, vio = _copies_scored(X, scorer, np.asarray(centre)[None], k, slack)
    return sup[0], vio[0]


def _copies_scored(X, scorer, centres, k, slack=True) -> tuple[np.ndarray, np.ndarray]:
    """(C, k-1, M) bool support and violation of the k-fold copies of X (M, 3) about each axis
    of ``centres`` (C, 2). A real base is turned by its steps only to within a few degrees (and
    a long leg a degree off lands beside its neighbour): a copy is supported when one of the
    steps turned by up to ``ROTATION_SLACK_DEG`` lands on the scan, and seen through when all
    of them land in free space.
    """
    turn = np.array([-1.0, -0.5, 0.0, 0.5, 1.0]) if slack else np.zeros(1)
    slack = np.radians(ROTATION_SLACK_DEG) * turn
    angles = (2 * np.pi * np.arange(1, k) / k)[:, None] + slack  # (k-1, J)
    c, s = np.cos(angles), np.sin(angles)
    C = np.asarray(centres, np.float64)
    x = X[:, 0][None, None, None] - C[:, 0, None, None, None]
    z = X[:, 2][None, None, None] - C[:, 1, None, None, None]
    c, s = c[None, :, :, None], s[None, :, :, None]
    # _rotation: x' = c x + s z, z' = -s x + c z about the axis
    mx = c * x + s * z + C[:, 0, None, None, None]
    mz = -s * x + c * z + C[:, 1, None, None, None]
    my = np.broadcast_to(X[:, 1], mx.shape)
    mapped = np.stack([mx, my, mz], axis=-1)  # (C, k-1, J, M, 3)
    n, J, M = len(C), len(slack), len(X)
    sup, vio = scorer(mapped.reshape(n, -1, 3))
    sup = sup.reshape(n, k - 1, J, M).any(axis=2)
    vio = vio.reshape(n, k - 1, J, M).all(axis=2)
    return sup, vio


def _pieces_held(base, piece, scorer, centre, k) -> np.ndarray:
    """(M,) bool: the base points in the pieces the rotation holds for."""
    sup, vio = _copies_on(base, scorer, centre, k)
    n = np.bincount(piece).astype(np.float64)
    found = np.bincount(piece, sup.any(axis=0)) / n
    seen_through = np.bincount(piece, vio.mean(axis=0)) / n
    ok = (found >= MIN_ROTATION_SUPPORT) & (seen_through <= MAX_ROTATION_VIOLATION)
    return ok[piece]


def _rotation_search(X, scorer, cell, k, rng, centre, bounds, slack=True) -> np.ndarray:
    """(2,) the axis (x, z) where k-fold copies of X (M, 3) land best (support minus weighted
    violation), coarse to fine over X's footprint within ``bounds`` (lo, hi), or around
    ``centre`` when given.
    """
    B = X[rng.choice(len(X), min(len(X), 300), replace=False)]
    lo = np.maximum(B[:, [0, 2]].min(axis=0), bounds[0])
    hi = np.minimum(B[:, [0, 2]].max(axis=0), bounds[1])
    hi = np.maximum(hi, lo)
    step = max(cell, (hi - lo).max() / 16)
    if centre is not None:
        step = max(cell, step / 3)
    for _ in range(3):
        if centre is None:
            xs = np.arange(lo[0], hi[0] + step, step)
            zs = np.arange(lo[1], hi[1] + step, step)
        else:
            xs = centre[0] + np.arange(-3, 4) * step
            zs = centre[1] + np.arange(-3, 4) * step
        gx, gz = np.meshgrid(xs, zs, indexing="ij")
        axes = np.stack([gx.ravel(), gz.ravel()], axis=1)
        sup, vio = _copies_scored(B, scorer, axes, k, slack)
        score = sup.mean(axis=(1, 2)) - VIOLATION_WEIGHT * vio.mean(axis=(1, 2))
        centre = axes[int(np.argmax(score))]
        step /= 3
    return centre


@dataclass(frozen=True, eq=False)
class _Region:
    """Where a rotation holds: occupied cells (size ``cell``) of a boolean grid from ``lo``."""

    lo: np.ndarray
    cell: float
    occ: np.ndarray

    @classmethod
    def around(cls, X: np.ndarray, centre, k: int, cell: float) -> _Region:
        """The cells of X (M, 3) turned through every step of the k-fold rotation, grown by one."""
        turned = np.concatenate(
            [X @ A.T + b for A, b in (_rotation(2 * np.pi * i / k, *centre) for i in range(k))]
        )
        lo = turned.min(axis=0) - 2 * cell
        idx = np.floor((turned - lo) / cell).astype(np.int64)
        occ = np.zeros(tuple(idx.max(axis=0) + 3), bool)
        occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
        return cls(lo, cell, ndimage.binary_dilation(occ, np.ones((3, 3, 3), bool)))

    def __call__(self, points: np.ndarray) -> np.ndarray:
        idx = np.floor((np.asarray(points) - self.lo) / self.cell).astype(np.int64)
        ok = ((idx >= 0) & (idx < self.occ.shape)).all(axis=1)
        idx = np.where(ok[:, None], idx, 0)
        return ok & self.occ[idx[:, 0], idx[:, 1], idx[:, 2]]


def _circle(x: np.ndarray, z: np.ndarray) -> tuple[float, float, float]:
    """The circle (cx, cz, r) through points (x, z) (M,) each, by algebraic least squares."""
    A = np.stack([x, z, np.ones_like(x)], axis=1)
    (d, e, f), *_ = np.linalg.lstsq(A, -(x * x + z * z), rcond=None)
    cx, cz = -d / 2.0, -e / 2.0
    return float(cx), float(cz), float(np.sqrt(max(cx * cx + cz * cz - f, 0.0)))


@dataclass(frozen=True)
class _Section:
    """A level slab's fit: its circle's centre (2,) and radius, whether it is round
    (:func:`_section`) and the azimuths (K,) of its side faces' normals.
    """

    centre: np.ndarray
    radius: float
    round: bool
    azimuths: np.ndarray


def _section(P: np.ndarray, N: np.ndarray, cell: float) -> _Section:
    """The fit of one slab's points P (M, 3) with normals N (M, 3), upright: round when its
    points span ``ROUND_SPAN_DEG`` of arc about their circle, lie within ``ROUND_RESIDUAL`` of
    its radius of it, the circle is ``ROUND_MIN_RADIUS`` cells wide or more and the side faces
    turn out from its centre (``ROUND_FACING_SHARE``).
    """
    x, z = P[:, 0], P[:, 2]
    cx, cz, r = _circle(x, z)
    d = np.hypot(x - cx, z - cz)
    side = np.abs(N[:, 1]) < 0.5
    az = np.arctan2(N[side, 2], N[side, 0])
    ok = r >= ROUND_MIN_RADIUS * cell and side.sum() >= ROUND_MIN_POINTS // 2
    if ok:
        th = np.sort(np.arctan2(z - cz, x - cx))
        gap = np.diff(np.append(th, th[0] + 2 * np.pi)).max()
        out = (np.cos(az) * (x[side] - cx) + np.sin(az) * (z[side] - cz)) / np.maximum(
            d[side], 1e-12
        )
        ok = bool(
            np.degrees(2 * np.pi - gap) >= ROUND_SPAN_DEG
            and np.median(np.abs(d - r)) <= ROUND_RESIDUAL * r
            and (out >= ROUND_FACING).mean() >= ROUND_FACING_SHARE
        )
    return _Section(np.array([cx, cz]), r, ok, az)


def _common_centre(P: np.ndarray, slab: np.ndarray, slabs: list[int]) -> np.ndarray:
    """(2,) the centre (x, z) of the circles through the points P (N, 3) of each of ``slabs``
    (ids in ``slab`` (N,)) about one centre, each its own radius (algebraic least squares).
    """
    m = np.isin(slab, slabs)
    x, z = P[m, 0], P[m, 2]
    own = (slab[m][:, None] == np.asarray(slabs)[None, :]).astype(np.float64)
    A = np.concatenate([x[:, None], z[:, None], own], axis=1)
    sol, *_ = np.linalg.lstsq(A, -(x * x + z * z), rcond=None)
    return np.array([-sol[0] / 2.0, -sol[1] / 2.0])


def _within(Q: np.ndarray, centre: np.ndarray, radius: float, cell: float) -> bool:
    """Whether a slab's points Q (M, 2) (x, z) belong to the round part about ``centre`` (2,):
    within its widest circle (``radius``; a lid, a foot), and where they are as thin as a pole
    (within ``ROUND_MIN_RADIUS`` cells of their mean), their mean within a cell of the axis (off
    it, up is askew, and turned about a level axis a pole sweeps a cone).
    """
    if not len(Q):
        return False
    if (np.hypot(*(Q - centre).T) <= 1.1 * radius + cell).mean() < 0.95:
        return False
    mean = Q.mean(axis=0)
    if np.hypot(*(Q - mean).T).max() > ROUND_MIN_RADIUS * cell:
        return True
    return bool(np.hypot(*(mean - centre)) <= cell)


def _on_axis(fit: _Section, centre: np.ndarray, cell: float) -> bool:
    """Whether a slab's circle ``fit`` is centred on the axis at ``centre`` (2,): within
    ``ROUND_AXIS`` of its radius, or a cell.
    """
    return bool(np.hypot(*(fit.centre - centre)) <= max(ROUND_AXIS * fit.radius, cell))


def _fold_of(azimuths: np.ndarray) -> int:
    """The fold of a regular polygon whose faces point along ``azimuths`` (K,) radians: the k
    in 3..12 whose k-th circular moment ``|mean exp(i k phi)|`` is highest (all the faces'
    directions a multiple of 360/k degrees apart: 1), the least of those within 5 % of it (a
    hexagon's faces are also 12-fold), where it is at least ``ROUND_POLYGON``; a circle's (no
    such k): ``ROUND_FOLD``.

    >>> _fold_of(np.radians(np.repeat([0.0, 45.0, 90.0], 20)))
    8
    >>> _fold_of(np.radians(np.linspace(0.0, 150.0, 60)))
    8
    >>> _fold_of(np.radians(np.repeat([10.0, 70.0, 130.0], 20)))
    6
    """
    moment = np.array([abs(np.exp(1j * k * azimuths).mean()) for k in range(3, 13)])
    if moment.max() < ROUND_POLYGON:
        return ROUND_FOLD
    return 3 + int(np.flatnonzero(moment >= 0.95 * moment.max())[0])


def revolution(
    points: np.ndarray,
    normals: np.ndarray,
    free: Callable[[np.ndarray], np.ndarray],
    cell: float,
) -> Symmetry | None:
    """The turn of a round object about its vertical axis, or None.

    points, normals : (N, 3) upright (y up, the floor at 0) points and their unit normals;
    free : callable on (M, 3) upright points -> (M,) bool, the space a camera saw through;
    cell : the support tolerance, world units.

    The object's height is cut into ``ROUND_SLABS`` level slabs; each is fitted a circle
    (:func:`_section`). The round slabs whose centres agree (within ``ROUND_AXIS`` of their
    radius of the median centre) place the axis: their circles fitted about one centre
    (:func:`_common_centre`). The whole turns when they hold ``ROUND_SHARE`` of the points
    and, with the slabs that lie within their widest circle (:func:`_within`: a lid, a foot, a
    pole on the axis), ``ROUND_HELD``, where ``ROUND_SUPPORT`` of the turned copies land on
    the scan and at most ``ROUND_VIOLATION`` where a camera saw through. The turn's step is a
    regular polygon's (:func:`_fold_of` on the round slabs' side faces) or a circle's
    ``ROUND_FOLD``; it applies at the heights of those slabs (``Symmetry.bands``).

    Examples
    --------
    A round bin's front seen from one side: a half cylinder of radius 0.2 m, faces turned out.

    >>> t = np.linspace(-1.2, 1.2, 60)
    >>> y = np.linspace(0.0, 0.6, 30)
    >>> T, Y = np.meshgrid(t, y)
    >>> P = np.stack([0.2 * np.sin(T), Y, 0.2 * np.cos(T)], axis=-1).reshape(-1, 3)
    >>> N = np.stack([np.sin(T), 0 * T, np.cos(T)], axis=-1).reshape(-1, 3)
    >>> turn = revolution(P, N, lambda q: np.zeros(len(q), bool), 0.01)
    >>> turn.fold, abs(turn.params["axis_x"]) < 1e-6, abs(turn.params["axis_z"]) < 1e-6
    (8, True, True)
    """
    P, N = np.asarray(points, np.float64), np.asarray(normals, np.float64)
    top = float(P[:, 1].max())
    if len(P) < ROUND_MIN_POINTS or top <= 0:
        return None
    slab = np.clip((P[:, 1] / top * ROUND_SLABS).astype(np.int64), 0, ROUND_SLABS - 1)
    of = [slab == k for k in range(ROUND_SLABS)]
    fits = {
        k: _section(P[m], N[m], cell)
        for k, m in enumerate(of)
        if np.count_nonzero(m) >= ROUND_MIN_POINTS
    }
    found = [k for k, f in fits.items() if f.round]
    if not found:
        return None
    centre = np.median([fits[k].centre for k in found], axis=0)
    found = [k for k in found if _on_axis(fits[k], centre, cell)]
    if not found:
        return None
    # one axis for them all: their circles fitted about a shared centre
    centre = _common_centre(P, slab, found)
    found = [k for k in found if _on_axis(fits[k], centre, cell)]
    if not found:
        return None
    radius = max(fits[k].radius for k in found)
    within = [
        k
        for k in range(ROUND_SLABS)
        if k not in found and _within(P[of[k]][:, [0, 2]], centre, radius, cell)
    ]
    held = np.isin(slab, found + within)
    if np.isin(slab, found).mean() < ROUND_SHARE or held.mean() < ROUND_HELD:
        return None
    fold = _fold_of(np.concatenate([fits[k].azimuths for k in found]))
    A, b = _rotation(2 * np.pi / fold, *centre)
    copies = [P[held]]
    for _ in range(fold - 1):
        copies.append(copies[-1] @ A.T + b)
    sup, vio = _Scorer(P, free, cell)(np.stack(copies[1:]))
    if sup.mean() < ROUND_SUPPORT or vio.mean() > ROUND_VIOLATION:
        return None
    return Symmetry(
        "rotation",
        A,
        b,
        float(sup.mean()),
        float(vio.mean()),
        fold=fold,
        bands=_slab_bands(sorted(found + within), top),
        params={
            "fold": fold,
            "axis_x": float(centre[0]),
            "axis_z": float(centre[1]),
            "radius": float(radius),
            "round": True,
        },
    )


def _slab_bands(slabs: list[int], top: float) -> tuple:
    """The height intervals of the runs of consecutive ``slabs`` (sorted ids of
    ``ROUND_SLABS`` slabs up to ``top``), the lowest open below and the highest above.
    """
    bands: list[list[float]] = []
    for k in slabs:
        lo = -np.inf if k == 0 else k * top / ROUND_SLABS
        hi = np.inf if k == ROUND_SLABS - 1 else (k + 1) * top / ROUND_SLABS
        if bands and bands[-1][1] == lo:
            bands[-1][1] = hi
        else:
            bands.append([lo, hi])
    return tuple((a, b) for a, b in bands)
