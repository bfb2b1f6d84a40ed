"""Which way an object faces about its up axis: the turn that squares its faces to x and z.

Every zone is a slab between two planes square to x, y or z. An object turned about up (a
photogrammetry mesh, a model placed at an angle) has no slab of constant cross-section along
x or z: suggest finds little, and fit falls back to thin slabs or global scaling.
:func:`square_turn` finds the turn that squares it, or says there is none to make;
``partscale import --square`` applies it to a mesh, and ``partscale scale IN.glb -o OUT.glb
--square`` edits a mesh turned square and turns the result back.

Up is +y (partscale's convention); a turn by ``angle`` degrees maps ``(x, z)`` to
``(x cos a + z sin a, -x sin a + z cos a)`` (right-handed about +y, as :func:`turn_about_up`).
"""

from __future__ import annotations

import numpy as np

from .csdf import CSDF

#: Turns smaller than this (degrees) are left undone: the object is square.
SQUARE_DEGREES = 0.5

#: Of the area of the walls (faces within ~17 degrees of vertical), at least this fraction must
#: run within :data:`_SPREAD_DEGREES` of one direction (or square to it) for that direction to
#: count as the object's.
MIN_SHARE = 0.5

#: The footprint's bounding rectangle, turned square, must be at least this much smaller than
#: as it stands: faces that run diagonally on an object that is square (a chair's crossed leg
#: frames, a star base) would make it larger.
MIN_SHRINK = 0.01

#: The axes the walls are squared to (up is y): edits along them are what a turn spoils.
WALL_AXES = ("x", "z")

_SPREAD_DEGREES = 2.0
_WALL = 0.3  # |n_y| below this: a wall, whose horizontal direction counts
_BIN = 0.25  # degrees of the 4-fold angle histogram


def off_square_message(turn: float, csdf: CSDF | None = None, *, mesh_route: bool = False) -> str:
    """The warning for an object whose walls run ``turn`` degrees off x and z, with its cure.

    What import, info, suggest, fit and the mesh route say (``turn`` from :func:`square_turn`
    or :func:`csdf_turn`). The cure is ``--square`` where the object is (or, given ``csdf``, was
    imported from) a mesh, else turning the source (a grid or a scan); the mesh route edits the
    file as it stands, so there both.

    Parameters
    ----------
    turn : float
        Degrees the walls run off x and z about up.
    csdf : CSDF, optional
        The object, whose history says whether it was imported from a mesh; None: a mesh.
    mesh_route : bool
        The message of the mesh route (which edits with ``--square``).

    Returns
    -------
    str
        One line, without a ``warning:`` prefix.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.orient import off_square_message
    >>> off_square_message(-20.0)
    'the walls run -20.0° off x and z about up: ... import the mesh with --square to turn it square'
    >>> off_square_message(-20.0, shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.1))
    '... turn its source so its walls run along x and z before import'
    """
    first = (csdf.meta.get("history") or [{}])[0] if csdf is not None else {}
    from_mesh = csdf is None or (first.get("op") == "import" and first.get("format") == "mesh")
    if mesh_route:
        cure = "edit it with --square (turned square for the edit, then back)"
    elif from_mesh:
        cure = "import the mesh with --square to turn it square"
    else:
        cure = "turn its source so its walls run along x and z before import"
    return (
        f"the walls run {turn:+.1f}° off x and z about up: zones are planes square to x, y, z, "
        f"so along x and z suggest and fit find little; {cure}"
    )


def square_note(turn: float, *, edit: bool = False) -> str:
    """What ``--square`` says it did: turned by ``turn`` degrees, or not turned.

    Parameters
    ----------
    turn : float
        Degrees turned about up; 0.0 where none was needed or no direction was found.
    edit : bool
        The mesh route's note: turned for the edit and back after it.

    Returns
    -------
    str
        One line, starting ``--square:``.

    Examples
    --------
    >>> from partscale.orient import square_note
    >>> square_note(-20.0)
    '--square: turned -20.00° about up: the walls now run along x and z'
    >>> square_note(0.0)
    '--square: not turned (the walls run within 0.5° of x and z, or no direction holds most of them)'
    """
    if not turn:
        return (
            f"--square: not turned (the walls run within {SQUARE_DEGREES}° of x and z, or no "
            "direction holds most of them)"
        )
    if edit:
        return (
            f"--square: turned {turn:+.2f}° about up for the edit (the walls along x and z; "
            "positions refer to the turned mesh), then turned back"
        )
    return f"--square: turned {turn:+.2f}° about up: the walls now run along x and z"


def turn_matrix(angle: float) -> np.ndarray:
    """(3, 3) float64: the rotation by ``angle`` degrees about +y (see the module).

    Parameters
    ----------
    angle : float
        Degrees, right-handed about +y.

    Returns
    -------
    (3, 3) float64
        The matrix ``R``; a column point ``p`` turns to ``R @ p``.

    Examples
    --------
    >>> from partscale.orient import turn_matrix
    >>> turn_matrix(90).round(6)
    array([[ 0.,  0.,  1.],
           [ 0.,  1.,  0.],
           [-1.,  0.,  0.]])
    """
    a = np.radians(angle)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def turn_about_up(points: np.ndarray, angle: float) -> np.ndarray:
    """(N, 3) float64: ``points`` (N, 3) turned by ``angle`` degrees about +y (see the module).

    Parameters
    ----------
    points : (N, 3) array_like of float
        Points (x, y, z), y up.
    angle : float
        Degrees, right-handed about +y.

    Returns
    -------
    (N, 3) float64
        The turned points; y is unchanged.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.orient import turn_about_up
    >>> turn_about_up(np.array([[1.0, 2.0, 0.0]]), 90).round(6)
    array([[ 0.,  2., -1.]])
    """
    return np.asarray(points, np.float64) @ turn_matrix(angle).T


def square_turn(triangles: np.ndarray) -> float | None:
    """Degrees to turn a surface about +y so that its walls run along x and z, or None.

    The walls' direction is the 4-fold mode of their normals' horizontal angle, weighted by area
    (a wall and the one square to it vote alike). It counts only where at least
    :data:`MIN_SHARE` of the wall area runs within 2 degrees of it, and where turning by it
    shrinks the footprint's bounding rectangle (the xz extent of the corners) by at least
    :data:`MIN_SHRINK`: a square object whose leg frames run diagonally has a strong mode at 45
    degrees and no smaller footprint there.

    Parameters
    ----------
    triangles : (T, 9) or (T, 3, 3) float
        Corners a, b, c of each triangle (x, y, z each, y up; any uniform scale: grid indices
        will do).

    Returns
    -------
    float or None
        The turn in (-45, 45] degrees (:func:`turn_about_up` with it squares the surface); None
        where it is under :data:`SQUARE_DEGREES` (already square) or no direction counts.

    Examples
    --------
    A box turned 20 degrees about up is turned back by -20:

    >>> import trimesh
    >>> from partscale.orient import square_turn, turn_about_up
    >>> box = trimesh.creation.box((1.0, 0.4, 0.6))
    >>> turned = turn_about_up(box.triangles.reshape(-1, 3), 20).reshape(-1, 9)
    >>> round(square_turn(turned), 3), square_turn(box.triangles)
    (-20.0, None)
    """
    t = np.asarray(triangles, np.float64).reshape(-1, 9)
    # |cross| is twice the area: area normals
    n = np.cross(t[:, 3:6] - t[:, 0:3], t[:, 6:9] - t[:, 0:3])
    return _turn(n, t.reshape(-1, 3))


def csdf_turn(csdf: CSDF) -> float | None:
    """:func:`square_turn` of ``csdf``'s surface, read from its distances.

    The surface is read as the gradient (central differences) at the voxels 1 to 2 voxels
    outside it, each standing for a like patch of the offset surface, in grid indices (the
    voxels are cubes).

    The exact distances there point square to the nearest wall. Marching cubes' facets of a
    wall off the grid's axes are a staircase whose normals spread and lean to the axes (at 128,
    a tvUnit turned 12 degrees went unfound and turned dressers and bookcases came out up to 1
    degree off; from the shell, 12 objects turned 12 and 31 degrees all within 0.25 degree);
    on the surface itself, central differences across a panel a voxel thick meet both faces.

    Parameters
    ----------
    csdf : CSDF
        The object; only its distances are read.

    Returns
    -------
    float or None
        As :func:`square_turn`: the turn in (-45, 45] degrees that squares the walls, or None.

    Examples
    --------
    A slab sampled turned by -20 degrees (its distance read at points turned by +20):

    >>> from partscale import shapes
    >>> from partscale.orient import csdf_turn, turn_about_up
    >>> slab = shapes.grid(
    ...     lambda p: shapes.box_sdf(turn_about_up(p, 20), (-0.5, -0.2, -0.3), (0.5, 0.2, 0.3)),
    ...     [(-0.7, -0.3, -0.7), (0.7, 0.3, 0.7)],
    ...     voxel_size=0.025,
    ... )
    >>> abs(csdf_turn(slab) - 20) < 0.25
    True
    >>> csdf_turn(shapes.box((0, 0, 0), (1, 0.4, 0.6), voxel_size=0.025)) is None
    True
    """
    sdf = np.asarray(csdf.sdf)
    h = csdf.voxel_size
    ijk = np.argwhere((sdf >= h) & (sdf <= 2.0 * h))
    ijk = ijk[(ijk > 0).all(axis=1) & (ijk < np.array(sdf.shape) - 1).all(axis=1)]
    n = np.empty((len(ijk), 3))
    for a in range(3):
        step = np.zeros(3, np.int64)
        step[a] = 1
        up, dn = ijk + step, ijk - step
        n[:, a] = sdf[tuple(up.T)].astype(np.float64) - sdf[tuple(dn.T)]
    return _turn(n, ijk.astype(np.float64))


def _turn(n: np.ndarray, points: np.ndarray) -> float | None:
    """:func:`square_turn` from area normals ``n`` (N, 3) and the surface's ``points`` (M, 3)
    (its footprint).
    """
    norm = np.linalg.norm(n, axis=1)
    wall = (norm > 0) & (np.abs(n[:, 1]) < _WALL * norm)
    if not wall.any():
        return None
    # weighted by the horizontal part of n (an area normal); angle times four: square
    # directions coincide
    w = np.hypot(n[wall, 0], n[wall, 2])
    a4 = np.degrees(4.0 * np.arctan2(n[wall, 2], n[wall, 0])) % 360.0
    nbins = round(360.0 / _BIN)
    hist = np.bincount(np.minimum((a4 / _BIN).astype(np.int64), nbins - 1), w, nbins)
    # the mode of the histogram summed over the spread (circularly): the densest direction
    half = round(4.0 * _SPREAD_DEGREES / _BIN)
    window = np.convolve(np.concatenate([hist[-half:], hist, hist[:half]]), np.ones(2 * half + 1))
    dense = window[2 * half : 2 * half + nbins]
    peak = (int(dense.argmax()) + 0.5) * _BIN
    off = (a4 - peak + 180.0) % 360.0 - 180.0
    near = np.abs(off) <= 4.0 * _SPREAD_DEGREES
    if w[near].sum() < MIN_SHARE * w.sum():
        return None
    mode4 = peak + float(np.average(off[near], weights=w[near]))
    # the walls' direction modulo 90 degrees, in (-45, 45]: turning by it squares them
    angle = ((mode4 + 180.0) % 360.0 - 180.0) / 4.0
    if angle <= -45.0:
        angle += 90.0
    if abs(angle) < SQUARE_DEGREES:
        return None

    def footprint(points: np.ndarray) -> float:
        span = points[:, [0, 2]].max(axis=0) - points[:, [0, 2]].min(axis=0)
        return float(span[0] * span[1])

    if footprint(turn_about_up(points, angle)) > (1.0 - MIN_SHRINK) * footprint(points):
        return None
    return angle
