"""Cross-section profiles of a CSDF's solid along one axis: the signal zones are found in.

Each layer (voxel slice square to the axis) is summarised by its soft occupancy, the fraction of
each voxel inside the solid (``clip(0.5 - sdf / h, 0, 1)``: partial volume across the surface,
so a board edge between two voxel centres gives intermediate values and layers can be compared
at sub-voxel shifts). Layers are compared by a soft Jaccard distance computed for every pair at
once from one Gram matrix, so no per-voxel or per-pair Python loop runs.

A completed scan (:func:`from_scan`) is rough at the scale of its voxels: its surface was carved
from noisy depth and closed where no camera looked, so the layers of a constant board or body
differ by a few percent where a mesh's are equal (a pedal bin's body: median 0.028 between
neighbours, its mesh 0). Its layers are averaged over :data:`SCAN_LAYERS` along the axis before
they are compared, so that noise no longer breaks every constant run apart.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import overload

import numpy as np
from scipy import ndimage

from .._memory import check_bytes
from ..csdf import CSDF
from ..edit import AXES
from ..errors import InputError

#: In-plane downsampling of the cross-sections (voxels per cell): tolerates sub-voxel lateral
#: wobble between repeats (worn or hand-modelled copies) and keeps the Gram matrix small.
CELL = 2
#: Peak working bytes per pair of layers of a profile and the analyses that read it: the two
#: Gram matrices, :func:`partscale.zones.suggest`'s all-pairs distances and its (2N, N) table of
#: shifted distances with their temporaries (measured: 200 bytes a pair on 300 to 600 layers).
PAIR_BYTES = 256
#: Cells across the larger side of a coarse cross-section: the scale of an element's parts
#: (a cushion's crown, a drawer's handle), at which soft or hand-modelled copies that differ by
#: a few voxels of surface still compare equal.
COARSE_CELLS = 16
#: Layers over which a completed scan's cross-sections are averaged (:func:`from_scan`).
#: Eighteen three-view completions of nine objects (a bunk bed, tables, a desk, a sofa, a chair,
#: a bookcase, a side table, a bin) made 120 % along x and along y: ``fit`` found a zone on 16
#: of the 36 axes compared layer by layer as a mesh's (and tiled a false period on 3 more), on
#: 30 with the layers averaged over 5, the drift allowance of the scan
#: (:data:`~partscale.zones.suggest.SCAN_DRIFT`) and no periods unless asked for; the meshes
#: themselves on 34.
SCAN_LAYERS = 5


def from_scan(csdf: CSDF) -> bool:
    """Whether ``csdf`` was completed from a scan (``meta['completion']``, what
    :func:`partscale.complete.complete` writes; its edits keep it).

    Examples
    --------
    >>> from partscale import shapes
    >>> from_scan(shapes.bookcase())
    False
    """
    return "completion" in csdf.meta


@dataclass(frozen=True, eq=False)
class Profile:
    """Cross-sections of a solid along one axis.

    Parameters
    ----------
    axis : int
        0, 1 or 2 (x, y, z).
    coords : (N,) float64
        World coordinate of each layer (voxel centres along the axis).
    area : (N,) float64
        Soft inside area of each layer, in voxels.
    gram : (N, N) float64
        Inner products of the layers' (downsampled) soft occupancies.
    coarse : (N, N) float64
        The same at :data:`COARSE_CELLS` cells across the cross-section (tolerant comparisons).
    lo, hi : float
        The solid's extent along the axis (world units).
    voxel_size : float
        The object's voxel size.
    scan : bool
        Taken from a completed scan (:func:`from_scan`): its layers were averaged over
        :data:`SCAN_LAYERS` and differ by its noise.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> p = zones.profile(bookcase, "y")
    >>> p.coords.shape == p.area.shape == (bookcase.shape[1],)
    True
    """

    axis: int
    coords: np.ndarray
    area: np.ndarray
    gram: np.ndarray
    lo: float
    hi: float
    voxel_size: float
    coarse: np.ndarray | None = None
    scan: bool = False

    @property
    def n(self) -> int:
        """Number of layers."""
        return len(self.coords)

    def distance(self, i: np.ndarray, j: np.ndarray, *, coarse: bool = False) -> np.ndarray:
        """Soft Jaccard distance in [0, 1] between layers ``i`` and ``j`` (broadcast int arrays).

        ``|a - b|^2 / (|a|^2 + |b|^2 - a.b)``: 0 for equal layers (two empty layers too), 1 for
        disjoint ones; for binary layers, the share of their union where only one is solid.
        ``coarse``: compare the coarse cross-sections.
        """
        g = self._gram(coarse)
        gii, gjj, gij = g[i, i], g[j, j], g[i, j]
        union = gii + gjj - gij
        return np.where(union > 1e-9, (gii + gjj - 2 * gij) / np.maximum(union, 1e-9), 0.0)

    def _gram(self, coarse: bool) -> np.ndarray:
        return self.coarse if coarse and self.coarse is not None else self.gram

    def shifted_distance(
        self, i: np.ndarray, shift: float | np.ndarray, *, coarse: bool = False
    ) -> np.ndarray:
        """Distance between layer ``i`` and the layer ``shift`` (fractional, broadcast with
        ``i``) voxels beyond it.

        The shifted layer is the linear interpolation of its two neighbours; every term comes
        from the Gram matrix. Layers beyond the grid count as empty.
        """
        i = np.asarray(i, dtype=np.int64)
        shift = np.asarray(shift, dtype=np.float64)
        k = np.floor(shift).astype(np.int64)
        f = shift - k
        n = self.n
        j0, j1 = i + k, i + k + 1
        v0, v1 = (j0 >= 0) & (j0 < n), (j1 >= 0) & (j1 < n)
        j0c, j1c = np.clip(j0, 0, n - 1), np.clip(j1, 0, n - 1)
        w0 = np.where(v0, 1.0 - f, 0.0)
        w1 = np.where(v1, f, 0.0)
        g = self._gram(coarse)
        aa = g[i, i]
        bb = w0 * w0 * g[j0c, j0c] + w1 * w1 * g[j1c, j1c] + 2 * w0 * w1 * g[j0c, j1c]
        ab = w0 * g[i, j0c] + w1 * g[i, j1c]
        union = aa + bb - ab
        return np.where(union > 1e-9, (aa + bb - 2 * ab) / np.maximum(union, 1e-9), 0.0)

    @overload
    def index(self, x: float) -> float: ...
    @overload
    def index(self, x: np.ndarray) -> np.ndarray: ...
    def index(self, x: float | np.ndarray) -> float | np.ndarray:
        """Continuous layer index of world coordinate(s) ``x``."""
        return (np.asarray(x, dtype=np.float64) - self.coords[0]) / self.voxel_size

    @overload
    def world(self, i: float) -> float: ...
    @overload
    def world(self, i: np.ndarray) -> np.ndarray: ...
    def world(self, i: float | np.ndarray) -> float | np.ndarray:
        """World coordinate of continuous layer index(es) ``i``."""
        return self.coords[0] + np.asarray(i, dtype=np.float64) * self.voxel_size


def _axis_index(axis: str | int) -> int:
    """``'x'``, ``'y'``, ``'z'`` (any case) or 0, 1, 2 as 0, 1, 2; else an InputError."""
    if isinstance(axis, str) and axis.lower() in AXES:
        return AXES.index(axis.lower())
    if isinstance(axis, int | np.integer) and not isinstance(axis, bool) and 0 <= axis < 3:
        return int(axis)
    raise InputError(f"axis: expected one of x, y, z, got {axis!r}")


def profile(csdf: CSDF, axis: str | int) -> Profile:
    """The cross-section :class:`Profile` of ``csdf``'s solid along ``axis``.

    Cost: one pass over the grid and two (N, N) Gram matrices of the downsampled layers; the
    analyses that read them hold a few more (N, N) tables, so memory grows with the square of
    the layers along the axis. Refused (:class:`~partscale.errors.MemoryLimitError`, before any
    work) where :data:`PAIR_BYTES` per pair would not fit in the memory available.

    Parameters
    ----------
    csdf : CSDF
        The object.
    axis : {'x', 'y', 'z'} or {0, 1, 2}
        The axis.

    Returns
    -------
    Profile
        One layer per voxel along the axis.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> p = zones.profile(bookcase, "y")
    >>> p.axis, p.gram.shape
    (1, (67, 67))
    """
    axis = _axis_index(axis)
    n_layers = int(csdf.shape[axis])
    check_bytes(
        float(n_layers) ** 2 * PAIR_BYTES,
        what=f"the cross-sections along {AXES[axis]} ({n_layers} layers, compared pairwise)",
    )
    h = csdf.voxel_size
    occ = np.clip(0.5 - csdf.sdf / np.float32(h), 0.0, 1.0)
    occ = np.moveaxis(occ, axis, 0)
    if from_scan(csdf):
        # the scan's voxel-scale roughness averaged out along the axis (its slabs' drift is
        # judged against its noise too: suggest.drift_limit)
        occ = ndimage.uniform_filter1d(occ, SCAN_LAYERS, axis=0, mode="constant")
    n, a, b = occ.shape
    pa, pb = -a % CELL, -b % CELL
    if pa or pb:
        occ = np.pad(occ, ((0, 0), (0, pa), (0, pb)))
    cells = occ.reshape(n, (a + pa) // CELL, CELL, (b + pb) // CELL, CELL).mean(axis=(2, 4))
    flat = cells.reshape(n, -1).astype(np.float32)
    gram = (flat @ flat.T).astype(np.float64)
    # coarse cells: whole CELL cells pooled again (a, b are at most a few hundred)
    k = max(1, -(-max(cells.shape[1:]) // COARSE_CELLS))
    ca, cb = -cells.shape[1] % k, -cells.shape[2] % k
    big = np.pad(cells, ((0, 0), (0, ca), (0, cb))) if ca or cb else cells
    big = big.reshape(n, big.shape[1] // k, k, big.shape[2] // k, k).mean(axis=(2, 4))
    big = big.reshape(n, -1).astype(np.float32)
    coarse = (big @ big.T).astype(np.float64)
    area = occ.sum(axis=(1, 2), dtype=np.float64)
    sb = csdf.surface_bounds()
    return Profile(
        axis=int(axis),
        coords=csdf.axis_coords(axis),
        area=area,
        gram=gram,
        lo=float(sb[0, axis]),
        hi=float(sb[1, axis]),
        voxel_size=float(h),
        coarse=coarse,
        scan=from_scan(csdf),
    )


# -- calm runs: where constant slabs and local features are found --------------------------

#: Calm layers: neighbouring cross-sections closer than this (:meth:`Profile.distance`).
STEP = 0.02
#: Shortest constant slab reported, voxels.
MIN_SLAB = 3


def _runs(mask: np.ndarray) -> np.ndarray:
    """(R, 2) int64 ``[first, last]`` of the runs of True in a 1D boolean array."""
    m = np.concatenate([[False], mask, [False]])
    d = np.diff(m.astype(np.int8))
    return np.stack([np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1], axis=1)


def _solid_layers(p: Profile) -> tuple[int, int]:
    i0 = max(0, int(np.ceil(p.index(p.lo) - 0.5)))
    i1 = min(p.n - 1, int(np.floor(p.index(p.hi) + 0.5)))
    return i0, i1


def calm_runs(p: Profile) -> list[tuple[int, int]]:
    """The maximal runs of calm layers of a profile: where constant slabs and local features are found.

    A run is at least :data:`MIN_SLAB` non-empty layers whose neighbour-to-neighbour distance stays
    below :data:`STEP`.

    Parameters
    ----------
    p : Profile
        The cross-sections along an axis.

    Returns
    -------
    list of (int, int)
        ``(first, last)`` layer indices (inclusive) of each run, in order.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> zones.calm_runs(zones.profile(bookcase, "y"))[:3]
    [(5, 17), (20, 32), (34, 46)]
    """
    i0, i1 = _solid_layers(p)
    idx = np.arange(i0, i1)
    step = p.distance(idx, idx + 1)
    calm = (step < STEP) & (p.area[idx] > 0) & (p.area[idx + 1] > 0)
    runs = [(int(idx[a]), int(idx[b]) + 1) for a, b in _runs(calm)]
    return [(a, b) for a, b in runs if b - a + 1 >= MIN_SLAB]
