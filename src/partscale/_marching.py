"""Marching cubes straight into a triangle table, without the GIL (numba).

Re-evaluation (:mod:`partscale.edit.reevaluate`) needs the zero level set of a box of the field
as triangles, never as a mesh: no shared vertices, normals or values. scikit-image's marching
cubes (used for meshes elsewhere) holds the GIL, so the boxes an edit solves side by side
extracted their surfaces one after another (on the cabinet shrink at 128, 41 ms of 155); this
kernel releases it and writes each triangle's corners once.

The surface is the one marching cubes defines: vertices at the linear zero crossings along the
grid's edges, a corner with ``value <= 0`` inside (negative inside). Each cell's polygons are the
cycles its faces' segments close; a face whose diagonal corners share a side (the ambiguous
case) is resolved by the asymptotic decider on that face's bilinear interpolant. Both cells of a
face compute the same decision from the same four values in the same order, so the surface has
no cracks. Each polygon is a fan from its lowest-numbered edge, except one holding both
segments of an ambiguous face: a fan from a vertex would lay triangles flat in that face (the
neighbouring cell's too, a sheet where there is no surface), so it is a fan around its
vertices' mean, as Lewiner's tables add a point inside the cell in those cases.

Exports do not use this kernel: :func:`partscale.surface.to_mesh` (the exports, the metrics)
keeps scikit-image's marching cubes (Lewiner), which returns an indexed mesh (shared vertices,
so watertightness, decimation and texture atlases work on it), whereas this kernel returns a
triangle soup in which every triangle carries its own corners. Both place vertices at the same
linear zero crossings; they may triangulate a cell, and resolve an ambiguous face, differently.
Re-evaluation only needs the surface's distances, for which a soup suffices and which must not
hold the GIL; an export needs the mesh, once per file, where the GIL does not matter.

Conventions: corner ``c = 4 di + 2 dj + dk`` of the cell at ``(i, j, k)`` (index order i, j, k =
x, y, z); vertices in continuous grid indices of the array given.
"""

from __future__ import annotations

import numba
import numpy as np

# the 12 edges: (corner, corner) differing along one axis, by axis (bit 4: i, 2: j, 1: k)
_EDGES = np.array([(c, c | b) for b in (4, 2, 1) for c in range(8) if not c & b], dtype=np.int64)
# the 6 faces: axis, side; corners in the cyclic order of the two other axes (u < v)
_FACES = np.array(
    [
        [
            side * (1 << (2 - a)) + du * (1 << (2 - u)) + dv * (1 << (2 - v))
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1))
        ]
        for a in range(3)
        for side in (0, 1)
        for u, v in [tuple(x for x in range(3) if x != a)]
    ],
    dtype=np.int64,
)
#: the most triangles one cell can hold (12 crossed edges in one cycle, fanned around its mean)
_MAX_TRIANGLES = 12


@numba.njit(cache=True)
def _build_tables(edges, faces):
    """``(table (16384, 1 + 3 * 12) int8, means (16384, 4) int16, ambiguous (256,) uint8)``.

    ``table[config | decisions << 8]``: triangle count, then vertex triplets: an edge 0-11, or
    ``12 + q``, the mean of the edges in bit mask ``means[key, q]``; ``config`` has bit c set
    where corner c is outside (> 0); bit f of ``decisions``, for an ambiguous face f, set where
    its first and third corners are joined across it. ``ambiguous[config]``: bit f set where
    face f is ambiguous.
    """
    # Complexity 35 (radon), kept in one kernel: it runs once per process (16384 keys, a few
    # ms compiled) and reads as the construction it is, configuration by configuration: the
    # faces' segments, the cycles they close, then each cycle's fan. Splitting the walk from
    # the fan would pass the same five scratch arrays around.
    edge_of = np.full((8, 8), -1, np.int64)
    for e in range(12):
        edge_of[edges[e, 0], edges[e, 1]] = e
        edge_of[edges[e, 1], edges[e, 0]] = e
    table = np.zeros((256 * 64, 1 + 3 * _MAX_TRIANGLES), np.int8)
    means = np.zeros((256 * 64, 4), np.int16)
    ambiguous = np.zeros(256, np.uint8)
    side = np.empty(4, np.int64)
    nb = np.empty((12, 2), np.int64)
    segs = np.empty((2, 2), np.int64)
    done = np.empty(12, np.bool_)
    cycle = np.empty(12, np.int64)
    for config in range(256):
        for f in range(6):
            for q in range(4):
                side[q] = (config >> faces[f, q]) & 1
            if side[0] == side[2] and side[1] == side[3] and side[0] != side[1]:
                ambiguous[config] |= np.uint8(1 << f)
        for decisions in range(64):
            if decisions & ~np.int64(ambiguous[config]):
                continue
            # each crossed edge's two neighbours along the surface (one per face holding it)
            nb[:] = -1
            for f in range(6):
                ns = 0
                if (ambiguous[config] >> f) & 1:
                    # corners 0 and 2 joined: the segments cut off corners 1 and 3, else 0 and 2
                    start = 1 if (decisions >> f) & 1 else 0
                    for s in range(2):
                        q = start + 2 * s
                        segs[s, 0] = edge_of[faces[f, (q + 3) % 4], faces[f, q]]
                        segs[s, 1] = edge_of[faces[f, q], faces[f, (q + 1) % 4]]
                    ns = 2
                else:
                    for q in range(4):
                        a, b = faces[f, q], faces[f, (q + 1) % 4]
                        if ((config >> a) & 1) != ((config >> b) & 1):
                            segs[0, ns] = edge_of[a, b]
                            ns += 1
                    ns //= 2  # 0 or 2 crossed edges: no segment or one
                for s in range(ns):
                    e0, e1 = segs[s, 0], segs[s, 1]
                    nb[e0, 0 if nb[e0, 0] < 0 else 1] = e1
                    nb[e1, 0 if nb[e1, 0] < 0 else 1] = e0
            key = config | (decisions << 8)
            done[:] = False
            count = 0
            nmeans = 0
            for e in range(12):
                if done[e] or nb[e, 0] < 0:
                    continue
                # walk the cycle from its lowest edge, then fan it from there
                n = 0
                prev, cur = -1, e
                while True:
                    cycle[n] = cur
                    n += 1
                    done[cur] = True
                    nxt = nb[cur, 0] if nb[cur, 0] != prev else nb[cur, 1]
                    prev, cur = cur, nxt
                    if cur == e:
                        break
                # both segments of an ambiguous face in this cycle: all four of its edges
                twice = False
                for f in range(6):
                    if (ambiguous[config] >> f) & 1:
                        inside = 0
                        for q in range(4):
                            e_f = edge_of[faces[f, q], faces[f, (q + 1) % 4]]
                            for c in range(n):
                                if cycle[c] == e_f:
                                    inside += 1
                        twice = twice or inside == 4
                if twice:
                    mask = 0
                    for c in range(n):
                        mask |= 1 << cycle[c]
                    means[key, nmeans] = mask
                    for c in range(n):
                        table[key, 1 + 3 * count] = 12 + nmeans
                        table[key, 2 + 3 * count] = cycle[c]
                        table[key, 3 + 3 * count] = cycle[(c + 1) % n]
                        count += 1
                    nmeans += 1
                    continue
                for t in range(1, n - 1):
                    table[key, 1 + 3 * count] = cycle[0]
                    table[key, 2 + 3 * count] = cycle[t]
                    table[key, 3 + 3 * count] = cycle[t + 1]
                    count += 1
            table[key, 0] = count
    return table, means, ambiguous


_TABLES: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


def _tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    global _TABLES
    if _TABLES is None:
        _TABLES = _build_tables(_EDGES, _FACES)
    return _TABLES


@numba.njit(cache=True, nogil=True, inline="always")
def _key(v, i, j, k, val, ambiguous, faces):
    """The table key of cell ``(i, j, k)`` of ``v``; its corner values into ``val`` (8,)."""
    config = 0
    for c in range(8):
        x = v[i + (c >> 2), j + ((c >> 1) & 1), k + (c & 1)]
        val[c] = x
        if x > 0:
            config |= 1 << c
    key = config
    amb = ambiguous[config]
    if amb:
        for f in range(6):
            if (amb >> f) & 1:
                # the bilinear interpolant's saddle lies on the side of corners 0 and 2
                # (joined across the face) when |a c| > |b d|: a c > b d, as the diagonals'
                # products are both >= 0
                a, b = val[faces[f, 0]], val[faces[f, 1]]
                c_, d = val[faces[f, 2]], val[faces[f, 3]]
                if a * c_ > b * d:
                    key |= 1 << (8 + f)
    return key


@numba.njit(cache=True, nogil=True, inline="always")
def _signs(r00, r01, r10, r11, k):
    """Corner bits 0, 2, 4, 6 (``dk = 0``) of the cell at ``k`` between rows ``r00 ... r11`` (the
    rows at ``(di, dj)``): the corners whose value is > 0."""
    return (
        np.uint32(r00[k] > 0)
        | (np.uint32(r01[k] > 0) << 2)
        | (np.uint32(r10[k] > 0) << 4)
        | (np.uint32(r11[k] > 0) << 6)
    )


@numba.njit(cache=True, nogil=True)
def _march(v, table, means, ambiguous, edges, faces, width):
    """(F, ``width``) float64: columns 0-8 the corners (a, b, c) of every triangle of the zero
    level set of ``v`` (X, Y, Z) float32; the other columns uninitialised."""
    nx, ny, nz = v.shape
    if min(nx, ny, nz) < 2:
        return np.empty((0, width))
    # The cells the surface crosses (corners on both sides), in raster order: counted per row of
    # cells, then listed, the rows without any skipped. Along a row a cell's corners at k + 1
    # are the next cell's at k, so each corner's side is read once, and without branches (the
    # count vectorises); ~10 % of a box's cells are listed.
    rows = np.zeros((nx - 1, ny - 1), np.int64)
    for i in range(nx - 1):
        for j in range(ny - 1):
            r00, r01, r10, r11 = v[i, j], v[i, j + 1], v[i + 1, j], v[i + 1, j + 1]
            lo = _signs(r00, r01, r10, r11, 0)
            c = 0
            for k in range(nz - 1):
                hi = _signs(r00, r01, r10, r11, k + 1)
                config = lo | (hi << 1)
                lo = hi
                c += (config != 0) & (config != 255)
            rows[i, j] = c
    # one spare row: each cell is written, then kept by advancing the count
    cells = np.empty((rows.sum() + 1, 3), np.int32)
    nc = 0
    for i in range(nx - 1):
        for j in range(ny - 1):
            if rows[i, j] == 0:
                continue
            r00, r01, r10, r11 = v[i, j], v[i, j + 1], v[i + 1, j], v[i + 1, j + 1]
            lo = _signs(r00, r01, r10, r11, 0)
            for k in range(nz - 1):
                hi = _signs(r00, r01, r10, r11, k + 1)
                config = lo | (hi << 1)
                lo = hi
                cells[nc, 0] = i
                cells[nc, 1] = j
                cells[nc, 2] = k
                nc += (config != 0) & (config != 255)
    # their keys and triangle count, so the output is allocated once (growing it faulted in
    # pages that two threads then waited on each other for)
    val = np.empty(8)
    keys = np.empty(nc, np.int64)
    n = 0
    for q in range(nc):
        keys[q] = _key(v, cells[q, 0], cells[q, 1], cells[q, 2], val, ambiguous, faces)
        n += table[keys[q], 0]
    out = np.empty((n, width))
    px = np.empty(16)
    py = np.empty(16)
    pz = np.empty(16)
    n = 0
    for q in range(nc):
        i, j, k = cells[q, 0], cells[q, 1], cells[q, 2]
        key = keys[q]
        nt = table[key, 0]
        if nt == 0:
            continue
        for c in range(8):
            val[c] = v[i + (c >> 2), j + ((c >> 1) & 1), k + (c & 1)]
        for e in range(12):
            c0, c1 = edges[e, 0], edges[e, 1]
            a, b = val[c0], val[c1]
            if (a > 0) == (b > 0):
                continue
            t = a / (a - b)
            px[e] = i + (c0 >> 2) + t * ((c1 >> 2) - (c0 >> 2))
            py[e] = j + ((c0 >> 1) & 1) + t * (((c1 >> 1) & 1) - ((c0 >> 1) & 1))
            pz[e] = k + (c0 & 1) + t * ((c1 & 1) - (c0 & 1))
        for m_ in range(4):
            mask = means[key, m_]
            if mask == 0:
                break
            sx, sy, sz, m = 0.0, 0.0, 0.0, 0
            for e in range(12):
                if (mask >> e) & 1:
                    sx += px[e]
                    sy += py[e]
                    sz += pz[e]
                    m += 1
            px[12 + m_], py[12 + m_], pz[12 + m_] = sx / m, sy / m, sz / m
        for t_ in range(nt):
            for c in range(3):
                e = table[key, 1 + 3 * t_ + c]
                out[n, 3 * c] = px[e]
                out[n, 3 * c + 1] = py[e]
                out[n, 3 * c + 2] = pz[e]
            n += 1
    return out


def march(volume: np.ndarray, width: int = 9) -> np.ndarray:
    """(F, ``width``) float64 triangles of the zero level set of ``volume`` (X, Y, Z) float32.

    Columns 0-8 hold each triangle's corners (continuous grid indices); with ``width > 9`` the
    other columns are left uninitialised for the caller. Releases the GIL.
    """
    table, means, ambiguous = _tables()
    v = np.ascontiguousarray(volume, np.float32)
    return _march(v, table, means, ambiguous, _EDGES, _FACES, width)
