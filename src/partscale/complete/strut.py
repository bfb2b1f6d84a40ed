"""Struts: solid pieces the completion left apart from the object, joined to it.

A real object is one rigid piece, but a scan often misses what holds a part on: the thin grey
bar behind a swivel chair's seat that carries its back, a leg's end cut off by a shadow. After
the fusion such a part is a solid piece of its own, floating beside the rest. Each piece that
is not the largest (specks are gone by then: :func:`partscale.complete.tidy.drop_specks`) is
joined to it by the shortest path through space that no view saw *surely* free
(:func:`partscale.complete.column.sure_carver`: free space inferred from missing readings or a
cropped scan's silhouette is no evidence against a thin bar), when that path spans at most
``MAX_GAP_SHARE`` of the object's size in outside space; the path, thickened to a strut of
radius ``RADIUS``, is guessed surface. A piece that only a longer path, or only one through
surely free space, would reach stays apart.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ..csdf import BAND_VOXELS
from . import tidy as tidy_mod

MAX_GAP_SHARE = 0.2
"""Share of the object's longest side that a strut may span through outside space (its path's
length between the two solids): the TUM chairs' backs hang 14-15 cm above their seats (0.16-0.18
of the chair's height) on a bar no scan reads."""
RADIUS = 0.012
"""Metres: the strut's radius (a chair back's bar, a leg's end, 2-3 cm across)."""
FIRST_BALL = 8
"""Voxels: the radius of the first ball the struts' search covers around a piece (then doubled
up to the reach of the longest strut allowed)."""
MIN_RADIUS_VOXELS = 1.2
"""The strut's radius in voxels at least, so that a path's face neighbours are solid (a path
moving diagonally stays 6-connected)."""


@dataclass(frozen=True)
class Strut:
    """A strut from a piece (of ``piece_voxels`` solid voxels) to the object: ``start`` and
    ``end`` (3,) its path's ends in the grid's frame (world units), ``gap`` the outside space it
    spans and ``voxels`` the voxels it made solid (``mirrored_voxels``: its mirror image's).
    """

    piece_voxels: int
    start: np.ndarray
    end: np.ndarray
    gap: float
    voxels: int
    mirrored_voxels: int = 0

    def as_dict(self) -> dict:
        """The strut as JSON-ready numbers (an entry of ``meta['completion']['struts']``)."""
        return {
            "piece_voxels": self.piece_voxels,
            "start": np.round(self.start, 6).tolist(),
            "end": np.round(self.end, 6).tolist(),
            "gap": round(self.gap, 6),
            "voxels_added": self.voxels,
            "mirrored_voxels_added": self.mirrored_voxels,
        }


def add_struts(
    sdf: np.ndarray,
    prov: np.ndarray,
    origin: np.ndarray,
    h: float,
    sure_free,
    guessed: int,
    max_gap: float,
    radius: float = RADIUS,
    mirror=None,
) -> tuple[np.ndarray, np.ndarray, list[Strut]]:
    """The SDF (X, Y, Z) float32 (world units, negative inside) and provenance (X, Y, Z) uint8
    with every solid piece (26-connected: pieces touching along an edge or at a corner are
    joined by :func:`partscale.complete.tidy.fill_contacts`) apart from the largest joined to it
    by a strut where
    one spanning at most ``max_gap`` (world units) avoids the sure free space; the struts'
    surface marked ``guessed``. ``sure_free``: points (N, 3) in the grid's frame -> (N,) bool;
    ``origin`` (3,) the grid's first voxel centre; ``mirror``, optional: points (N, 3) in the
    grid's frame -> their images in the object's mirror plane (N, 3) and (N,) bool where the
    plane holds; each strut's image is drawn too where it runs from a piece still apart to the
    solid through no sure free space (two armrests, each on a bar). Returns them and the struts
    made.
    """
    solid = sdf < 0
    # pieces touching along an edge or at a corner are one: the contact fill joins them
    lab, n = ndimage.label(solid, structure=tidy_mod.CORNERS)
    if n < 2:
        return sdf, prov, []
    size = np.bincount(lab.ravel())
    size[0] = 0
    main = int(np.argmax(size))
    joined = lab == main
    r = max(float(radius), MIN_RADIUS_VOXELS * h)
    step = _Step(origin, h, r, max_gap, sure_free, guessed, mirror)
    boxes = ndimage.find_objects(lab)
    todo = [int(i) for i in np.argsort(-size) if size[i] > 0 and i != main]
    sdf, prov = sdf.copy(), prov.copy()
    struts: list[Strut] = []
    # a piece may reach the object only through another one joined before it: repeat while any
    # piece joins (a handful of pieces, each searched in its own box)
    while todo:
        left = []
        for p in todo:
            if joined[boxes[p - 1]][lab[boxes[p - 1]] == p].any():
                continue  # joined already, through a strut to another piece
            s = _strut(sdf, prov, lab, p, int(size[p]), joined, boxes[p - 1], step)
            if s is None:
                left.append(p)
                continue
            struts.append(s)
            joined = _reached(joined, sdf < 0)
        if len(left) == len(todo):
            break
        todo = left
    return sdf, prov, struts


def _reached(seed: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(X, Y, Z) bool: ``seed`` and the face-connected pieces of ``mask`` it touches, as
    ``ndimage.binary_propagation(seed, mask=mask)`` gives it, by one labelling instead of a
    dilation repeated until nothing changes.
    """
    lab, n = ndimage.label(mask)
    hit = np.zeros(n + 1, bool)
    hit[lab[seed]] = True
    off = seed & ~mask
    if off.any():  # a seed outside the mask reaches the mask's voxels beside it
        hit[lab[ndimage.binary_dilation(off)]] = True
    hit[0] = False
    return seed | hit[lab]


@dataclass(frozen=True)
class _Step:
    origin: np.ndarray
    h: float
    radius: float
    max_gap: float
    sure_free: Callable[[np.ndarray], np.ndarray]
    guessed: int
    mirror: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None


def _strut(sdf, prov, lab, p, n, joined, box, step: _Step) -> Strut | None:
    """Adds the strut of piece ``p`` of ``lab`` (``n`` voxels, bounding ``box``) to ``sdf``
    and ``prov`` in place; the :class:`Strut` or None.

    The shortest path is searched among the voxels whose distances to the piece and to the
    object add up to at most a radius that grows (``FIRST_BALL`` voxels, then doubled, up to
    the reach of ``max_gap``): a path of length ``c`` voxels passes only voxels whose distances
    add up to ``c`` at most, so a path found no longer than the radius is the shortest of all,
    and most pieces hang a few voxels from the object (a search over the whole reach around a
    large piece costs the cube of the reach times its surface).
    """
    h, max_gap = step.h, step.max_gap
    reach = int(np.ceil(max_gap / h)) + 2
    radius = min(FIRST_BALL, reach)
    while True:
        found = _shortest(sdf, lab, p, joined, box, step, radius)
        if found is None:
            if radius >= reach:
                return None
            radius = min(2 * radius, reach)
            continue
        cost, path = found
        if cost <= radius or radius >= reach:
            break
        radius = min(max(2 * radius, int(np.ceil(cost))), reach)
    # a step costs its length in voxels; the first step out of the piece and the last into the
    # object span one voxel of outside space between them
    gap = (cost - 1.0) * h
    if gap > max_gap:
        return None
    added = _draw(sdf, prov, path, step)
    mirrored = 0
    if step.mirror is not None:
        mirrored = _mirrored(sdf, prov, path, joined, step, step.mirror)
    ends = step.origin + path[[0, -1]] * h
    return Strut(n, ends[0], ends[1], gap, added, mirrored)


def _shortest(sdf, lab, p, joined, box, step: _Step, radius: int):
    """The shortest path from piece ``p`` of ``lab`` to ``joined`` through the voxels no view
    saw surely free whose distances to the two add up to at most ``radius`` (voxels): its
    length in voxels and (K, 3) int voxel indices, or None. Only the piece's ``box`` grown by
    the radius is read.
    """
    from skimage.graph import MCP_Geometric

    shape = np.array(sdf.shape)
    i0 = np.maximum([b.start - radius - 1 for b in box], 0)
    i1 = np.minimum([b.stop + radius + 1 for b in box], shape)
    sl = tuple(slice(int(a), int(b)) for a, b in zip(i0, i1, strict=True))
    target = joined[sl]
    if not target.any():
        return None
    piece = lab[sl] == p
    solid = sdf[sl] < 0
    # a path leaves the piece from a voxel on its rim and ends at the first voxel of the object
    # it meets, on the object's rim: the insides of both are never passed through (searching
    # them cost more than the space between)
    rim = piece & ~ndimage.binary_erosion(piece, tidy_mod.CORNERS)
    inner = (piece & ~rim) | ndimage.binary_erosion(target, tidy_mod.CORNERS)
    # a path no longer than the radius passes only voxels whose distances to the piece and to
    # the object add up to the radius at most: only those are passable, and of them the
    # outside ones are asked (the shell around a large piece away from the object is not)
    apart = _distances(~rim) + _distances(~target)
    near = apart <= radius + 1e-6
    ask = ~solid & near
    idx = np.argwhere(ask)
    free = ~near | inner
    free[ask] = step.sure_free(step.origin + (idx + i0) * step.h)
    cost = np.where(free, np.inf, 1.0)
    mcp = MCP_Geometric(cost, fully_connected=True)
    # the rim voxels a path can leave from: passable, beside a passable voxel that is no start
    # (the search costs a Python step per start, and a large piece's rim is mostly far)
    leave = rim & ~free & ndimage.binary_dilation(~free & ~rim, tidy_mod.CORNERS)
    if not leave.any():
        return None
    costs, _ = mcp.find_costs(np.argwhere(leave))
    at = np.where(target & np.isfinite(costs), costs, np.inf)
    k = int(np.argmin(at))
    if not np.isfinite(at.flat[k]):
        return None
    path = np.array(mcp.traceback(np.unravel_index(k, at.shape))) + i0
    return float(at.flat[k]), path


def _distances(mask: np.ndarray) -> np.ndarray:
    """(X, Y, Z) float64: each voxel's distance in voxels to the nearest False voxel of
    ``mask`` (X, Y, Z) bool, as ``ndimage.distance_transform_edt`` gives it bit for bit (the
    square root of the exact squared distance, an integer), from ``edt``'s squared distances
    on two threads (3x faster on a strut's box; the mask handed on as uint8, which edt runs
    faster than bool).
    """
    import edt

    sq = edt.edtsq(np.ascontiguousarray(mask).view(np.uint8), parallel=2)
    return np.sqrt(sq.astype(np.float64))


def _draw(sdf, prov, path, step: _Step) -> int:
    """Unites the strut along ``path`` (K, 3) voxel indices into ``sdf`` and ``prov`` in place
    (carved by the sure free space); the voxels it made solid.
    """
    h, r = step.h, step.radius
    # every voxel whose distance the strut can change within the band is rewritten
    m = int(np.ceil(r / h)) + BAND_VOXELS + 1
    i0 = np.maximum(path.min(axis=0) - m, 0)
    i1 = np.minimum(path.max(axis=0) + m + 1, sdf.shape)
    sl = tuple(slice(int(a), int(b)) for a, b in zip(i0, i1, strict=True))
    on = np.zeros(tuple(i1 - i0), bool)
    on[tuple((path - i0).T)] = True
    d = (_distances(~on) * h - r).astype(np.float32)
    old = sdf[sl].copy()
    take = d < old
    ask = take & (old >= 0)
    free = np.zeros(take.shape, bool)
    free[ask] = step.sure_free(step.origin + (np.argwhere(ask) + i0) * h)
    take &= ~free
    sdf[sl] = np.where(take, d, old)
    p = prov[sl]
    p[take & (np.abs(d) <= h)] = step.guessed
    p[take & (d < -h)] = 0  # buried by the strut: no longer surface
    prov[sl] = p
    return int((take & (d < 0) & (old >= 0)).sum())


def _mirrored(sdf, prov, path, joined, step: _Step, mirror) -> int:
    """The strut's image in the object's mirror plane, drawn where the plane holds, the image
    runs from a piece still apart (not ``joined`` before this strut: the piece itself or its
    image) to the solid and crosses no sure free space; the voxels it made solid.
    """
    pts, holds = mirror(step.origin + path * step.h)
    if not holds.all():
        return 0
    j = np.rint((pts - step.origin) / step.h).astype(np.int64)
    if ((j < 0) | (j >= sdf.shape)).any():
        return 0
    solid = sdf < 0
    out = ~solid[tuple(j.T)]
    if not out.any():
        return 0  # a strut in the plane, or its image already there

    # both ends in the solid (the piece's and the object's images are there: no dangling bar),
    # the first in a piece still apart (no second bar to a piece joined already)
    def around(v):
        return tuple(slice(max(int(e) - 1, 0), int(e) + 2) for e in v)

    if not (solid[around(j[0])] & ~joined[around(j[0])]).any() or not solid[around(j[-1])].any():
        return 0
    if step.sure_free(step.origin + j[out] * step.h).any():
        return 0
    return _draw(sdf, prov, j, step)
