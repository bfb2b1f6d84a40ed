"""Scores of a completion (or any surface) against the complete object: CD-L1, F-score at tau
(precision, recall), colour error, and the uniform surface samples they compare.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from ..csdf import CSDF
from ..surface import sample_linear, to_mesh

F_TAU = 0.01
"""F-score threshold as a fraction of the complete object's bounding-box diagonal."""
SAMPLES_PER_TAU2 = 3.0
"""Samples per ``tau**2`` of surface area that :func:`surface_samples` draws at least when told
the ``tau`` they will be scored at: a point of the surface then lies further than ``tau`` from
every sample with probability ``exp(-3 pi)``, under 0.01 %. A fixed count is too sparse on
objects of much surface: 20 000 samples give a cabinet with shelves and drawers 0.6 a ``tau**2``
at 1 % of its diagonal, and 15 % of its true surface then has no sample within ``tau``."""
MAX_SAMPLES = 4_000_000
"""The most samples :func:`surface_samples` draws (about 100 MB of points)."""


def surface_samples(
    csdf: CSDF, n: int = 20000, *, tau: float | None = None, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) float64 points uniformly on the CSDF's zero surface and their sRGB (n, 3) uint8.

    Parameters
    ----------
    csdf : CSDF
        The surface (its zero level, marching cubes).
    n : int
        How many points (at least, with ``tau``).
    tau : float, optional
        The distance the samples will be scored at (:func:`chamfer_fscore`): at least
        :data:`SAMPLES_PER_TAU2` samples are drawn per ``tau**2`` of the surface's area (up to
        :data:`MAX_SAMPLES`), so that the sampling itself leaves no part of the surface further
        than ``tau`` from every sample.
    seed : int
        Seed of the sampling.

    Returns
    -------
    points : (n, 3) float64
        World coordinates, uniform by area.
    colors : (n, 3) uint8
        The CSDF's sRGB colour at each point.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.evaluate import surface_samples
    >>> points, colors = surface_samples(shapes.box((0, 0, 0), (0.4, 0.2, 0.2), voxel_size=0.02), 1000)
    >>> points.shape, colors.dtype
    ((1000, 3), dtype('uint8'))

    Dense enough to score at 1 % of its diagonal: a surface against itself scores 1.

    >>> from partscale.evaluate import chamfer_fscore, f_tau
    >>> box = shapes.box((0, 0, 0), (0.4, 0.2, 0.2), voxel_size=0.01)
    >>> tau = f_tau(box)
    >>> a, b = surface_samples(box, tau=tau, seed=0)[0], surface_samples(box, tau=tau, seed=1)[0]
    >>> len(a) > 20000, chamfer_fscore(a, b, tau)["fscore"] > 0.999
    (True, True)
    """
    import trimesh

    mesh = to_mesh(csdf)
    if tau is not None:
        n = max(n, min(MAX_SAMPLES, int(np.ceil(SAMPLES_PER_TAU2 * mesh.area / tau**2))))
    pts, _ = trimesh.sample.sample_surface(mesh, n, seed=seed)
    rgb = sample_linear(csdf.rgb, csdf.world_to_index(pts))
    return np.asarray(pts), np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


def exterior(csdf: CSDF) -> CSDF:
    """The CSDF with its sealed cavities made solid: the surface a sensor can see from outside.

    A closed cabinet modelled with its inside (a carcass behind shut doors) has the inside's
    walls for surface too, though no view of the object reaches them: a completion scored
    against them loses recall it could never have. An empty voxel belongs to a sealed cavity
    when no path of face-neighbouring empty voxels joins it to the grid's border; its distance's
    sign is turned (negative: inside), so the cavity's walls are no longer a zero crossing. The
    distances are no longer true distances there; the zero surface is the exterior's.

    Parameters
    ----------
    csdf : CSDF
        The complete object.

    Returns
    -------
    CSDF
        The same grid, ``sdf`` (X, Y, Z) float32 negative in every sealed cavity; ``csdf``
        itself where it has none.

    Examples
    --------
    A box with a sealed hole inside it: the hole's walls are no surface of the exterior.

    >>> import numpy as np
    >>> from partscale import shapes
    >>> from partscale.evaluate import exterior
    >>> box = shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.05)
    >>> hollow = box.replace(sdf=np.maximum(box.sdf, -box.sdf - 0.1))  # walls 0.1 thick
    >>> centre = tuple(n // 2 for n in hollow.shape)
    >>> bool(hollow.sdf[centre] > 0), bool(exterior(hollow).sdf[centre] > 0)
    (True, False)
    """
    empty = csdf.sdf > 0
    label, _ = ndimage.label(empty)  # face-neighbours: a diagonal contact is no opening
    rim = np.concatenate(
        [side.ravel() for a in range(3) for side in (np.take(label, 0, a), np.take(label, -1, a))]
    )
    sealed = empty & ~np.isin(label, np.unique(rim))
    if not sealed.any():
        return csdf
    return csdf.replace(sdf=np.where(sealed, -csdf.sdf, csdf.sdf).astype(np.float32))


def f_tau(csdf: CSDF) -> float:
    """The F-score's distance for scoring against a complete object.

    Parameters
    ----------
    csdf : CSDF
        The complete object (its zero surface).

    Returns
    -------
    float
        :data:`F_TAU` times the diagonal of the zero surface's bounding box (world units): the
        ``tau`` of :func:`chamfer_fscore` and :func:`surface_samples`.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.evaluate import f_tau
    >>> round(f_tau(shapes.box((0, 0, 0), (0.4, 0.2, 0.2), voxel_size=0.02)), 4)
    0.0049
    """
    lo, hi = to_mesh(csdf).bounds
    return F_TAU * float(np.linalg.norm(np.asarray(hi) - np.asarray(lo)))


def chamfer_fscore(pred: np.ndarray, gt: np.ndarray, tau: float) -> dict:
    """CD-L1, precision, recall and F-score at ``tau`` of point set ``pred`` against ``gt``.

    Parameters
    ----------
    pred : (N, 3) float
        The points scored (a completion's :func:`surface_samples`, or a scan's points).
    gt : (M, 3) float
        Points on the true surface.
    tau : float
        Distance (world units) within which a point counts as right (usually :data:`F_TAU`
        times the true object's bounding-box diagonal).

    Returns
    -------
    dict
        ``cd_l1`` (the mean of the two mean nearest-neighbour distances, world units),
        ``precision`` (share of ``pred`` within ``tau`` of ``gt``), ``recall`` (share of ``gt``
        within ``tau`` of ``pred``) and ``fscore`` (their harmonic mean).

    Examples
    --------
    Half of a square's corners found, and nothing wrong:

    >>> import numpy as np
    >>> from partscale.evaluate import chamfer_fscore
    >>> square = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    >>> s = chamfer_fscore(square[:2], square, tau=0.01)
    >>> s["precision"], s["recall"], round(s["fscore"], 3)
    (1.0, 0.5, 0.667)
    """
    d_pg, _ = cKDTree(gt).query(pred, workers=2)
    d_gp, _ = cKDTree(pred).query(gt, workers=2)
    p = float((d_pg <= tau).mean())
    r = float((d_gp <= tau).mean())
    f = 2 * p * r / (p + r) if p + r > 0 else 0.0
    return {
        "cd_l1": float((d_pg.mean() + d_gp.mean()) / 2),
        "precision": p,
        "recall": r,
        "fscore": f,
    }


def colour_error(pred, pred_rgb, gt, gt_rgb, tau: float) -> float:
    """Mean absolute sRGB error of the predicted points within ``tau`` of the truth.

    Parameters
    ----------
    pred, pred_rgb : (N, 3) float, (N, 3) uint8
        The predicted surface points and their sRGB colours.
    gt, gt_rgb : (M, 3) float, (M, 3) uint8
        The true surface points and theirs.
    tau : float
        Distance (world units) within which a predicted point is scored.

    Returns
    -------
    float
        The mean over channels (0..255) against the colour of the nearest true point; NaN when
        no predicted point lies within ``tau``.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.evaluate import colour_error
    >>> P = np.zeros((1, 3))
    >>> colour_error(P, np.array([[100, 100, 100]], np.uint8), P, np.array([[110, 100, 90]], np.uint8), 0.01)
    6.666666666666667
    """
    d, nn = cKDTree(gt).query(pred, workers=2)
    ok = d <= tau
    if not ok.any():
        return float("nan")
    diff = np.abs(pred_rgb[ok].astype(np.int64) - gt_rgb[nn[ok]].astype(np.int64))
    return float(diff.mean())
