"""Fusion: surface points, free space and symmetries -> a watertight coloured SDF on a grid.

The solid is every voxel within ``closure`` voxels of a surface point (observed, or a symmetric
copy that the free space allows) that no camera saw through, directly or in a symmetric view
(the mirror image of a free voxel is free unless it is next to the observed surface), and that
is above the floor; enclosed cavities are filled. The solid that reaches the band above the
floor where the scan's points were taken for the floor goes on down to it (a chair's feet). So
the observed surface bounds the solid where it was seen, a mirrored surface where it was
mirrored, and elsewhere the solid is closed ``closure`` voxels behind the surface: the
conservative closure (thin, never a blob in space the scan says nothing about).

Distances: near surface points, the exact distance to the nearest point (so the zero level
passes through the observed and mirrored points, not through voxel corners); elsewhere the
Euclidean distance to the other side of the voxel solid. Colours: the nearest observed or
mirrored point's within 1.5 voxels, elsewhere diffused (normalised Gaussian, then nearest).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from .._workers import thread_map, thread_soon
from ..csdf import BAND_VOXELS
from . import body as body_mod
from . import tidy as tidy_mod
from .carve import affine_rows

OBSERVED, MIRRORED, GUESSED = 1, 2, 3
KINDS = {OBSERVED: "observed", MIRRORED: "mirrored", GUESSED: "guessed"}
KIND_COLORS = {OBSERVED: (70, 150, 230), MIRRORED: (240, 170, 40), GUESSED: (220, 60, 60)}
"""Display colours of the three kinds of surface (``render --completion``): blue, amber, red."""
SNAP_VOXELS = 1.5
BETWEEN_VOXELS = 64
"""Voxels behind a surface point within which an opposite surface measures the part's
thickness there for the slabs (:func:`_slab`), and the longest walk of a slab's side face that
measures a thickness and not a width. Farther, a march measures across an object (a table
top's edges, a cabinet's sides), no part's thickness: carried in from the faces' edges, such
widths thickened a table's top and filled a television unit's open shelves."""
BETWEEN_REACH = 256
"""Voxels behind a surface point within which an opposite surface fills the solid between (a
closed cabinet's sides, however wide): the fill stays only where it leaves less boundary than
the thin closure (:func:`close_between`)."""
BETWEEN_CLOSING = 2
"""Voxels: radius of the closing that seals the channels between filled segments."""
BETWEEN_FACING = 0.5
"""Cosine below which two normals face opposite ways."""
SLAB_FLAT = 0.9
"""|Cosine| between a point's normal and the nearest grid axis above which it lies on a flat
face of a slab (a face along the grid's axes: a seat's top, a leg's side)."""
SLAB_GAP = 2
"""Voxels of a side face without points (sensor holes, dropped edge pixels) a walk steps over."""
SLAB_ABOVE = 3
"""Voxels in front of a point where a side face means a junction, not an edge (beyond the two
voxels the side faces are widened by)."""
SLAB_AGREE = 0.5
"""Share of the nearest edge measurements within a voxel of the most common one that makes a
thickness sure (a flat slab's edges agree; a curved cushion's do not)."""
SLAB_EDGE_SHARE = 0.05
"""Share of the points facing one way that must measure at an edge for that way to have a
thickness (a square face L voxels wide has about 8/L of its points within its edge band)."""
SLAB_RING = 2
SLAB_RING_TURNED = 0.6
"""A walk that runs past the reach (a width: a stool's rim walked along its front) measures
only from a sharp edge: of the voxels holding points in the cube ``2 * SLAB_RING + 1`` wide
around its start, at most this share hold only points turned off the axes (SheenChair's
rounded cushion ends, three views: 0.64-0.91; the stool's rim, one view: median 0.38)."""
SLAB_BAND = 0.5
"""A width carried as a thickness (:data:`SLAB_RING_TURNED`) comes from a band: the face it is
carried from spans at most this share of that width across (a stool's rim, a few voxels high,
carried across the seat), not a side panel as tall as the cabinet is deep."""
SLAB_OUTLIER = 3.0
SLAB_OUTLIER_SHARE = 0.1
"""Measurements of a face's thickness more than ``SLAB_OUTLIER`` times the median of its way's
(all the points facing one way), made by fewer than ``SLAB_OUTLIER_SHARE`` of them, ran down a
part flush below the edge, not the slab: a table's legs flush with its top's edge measure the
top 47 voxels thick at each corner (the rest of its edge 2 to 7), and near the corners the
most common measurement is theirs. (A quarter instead of a tenth: Sweet Home 3D's bookcase from
three views 0.832 -> 0.865, Kenney's crossed-leg table 0.923 -> 0.770; a tenth moves no scan of
the wide benchmark by more than 0.02.)"""
SLAB_NEIGHBOURS = 32
"""Measurements of a face's thickness whose most common value carries it across the face."""
SLAB_SEEN_FROM = 3
"""Voxels behind a flat face from which its other side, seen, measures its thickness: the march
to it starts two voxels in and the faces it finds are widened by one, so a side nearer than
this is the same board read on both faces (a thin shelf), not a depth to carry across."""
PIECE_OBSERVED_VOXELS = 27
"""Observed voxels that keep a piece whatever its share of the largest (:func:`drop_pieces`):
a baluster of a railing seen in part, not a flying pixel."""
BACK_SHIFT = 0.4
"""Voxels by which an unobserved boundary of the solid is drawn in (below 0.5: no voxel
changes side, so no thin sheet loses its voxels)."""
BEHIND_SLACK = 0.5
"""Voxels in front of its nearest surface point that a voxel of the closure may lie."""
NEAREST_EXACT_VOXELS = 4.0
"""Voxels within which a voxel's nearest surface point is found exactly (beyond: a point of the
nearest voxel holding one, :func:`nearest_surface_point`)."""
DIFFUSE_SIGMA = 2.0
FLOOR_REACH_VOXELS = 1.5
"""Voxels above the floor cut within which the solid near a surface point goes on straight down
to the floor (:func:`floor_reach`)."""
ENCLOSED_SHARE = 0.25
"""A fill region with this share of its faces on the thin closure may be the body behind it."""
BULK_RADIUS = 2
BULK_SHARE = 0.6
"""A body keeps this share of its voxels through an opening by a ball of ``BULK_RADIUS``."""
RIM_SEEN = 0.04
"""A body behind an open shell: at most this share of the voxels around it seen through."""
TUNNEL_VOXELS = 200
"""Holes in a slice of the fill up to this many voxels (a disc 16 voxels across) are tunnels."""
SHEET_VOXELS = 6
"""A hole through a thin part goes through at most this many slices (a tube's inside, a bin's
seen from the side, runs on along it: not a hole, :func:`close_holes`)."""
THREAD_VOXELS = 2**24
"""Voxels up to which independent steps over the whole grid run on threads at once (each
holds arrays of the grid; on a finer grid one after another, so that the memory a completion
needs stays what its check counted)."""
PEAK_BYTES_PER_VOXEL = 64
"""The completion's peak working memory per voxel of its grid where its steps run one after
another (above ``THREAD_VOXELS``): Kenney's kitchen drawer cabinet at --res 256, 18.7 million
voxels, peaked at 1042 MB (56 bytes a voxel, the scan's points and tables included)."""
PEAK_BYTES_PER_VOXEL_THREADED = 96
"""The same where independent steps run on threads at once (at most ``THREAD_VOXELS``): 89
bytes a voxel more between --res 160 and 200 of the same cabinet (the colours filled beside
the guessed parts)."""
LID_SLICES = 6
LID_ASPECT = 0.25
"""Level slices a plate's rim spans at most (a table top's edge, an apron flush below it): the
larger of ``LID_SLICES`` and ``LID_ASPECT`` times the narrower width of what it encloses (a
plate is thin for its size: Kenney's coffee table's top, a solid plate, is an edge 12 slices
tall round 75 voxels of unseen top). A bin's wall, or a cabinet's, as tall as it is wide or
taller, runs through many more."""
RIM_SHARE = 0.5
"""Share of the most common slice's count of a rim's tops that a slice beside it holds to be
part of the plate's edge (:func:`_rim_tops`)."""
RIM_SHARP = 0.25
"""Share of that count above which a slice just beyond the edge makes it a rounded one (a
cushion's edge tails off: SheenChair's seat, 0.45; a shelf's board ends sharply: 0.04-0.12),
whose thickness its tops do not measure."""
LID_REACH = 3
"""Slices either side of a level slice whose voxels close its rim (:func:`close_lids`)."""
LID_CLEAR = 8
LID_COVERED = 0.1
"""Slices above a plate's top within which solid over more than ``LID_COVERED`` of it makes
its rim a frame under something else, not a plate's edge (:func:`close_lids`)."""
LID_THICK = 2
"""Slices of the plate a rim encloses, down from the rim's top: as thin as the closure (how
thick it is no camera saw; a table's top flush with its apron is a rim as tall as both)."""
LID_TOP = 0.03
"""Metres: the plate a rim encloses at the object's top (its rim's top within ``LID_TOP_SLICES``
of the highest solid) is this thick, and at least ``LID_THICK`` slices (:func:`_lid_slices`): a
table's or a cabinet's top is 25-40 mm, thicker than the shelves inside it (16-19 mm), and
nothing a camera at its height sees measures it (its face is unseen and its underside hidden
behind an apron flush with its edge). Two slices of a 1.5 m table at 128 (23 mm, its solid
voxels' centres up to the edge's points) left Sweet Home's table's underside, 29 % of its
surface, 2 cm over the true one; the same two slices at 256 would be half as thick."""
LID_TOP_SLICES = 2
LID_FACE = 0.06
"""Metres: a plate's outer face seen from its rim's top down to at most this far is its edge
(:func:`_edge_faces`; a table's top is 18-60 mm thick). A face running on further is an
apron's or a wall's, flush with the edge, and tells nothing of the plate's thickness."""
REPEAT_AREA = 0.5
"""A level slice holding at least this share of the largest slice's solid is a plate's
(:func:`repeat_plates`: a shelf's, across a bookcase; its sides hold a tenth)."""
REPEAT_MIN = 3
REPEAT_SPACING = 0.1
"""Plates repeat where at least ``REPEAT_MIN`` of them follow one another at spacings within
this share (and 1.5 slices) of their median spacing, each overlapping the next in plan by
``REPEAT_OVERLAP`` of the smaller (a stair's treads step sideways: they do not repeat)."""
REPEAT_OVERLAP = 0.6
REPEAT_EDGE = 0.15
"""Share of a repeated plate's outline that observed points at its height, and none just above
or below it, mark (its front edge, seen end on) for the plate to go on there."""
LID_LEVEL = 0.99
"""|Cosine| between up and the nearest grid axis above which the grid's slices are level."""
HOLE_NEAR = 2
"""Voxels around a hole within which the surface points tell a sheet from a slit."""
HOLE_SEEN = 0.1
"""A hole through a thin part with at most this share of its voxels seen through: no camera
looked through it (:func:`close_holes`)."""


def _map(fn: Callable, items, voxels: int) -> list:
    """``[fn(x) for x in items]``, on threads (:func:`partscale._workers.thread_map`) where the
    grid has at most ``THREAD_VOXELS`` ``voxels``: each item holds arrays of the whole grid.
    """
    if voxels <= THREAD_VOXELS:
        return thread_map(fn, items)
    return [fn(x) for x in items]


def peak_bytes(voxels: int) -> int:
    """Bytes the completion's working set peaks at on a grid of ``voxels`` voxels
    (``PEAK_BYTES_PER_VOXEL``, or ``PEAK_BYTES_PER_VOXEL_THREADED`` where its steps run on
    threads at once), for the memory check before any work.

    Examples
    --------
    >>> from partscale.complete.fuse import peak_bytes
    >>> peak_bytes(100**3) // 10**6, peak_bytes(300**3) // 10**9
    (96, 1)
    """
    per = PEAK_BYTES_PER_VOXEL_THREADED if voxels <= THREAD_VOXELS else PEAK_BYTES_PER_VOXEL
    return int(per * voxels)


def _soon(fn: Callable[[], np.ndarray], voxels: int) -> Callable[[], np.ndarray]:
    """``fn()`` started on the pool's other thread where the grid has at most ``THREAD_VOXELS``
    ``voxels`` (:func:`partscale._workers.thread_soon`), else run when asked for (above it,
    its arrays of the whole grid would be held beside the caller's); returns the callable that
    gives its result.
    """
    return thread_soon(fn) if voxels <= THREAD_VOXELS else fn


def nearest_voxels(occ: np.ndarray) -> np.ndarray:
    """(3, X, Y, Z) int32: for every voxel, the indices of the nearest voxel of ``occ``
    (X, Y, Z) bool (``ndimage.distance_transform_edt``'s feature transform).
    """
    return ndimage.distance_transform_edt(~occ, return_distances=False, return_indices=True)


def _edt(mask: np.ndarray) -> np.ndarray:
    """(X, Y, Z) float32: each voxel's distance in voxels to the nearest False voxel of
    ``mask`` (X, Y, Z) bool, 0 on them.

    The mask goes to ``edt`` as uint8 (the same bytes): edt 3.1 takes a bool array on a
    path 3-5x slower than the same zeros and ones as uint8, with the same result.
    """
    import edt

    data = np.ascontiguousarray(mask).view(np.uint8)
    return edt.edt(data, parallel=2).astype(np.float32, copy=False)


def _fill_holes(mask: np.ndarray) -> np.ndarray:
    """(X, Y, Z) bool: ``mask`` with every empty region that reaches no face of the array
    filled, as ``ndimage.binary_fill_holes`` (empty space face-connected) gives it, by one
    labelling instead of a dilation repeated until nothing changes (3x faster at 150^3).
    """
    lab, n = ndimage.label(~mask)
    outside = np.zeros(n + 1, bool)
    for ax in range(mask.ndim):
        for end in (0, -1):
            outside[lab.take(end, axis=ax)] = True
    outside[0] = False  # the mask itself
    return ~outside[lab]


def bound_far(sdf: np.ndarray, h: float) -> np.ndarray:
    """(X, Y, Z) float32 ``sdf`` with every value beyond the band no larger in magnitude than
    the final solid's voxel distance (as :func:`fuse` gives it), in place.

    Steps after the fusion (a column, struts, filled contacts) rewrite the band around what they
    add; beyond it the fused values still measure to the old solid and may overstate the
    distance many times over (a sphere tracer then steps through a strut). Values are only ever
    lowered, so nothing already right moves.
    """
    solid = sdf < 0
    far = np.abs(sdf) > BAND_VOXELS * h
    e_out = (_edt(~solid) - 0.5) * h
    e_in = (_edt(solid) - 0.5 - BACK_SHIFT) * h
    lim = np.where(solid, -np.maximum(e_in, 0.0), np.maximum(e_out, 0.0)).astype(np.float32)
    sdf[far & solid] = np.maximum(sdf[far & solid], lim[far & solid])
    sdf[far & ~solid] = np.minimum(sdf[far & ~solid], lim[far & ~solid])
    return sdf


@dataclass(frozen=True, eq=False)
class GridFrame:
    """The grid: ``shape`` voxels of size ``h`` from voxel centre ``origin`` (grid coordinates),
    placed in the world by ``grid_to_world`` (4, 4) float64.
    """

    grid_to_world: np.ndarray
    shape: tuple[int, ...]
    origin: np.ndarray
    h: float

    def centres(self, flat: np.ndarray) -> np.ndarray:
        """(M, 3) float32 grid coordinates of the voxels at flat indices ``flat`` (M,)."""
        ijk = np.stack(np.unravel_index(flat, self.shape), axis=1)
        return (self.origin + ijk * self.h).astype(np.float32)

    def all_centres(self) -> np.ndarray:
        """(X * Y * Z, 3) float32 grid coordinates of every voxel in flat order: the values
        :meth:`centres` gives (each axis's coordinates computed once, then broadcast).
        """
        out = np.empty((*self.shape, 3), np.float32)
        for a, n in enumerate(self.shape):
            along = (self.origin[a] + np.arange(n) * self.h).astype(np.float32)
            shape = [1] * len(self.shape)
            shape[a] = n
            out[..., a] = along.reshape(shape)
        return out.reshape(-1, 3)

    def to_world(self, centres: np.ndarray) -> np.ndarray:
        """(M, 3) float32 world coordinates of grid points ``centres`` (M, 3) float32."""
        return affine_rows(centres, self.grid_to_world[:3, :3], self.grid_to_world[:3, 3])


@dataclass(frozen=True, eq=False)
class SurfacePoints:
    """Surface points on the grid: ``points`` (N, 3) float64 grid coordinates, ``colors`` (N, 3)
    uint8, ``kind`` (N,) uint8 (``OBSERVED`` / ``MIRRORED``), ``normals`` (N, 3) unit, out of the
    object, ``idx`` (N, 3) int64 their voxels, ``occ`` and ``occ_obs`` (X, Y, Z) bool the voxels
    holding any point and an observed one.
    """

    points: np.ndarray
    colors: np.ndarray
    kind: np.ndarray
    normals: np.ndarray
    idx: np.ndarray
    occ: np.ndarray
    occ_obs: np.ndarray


@dataclass(frozen=True, eq=False)
class Candidates:
    """Voxels that may be solid before the carving: ``within`` (X, Y, Z) bool (the closure, the
    fill between opposite surfaces and the slabs), ``within_closure`` (the closure and the sure
    slabs), ``free_all`` (X, Y, Z) bool every voxel's free space, or None without the fill.
    """

    within: np.ndarray
    within_closure: np.ndarray
    free_all: np.ndarray | None


def fuse(
    grid_to_world: np.ndarray,
    shape: tuple[int, ...],
    origin: np.ndarray,
    h: float,
    points: np.ndarray,
    colors: np.ndarray,
    kind: np.ndarray,
    normals: np.ndarray,
    free_world: Callable[[np.ndarray], np.ndarray],
    sym_free: list[Callable[[np.ndarray], np.ndarray]],
    height_world: Callable[[np.ndarray], np.ndarray],
    closure: float,
    fill_between: bool = True,
    floor_cut: float | None = None,
    sure_free: Callable[[np.ndarray], np.ndarray] | None = None,
) -> tuple[np.ndarray, Callable[[], np.ndarray], np.ndarray]:
    """Solid, SDF, colour and provenance on the grid.

    The steps: the points on the grid (:func:`surface_on_grid`), the voxels that may be solid
    (:func:`candidates`) with the closure's foot carried to the floor (:func:`floor_reach`),
    those no camera saw through (:func:`carve`), the channels between filled segments closed
    (:func:`close_between`), the holes the sensor left through thin parts closed
    (:func:`close_holes`), the plates that low rims enclose (:func:`close_lids`; with
    ``fill_between`` only) and the repeated ones carried on (:func:`repeat_plates`), the
    bodies under tops behind walls that reach down toward the floor (:func:`fill_bodies`;
    with ``fill_between`` and a floor), the bottom of what stands on the
    floor carried down to it (:func:`floor_base`), holes filled and specks dropped
    (:func:`drop_pieces`), the distances (:func:`distances`) and the colours and provenance
    near the surface (:func:`surface_attributes`).

    Parameters
    ----------
    grid_to_world : (4, 4) float64
        The grid frame in the world (voxel centre ``origin + ijk * h`` in grid coordinates).
    points : (N, 3) float64
        Surface points in grid coordinates; ``colors`` (N, 3) uint8; ``kind`` (N,) uint8
        (``OBSERVED`` or ``MIRRORED``); ``normals`` (N, 3) unit, pointing out of the object.
    free_world : world points (M, 3) -> (M,) bool, the observed free space.
    sym_free : list of the same for each symmetric view of the free space.
    height_world : world points -> height above the floor.
    closure : voxels behind the surface that close it where nothing else does.
    fill_between : fill the solid between opposite surfaces (:func:`_between`).
    floor_cut : the height (world units) below which the scan's points were taken for the floor,
        or None where no floor was found: the solid down to the cut goes on to the floor
        (:func:`floor_reach`, :func:`floor_base`).
    sure_free : world points (M, 3) -> (M,) bool, the space the cameras surely saw through
        (pixels without a reading say nothing), which keeps a hole through a thin part open
        (:func:`close_holes`); None: ``free_world``.

    Returns
    -------
    sdf (X, Y, Z) float32; the colours: a callable giving rgb (X, Y, Z, 3) uint8, filled on the
    pool's other thread while the caller goes on (:meth:`NearColours.filled`: the steps after
    the fusion read no colours); provenance (X, Y, Z) uint8 (0 away from the surface, else
    OBSERVED / MIRRORED / GUESSED).
    """
    grid = GridFrame(grid_to_world, tuple(int(s) for s in shape), origin, h)
    sp = surface_on_grid(grid, points, colors, kind, normals)
    # the carving's far voxels need each voxel's nearest voxel holding a point: started now, on
    # the other core beside the candidates (ndimage lets go of the GIL)
    feature = _soon(lambda: nearest_voxels(sp.occ), sp.occ.size)
    cand = candidates(grid, sp, free_world, closure, fill_between)
    if floor_cut is not None:
        reach = floor_reach(grid, sp, cand.within_closure, free_world, height_world, floor_cut)
        cand = Candidates(cand.within | reach, cand.within_closure | reach, cand.free_all)
    solid = carve(grid, sp, cand.within, free_world, sym_free, height_world, feature)
    if cand.free_all is not None:
        solid = close_between(solid, cand)
    seen_through = free_world if sure_free is None else sure_free
    solid = close_holes(solid, grid, sp, seen_through)
    if fill_between:
        solid = close_lids(solid, grid, height_world, seen_through)
        solid = repeat_plates(solid, grid, sp, height_world, seen_through)
    if cand.free_all is not None and floor_cut is not None:
        solid = fill_bodies(solid, grid, sp, height_world, seen_through, cand.free_all)
    if floor_cut is not None:
        # after the closing: carried down before it, the slab under a closed box's fill was a
        # region of its own that added boundary, and the regions' test dropped it (a cabinet
        # stood 3 cm off the floor)
        solid = floor_base(grid, solid, free_world, height_world, floor_cut)
    solid = drop_pieces(_fill_holes(solid), sp.occ_obs)
    sdf = distances(solid, h)
    near, prov = surface_attributes(grid, sp, solid, sdf)
    return sdf, _soon(near.filled, solid.size), prov


def surface_on_grid(
    grid: GridFrame,
    points: np.ndarray,
    colors: np.ndarray,
    kind: np.ndarray,
    normals: np.ndarray,
) -> SurfacePoints:
    """The surface points (N, 3) float64 grid coordinates (with ``colors``, ``kind``,
    ``normals``) that fall in the grid, their voxels and the occupancy they give.
    """
    idx = np.rint((points - grid.origin) / grid.h).astype(np.int64)
    inb = ((idx >= 0) & (idx < np.asarray(grid.shape))).all(axis=1)
    idx, points, colors, kind, normals = idx[inb], points[inb], colors[inb], kind[inb], normals[inb]
    occ = np.zeros(grid.shape, bool)
    occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    occ_obs = np.zeros(grid.shape, bool)
    o = idx[kind == OBSERVED]
    occ_obs[o[:, 0], o[:, 1], o[:, 2]] = True
    return SurfacePoints(points, colors, kind, normals, idx, occ, occ_obs)


def candidates(
    grid: GridFrame,
    sp: SurfacePoints,
    free_world: Callable[[np.ndarray], np.ndarray],
    closure: float,
    fill_between: bool,
) -> Candidates:
    """The voxels within ``closure`` voxels of a surface point and, with ``fill_between``, those
    between opposite surfaces (:func:`_between`) and inside slabs (:func:`_slab`).
    """
    shape, origin, h = grid.shape, grid.origin, grid.h
    within = _edt(~sp.occ) <= closure
    within_closure = within.copy()
    free_all = None
    if fill_between:
        free_all = free_world(grid.to_world(grid.all_centres())).reshape(shape)
        between, sure, unsure = _fills(sp.points, sp.normals, sp.idx, origin, h, free_all)
        within |= between | sure | unsure
        within_closure |= sure
    return Candidates(within, within_closure, free_all)


def floor_reach(
    grid: GridFrame,
    sp: SurfacePoints,
    closed: np.ndarray,
    free_world: Callable[[np.ndarray], np.ndarray],
    height_world: Callable[[np.ndarray], np.ndarray],
    cut: float,
) -> np.ndarray:
    """(X, Y, Z) bool: the voxels straight below the solid's foot down to the floor.

    The scan's points within ``cut`` (world units) of the floor were taken for the floor, with
    the bottom of everything standing on it: a chair's legs ended 2 cm above the floor. Where a
    surface point lies within ``FLOOR_REACH_VOXELS`` of the cut, the part it belongs to stands on
    the floor: the voxels of ``closed`` (X, Y, Z) bool (the closure) near such points and below
    the cut's band are carried down along the up direction to the floor, each until a camera
    saw through a voxel below it (a copy mirrored beside the object, where the floor was seen,
    stays where it is; the carving then keeps only what lies behind its nearest surface point).
    """
    h = grid.h
    top = cut + FLOOR_REACH_VOXELS * h
    out = np.zeros(grid.shape, bool)
    low_points = height_world(grid.to_world(sp.points.astype(np.float32))) <= top
    if not low_points.any():
        return out
    centres = grid.centres(np.flatnonzero(closed.ravel()))
    height = height_world(grid.to_world(centres))
    centres, height = centres[height <= top], height[height <= top]
    near = cKDTree(sp.points[low_points]).query(centres, distance_upper_bound=2 * h)[0] < np.inf
    return _down_to_floor(grid, centres[near], height[near], free_world, height_world)


def floor_base(
    grid: GridFrame,
    solid: np.ndarray,
    free_world: Callable[[np.ndarray], np.ndarray],
    height_world: Callable[[np.ndarray], np.ndarray],
    cut: float,
) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` with its bottom carried down to the floor where it ends within
    ``FLOOR_REACH_VOXELS`` of the floor's ``cut`` (world units): the whole underside of a part
    standing on the floor, not only the closure along its walls (:func:`floor_reach`). A bin's
    base left a hollow skirt 3 cm high, its walls carried down and the bottom between them at
    the cut. Each column stops where a camera saw through a voxel below it.
    """
    top = cut + FLOOR_REACH_VOXELS * grid.h
    centres = grid.centres(np.flatnonzero(solid.ravel()))
    height = height_world(grid.to_world(centres))
    low = height <= top
    return solid | _down_to_floor(grid, centres[low], height[low], free_world, height_world)


def _grid_up(grid: GridFrame, height_world: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """(3,) float64 unit: the up direction in ``grid``'s coordinates (height is affine in them)."""
    o = np.zeros((1, 3), np.float32)
    h0 = height_world(grid.to_world(o))[0]
    up = np.array(
        [
            height_world(grid.to_world(np.eye(3, dtype=np.float32)[k : k + 1]))[0] - h0
            for k in range(3)
        ]
    )
    return up / np.linalg.norm(up)


def _level_axis(
    grid: GridFrame, height_world: Callable[[np.ndarray], np.ndarray]
) -> tuple[int, bool] | None:
    """The axis of ``grid`` nearest up and whether up runs towards its lower indices; None
    where the grid's slices across it are not level (its cosine with up under ``LID_LEVEL``).
    """
    up = _grid_up(grid, height_world)
    ax = int(np.argmax(np.abs(up)))
    if abs(up[ax]) < LID_LEVEL:
        return None
    return ax, bool(up[ax] < 0)


def _down_to_floor(
    grid: GridFrame,
    start: np.ndarray,
    start_h: np.ndarray,
    free_world: Callable[[np.ndarray], np.ndarray],
    height_world: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """(X, Y, Z) bool: the voxels straight below grid points ``start`` (N, 3) float, at heights
    ``start_h`` (N,) above the floor, down to the floor; each column stops at the first voxel a
    camera saw through (``free_world``).
    """
    h = grid.h
    out = np.zeros(grid.shape, bool)
    if not len(start):
        return out
    up = _grid_up(grid, height_world)
    shape = np.asarray(grid.shape)
    alive = np.ones(len(start), bool)
    for k in range(1, int(np.ceil(2 * start_h.max() / h)) + 2):
        down = 0.5 * k * h
        alive &= start_h - down >= -0.5 * h
        go = np.flatnonzero(alive)
        if not len(go):
            break
        idx = np.rint((start[go] - down * up - grid.origin) / h).astype(np.int64)
        ok = ((idx >= 0) & (idx < shape)).all(axis=1)
        ok[ok] = ~free_world(grid.to_world(grid.origin + idx[ok] * h))
        alive[go[~ok]] = False
        out[idx[ok, 0], idx[ok, 1], idx[ok, 2]] = True
    return out


def carve(
    grid: GridFrame,
    sp: SurfacePoints,
    within: np.ndarray,
    free_world: Callable[[np.ndarray], np.ndarray],
    sym_free: list[Callable[[np.ndarray], np.ndarray]],
    height_world: Callable[[np.ndarray], np.ndarray],
    feature: Callable[[], np.ndarray] | None = None,
) -> np.ndarray:
    """(X, Y, Z) bool: the voxels of ``within`` that no camera saw through (directly or in a
    symmetric view), above the floor and behind their nearest surface point; the voxels holding
    surface points always. ``feature``: gives :func:`nearest_voxels` of ``sp.occ`` (made here
    where None).
    """
    h = grid.h
    near = np.flatnonzero(within.ravel())
    centres = grid.centres(near)
    world = grid.to_world(centres)
    keep = ~free_world(world) & (height_world(world) >= -0.5 * h)
    # the closure lies behind the surface: a voxel in front of its nearest surface point is
    # space the scan says nothing about (beyond the sensor's range, a hole), not the object
    nn0 = nearest_surface_point(centres, near, sp, h, feature)
    keep &= np.einsum("ni,ni->n", centres - sp.points[nn0], sp.normals[nn0]) <= BEHIND_SLACK * h
    if sym_free:
        d_obs = _edt(~sp.occ_obs).ravel()[near]
        # a symmetric view may not carve next to what was observed
        may = keep & (d_obs > SNAP_VOXELS)
        for f in sym_free:
            sel = np.flatnonzero(may)
            hit = f(world[sel])
            keep[sel[hit]] = False
            may[sel[hit]] = False
    # the voxels holding the surface points are solid whatever the carving says: a sheet seen
    # from one side would otherwise lose the half of its voxels whose centres lie in front of it
    keep |= sp.occ.ravel()[near]
    solid = np.zeros(grid.shape, bool)
    solid.ravel()[near[keep]] = True
    return solid


def nearest_surface_point(
    centres: np.ndarray,
    flat: np.ndarray,
    sp: SurfacePoints,
    h: float,
    feature: Callable[[], np.ndarray] | None = None,
) -> np.ndarray:
    """(M,) int64: for voxel ``centres`` (M, 3) (grid coordinates; flat indices ``flat`` (M,)),
    the index of their nearest surface point of ``sp``: exact within ``NEAREST_EXACT_VOXELS``,
    beyond it a point in the nearest voxel holding one (``feature``: gives
    :func:`nearest_voxels` of ``sp.occ``, made here where None).

    A k-d tree's query costs about the surface area within the distance it must search: the
    voxels deep inside a filled cabinet, 30 cm from flat walls of many points, took 17 s of
    exact queries where the voxels' own nearest-feature transform takes 0.1 s. Far from the
    surface which of a voxel's few nearest points is used does not change on which side of it
    the voxel lies (0.3 % of the far voxels of a chair at --res 128, 0.02 % of a cabinet's).
    """
    d, nn = cKDTree(sp.points).query(
        centres, k=1, distance_upper_bound=NEAREST_EXACT_VOXELS * h, workers=2
    )
    far = ~np.isfinite(d)
    if far.any():
        rep = np.zeros(sp.occ.shape, np.int64)
        rep[sp.idx[:, 0], sp.idx[:, 1], sp.idx[:, 2]] = np.arange(len(sp.points))
        nearest = nearest_voxels(sp.occ) if feature is None else feature()
        v = nearest.reshape(3, -1)[:, flat[far]]
        nn[far] = rep[v[0], v[1], v[2]]
    return nn


def close_between(solid: np.ndarray, cand: Candidates) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` with the narrow channels the segments between opposite surfaces
    leave (rounding, sensor holes) closed, each region of the fill kept only where it leaves
    less boundary than the thin closure alone or is the body behind it (:func:`_fill_regions`),
    and the tunnels through what is kept closed (:func:`_close_tunnels`).
    """
    free_all = cand.free_all
    assert free_all is not None  # only with the fill between surfaces
    from skimage.morphology import ball as make_ball

    r = BETWEEN_CLOSING
    ball = make_ball(r).astype(bool)

    def closed(m):
        # in the box of m, r + 2 voxels wider (or to the grid's edge): the closing reaches no
        # further, and the empty rim around it is the outside the hole filling needs
        box = _box(m, r + 2)
        mb = m[box]
        c = ndimage.binary_closing(np.pad(mb, r + 1), ball)[
            r + 1 : -r - 1, r + 1 : -r - 1, r + 1 : -r - 1
        ]
        out = np.zeros_like(m)
        out[box] = _fill_holes(mb | (c & ~free_all[box]))
        return out

    # the two closings are independent and ndimage lets go of the GIL: a thread each
    filled, shell = _map(closed, [solid, solid & cand.within_closure], solid.size)
    # where the segments fill the object only in part (thick curved parts whose opposite
    # sides were seen in patches) the voids between them are surfaces deep inside it: each
    # region of the fill is kept only where it leaves less boundary than the thin closure
    # alone, so a leg or a seat that closes cleanly keeps it beside a cushion that does not,
    # or where it is the body behind an open shell (a cabinet seen from the front)
    return shell | _close_tunnels(_fill_regions(shell, filled & ~shell, free_all), free_all)


def drop_pieces(solid: np.ndarray, occ_obs: np.ndarray) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` without the small pieces the scan barely saw (flying pixels, a
    neighbour's edge); a piece is what touches by a face, an edge or a corner (a rod a voxel
    thick across the grid's axes is one piece, not one per voxel). A piece stays if it has 2 %
    of the largest's voxels or 5 % of the most observed one's observed voxels (``occ_obs``).
    """
    lab, n = ndimage.label(solid, structure=tidy_mod.CORNERS)
    if n <= 1:
        return solid
    size = np.bincount(lab.ravel())
    size[0] = 0
    obs_in = np.bincount(lab.ravel(), weights=occ_obs.ravel(), minlength=n + 1)
    good = (size >= 0.02 * size.max()) | (obs_in >= 0.05 * obs_in.max())
    good |= obs_in >= PIECE_OBSERVED_VOXELS
    good[0] = False
    return good[lab]


def distances(solid: np.ndarray, h: float) -> np.ndarray:
    """(X, Y, Z) float32 signed distances (world units) of the voxel solid ``solid``."""
    e_out = _edt(~solid) - 0.5
    # the inside distance runs to BACK_SHIFT voxels short of the solid's voxel boundary: the
    # unobserved side of a thin closure then lies about a voxel behind the surface it closes
    e_in = _edt(solid) - 0.5 - BACK_SHIFT
    return np.where(solid, -e_in, e_out).astype(np.float32) * h


@dataclass(frozen=True, eq=False)
class NearColours:
    """The colours near the surface: ``rgb`` (X, Y, Z, 3) uint8 the nearest surface point's at
    the voxels of the band ``band`` (M,) int64 flat indices within ``SNAP_VOXELS`` of one,
    ``known`` (X, Y, Z) bool those voxels.
    """

    rgb: np.ndarray
    known: np.ndarray
    band: np.ndarray

    def filled(self) -> np.ndarray:
        """(X, Y, Z, 3) uint8: every voxel's colour, diffused from the known ones (in place of
        ``rgb``; :func:`_diffuse`).
        """
        return _diffuse(self.rgb, self.known, self.band)


def surface_attributes(
    grid: GridFrame, sp: SurfacePoints, solid: np.ndarray, sdf: np.ndarray
) -> tuple[NearColours, np.ndarray]:
    """Near the surface, ``sdf`` (in place) made the exact distance to the nearest surface point;
    returns the colours near the surface (the nearest point's; :meth:`NearColours.filled`
    diffuses them beyond) and provenance (X, Y, Z) uint8 (OBSERVED / MIRRORED / GUESSED near
    the surface, else 0).
    """
    shape, origin, h = grid.shape, grid.origin, grid.h
    points, colors, kind = sp.points, sp.colors, sp.kind
    band = np.flatnonzero(np.abs(sdf.ravel()) <= (BAND_VOXELS + 1) * h)
    # points deep inside the solid are no surface (a copy landing in a filled region)
    pidx = sp.idx
    boundary = ndimage.binary_dilation(solid) & ~ndimage.binary_erosion(solid)
    on = boundary[pidx[:, 0], pidx[:, 1], pidx[:, 2]]
    tree = cKDTree(points[on]) if on.any() else None
    sp_col, sp_n = colors[on], sp.normals[on]
    rgb = np.zeros((*shape, 3), np.uint8)
    prov = np.zeros(shape, np.uint8)
    band_pts = origin + np.stack(np.unravel_index(band, shape), axis=1) * h
    if tree is not None:
        dist, nn = tree.query(band_pts, k=1, distance_upper_bound=(BAND_VOXELS + 1) * h, workers=2)
    else:
        dist, nn = np.full(len(band), np.inf), np.zeros(len(band), np.int64)
    close = np.isfinite(dist)
    nn = np.where(close, nn, 0)
    flat_sdf = sdf.ravel()
    cur = flat_sdf[band]
    # the voxel solid reaches up to a voxel (and the carving margin) in front of the surface
    # points; in front of its nearest point's surface a voxel is outside, so the zero level
    # passes through the points rather than ahead of them
    plane = np.einsum("ni,ni->n", band_pts - points[on][nn], sp_n[nn])
    ahead = close & (plane > 0)
    # ... unless no solid voxel behind it stays inside: a board about a voxel thin, seen from
    # both sides, has each voxel ahead of one face, and would vanish
    idx = np.flatnonzero(ahead & (cur < 0))
    stays = solid.copy()
    stays.ravel()[band[idx]] = False
    behind = np.rint((band_pts[idx] - sp_n[nn[idx]] * h - origin) / h).astype(np.int64)
    behind = np.clip(behind, 0, np.array(shape) - 1)
    ahead[idx[~stays[behind[:, 0], behind[:, 1], behind[:, 2]]]] = False
    cur = np.where(ahead, np.abs(cur), cur)
    exact = np.where(cur < 0, -np.minimum(dist, -cur), np.minimum(dist, cur))
    flat_sdf[band] = np.where(close, exact, cur).astype(np.float32)
    # keep a hair off zero so marching cubes has no degenerate cells
    tiny = np.float32(1e-3 * h)
    s = flat_sdf[band]
    s[(s >= 0) & (s < tiny)] = tiny
    s[(s < 0) & (s > -tiny)] = -tiny
    flat_sdf[band] = s

    snapped = close & (dist <= SNAP_VOXELS * h)
    known = np.zeros(shape, bool)
    known.ravel()[band[snapped]] = True
    rgb.reshape(-1, 3)[band[snapped]] = sp_col[nn[snapped]]
    surf = np.abs(flat_sdf[band]) <= 1.5 * h
    prov.ravel()[band[surf]] = GUESSED
    ks = snapped & surf
    prov.ravel()[band[ks]] = MIRRORED
    # where a symmetric copy lands on the observed surface (it does, where the plane is right),
    # the surface was seen: observed wins, in kind and in colour
    seen = on & (kind == OBSERVED)
    if seen.any():
        d_seen, nn_seen = cKDTree(points[seen]).query(
            band_pts[ks], k=1, distance_upper_bound=SNAP_VOXELS * h, workers=2
        )
        hit = np.isfinite(d_seen)
        prov.ravel()[band[ks][hit]] = OBSERVED
        rgb.reshape(-1, 3)[band[ks][hit]] = colors[seen][nn_seen[hit]]
    return NearColours(rgb, known, band), prov


def _box(m: np.ndarray, margin: int) -> tuple[slice, ...]:
    """The bounding box of ``m`` (X, Y, Z) bool, ``margin`` voxels wider within the grid."""
    box = []
    for ax in range(m.ndim):
        hit = np.flatnonzero(m.any(axis=tuple(a for a in range(m.ndim) if a != ax)))
        if len(hit) == 0:
            return tuple(slice(0, 0) for _ in m.shape)
        box.append(slice(max(hit[0] - margin, 0), min(hit[-1] + 1 + margin, m.shape[ax])))
    return tuple(box)


def _fill_regions(shell: np.ndarray, extra: np.ndarray, free: np.ndarray) -> np.ndarray:
    """(X, Y, Z) bool: the connected regions of ``extra`` (the fill beyond ``shell``) whose union
    with ``shell`` has less boundary (:func:`_faces`) than ``shell`` alone, or that are the
    body behind an open shell (:func:`_behind_shell`; ``free`` (X, Y, Z) bool: the voxels a
    camera saw through).

    A closed cabinet seen from the front and one side is a shell open at the back (its front,
    its seen side and the mirrored one), and the fill between its sides a body whose back is
    as ragged as the sides' readings end: more boundary than the open shell, which is the
    worse result (from behind, a box with no back). A compartment the camera looked into (a
    shelf's, between its boards) has seen space around it, and stays open.

    Each region is judged in its own box, one voxel wider than it (the voxels whose side it can
    change), so the cost follows the fill, not the grid. The boundary is counted in voxel
    faces, not boundary voxels: a wall one voxel thick has two sides, and counted once, a
    closed cabinet's thin hollow shell had less boundary than the cabinet filled.
    """
    lab, n = ndimage.label(extra)
    keep = np.zeros(n + 1, bool)
    shape = shell.shape
    for k, sl in enumerate(ndimage.find_objects(lab), start=1):
        if sl is None:
            continue
        # one voxel around the region: the voxels whose side it can change
        win = tuple(
            slice(max(s.start - 1, 0), min(s.stop + 1, d)) for s, d in zip(sl, shape, strict=True)
        )
        sh, region = shell[win], lab[win] == k
        union, shell_faces = _faces(sh | region), _faces(sh)
        keep[k] = union < shell_faces or _behind_shell(region, sh, free[win], union, shell_faces)
    keep[0] = False
    return keep[lab]


def _behind_shell(
    region: np.ndarray, shell: np.ndarray, free: np.ndarray, union: int, shell_faces: int
) -> bool:
    """Whether ``region`` (X, Y, Z) bool is the body behind the open ``shell`` (X, Y, Z) bool:
    ``ENCLOSED_SHARE`` of its faces on the shell, the space around the rest unseen
    (:func:`_unseen_rim`; ``free`` (X, Y, Z) bool: the voxels a camera saw through) and a body,
    not sheets (:func:`_bulk`); ``union`` and ``shell_faces``: the faces (:func:`_faces`) of the
    two together and of the shell alone. Cheapest test first: most regions fail the share.
    """
    alone = _faces(region)
    # the faces the region shares with the shell: each counted once in each alone
    shared = (alone + shell_faces - union) / 2
    return shared >= ENCLOSED_SHARE * alone and _unseen_rim(region, shell, free) and _bulk(region)


def _slice_holes(
    m: np.ndarray, most: int, deepest: int | None = None, faces: np.ndarray | None = None
) -> np.ndarray:
    """(X, Y, Z) int32: the holes of ``m`` (X, Y, Z) bool's slices across any axis of at most
    ``most`` voxels, labelled 1.. (a voxel in holes across two axes takes the later's label; 0:
    no hole); with ``deepest``, only those of a run of holes in consecutive slices at most
    ``deepest`` slices long; with ``faces`` (3, X, Y, Z) int8 (per axis: +1 on the voxels of
    surface points whose normal lies along the axis, so facing across the slices across it, -1
    on the other points' voxels), only those whose run has more voxels of +1 than of -1 within
    ``HOLE_NEAR`` voxels: through a sheet, not along a tube or between two boards.
    """
    out = np.zeros(m.shape, np.int32)
    n = 0
    # the three axes' labellings are independent and ndimage lets go of the GIL: a thread each
    for holes, k, small in _map(
        lambda ax: _axis_holes(m, ax, most, deepest, faces), range(m.ndim), m.size
    ):
        lab = np.where(small, np.arange(k + 1) + n, 0).astype(np.int32)[holes]
        out = np.where(lab > 0, lab, out)
        n += k
    return out


def _axis_holes(m, ax, most, deepest, faces) -> tuple[np.ndarray, int, np.ndarray]:
    """:func:`_slice_holes` across axis ``ax``: the empty regions of the slices labelled
    (X, Y, Z) int32, their number and (k + 1,) bool which of them are holes kept.
    """
    across = np.zeros((3, 3, 3), bool)
    plane = [slice(None)] * 3
    plane[ax] = slice(1, 2)
    across[tuple(plane)] = ndimage.generate_binary_structure(3, 1)[tuple(plane)]
    # the empty regions of each slice that reach no face of the array: one labelling (the
    # repeated dilation of ndimage.binary_fill_holes took 0.1 s an axis at 150^3)
    holes, k = ndimage.label(~m, across)
    small = np.bincount(holes.ravel(), minlength=k + 1) <= most
    for face in range(m.ndim):
        for end in (0, -1):
            small[holes.take(end, axis=face)] = False
    small[0] = False
    if (deepest is not None or faces is not None) and small.any():
        # judged by the run of holes through consecutive slices, each slice's its own label
        runs, r = ndimage.label(small[holes])
        bad = np.zeros(r + 1, bool)
        if deepest is not None:
            spans = [0] + [sl[ax].stop - sl[ax].start for sl in ndimage.find_objects(runs)]
            bad |= np.asarray(spans) > deepest
        if faces is not None:
            near = ndimage.maximum_filter(runs, 2 * HOLE_NEAR + 1)
            at = np.flatnonzero(faces[ax])
            score = np.bincount(near.flat[at], weights=faces[ax].flat[at], minlength=r + 1)
            bad |= score <= 0
        bad[0] = False
        small[np.unique(holes[bad[runs]])] = False
    return holes, k, small


def close_holes(
    solid: np.ndarray,
    grid: GridFrame,
    sp: SurfacePoints,
    sure_free: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` with the holes through its thin parts closed: the holes of its
    slices across each axis of at most ``TUNNEL_VOXELS`` voxels, through at most
    ``SHEET_VOXELS`` slices, in a sheet (more surface points of ``sp`` near them face across
    the slice than along it), through which no camera surely saw (``sure_free``: world points
    (M, 3) -> (M,) bool; at most ``HOLE_SEEN`` of a hole's voxels in it).

    A sensor leaves pixels without a reading on a flat face (a dark or glossy patch, a grazing
    angle); the closure is built behind the points it got, so a board seen from one side came
    out as a sheet with holes through it: a bedside cabinet's front and top from one frame had
    about seventy. The scan's own free space carves such a blotch as far as the readings around
    it reach (the sensor's rule for silhouettes), through the board; the space surely seen
    through does not, where a hole in the object (a handle's loop, the gap between slats) seen
    at all was surely seen through. A slit between two boards (a sofa's seat and its base) is
    a hole in the slices across the boards, whose faces turn along the slice: it stays (closed,
    a sofa seen from three views lost 0.03 of its F-score).
    """
    if not solid.any():
        return solid
    box = _box(solid, 1)
    shape = tuple(b.stop - b.start for b in box)
    faces = np.zeros((3, *shape), np.int8)
    lo = np.array([b.start for b in box])
    inside = ((sp.idx >= lo) & (sp.idx < lo + shape)).all(axis=1)
    at = tuple((sp.idx[inside] - lo).T)
    for ax in range(3):
        faces[ax][at] = np.where(np.abs(sp.normals[inside, ax]) >= SLAB_FLAT, 1, -1)
    holes = _slice_holes(solid[box], TUNNEL_VOXELS, SHEET_VOXELS, faces)
    flat = np.flatnonzero(holes.ravel())
    if not len(flat):
        return solid
    sub = GridFrame(grid.grid_to_world, holes.shape, grid.origin + lo * grid.h, grid.h)
    seen = sure_free(sub.to_world(sub.centres(flat)))
    lab = holes.ravel()[flat]
    n = int(lab.max()) + 1
    size = np.bincount(lab, minlength=n)
    share = np.bincount(lab, weights=seen, minlength=n) / np.maximum(size, 1)
    shut = (size > 0) & (share <= HOLE_SEEN)
    out = solid.copy()
    out[box] |= shut[holes] & (holes > 0)
    return out


def close_lids(
    solid: np.ndarray,
    grid: GridFrame,
    height_world: Callable[[np.ndarray], np.ndarray],
    sure_free: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` with the plates its rims enclose filled: the holes of its
    level slices (across up), each slice taken with the ``LID_REACH`` slices either side of it
    (a rim read by a noisy sensor is whole only over a few slices), of any size, in a run
    through no more slices beyond those than a plate's edge spans (:func:`_plates`); each run
    a plate ``LID_THICK`` slices thick down from its rim's top (:func:`_rim_tops`; as tall as
    its edge's face where that is seen to end within ``LID_FACE``, :func:`_edge_faces`; at the
    object's top ``LID_TOP`` metres, :func:`_lid_slices`, beyond ``LID_THICK`` slices only
    where no camera surely saw under its edge), filled where no camera surely saw through its
    top ``LID_THICK`` slices (at most ``HOLE_SEEN`` of them in ``sure_free``) and nothing
    stands over it (at most ``LID_COVERED`` of them under solid within ``LID_CLEAR`` slices: a
    chair's seat over the rails between its legs makes them a frame, not a plate's edge).

    A table's top seen from its own height shows its edge all round and nothing of its face:
    closed thinly, it was a ring. A rim no taller than a plate's edge that encloses what no
    camera saw is the edge of a plate; a bin's wall, as tall as the bin, is not.
    """
    level = _level_axis(grid, height_world)
    if not solid.any() or level is None:
        return solid
    ax, _ = level
    box = _box(solid, LID_REACH + 1)
    m = solid[box]
    wide = ndimage.maximum_filter1d(m.view(np.uint8), 2 * LID_REACH + 1, axis=ax).astype(bool)
    holes, _, small = _axis_holes(wide, ax, wide.size, None, None)
    if not small[1:].any():
        return solid
    # a hole through consecutive slices is one plate's
    lab, _ = ndimage.label(small[holes])
    lab = np.where(_plates(lab, ax)[lab], lab, 0)
    top, edge = _rim_tops(m, lab, ax)
    face = _edge_faces(m, lab, ax, top, grid.h)
    thick = np.maximum(np.maximum(_lid_slices(m, top, ax, grid.h), edge), face)
    n = len(top)
    flat = np.flatnonzero(lab.ravel())
    lf = lab.ravel()[flat]
    at = np.unravel_index(flat, m.shape)[ax]
    inside = (at <= top[lf]) & (at > top[lf] - thick[lf])
    flat, lf = flat[inside], lf[inside]
    if not len(flat):
        return solid
    # the plate as thin as the closure tells whether it is one; a top's thicker plate stops
    # wherever a camera surely saw under its edge
    thin = at[inside] > top[lf] - LID_THICK
    lo = np.array([b.start for b in box])
    sub = GridFrame(grid.grid_to_world, m.shape, grid.origin + lo * grid.h, grid.h)
    seen = sure_free(sub.to_world(sub.centres(flat)))
    count = np.bincount(lf[thin], minlength=n)
    share = np.bincount(lf[thin], weights=seen[thin], minlength=n) / np.maximum(count, 1)
    cover = np.zeros(int(thin.sum()), bool)
    ijk = np.stack(np.unravel_index(flat[thin], m.shape), axis=1)
    for _ in range(LID_CLEAR):  # each slice above, in turn
        ijk[:, ax] += 1
        ok = ijk[:, ax] < m.shape[ax]
        cover[ok] |= m[ijk[ok, 0], ijk[ok, 1], ijk[ok, 2]]
    covered = np.bincount(lf[thin], weights=cover, minlength=n) / np.maximum(count, 1)
    shut = (count > 0) & (share <= HOLE_SEEN) & (covered <= LID_COVERED)
    out = solid.copy()
    fill = np.zeros(m.shape, bool)
    fill.ravel()[flat[shut[lf] & (thin | ~seen)]] = True
    out[box] |= fill
    return out


def repeat_plates(
    solid: np.ndarray,
    grid: GridFrame,
    sp: SurfacePoints,
    height_world: Callable[[np.ndarray], np.ndarray],
    sure_free: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` with its repeated level plates (a bookcase's shelves) carried on
    at their spacing, within its height, where observed points mark the plate's outline at that
    height and none just above or below it (its edge, seen end on), and no camera surely saw
    through it (at most ``HOLE_SEEN`` of it in ``sure_free``).

    A bookcase's upper shelves seen from standing height are seen end on: their faces too
    obliquely for a reading, their front edges as a few points each. The lower ones, seen from
    above, are whole, and they repeat (:func:`_repeated`): the plate is their common outline,
    as thick as they are.
    """
    level = _level_axis(grid, height_world)
    if not solid.any() or level is None:
        return solid
    ax, _ = level
    m = np.moveaxis(solid, ax, -1)
    run = _repeated(m)
    if run is None:
        return solid
    centres, thick, plan = run
    obs = np.moveaxis(sp.occ_obs, ax, -1)
    slices = np.flatnonzero(m.any(axis=(0, 1)))
    outline = plan & ~ndimage.binary_erosion(plan)
    out = m.copy()
    for c in _carried(centres, float(np.median(np.diff(centres))), slices.min(), slices.max()):
        lo = round(c - (thick - 1) / 2)
        hi = lo + thick
        if lo < 0 or hi > m.shape[-1] or m[..., lo:hi][plan].mean() > 0.5:
            continue  # beyond the grid, or the plate is there
        if _edge_seen(obs, outline, lo, hi) and _seen_through(grid, plan, lo, hi, ax, sure_free):
            out[..., lo:hi] |= plan[..., None]
    return np.moveaxis(out, -1, ax)


def _edge_seen(obs: np.ndarray, outline: np.ndarray, lo: int, hi: int) -> bool:
    """Whether observed points ``obs`` (A, B, S) bool, level slices along the last axis, mark
    at least ``REPEAT_EDGE`` of a plate's ``outline`` (A, B) bool in slices ``lo``..``hi`` (a
    voxel and a slice either side allowed), with none in the two slices beyond either side: a
    plate's edge, not a wall running past it (a bookcase's side panel).
    """
    near = ndimage.binary_dilation(outline)
    band = obs[..., max(lo - 1, 0) : hi + 1].any(axis=-1)
    beside = obs[..., max(lo - 3, 0) : max(lo - 1, 0)].any(axis=-1)
    beside |= obs[..., hi + 1 : hi + 3].any(axis=-1)
    return bool((near & band & ~beside).sum() >= REPEAT_EDGE * outline.sum())


def _seen_through(
    grid: GridFrame,
    plan: np.ndarray,
    lo: int,
    hi: int,
    ax: int,
    sure_free: Callable[[np.ndarray], np.ndarray],
) -> bool:
    """Whether no camera surely saw through the plate ``plan`` (A, B) bool in level slices
    ``lo``..``hi`` along ``ax`` of ``grid`` (at most ``HOLE_SEEN`` of it in ``sure_free``).
    """
    cols = np.argwhere(plan)
    cells = np.concatenate([np.c_[cols, np.full(len(cols), k)] for k in range(lo, hi)])
    ijk = np.insert(cells[:, :2], ax, cells[:, 2], axis=1)  # back to the grid's axes
    flat = np.ravel_multi_index(tuple(ijk.T), grid.shape)
    return bool(sure_free(grid.to_world(grid.centres(flat))).mean() <= HOLE_SEEN)


def _repeated(m: np.ndarray) -> tuple[np.ndarray, int, np.ndarray] | None:
    """The longest run of plates in ``m`` (A, B, S) bool, level slices along its last axis,
    that repeat: their centres (K,) float64 (slices), their thickness (slices) and their common
    plan (A, B) bool (where at least half of them hold solid); None where no ``REPEAT_MIN``
    plates repeat.
    """
    area = m.sum(axis=(0, 1))
    if area.max() == 0:
        return None
    big = area >= REPEAT_AREA * area.max()
    lab, n = ndimage.label(big)
    if n < REPEAT_MIN:
        return None
    spans = ndimage.find_objects(lab)
    centres = np.array([(s[0].start + s[0].stop - 1) / 2 for s in spans])
    thick = np.array([s[0].stop - s[0].start for s in spans])
    plans = [m[..., s[0]].any(axis=-1) for s in spans]
    best: list[int] = []
    for i in range(n):
        seq = [i]
        for j in range(i + 1, n):
            gap = centres[j] - centres[seq[-1]]
            first = centres[seq[1]] - centres[seq[0]] if len(seq) > 1 else gap
            a, b = plans[seq[-1]], plans[j]
            over = (a & b).sum() / max(min(a.sum(), b.sum()), 1)
            if abs(gap - first) <= max(1.5, REPEAT_SPACING * first) and over >= REPEAT_OVERLAP:
                seq.append(j)
            else:
                break
        if len(seq) > len(best):
            best = seq
    if len(best) < REPEAT_MIN:
        return None
    plan = np.mean([plans[k] for k in best], axis=0) >= 0.5
    return centres[best], int(np.median(thick[best])), plan


def _carried(centres: np.ndarray, spacing: float, lowest: int, highest: int) -> list[float]:
    """Slices (centres) a run of plates at ``centres`` (K,), ``spacing`` apart, goes on at, both
    ways, within ``lowest`` and ``highest`` (the solid's slices).

    >>> _carried(np.array([2.0, 12.0, 22.0]), 10.0, 0, 45)
    [32.0, 42.0]
    """
    out: list[float] = []
    c = float(centres[-1]) + spacing
    while c <= highest:
        out.append(c)
        c += spacing
    c = float(centres[0]) - spacing
    while c >= lowest:
        out.append(c)
        c -= spacing
    return out


def fill_bodies(
    solid: np.ndarray,
    grid: GridFrame,
    sp: SurfacePoints,
    height_world: Callable[[np.ndarray], np.ndarray],
    sure_free: Callable[[np.ndarray], np.ndarray],
    free: np.ndarray,
) -> np.ndarray:
    """(X, Y, Z) bool: ``solid`` with the bodies under its tops filled
    (:func:`partscale.complete.body.close_bodies`): under a top, behind a wall that reaches
    most of the way down to the floor, what no camera surely saw through (``sure_free``) is a
    body's inside, never where any camera saw through (``free`` (X, Y, Z) bool). On a level
    grid only, and only where the floor was found (without it, a ray under a desk reads nothing
    and its knee space is unseen).
    """
    level = _level_axis(grid, height_world)
    if not solid.any() or level is None:
        return solid
    ax, downward = level
    slices = np.repeat(grid.origin[None, :].astype(np.float32), grid.shape[ax], axis=0)
    slices[:, ax] += np.arange(grid.shape[ax], dtype=np.float32) * np.float32(grid.h)
    heights = height_world(grid.to_world(slices)).astype(np.float64)
    # what the cameras surely saw through lies within what they saw through: only the voxels
    # seen through are asked
    unseen = np.ones(grid.shape, bool)
    seen = np.flatnonzero(free.ravel())
    unseen.ravel()[seen] = ~sure_free(grid.to_world(grid.centres(seen)))
    return body_mod.close_bodies(
        solid, sp.idx, sp.normals, ax, downward, heights, grid.h, unseen, free
    )


def _plates(lab: np.ndarray, ax: int) -> np.ndarray:
    """(L + 1,) bool: which runs of holes ``lab`` (X, Y, Z) int32 labels 1..L through the
    level slices (across ``ax``, up), each slice widened ``LID_REACH`` slices either way, span
    no more slices beyond those than a plate's edge: ``LID_SLICES``, or ``LID_ASPECT`` of the
    run's narrower level width where that is more; False for 0.
    """
    keep = np.zeros(int(lab.max()) + 1, bool)
    for k, sl in enumerate(ndimage.find_objects(lab), start=1):
        if sl is None:
            continue
        sizes = [s.stop - s.start for s in sl]
        width = min(size for a, size in enumerate(sizes) if a != ax)
        keep[k] = sizes[ax] - 2 * LID_REACH <= max(LID_SLICES, LID_ASPECT * width)
    return keep


def _lid_slices(m: np.ndarray, top: np.ndarray, ax: int, h: float) -> np.ndarray:
    """(L + 1,) int64: the slices thick each plate is, down from its rim's ``top`` (L + 1,)
    (:func:`_rim_tops`) in ``m`` (X, Y, Z) bool, up along ``ax`` towards higher indices (as
    :func:`_rim_tops` reads it): ``LID_TOP`` metres (``h`` a voxel's side) where the rim's top
    is within ``LID_TOP_SLICES`` of the highest solid slice, ``LID_THICK`` elsewhere; both at
    least ``LID_THICK``.

    >>> m = np.zeros((4, 12, 4), bool); m[:, :11] = True  # solid up to slice 10
    >>> _lid_slices(m, np.array([-1, 10, 5]), 1, 0.005).tolist()  # 5 mm voxels
    [2, 6, 2]
    """
    level = np.flatnonzero(m.any(axis=tuple(a for a in range(3) if a != ax)))
    highest = level.max() if len(level) else -1
    at_top = (top >= 0) & (np.abs(top - highest) <= LID_TOP_SLICES)
    return np.where(at_top, max(LID_THICK, round(LID_TOP / h)), LID_THICK).astype(np.int64)


def _rim_tops(m: np.ndarray, lab: np.ndarray, ax: int) -> tuple[np.ndarray, np.ndarray]:
    """(L + 1,) int64 each: for each plate ``lab`` (X, Y, Z) int32 labels 1..L in ``m`` (X, Y,
    Z) bool, the slice across ``ax`` (up) of its rim's top and the slices its edge spans (-1
    and 0 where it has none).

    The voxels of ``m`` beside the plate in its slices with none above them have their tops
    where the rim's solid ends: along the edge's top, and down the inner side of the closure
    behind the edge's face, as tall as that face (a shelf's board 20 mm thick, seen at its
    front edge, closed behind it, has tops over its 5 slices at 4 mm). The edge: the run of
    slices round the one most tops lie in (a wall that runs on above the plate, a bookcase's
    side beside a shelf, has its top elsewhere) where at least ``RIM_SHARE`` as many lie; the
    top: its highest slice. Where a slice just beyond that run holds more than ``RIM_SHARP``
    as many, the edge is rounded (a cushion's): the top is the most common slice, and no
    edge is measured (0).

    >>> m = np.zeros((8, 6, 8), bool); m[:, :4] = True  # a board, slices 0-3
    >>> m[2:6, :, 2:6] = False  # its hole
    >>> m[1, 3] = m[6, 3] = False  # the rim's tops: at slice 2 along two sides, 3 along two
    >>> lab = np.zeros(m.shape, np.int32); lab[2:6, :, 2:6] = 1
    >>> [a.tolist() for a in _rim_tops(m, lab, 1)]  # top slice 3, an edge 2 slices tall
    [[-1, 3], [0, 2]]
    """
    size = [3, 3, 3]
    size[ax] = 1
    near = ndimage.maximum_filter(lab, size=size)
    above = np.zeros_like(m)
    lower, upper = [slice(None)] * 3, [slice(None)] * 3
    lower[ax], upper[ax] = slice(0, -1), slice(1, None)
    above[tuple(lower)] = m[tuple(upper)]
    rim = np.flatnonzero((m & ~above & (near > 0)).ravel())
    per = np.zeros((int(lab.max()) + 1, m.shape[ax]), np.int64)
    np.add.at(per, (near.ravel()[rim], np.unravel_index(rim, m.shape)[ax]), 1)
    rows, n = np.arange(len(per)), per.shape[1]
    mode = np.argmax(per, axis=1)
    most = per[rows, mode]
    # the run of slices round the mode holding RIM_SHARE of its count: the edge
    held = per >= RIM_SHARE * most[:, None]
    idx = np.arange(n)[None, :]
    gap_above = np.where(~held & (idx > mode[:, None]), idx, n).min(axis=1)
    gap_below = np.where(~held & (idx < mode[:, None]), idx, -1).max(axis=1)
    # a board's edge ends sharply; a cushion's rounded one tails off: its most common top
    beyond = np.maximum(
        np.where(gap_above < n, per[rows, np.minimum(gap_above, n - 1)], 0),
        np.where(gap_below >= 0, per[rows, np.maximum(gap_below, 0)], 0),
    )
    sharp = beyond <= RIM_SHARP * most
    has = per.any(axis=1)
    top = np.where(has, np.where(sharp, gap_above - 1, mode), -1)
    return top, np.where(has & sharp, gap_above - gap_below - 1, 0)


def _edge_faces(m: np.ndarray, lab: np.ndarray, ax: int, top: np.ndarray, h: float) -> np.ndarray:
    """(L + 1,) int64: for each plate ``lab`` (X, Y, Z) int32 labels 1..L in ``m`` (X, Y, Z)
    bool with its rim's top slice ``top`` (L + 1,) (:func:`_rim_tops`, up along ``ax`` towards
    higher indices), the slices its outer face spans down from that top: the median run of
    solid down from the top along the outline of the plate with its rim (what the cameras saw
    of its edge, closed behind); 0 where that is more than ``LID_FACE`` metres (``h`` a voxel's
    side) or the plate has no top.

    A table's top seen from above its height shows its edge's face down to its underside, and
    the space under that seen free; the closure behind the face is as tall. Its rim's tops, all
    at the top's face, do not measure it.

    >>> m = np.zeros((10, 8, 10), bool); m[:, 2:7] = True  # a top 5 slices thick, 2-6
    >>> m[3:7, :, 3:7] = False  # its unseen middle
    >>> lab = np.zeros(m.shape, np.int32); lab[3:7, :, 3:7] = 1
    >>> _edge_faces(m, lab, 1, np.array([-1, 6]), 0.01).tolist()  # 10 mm voxels
    [0, 5]
    >>> _edge_faces(m, lab, 1, np.array([-1, 6]), 0.005).tolist()  # 25 mm: within 60 mm
    [0, 5]
    >>> _edge_faces(m, lab, 1, np.array([-1, 6]), 0.02).tolist()  # 100 mm: an apron's
    [0, 0]
    """
    mm, ll = np.moveaxis(m, ax, -1), np.moveaxis(lab, ax, -1)
    # run[..., s]: solid slices from s down, s included
    run = np.zeros(mm.shape, np.int16)
    run[..., 0] = mm[..., 0]
    for s in range(1, mm.shape[-1]):
        run[..., s] = (run[..., s - 1] + 1) * mm[..., s]
    face = np.zeros(len(top), np.int64)
    reach = LID_FACE / h
    for s in np.unique(top[top >= 0]):
        holes = ll[..., s]
        cc, _ = ndimage.label(mm[..., s] | (holes > 0))
        pieces, plates = ndimage.find_objects(cc), ndimage.find_objects(holes)
        known: dict[tuple[int, ...], int] = {}  # plates in the same pieces share an outline
        for k in np.flatnonzero(top == s):
            if k > len(plates) or plates[k - 1] is None:
                continue
            ids = np.unique(cc[plates[k - 1]][holes[plates[k - 1]] == k])
            if tuple(ids) not in known:
                known[tuple(ids)] = _outline_run(cc, ids, pieces, mm[..., s], run[..., s], reach)
            face[k] = known[tuple(ids)]
    return face


def _outline_run(
    cc: np.ndarray, ids: np.ndarray, pieces: list, solid: np.ndarray, run: np.ndarray, reach: float
) -> int:
    """The median of ``run`` (A, B) int16 along the outline of the pieces ``ids`` of ``cc`` (A,
    B) int32 labels (their boxes ``pieces``, :func:`scipy.ndimage.find_objects`), their holes
    filled, where ``solid`` (A, B) bool; 0 where that is more than ``reach`` or there is none.
    """
    # within the box of the pieces: the slice may hold many
    box = tuple(
        slice(min(pieces[i - 1][a].start for i in ids), max(pieces[i - 1][a].stop for i in ids))
        for a in range(2)
    )
    disc = ndimage.binary_fill_holes(np.isin(cc[box], ids))
    outline = disc & ~ndimage.binary_erosion(disc) & solid[box]
    if not outline.any():
        return 0
    r = float(np.median(run[box][outline]))
    return round(r) if r <= reach else 0


def _close_tunnels(fill: np.ndarray, free: np.ndarray) -> np.ndarray:
    """(X, Y, Z) bool: ``fill`` with its tunnels closed: the holes of its slices across each
    axis of at most ``TUNNEL_VOXELS`` voxels where no camera saw through.

    The fill between two opposite sides is marched from their points; a hole in the sensor's
    reading of one side, mirrored onto the other, leaves no point at either end, and the fill a
    tunnel through the object.
    """
    if not fill.any():
        return fill
    box = _box(fill, 1)
    out = _slice_holes(fill[box], TUNNEL_VOXELS) > 0
    fill = fill.copy()
    fill[box] |= out & ~free[box]
    return fill


def _unseen_rim(region: np.ndarray, shell: np.ndarray, free: np.ndarray) -> bool:
    """Whether a camera saw through at most ``RIM_SEEN`` of the voxels around ``region`` (X, Y,
    Z) bool, outside it and ``shell``; ``free`` (X, Y, Z) bool: the voxels it saw through.
    """
    rim = ndimage.binary_dilation(region) & ~region & ~shell
    return bool(np.count_nonzero(free[rim]) <= RIM_SEEN * np.count_nonzero(rim))


def _bulk(region: np.ndarray) -> bool:
    """Whether ``region`` (X, Y, Z) bool is a body rather than sheets or rods: an opening by a
    ball of radius ``BULK_RADIUS`` voxels keeps at least ``BULK_SHARE`` of its voxels.
    """
    from skimage.morphology import ball

    r = BULK_RADIUS
    opened = ndimage.binary_opening(np.pad(region, r + 1), ball(r).astype(bool))
    return bool(opened.sum() >= BULK_SHARE * region.sum())


def _faces(solid: np.ndarray) -> int:
    """The number of voxel faces between ``solid`` (X, Y, Z) bool and the space outside it
    (beyond the array's edge: outside).
    """
    s = np.pad(solid, 1)
    return sum(int(np.count_nonzero(np.diff(s, axis=a))) for a in range(3))


def _fills(points, normals, idx, origin, h, free) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Three (X, Y, Z) bool: the fill between opposite surfaces (:func:`_between`) and the
    slabs, sure and unsure (:func:`_slab`), of surface ``points`` (N, 3) grid coordinates with
    unit ``normals`` (N, 3) in voxels ``idx`` (N, 3) int of a grid (``origin``, voxel ``h``)
    whose voxels no camera saw through are ``~free`` (X, Y, Z) bool.
    """
    facing = _facing(normals, idx, free.shape)
    between, seen = _between(points, normals, origin, h, facing, free)
    sure, unsure = _slab(points, normals, idx, origin, h, free, seen, facing)
    return between, sure, unsure


def _facing(normals: np.ndarray, idx: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """(X, Y, Z) uint8: which ways the points (``normals`` (N, 3) unit, in voxels ``idx`` (N, 3)
    int) in and next to each voxel face, one bit per axis direction (bit ``2 * axis + 1`` for
    the negative way), dilated by a 3x3x3 cube.
    """
    axis = np.argmax(np.abs(normals), axis=1)
    neg = normals[np.arange(len(normals)), axis] < 0
    bits = np.zeros(shape, np.uint8)
    np.bitwise_or.at(
        bits, (idx[:, 0], idx[:, 1], idx[:, 2]), (1 << (2 * axis + neg)).astype(np.uint8)
    )
    return _dilate_bits(bits)


def _between(points, normals, origin, h, facing, free) -> tuple[np.ndarray, np.ndarray]:
    """(X, Y, Z) bool: voxels between a surface point and the first surface behind it that
    faces the other way (a leg's front and back, a seat's left and right side), within
    ``BETWEEN_VOXELS``, where no camera saw through any voxel of the segment: the thickness the
    scan measured, instead of a thin closure with the unseen back of its shell inside the
    object. And (N,) int64: the voxels behind each point at which that surface was found (0:
    none). ``facing`` (X, Y, Z) uint8: the ways the points in and next to each voxel face.
    """
    dirs = np.zeros((6, 3))
    dirs[np.arange(6), np.arange(6) // 2] = np.where(np.arange(6) % 2 == 0, 1.0, -1.0)
    cos = normals @ dirs.T
    opposite = ((cos < -BETWEEN_FACING) * (1 << np.arange(6))).sum(axis=1)
    across = ((np.abs(cos) < BETWEEN_FACING) * (1 << np.arange(6))).sum(axis=1)
    out = np.zeros(free.shape, bool)
    seen = np.zeros(len(points), np.int64)
    _march(
        ((points - origin) / h).astype(np.float64),
        normals.astype(np.float64),
        opposite.astype(np.uint8),
        across.astype(np.uint8),
        facing,
        free,
        int(BETWEEN_REACH),
        int(BETWEEN_VOXELS),
        out,
        seen,
    )
    return out, seen


def _slab(points, normals, idx, origin, h, free, seen, facing) -> tuple[np.ndarray, np.ndarray]:
    """Two (X, Y, Z) bool, sure and unsure: each face carried in to the thickness its side faces
    and its other side, where seen, show.

    Where a face ends at a convex edge, the face perpendicular to it there (a seat's front below
    its top, a leg's side beside its front) runs in from the edge as far as the part is thick: a
    walk from an edge point along its face's axis, through voxels within two of points facing
    sideways (gaps of ``SLAB_GAP`` stepped over), measures it. A point with a side face
    ``SLAB_ABOVE`` voxels in front of it stands at a junction (a back rising from a seat), one
    with none next to it inside the face: neither measures. A walk whose side face runs on past
    ``BETWEEN_VOXELS`` measured a width (a seat's front walked from its end): it counts only from
    a sharp edge (a stool's flat rim), not from a rounded one, where most voxels around the
    point hold only points turned off the axes (a cushion's end: carried in, its flat band
    would be a sheet across the thick cushion), and only along a band: a face spanning at most
    ``SLAB_BAND`` of that width across (a rim), not a cabinet's side panel as tall as the
    cabinet is deep (carried in, it fills what no camera saw under each shelf). Every point takes the most common
    of its ``SLAB_NEIGHBOURS`` nearest measurements facing the same way (a leg flush below an
    edge lengthens a few, holes at an edge shorten a few) and is carried in along its face's
    axis to that depth through voxels no camera saw through: the thickness of a slab whose
    underside no camera saw, where the between-fill finds no opposite surface.

    Where a camera saw the face's other side, ``SLAB_SEEN_FROM`` or more voxels behind a flat
    point (``seen``, from :func:`_between`), that distance is a measurement too, and a carry
    stops at the other side: a cabinet's top seen from inside an open compartment is as thick
    as its board there, not as deep as the side panel its edge runs down, and is not carried
    through the compartment's unseen back.
    """
    shape = free.shape
    axis = np.argmax(np.abs(normals), axis=1)
    neg = normals[np.arange(len(normals)), axis] < 0
    cls = (2 * axis + neg).astype(np.int64)
    # flat faces along the grid's axes only: on a curved surface the dominant axis turns
    # gradually, and its classes meet at no edge
    flat = np.abs(normals[np.arange(len(normals)), axis]) >= SLAB_FLAT
    bits = np.zeros(shape, np.uint8)
    f = idx[flat]
    np.bitwise_or.at(bits, (f[:, 0], f[:, 1], f[:, 2]), (1 << cls[flat]).astype(np.uint8))
    every = np.zeros(shape, np.uint8)
    every[idx[:, 0], idx[:, 1], idx[:, 2]] = 1
    every = _dilate_bits(_dilate_bits(every)) > 0
    near = _dilate_bits(bits)
    dil = _dilate_bits(near)
    side = ((1 << np.arange(6))[None, :] * (np.arange(6)[None, :] // 2 != axis[:, None])).sum(1)
    p = ((points - origin) / h).astype(np.float64)
    # measured and carried along the face's axis: an edge point's own normal leans off the face
    # (its neighbours span the edge), would walk off the side face it measures, and carried
    # far, would drift off the slab (under a table's top)
    n_axis = np.zeros((len(points), 3))
    n_axis[np.arange(len(points)), axis] = np.where(neg, -1.0, 1.0)
    depth = np.zeros(len(points), np.int64)
    wide = np.zeros(len(points), np.bool_)
    _slab_measure(
        p, n_axis, side.astype(np.uint8), near, dil, every, int(BETWEEN_VOXELS), depth, wide
    )
    # a width is carried (as a thickness) only from a sharp edge: a rounded end's flat band is
    # ringed by points turned off the axes, a stool's flat rim is not
    wide_walk = wide.copy()
    if wide.any():
        # by voxels, not points: a scan samples a curve as densely as it likes
        held = np.zeros(shape, np.float32)
        held[idx[:, 0], idx[:, 1], idx[:, 2]] = 1.0
        turned = held * (bits == 0)
        size = 2 * SLAB_RING + 1
        iw = idx[wide]
        at = tuple(iw.T)
        share = ndimage.uniform_filter(turned, size, mode="constant")[at] / np.maximum(
            ndimage.uniform_filter(held, size, mode="constant")[at], 1e-9
        )
        w = np.flatnonzero(wide)
        wide[w[share <= SLAB_RING_TURNED]] = False
        # and only along a band: a face narrow across (a rim), not one as wide or tall as the
        # width it would be carried (a cabinet's side panel, carried in by its top's width,
        # fills the unseen space under each shelf)
        rim = np.flatnonzero(wide_walk & ~wide)
        band = np.zeros(len(rim), np.int64)
        _band(p[rim], axis[rim].astype(np.int64), cls[rim], near, band)
        wide[rim[band > SLAB_BAND * depth[rim]]] = True
        depth[wide] = 0
    # the other side seen behind a flat point: the part's thickness there (the fill between
    # reaches the widened side, one voxel short of it)
    other_side = flat & (seen >= SLAB_SEEN_FROM)
    depth[other_side] = np.minimum(seen[other_side] + 1, int(BETWEEN_VOXELS))
    # thickness at every point, from the nearest measurements facing its way
    t = np.zeros(len(points))
    agree = np.zeros(len(points), bool)
    for c in range(6):
        m = cls == c
        e = m & (depth >= 1)
        if e.any():
            # a few walks down a leg flush below the edge: not the slab's thickness (a width
            # carried from a band is no walk down: see above)
            high = e & ~wide_walk & (depth > SLAB_OUTLIER * np.median(depth[e]))
            if high.sum() < SLAB_OUTLIER_SHARE * e.sum():
                e &= ~high
        # a box's faces have edges all round (a seat's top: 14 % of its points measure); a
        # rounded cushion gives a few scattered walks (0.3-2 %), no thickness, unless its
        # other side was seen
        if e.sum() < SLAB_EDGE_SHARE * m.sum() or e.sum() == 0:
            continue
        k = min(SLAB_NEIGHBOURS, int(e.sum()))
        dist, nn = cKDTree(p[e]).query(p[m], k=k, workers=2)
        nn = nn.reshape(int(m.sum()), k)
        # the most common thickness: legs flush below an edge lengthen a few walks, sensor
        # holes at an edge shorten a few
        nb = int(BETWEEN_VOXELS) + 1
        row = np.repeat(np.arange(int(m.sum())), k)
        votes = np.bincount(row * nb + depth[e][nn].ravel(), minlength=int(m.sum()) * nb)
        votes = votes.reshape(int(m.sum()), nb)
        mode = np.argmax(votes, axis=1)
        cum = np.concatenate([np.zeros((len(votes), 1), np.int32), np.cumsum(votes, 1)], 1)
        lo_, hi_ = np.maximum(mode - 1, 0), np.minimum(mode + 2, votes.shape[1])
        share = (cum[np.arange(len(votes)), hi_] - cum[np.arange(len(votes)), lo_]) / k
        far = np.asarray(dist).reshape(int(m.sum()), k)[:, 0] > BETWEEN_VOXELS
        t[m] = np.where(far, 0.0, mode)
        agree[m] = share >= SLAB_AGREE
    t[~flat] = 0.0
    # the bit of the way a point's other side faces
    other = (1 << (2 * axis + ~neg)).astype(np.uint8)
    sure = np.zeros(shape, bool)
    _carry(p[agree], n_axis[agree], t[agree], free, sure, other[agree], facing)
    unsure = np.zeros(shape, bool)
    _carry(p[~agree], n_axis[~agree], t[~agree], free, unsure, other[~agree], facing)
    return sure, unsure


def _dilate_bits(bits: np.ndarray) -> np.ndarray:
    """(X, Y, Z) uint8: the OR of each voxel's 3x3x3 neighbourhood (separable: per axis)."""
    dil = bits
    for ax in range(3):
        d = dil.copy()
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[ax], hi[ax] = slice(None, -1), slice(1, None)
        d[tuple(lo)] |= dil[tuple(hi)]
        d[tuple(hi)] |= dil[tuple(lo)]
        dil = d
    return dil


@numba.njit(cache=True, inline="always")
def _voxel_at(p, n, i, s):
    """The voxel (three ints) holding point ``p[i] - s * n[i]`` (continuous indices)."""
    return (
        int(np.rint(p[i, 0] - n[i, 0] * s)),
        int(np.rint(p[i, 1] - n[i, 1] * s)),
        int(np.rint(p[i, 2] - n[i, 2] * s)),
    )


@numba.njit(cache=True, inline="always")
def _in_grid(a, b, c, shape):
    """Whether voxel ``(a, b, c)`` (ints) lies in a grid of ``shape`` (X, Y, Z): the walks stop
    at the grid's border.
    """
    return 0 <= a < shape[0] and 0 <= b < shape[1] and 0 <= c < shape[2]


@numba.njit(cache=True, parallel=True)
def _slab_measure(p, n, side, near, bits, anyb, reach, depth, wide):
    for i in numba.prange(p.shape[0]):
        last = 0
        # a face rising beside the point (a junction, the back above a seat) is no edge
        a, b, c = _voxel_at(p, n, i, -SLAB_ABOVE)
        if _in_grid(a, b, c, bits.shape) and bits[a, b, c] & side[i]:
            depth[i] = 0
            continue
        # and a point not next to a side face is no edge either (its walk would only graze it)
        a, b, c = _voxel_at(p, n, i, 1.0)
        if not (_in_grid(a, b, c, bits.shape) and near[a, b, c] & side[i]):
            depth[i] = 0
            continue
        ended = False
        for s in range(1, reach + 1):
            a, b, c = _voxel_at(p, n, i, s)
            if not _in_grid(a, b, c, bits.shape):
                ended = True  # the grid's edge: nothing can lie beyond it
                break
            # along the side face, not through it: its voxels may be seen free by a hair
            if bits[a, b, c] & side[i]:
                last = s
            elif s - last > SLAB_GAP:
                # where the side face ends but the surface goes on (it rounds into a cushion's
                # underside, turned off the axes), the walk measured the flat band, not the part
                if anyb[a, b, c]:
                    last = 0
                ended = True
                break
        # the side face runs on beyond the reach: the walk measured a width (a seat's front
        # walked from its end), which is the part's thickness only where the face it carries
        # spans the part (a stool's flat rim), not where it is a band of a rounded end
        wide[i] = not ended
        # the side face's last voxel lies up to two voxels (the widening) past its points
        depth[i] = max(last - 2, 0)


@numba.njit(cache=True, parallel=True)
def _band(p, axis, cls, near, band):
    # a face's extent through each point (voxels), the least over the two axes across its
    # normal: walked both ways through voxels next to points facing its way, gaps of SLAB_GAP
    # stepped over
    for i in numba.prange(p.shape[0]):
        v0 = (int(np.rint(p[i, 0])), int(np.rint(p[i, 1])), int(np.rint(p[i, 2])))
        bit = 1 << cls[i]
        least = 1 << 30
        for ax in range(3):
            if ax == axis[i]:
                continue
            extent = 0
            for sign in (-1, 1):
                last = 0
                s = 0
                while True:
                    s += 1
                    a, b, c = v0
                    if ax == 0:
                        a += sign * s
                    elif ax == 1:
                        b += sign * s
                    else:
                        c += sign * s
                    if not _in_grid(a, b, c, near.shape):
                        break
                    if near[a, b, c] & bit:
                        last = s
                    elif s - last > SLAB_GAP:
                        break
                extent += last
            least = min(least, extent)
        band[i] = least


@numba.njit(cache=True, parallel=True)
def _carry(p, n, t, free, out, other, facing):
    for i in numba.prange(p.shape[0]):
        steps = int(2 * t[i])
        for k in range(1, steps + 1):
            s = 0.5 * k
            a, b, c = _voxel_at(p, n, i, s)
            if not _in_grid(a, b, c, free.shape) or free[a, b, c]:
                break
            out[a, b, c] = True
            # the part's other side, seen: the slab ends there
            if s >= 1.0 and facing[a, b, c] & other[i]:
                break


@numba.njit(cache=True, parallel=True)
def _march(p, n, opposite, across, bits, free, reach, measure, out, seen):
    for i in numba.prange(p.shape[0]):
        hit = 0
        for s in range(2, reach + 1):
            a, b, c = _voxel_at(p, n, i, s)
            if not _in_grid(a, b, c, bits.shape):
                break
            if free[a, b, c]:
                break
            if bits[a, b, c] & opposite[i]:
                hit = s
                break
        if hit == 0:
            continue
        ok = True
        # half-voxel steps, no free voxel slipping between samples; the two ends lie on the
        # surfaces, where half a voxel may be seen free
        for k in range(2, 2 * hit - 1):
            t = 0.5 * k
            a, b, c = _voxel_at(p, n, i, t)
            if not _in_grid(a, b, c, bits.shape) or free[a, b, c]:
                ok = False
                break
        if ok:
            # a thickness only through one part's inside: not down a leg or along a wall,
            # beside faces turned across the way (a seat's top to a rail below its legs)
            beside = 0
            for s in range(2, hit):
                a, b, c = _voxel_at(p, n, i, s)
                if bits[a, b, c] & across[i]:
                    beside += 1
            if beside <= SLAB_GAP and hit <= measure:
                seen[i] = hit
            for k in range(2 * hit + 1):
                t = 0.5 * k
                a, b, c = _voxel_at(p, n, i, t)
                out[a, b, c] = True


def _diffuse(rgb: np.ndarray, known: np.ndarray, band: np.ndarray) -> np.ndarray:
    """Colours where ``known`` is False: normalised Gaussian of the known colours near them,
    then the nearest known colour (inside and far from the surface).
    """
    if not known.any():
        rgb[...] = 160
        return rgb
    w = known.astype(np.float32)
    flat_known = known.ravel()
    todo = band[~flat_known[band]]

    def blur(c: int) -> np.ndarray:
        # the weights' blur (c = 3), or a channel's weighted; a thread each (ndimage lets go of
        # the GIL), only the band's values kept
        a = w if c == 3 else rgb[..., c].astype(np.float32) * w
        return ndimage.gaussian_filter(a, DIFFUSE_SIGMA, truncate=3.0).ravel()[todo]

    *num, den = _map(blur, range(4), known.size)
    blurred = np.stack(num, axis=1) / np.maximum(den, 1e-12)[:, None]
    reached = den > 1e-4
    flat = rgb.reshape(-1, 3)
    flat[todo[reached]] = np.clip(np.rint(blurred[reached]), 0, 255).astype(np.uint8)
    have = known.copy()
    have.ravel()[todo[reached]] = True
    ind = ndimage.distance_transform_edt(~have, return_distances=False, return_indices=True)
    lin = np.ravel_multi_index(tuple(ind), known.shape)
    return flat[lin.ravel()].reshape(rgb.shape)
