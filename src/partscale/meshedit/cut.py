"""Triangle arrays cut at axis-aligned planes and mapped along the axis (the mesh route's core).

A :class:`Piece` is one mesh in world coordinates with per-vertex attributes (UVs, normals,
colours: anything interpolated linearly along an edge) and per-face attributes (copied).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Piece:
    """One triangle mesh in world coordinates.

    vertices : (V, 3) float64
    faces : (F, 3) int64, wound as given
    vattrs : name -> (V, k) float64, interpolated linearly where an edge is cut
    fattrs : name -> (F, ...) any dtype, copied to every triangle a face is cut into
    """

    vertices: np.ndarray
    faces: np.ndarray
    vattrs: dict[str, np.ndarray] = field(default_factory=dict)
    fattrs: dict[str, np.ndarray] = field(default_factory=dict)


def cut(piece: Piece, axis: int, plane: float) -> Piece:
    """``piece`` with every triangle that crosses ``x[axis] = plane`` split along it.

    A crossing edge gets one new vertex (shared by both triangles on it, so a closed mesh stays
    closed) at exactly ``plane``; its attributes are interpolated from the edge's end points,
    ordered by side, so coincident edges (seams of UV charts) get bit-identical new vertices.
    Existing vertices and uncut triangles are kept unchanged and in order; the pieces of cut
    triangles are appended, wound like their triangle (pieces of a triangle of no area that
    have two corners at one point are dropped). A four-cornered piece is split at the
    diagonal from its least corner by position, whatever the triangle's first corner: a face
    stored once per winding (a two-sided face) is cut into pieces stored once per winding too.
    """
    V, F = piece.vertices, piece.faces
    if len(F) == 0:
        return piece
    # a corner within rounding of the plane lies on it: cut there, it would leave a sliver of
    # no area (a degenerate triangle, and a two-sided face's copies cut apart)
    off = V[:, axis] - plane
    tol = 1e-12 * (float(np.ptp(V[:, axis])) + abs(plane))
    side = np.where(np.abs(off) <= tol, 0, np.sign(off)).astype(np.int8)
    s = side[F]
    crossing = (s.min(axis=1) < 0) & (s.max(axis=1) > 0)
    if not crossing.any():
        return piece
    tri = F[crossing]
    # every edge of a crossing triangle whose ends lie strictly on opposite sides
    a = tri.reshape(-1)
    b = np.roll(tri, -1, axis=1).reshape(-1)
    cross_edge = side[a] * side[b] < 0
    lo = np.where(side[a] < 0, a, b)[cross_edge]
    hi = np.where(side[a] < 0, b, a)[cross_edge]
    pairs, inverse = np.unique(np.stack([lo, hi], 1), axis=0, return_inverse=True)
    p0, p1 = pairs[:, 0], pairs[:, 1]
    t = ((plane - V[p0, axis]) / (V[p1, axis] - V[p0, axis]))[:, None]
    new_v = V[p0] + t * (V[p1] - V[p0])
    new_v[:, axis] = plane
    base = len(V)
    cut_index: np.ndarray = np.full(len(a), -1, np.int64)
    cut_index[np.flatnonzero(cross_edge)] = base + inverse.reshape(-1)
    cut_index = cut_index.reshape(-1, 3)  # cut vertex on edge (k, k+1) of each crossing triangle
    faces_out, owner_local = [], []
    tri_side = s[crossing]
    # corners ranked by position (x, then y, then z): where to start a four-cornered piece
    every = np.concatenate([V, new_v])
    rank = np.empty(len(every), np.int64)
    rank[np.lexsort((every[:, 2], every[:, 1], every[:, 0]))] = np.arange(len(every))
    for n in range(len(tri)):
        poly, sides = [], []
        for k in range(3):
            poly.append(tri[n, k])
            sides.append(tri_side[n, k])
            if cut_index[n, k] >= 0:
                poly.append(cut_index[n, k])
                sides.append(0)
        for keep in (-1, 1):
            sub = [v for v, sd in zip(poly, sides, strict=True) if sd * keep >= 0]
            if len(sub) > 3:
                first = min(range(len(sub)), key=lambda i: rank[sub[i]])
                sub = sub[first:] + sub[:first]
            for j in range(1, len(sub) - 1):
                faces_out.append((sub[0], sub[j], sub[j + 1]))
                owner_local.append(n)
    pieces = np.asarray(faces_out, np.int64).reshape(-1, 3)
    # a triangle of no area (its corners in a line) is cut at one point of two of its edges:
    # its pieces with two corners there are dropped (no area; each edge of theirs would be
    # met once, and an importer would read the surface as open there)
    P = every[pieces]
    flat = (
        (P[:, 0] == P[:, 1]).all(axis=1)
        | (P[:, 1] == P[:, 2]).all(axis=1)
        | (P[:, 2] == P[:, 0]).all(axis=1)
    )
    pieces = pieces[~flat]
    owner = np.flatnonzero(crossing)[np.asarray(owner_local, np.int64)[~flat]]
    faces = np.concatenate([F[~crossing], pieces])
    order = np.concatenate([np.flatnonzero(~crossing), owner])
    vattrs = {k: np.concatenate([v, v[p0] + t * (v[p1] - v[p0])]) for k, v in piece.vattrs.items()}
    fattrs = {k: v[order] for k, v in piece.fattrs.items()}
    return Piece(np.concatenate([V, new_v]), faces, vattrs, fattrs)


def subset(piece: Piece, face_mask: np.ndarray) -> tuple[Piece, np.ndarray]:
    """The faces in ``face_mask`` with only the vertices they use, and those vertices' indices."""
    faces = piece.faces[face_mask]
    used = np.unique(faces)
    remap = np.full(len(piece.vertices), -1, np.int64)
    remap[used] = np.arange(len(used))
    out = Piece(
        piece.vertices[used],
        remap[faces],
        {k: v[used] for k, v in piece.vattrs.items()},
        {k: v[face_mask] for k, v in piece.fattrs.items()},
    )
    return out, used


def concatenate(pieces: list[Piece]) -> Piece:
    """One piece holding all of ``pieces`` (vertex indices offset; attribute names must agree)."""
    offsets = np.cumsum([0] + [len(p.vertices) for p in pieces[:-1]])
    return Piece(
        np.concatenate([p.vertices for p in pieces]),
        np.concatenate([p.faces + o for p, o in zip(pieces, offsets, strict=True)]),
        {k: np.concatenate([p.vattrs[k] for p in pieces]) for k in pieces[0].vattrs},
        {k: np.concatenate([p.fattrs[k] for p in pieces]) for k in pieces[0].fattrs},
    )
