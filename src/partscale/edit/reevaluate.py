"""Re-evaluation: turn an edited (resampled) field back into true distances near its surface.

A resampled SDF is no longer a distance: along the edit axis it is scaled by the stretch factor,
and near the zone's planes the nearest surface may now be elsewhere. :func:`reevaluate` recomputes,
for chosen voxels, the distance to the field's own zero level set as the grid represents it (the
piecewise-linear surface through its zero crossings; at sharp edges and corners up to about 0.9
voxel from the true object's, see :mod:`partscale.edit`):

1. the zero level set near those voxels is extracted with sub-voxel precision (marching cubes of
   the field in a box around them, :mod:`partscale._marching`: vertices are the linear zero
   crossings along grid edges, written straight into the triangle table, without the GIL);
2. every voxel of the band in that box gets its nearest triangle by *closest-triangle propagation*
   (a numba kernel): triangles seed the eight corners of their cell, then two raster sweeps, one
   forward and one back, let each voxel test the nearest triangles of its 18 face and edge
   neighbours (exact point-triangle distances, after a lower bound); a voxel the seeds put
   within one voxel of a triangle is already exact and is not visited;
3. the chosen voxels take that distance with the sign of the field (the surface is not moved:
   linear zero crossings of the old and new values coincide where the surface is locally flat),
   the colour at their nearest surface point (trilinear in ``rgb``) and that point's part (the
   label of the nearest inside voxel of its cell: the solid carries the parts).

After an edit, :func:`~partscale.edit._recompute.recompute_mask` (planar edits) or
:func:`~partscale.edit._warp_kernels.reevaluation_mask` (warps) picks the voxels whose distance
could have changed (the paper's rule, less those provably unchanged); only those are recomputed.

This module cuts the work into boxes and runs them side by side; the kernels live by concern:
:mod:`~partscale.edit._boxes` (a box's targets, relays and field), :mod:`~partscale.edit._propagate`
(step 2) and :mod:`~partscale.edit._values` (step 3 and the writes). Units inside the kernels are
voxels (continuous indices); results are scaled by ``voxel_size``.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from .._marching import march
from .._options import keyword_options
from .._workers import thread_map
from ..csdf import BAND_VOXELS, CSDF
from ..errors import InputError
from ..progress import ProgressCallback, resolve
from ._boxes import box_copy, box_targets, layer_targets, relays, target_layers
from ._propagate import complete_table, propagate
from ._values import box_values, write

#: A cluster of target layers longer than this is re-evaluated in pieces of at most this many
#: layers (a box each, solved side by side), cut where only the layer count says: the same
#: pieces, and results, on any machine. A piece's box reaches ``pad`` layers into its
#: neighbours (every surface point within the band of its targets, and the relays near them);
#: the sweeps start afresh in each box, so values differ slightly from one box's, no less exact
#: (see ``test_reevaluate``). Each cut adds ~2 ``pad`` layers of work: on the cabinet shrink
#: at 128 (104 layers, two pieces) 12 % more voxel visits, each piece on its own core.
_PIECE_LAYERS = 64


def reevaluate_arrays(
    sdf: np.ndarray,
    rgb: np.ndarray,
    parts: np.ndarray,
    voxel_size: float,
    mask: np.ndarray,
    *,
    band: float = BAND_VOXELS,
    npass: int = 2,
    row0: int = 0,
    far: float | None = None,
) -> int:
    """Recompute ``sdf``, ``rgb``, ``parts`` in place at ``mask`` voxels within ``band`` voxels.

    Parameters
    ----------
    sdf : (X, Y, Z) float32, writeable
        Field whose zero level set is the surface; its sign is kept.
    rgb : (X, Y, Z, 3) uint8, writeable
    parts : (X, Y, Z) int16, writeable
    voxel_size : float
    mask : (M, Y, Z) bool or uint8
        Voxels to recompute, of layers ``row0 ... row0 + M - 1`` (all layers beyond hold none);
        those with ``|sdf| > band`` voxels are left as they are. As uint8, code 2 marks voxels
        whose current |sdf| is known to be an upper bound of the distance: they keep it (and
        their colour and part) where it is smaller than the recomputed one.
    band : float
        Half-width of the band, in voxels.
    row0 : int
        First layer (along axis 0) ``mask`` covers.
    far : float, optional
        Recomputed voxels whose distance or part changed and whose new distance exceeds ``far``
        (outside, beyond the labelled band) get part -1.

    Returns
    -------
    int
        Number of voxels recomputed.
    """
    h = float(voxel_size)
    lim = band * h
    mask = np.asarray(mask)
    capping = mask.dtype == np.uint8
    if mask.dtype == bool:
        mask = mask.view(np.uint8)
    # only the layers the mask covers are read: the edit's slab and band, not the whole grid;
    # one pass gives each layer's count of targets and their bounds across it (float32
    # threshold: the comparison numpy makes of the float32 field with a Python float)
    count, bounds = target_layers(sdf, mask, row0, np.float32(lim))
    layers = np.flatnonzero(count) + row0
    if layers.size == 0:
        return 0
    # a target's nearest surface point lies within the band, in a cell whose corners lie within
    # ceil(band) + 1 layers: the box holds them (and relays within ceil(band) of a target read
    # the seeds at those corners)
    pad = int(np.ceil(band)) + 1
    # Targets cluster at the zone's planes and the tile seams: one box per cluster of layers
    # (along axis 0) instead of one box spanning them all. Every box reads the unchanged field;
    # all writes happen at the end, so the result does not depend on the order of the boxes.
    breaks = np.flatnonzero(np.diff(layers) > 2 * pad + 1)
    runs = _pieces(np.split(layers, breaks + 1))

    far32 = np.float32(far or 0.0)
    use_far = far is not None

    def solve(run: np.ndarray):
        # the box around the run's targets that holds every surface point within the band
        # of them (it holds no other cluster's targets: clusters are > 2 pad layers apart;
        # a piece's box holds the neighbouring pieces' targets of its ``pad`` outer layers)
        b = bounds[run - row0]
        lo = [max(int(run[0]) - pad, 0)] + [max(int(b[:, 2 * a].min()) - pad, 0) for a in (0, 1)]
        hi = [min(int(run[-1]) + pad + 1, sdf.shape[0])] + [
            min(int(b[:, 2 * a + 1].max()) + pad + 1, sdf.shape[a + 1]) for a in (0, 1)
        ]
        got = _solve_box(sdf, mask, row0, lo, hi, (int(run[0]), int(run[-1])), h, lim, pad, npass)
        if got is None:
            return None
        lo_a = np.asarray(lo, np.int64)
        # colours and parts are read here, from the unchanged arrays, in this thread
        args = (sdf, rgb, parts, mask, row0, capping, *got, lo_a, h, use_far, far32)
        out = box_values(*args)
        return out if out[0].shape[0] else None

    # boxes are independent (each reads the unchanged field; all writes come after) and their
    # kernels release the GIL: they are solved side by side (the pieces
    # depend on the layers only, never on the number of threads, so neither do the results)
    found = [got for got in thread_map(solve, runs) if got is not None]
    if not found:
        return 0
    # each box writes its own layers' voxels (no two boxes share one): side by side too
    thread_map(lambda got: write(sdf, rgb, parts, *got), found)
    return sum(f[0].shape[0] for f in found)


def _pieces(runs: list[np.ndarray]) -> list[np.ndarray]:
    """``runs`` (ascending layer indices), those spanning more than :data:`_PIECE_LAYERS`
    layers cut into equal spans of at most that many (empty spans dropped).
    """
    out: list[np.ndarray] = []
    for run in runs:
        span = int(run[-1]) - int(run[0]) + 1
        n = -(-span // _PIECE_LAYERS)
        cuts = int(run[0]) + (np.arange(1, n) * span) // n
        out.extend(p for p in np.split(run, np.searchsorted(run, cuts)) if p.size)
    return out


def _solve_box(sdf, mask, row0, lo, hi, own, h, lim, pad, npass):
    """Nearest triangles of the targets of layers ``own[0] ... own[1]`` in box ``lo ... hi - 1``
    of ``sdf``: the zero level set's.

    Targets: voxels of ``mask`` (uint8, layers ``row0 ...``) with ``|sdf| <= lim``; all
    targets of the box gather relays, only those of the ``own`` layers are solved. Returns
    ``(sub, tri, best_d2, best_t, best_vw, wanted)`` (the box's field, its triangle table,
    squared distances, triangles and closest points' barycentrics per flat index, the solved
    targets' flat indices; see
    :func:`~partscale.edit._values.box_values`) or None.
    """
    # numpy's copies, fills and searches hold the GIL: kernels here, so boxes solved side by
    # side never wait on each other
    sub = box_copy(sdf, np.asarray(lo, np.int64), np.asarray(hi, np.int64))
    if min(sub.shape) < 2:
        return None
    tri = march(sub, width=17)  # none where the box holds no sign change
    if tri.shape[0] == 0:
        return None
    complete_table(tri)
    # band voxels near the targets relay nearest triangles; a voxel farther than the band from
    # every target cannot be on a target's path, nor one beyond the band (a target's path to
    # its nearest surface runs through voxels nearer that surface: half a voxel of slack there
    # cost 4 % of the propagation and changed one voxel of the suite's 22 edits' bands, by
    # 0.006 voxel)
    t_box = box_targets(sdf, mask, row0, np.float32(lim), np.asarray(lo, np.int64), sub.shape)
    order = relays(sub, t_box, pad - 1, np.float32(lim))
    wanted = layer_targets(t_box, own[0] - lo[0], own[1] + 1 - lo[0])
    if wanted.size == 0:
        return None
    shape = np.array(sub.shape, np.int64)
    best_d2, best_t, best_vw = propagate(tri, order, shape, npass, wanted[0], wanted[-1])
    return sub, tri, best_d2, best_t, best_vw, wanted


@keyword_options
def reevaluate(
    csdf: CSDF,
    mask: np.ndarray | None = None,
    *,
    band: float = BAND_VOXELS,
    progress: ProgressCallback | None = None,
) -> CSDF:
    """Distances, colours and parts at ``mask`` voxels within the band of ``csdf``'s surface.

    Parameters
    ----------
    csdf : CSDF
        Any field whose zero level set is the surface (e.g. a naive resampling).
    mask : (X, Y, Z) bool, optional
        Voxels to recompute (integers: nonzero); all voxels of the band when omitted.
    band : float
        Half-width of the band, in voxels (default :data:`BAND_VOXELS`); finite and > 0.

    Raises
    ------
    InputError
        A mask of another shape or neither bool nor integer; a band that is not a finite
        positive number.

    Returns
    -------
    CSDF
        Same grid; recomputed voxels hold the distance to the (unmoved) zero level set's
        piecewise-linear surface (see the module docstring), with the field's sign, and the
        colour and part of their nearest surface point.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import naive_edit, reevaluate
    >>> stretched = naive_edit(bar, {"axis": "x", "zone": [0.3, 0.6], "to": 0.8})
    >>> reevaluate(stretched).shape == stretched.shape
    True
    """
    if (
        isinstance(band, bool | np.bool_)
        or not isinstance(band, numbers.Real)
        or not (math.isfinite(band) and band > 0)
    ):
        raise InputError(f"band: expected a finite positive number of voxels, got {band!r}")
    if mask is None:
        mask = np.ones(csdf.shape, bool)
    else:
        got = np.asarray(mask)
        if got.shape != csdf.shape or not (got.dtype == bool or got.dtype.kind in "iu"):
            desc = f"shape {got.shape} {got.dtype}" if got.ndim else repr(mask)
            raise InputError(f"mask: expected a {csdf.shape} bool array, got {desc}")
        mask = got.astype(bool)
    band = float(band)
    report = resolve(progress)
    report(0.0, "re-evaluating distances")
    sdf = np.array(csdf.sdf)
    rgb = np.array(csdf.rgb)
    parts = np.array(csdf.parts)
    reevaluate_arrays(sdf, rgb, parts, csdf.voxel_size, mask, band=band)
    report(1.0, "re-evaluated")
    return csdf.replace(sdf=sdf, rgb=rgb, parts=parts)
