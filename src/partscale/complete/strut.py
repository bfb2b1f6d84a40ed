"""Struts: solid pieces the completion left apart from the object, joined to it.

A real object is one rigid piece, but a scan often misses what holds a part on: the thin grey
bar behind a swivel chair's seat that carries its back, a leg's end cut off by a shadow. After
the fusion such a part is a solid piece of its own, floating beside the rest. Each piece that
is not the largest (specks are gone by then: :func:`partscale.complete.tidy.drop_specks`) is
joined to it by the shortest path through space that no view saw *surely* free
(:func:`partscale.complete.column.sure_free`: free space inferred from missing readings or a
cropped scan's silhouette is no evidence against a thin bar), when that path spans at most
``MAX_GAP_SHARE`` of the object's size in outside space; the path, thickened to a strut of
radius ``RADIUS``, is guessed surface. A piece that only a longer path, or only one through
surely free space, would reach stays apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

MAX_GAP_SHARE = 0.2
"""Share of the object's longest side that a strut may span through outside space (its path's
length between the two solids): the TUM chairs' backs hang 14-15 cm above their seats (0.16-0.18
of the chair's height) on a bar no scan reads."""
RADIUS = 0.012
"""Metres: the strut's radius (a chair back's bar, a leg's end, 2-3 cm across)."""
MIN_RADIUS_VOXELS = 1.2
"""The strut's radius in voxels at least, so that a path's face neighbours are solid (a path
moving diagonally stays 6-connected)."""


@dataclass(frozen=True)
class Strut:
    """A strut from a piece (of ``piece_voxels`` solid voxels) to the object: ``start`` and
    ``end`` (3,) its path's ends in the grid's frame (world units), ``gap`` the outside space it
    spans and ``voxels`` the voxels it made solid."""

    piece_voxels: int
    start: np.ndarray
    end: np.ndarray
    gap: float
    voxels: int

    def as_dict(self) -> dict:
        return {
            "piece_voxels": self.piece_voxels,
            "start": np.round(self.start, 6).tolist(),
            "end": np.round(self.end, 6).tolist(),
            "gap": round(self.gap, 6),
            "voxels_added": self.voxels,
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
) -> tuple[np.ndarray, np.ndarray, list[Strut]]:
    """The SDF (X, Y, Z) float32 (world units, negative inside) and provenance (X, Y, Z) uint8
    with every solid piece (6-connected) apart from the largest joined to it by a strut where
    one spanning at most ``max_gap`` (world units) avoids the sure free space; the struts' surface marked
    ``guessed``. ``sure_free``: points (N, 3) in the grid's frame -> (N,) bool; ``origin``
    (3,) the grid's first voxel centre. Returns them and the struts made."""
    solid = sdf < 0
    lab, n = ndimage.label(solid)
    if n < 2:
        return sdf, prov, []
    size = np.bincount(lab.ravel())
    size[0] = 0
    main = int(np.argmax(size))
    joined = lab == main
    step = _Step(origin, h, max(float(radius), MIN_RADIUS_VOXELS * h), max_gap, sure_free, guessed)
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
            s = _strut(sdf, prov, lab == p, joined, boxes[p - 1], step)
            if s is None:
                left.append(p)
                continue
            struts.append(s)
            joined = ndimage.binary_propagation(joined, mask=sdf < 0)
        if len(left) == len(todo):
            break
        todo = left
    return sdf, prov, struts


@dataclass(frozen=True)
class _Step:
    origin: np.ndarray
    h: float
    radius: float
    max_gap: float
    sure_free: object
    guessed: int


def _strut(sdf, prov, piece, joined, box, step: _Step) -> Strut | None:
    """Adds one piece's strut to ``sdf`` and ``prov`` in place; the :class:`Strut` or None."""
    from skimage.graph import MCP_Geometric

    origin, h, r, max_gap = step.origin, step.h, step.radius, step.max_gap
    reach = int(np.ceil(max_gap / h)) + 2
    shape = np.array(sdf.shape)
    i0 = np.maximum([b.start - reach for b in box], 0)
    i1 = np.minimum([b.stop + reach for b in box], shape)
    sl = tuple(slice(int(a), int(b)) for a, b in zip(i0, i1, strict=True))
    target = joined[sl]
    if not target.any():
        return None
    src = piece[sl]
    solid = sdf[sl] < 0
    # only outside voxels within the reach of the piece are asked (the rest stay passable: a
    # path through them is longer than the bound anyway)
    ask = ~solid & (ndimage.distance_transform_edt(~src) <= reach)
    idx = np.argwhere(ask)
    free = np.zeros(solid.shape, bool)
    free[ask] = step.sure_free(origin + (idx + i0) * h)
    cost = np.where(free, np.inf, 1.0)
    mcp = MCP_Geometric(cost, fully_connected=True)
    costs, _ = mcp.find_costs(np.argwhere(src))
    at = np.where(target & np.isfinite(costs), costs, np.inf)
    k = int(np.argmin(at))
    # a step costs its length in voxels; the first step out of the piece and the last into the
    # object span one voxel of outside space between them
    gap = (float(at.flat[k]) - 1.0) * h
    if not np.isfinite(at.flat[k]) or gap > max_gap:
        return None
    path = np.array(mcp.traceback(np.unravel_index(k, at.shape)))
    on = np.zeros(solid.shape, bool)
    on[tuple(path.T)] = True
    d = (ndimage.distance_transform_edt(~on) * h - r).astype(np.float32)
    old = sdf[sl]
    take = (d < old) & ~free
    sdf[sl] = np.where(take, d, old)
    p = prov[sl]
    p[take & (np.abs(d) <= h)] = step.guessed
    p[take & (d < -h)] = 0  # buried by the strut: no longer surface
    prov[sl] = p
    ends = origin + (path[[0, -1]] + i0) * h
    return Strut(int(piece.sum()), ends[0], ends[1], gap, int((take & (d < 0) & ~solid).sum()))
