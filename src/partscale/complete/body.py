"""Bodies under seen tops: the solid under a top, behind a wall, that no camera saw.

A cabinet seen from the front and above shows its top and its front. What lies behind the
front, under the top, no camera saw; closed thinly (the fusion's closure), the cabinet came out
two boards, and where a drawer's edges or a plinth's recess broke the fill between opposite
faces, a shell with its inside showing. Under each column of a top, the faces turned out along
each level grid axis in front of it (its walls) are walked down from the top; a wall that spans
most of the column's height above the floor (:data:`BODY_WALL`), over a column no camera saw
through down to the wall's bottom, says the column stands inside a body. A top is a body's as a
whole or not at all (:data:`BODY_SHARE`): a table's apron is a wall a tenth of its height, and
the few columns lined up with a leg do not make its top a box.

Index order in this module: the grid's axes with up second (``i, j, k``, ``j`` up, increasing
with height); :func:`close_bodies` turns the fusion's grid so and back.
"""

from __future__ import annotations

import numba
import numpy as np
from scipy import ndimage

BODY_WALL = 0.8
"""Share of a column's height above the floor that a wall in front of it spans, from the top
down, for the column to stand inside a body (a cabinet's front reaches down to its plinth; a
table's apron spans a tenth of the table's height)."""
BODY_SHARE = 0.5
"""Share of a top's columns that stand inside a body for the whole top to be a body's."""
BODY_GAP = 2
"""Slices of a wall without points (sensor holes, sparse rows) its walk down steps over."""
BODY_ACROSS = 5
"""Columns across its way by which a wall's points are widened (a sparse scan's rows of points
lie a few columns apart)."""
WALL_FACING = 0.7
"""Cosine between a point's normal and a level axis above which it lies on a wall turned that
way."""
TOP_FACING = 0.9
"""Cosine between a point's normal and up above which it lies on a top."""
NONE = 1 << 30


def close_bodies(
    solid: np.ndarray,
    idx: np.ndarray,
    normals: np.ndarray,
    up_axis: int,
    down: bool,
    heights: np.ndarray,
    h: float,
    unseen: np.ndarray,
    free: np.ndarray,
) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` with the bodies under its tops filled.

    Parameters
    ----------
    solid : (X, Y, Z) bool
        The solid so far.
    idx : (N, 3) int64
        The voxels of the surface points; ``normals`` (N, 3) float their unit normals (out of
        the object, in the grid's axes).
    up_axis : int
        The grid axis along up; ``down``: whether up runs toward its lower indices.
    heights : (S,) float64
        Height above the floor of each slice across ``up_axis``, in the grid's index order;
        ``h`` the voxel's size (a body reaches down to the first slice half a voxel above the
        floor).
    unseen : (X, Y, Z) bool
        The voxels no camera surely saw through (a column of a body is unseen from its top to
        its wall's bottom).
    free : (X, Y, Z) bool
        The voxels any camera saw through, sensor holes included: never filled (a body's fill
        never puts surface where a camera saw through it).

    Examples
    --------
    >>> solid = np.zeros((12, 12, 12), bool)
    >>> solid[2:10, 10, 2:10] = True  # a top
    >>> solid[2:10, 2:11, 9] = True  # its front, down to the floor
    >>> idx = np.argwhere(solid)
    >>> normals = np.where((idx[:, 1] == 10)[:, None], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0])
    >>> heights = np.arange(12) - 1.0
    >>> unseen = np.ones_like(solid)
    >>> unseen[:, 11, :] = unseen[:, :, 10:] = False
    >>> out = close_bodies(solid, idx, normals, 1, False, heights, 1.0, unseen, ~unseen)
    >>> bool(out[2:10, 2:11, 2:10].all()), int(out.sum() - out[2:10, 2:11, 2:10].sum())
    (True, 0)
    """
    ax = int(up_axis)
    if not solid.any():
        return solid

    def upright(a: np.ndarray) -> np.ndarray:
        a = np.moveaxis(a, ax, 1)
        return a[:, ::-1] if down else a

    S = upright(solid)
    hgt = np.asarray(heights, np.float64)[::-1] if down else np.asarray(heights, np.float64)
    sign = -1.0 if down else 1.0
    level = [a for a in range(3) if a != ax]
    tops = _marked(solid.shape, idx, normals[:, ax] * sign > TOP_FACING, upright)
    tops = ndimage.binary_dilation(tops, iterations=1)
    walls = np.zeros((4, *S.shape), bool)
    for d, (a, way) in enumerate([(level[0], 1), (level[0], -1), (level[1], 1), (level[1], -1)]):
        w = _marked(solid.shape, idx, normals[:, a] * way > WALL_FACING, upright)
        across = (1, 1, BODY_ACROSS) if d < 2 else (BODY_ACROSS, 1, 1)
        walls[d] = ndimage.maximum_filter(w, size=across)
    top = np.full((S.shape[0], S.shape[2]), -1, np.int64)
    _top_slices(S, tops, top)
    floor = int(np.argmax(hgt > 0.5 * h))
    bottoms = np.full((4, *top.shape), NONE, np.int64)
    _wall_bottoms(walls, top, floor, BODY_GAP, bottoms)
    bottom = _wall_bottom(top, bottoms, floor)
    inside = np.zeros(top.shape, bool)
    _unseen_down(upright(unseen), top, bottom, inside)
    fill = _tops_filled(S.shape, top, bottom, inside)
    fill &= ~upright(free)
    if down:
        fill = fill[:, ::-1]
    return solid | np.moveaxis(fill, 1, ax)


def _marked(shape, idx, which, upright) -> np.ndarray:
    """(X, Y, Z) bool, turned by ``upright``: the voxels of a grid of ``shape`` holding the
    points ``which`` (N,) bool of ``idx`` (N, 3) int.
    """
    m = np.zeros(shape, bool)
    q = idx[which]
    m[q[:, 0], q[:, 1], q[:, 2]] = True
    return upright(m)


def _wall_bottom(top: np.ndarray, bottoms: np.ndarray, floor: int) -> np.ndarray:
    """(X, Z) int64: each column's wall bottom, the shallowest of the walls in front of it that
    span ``BODY_WALL`` of its height above the ``floor`` slice (a sofa's front ends above its
    legs; its arm's side runs on down one of them); -1 where none does.
    """
    tall = (bottoms < NONE) & (top[None] - bottoms + 1 >= BODY_WALL * (top[None] + 1 - floor))
    return np.where(tall, bottoms, -1).max(axis=0)


def _tops_filled(shape, top: np.ndarray, bottom: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """(X, Y, Z) bool of ``shape``: the bodies' fill. Each top (a connected region of columns
    under a top) with ``BODY_SHARE`` of its columns ``inside`` (X, Z) bool is filled within the
    convex hull of those columns, from each column's ``top`` (X, Z) int down to the median of
    their wall ``bottom``s (X, Z) int: a body's inside is whole, not only the columns that
    passed (those beside a wall's sensor holes, under a drawer's gap, did not).
    """
    from skimage.morphology import convex_hull_image

    lab, n = ndimage.label(top >= 0)
    out = np.zeros(shape, bool)
    if n == 0:
        return out
    count = np.bincount(lab.ravel(), minlength=n + 1)
    ok = np.bincount(lab.ravel(), weights=inside.ravel(), minlength=n + 1)
    j = np.arange(out.shape[1])[None, :, None]
    for r in np.flatnonzero(ok[1:] >= BODY_SHARE * count[1:]) + 1:
        mine = lab == r
        hull = convex_hull_image(mine & inside) & mine
        low = int(np.median(bottom[mine & inside]))
        out |= hull[:, None, :] & (j <= top[:, None, :]) & (j >= low)
    return out


@numba.njit(cache=True)
def _top_slices(S, tops, top):
    # each column's top: its highest solid voxel, where a top's points lie
    X, Y, Z = S.shape
    for a in range(X):
        for c in range(Z):
            for j in range(Y - 1, -1, -1):
                if S[a, j, c]:
                    if tops[a, j, c]:
                        top[a, c] = j
                    break


@numba.njit(cache=True)
def _wall_bottoms(walls, top, floor, gap, bottoms):
    # for each way, walked from the far end of the way the wall faces back to each column: the
    # slices the walls in front of it cover, and from its top down through them (gaps of
    # ``gap`` slices stepped over) the lowest
    X, Y, Z = walls.shape[1], walls.shape[2], walls.shape[3]
    run = np.zeros(Y, np.bool_)
    for d in range(4):
        along_x = d < 2
        ahead = d % 2 == 0
        n_lines = Z if along_x else X
        n_along = X if along_x else Z
        for line in range(n_lines):
            run[:] = False
            out = 0
            for k in range(n_along):
                pos = n_along - 1 - k if ahead else k
                a, c = (pos, line) if along_x else (line, pos)
                if top[a, c] >= 0:
                    out = 0
                else:
                    out += 1
                    if out > gap:
                        run[:] = False  # past the top's edge: another part's walls
                        continue
                for y in range(Y):
                    if walls[d, a, y, c]:
                        run[y] = True
                t = top[a, c]
                if t > floor:
                    low = t
                    miss = 0
                    y = t
                    while y >= floor:
                        if run[y]:
                            low = y
                            miss = 0
                        else:
                            miss += 1
                            if miss > gap:
                                break
                        y -= 1
                    if low < t:
                        bottoms[d, a, c] = low


@numba.njit(cache=True)
def _unseen_down(unseen, top, bottom, inside):
    # a column stands inside a body where no camera saw through it from its top to its wall's
    # bottom
    X, Z = top.shape
    for a in range(X):
        for c in range(Z):
            if bottom[a, c] < 0 or top[a, c] < 0:
                continue
            ok = True
            for y in range(bottom[a, c], top[a, c]):
                if not unseen[a, y, c]:
                    ok = False
                    break
            inside[a, c] = ok
