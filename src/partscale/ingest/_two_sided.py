"""Two-sided faces: a triangle stored once per winding, so that a viewer shows both its sides.

Exporters make faces two-sided that way (Kenney's furniture does it for whole bodies: every
wall of a cabinet, the stringer of a stair). The copies cancel in the winding number, so a
body built of them reads ``w = 0`` inside and would be lost. Where such pairs read the same
whole ``w`` on both sides (0 outside; 1 or more where another solid overlaps them) and close
up edge to edge, the import keeps one copy of each, wound as its neighbours are, and the
body is a solid again. The others stay as they are: pairs in open or T-jointed groups, and
the shared face of two one-sided boxes touching face to face (its edges are shared by three
faces: not closed).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Pairs:
    """The two-sided triangles of a mesh (F faces, G pairs).

    ``points`` (M, 3) float64 the distinct corner positions, ``W`` (F, 3) int64 each face's
    corners among them; ``pair`` (F,) int64 the pair of each face (-1: in none); ``fwd``
    and ``rev`` (G,) int64 one copy of each pair per winding (the others, if a pair is
    stored more than once per winding, are its extra copies).
    """

    points: np.ndarray
    W: np.ndarray
    pair: np.ndarray
    fwd: np.ndarray
    rev: np.ndarray


def opposite_pairs(V: np.ndarray, F: np.ndarray) -> Pairs:
    """The triangles stored as often with one winding as with the other (corners compared by
    position). V : (N, 3) float64, F : (F, 3) int64.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.eye(3)[::-1]
    >>> opposite_pairs(V, np.array([[0, 1, 2], [0, 2, 1], [1, 2, 0]])).pair
    array([-1, -1, -1])
    >>> p = opposite_pairs(V, np.array([[0, 1, 2], [2, 1, 0]]))
    >>> p.pair, p.fwd, p.rev
    (array([0, 0]), array([0]), array([1]))
    """
    # corners by position: rows compared byte for byte (+ 0.0 makes -0.0 +0.0), one sort
    rows = np.ascontiguousarray(np.asarray(V, np.float64) + 0.0)
    _, first, vid = np.unique(
        rows.view(np.dtype((np.void, 24))).ravel(), return_index=True, return_inverse=True
    )
    W = vid.ravel()[F]
    s = np.sort(W, axis=1)
    n = len(V)
    if n < 2**21:  # a triangle's sorted corners as one int64
        _, key = np.unique((s[:, 0] * n + s[:, 1]) * n + s[:, 2], return_inverse=True)
    else:
        _, key = np.unique(s, axis=0, return_inverse=True)
    key = key.ravel()
    # the winding: a corner order that is an even permutation of the sorted one is forward
    low = np.argmin(W, axis=1)
    at = np.arange(len(W))
    forward = W[at, (low + 1) % 3] < W[at, (low + 2) % 3]
    n = int(key.max()) + 1 if len(key) else 0
    nf = np.bincount(key, forward, minlength=n)
    nr = np.bincount(key, ~forward, minlength=n)
    is_pair = (nf == nr) & (nf > 0)
    pid = np.full(n, -1, np.int64)
    pid[is_pair] = np.arange(int(is_pair.sum()))
    pair = pid[key]
    fwd = np.zeros(int(is_pair.sum()), np.int64)
    rev = np.zeros_like(fwd)
    on = np.flatnonzero(pair >= 0)[::-1]  # the first copy of each winding wins
    fwd[pair[on[forward[on]]]] = on[forward[on]]
    rev[pair[on[~forward[on]]]] = on[~forward[on]]
    return Pairs(rows[first], W, pair, fwd, rev)


def kept(pairs: Pairs, choice: np.ndarray) -> np.ndarray:
    """(F,) bool: the faces kept where pair ``g`` keeps only its ``fwd`` copy (``choice[g]``
    +1), only its ``rev`` copy (-1) or every copy (0); faces of no pair are kept.

    Examples
    --------
    >>> import numpy as np
    >>> p = opposite_pairs(np.eye(3)[::-1], np.array([[0, 1, 2], [2, 1, 0], [0, 1, 2], [1, 0, 2]]))
    >>> kept(p, np.array([1])), kept(p, np.array([-1])), kept(p, np.array([0]))
    (array([ True, False, False, False]), array([False,  True, False, False]), array([ True,  True,  True,  True]))
    """
    keep = pairs.pair < 0
    keep[pairs.pair >= 0] = choice[pairs.pair[pairs.pair >= 0]] == 0
    keep[pairs.fwd[choice > 0]] = True
    keep[pairs.rev[choice < 0]] = True
    return keep


def keep_one(pairs: Pairs, two: np.ndarray):
    """Which copy each two-sided pair keeps: ``choice`` (G,) int8 (see :func:`kept`) and
    ``group`` (G,) int64 the group of linked pairs it belongs to (-1: every copy kept).

    ``two`` (G,) bool: the pairs that may keep one copy (the others cancel, as faces of no
    solid). Pairs are linked across the edges that exactly two faces share (faces of no pair
    and of the pairs ``two``, each pair counted once); a group of linked pairs is *closed*
    when every edge of its pairs is shared by an even number of faces (its faces meet edge
    to edge; two bodies may share an edge). The copy kept winds as its neighbours do: the
    faces of no pair hold their winding and the pairs linked to them follow; a group that
    meets none of them winds so that its signed volume is positive (outwards). A group
    that is open or T-jointed (no inside to win), or that cannot wind as all its neighbours
    do, keeps every copy.

    Examples
    --------
    >>> import numpy as np
    >>> import trimesh
    >>> box = trimesh.creation.box()
    >>> F = np.concatenate([box.faces, box.faces[:, ::-1]])  # every face two-sided
    >>> p = opposite_pairs(box.vertices, F)
    >>> choice, group = keep_one(p, np.ones(12, bool))
    >>> keep = kept(p, choice)
    >>> bool(trimesh.Trimesh(box.vertices, F[keep]).volume > 0), int(keep.sum())
    (True, 12)
    >>> int(kept(p, keep_one(p, np.arange(12) > 0)[0]).sum())  # one cancels: open
    24
    >>> F = np.concatenate([box.faces[1:], box.faces[1:, ::-1]])  # open: a triangle missing
    >>> p = opposite_pairs(box.vertices, F)
    >>> int(kept(p, keep_one(p, np.ones(11, bool))[0]).sum())
    22
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n_g = len(pairs.fwd)
    closed, pq, agree = _edges(pairs, two)
    link = (pq >= 0).all(axis=1) & two[pq].all(axis=1)
    p, q, ag = pq[link, 0], pq[link, 1], agree[link]
    graph = coo_matrix((np.ones(len(p)), (p, q)), shape=(n_g, n_g))
    n_comp, comp = connected_components(graph, directed=False)
    # the windings as a graph: node 2g keeps pair g's fwd copy, 2g + 1 its rev copy; node
    # 2G stands for the faces of no pair (they hold their winding)
    side = pq[(pq >= 0).sum(axis=1) == 1].max(axis=1)
    s_ag = agree[(pq >= 0).sum(axis=1) == 1][two[side]]
    side = side[two[side]]
    src = np.concatenate([2 * p, 2 * p + 1, np.full(len(side), 2 * n_g)])
    dst = np.concatenate([2 * q + ~ag, 2 * q + ag, 2 * side + ~s_ag])
    m = 2 * n_g + 1
    _, lab = connected_components(coo_matrix((np.ones(len(src)), (src, dst)), shape=(m, m)))
    fwd_l, rev_l, fixed = lab[0 : 2 * n_g : 2], lab[1 : 2 * n_g : 2], lab[2 * n_g]
    ok = np.ones(n_comp, bool)
    ok[comp[~(closed & two) | (fwd_l == rev_l)]] = False
    # each group winds as its first pair, or the other way round (its signed volume) ...
    root = np.zeros(n_comp, np.int64)
    root[comp[::-1]] = np.arange(n_g)[::-1]
    choice = np.where(fwd_l == fwd_l[root[comp]], 1, -1).astype(np.int8)
    tri = pairs.points[pairs.W[pairs.fwd]]
    count = np.maximum(np.bincount(comp, minlength=n_comp), 1)[:, None]
    centre = np.stack([np.bincount(comp, tri[:, :, i].mean(axis=1), n_comp) for i in range(3)], 1)
    tri = tri - (centre / count)[comp][:, None]
    vol = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))
    turn = np.bincount(comp, choice * vol, n_comp) < 0
    choice[turn[comp]] *= -1
    # ... unless it meets faces of no pair: then as they do
    choice[fwd_l == fixed] = 1
    choice[rev_l == fixed] = -1
    use = ok[comp] & two
    choice[~use] = 0
    return choice, np.where(use, comp, -1).astype(np.int64)


def _edges(pairs: Pairs, two: np.ndarray):
    """The edges of the faces of no pair and of the forward copy of each pair ``two`` (the
    other pairs cancel: no face of the solid).

    Returns ``closed`` (G,) bool (every edge of the pair shared by an even number of those
    faces), ``pq`` (E, 2) int64 the pairs of the two faces of each edge shared by exactly two
    (-1: a face of no pair) and ``agree`` (E,) bool (the two faces run it in opposite
    directions: their windings agree).
    """
    faces = np.concatenate([np.flatnonzero(pairs.pair < 0), pairs.fwd[two]])
    node = np.concatenate([np.full(len(faces) - int(two.sum()), -1), np.flatnonzero(two)])
    a = pairs.W[faces].ravel()
    b = np.roll(pairs.W[faces], -1, axis=1).ravel()
    owner = node[np.repeat(np.arange(len(faces)), 3)]
    n = len(pairs.points)
    _, ekey, count = np.unique(
        np.minimum(a, b) * n + np.maximum(a, b), return_inverse=True, return_counts=True
    )
    closed = np.ones(len(pairs.fwd), bool)
    closed[owner[(count[ekey] % 2 == 1) & (owner >= 0)]] = False
    shared = count[ekey] == 2
    order = np.argsort(ekey[shared], kind="stable")
    pq = owner[shared][order].reshape(-1, 2)
    e_dir = (a < b)[shared][order].reshape(-1, 2)
    return closed, pq, e_dir[:, 0] != e_dir[:, 1]
