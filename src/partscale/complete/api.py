"""Partial scan -> completed CSDF: the orchestration of the completion stage."""

from __future__ import annotations

import base64
import math
import os
import warnings
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import _schema
from .._options import keyword_options
from .._workers import thread_map
from ..csdf import BAND_VOXELS, CSDF, make
from ..errors import InputError, PartscaleWarning
from ..progress import ProgressCallback, resolve
from . import body as body_mod
from . import column as column_mod
from . import floor as floor_mod
from . import fuse as fuse_mod
from . import guard as guard_mod
from . import metric as metric_mod
from . import strut as strut_mod
from . import symmetry as sym_mod
from . import tidy as tidy_mod
from .carve import Carver, FreeGrid, affine_rows
from .floor import base_plane, clusters, find_floor, floor_scraps, in_plane_axes
from .scan import (
    MAX_PIXEL,
    Frame,
    denoise,
    frame_from_points,
    read_frame,
    read_points,
    read_views,
    upsample,
)

METHOD = "carve+floor+symmetry+between+slab+body+closure+reach+column+strut"
FLOOR_TOL = 0.015
"""Metres: RANSAC inlier distance of the floor."""
FLOOR_CUT = 2 * FLOOR_TOL
"""Metres above the floor below which the scan's points are taken for the floor (and with them
the bottom of what stands on it, which the fusion carries down to the floor again)."""
FACES_FLOOR_TILT_DEG = 5.0
"""Degrees from the up that the scan's faces give within which the floor is searched first."""
FACES_AGAINST_DEG = 10.0
"""Degrees from the faces' up beyond which a plane found near the camera's up is no floor."""
CLUSTER_CELL = 0.03
"""Metres: points closer than about this are one object when isolating it automatically (at
least; a sparser scan's cell is :data:`CLUSTER_SPACINGS` times its point spacing)."""
CLUSTER_SPACINGS = 4.0
"""The cell within which points are one object, in point spacings of the scan (the first frame's
pixel footprint at its median depth): a scan sparser than CLUSTER_CELL / CLUSTER_SPACINGS (a
far view, a coarse sensor) would otherwise fall apart into pieces of one object."""
MAX_OBJECT_EXTENT = 4.0
"""Metres: the largest object isolated automatically (a 3.3 m lounge sofa, a table for ten);
larger clusters are walls or the room."""
JOIN_WITHIN = 0.9
"""Share of a cluster standing within an object's footprint (or of the object within the
cluster's) that makes it part of the object when isolating automatically."""
STACK_GAP = 0.25
"""Metres between the boxes of two clusters one over the other within which they are one
object when isolating automatically (a riser's height and a tread's thickness: an open stair's
treads; a table's top over its pedestal)."""
MAX_JOINS = 32
"""Rounds of trying every cluster against the object when isolating automatically (a cluster
joins as soon as the object reaches it; a round that joins none ends the search)."""
FLOOR_CELL_M = 0.02
FLOOR_BROAD_M = 0.04
FLOOR_BROAD_SHARE = 0.6
"""A floor keeps at least this share of its cells (FLOOR_CELL_M) through an opening by a disc of
radius FLOOR_BROAD_M (floors seen 0.95-0.99; the TUM yellow chair's star base 0.24)."""
CLOSURE = 1.5
"""Voxels behind a surface point that the solid extends into space nobody saw (the closure)."""
CLOSURE_SPACINGS = 1.5
"""The scan's point spacings that the closure reaches at least (:func:`closure_for`)."""
NORMAL_NEIGHBOURS = 12
"""Scan points whose spread gives a point's normal (the side a camera saw it from)."""
KEEP_INSIDE = 0.05
"""Voxels inside the surface at which a voxel whose nearest voxel of the upright grid is
solid is kept, where interpolation would put it outside (:func:`into_input_frame`)."""
WALLS_ASKEW_DEG = 10.0
"""Degrees between the first mirror plane and the object's walls beyond which the upright grid
lies along the walls instead (:func:`lengthwise`)."""
SQUARE_COSINE = 0.9
"""|Cosine| between a second mirror plane's normal and the upright z above which the two planes
cross square (:func:`lengthwise`)."""
CARVE_MARGIN = 0.5
"""Voxels a point must lie in front of a reading to be free space (absorbs sensor noise)."""


BORDER_PIXELS = 2
CUT_PIXELS = 5
CUT_SHARE = 0.002
"""An object's pixels within ``BORDER_PIXELS`` of a side of the image, at least ``CUT_PIXELS``
of them and ``CUT_SHARE`` of its pixels in that frame, run out of it there
(:func:`cut_by_frames`)."""
UPSAMPLE_MAX = 4
"""Largest factor a frame's pixels are upsampled by along each side (:func:`densify`)."""
UPSAMPLE_ABOVE = 1.0
"""Pixel width (or point spacing) at the object, in voxels, above which a frame is upsampled:
points further apart than a voxel leave holes in the closure (a sofa's point cloud at 1.4)."""
UPSAMPLE_PIXELS = 8_000_000
"""Most pixels an upsampled frame may have (a 640 x 480 frame 5 times over)."""

MIN_UP_TILT_DEG = 0.5
"""Degrees below which the mirror plane's tilt does not correct up (the frame and the mirror
planes are not rebuilt for it; the tilt search's finest step is 0.25 degrees)."""
SYMMETRY_MARGIN = 3.0
"""Voxels a symmetric copy must lie in front of a reading to contradict the scan."""
SYMMETRY_RES = 128
"""Voxels across the object below which the symmetry tests' voxel stops shrinking: a finer grid
does not make the sensor's points more exact (at --res 256 the TUM purple chair's legs no longer
landed on each other within half its cells, and its base found no turn)."""
FREE_GRID_VOXELS = 1.5
"""Voxels between the points where the symmetry search tabulates the free space (a query reads
the nearest, at most 0.87 of these away: well inside SYMMETRY_MARGIN)."""


def _is_floor(P: np.ndarray, plane, inliers: np.ndarray, cropped: bool) -> bool:
    """A floor is broad (most of it survives an opening by a disc of ``FLOOR_BROAD_M``: the legs
    of a star base, wider than the seat, do not) and, in a cropped scan, reaches beyond what
    stands on it (in a full frame the rest is the room, wider than the floor seen).
    """
    rest = P[~inliers & (plane.height(P) > FLOOR_CUT)]
    if len(rest) < 10:
        return True
    a, b = in_plane_axes(plane.normal)
    if _broad(np.stack([P[inliers] @ a, P[inliers] @ b], axis=1)) < FLOOR_BROAD_SHARE:
        return False
    if not cropped:
        return True

    def extent(X):
        return max(np.subtract(*np.percentile(X @ d, [98, 2])) for d in (a, b))

    return extent(P[inliers]) > 1.3 * extent(rest)


def _faces_up(P: np.ndarray, pose: np.ndarray) -> np.ndarray | None:
    """(3,) up from the scan's faces (:func:`partscale.complete.floor.faces_up`) where they
    give it clearly, else None.
    """
    found = floor_mod.faces_up(P, pose)
    return found.up if found.clear else None


def _floor(P: np.ndarray, up: np.ndarray, faces: np.ndarray | None, cropped: bool):
    """The floor (Plane, (N,) bool inliers) of the scan's points ``P`` (N, 3), or None: near
    the ``faces``' up where they gave one (``FACES_FLOOR_TILT_DEG``), else near the camera's
    ``up``; a camera pitched far down (a handheld scan from above) sees the floor farther off
    its axis: searched there once more where it is a floor (broad, under all that stands on
    it). A plane found near the camera's up that lies far off the faces' up (a chair's back
    seen from above, a stair's riser) is no floor.
    """
    if faces is not None:
        found = find_floor(P, faces, FLOOR_TOL, max_tilt=FACES_FLOOR_TILT_DEG)
        if found is not None:
            return found
    found = find_floor(P, up, FLOOR_TOL)
    if found is None and not cropped:
        wide = find_floor(P, up, FLOOR_TOL, max_tilt=floor_mod.WIDE_TILT_DEG)
        if wide is not None and _is_floor(P, wide[0], wide[1], cropped):
            found = wide
    if found is not None and faces is not None:
        if found[0].normal @ faces < np.cos(np.radians(FACES_AGAINST_DEG)):
            return None
    return found


def _broad(X: np.ndarray) -> float:
    """Share of the occupied cells (FLOOR_CELL_M) of 2-D points X (N, 2) that an opening by a
    disc of radius FLOOR_BROAD_M keeps.
    """
    from scipy import ndimage

    idx = np.floor((X - X.min(axis=0)) / FLOOR_CELL_M).astype(np.int64)
    occ = np.zeros(tuple(idx.max(axis=0) + 1), bool)
    occ[idx[:, 0], idx[:, 1]] = True
    occ |= ndimage.binary_closing(occ, np.ones((3, 3), bool))  # the gaps between scan rows
    r = round(FLOOR_BROAD_M / FLOOR_CELL_M)
    yy, xx = np.mgrid[-r : r + 1, -r : r + 1]
    kept = ndimage.binary_opening(occ, yy**2 + xx**2 <= r * r)
    return float(kept.sum() / max(occ.sum(), 1))


def cluster_cell(frame: Frame) -> float:
    """Metres within which scan points are one object: :data:`CLUSTER_CELL`, or
    :data:`CLUSTER_SPACINGS` times the point spacing of a sparser ``frame`` (its pixel footprint
    at its median depth).
    """
    spacing = metric_mod.of_frame(frame).spacing
    return max(CLUSTER_CELL, CLUSTER_SPACINGS * spacing)


def _up_prior(frame: Frame) -> np.ndarray:
    return -frame.pose[:3, 1]


def _isolate(frames, P, pix, height, up, box, cropped, cell) -> np.ndarray:
    """(N,) bool: the object's points (above the floor, in the box, or found automatically)."""
    above = height > FLOOR_CUT
    if not above.any():
        raise InputError(
            "scan: expected an object above the floor, got only floor (or no points above it)"
        )
    if box is not None:
        x0, y0, x1, y1 = box
        W = frames[0].shape[1]
        u, v = pix % W, pix // W
        inbox = (pix >= 0) & (u >= x0) & (u < x1) & (v >= y0) & (v < y1)
        if not (above & inbox).any():
            raise InputError(
                f"box: expected scan points above the floor in pixels {list(box)}, got none"
            )
        idx = np.flatnonzero(above & inbox)
        lab = clusters(P[idx], cell)
        counts = np.bincount(lab)
        # a piece the box cuts (a desk edge behind the chair's back) is something else: only
        # the box's own sides cut, not the image's border
        H, W = frames[0].shape
        u, v = u[idx], v[idx]
        at_edge = (
            ((u <= x0) & (x0 > 0))
            | ((u >= x1 - 1) & (x1 < W))
            | ((v <= y0) & (y0 > 0))
            | ((v >= y1 - 1) & (y1 < H))
        )
        best = int(np.argmax(counts))
        cut = np.bincount(lab, at_edge, minlength=len(counts)) >= 3
        return _join_footprint(P, idx, lab, np.where(cut, 0, counts), best, up, cell)
    if cropped:
        return above
    idx = np.flatnonzero(above)
    lab = clusters(P[idx], cell)
    counts = np.bincount(lab)
    best = _nearest_centre(frames[0].shape, P, pix, height, idx, lab, counts)
    if best < 0:
        raise InputError(
            f"scan: expected an object of at most {MAX_OBJECT_EXTENT} m across above the floor, "
            "got none; pick one with box",
            params=("box",),
        )
    return _join_footprint(P, idx, lab, counts, best, up, cell)


def _nearest_centre(shape, P, pix, height, idx, lab, counts) -> int:
    """The label of the cluster nearest the image centre among those of an object's size
    standing on the floor; where none stands on it, among all of an object's size (seen from
    above or far off, a chair's legs or a table's may leave too few points to be one: the seat
    or the top floats); -1 where none is of an object's size.
    """
    H, W = shape
    picks = {True: (-1, (np.inf, 0)), False: (-1, (np.inf, 0))}
    # a cluster of an object's points: 200 of them, a quarter of a sparse scan's (a far view)
    least = max(min(200.0, 0.25 * len(idx)), 0.002 * len(idx), 30.0)
    for c in np.flatnonzero(counts >= least):
        m = idx[lab == c]
        ext = P[m].max(axis=0) - P[m].min(axis=0)
        if ext.max() > MAX_OBJECT_EXTENT:
            continue  # a wall or the room
        p0 = pix[m][pix[m] >= 0]
        if len(p0) == 0:
            continue
        # nearest the centre: the distance from the image centre to the cluster's pixel box, the
        # largest of those around it first (a stool's leg cut off by its seat's shadow is nearer
        # the centre than the stool by its mean, not by its box)
        u, v = p0 % W, p0 // W
        du = max(u.min() - W / 2, W / 2 - u.max(), 0.0)
        dv = max(v.min() - H / 2, H / 2 - v.max(), 0.0)
        key = (math.hypot(du, dv), -int(counts[c]))
        standing = bool(height[m].min() <= floor_mod.STANDS_WITHIN)
        if key < picks[standing][1]:
            picks[standing] = (int(c), key)
    return picks[True][0] if picks[True][0] >= 0 else picks[False][0]


def _join_footprint(P, idx, lab, counts, best, up, cell) -> np.ndarray:
    """(N,) bool: cluster ``best`` of the points ``P[idx]`` (labels ``lab``) and the clusters
    standing over its footprint or stacked on it.

    Parts of the same object the sensor separated (a swivel chair's seat above its base, with
    the gas-lift column lost along silhouettes; a stool's leg cut off its seat along the seat's
    shadow; a table's top above its legs; a star base wider than the seat): a cluster joins when
    its centre stands over the object's footprint, or nearly all of it within the footprint, or
    nearly all of the object within the cluster's (the cluster picked may be the leg), or it
    lies over or under the object, their boxes within :data:`STACK_GAP` (a round
    table's top over its pedestal, seen from above: the top hides its own underside and the
    pedestal's head; an open stair's treads, one over the next).
    """
    a, b = in_plane_axes(up)
    flat = np.stack([P[idx] @ a, P[idx] @ b], axis=1)
    height = P[idx] @ up
    members = {int(best)}
    m = lab == best
    # the object so far, taken again only when a cluster joins
    flat_m, h_m = flat[m], height[m]
    lo, hi = P[idx[m]].min(axis=0), P[idx[m]].max(axis=0)
    for _ in range(MAX_JOINS):
        grew = False
        for c in np.flatnonzero(counts >= 30):
            if c in members:
                continue
            mc = lab == c
            if not _joins(flat[mc], flat_m, height[mc], h_m, cell):
                continue
            Pc = P[idx[mc]]
            lo_c, hi_c = np.minimum(lo, Pc.min(axis=0)), np.maximum(hi, Pc.max(axis=0))
            if (hi_c - lo_c).max() > MAX_OBJECT_EXTENT:
                continue
            members.add(int(c))
            m |= mc
            flat_m, h_m, lo, hi = flat[m], height[m], lo_c, hi_c
            grew = True
        if not grew:
            break
    out = np.zeros(len(P), bool)
    out[idx[m]] = True
    return out


def _joins(flat_c, flat_m, h_c, h_m, cell) -> bool:
    """Whether a cluster (footprint points ``flat_c`` (n, 2), heights ``h_c`` (n,)) is part of
    the object found so far (``flat_m``, ``h_m``): see :func:`_join_footprint`.
    """

    def within(X, Y):
        # the share of footprint points X inside the box around footprint points Y
        lo_, hi_ = Y.min(axis=0) - cell, Y.max(axis=0) + cell
        return float(((X >= lo_) & (X <= hi_)).all(axis=1).mean())

    lo_m, hi_m = flat_m.min(axis=0) - cell, flat_m.max(axis=0) + cell
    centre = flat_c.mean(axis=0)
    if bool(((centre >= lo_m) & (centre <= hi_m)).all()):
        return True
    if max(within(flat_c, flat_m), within(flat_m, flat_c)) >= JOIN_WITHIN:
        return True
    # one over the other (heights apart) and their boxes within STACK_GAP of each other
    rise = max(float(h_c.min() - h_m.max()), float(h_m.min() - h_c.max()))
    apart = np.maximum(
        0.0,
        np.maximum(
            flat_c.min(axis=0) - flat_m.max(axis=0), flat_m.min(axis=0) - flat_c.max(axis=0)
        ),
    )
    return rise >= 0.0 and math.hypot(rise, *apart) <= STACK_GAP


def _upright(up: np.ndarray, forward: np.ndarray, floor_offset: float, centre: np.ndarray):
    """(4, 4) world -> upright: y = up (floor at 0), z = towards the camera, centred."""
    y = up / np.linalg.norm(up)
    z = -(forward - (forward @ y) * y)
    if np.linalg.norm(z) < 1e-6:  # looking straight down
        z = np.cross(np.array([1.0, 0, 0]), y)
    z /= np.linalg.norm(z)
    x = np.cross(y, z)
    U = np.eye(4)
    U[:3, :3] = np.stack([x, y, z])
    U[:3, 3] = -U[:3, :3] @ centre
    U[1, 3] = -floor_offset
    return U


def _apply(T: np.ndarray, P: np.ndarray) -> np.ndarray:
    return affine_rows(P, T[:3, :3], T[:3, 3])


def _sym4(s: sym_mod.Symmetry) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = s.A, s.b
    return T


@dataclass(frozen=True, eq=False)
class Observation:
    """What a scan says about one object: its points (N, 3) world and colours (N, 3) uint8,
    ``U`` (4, 4) world -> upright (y up, floor at 0, centred), the floor (Plane, inliers) or None,
    the (denoised) frames, the points' unit normals (N, 3) world, facing their camera, what
    gave up: ``"floor"``, ``"underside"`` (a level plane under the object that is no floor),
    ``"base"`` (:func:`partscale.complete.floor.base_plane`), ``"faces"``
    (:func:`partscale.complete.floor.faces_up`) or ``"camera"`` (its -y axis), and
    the factor each frame was upsampled by (:func:`densify`; empty: none was) and, for each
    frame, the sides of its image the object runs out of (:func:`cut_by_frames`).
    """

    frames: list
    points: np.ndarray
    colors: np.ndarray
    U: np.ndarray
    floor: object
    normals: np.ndarray
    up_from: str = "camera"
    cluster_cell: float = CLUSTER_CELL
    upsampled: tuple[int, ...] = ()
    cut: tuple[tuple[str, ...], ...] = ()


def normals(points: np.ndarray, eyes: np.ndarray) -> np.ndarray:
    """(N, 3) float64 unit normals of scan ``points`` (N, 3): the least-variance axis of their
    ``NORMAL_NEIGHBOURS`` nearest neighbours, turned towards the camera at ``eyes`` (N, 3) that
    saw each point.
    """
    from scipy.spatial import cKDTree

    k = min(NORMAL_NEIGHBOURS, len(points))
    _, nn = cKDTree(points).query(points, k=k, workers=2)
    X = points[nn] - points[nn].mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", X, X)
    _, vec = np.linalg.eigh(cov)
    n = vec[:, :, 0]
    flip = np.einsum("ni,ni->n", n, eyes - points) < 0
    n[flip] = -n[flip]
    return n


def _frame_points(frames: list[Frame]):
    """The frames' readings: points (N, 3) world, colours (N, 3) uint8, their flat pixels (N,)
    in the frame that read each, that frame's index (N,) and the eye that saw each (N, 3).
    """
    pts, cols, pixs, ids, eyes = [], [], [], [], []
    for i, f in enumerate(frames):
        p, c, q = f.points()
        pts.append(p)
        cols.append(c)
        pixs.append(q)
        ids.append(np.full(len(q), i))
        eyes.append(np.broadcast_to(f.pose[:3, 3], p.shape))
    out = (pts, cols, pixs, ids, eyes)
    return tuple(np.concatenate(a) for a in out)


def cut_by_frames(
    frames: list[Frame], pixels: np.ndarray, ids: np.ndarray
) -> tuple[tuple[str, ...], ...]:
    """For each frame, the sides of its image (``"left"``, ``"right"``, ``"top"``,
    ``"bottom"``) that the object's pixels reach: within ``BORDER_PIXELS`` of the side, at
    least ``CUT_PIXELS`` of them and ``CUT_SHARE`` of the object's pixels in that frame (the
    object runs on beyond what the camera framed); none for a frame made from a cropped mesh
    or point cloud (framed to hold it all). ``pixels`` (N,) int64: the object's flat pixels,
    ``ids`` (N,) the frame that read each.

    >>> import numpy as np
    >>> from partscale.complete import Frame
    >>> f = Frame(np.ones((10, 20), np.float32), None, np.eye(3), np.eye(4))
    >>> rows, cols = np.mgrid[4:10, 0:8]  # a block reaching the left and the bottom
    >>> cut_by_frames([f], (rows * 20 + cols).ravel(), np.zeros(48, int))
    (('left', 'bottom'),)
    """
    out: list[tuple[str, ...]] = []
    for i, f in enumerate(frames):
        q = pixels[ids == i]
        if f.cropped or not len(q):
            out.append(())
            continue
        H, W = f.shape
        v, u = np.divmod(q, W)
        near = {
            "left": u < BORDER_PIXELS,
            "right": u >= W - BORDER_PIXELS,
            "top": v < BORDER_PIXELS,
            "bottom": v >= H - BORDER_PIXELS,
        }
        least = max(CUT_PIXELS, CUT_SHARE * len(q))
        out.append(tuple(side for side, m in near.items() if m.sum() >= least))
    return tuple(out)


def observe(frames: list[Frame], *, box=None, source: str = "scan"):
    """The object's observed points and the upright frame: what every completion starts from.

    Returns
    -------
    Observation
    """
    # sensor noise would roughen every observed surface: smooth the range images (not the
    # frames made from meshes, whose points are kept as given)
    frames = [f if f.cropped else denoise(f) for f in frames]
    P, C, q, fid, E = _frame_points(frames)
    pix = np.where(fid == 0, q, -1)  # the first frame's pixels: where a box is drawn
    if len(P) < 10:
        raise InputError(f"{source}: expected a scan with depth readings, got {len(P)} points")
    cropped = all(f.cropped for f in frames)
    cell = cluster_cell(frames[0])
    up = _up_prior(frames[0])
    faces = None if cropped else _faces_up(P, frames[0].pose)
    found = _floor(P, up, faces, cropped)
    support = None
    if found is not None and not _is_floor(P, found[0], found[1], cropped):
        # a flat underside (a swivel chair's base, the legs of a star): it gives up, not a
        # floor. Whether it reaches beyond what stands on it is asked only of a cropped scan: a
        # sensor frame sees the room, and a large object framed closely (a sofa) leaves little
        # floor beside it
        support, found = found[0], None
    up_from = "camera"
    if found is None and support is None and cropped:
        # no floor and no level underside (the floor cut away): the plane of what the sensor
        # separated below the rest, a swivel chair's star base, before the camera's tilt
        support = base_plane(P, up, cell)
        up_from = "base" if support is not None else up_from
    elif support is not None:
        up_from = "underside"
    elif found is None and faces is not None:
        up, up_from = faces, "faces"
    if found is not None:
        plane, _ = found
        up, floor_offset = plane.normal, plane.offset
        height = plane.height(P)
        up_from = "floor"
    else:
        if support is not None:
            up = support.normal
        floor_offset = None
        height = P @ up
        height = height - height.min() + FLOOR_CUT + FLOOR_TOL  # every point is object
    obj = _isolate(frames, P, pix, height, up, box, cropped, cell)
    if up_from == "underside" and support is not None:
        # the level plane under an object that is no floor: scraps of the floor the scan kept
        # lie in it beside the object (the derived yellow chair's, beside its star base)
        obj &= ~floor_scraps(P, support, FLOOR_TOL, FLOOR_CELL_M, FLOOR_BROAD_M)
    Q, QC = P[obj], C[obj]
    if len(Q) < 30:
        raise InputError(f"{source}: expected an object of at least 30 points, got {len(Q)}")
    if floor_offset is None:
        floor_offset = float((Q @ up).min())
    centre = Q.mean(axis=0)
    U = _upright(up, frames[0].pose[:3, 2], floor_offset, centre)
    cut = cut_by_frames(frames, q[obj], fid[obj])
    return Observation(frames, Q, QC, U, found, normals(Q, E[obj]), up_from, cell, cut=cut)


def observe_metric(
    frames: list[Frame], *, box=None, source: str = "scan", scale: float | None = None
) -> tuple[Observation, tuple[float, str] | None, metric_mod.Plausibility]:
    """:func:`observe` the scan in metres: multiplied by ``scale`` where given; otherwise checked
    (:mod:`partscale.complete.metric`) and, where it is not plausible furniture in metres,
    warned about and observed at the guessed power of ten where there is one.

    Returns
    -------
    Observation
    (float, str) or None
        The factor applied to the scan and ``"option"`` or ``"guessed"``; None where none was.
    Plausibility
        The observation's extent and point spacing (:func:`partscale.complete.metric.of_points`).
    """
    if scale is not None:
        s = metric_mod.check_scale(scale)
        given = observe(metric_mod.scale_frames(frames, s), box=box, source=source)
        return given, (s, "option"), metric_mod.of_points(given.points, given.U)
    ob: Observation | None
    try:
        ob = observe(frames, box=box, source=source)
    except InputError:
        # no object found: a scan in other units may hold none of furniture's size
        ob, p = None, metric_mod.of_frame(frames[0])
        if p.plausible or p.guess() is None:
            raise
    else:
        p = metric_mod.of_points(ob.points, ob.U)
        if p.plausible:
            return ob, None, p
    factor = p.guess()
    scaled = None
    if factor is not None:
        try:
            scaled = observe(metric_mod.scale_frames(frames, factor), box=box, source=source)
        except InputError:
            if ob is None:
                raise
    if scaled is None:
        factor = None  # nothing to guess, or nothing found at that scale: the scan as it is
    warnings.warn(metric_mod.warning(p, source, factor), PartscaleWarning, stacklevel=3)
    if scaled is not None and factor is not None:
        return scaled, (factor, "guessed"), metric_mod.of_points(scaled.points, scaled.U)
    assert ob is not None  # observed as it is (a failed observation raised above)
    return ob, None, p  # measured on ob (a frame stands in only where no object was found)


def closure_for(closure: float, measured: metric_mod.Plausibility, res: int) -> float:
    """The closure in voxels: ``closure``, or ``CLOSURE_SPACINGS`` of the scan's point spacing
    (``measured``) on a grid ``res`` voxels along the object where that is more. Where the
    points lie more than a voxel apart (a fine grid, a far or sparse scan), a closure of so many
    voxels is thinner than the gaps between them, and the solid closes into a lace of tunnels
    (a sofa's range frame at --res 256, its points 2.5 voxels apart: 202 tunnels through its
    surface, 78 at the 3.8 voxels the closure reaches now).

    Examples
    --------
    >>> from partscale.complete.metric import Plausibility
    >>> closure_for(1.5, Plausibility(1.0, 0.005), 128)  # points 0.64 voxel apart
    1.5
    >>> closure_for(1.5, Plausibility(1.0, 0.02), 128)  # 2.56 voxels apart
    3.84
    """
    assert measured.extent is not None  # the points' own extent, always measured
    apart = measured.spacing * res / measured.extent
    return round(max(float(closure), CLOSURE_SPACINGS * apart), 2)


def densify(ob: Observation, res: int, measured: metric_mod.Plausibility) -> Observation:
    """The observation with its points read from its frames upsampled
    (:func:`partscale.complete.scan.upsample`) where their pixels at the object, or its points,
    lie more than ``UPSAMPLE_ABOVE`` voxels of a grid ``res`` voxels along the object apart: a
    sparse scan's points would otherwise close into a blob each, apart from their neighbours (a
    far view's fragment of a staircase fell into 157 pieces, dropped as specks), or into a lace
    of tunnels (a point cloud, whose frame leaves about half its pixels empty).

    Each frame by the smallest whole factor that brings them within a voxel, at most
    ``UPSAMPLE_MAX`` and ``UPSAMPLE_PIXELS`` pixels; ``ob`` itself where none is needed. What
    the observation found stays (up, the floor, which points are the object): the new points
    are those within a coarse pixel of the object's and above its floor. ``measured``: the
    observation's extent and point spacing (:func:`partscale.complete.metric.of_points`).
    """
    assert measured.extent is not None  # the points' own extent, always measured
    h = measured.extent / res
    ks, feet = [], []
    for f in ob.frames:
        z = (ob.points - f.pose[:3, 3]) @ f.pose[:3, 2]
        z = z[z > 0]
        foot = float(np.median(z)) / float(min(f.K[0, 0], f.K[1, 1])) if len(z) else 0.0
        foot = max(foot, measured.spacing)
        k = int(min(UPSAMPLE_MAX, math.ceil(foot / h - 1e-9))) if foot > UPSAMPLE_ABOVE * h else 1
        H, W = f.shape
        while k > 1 and H * W * k * k > UPSAMPLE_PIXELS:
            k -= 1
        ks.append(k)
        feet.append(foot)
    if max(ks) == 1:
        return ob
    from scipy.spatial import cKDTree

    P, C, _, _, E = _frame_points([upsample(f, k) for f, k in zip(ob.frames, ks, strict=True)])
    # a coarse pixel's diagonal around the object's own points: what lies between them
    reach = 1.5 * max(feet)
    near = np.isfinite(cKDTree(ob.points).query(P, distance_upper_bound=reach, workers=2)[0])
    if ob.floor is not None:
        near &= _apply(ob.U, P)[:, 1] > FLOOR_CUT
    P, C, E = P[near], C[near], E[near]
    # the free space stays the frames' own: their pixels are the rays the sensor cast, and the
    # silhouette's gaps and holes are sized in them
    return replace(ob, points=P, colors=C, normals=normals(P, E), upsampled=tuple(ks))


@keyword_options
def complete(
    frames: list[Frame],
    *,
    res: int = 128,
    box: Sequence[int] | None = None,
    upright: bool = False,
    symmetry: bool = True,
    closure: float = CLOSURE,
    force_completion: bool = False,
    scale: float | None = None,
    source: str = "scan",
    progress: ProgressCallback | None = None,
) -> CSDF:
    """Complete a partial scan into a watertight coloured SDF.

    Parameters
    ----------
    frames : list of Frame
        One or more registered views (:func:`read_frame`, :func:`frame_from_points`).
    res : int
        Voxels along the completed object's longest side (>= 16).
    box : (x0, y0, x1, y1), optional
        Pixel rectangle of the first frame holding the object (default: found automatically:
        the object standing on the floor nearest the image centre; a cropped scan is all object).
    upright : bool
        Write the grid in the upright frame (floor at y = 0, y up, the mirror plane at x = 0;
        with two mirror planes, x along the longer side: :func:`lengthwise`) instead of the
        input's frame. The completion is made upright either way; in the input's frame it is
        then resampled (:func:`into_input_frame`).
    symmetry : bool
        Look for and apply mirror planes and rotations (off: the closure alone).
    closure : float
        Voxels behind the surface that close the solid where nothing else does; at least 1.5
        of the scan's point spacings where its points lie further apart (:func:`closure_for`;
        the history's ``closure_voxels`` gives the closure used).
    force_completion : bool
        Keep the completion even where the scan's evidence speaks against it. Without it, a
        completion that drops observed surface, stands where the cameras saw through or falls
        apart into struts gives way to the scan as observed, closed (no symmetric copies or
        guessed parts), with a warning saying why (:mod:`partscale.complete.guard`).
    scale : float, optional
        Metres per unit of the scan: its coordinates (depths, camera positions) are multiplied by
        this. Without it, a scan whose extent or point spacing is not plausible furniture in
        metres gets a warning naming ``--scale``, and is completed at the power of ten that
        makes it plausible where there is one (:mod:`partscale.complete.metric`).
    source : str
        What the CSDF's ``meta['source']`` and the messages call the scan.
    progress : callable (fraction: float, message: str) -> None, optional
        Told how far the completion has got.

    Returns
    -------
    CSDF
        ``meta['completion']``: fractions of the surface ``observed``, ``mirrored`` (symmetric
        copies) and ``guessed``, the symmetries and floor found, ``to_input_frame`` (4x4, grid
        frame -> input frame), the per-voxel provenance (:func:`provenance`) and ``guard``:
        which result was kept (``"completion"`` or ``"observed"``), why, and the evidence.

    Raises
    ------
    InputError
        No views, a bad ``res`` or ``box``, or too few points of an object in the scan.

    Examples
    --------
    One view of the shipped table from a virtual sensor, completed at 32 voxels (without the
    search for symmetries, the slow part, to keep the example short):

    >>> from partscale import data, ingest
    >>> from partscale.complete import complete
    >>> from partscale.evaluate import virtual_scan
    >>> frames = virtual_scan(ingest.load_mesh(data.table()), 1)
    >>> table = complete(frames, res=32, symmetry=False)
    >>> max(table.shape) >= 32, table.meta["units"]
    (True, 'm')
    >>> done = table.meta["completion"]
    >>> round(float(done["observed"] + done["mirrored"] + done["guessed"]), 3)
    1.0
    >>> bool(done["observed"] > 0.3)
    True
    """
    from .._options import check_res

    report = resolve(progress)
    res = check_res(res, source)
    if not frames:
        raise InputError(f"{source}: expected at least one view, got none")
    if box is not None:
        box = tuple(
            int(_schema.number(b, "box", lo=-MAX_PIXEL, hi=MAX_PIXEL))
            for b in _schema.sequence(box, "box", length=4)
        )
        if len(box) != 4 or box[2] <= box[0] or box[3] <= box[1]:
            raise InputError(f"box: expected x0 y0 x1 y1 with x0 < x1 and y0 < y1, got {list(box)}")
    report(0.0, "reading the scan")
    ob, factor, measured = observe_metric(frames, box=box, source=source, scale=scale)
    dense = densify(ob, res, measured)
    # made in the object's upright frame whatever the output's: a grid along the scan's own axes
    # lies askew to the object's walls (a camera's frame), and the steps that read faces along
    # the grid's axes then miss them (into_input_frame)
    opts = Settings(res, box, True, closure_for(closure, measured, res), source, factor)
    # the space the cameras surely saw through: pixels without a reading say nothing
    carver = column_mod.sure_carver(ob.frames, 0.0)

    def observed() -> CSDF:
        report(0.9, "the scan as observed, closed")
        return _complete(
            ob, opts, symmetry=False, extras=False, report=lambda f, m: None, dense=dense
        )

    report(0.15, "symmetries")
    sy = find_symmetries(ob, opts.res, symmetry)
    weak = guard_mod.weak({"up_from": sy.up_from, "symmetries": _symmetries_meta(sy)})
    if weak and not force_completion:
        # symmetries on a guessed up or a doubtful turn: the guard keeps the scan as observed
        # whatever the completion's evidence, so the completion is not made
        out = guard_mod.give_way(observed(), ob.points, carver, weak)
    else:
        full = _complete(
            ob, opts, symmetry=symmetry, extras=True, report=report, dense=dense, sy=sy
        )
        out = guard_mod.choose(full, ob.points, carver, observed, force=force_completion)
    if not upright:
        report(0.97, "into the scan's frame")
        out = into_input_frame(out)
    report(1.0, "done")
    return out


def into_input_frame(c: CSDF) -> CSDF:
    """A completion made upright (its grid along the object's walls) on a grid along the scan's
    own axes: its distances interpolated (trilinear), its colours and provenance the nearest
    voxel's, ``to_input_frame`` then a translation at most and ``frame`` ``'input'``.

    Made in the scan's frame, a completion was voxelized askew to the object wherever the
    scan's world is not the object's own frame (a camera's is not): with the world turned 30
    degrees about up (``bench_complete_wide.py --world-yaw 30``), the 40 single views of
    untuned objects scored a median F@1% of 0.527 made so, 0.558 made upright and resampled
    (its 12 tuned objects 0.653 and 0.808).

    Parameters
    ----------
    c : CSDF
        A completion (:func:`complete` with ``upright=True``).

    Returns
    -------
    CSDF
        The same object in the scan's frame, the same voxel size.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import data, ingest
    >>> from partscale.complete import complete
    >>> from partscale.complete.api import into_input_frame
    >>> from partscale.evaluate import virtual_scan
    >>> up = complete(virtual_scan(ingest.load_mesh(data.table()), 1), res=32, upright=True)
    >>> c = into_input_frame(up)
    >>> c.meta["completion"]["frame"], c.voxel_size == up.voxel_size
    ('input', True)
    """
    from scipy import ndimage

    from .._memory import check_memory

    comp = c.meta["completion"]
    T = np.asarray(comp["to_input_frame"], np.float64)
    h = c.voxel_size
    # the solid's box in the scan's frame, padded for the band
    sb = c.surface_bounds()
    corners = np.array(
        [[sb[i, 0], sb[j, 1], sb[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )
    world = corners @ T[:3, :3].T + T[:3, 3]
    pad = (BAND_VOXELS + 2) * h
    lo, hi = world.min(axis=0) - pad, world.max(axis=0) + pad
    # the new lattice through the image of the old grid's middle voxel: where the turn is
    # small (a camera level with the object's walls), new centres fall on old ones near it
    mid = np.asarray(c.origin, np.float64) + (np.asarray(c.shape) // 2) * h
    anchor = T[:3, :3] @ mid + T[:3, 3]
    lo = anchor - np.ceil((anchor - lo) / h - 1e-9) * h
    shape = tuple(int(n) for n in np.ceil((hi - lo) / h - 1e-9).astype(np.int64) + 1)
    check_memory(shape, 40, what=f"{c.meta.get('source', 'the completion')} in its scan's frame")
    # each new voxel's centre in the old grid's index space: (T^-1 w - origin) / h
    back = np.linalg.inv(T)
    origin = np.asarray(c.origin, np.float64)[:, None]
    prov = provenance(c)
    far = float(c.sdf.max())
    sdf = np.empty(shape, np.float32)
    rgb = np.empty((*shape, 3), np.uint8)
    kinds = np.empty(shape, np.uint8)
    jk = np.indices(shape[1:], dtype=np.float64).reshape(2, -1)

    def slab(i: int) -> None:  # a slab at a time: the coordinates of one are small
        w = np.vstack([np.full(jk.shape[1], float(i)), jk]) * h + lo[:, None]
        g = (back[:3, :3] @ w + back[:3, 3][:, None] - origin) / h
        d = ndimage.map_coordinates(c.sdf, g, order=1, mode="constant", cval=far)
        near = np.rint(g).astype(np.int64)
        inside = ((near >= 0) & (near < np.asarray(c.shape)[:, None])).all(axis=0)
        nc = np.clip(near, 0, np.asarray(c.shape)[:, None] - 1)
        at = np.ravel_multi_index(tuple(nc), c.shape)  # the nearest old voxel, once
        # a sheet a voxel thick falls between the new voxels' centres: the nearest old voxel
        # keeps it solid (interpolated, its distances stay above zero)
        solid = inside & (c.sdf.ravel()[at] < 0)
        d = np.where(solid, np.minimum(d, -KEEP_INSIDE * h), d)
        sdf[i] = d.reshape(shape[1:])
        rgb[i] = c.rgb.reshape(-1, 3)[at].reshape(*shape[1:], 3)
        kinds[i] = np.where(inside, prov.ravel()[at], 0).reshape(shape[1:])

    # the slabs on threads (interpolation and numpy's gathers let go of the GIL)
    thread_map(slab, range(shape[0]))
    # the staircase of a turned grid touches itself along edges: filled as the fusion's own
    sdf, _ = tidy_mod.fill_contacts(sdf, h)
    # beyond the old grid the new voxels took its largest distance: a sphere tracer entering
    # there stepped that far at once, through a table's top (a completion's picture showed half
    # of it); bounded by the distance to the solid, as the fusion's own far values are
    sdf = fuse_mod.bound_far(sdf, h)
    meta = dict(c.meta)
    done = {**comp, "frame": "input", "to_input_frame": np.eye(4).tolist()}
    done["provenance"] = _encode(kinds)
    meta["completion"] = done
    history = [dict(x) for x in meta.get("history", [])]
    if history:
        history[-1]["upright"] = False
        history[-1]["made_upright"] = True
    meta["history"] = history
    return make(sdf, rgb, None, lo, h, meta)


@dataclass(frozen=True)
class Settings:
    """The options of one completion, checked: ``res`` voxels along the longest side, the pixel
    ``box`` or None, ``upright`` output, ``closure`` voxels, the ``source``'s name and the
    ``scale`` applied to the scan with where it came from (``"option"`` or ``"guessed"``), if any.
    """

    res: int
    box: tuple[int, ...] | None
    upright: bool
    closure: float
    source: str
    scale: tuple[float, str] | None = None


class FreeUp:
    """Free space at upright points (M, 3) -> (M,) bool, tabulated once (:class:`FreeGrid`) in
    the first upright frame ``U0``; :meth:`turn` follows the frame as the search turns it.
    """

    def __init__(self, free_grid: FreeGrid, U0: np.ndarray):
        self.free_grid, self.U0, self.U, self.Uinv = free_grid, U0, U0, np.linalg.inv(U0)

    def turn(self, U: np.ndarray) -> None:
        """The upright frame is now ``U`` (4, 4) world -> upright."""
        self.U, self.Uinv = U, np.linalg.inv(U)

    def __call__(self, p: np.ndarray) -> np.ndarray:
        """(M,) bool: whether upright points ``p`` (M, 3) lie in the scan's free space."""
        # until the frame turns (the mirror search) the upright frame is the table's: millions
        # of candidate points skip a transform by the identity
        if self.U is self.U0:
            return self.free_grid(p)
        return self.free_grid(p, frame=self.U0 @ self.Uinv)


@dataclass(eq=False)
class Symmetries:
    """The upright frame ``U`` (4, 4) world -> upright (``Uinv`` back; the first mirror plane at
    x = 0) and the symmetries found in it: mirror planes ``syms``, a turning base's ``rot`` (or
    None), a round object's ``turn`` (or None), where up came from and by how many degrees the
    mirror plane tilted it, the symmetry tests' voxel ``hs`` and ``cell`` (metres), the scan's
    free space (``carver``, ``free_up`` upright).
    """

    U: np.ndarray
    Uinv: np.ndarray
    syms: list[sym_mod.Symmetry]
    rot: sym_mod.Symmetry | None
    turn: sym_mod.Symmetry | None
    up_from: str
    up_tilt: float
    hs: float
    cell: float
    carver: Carver
    free_up: FreeUp


@dataclass(frozen=True, eq=False)
class Surface:
    """The surface to fuse, upright: ``points`` (N, 3) float64, ``colors`` (N, 3) uint8,
    ``kind`` (N,) uint8 (observed or mirrored), ``normals`` (N, 3); the symmetric ``views``
    ((4, 4) upright transform, where it holds) and the copies dropped in free space.
    """

    points: np.ndarray
    colors: np.ndarray
    kind: np.ndarray
    normals: np.ndarray
    views: list[tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]]
    n_dropped: int


@dataclass(frozen=True, eq=False)
class Grid:
    """The output grid (:class:`partscale.complete.fuse.GridFrame`), the surface in it
    (``points``, ``normals`` (N, 3) grid coordinates) and its extent ``lo``, ``hi`` (3,).
    """

    frame: fuse_mod.GridFrame
    points: np.ndarray
    normals: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


@dataclass(frozen=True, eq=False)
class Solid:
    """The completed field: ``sdf`` (X, Y, Z) float32, ``colours`` a callable giving rgb
    (X, Y, Z, 3) uint8 (made beside the steps after the fusion: :func:`fuse_mod.fuse`),
    ``prov`` (X, Y, Z) uint8 and what the steps after the fusion added or dropped.
    """

    sdf: np.ndarray
    colours: Callable[[], np.ndarray]
    prov: np.ndarray
    column: column_mod.Column | None = None
    n_column: int = 0
    n_specks: int = 0
    struts: tuple = ()
    n_filled: int = 0


def _complete(
    ob: Observation,
    opts: Settings,
    *,
    symmetry: bool,
    extras: bool,
    report: Callable[[float, str], None],
    dense: Observation | None = None,
    sy: Symmetries | None = None,
) -> CSDF:
    """The completion of an observation; ``extras`` False: no guessed column or struts; the
    symmetries are found on ``ob``'s points (``sy``: found already) and copy ``dense``'s
    (:func:`densify`) where given.

    The steps, each reported by name: the symmetries and the upright frame they fix
    (:func:`find_symmetries`), the symmetric copies of the surface (:func:`symmetric_copies`),
    the grid (:func:`plan_grid`), the carved and closed solid (:func:`fuse_solid`), the guessed
    parts (:func:`guess_parts`) and the metadata (:func:`completion_meta`).
    """
    if sy is None:
        report(0.15, "symmetries")
        sy = find_symmetries(ob, opts.res, symmetry)
    report(0.3, "symmetric copies")
    dense = ob if dense is None else dense
    surface = symmetric_copies(dense, sy)
    report(0.45, "grid")
    grid = plan_grid(surface, sy, opts)
    report(0.55, "carving and closing")
    # the scan as observed (no extras) is closed thinly: filled between opposite faces or
    # carried in as slabs, a side seen alone grew a block behind it that no camera saw
    solid = fuse_solid(ob, sy, surface, grid, opts, fill_between=extras)
    report(0.8, "guessed parts")
    solid = guess_parts(ob, sy, surface, grid, solid, symmetry=symmetry, extras=extras)
    report(0.95, "metadata")
    meta = completion_meta(dense, sy, surface, grid, solid, opts, symmetry=symmetry, extras=extras)
    g = grid.frame
    return make(solid.sdf, solid.colours(), None, g.origin, g.h, meta)


def find_symmetries(ob: Observation, res: int, symmetry: bool) -> Symmetries:
    """The observation's mirror planes and rotation (none without ``symmetry``) and the upright
    frame they fix: up corrected by the first plane's tilt where no level plane gave it, the
    first plane turned to x = 0; without a turning base, the turn of a round object
    (:func:`partscale.complete.symmetry.revolution`).
    """
    Q = ob.points
    U = ob.U
    Qu = _apply(U, Q)
    ext = Qu.max(axis=0) - Qu.min(axis=0)
    h0 = float(ext.max()) / res
    carver = Carver(ob.frames, CARVE_MARGIN * h0)
    # symmetry tests: "clearly in front of a reading", beyond depth noise and slopes; tabulated
    # once in the first upright frame around the object (copies land within about its size)
    lo0, hi0 = Qu.min(axis=0) - 0.25 * ext, Qu.max(axis=0) + 0.25 * ext
    hs = max(h0, float(ext.max()) / SYMMETRY_RES)
    free_grid = FreeGrid(
        carver, np.linalg.inv(U), lo0, hi0, FREE_GRID_VOXELS * hs, SYMMETRY_MARGIN * hs
    )
    free_up = FreeUp(free_grid, U)
    rng = np.random.default_rng(0)
    sub = rng.choice(len(Qu), min(len(Qu), 20000), replace=False)
    cell = 1.5 * hs
    syms: list[sym_mod.Symmetry] = []
    up_from, up_tilt = ob.up_from, 0.0
    if symmetry:
        syms, U, up_from, up_tilt = _mirrors_and_up(ob, U, sub, cell, free_up)
    if syms:
        syms, U = _plane_at_x0(syms, U)
        free_up.turn(U)
    Qs = _apply(U, Q)[sub]
    rot = sym_mod.rotation_axis(Qs, free_up, cell) if symmetry else None
    turn = None
    if symmetry and rot is None:
        turn = sym_mod.revolution(Qs, ob.normals[sub] @ U[:3, :3].T, free_up, cell)
    return Symmetries(
        U, np.linalg.inv(U), syms, rot, turn, up_from, up_tilt, hs, cell, carver, free_up
    )


def _mirrors_and_up(
    ob: Observation, U: np.ndarray, sub: np.ndarray, cell: float, free_up: FreeUp
) -> tuple[list[sym_mod.Symmetry], np.ndarray, str, float]:
    """Mirror planes of the scan's points ``sub`` in the upright frame ``U``; where up came from
    no level plane (a base, the faces, the camera), up tilted to the first plane's tilt and the
    planes searched again in that frame. Returns the planes, the frame, where up came from, the
    tilt (degrees).
    """
    Q, QC, QN = ob.points, ob.colors, ob.normals
    Qu, Nu0 = _apply(U, Q), QN @ U[:3, :3].T
    syms = sym_mod.mirror_planes(Qu[sub], QC[sub], free_up, cell, normals=Nu0[sub])
    up_from = ob.up_from
    if not syms or up_from not in ("base", "camera", "faces"):
        return syms, U, up_from, 0.0
    # a mirror plane contains up: where up is no level plane's (a floor, an underside) the
    # plane tilted across itself to fit the scan best says how far up is off across it (a
    # base's plane leans with its legs rising to the hub, the camera with its own tilt)
    n3, _ = sym_mod.tilted_plane(syms[0], Qu[sub], Nu0[sub], cell)
    y = np.array([0.0, 1.0, 0.0]) - n3[1] * n3
    y /= np.linalg.norm(y)
    up_tilt = float(np.degrees(np.arccos(np.clip(y[1], -1.0, 1.0))))
    # the tilt search's finest step is 0.25 degrees: a step or two of it is noise, not
    # worth the frame and the mirror search rebuilt
    if up_tilt < MIN_UP_TILT_DEG:
        return syms, U, up_from, 0.0
    up_w = np.linalg.inv(U)[:3, :3] @ y
    U = _upright(up_w, ob.frames[0].pose[:3, 2], float((Q @ up_w).min()), Q.mean(axis=0))
    free_up.turn(U)
    Qu, Nu0 = _apply(U, Q), QN @ U[:3, :3].T
    syms = sym_mod.mirror_planes(Qu[sub], QC[sub], free_up, cell, normals=Nu0[sub])
    return syms, U, up_from + "+mirror", up_tilt


def along_walls(points: np.ndarray, walls: float | None) -> np.ndarray:
    """(4, 4) float64: grid -> upright, a turn about up that lays the grid's x and z along the
    object's walls in plan, x along the longer, z as near the camera's way as it can be; the
    identity where its faces run no two ways square to each other (a round object).

    Without a mirror plane the upright frame's x and z follow the camera; the upright output
    grid then ran askew across an L-shaped sofa seen 20 degrees off its front, and ``fit`` read
    its straight back and seat as a slanted outline (refused: "round or curved there").
    ``points`` (N, 3) float64 are the surface, upright; ``walls`` the direction of its walls
    (:func:`partscale.complete.symmetry.walls_direction` of its normals, radians) or None.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.complete.api import along_walls
    >>> a = np.radians(20.0)
    >>> n = np.array([[np.cos(a), 0, np.sin(a)], [-np.sin(a), 0, np.cos(a)]] * 100)
    >>> p = np.c_[np.linspace(-1, 1, 200), np.zeros(200), np.zeros(200)] @ [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
    >>> from partscale.complete.symmetry import walls_direction
    >>> V = along_walls(p, walls_direction(n))
    >>> np.round(np.degrees(np.arctan2(V[2, 0], V[0, 0])), 1)  # the grid's x, upright
    np.float64(20.0)
    """
    V = np.eye(4)
    if walls is None or len(points) == 0:
        return V
    best = None
    for k in range(4):
        a = walls + k * np.pi / 2
        ex = np.array([np.cos(a), 0.0, np.sin(a)])
        ez = np.array([-np.sin(a), 0.0, np.cos(a)])
        key = (float(np.ptp(points @ ex)) > float(np.ptp(points @ ez)), float(ez[2]))
        if best is None or key > best[0]:
            best = (key, ex, ez)
    assert best is not None
    # columns: the grid's axes in the upright frame (grid -> upright, as lengthwise's turn)
    V[:3, :3] = np.stack([best[1], [0.0, 1.0, 0.0], best[2]], axis=1)
    return V


def _plane_at_x0(
    syms: list[sym_mod.Symmetry], U: np.ndarray
) -> tuple[list[sym_mod.Symmetry], np.ndarray]:
    """The upright frame ``U`` turned so that the first mirror plane is x = 0, and the planes
    in the turned frame.
    """
    p = syms[0].params
    n = np.array([np.cos(p["theta"]), 0.0, np.sin(p["theta"])])
    if n[0] < 0:
        n = -n
    V = np.eye(4)
    V[:3, :3] = np.stack([n, [0, 1, 0], np.cross(n, [0, 1, 0])])
    V[0, 3] = -float(n @ (syms[0].b / 2))
    Vinv = np.linalg.inv(V)
    turned = [
        sym_mod.Symmetry(
            s.kind,
            (V @ _sym4(s) @ Vinv)[:3, :3],
            (V @ _sym4(s) @ Vinv)[:3, 3],
            s.support,
            s.violation,
            s.fold,
            s.bands,
            s.params,
        )
        for s in syms
    ]
    return turned, V @ U


def symmetric_copies(ob: Observation, sy: Symmetries) -> Surface:
    """The observed surface (upright) and its copies by the group the mirrors generate (two
    planes: also their composition) and then the turns (a base's, a round object's); copies
    that land where a camera saw through are dropped.
    """
    U = sy.U
    Qu, QC = _apply(U, ob.points), ob.colors
    syms = sy.syms
    group: list[tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]] = [
        (_sym4(s), s.where) for s in syms
    ]
    if len(group) == 2:
        both = syms[0].where
        group.append((group[1][0] @ group[0][0], lambda p: both(p) & syms[1].where(p)))
    Nu = ob.normals @ U[:3, :3].T
    surf, surf_c, surf_n = [Qu], [QC], [Nu]
    kind = [np.full(len(Qu), fuse_mod.OBSERVED, np.uint8)]
    for g, where in group:
        w = where(Qu)
        cp = _apply(g, Qu[w])
        surf.append(cp)
        surf_c.append(QC[w])
        surf_n.append(Nu[w] @ g[:3, :3].T)
        kind.append(np.full(len(cp), fuse_mod.MIRRORED, np.uint8))
    rot_steps: list[tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]] = []
    for rot in (r for r in (sy.rot, sy.turn) if r is not None):
        allp, allc, alln = np.concatenate(surf), np.concatenate(surf_c), np.concatenate(surf_n)
        low = rot.where(allp)
        from scipy.spatial import cKDTree

        there = allp
        tree = cKDTree(there)
        step = np.eye(4)
        for _ in range(rot.fold - 1):
            step = _sym4(rot) @ step
            rot_steps.append((step.copy(), rot.where))
            cp = _apply(step, allp[low])
            # a turned copy completes what the scan lacks; on surface already there it would
            # only double it a little off. A round side's arc turned by a step shorter than the
            # arc lands on the copies before it too (a base's legs turned land apart): those
            # count as there (Kenney's bin from one view: 4.7 -> 3.0 s, the same F-score)
            new = tree.query(cp, distance_upper_bound=sy.cell, workers=2)[0] > sy.cell
            if rot.params.get("round"):
                there = np.concatenate([there, cp[new]])
                tree = cKDTree(there)
            surf.append(cp[new])
            surf_c.append(allc[low][new])
            surf_n.append(alln[low][new] @ step[:3, :3].T)
            kind.append(np.full(int(new.sum()), fuse_mod.MIRRORED, np.uint8))
    S, SC, SK = np.concatenate(surf), np.concatenate(surf_c), np.concatenate(kind)
    SN = np.concatenate(surf_n)
    copy = SK != fuse_mod.OBSERVED
    if copy.any():
        bad = np.zeros(len(S), bool)
        bad[copy] = sy.free_up(S[copy])
        S, SC, SK, SN = S[~bad], SC[~bad], SK[~bad], SN[~bad]
    n_dropped = int(copy.sum() - (SK != fuse_mod.OBSERVED).sum())
    return Surface(S, SC, SK, SN, group + rot_steps, n_dropped)


def plan_grid(surface: Surface, sy: Symmetries, opts: Settings) -> Grid:
    """The output grid around the surface: ``res`` voxels along its longest side, padded for the
    closure and the band, in the upright frame or the input's (``upright``); refused where it
    would not fit in memory.
    """
    turn = lengthwise(surface.points, surface.normals, sy.syms) if opts.upright else np.eye(4)
    grid_to_world = sy.Uinv @ turn if opts.upright else turn
    world_to_grid = np.linalg.inv(grid_to_world)
    Sg = _apply(world_to_grid @ sy.Uinv, surface.points)
    SNg = surface.normals @ (world_to_grid @ sy.Uinv)[:3, :3].T
    lo, hi = Sg.min(axis=0), Sg.max(axis=0)
    h = float((hi - lo).max()) / opts.res
    pad = math.ceil(opts.closure) + BAND_VOXELS + 2
    shape = np.ceil((hi - lo) / h - 1e-9).astype(np.int64) + 1 + 2 * pad
    origin = (lo + hi) / 2 - (shape - 1) / 2 * h
    if opts.upright:
        # the floor is the solid's lowest possible level: keep the grid from wasting space below
        cut = int(max(0, math.floor((lo[1] - origin[1]) / h) - pad))
        origin[1] += cut * h
        shape[1] -= cut
    from .._memory import check_memory

    shape_t = tuple(int(s) for s in shape)
    n = math.prod(shape_t)
    check_memory(
        shape_t,
        fuse_mod.peak_bytes(n) / n,
        what=f"{opts.source} at res {opts.res}",
        params=("res",),
    )
    return Grid(fuse_mod.GridFrame(grid_to_world, shape_t, origin, h), Sg, SNg, lo, hi)


def lengthwise(points: np.ndarray, normals: np.ndarray, syms: list[sym_mod.Symmetry]) -> np.ndarray:
    """(4, 4) float64: the upright output grid's axes in the upright frame (the first mirror
    plane at x = 0): turned a quarter about up where a second mirror plane crosses the first
    square (z = 0) and the object is longer along z, so that x runs along its length; with no
    mirror plane, or one askew to the walls (a square table's diagonal), along its walls
    (:func:`along_walls`).

    An object with one mirror plane has a left and a right (a chair, a sofa, a cabinet): x is
    across that plane, as a catalogue gives its width. One with two (a table, a bed) has no
    front; catalogues give the longer side first, and ``fit --size`` reads its x as that.
    ``points`` and ``normals`` (N, 3) float64 are its surface, upright.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.complete.api import lengthwise
    >>> lengthwise(np.zeros((2, 3)), np.zeros((2, 3)), []).tolist() == np.eye(4).tolist()
    True
    """
    R = np.eye(4)
    mirrors = [s for s in syms if s.kind == "mirror"]
    walls = sym_mod.walls_direction(normals)
    # a square object's diagonal is a mirror plane too: its walls, not the diagonal, give the
    # grid's axes (a bedside table 40 cm square, voxelized along its diagonal: F@1% 0.816 ->
    # 0.660 from three views)
    askew = walls is not None and abs((np.degrees(walls) + 45.0) % 90.0 - 45.0) > WALLS_ASKEW_DEG
    if not mirrors or askew:
        return along_walls(points, walls)
    if len(mirrors) < 2 or len(points) == 0:
        return R
    # the second plane's normal: the reflection's -1 eigenvector
    w, v = np.linalg.eigh(mirrors[1].A)
    normal = v[:, int(np.argmin(w))]
    ext = points.max(axis=0) - points.min(axis=0)
    if abs(normal[2]) < SQUARE_COSINE or ext[2] <= ext[0]:
        return R
    # grid x along upright z, grid z along upright -x (a turn about y: right-handed)
    R[:3, :3] = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    return R


def fuse_solid(
    ob: Observation,
    sy: Symmetries,
    surface: Surface,
    grid: Grid,
    opts: Settings,
    *,
    fill_between: bool = True,
) -> Solid:
    """The solid the surface, the free space (seen, and in each symmetric view) and the floor
    give (:func:`partscale.complete.fuse.fuse`; ``fill_between`` False: the closure alone).
    """
    g = grid.frame
    U, Uinv, carver = sy.U, sy.Uinv, sy.carver
    carver.margin = CARVE_MARGIN * g.h
    sym_free: list[Callable[[np.ndarray], np.ndarray]] = []
    for m, where in surface.views:
        gi = np.linalg.inv(m)

        def f(pw, gi=gi, where=where):
            # a symmetric view of the free space, only at heights where the symmetry holds
            pu = _apply(U, pw)
            out = np.zeros(len(pw), bool)
            w = where(pu)
            out[w] = carver.free(_apply(Uinv @ gi, pu[w]))
            return out

        sym_free.append(f)

    def height_world(pw):
        return _apply(U, pw)[:, 1]

    sdf, colours, prov = fuse_mod.fuse(
        g.grid_to_world,
        g.shape,
        g.origin,
        g.h,
        grid.points,
        surface.colors,
        surface.kind,
        grid.normals,
        carver.free,
        sym_free,
        height_world,
        opts.closure,
        fill_between=fill_between,
        floor_cut=None if ob.floor is None else FLOOR_CUT,
        sure_free=column_mod.sure_carver(ob.frames, CARVE_MARGIN * g.h).free,
    )
    if not (sdf < 0).any():
        raise InputError(f"{opts.source}: expected a solid after completion, got none (all carved)")
    return Solid(sdf, colours, prov)


def guess_parts(
    ob: Observation,
    sy: Symmetries,
    surface: Surface,
    grid: Grid,
    solid: Solid,
    *,
    symmetry: bool,
    extras: bool,
) -> Solid:
    """The fused solid with a turning base's guessed column (with ``symmetry``), the scan's
    specks dropped, the pieces it left apart joined by struts (with ``extras``) and its
    diagonal-only contacts filled; the distances beyond the band bounded again.
    """
    g = grid.frame
    h, origin = g.h, g.origin
    sdf, prov = solid.sdf, solid.prov
    # a turning base's column to the seat, which sensors rarely read (thin, black): guessed
    # where only the sure free space allows it
    sure = column_mod.sure_carver(ob.frames, column_mod.SURE_MARGIN_VOXELS * h)
    Uinv = sy.Uinv

    def sure_free_up(pu):
        return sure.free(_apply(Uinv, pu))

    col = None
    if symmetry:
        col = column_mod.find_column(surface.points, sy.rot, sure_free_up, h)
        if col is None and sy.rot is None:
            # no turning base: a pedestal under a top, on the mirror planes' crossing
            col = column_mod.find_pedestal(surface.points, sy.syms, sure_free_up, h)
    n_column = 0
    grid_to_up = sy.U @ g.grid_to_world
    if col is not None:
        sdf, prov, n_column = column_mod.add_column(
            sdf, prov, col, grid_to_up, origin, h, sure_free_up, fuse_mod.GUESSED
        )
    # made fit to mesh: scan noise's floating specks dropped, diagonal-only contacts filled
    # (marching cubes would join them by edges of four faces)
    sdf, n_specks = tidy_mod.drop_specks(sdf, h)
    # a part the scan left apart (a chair's back on a bar nobody saw, a leg's end): joined by a
    # thin strut where the sure free space leaves a short path
    struts: list = []
    if extras:
        sdf, prov, struts = strut_mod.add_struts(
            sdf,
            prov,
            origin,
            h,
            lambda pg: sure_free_up(_apply(grid_to_up, pg)),
            fuse_mod.GUESSED,
            strut_mod.MAX_GAP_SHARE * float((grid.hi - grid.lo).max()),
            mirror=_mirror_in_grid(sy.syms, grid_to_up),
        )
    sdf, n_filled = tidy_mod.fill_contacts(sdf, h)
    # beyond the band, distances to what the steps since the fusion added
    sdf = fuse_mod.bound_far(sdf, h)
    return Solid(sdf, solid.colours, prov, col, n_column, n_specks, tuple(struts), n_filled)


def _mirror_in_grid(syms: list[sym_mod.Symmetry], grid_to_up: np.ndarray):
    """The first mirror plane (x = 0 upright) in grid coordinates, where it holds: grid points
    (M, 3) -> (their images (M, 3), (M,) bool where it holds); None without a plane.
    """
    if not syms:
        return None
    M = np.linalg.inv(grid_to_up) @ _sym4(syms[0]) @ grid_to_up

    def mirror_grid(pg):
        return _apply(M, pg), syms[0].where(_apply(grid_to_up, pg))

    return mirror_grid


def completion_meta(
    ob: Observation,
    sy: Symmetries,
    surface: Surface,
    grid: Grid,
    solid: Solid,
    opts: Settings,
    *,
    symmetry: bool,
    extras: bool,
) -> dict:
    """The completion's ``meta``: ``source``, ``units``, the history entry and ``completion``
    (shares of the surface by kind, what was found and added, the frames, the provenance).
    """
    g = grid.frame
    surface_vox = np.abs(solid.sdf) <= g.h
    counts = np.bincount(solid.prov[surface_vox], minlength=4).astype(np.float64)
    total = max(counts[1:].sum(), 1.0)
    found: Any = ob.floor
    col = solid.column
    inside = solid.sdf < 0
    n_pieces, apart = pieces(inside)
    completion = {
        "method": METHOD if extras else "carve+floor+closure+reach",
        "observed": round(counts[fuse_mod.OBSERVED] / total, 4),
        "mirrored": round(counts[fuse_mod.MIRRORED] / total, 4),
        "guessed": round(counts[fuse_mod.GUESSED] / total, 4),
        "views": len(ob.frames),
        "points_observed": len(ob.points),
        "upsampled": list(ob.upsampled) or None,
        "copies_dropped_in_free_space": surface.n_dropped,
        "specks_dropped": solid.n_specks,
        "contact_voxels_filled": solid.n_filled,
        "column": None if col is None else {**col.as_dict(), "voxels_added": solid.n_column},
        "struts": [st.as_dict() for st in solid.struts],
        "floor": None
        if found is None
        else {"normal": found[0].normal.round(6).tolist(), "offset": round(found[0].offset, 6)},
        "cut_by_frame": [list(c) for c in ob.cut],
        "pieces": n_pieces,
        "apart": apart,
        # the lowest solid voxel is a surface voxel (nothing solid below it): those alone
        "above_floor": None if found is None else above_floor(inside & surface_vox, g, found[0]),
        "up": sy.U[1, :3].round(6).tolist(),
        "up_from": sy.up_from,
        "up_tilt_by_mirror_deg": round(sy.up_tilt, 3),
        "symmetries": _symmetries_meta(sy),
        "frame": "upright" if opts.upright else "input",
        "to_input_frame": g.grid_to_world.round(9).tolist(),
        "upright_from_input": sy.U.round(9).tolist(),
        "provenance": _encode(solid.prov),
    }
    history = _history(ob, sy, opts, symmetry=symmetry)
    return {"source": opts.source, "units": "m", "history": [history], "completion": completion}


def pieces(solid: np.ndarray) -> tuple[int, float]:
    """The number of pieces of ``solid`` (X, Y, Z) bool (voxels touching by a face, an edge or a
    corner are one piece, as :func:`partscale.complete.strut.add_struts` joins them) and the
    share of its voxels outside the largest, rounded to 4 places.

    >>> import numpy as np
    >>> s = np.zeros((6, 3, 3), bool)
    >>> s[0, 1, 1] = s[1, 2, 2] = s[4, 1, 1] = True  # two touching at a corner, one apart
    >>> pieces(s)
    (2, 0.3333)
    """
    from scipy import ndimage

    lab, n = ndimage.label(solid, structure=tidy_mod.CORNERS)
    if n < 2:
        return int(n), 0.0
    size = np.bincount(lab.ravel())[1:]
    return int(n), round(1.0 - float(size.max()) / float(size.sum()), 4)


def above_floor(solid: np.ndarray, grid: fuse_mod.GridFrame, floor) -> float | None:
    """Metres from the ``floor`` (a :class:`partscale.complete.floor.Plane` in the scan's
    world) up to the lowest face of ``solid`` (X, Y, Z) bool on ``grid`` (whose ``to_world``
    gives the scan's world): its lowest voxel centre less half a voxel, rounded to the
    millimetre; None without a solid.
    """
    at = np.flatnonzero(solid.ravel())
    if not len(at):
        return None
    lowest = float(floor.height(grid.to_world(grid.centres(at))).min()) - 0.5 * grid.h
    return round(lowest, 3)


def _symmetries_meta(sy: Symmetries) -> list[dict]:
    """The mirror planes (support, violation, the heights where each is applied, and of those
    the heights where its copies land only where no camera looked) and the rotation.
    """

    def heights(bands) -> list[list[float]]:
        return [[max(a, -1e9), min(b, 1e9)] for a, b in bands]

    out: list[dict] = [
        {
            "kind": "mirror",
            "support": round(s.support, 3),
            "violation": round(s.violation, 3),
            "heights": heights(s.bands),
            "heights_unseen": heights(s.params.get("unseen_bands", ())),
        }
        for s in sy.syms
    ]
    for rot in (r for r in (sy.rot, sy.turn) if r is not None):
        out.append(
            {
                "kind": "rotation",
                "of": "round object" if rot.params.get("round") else "base",
                "fold": rot.fold,
                "support": round(rot.support, 3),
                "violation": round(rot.violation, 3),
            }
        )
    return out


def _history(ob: Observation, sy: Symmetries, opts: Settings, *, symmetry: bool) -> dict:
    """The history entry of a completion: its options and the method's constants."""
    out: dict[str, Any] = {
        "op": "complete",
        "source": opts.source,
        "method": METHOD,
        "res": opts.res,
        "views": len(ob.frames),
        "box": list(opts.box) if opts.box is not None else None,
        "upright": bool(opts.upright),
        "symmetry": bool(symmetry),
        "closure_voxels": opts.closure,
        "between_reach_voxels": fuse_mod.BETWEEN_VOXELS,
        "between_closing_voxels": fuse_mod.BETWEEN_CLOSING,
        "back_shift_voxels": fuse_mod.BACK_SHIFT,
        "slab_flat_cosine": fuse_mod.SLAB_FLAT,
        "slab_neighbours": fuse_mod.SLAB_NEIGHBOURS,
        "slab_agree": fuse_mod.SLAB_AGREE,
        "slab_edge_share": fuse_mod.SLAB_EDGE_SHARE,
        "slab_band": fuse_mod.SLAB_BAND,
        "lid_voxels": fuse_mod.LID_THICK,
        "lid_top_m": fuse_mod.LID_TOP,
        "lid_edge_share": fuse_mod.RIM_SHARE,
        "lid_edge_sharp": fuse_mod.RIM_SHARP,
        "lid_face_m": fuse_mod.LID_FACE,
        "repeat_area_share": fuse_mod.REPEAT_AREA,
        "repeat_min": fuse_mod.REPEAT_MIN,
        "repeat_spacing_share": fuse_mod.REPEAT_SPACING,
        "repeat_overlap_share": fuse_mod.REPEAT_OVERLAP,
        "repeat_edge_share": fuse_mod.REPEAT_EDGE,
        "body_wall_share": body_mod.BODY_WALL,
        "body_top_share": body_mod.BODY_SHARE,
        "carve_margin_voxels": CARVE_MARGIN,
        "speck_share": tidy_mod.SPECK_SHARE,
        "column_radius_m": [column_mod.MIN_RADIUS, column_mod.MAX_RADIUS],
        "column_hub_reach_m": column_mod.HUB_REACH,
        "column_sure_rays_px": column_mod.SURE_RAYS,
        "column_sure_margin_voxels": column_mod.SURE_MARGIN_VOXELS,
        "strut_radius_m": strut_mod.RADIUS,
        "strut_min_radius_voxels": strut_mod.MIN_RADIUS_VOXELS,
        "strut_max_gap_share": strut_mod.MAX_GAP_SHARE,
        "floor_tol_m": FLOOR_TOL,
        "up_from": sy.up_from,
        "max_plane_tilt_deg": sym_mod.MAX_PLANE_TILT_DEG,
        "cluster_cell_m": ob.cluster_cell,
        "symmetry_min_support": sym_mod.MIN_SUPPORT,
        "symmetry_max_violation": sym_mod.MAX_VIOLATION,
        "round_residual": sym_mod.ROUND_RESIDUAL,
        "round_support": sym_mod.ROUND_SUPPORT,
        # the voxel the symmetry tests measured in: the grid's, never finer than SYMMETRY_RES's
        "symmetry_voxel_m": round(sy.hs, 6),
        "symmetry_res": SYMMETRY_RES,
    }
    if opts.scale is not None:
        out["scale"], out["scale_from"] = opts.scale
    return out


def _encode(prov: np.ndarray) -> dict:
    data = base64.b64encode(zlib.compress(np.ascontiguousarray(prov).tobytes(), 6)).decode()
    return {"encoding": "uint8 C-order, zlib, base64", "shape": list(prov.shape), "data": data}


def provenance(csdf: CSDF) -> np.ndarray:
    """(X, Y, Z) uint8 kind of surface near each voxel: 0 none, 1 observed, 2 mirrored, 3 guessed.

    Parameters
    ----------
    csdf : CSDF
        A completion (:func:`complete`) as it was made: not edited or resampled since.

    Returns
    -------
    (X, Y, Z) uint8
        :data:`OBSERVED`, :data:`MIRRORED` or :data:`GUESSED` at voxels near the surface, 0
        elsewhere.

    Raises
    ------
    InputError
        ``csdf`` was not made by the completion, or its grid has changed since.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import data, ingest
    >>> from partscale.complete import KINDS, complete, provenance
    >>> from partscale.evaluate import virtual_scan
    >>> frames = virtual_scan(ingest.load_mesh(data.table()), 1)
    >>> table = complete(frames, res=32, symmetry=False)
    >>> kinds = provenance(table)
    >>> kinds.shape == table.shape, kinds.dtype
    (True, dtype('uint8'))
    >>> [KINDS[k] for k in np.unique(kinds) if k]
    ['observed', 'guessed']
    """
    comp = csdf.meta.get("completion")
    if not isinstance(comp, dict) or "provenance" not in comp:
        raise InputError("completion colours: expected a CSDF made by the completion, got none")
    p = comp["provenance"]
    if list(p.get("shape", [])) != list(csdf.shape):
        raise InputError(
            f"completion colours: expected the grid the completion wrote {p.get('shape')}, got "
            f"{list(csdf.shape)} (edited since)"
        )
    raw = zlib.decompress(base64.b64decode(p["data"]))
    return np.frombuffer(raw, np.uint8).reshape(csdf.shape)


def completion_colors(csdf: CSDF) -> np.ndarray:
    """(X, Y, Z, 3) uint8: the display colour of each voxel's kind of surface.

    What ``render --completion`` shows: :data:`KIND_COLORS` (observed blue, mirrored amber,
    guessed red) of the nearest voxel with a kind (:func:`provenance`).

    Parameters
    ----------
    csdf : CSDF
        A completion as it was made (as :func:`provenance`).

    Returns
    -------
    (X, Y, Z, 3) uint8
        sRGB colours, in place of ``csdf.rgb`` (``csdf.replace(rgb=...)``).

    Raises
    ------
    InputError
        As :func:`provenance`.

    Examples
    --------
    >>> from partscale import data, ingest
    >>> from partscale.complete import complete, completion_colors
    >>> from partscale.evaluate import virtual_scan
    >>> frames = virtual_scan(ingest.load_mesh(data.table()), 1)
    >>> table = complete(frames, res=32, symmetry=False)
    >>> shown = table.replace(rgb=completion_colors(table))
    >>> shown.rgb.shape == (*table.shape, 3), shown.rgb.dtype
    (True, dtype('uint8'))
    """
    from scipy import ndimage

    prov = provenance(csdf)
    lut = np.full((4, 3), 128, np.uint8)
    for k, c in fuse_mod.KIND_COLORS.items():
        lut[k] = c
    ind = ndimage.distance_transform_edt(prov == 0, return_distances=False, return_indices=True)
    return lut[prov[tuple(ind)]]


def complete_file(
    scan: str | os.PathLike | None = None,
    *,
    depth: str | os.PathLike | None = None,
    color: str | os.PathLike | None = None,
    intrinsics: str | os.PathLike | None = None,
    depth_scale: float = 5000.0,
    camera=None,
    views: str | os.PathLike | None = None,
    **options,
) -> CSDF:
    """Read a scan from files and :func:`complete` it.

    Exactly one of ``scan``, ``depth`` and ``views`` names what to read.

    Parameters
    ----------
    scan : str or os.PathLike, optional
        A PLY/OBJ range mesh or point cloud of the object alone, in the camera's frame
        (:func:`read_points`, :func:`frame_from_points`).
    depth, color, intrinsics : str or os.PathLike, optional
        An RGB-D frame: depth image, colour image, intrinsics JSON (:func:`read_frame`).
    depth_scale : float
        Depth image units per metre.
    camera : (4, 4) array_like, optional
        The camera-to-world pose of ``scan`` or ``depth`` (default: identity).
    views : str or os.PathLike, optional
        A JSON list of registered views (:func:`read_views`).
    **options
        :func:`complete`'s keywords (``res``, ``box``, ``upright``, ``symmetry``, ``closure``,
        ``force_completion``, ``scale``, ``progress``).

    Returns
    -------
    CSDF
        As :func:`complete`; ``meta['source']`` is the file read.

    Raises
    ------
    InputError
        Not exactly one of ``scan``, ``depth``, ``views``; colour or intrinsics given with a
        scan; or a file that cannot be read.

    Examples
    --------
    A point cloud of the shipped table (the points a virtual sensor read, in its frame),
    written to a PLY file and completed:

    >>> import trimesh
    >>> from partscale import data, ingest
    >>> from partscale.complete import complete_file
    >>> from partscale.evaluate import virtual_scan
    >>> (seen,) = virtual_scan(ingest.load_mesh(data.table()), 1, floor=False)
    >>> points, colors, _ = seen.points()
    >>> in_camera = (points - seen.pose[:3, 3]) @ seen.pose[:3, :3]
    >>> _ = trimesh.PointCloud(in_camera, colors=colors).export("scan.ply")
    >>> table = complete_file("scan.ply", res=32, symmetry=False)
    >>> table.meta["source"], max(table.shape) >= 32
    ('scan.ply', True)
    """
    given = [x is not None for x in (scan, depth, views)]
    if sum(given) != 1:
        raise InputError(
            f"complete: expected exactly one of a scan file, depth or views, got {sum(given)}",
            params=("depth", "views"),
        )
    if scan is not None:
        if intrinsics is not None or color is not None:
            raise InputError(
                f"{scan}: expected color and intrinsics only with depth, got them with a mesh",
                params=("color", "intrinsics", "depth"),
            )
        P, C = read_points(scan)
        pose = np.eye(4) if camera is None else camera
        from .scan import check_pose

        pose = check_pose(pose, "camera")
        world = P @ pose[:3, :3].T + pose[:3, 3]
        frames = [frame_from_points(world, C, pose)]
        source = str(scan)
    elif depth is not None:
        frames = [read_frame(depth, color, intrinsics, depth_scale=depth_scale, pose=camera)]
        source = str(depth)
    else:
        assert views is not None  # exactly one of scan, depth, views (checked above)
        frames = read_views(views)
        source = str(views)
    return complete(frames, source=Path(source).name and source, **options)
