"""The mesh route: a recipe applied to the source mesh itself (glTF/GLB, OBJ+MTL, PLY).

Every scene node's mesh is taken to world coordinates, cut at the zone planes and mapped along
the axis with the same 1D maps as the CSDF route (:func:`partscale.edit.source_coordinate`'s
inverse): ``stretch`` scales the slab linearly, ``tile`` copies the slab's triangles
``tile_count`` times each scaled to fit, ``global`` scales the whole object about its min.
Positions resolve like the CSDF route's (:meth:`partscale.edit.Edit.resolve`): object units, or
``%`` of the extent along the axis, here the mesh's own bounding box; the shift is not snapped to
voxels (there are none). Vertices before a zone keep their stored coordinates bit for bit; those
beyond are translated (in the node's frame, by the shift rotated into it); only vertices inside a
zone and the new ones on its planes are mapped. UVs, vertex colours and normals are interpolated
where a triangle is cut and copied with the slab; materials, textures and the node structure are
kept.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._memory import check_bytes
from .._scenes import triangle_meshes
from ..edit import Edit, Recipe, forward_coordinate, tile_count
from ..errors import InputError, PartscaleWarning
from ..ingest import load_mesh_scene
from ..orient import WALL_AXES, square_turn, turn_matrix
from .cut import Piece, concatenate, cut, subset

if TYPE_CHECKING:
    import trimesh

OUTPUT_SUFFIXES = (".glb", ".obj", ".ply", ".usd", ".usda", ".usdc", ".usdz")

#: lateral distance (relative to the object's size) within which two seam points are one
WELD_TOLERANCE = 1e-5
#: How many times over a tile's copies are held at the peak (see :func:`_check_copies`)
COPY_PEAK = 4
#: Largest coordinate an output may hold: GLB and PLY store float32 positions
MAX_COORDINATE = float(np.finfo(np.float32).max)


@dataclass(frozen=True)
class Seam:
    """A tile seam between copies: where it is and how much of it was welded.

    Attributes
    ----------
    axis : {'x', 'y', 'z'}
        The axis the zone was tiled along.
    position : float
        The seam plane in the result (world units).
    welded : int
        Vertices welded to a partner across the seam.
    unmatched : int
        Vertices without one (the cross-sections at the zone's planes differ).

    Examples
    --------
    >>> from partscale import meshedit
    >>> seam = meshedit.Seam("x", 0.36, welded=44, unmatched=0)
    >>> seam.ok, seam.message()
    (True, 'seam at x = 0.36: welded (44 vertices)')
    """

    axis: str
    position: float
    welded: int
    unmatched: int

    @property
    def ok(self) -> bool:
        """Whether every vertex of the seam was welded."""
        return self.unmatched == 0

    def message(self) -> str:
        """The seam in one line for the user, with what to do where it could not be welded."""
        if self.ok:
            return f"seam at {self.axis} = {self.position:.6g}: welded ({self.welded} vertices)"
        return (
            f"seam at {self.axis} = {self.position:.6g}: cannot be welded, the cross-sections at "
            f"the zone's planes differ ({self.unmatched} of {self.welded + self.unmatched} "
            "vertices without a partner); snap the zone to a period (partscale scale --snap) "
            "or use the CSDF route (import, scale, export), which blends seams"
        )


@dataclass
class _Instance:
    """One scene node's mesh in world coordinates, with what is needed to go back."""

    node: str
    geometry: trimesh.Trimesh
    transform: np.ndarray  # (4, 4) node -> world
    piece: Piece


def _piece(mesh, transform: np.ndarray) -> Piece:
    local = np.asarray(mesh.vertices, np.float64)
    world = local @ transform[:3, :3].T + transform[:3, 3]
    vattrs = {"_local": local.copy(), "_mapped": np.zeros((len(local), 1))}
    if "vertex_normals" in mesh._cache:
        # normals stored in the file (a computed cache entry would be dropped: it is recomputed)
        vattrs["normal"] = np.asarray(mesh.vertex_normals, np.float64) @ transform[:3, :3].T
    visual = mesh.visual
    if getattr(visual, "uv", None) is not None and len(visual.uv) == len(local):
        vattrs["uv"] = np.asarray(visual.uv, np.float64)
    if visual.kind == "vertex":
        vattrs["color"] = np.asarray(visual.vertex_colors, np.float64)
    for name, a in getattr(visual, "vertex_attributes", {}).items():
        if len(a) == len(local):
            vattrs[f"va:{name}"] = np.asarray(a, np.float64).reshape(len(local), -1)
    fattrs = {}
    if visual.kind == "face":
        fattrs["color"] = np.asarray(visual.face_colors)
    return Piece(world, np.asarray(mesh.faces, np.int64), vattrs, fattrs)


def _cut_planes(piece: Piece, axis: int, planes: tuple[float, ...]) -> Piece:
    for p in planes:
        n0 = len(piece.vertices)
        piece = cut(piece, axis, p)
        if len(piece.vertices) > n0:
            piece.vattrs["_mapped"][n0:] = 1.0
    return piece


def _translate(piece: Piece, rows: np.ndarray, axis: int, shift: float, rot: np.ndarray) -> None:
    """Move ``rows`` by ``shift`` along ``axis`` (world), and their stored node coordinates."""
    d = np.zeros(3)
    d[axis] = shift
    piece.vertices[rows, axis] += shift
    piece.vattrs["_local"][rows] += np.linalg.solve(rot, d)


def _scale_normals(piece: Piece, rows: np.ndarray, axis: int, factor: float) -> None:
    n = piece.vattrs.get("normal")
    if n is None or not rows.any():
        return
    n[rows, axis] /= factor  # normals transform by the inverse transpose of the stretch
    n[rows] /= np.maximum(np.linalg.norm(n[rows], axis=1, keepdims=True), 1e-30)


def _stretch(piece, axis, s, e, d, rot):
    piece = _cut_planes(piece, axis, (s, e))
    x = piece.vertices[:, axis]
    inside = (x > s) & (x < e)
    beyond = x >= e
    factor = (d - s) / (e - s)
    x[inside] = s + (x[inside] - s) * factor
    piece.vattrs["_mapped"][inside] = 1.0
    _scale_normals(piece, inside, axis, factor)
    _translate(piece, beyond, axis, d - e, rot)
    return piece, []


def _global(piece, axis, lo, hi, shift, rot):
    factor = (hi - lo + shift) / (hi - lo)
    x = piece.vertices[:, axis]
    x[:] = lo + (x - lo) * factor
    piece.vattrs["_mapped"][:] = 1.0
    _scale_normals(piece, np.ones(len(x), bool), axis, factor)
    return piece, []


def _copy_piece(p: Piece, rows: np.ndarray | None = None) -> Piece:
    rows = np.arange(len(p.vertices)) if rows is None else rows
    return Piece(
        p.vertices[rows].copy(),
        np.zeros((0, 3), np.int64),
        {k: v[rows].copy() for k, v in p.vattrs.items()},
        {k: v[:0] for k, v in p.fattrs.items()},
    )


def _plane_edges(piece: Piece, slab: np.ndarray, axis: int, plane: float) -> np.ndarray:
    """(E, 2) vertex pairs of slab triangles' edges lying in ``x[axis] = plane``."""
    F = piece.faces[slab]
    on = piece.vertices[F, axis] == plane
    pairs = [F[on[:, k] & on[:, (k + 1) % 3]][:, [k, (k + 1) % 3]] for k in range(3)]
    return np.concatenate(pairs)


def _conform(piece: Piece, axis: int, s: float, e: float, tol: float) -> Piece:
    """Split the zone planes' cross-section edges so both planes have the same vertices.

    A point of one plane's cross-section that lies on an edge of the other's (the same outline
    triangulated differently: the usual case for a board crossing the zone) becomes a vertex
    there, in every triangle on that edge (those outside the zone too), so tiled copies meet
    vertex to vertex and stay closed. Points on no edge are left: the weld reports them.
    """
    from scipy.spatial import cKDTree

    lat = [a for a in range(3) if a != axis]
    for src, dst in ((e, s), (s, e)):
        V, F = piece.vertices, piece.faces
        slab = (V[F, axis].mean(axis=1) > s) & (V[F, axis].mean(axis=1) < e)
        q = V[np.unique(F[slab][V[F[slab], axis] == src])][:, lat]
        edges = _plane_edges(piece, slab, axis, dst)
        if len(q) == 0 or len(edges) == 0:
            continue
        ends = np.unique(edges)
        near = cKDTree(V[ends][:, lat]).query(q, distance_upper_bound=tol)[0]
        q = q[~np.isfinite(near)]
        if len(q) == 0:
            continue
        A, B = V[edges[:, 0]][:, lat], V[edges[:, 1]][:, lat]
        AB = (B - A)[None]
        t = ((q[:, None] - A[None]) * AB).sum(-1) / np.maximum((AB * AB).sum(-1), 1e-300)
        dist = np.linalg.norm(A[None] + np.clip(t, 0, 1)[..., None] * AB - q[:, None], axis=-1)
        best = np.argmin(dist, axis=1)
        tb = t[np.arange(len(q)), best]
        ok = (dist[np.arange(len(q)), best] <= tol) & (tb > 0) & (tb < 1)
        if not ok.any():
            continue
        piece = _split_edges(piece, edges[best[ok]], tb[ok], axis, dst)
    return piece


def _split_edges(piece: Piece, edges: np.ndarray, t: np.ndarray, axis: int, plane: float) -> Piece:
    """Insert a vertex at ``t`` along each undirected edge ``(a, b)`` in every triangle on it."""
    V, F = piece.vertices, piece.faces
    a, b = edges[:, 0], edges[:, 1]
    new_v = V[a] + t[:, None] * (V[b] - V[a])
    new_v[:, axis] = plane
    base = len(V)
    vattrs = {
        k: np.concatenate([v, v[a] + t[:, None] * (v[b] - v[a])]) for k, v in piece.vattrs.items()
    }
    vattrs["_mapped"][base:] = 1.0
    # points per undirected edge, ordered from its first to its second vertex
    points: dict[tuple[int, int], list[tuple[float, int]]] = {}
    for i, (x, y) in enumerate(edges.tolist()):
        points.setdefault((x, y), []).append((float(t[i]), base + i))
    keep = np.ones(len(F), bool)
    extra, owner = [], []
    key: dict[int, list[int]] = {}
    for k in range(3):
        for r, (x, y) in enumerate(zip(F[:, k].tolist(), F[:, (k + 1) % 3].tolist(), strict=True)):
            if (x, y) in points or (y, x) in points:
                key.setdefault(r, []).append(k)
    for r, ks in key.items():
        tri = F[r].tolist()
        # the triangle's boundary as a polygon with the inserted points, fanned from a corner
        poly = []
        for k in range(3):
            x, y = tri[k], tri[(k + 1) % 3]
            poly.append(x)
            if k in ks:
                if (x, y) in points:
                    poly += [v for _, v in sorted(points[(x, y)])]
                else:
                    poly += [v for _, v in sorted(points[(y, x)], reverse=True)]
        keep[r] = False
        # fan from the corner opposite the split edge keeps the triangles non-degenerate
        k0 = (ks[0] + 2) % 3
        start = poly.index(tri[k0])
        poly = poly[start:] + poly[:start]
        for j in range(1, len(poly) - 1):
            extra.append((poly[0], poly[j], poly[j + 1]))
            owner.append(r)
    faces = np.concatenate([F[keep], np.asarray(extra, np.int64).reshape(-1, 3)])
    order = np.concatenate([np.flatnonzero(keep), np.asarray(owner, np.int64)])
    fattrs = {k: v[order] for k, v in piece.fattrs.items()}
    return Piece(np.concatenate([V, new_v]), faces, vattrs, fattrs)


def _remove(piece, axis, s, e, rot, size):
    """A tile with 0 copies: the zone's triangles dropped, everything beyond it moved back by
    its length, END's outline snapped onto START's where they match (one join, a Seam).
    """
    from scipy.spatial import cKDTree

    piece = _cut_planes(piece, axis, (s, e))
    piece = _conform(piece, axis, s, e, WELD_TOLERANCE * size)
    centre = piece.vertices[piece.faces, axis].mean(axis=1)
    piece, _ = subset(piece, ~((centre > s) & (centre < e)))
    x = piece.vertices[:, axis].copy()
    _translate(piece, x >= e, axis, s - e, rot)
    V = piece.vertices
    V[x == e, axis] = s  # exactly on START
    lat = [a for a in range(3) if a != axis]
    ps, pe = np.flatnonzero(x == s), np.flatnonzero(x == e)
    if len(ps) == 0 or len(pe) == 0:
        return piece, [Seam("xyz"[axis], s, 0, len(ps) + len(pe))] if len(ps) + len(pe) else []
    tol = WELD_TOLERANCE * size
    dist, j = cKDTree(V[ps][:, lat]).query(V[pe][:, lat], distance_upper_bound=tol)
    matched = np.isfinite(dist)
    back = cKDTree(V[pe][:, lat]).query(V[ps][:, lat], distance_upper_bound=tol)[0]
    V[pe[matched]] = V[ps[j[matched]]]
    unmatched = int((~matched).sum() + (~np.isfinite(back)).sum())
    return piece, [Seam("xyz"[axis], s, int(matched.sum()), unmatched)]


def _row_bytes(arrays) -> float:
    """Bytes per row of arrays sharing their first dimension."""
    return float(sum(a.nbytes / max(len(a), 1) for a in arrays))


def _check_copies(piece: Piece, axis: int, s: float, e: float, n: int) -> None:
    """Refuse ``n`` copies of the zone ``[s, e]``'s triangles that would not fit in memory.

    Each copy holds the slab's vertices and triangles with all their attributes; the copies are
    held about :data:`COPY_PEAK` times over (the copies, their concatenation, the trimesh
    meshes and the file's bytes).
    """
    centre = piece.vertices[piece.faces, axis].mean(axis=1)
    in_zone = (centre > s) & (centre < e)
    n_faces = int(in_zone.sum())
    n_verts = len(np.unique(piece.faces[in_zone]))
    per_copy = n_verts * _row_bytes([piece.vertices, *piece.vattrs.values()])
    per_copy += n_faces * _row_bytes([piece.faces, *piece.fattrs.values()])
    copies = f"{n:,}" if n < 10**9 else f"{float(n):.3g}"
    check_bytes(
        float(n) * per_copy * COPY_PEAK,
        what=f"tile along {'xyz'[axis]}: {copies} copies of {n_faces:,} triangles",
    )


def _tile(piece, axis, s, e, d, rot, size):
    if d == s:
        return _remove(piece, axis, s, e, rot, size)
    n = tile_count(e - s, d - s)
    piece = _cut_planes(piece, axis, (s, e))
    _check_copies(piece, axis, s, e, n)
    if n > 1:
        piece = _conform(piece, axis, s, e, WELD_TOLERANCE * size)
    period = (d - s) / n
    factor = period / (e - s)
    V, F = piece.vertices, piece.faces
    x = V[:, axis].copy()
    centre = V[F, axis].mean(axis=1)
    slab_faces = (centre > s) & (centre < e)
    slab, used = subset(piece, slab_faces)
    sx = slab.vertices[:, axis]
    start_l, end_l = np.flatnonzero(sx == s), np.flatnonzero(sx == e)
    n_orig = len(V)
    # appended: copy 0's end plane (n > 1), then copies 1..n-1 of every slab vertex
    extra = []
    if n > 1:
        extra.append(_copy_piece(slab, end_l))
        extra[0].vertices[:, axis] = s + period
    for k in range(1, n):
        c = _copy_piece(slab)
        c.vertices[:, axis] = s + k * period + (sx - s) * factor
        _scale_normals(c, np.ones(len(sx), bool), axis, factor)
        extra.append(c)
    for c in extra:
        c.vattrs["_mapped"][:] = 1.0
    inside = (x > s) & (x < e)
    V[inside, axis] = s + (x[inside] - s) * factor
    piece.vattrs["_mapped"][inside] = 1.0
    _scale_normals(piece, inside, axis, factor)
    _translate(piece, x >= e, axis, d - e, rot)
    V[x == e, axis] = d  # exactly where the last copy ends
    faces = [piece.faces[~slab_faces]]
    first_end = n_orig
    copy_base = [None] + [n_orig + len(end_l) + (k - 1) * len(sx) for k in range(1, n)]
    for k in range(n):
        if k == 0:
            m = used.copy()
        else:
            base_k = copy_base[k]
            assert base_k is not None  # only copy 0, the original, has no base
            m = base_k + np.arange(len(sx))
        if n > 1 and k == 0:
            m[end_l] = first_end + np.arange(len(end_l))
        if n > 1 and k == n - 1:
            m[end_l] = used[end_l]
        faces.append(m[slab.faces])
    fattrs = {
        kk: np.concatenate([v[~slab_faces]] + [slab.fattrs[kk]] * n)
        for kk, v in piece.fattrs.items()
    }
    merged = concatenate([piece, *extra]) if extra else piece
    piece = Piece(merged.vertices, np.concatenate(faces), merged.vattrs, fattrs)
    seams = []
    if n > 1:
        seams = _weld(piece, axis, slab, start_l, end_l, n, s, period, size, first_end, copy_base)
    return piece, seams


def _weld(piece, axis, slab, start_l, end_l, n, s, period, size, first_end, copy_base):
    """Snap each internal seam's end-plane vertices onto the next copy's start-plane vertices."""
    from scipy.spatial import cKDTree

    lat = [a for a in range(3) if a != axis]
    tol = WELD_TOLERANCE * size
    ps, pe = slab.vertices[start_l][:, lat], slab.vertices[end_l][:, lat]
    if len(ps) == 0 or len(pe) == 0:
        unmatched, matched, j = len(ps) + len(pe), np.zeros(len(pe), bool), np.zeros(len(pe), int)
    else:
        dist, j = cKDTree(ps).query(pe, distance_upper_bound=tol)
        matched = np.isfinite(dist)
        back = cKDTree(pe).query(ps, distance_upper_bound=tol)[0]
        unmatched = int((~matched).sum() + (~np.isfinite(back)).sum())
    V = piece.vertices
    seams = []
    for k in range(n - 1):
        ends = first_end + np.arange(len(end_l)) if k == 0 else copy_base[k] + end_l
        starts = copy_base[k + 1] + start_l
        V[ends[matched]] = V[starts[j[matched]]]
        seams.append(Seam("xyz"[axis], s + (k + 1) * period, int(matched.sum()), unmatched))
    return seams


def _resolve(edit: Edit, lo: float, hi: float) -> tuple[float, float, float]:
    s, e, d = edit.resolve(lo, hi)
    if not s < e:
        raise InputError(f"zone: expected start < end, got start {s:.6g} >= end {e:.6g}")
    if not (d > s or (edit.mode == "tile" and d == s)):  # tile to its start: zone removed
        how = f" for {edit.mode} (to remove the zone use mode tile)" if d == s else ""
        raise InputError(f"to: expected DEST > START {s:.6g}{how}, got {d:.6g}")
    tol = 1e-9 * max(abs(lo), abs(hi), hi - lo)
    if s < lo - tol or e > hi + tol:
        raise InputError(
            f"zone: expected inside the mesh's extent [{lo:.6g}, {hi:.6g}] along {edit.axis}, "
            f"got [{s:.6g}, {e:.6g}]"
        )
    return s, e, d


def _planar(recipe: Recipe) -> list[Edit]:
    """The recipe's zones across an axis; refused (one line, naming the CSDF route) where one
    is not (see :func:`off_plane_zones`).
    """
    out = []
    for i, e in enumerate(recipe.edits):
        if not isinstance(e, Edit):
            raise InputError(
                f"edits[{i}]: expected a zone across x, y or z on the mesh route, got a {_kind(e)} "
                "zone (import the mesh and edit its CSDF: partscale import, then scale)"
            )
        out.append(e)
    return out


def off_plane_zones(recipe: Recipe) -> list[str]:
    """The kinds of the recipe's zones the mesh route cannot cut, in order.

    The mesh route cuts triangles at planes across x, y or z; ``fit`` applies a recipe with any
    other zone (``"step"``, ``"radial"``, ``"helix"``, ``"oblique"``) to the mesh's CSDF
    instead, and remeshes the result.

    Parameters
    ----------
    recipe : partscale.edit.Recipe
        The recipe.

    Returns
    -------
    list of str
        Empty where the mesh route applies the whole recipe.

    Examples
    --------
    >>> from partscale import meshedit
    >>> from partscale.edit import Recipe
    >>> meshedit.off_plane_zones(Recipe.parse({"edits": [{"axis": "x", "zone": [0, 1], "to": 2}]}))
    []
    >>> meshedit.off_plane_zones(
    ...     Recipe.parse({"edits": [{"normal": [1, 1, 0], "zone": [0, 1], "to": 2}]})
    ... )
    ['oblique']
    """
    return [_kind(e) for e in recipe.edits if not isinstance(e, Edit)]


def _kind(edit) -> str:
    kinds = {"radial": "radial", "screw": "step", "helix": "helix"}
    return next((v for k, v in kinds.items() if k in edit.to_json()), "oblique")


def apply_recipe_to_scene(scene: trimesh.Scene, recipe: Recipe) -> tuple[trimesh.Scene, list[Seam]]:
    """Apply ``recipe`` to a trimesh Scene's meshes; returns the edited copy and its tile seams.

    Parameters
    ----------
    scene : trimesh.Scene
        As loaded (``trimesh.load(path, force='scene', process=False)``).
    recipe : partscale.edit.Recipe
        Edits in order; as on the CSDF route (:func:`partscale.edit.apply_recipe`) every
        position refers to the input mesh (``%`` of its extent), planes carried through earlier
        edits on the same axis by :func:`partscale.edit.forward_coordinate`.

    Returns
    -------
    trimesh.Scene
        The edited copy (``scene`` is not changed).
    list of Seam
        The tile seams, one per join between copies.

    Examples
    --------
    >>> from partscale import data, meshedit
    >>> from partscale.edit import Recipe
    >>> table = meshedit.load_scene(data.table())
    >>> longer = Recipe.parse({"edits": [{"axis": "x", "zone": ["30%", "70%"], "to": "120%"}]})
    >>> out, seams = meshedit.apply_recipe_to_scene(table, longer)
    >>> table.extents.round(2).tolist(), out.extents.round(2).tolist(), seams
    ([2.44, 0.95, 1.3], [3.66, 0.95, 1.3], [])
    """
    instances = [
        _Instance(node, geom, np.asarray(transform, float), _piece(geom, transform))
        for node, _, geom, transform in triangle_meshes(scene)
    ]
    if not instances:
        raise InputError("mesh: expected triangles in the scene, got none")
    seams: list[Seam] = []
    allv = np.concatenate([p.piece.vertices[np.unique(p.piece.faces)] for p in instances])
    bounds = np.stack([allv.min(axis=0), allv.max(axis=0)])
    size = float(np.ptp(allv, axis=0).max())
    applied: list[tuple[int, dict]] = []  # (axis, forward-map arguments), as apply_recipe
    for edit in _planar(recipe):
        ax = edit.axis_index
        # positions refer to the recipe's input: planes carried through earlier same-axis edits
        lo0, hi0 = float(bounds[0, ax]), float(bounds[1, ax])
        s0, e0, d0 = _resolve(edit, lo0, hi0)
        planes = np.array([s0, e0])
        for a, kw in applied:
            if a == ax:
                planes = forward_coordinate(planes, **kw)
        s, e = float(planes[0]), float(planes[1])
        d = s if d0 == s0 else e + (d0 - e0)  # a destination at the start stays there
        cur = np.concatenate([p.piece.vertices[np.unique(p.piece.faces)] for p in instances])
        lo, hi = float(cur[:, ax].min()), float(cur[:, ax].max())
        for inst in instances:
            rot = inst.transform[:3, :3]
            if edit.mode == "stretch":
                inst.piece, _ = _stretch(inst.piece, ax, s, e, d, rot)
            elif edit.mode == "tile":
                inst.piece, sm = _tile(inst.piece, ax, s, e, d, rot, size)
                seams += sm
            else:
                inst.piece, _ = _global(inst.piece, ax, lo, hi, d - e, rot)
        kw = {"mode": edit.mode, "start": s, "end": e, "dest": d}
        if edit.mode == "global":
            kw.update(lo=lo, hi=hi)
        applied.append((ax, kw))
    out = scene.copy()
    for inst in instances:
        name = scene.graph[inst.node][1]
        if _shared(scene, inst):  # an instanced mesh is edited per instance: each its own copy
            name = f"{name}:{inst.node}"
            out.graph.transforms.node_data[inst.node]["geometry"] = name
        out.geometry[name] = _to_trimesh(inst)
    out.graph._cache.clear()
    return out, _merge_seams(seams)


def _shared(scene, inst) -> bool:
    name = scene.graph[inst.node][1]
    return sum(scene.graph[n][1] == name for n in scene.graph.nodes_geometry) > 1


def _merge_seams(seams: list[Seam]) -> list[Seam]:
    """One entry per seam position (each instance reports its own vertices)."""
    by: dict[tuple[str, float], Seam] = {}
    for sm in seams:
        key = (sm.axis, round(sm.position, 12))
        if key in by:
            o = by[key]
            by[key] = Seam(o.axis, o.position, o.welded + sm.welded, o.unmatched + sm.unmatched)
        else:
            by[key] = sm
    return list(by.values())


def _to_trimesh(inst: _Instance):
    import trimesh

    p, geom = inst.piece, inst.geometry
    T = inst.transform
    local = p.vattrs["_local"].copy()
    mapped = p.vattrs["_mapped"][:, 0] > 0
    if mapped.any():
        local[mapped] = np.linalg.solve(T[:3, :3], (p.vertices[mapped] - T[:3, 3]).T).T
    kwargs = {}
    if "normal" in p.vattrs:
        n = np.linalg.solve(T[:3, :3], p.vattrs["normal"].T).T
        kwargs["vertex_normals"] = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    visual = geom.visual
    if isinstance(visual, trimesh.visual.TextureVisuals):
        # a material with or without UVs (OBJ groups with a Kd colour have none)
        vis: trimesh.visual.TextureVisuals | trimesh.visual.ColorVisuals | None = (
            trimesh.visual.TextureVisuals(uv=p.vattrs.get("uv"), material=visual.material)
        )
    elif "color" in p.vattrs:
        vis = trimesh.visual.ColorVisuals(
            vertex_colors=np.clip(np.rint(p.vattrs["color"]), 0, 255).astype(np.uint8)
        )
    elif "color" in p.fattrs:
        vis = trimesh.visual.ColorVisuals(face_colors=p.fattrs["color"])
    else:
        vis = None
    mesh = trimesh.Trimesh(local, p.faces, visual=vis, process=False, **kwargs)
    for k, v in p.vattrs.items():
        if k.startswith("va:") and isinstance(mesh.visual, trimesh.visual.TextureVisuals):
            mesh.visual.vertex_attributes[k[3:]] = v.astype(np.float32)
    mesh.metadata.update(geom.metadata)
    return mesh


load_scene = load_mesh_scene
"""A mesh file as a trimesh Scene to edit: the route reads a mesh as the import does (checked for
triangles, indices, finite values and extent), :func:`partscale.ingest.load_mesh_scene`."""


def save_scene(scene: trimesh.Scene, path: str | os.PathLike) -> list[Path]:
    """Write ``scene`` (GLB, PLY, OBJ, USD or USDZ by the suffix), atomically.

    OBJ goes through :func:`partscale.export.save_obj`, USD and USDZ through
    :func:`partscale.export.save_usd` (the optional usd-core).

    Parameters
    ----------
    scene : trimesh.Scene
        The meshes to write.
    path : str or os.PathLike
        The output; its suffix (one of :data:`OUTPUT_SUFFIXES`) picks the format.

    Returns
    -------
    list of Path
        The files written: the mesh, then an OBJ's MTL and textures (named after it).

    Examples
    --------
    >>> from partscale import data, meshedit
    >>> meshedit.save_scene(meshedit.load_scene(data.table()), "table.obj")
    [PosixPath('table.obj'), PosixPath('table.mtl')]
    """
    from .._files import atomic_path
    from ..export import USD_SUFFIXES, save_obj, save_usd

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in OUTPUT_SUFFIXES:
        raise InputError(
            f"{path}: expected an output mesh ({', '.join(OUTPUT_SUFFIXES)}), got "
            f"{suffix or 'no suffix'}"
        )
    _check_finite_scene(scene, path)
    if suffix in USD_SUFFIXES:
        return save_usd(scene, path)
    if suffix == ".obj":
        # the scene itself, not one concatenated mesh: one usemtl group per material
        return save_obj(display_colours(scene, ".obj"), path)
    if suffix == ".glb":
        data = scene.export(file_type="glb")
    else:
        data = display_colours(scene, ".ply").to_mesh().export(file_type="ply", encoding="binary")
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(data)
    return [path]


def _check_finite_scene(scene: trimesh.Scene, path: str | os.PathLike) -> None:
    """Refuse to write ``scene`` to ``path`` where a placed vertex is not a finite float32.

    Every mesh's vertices placed by its node's transform must be finite and within
    :data:`MAX_COORDINATE` (GLB and PLY store float32; a reader gets ``inf`` beyond it). A
    destination too far (``to`` 1e308) or a NaN in a node matrix would otherwise give a file
    of infinities that every reader refuses or draws as nothing.

    Parameters
    ----------
    scene : trimesh.Scene
        The meshes about to be written.
    path : str or os.PathLike
        The output, for the message.

    Raises
    ------
    partscale.errors.InputError
        Naming how many vertices are out of range.

    Examples
    --------
    >>> from partscale import data
    >>> from partscale.meshedit.route import _check_finite_scene, load_scene
    >>> _check_finite_scene(load_scene(data.table()), "table.glb")
    """
    bad = total = 0
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        vertices = getattr(scene.geometry.get(name), "vertices", None)
        if vertices is None:
            continue
        T = np.asarray(transform, np.float64)
        with np.errstate(all="ignore"):
            world = np.asarray(vertices, np.float64) @ T[:3, :3].T + T[:3, 3]
            ok = np.isfinite(world).all(axis=1) & (np.abs(world) <= MAX_COORDINATE).all(axis=1)
        bad += int((~ok).sum())
        total += len(world)
    if bad:
        raise InputError(
            f"{path}: expected finite vertices within float32's range (|x| <= "
            f"{MAX_COORDINATE:.3g}), got {bad:,} of {total:,} beyond it (a destination too far, or "
            "a NaN or infinity in the source's vertices or node matrices); nothing written"
        )


def display_colours(scene: trimesh.Scene, suffix: str) -> trimesh.Scene:
    """A copy of ``scene`` whose colours OBJ or PLY can carry as display (sRGB) values.

    glTF's base colour factors are linear light; an MTL's ``Kd`` and a PLY's vertex colours are
    display values (what :func:`partscale.ingest.load` reads, and most tools). For ``.obj`` each
    glTF (PBR) material becomes a simple one: ``Kd`` the factor in sRGB, its base colour
    texture kept. For ``.ply``, which has no materials, every mesh gets vertex colours: its
    texture sampled at each vertex's UV times its factor (in linear light), or its material's
    colour, in sRGB. Meshes with vertex colours are kept as they are.
    """
    from trimesh.visual import ColorVisuals, TextureVisuals
    from trimesh.visual.color import to_float, uv_to_color
    from trimesh.visual.material import PBRMaterial, SimpleMaterial

    from ..color import linear_to_srgb8, srgb8_to_linear

    out = scene.copy()
    for g in out.geometry.values():
        vis = getattr(g, "visual", None)
        if not isinstance(vis, TextureVisuals):
            continue
        mat = vis.material
        if isinstance(mat, PBRMaterial):
            # glTF factors are linear: 8-bit as trimesh reads them, float where an OBJ's Kd
            # was linearised (partscale.ingest.load_mesh_scene)
            factor = mat.baseColorFactor if mat.baseColorFactor is not None else [1.0] * 4
            lin = to_float(np.asarray(factor))[:3]
            if suffix == ".obj":
                kd = linear_to_srgb8(lin[None])[0]
                simple = SimpleMaterial(
                    image=mat.baseColorTexture, diffuse=[*kd, 255], name=mat.name
                )
                g.visual = TextureVisuals(uv=vis.uv, material=simple)
                continue
            n = len(g.vertices)
            if mat.baseColorTexture is not None and vis.uv is not None:
                texel = uv_to_color(vis.uv, mat.baseColorTexture)[:, :3]
                lin = srgb8_to_linear(texel) * lin
            rgb = linear_to_srgb8(np.broadcast_to(lin, (n, 3)).astype(np.float64))
        elif suffix == ".ply":
            rgb = vis.to_color().vertex_colors[:, :3]  # a simple material: display values
        else:
            continue
        alpha = np.full((len(rgb), 1), 255, np.uint8)
        g.visual = ColorVisuals(g, vertex_colors=np.hstack([rgb, alpha]))
    return out


@dataclass(frozen=True)
class MeshEditResult:
    """What :func:`edit_mesh_file` did: files written, triangles before and after, seams.

    Attributes
    ----------
    written : list of Path
        The files written (the mesh first).
    faces_in, faces_out : int
        Triangles in the source and in the result.
    seams : list of Seam
        The tile seams.
    off_square_deg : float, optional
        The turn about up that would square the source's walls (see below).
    turned_deg : float, optional
        With ``square``: the turn made for the edit (see below).

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale import meshedit
    >>> result = meshedit.MeshEditResult([Path("out.glb")], 120, 210, [])
    >>> result.faces_out - result.faces_in, result.off_square_deg
    (90, None)
    """

    written: list[Path]
    faces_in: int
    faces_out: int
    seams: list[Seam]
    #: the turn about up that would square the source's walls where the recipe changes x or z
    #: (:func:`partscale.orient.square_turn`); None where it is square or x and z are unchanged,
    #: and with ``square`` (which makes it)
    off_square_deg: float | None = None
    #: with ``square``: the turn made for the edit (and undone after it); 0.0 where none was
    #: needed or found
    turned_deg: float | None = None


def _face_count(scene) -> int:
    return int(
        sum(len(scene.geometry[scene.graph[n][1]].faces) for n in scene.graph.nodes_geometry)
    )


def _turn_scene(scene: trimesh.Scene, angle: float) -> dict:
    """Turn every node of ``scene`` by ``angle`` degrees about +y, about the origin, in place
    (the transforms of the base frame's children; no vertex is touched). Returns those
    transforms as they were, for :func:`_restore_turn`.
    """
    base = scene.graph.base_frame
    saved = {c: scene.graph[c][0].copy() for c in scene.graph.transforms.children[base]}
    m = np.eye(4)
    m[:3, :3] = turn_matrix(angle)
    scene.apply_transform(m)
    return saved


def _restore_turn(scene: trimesh.Scene, saved: dict) -> None:
    """Put back the transforms :func:`_turn_scene` changed, exactly (not turned back: a turn
    and its inverse leave the last bits of a matrix changed).
    """
    base = scene.graph.base_frame
    for child, matrix in saved.items():
        scene.graph.update(frame_from=base, frame_to=child, matrix=matrix)


def edit_mesh_file(
    src: str | os.PathLike,
    dst: str | os.PathLike,
    recipe: Recipe,
    *,
    square: bool = False,
    welded_only: bool = False,
) -> MeshEditResult:
    """Apply ``recipe`` to the mesh file ``src`` and write the edited mesh to ``dst``.

    With ``square`` the scene is turned about up (about the origin) so that its walls run
    along x and z (:func:`partscale.orient.square_turn`), edited there (the recipe's positions
    refer to the turned mesh: give them in ``%`` of its extent), and turned back: the output
    keeps the source's orientation in its scene.

    Parameters
    ----------
    src : str or os.PathLike
        The source mesh (one of :data:`MESH_SUFFIXES`).
    dst : str or os.PathLike
        The output mesh (one of :data:`OUTPUT_SUFFIXES`), written atomically.
    recipe : partscale.edit.Recipe
        The edits (positions refer to the source mesh).
    square : bool
        Edit the mesh turned square (see above).
    welded_only : bool
        Write nothing where a tile seam cannot be welded (its copies would meet with cracks):
        the result's ``written`` is then empty and its ``seams`` say which (``fit`` then edits
        the mesh's CSDF instead).

    Returns
    -------
    MeshEditResult
        Files written, triangles before and after, tile seams and the turn.

    Examples
    --------
    The shipped table made longer, then with its middle tiled: the triangles grow only by the
    cuts and the copies, and every seam is welded.

    >>> from partscale import data, meshedit
    >>> from partscale.edit import Recipe
    >>> longer = Recipe.parse({"edits": [{"axis": "x", "zone": ["30%", "70%"], "to": "120%"}]})
    >>> meshedit.edit_mesh_file(data.table(), "longer.glb", longer)
    MeshEditResult(written=[PosixPath('longer.glb')], faces_in=120, faces_out=210, seams=[], ...)
    >>> tiled = Recipe.parse(
    ...     {"edits": [{"axis": "x", "zone": ["30%", "70%"], "to": "170%", "mode": "tile"}]}
    ... )
    >>> result = meshedit.edit_mesh_file(data.table(), "tiled.obj", tiled)
    >>> result.written, len(result.seams), all(s.ok for s in result.seams)
    ([PosixPath('tiled.obj'), PosixPath('tiled.mtl')], 3, True)
    """
    dst = Path(dst)
    if dst.suffix.lower() not in OUTPUT_SUFFIXES:
        raise InputError(
            f"{dst}: expected an output mesh ({', '.join(OUTPUT_SUFFIXES)}), got "
            f"{dst.suffix or 'no suffix'}"
        )
    if not isinstance(square, bool):
        raise InputError(f"square: expected True or False, got {square!r}")
    from ..export import require_usd

    require_usd(dst)  # before any work: usd-core is an optional extra
    with warnings.catch_warnings(record=True) as said:
        # what reading noticed (a missing texture) is said once the edit is known to go
        # through: a refused edit gets its one error line alone
        warnings.simplefilter("always", PartscaleWarning)
        scene = load_scene(src)
    # the source's walls, before the recipe touches the scene
    wanted = square or any(e.axis in WALL_AXES for e in _planar(recipe))
    turn = square_turn(scene.triangles) if wanted else None
    saved = _turn_scene(scene, turn) if square and turn is not None else None
    out, seams = apply_recipe_to_scene(scene, recipe)
    for w in said:
        warnings.warn(w.message, w.category, stacklevel=2)
    if saved is not None:
        _restore_turn(out, saved)
    welded = all(seam.ok for seam in seams)
    written = save_scene(out, dst) if welded or not welded_only else []
    faces = _face_count(scene), _face_count(out)
    if square:
        return MeshEditResult(written, *faces, seams, turned_deg=round(turn or 0.0, 2))
    return MeshEditResult(written, *faces, seams, off_square_deg=turn)


@dataclass(frozen=True)
class MeshFrame:
    """A mesh file's extent and units, standing in for a CSDF where edit options are resolved.

    Options given in lengths or counts (``--by``, ``--copies``) read ``meta['units']`` and
    :meth:`surface_bounds`, as they would a CSDF's.

    Attributes
    ----------
    bounds : (2, 3) float64
        The world bounding box of the triangles: min corner, max corner.
    meta : dict
        ``{"units": "m"}``.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import meshedit
    >>> frame = meshedit.MeshFrame(np.array([[0.0, 0, 0], [2, 1, 1]]), {"units": "m"})
    >>> frame.surface_bounds().tolist()
    [[0.0, 0.0, 0.0], [2.0, 1.0, 1.0]]
    """

    bounds: np.ndarray  # (2, 3) float64
    meta: dict

    def surface_bounds(self) -> np.ndarray:
        """(2, 3) float64: :attr:`bounds`, as :meth:`partscale.csdf.CSDF.surface_bounds`."""
        return self.bounds


def mesh_frame(path: str | os.PathLike, *, square: bool = False) -> MeshFrame:
    """The world bounding box of a mesh file's triangles (all nodes placed), units metres.

    Parameters
    ----------
    path : str or os.PathLike
        A mesh file (one of :data:`MESH_SUFFIXES`).
    square : bool
        The bounds of the mesh turned square, as :func:`edit_mesh_file` edits it.

    Returns
    -------
    MeshFrame
        Its bounds and units.

    Examples
    --------
    >>> from partscale import data, meshedit
    >>> meshedit.mesh_frame(data.table()).surface_bounds().round(2).tolist()
    [[-1.23, 0.0, -0.65], [1.21, 0.95, 0.65]]
    """
    with warnings.catch_warnings():
        # a missing texture or material library is said once, by the edit that reads the
        # file for its colours (edit_mesh_file), not again for its extent
        warnings.simplefilter("ignore", PartscaleWarning)
        scene = load_scene(path)
    if square:
        turn = square_turn(scene.triangles)
        if turn is not None:
            _turn_scene(scene, turn)
    return MeshFrame(np.asarray(scene.bounds, np.float64), {"units": "m"})
