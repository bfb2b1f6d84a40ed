"""Scores of a completion against the complete object: CD-L1, F-score at tau, colour error."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..csdf import CSDF
from ..surface import sample_linear, to_mesh

F_TAU = 0.01
"""F-score threshold as a fraction of the complete object's bounding-box diagonal."""


def surface_samples(csdf: CSDF, n: int = 20000, *, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) float64 points uniformly on the CSDF's zero surface and their sRGB (n, 3) uint8."""
    import trimesh

    mesh = to_mesh(csdf)
    pts, _ = trimesh.sample.sample_surface(mesh, n, seed=seed)
    rgb = sample_linear(csdf.rgb, csdf.world_to_index(pts))
    return np.asarray(pts), np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


def chamfer_fscore(pred: np.ndarray, gt: np.ndarray, tau: float) -> dict:
    """CD-L1 (mean of the two mean nearest-neighbour distances, world units), precision, recall
    and F-score at ``tau`` of point sets ``pred`` (N, 3) and ``gt`` (M, 3).
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
    """Mean absolute sRGB error (0..255, over channels) of the predicted surface points within
    ``tau`` of the truth, against the colour of the nearest true surface point.
    """
    d, nn = cKDTree(gt).query(pred, workers=2)
    ok = d <= tau
    if not ok.any():
        return float("nan")
    diff = np.abs(pred_rgb[ok].astype(np.int64) - gt_rgb[nn[ok]].astype(np.int64))
    return float(diff.mean())
