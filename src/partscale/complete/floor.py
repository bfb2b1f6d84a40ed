"""The floor: a RANSAC plane that gives "up" and the support bound, and what stands on it.

A floor is a plane whose normal lies within ``MAX_TILT_DEG`` of the up prior (the camera's
negative y axis), with at least ``MIN_INLIER_FRACTION`` of the points on it and almost none below
it (a desk top has the floor and the chairs below it; the floor has only noise). Without a floor,
the plane of an object's base (:func:`base_plane`) gives up, within the same bound of the prior.
Furniture's faces are mostly level or upright: the direction most of a scan's flat patches lie
square to (:func:`faces_up`) is up, found without a floor and, where it is clear, the prior the
floor is searched near (a camera pitched far down sees the floor far off its own axis).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy import ndimage

MAX_TILT_DEG = 40.0
WIDE_TILT_DEG = 60.0
"""Degrees between the floor's normal and the up prior in the second search of a full sensor
frame that found no floor within ``MAX_TILT_DEG``: a camera held pitched 45 degrees down at an
object (a handheld scan from above) sees the floor 45 degrees off its own axis."""
STANDS_WITHIN = 0.15
"""Metres above the floor within which something stands on it: a cluster picked first when
isolating an object automatically, and a result said to stand above the floor seen beyond it
(:func:`partscale.complete.guard.caveats`: what holds it up was not seen)."""
MIN_INLIER_FRACTION = 0.04
MAX_BELOW_FRACTION = 0.03
ITERATIONS = 600
FACES_SAMPLE = 6000
"""Scan points whose neighbourhoods' flatness and normals :func:`faces_up` reads."""
FACES_NEIGHBOURS = 12
FACES_FLAT = 0.05
"""A neighbourhood is a flat patch where its least spread (variance) is at most this share of
the next."""
FACES_SIGMA_DEG = 3.0
"""Degrees of a patch's normal from level or upright over which its vote falls to 0.61."""
FACES_PITCH_DEG = (-40.0, 85.0)
"""Camera pitches (degrees down) :func:`faces_up` searches: from looking up at a tall shelf to
looking almost straight down."""
FACES_ROLL_DEG = 15.0
"""Largest roll of the camera about its axis that :func:`faces_up` searches (hand-held)."""
FACES_MIN_SCORE = 0.17
"""The least mean vote (0 to 1.5: each patch votes up to 1 for level and
``FACES_UPRIGHT_VOTE`` for upright) at which the faces give up."""
FACES_MIN_LEVEL = 0.02
"""The least mean level vote at which the faces give up: upright faces alone leave it open
(a box's front seen level pins only the plane up lies in) or mislead (a lamp's shade, a shallow
cone, seen from 15 degrees above held its normals square to an up 10 degrees off)."""
FACES_UPRIGHT_VOTE = 0.5
"""An upright patch's vote against a level one's (1): level pins up to its normal, upright
only to a circle square to it (the normals round a cylinder, a rolled cushion along a bench,
are all square to its axis, which would take their upright votes for up)."""
FACES_DOWN = 0.02
"""Mean level vote facing down (less that facing up) above which a candidate is the quarter
turn off up: its level faces are the object's fronts, seen from below."""
VOTES_BLOCK = 256
"""Directions whose votes for all the candidates up are reckoned at once (:func:`_votes`)."""
VOTES_CUT = 20.0
"""A direction's vote for a candidate below exp(-VOTES_CUT) of its weight counts as none."""
FACES_TILT_COST = 0.0005
FACES_ROLL_COST = 0.002
"""Vote per degree of pitch and of roll away from the camera's own up that a candidate pays:
where the faces leave up open (a box's front seen level constrains only the plane up lies in)
the camera's up, held level, wins."""
BASE_MIN_SHARE = 0.03
"""Share of an object's points its base must hold to give up (:func:`base_plane`)."""
BASE_MAX_FLATNESS = 0.5
"""A base gives up when its spread across its plane is at most this share of its spread along
its narrower side (the TUM purple chair's two legs seen: 0.45; the yellow chair's star: 0.2)."""


@dataclass(frozen=True)
class Plane:
    """Points ``p`` with ``normal @ p == offset``; ``normal`` (3,) unit, pointing up."""

    normal: np.ndarray
    offset: float

    def height(self, points: np.ndarray) -> np.ndarray:
        """(N,) signed height of ``points`` (N, 3) above the plane."""
        return np.asarray(points) @ self.normal - self.offset


def _fit(points: np.ndarray, up: np.ndarray) -> Plane:
    c = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c, full_matrices=False)
    n = vt[-1]
    n = n if n @ up >= 0 else -n
    return Plane(n, float(n @ c))


def find_floor(
    points: np.ndarray,
    up_prior: np.ndarray,
    tol: float,
    *,
    seed: int = 0,
    max_tilt: float = MAX_TILT_DEG,
):
    """The floor plane of a scene, or None.

    Parameters
    ----------
    points : (N, 3) float64
        World points of the whole scan.
    up_prior : (3,) float64
        Expected up direction (the camera's -y axis in the world).
    tol : float
        Inlier distance, world units.
    seed : int
        Seed of the RANSAC samples.
    max_tilt : float
        Degrees the floor's normal may lie from ``up_prior``.

    Returns
    -------
    (Plane, (N,) bool inliers) or None when no plane qualifies.
    """
    P = np.asarray(points, np.float64)
    if len(P) < 50:
        return None
    up = np.asarray(up_prior, np.float64)
    up = up / np.linalg.norm(up)
    rng = np.random.default_rng(seed)
    sub = P[rng.choice(len(P), min(len(P), 4000), replace=False)]
    tri = sub[rng.integers(0, len(sub), (ITERATIONS, 3))]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(n, axis=1)
    ok = norm > 1e-12
    n = n[ok] / norm[ok, None]
    tri = tri[ok]
    n *= np.where(n @ up >= 0, 1.0, -1.0)[:, None]
    ok = n @ up >= np.cos(np.radians(max_tilt))
    n, tri = n[ok], tri[ok]
    if len(n) == 0:
        return None
    off = np.einsum("kd,kd->k", n, tri[:, 0])
    h = sub @ n.T - off  # (S, K) heights
    inl = (np.abs(h) <= tol).mean(axis=0)
    below = (h < -3 * tol).mean(axis=0)
    good = (inl >= MIN_INLIER_FRACTION) & (below <= MAX_BELOW_FRACTION)
    if not good.any():
        return None
    best = int(np.argmax(np.where(good, inl, -1)))
    plane = Plane(n[best], float(off[best]))
    for _ in range(2):  # least-squares refinement on the inliers
        inliers = np.abs(plane.height(P)) <= tol
        plane = _fit(P[inliers], up)
    inliers = np.abs(plane.height(P)) <= tol
    if np.degrees(np.arccos(np.clip(plane.normal @ up, -1, 1))) > max_tilt:
        return None
    return plane, inliers


def clusters(points: np.ndarray, cell: float) -> np.ndarray:
    """(N,) int labels (0..C-1) of 26-connected clusters of ``points`` at ``cell`` resolution."""
    P = np.asarray(points)
    lo = P.min(axis=0)
    idx = np.floor((P - lo) / cell).astype(np.int64)
    shape = idx.max(axis=0) + 1
    if np.prod(shape) > 64e6:  # huge scenes: coarser cells keep the grid in memory
        return clusters(points, cell * float(np.cbrt(np.prod(shape) / 64e6)) * 1.01)
    occ = np.zeros(tuple(shape), bool)
    occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    lab, _ = ndimage.label(occ, structure=np.ones((3, 3, 3), bool))
    return lab[idx[:, 0], idx[:, 1], idx[:, 2]] - 1


def floor_scraps(points: np.ndarray, plane: Plane, tol: float, cell: float, margin: float):
    """(N,) bool: the pieces of ``points`` (N, 3) that are floor left beside an object.

    A scan cut at the floor keeps scraps of it (strips beside the base the cut missed). The
    points are cut into pieces (26-connected at ``cell``); a piece is floor when most of its
    points lie within ``2 * tol`` of ``plane`` (the level plane under the object) and most of
    those stand outside the footprint of the other pieces' points above that height, grown by
    ``margin`` (a caster beside its leg's end stays: it stands under the leg).
    """
    P = np.asarray(points, np.float64)
    low = plane.height(P) <= 2 * tol
    piece = clusters(P, cell)
    n = np.bincount(piece).astype(np.float64)
    flat = np.bincount(piece, low) >= 0.5 * n
    a, b = in_plane_axes(plane.normal)
    X = np.stack([P @ a, P @ b], axis=1)
    lo = X.min(axis=0)
    idx = np.floor((X - lo) / cell).astype(np.int64)
    stands = ~low & ~flat[piece]
    occ = np.zeros(tuple(idx.max(axis=0) + 1), bool)
    occ[idx[stands, 0], idx[stands, 1]] = True
    r = max(int(np.ceil(margin / cell)), 0)
    yy, xx = np.mgrid[-r : r + 1, -r : r + 1]
    foot = ndimage.binary_dilation(occ, yy**2 + xx**2 <= r * r)
    outside = low & ~foot[idx[:, 0], idx[:, 1]]
    scrap = flat & (np.bincount(piece, outside) >= 0.5 * np.bincount(piece, low))
    return scrap[piece]


def in_plane_axes(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two (3,) float64 orthonormal axes across a plane with unit ``normal`` (3,): a point's
    coordinates seen along the normal are its dot products with them.
    """
    n = np.asarray(normal, np.float64)
    a = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    a /= np.linalg.norm(a)
    return a, np.cross(n, a)


def base_plane(points: np.ndarray, up_prior: np.ndarray, cell: float) -> Plane | None:
    """The plane of an object's base, or None: "up" where the scan has no floor.

    A base is what the sensor separated below the rest (a swivel chair's star, its gas-lift
    column unseen): the clusters (``cell``) below the lowest gap in height between clusters
    that has at least ``BASE_MIN_SHARE`` of the points below it, their centre under the
    footprint of the rest. Its legs
    run level, so its least-squares plane's normal is up when the base is flat
    (``BASE_MAX_FLATNESS``) and within ``MAX_TILT_DEG`` of the prior. Heights are taken along
    the prior, then once more along the plane found (which pieces lie below depends on it).

    Parameters
    ----------
    points : (N, 3) float64
        The object's points, world (no floor among them).
    up_prior : (3,) float64
        Expected up direction (the camera's -y axis in the world).
    cell : float
        Points closer than about this are one cluster, world units.

    Returns
    -------
    Plane through the base (normal up), or None.
    """
    P = np.asarray(points, np.float64)
    prior = np.asarray(up_prior, np.float64)
    prior = prior / np.linalg.norm(prior)
    if len(P) < 50:
        return None
    lab = clusters(P, cell)
    counts = np.bincount(lab)
    big = np.flatnonzero(counts >= 30)
    up, plane = prior, None
    for _ in range(2):
        h = P @ up
        low = np.full(len(counts), np.inf)
        high = np.full(len(counts), -np.inf)
        np.minimum.at(low, lab, h)
        np.maximum.at(high, lab, h)
        # the lowest gap in height between the pieces below which they hold enough points
        order = big[np.argsort(low[big])]
        reach = np.maximum.accumulate(high[order])
        gaps = np.flatnonzero(low[order][1:] > reach[:-1])
        share = np.cumsum(counts[order]) / len(P)
        gaps = gaps[share[gaps] >= BASE_MIN_SHARE]
        if len(gaps) == 0:
            return None
        base = np.isin(lab, order[: gaps[0] + 1]) | np.isin(
            lab, np.flatnonzero(high <= reach[gaps[0]])
        )
        X = P[base]
        c = X.mean(axis=0)
        _, s, vt = np.linalg.svd(X - c, full_matrices=False)
        if s[2] > BASE_MAX_FLATNESS * s[1]:
            return None
        n = vt[2] if vt[2] @ prior >= 0 else -vt[2]
        if n @ prior < np.cos(np.radians(MAX_TILT_DEG)):
            return None
        # a base stands under what it carries
        a, b = in_plane_axes(n)
        B = P[~base] @ np.stack([a, b], axis=1)
        lo, hi = np.percentile(B, 2, axis=0) - cell, np.percentile(B, 98, axis=0) + cell
        foot = np.array([c @ a, c @ b])
        if not ((foot >= lo) & (foot <= hi)).all():
            return None
        plane, up = Plane(n, float(n @ c)), n
    return plane


class FacesUp(NamedTuple):
    """Up from a scan's faces (:func:`faces_up`): ``up`` (3,) unit, world; ``score`` its mean
    vote (0 to 1.5); ``level`` the level patches' share of it (0 to 1); ``clear`` whether
    they give up (``FACES_MIN_SCORE``, ``FACES_MIN_LEVEL``).
    """

    up: np.ndarray
    score: float
    level: float

    @property
    def clear(self) -> bool:
        """Whether the faces give up: enough votes, and level faces among them."""
        return self.score >= FACES_MIN_SCORE and self.level >= FACES_MIN_LEVEL


def faces_up(points: np.ndarray, pose: np.ndarray, *, seed: int = 0) -> FacesUp:
    """Up from the faces of a scan: the direction most of its flat patches lie level or upright
    to, among the camera's pitches and small rolls.

    Each sampled patch (``FACES_SAMPLE`` points' ``FACES_NEIGHBOURS`` nearest, flat within
    ``FACES_FLAT``) votes for the candidates its normal is parallel to (a level face: a seat,
    a top, a shelf, the floor) or square to (an upright face: a side, a door, a leg), with a
    Gaussian of ``FACES_SIGMA_DEG``. The candidates are the camera's -y axis pitched by
    ``FACES_PITCH_DEG`` about its x axis and rolled up to ``FACES_ROLL_DEG`` about its view
    axis, a degree apart. A candidate's level faces must face up more than down (seen from
    above, a top, not an underside): the candidate a quarter turn off, for which the object's
    fronts are level and its tops upright, votes as well. The best is refined by least squares
    on the patches within two sigmas of level or upright.

    Parameters
    ----------
    points : (N, 3) float64
        World points of the whole scan (the room, the floor where seen, the object).
    pose : (4, 4) float64
        The first camera's pose, camera to world (x right, y down, z forward).

    Returns
    -------
    FacesUp
        The up found, its votes, and whether they give it clearly (``.clear``).

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.evaluate import virtual_scan
    >>> table = ingest.load_mesh(data.table())  # y up
    >>> (f,) = virtual_scan(table, 1, elevation=40.0, floor=False)
    >>> found = faces_up(f.points()[0], f.pose)
    >>> bool(found.up @ [0, 1, 0] > 0.999), found.clear
    (True, True)
    """
    from scipy.spatial import cKDTree

    P = np.asarray(points, np.float64)
    none = FacesUp(-np.asarray(pose, np.float64)[:3, 1], 0.0, 0.0)
    if len(P) < FACES_NEIGHBOURS * 4:
        return none
    rng = np.random.default_rng(seed)
    S = P[rng.choice(len(P), min(len(P), FACES_SAMPLE), replace=False)]
    _, nn = cKDTree(P).query(S, k=FACES_NEIGHBOURS)
    X = P[nn] - P[nn].mean(axis=1, keepdims=True)
    w, vec = np.linalg.eigh(np.einsum("nki,nkj->nij", X, X))
    flat = w[:, 0] <= FACES_FLAT * w[:, 1]
    n = vec[flat, :, 0]
    towards = np.asarray(pose, np.float64)[:3, 3] - S[flat]  # the camera: tops face up
    n[np.einsum("ni,ni->n", n, towards) < 0] *= -1
    if len(n) < 30:
        return none
    U, cost = _up_candidates(np.asarray(pose, np.float64))
    vote, level, face = _votes(n, U)
    adj = np.where(face >= -FACES_DOWN, vote, -np.inf) - cost
    k = int(np.argmax(adj))
    if not np.isfinite(adj[k]):
        return none
    return FacesUp(_refine_up(n, U[k]), float(vote[k]), float(level[k]))


def _up_candidates(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, 3) unit candidates for up (the camera's -y pitched and rolled, a degree apart) and
    (K,) what each pays for its pitch and roll (``FACES_TILT_COST``, ``FACES_ROLL_COST``).
    """
    x, y, z = pose[:3, 0], pose[:3, 1], pose[:3, 2]
    pitch = np.radians(np.arange(FACES_PITCH_DEG[0], FACES_PITCH_DEG[1] + 0.5, 1.0))
    roll = np.radians(np.arange(-FACES_ROLL_DEG, FACES_ROLL_DEG + 0.5, 1.0))
    T, R = (a.ravel()[:, None] for a in np.meshgrid(pitch, roll, indexing="ij"))
    # a camera pitched down by t (rolled by r) sees up as cos t (its -y, rolled) - sin t z
    U = np.cos(T) * (np.cos(R) * -y + np.sin(R) * x) - np.sin(T) * z
    cost = FACES_TILT_COST * np.degrees(np.abs(T[:, 0])) + FACES_ROLL_COST * np.degrees(
        np.abs(R[:, 0])
    )
    return U, cost


def _votes(n: np.ndarray, U: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(K,) mean vote of normals ``n`` (M, 3) for candidates ``U`` (K, 3), (K,) its level
    part, and (K,) the mean level vote facing up less that facing down (positive: tops seen;
    negative: undersides).
    """
    sig = np.radians(FACES_SIGMA_DEG)
    # the normals of a flat face agree: each direction once (to about half a degree), weighted
    # by how many patches share it
    dirs, inverse, count = np.unique(
        np.round(n * 100).astype(np.int16), axis=0, return_inverse=True, return_counts=True
    )
    rep = np.zeros((len(dirs), 3))
    np.add.at(rep, inverse.ravel(), n)
    rep /= np.linalg.norm(rep, axis=1, keepdims=True)
    w = (count / len(n)).astype(np.float32)
    lev, upr, face = (np.zeros(len(U)) for _ in range(3))
    Ut = U.T.astype(np.float32)
    # a block of directions at a time: the (D, K) products of a curved object's thousands of
    # directions and thousands of candidates would be arrays of a hundred megabytes each
    for b in range(0, len(rep), VOTES_BLOCK):
        d = rep[b : b + VOTES_BLOCK].astype(np.float32) @ Ut  # (block, K)
        a = np.abs(d)
        wb = w[b : b + VOTES_BLOCK]
        # small angles: from level 1 - cos ~ angle^2 / 2; from upright |cos| ~ angle
        # a pair beyond about six sigmas of level or of upright weighs below exp(-VOTES_CUT):
        # nothing, and not reckoned
        x = (a - 1.0) / np.float32(sig**2)
        level = np.exp(x, out=np.zeros_like(x), where=x > -VOTES_CUT)
        lev += wb @ level
        x = np.float32(-0.5 / sig**2) * a * a
        upr += wb @ np.exp(x, out=np.zeros_like(x), where=x > -VOTES_CUT)
        face += wb @ np.copysign(level, d)
    return lev + FACES_UPRIGHT_VOTE * upr, lev, face


def _refine_up(n: np.ndarray, up: np.ndarray) -> np.ndarray:
    """``up`` refined: the direction that least squares makes level to the normals ``n`` near
    level and square to those near upright; kept where the patches leave it open (only one
    upright direction seen) or it would move by more than two degrees.
    """
    band = np.sin(np.radians(2 * FACES_SIGMA_DEG))
    u = up
    for _ in range(2):
        d = n @ u
        lev, upr = n[np.abs(d) >= np.cos(np.radians(2 * FACES_SIGMA_DEG))], n[np.abs(d) <= band]
        M = upr.T @ upr - lev.T @ lev
        w, vec = np.linalg.eigh(M)
        if w[1] - w[0] < 1e-3 * max(len(n), 1):
            return u  # open: the smallest two agree
        v = vec[:, 0] if vec[:, 0] @ u >= 0 else -vec[:, 0]
        if v @ up < np.cos(np.radians(2.0)):
            return u
        u = v
    return u
