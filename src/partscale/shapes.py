"""Analytic shapes as CSDFs, with their closed-form signed distances.

Used for tests against analytic truth, for the evaluation's constructed cases and for demos
without data. Each ``*_sdf`` function evaluates the exact signed distance (negative inside) at
world points; :func:`grid` samples one on a grid that covers its bounds with a margin.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike

from .csdf import CSDF, make

SdfFunction = Callable[[np.ndarray], np.ndarray]


def box_sdf(points: np.ndarray, lo: ArrayLike, hi: ArrayLike) -> np.ndarray:
    """Exact signed distance to the axis-aligned box ``[lo, hi]``.

    Parameters
    ----------
    points : (..., 3) float
        World points.
    lo, hi : (3,) array_like of float
        The box's min and max corner.

    Returns
    -------
    (...,) float64
        Distance to the box's surface, negative inside.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.shapes import box_sdf
    >>> box_sdf(np.array([[0.5, 0.5, 0.5], [2, 0.5, 0.5]]), (0, 0, 0), (1, 1, 1))
    array([-0.5,  1. ])
    """
    p = np.asarray(points, dtype=np.float64)
    c = (np.asarray(lo, float) + np.asarray(hi, float)) / 2
    r = (np.asarray(hi, float) - np.asarray(lo, float)) / 2
    q = np.abs(p - c) - r
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
    inside = np.minimum(q.max(axis=-1), 0.0)
    return outside + inside


def sphere_sdf(points: np.ndarray, center: ArrayLike, radius: float) -> np.ndarray:
    """Exact signed distance to a sphere.

    Parameters
    ----------
    points : (..., 3) float
        World points.
    center : (3,) array_like of float
        The sphere's centre.
    radius : float
        Its radius.

    Returns
    -------
    (...,) float64
        Distance to the sphere, negative inside.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.shapes import sphere_sdf
    >>> sphere_sdf(np.array([[0, 0, 0], [2, 0, 0]]), (0, 0, 0), 1.0)
    array([-1.,  1.])
    """
    p = np.asarray(points, dtype=np.float64)
    return np.linalg.norm(p - np.asarray(center, float), axis=-1) - radius


def boxes_sdf(points: np.ndarray, boxes: Sequence[tuple[ArrayLike, ArrayLike]]):
    """Signed distance to a union of boxes: the least of their distances.

    Exact outside the union and for disjoint boxes; inside boxes that overlap it is the distance
    to the nearest box's own surface.

    Parameters
    ----------
    points : (..., 3) float
        World points.
    boxes : sequence of (lo, hi)
        Each box's min and max corner.

    Returns
    -------
    (...,) float64
        Distance, negative inside.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.shapes import boxes_sdf
    >>> boxes_sdf(np.array([[1.5, 0.5, 0.5]]), [((0, 0, 0), (1, 1, 1)), ((2, 0, 0), (3, 1, 1))])
    array([0.5])
    """
    return np.min([box_sdf(points, lo, hi) for lo, hi in boxes], axis=0)


def grid(
    sdf_function: SdfFunction,
    bounds: ArrayLike,
    *,
    voxel_size: float,
    margin: int = 3,
    color: Callable[[np.ndarray], np.ndarray] | Sequence[int] = (200, 120, 60),
    source: str = "analytic",
) -> CSDF:
    """Sample an analytic SDF on a grid covering ``bounds`` plus ``margin`` voxels.

    Parameters
    ----------
    sdf_function : callable (N, 3) float64 -> (N,) float64
        The signed distance (negative inside) at world points.
    bounds : (2, 3) array_like of float
        World box the shape lies in.
    voxel_size : float
        Voxel edge length, world units.
    margin : int
        Empty voxels between the bounds and the grid border.
    color : (3,) uint8 or callable (N, 3) points -> (N, 3) uint8
        sRGB colour, constant or a function of position.
    source : str
        What ``meta['source']`` says.

    Returns
    -------
    CSDF
        The sampled object.

    Examples
    --------
    >>> from partscale import shapes
    >>> ball = shapes.grid(
    ...     lambda p: shapes.sphere_sdf(p, (0, 0, 0), 0.5),
    ...     [(-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)],
    ...     voxel_size=0.1,
    ... )
    >>> ball.shape, ball.meta["source"]
    ((17, 17, 17), 'analytic')
    """
    b = np.asarray(bounds, dtype=np.float64)
    origin = b[0] - margin * voxel_size
    shape = np.ceil((b[1] - b[0]) / voxel_size).astype(int) + 2 * margin + 1
    axes = [origin[a] + np.arange(shape[a]) * voxel_size for a in range(3)]
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    sdf = sdf_function(pts).reshape(tuple(shape)).astype(np.float32)
    if callable(color):
        rgb = np.asarray(color(pts), dtype=np.uint8).reshape((*shape, 3))
    else:
        rgb = np.broadcast_to(np.asarray(color, np.uint8), (*shape, 3))
    return make(sdf, rgb, None, origin, voxel_size, {"source": source})


def box(lo, hi, *, voxel_size: float, margin: int = 3, color=(200, 120, 60)) -> CSDF:
    """A CSDF of the box ``[lo, hi]`` (exact SDF at every voxel).

    Parameters
    ----------
    lo, hi : (3,) array_like of float
        The box's min and max corner, world units.
    voxel_size : float
        Voxel edge length.
    margin : int
        Empty voxels around it.
    color : (3,) int
        sRGB colour.

    Returns
    -------
    CSDF
        The box.

    Examples
    --------
    >>> from partscale import shapes
    >>> b = shapes.box((0, 0, 0), (1, 0.5, 0.25), voxel_size=0.05)
    >>> b.shape, round(float(b.sdf.min()), 3)
    ((27, 17, 12), -0.1)
    """
    return grid(
        lambda p: box_sdf(p, lo, hi),
        (lo, hi),
        voxel_size=voxel_size,
        margin=margin,
        color=color,
        source=f"box {list(lo)} {list(hi)}",
    )


def sphere(center, radius, *, voxel_size: float, margin: int = 3, color=(60, 120, 200)) -> CSDF:
    """A CSDF of a sphere (exact SDF at every voxel).

    Parameters
    ----------
    center : (3,) array_like of float
        The sphere's centre.
    radius : float
        Its radius.
    voxel_size, margin, color
        As for :func:`box`.

    Returns
    -------
    CSDF
        The sphere.

    Examples
    --------
    >>> from partscale import shapes
    >>> ball = shapes.sphere((0, 0, 0), 1.0, voxel_size=0.1)
    >>> ball.shape, ball.rgb[10, 10, 10].tolist()
    ((27, 27, 27), [60, 120, 200])
    """
    c = np.asarray(center, float)
    return grid(
        lambda p: sphere_sdf(p, c, radius),
        (c - radius, c + radius),
        voxel_size=voxel_size,
        margin=margin,
        color=color,
        source="sphere",
    )


def bars(
    n: int,
    *,
    width: float,
    gap: float,
    height: float,
    depth: float,
    axis: int = 0,
    voxel_size: float,
    margin: int = 3,
) -> tuple[CSDF, list[tuple[np.ndarray, np.ndarray]]]:
    """A row of ``n`` identical disjoint bars spaced along ``axis``.

    Bar ``m`` spans ``[m * (width + gap), m * (width + gap) + width]`` along ``axis``; the other
    two axes span ``[0, height]`` and ``[0, depth]``.

    Parameters
    ----------
    n : int
        Number of bars.
    width, gap : float
        Each bar's width and the gap between two, along ``axis``.
    height, depth : float
        The bars' extent along the other two axes (in order).
    axis : int
        0, 1 or 2.
    voxel_size : float
        Voxel edge length.
    margin : int
        Empty voxels around them.

    Returns
    -------
    CSDF
        The bars.
    list of (lo, hi)
        Each bar's box, for analytic checks.

    Examples
    --------
    >>> from partscale import shapes
    >>> row, boxes = shapes.bars(3, width=0.1, gap=0.2, height=0.5, depth=0.3, voxel_size=0.02)
    >>> row.shape, len(boxes), boxes[1][0].round(2).tolist()
    ((42, 32, 22), 3, [0.3, 0.0, 0.0])
    """
    boxes = []
    others = [a for a in range(3) if a != axis]
    for m in range(n):
        lo = np.zeros(3)
        hi = np.zeros(3)
        lo[axis] = m * (width + gap)
        hi[axis] = lo[axis] + width
        hi[others[0]] = height
        hi[others[1]] = depth
        boxes.append((lo, hi))
    b = np.array([boxes[0][0], boxes[-1][1]])
    c = grid(
        lambda p: boxes_sdf(p, boxes), b, voxel_size=voxel_size, margin=margin, source=f"{n} bars"
    )
    return c, boxes


def bookcase(
    rows: int = 4,
    *,
    width: float = 0.8,
    height: float = 1.2,
    depth: float = 0.3,
    board: float = 0.02,
    voxel_size: float = 0.02,
    margin: int = 3,
) -> CSDF:
    """An open bookcase: two side boards and ``rows + 1`` shelves, equally spaced.

    The sides span ``[0, board]`` and ``[width - board, width]`` on x, ``[0, height]`` on y;
    shelf ``i`` spans ``[i * s, i * s + board]`` on y with ``s = (height - board) / rows``, between
    the sides; everything spans ``[0, depth]`` on z. The object the zone finders' examples use
    (``rows`` equal compartments along y).

    Parameters
    ----------
    rows : int
        Compartments (one fewer than the shelves).
    width, height, depth : float
        The outer box, world units.
    board : float
        Every board's thickness.
    voxel_size : float
        Voxel edge length.
    margin : int
        Empty voxels around it.

    Returns
    -------
    CSDF
        The bookcase.

    Examples
    --------
    >>> from partscale import shapes
    >>> case = shapes.bookcase()
    >>> case.surface_bounds().round(2).tolist()
    [[0.0, 0.0, 0.0], [0.8, 1.2, 0.3]]
    """
    boards = [((0, 0, 0), (board, height, depth)), ((width - board, 0, 0), (width, height, depth))]
    step = (height - board) / rows
    boards += [
        ((board, y, 0), (width - board, y + board, depth)) for y in step * np.arange(rows + 1)
    ]
    return grid(
        lambda p: boxes_sdf(p, boards),
        [(0, 0, 0), (width, height, depth)],
        voxel_size=voxel_size,
        margin=margin,
    )


def door(*, voxel_size: float = 0.01, margin: int = 3) -> CSDF:
    """A door with a knob: a board 0.8 wide, 1.2 high and 0.04 thick, a knob on its face.

    The board spans ``[0, 0.8]`` on x, ``[0, 1.2]`` on y and ``[0, 0.04]`` on z; the knob
    ``[0.62, 0.68]``, ``[0.55, 0.65]`` and ``[0.04, 0.08]``, standing out of the board's face.
    The object the local-feature examples use (:func:`partscale.zones.local_features`).

    Parameters
    ----------
    voxel_size, margin
        As :func:`grid` takes them.

    Returns
    -------
    CSDF
        The door.

    Examples
    --------
    >>> from partscale import shapes
    >>> shapes.door().surface_bounds().round(2).tolist()
    [[0.0, 0.0, 0.0], [0.8, 1.2, 0.08]]
    """
    parts = [((0, 0, 0), (0.8, 1.2, 0.04)), ((0.62, 0.55, 0.04), (0.68, 0.65, 0.08))]
    return grid(
        lambda p: boxes_sdf(p, parts),
        [(0, 0, 0), (0.8, 1.2, 0.08)],
        voxel_size=voxel_size,
        margin=margin,
    )
