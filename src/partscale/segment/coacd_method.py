"""CoACD (approximate convex decomposition, Wei et al. 2022) on the marching-cubes mesh.

CoACD returns convex hulls, not a labelling of the input: each surface face is given to the hull
that contains it most deeply, or the nearest one when it lies outside all of them.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from .._options import count
from ..errors import InputError
from ..progress import ProgressCallback

PARAMS: dict[str, Any] = {
    "max_convex_hull": -1,
    "preprocess_mode": "auto",
    "preprocess_resolution": 50,
    "resolution": 2000,
    "mcts_nodes": 20,
    "mcts_iterations": 150,
    "mcts_max_depth": 3,
    "merge": True,
}
"""CoACD's own parameters and defaults (besides threshold and seed), exposed as options."""

PREPROCESS_MODES = ("auto", "on", "off")


def check_params(params: dict) -> dict:
    """Validate CoACD options; returns them with defaults filled in."""
    out = dict(PARAMS)
    out.update(params)
    if out["preprocess_mode"] not in PREPROCESS_MODES:
        raise InputError(
            f"preprocess_mode: expected one of {', '.join(PREPROCESS_MODES)}, "
            f"got {out['preprocess_mode']!r}"
        )
    for name in (
        "preprocess_resolution",
        "resolution",
        "mcts_nodes",
        "mcts_iterations",
        "mcts_max_depth",
    ):
        out[name] = count(out[name], name)
    out["max_convex_hull"] = int(out["max_convex_hull"])
    out["merge"] = bool(out["merge"])
    return out


def run(
    mesh,
    *,
    threshold: float,
    seed: int,
    params: dict,
    progress: ProgressCallback,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Run CoACD on a watertight mesh; returns its hulls as (vertices (V, 3), faces (F, 3)).

    CoACD has no progress hook: it runs in a worker thread (ctypes releases the GIL) while this
    thread reports the elapsed time.
    """
    coacd = import_coacd()
    coacd.set_log_level("error")
    cmesh = coacd.Mesh(np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int32))
    result: dict = {}

    def work() -> None:
        try:
            result["hulls"] = coacd.run_coacd(cmesh, threshold=threshold, seed=seed, **params)
        except BaseException as exc:  # re-raised in the caller's thread
            result["error"] = exc

    worker = threading.Thread(target=work, name="coacd", daemon=True)
    t0 = time.monotonic()
    worker.start()
    while worker.is_alive():
        worker.join(0.25)
        elapsed = time.monotonic() - t0
        # CoACD takes ~1-120 s: an asymptotic bar that never claims to be finished
        progress(elapsed / (elapsed + 30.0), f"CoACD decomposition ({elapsed:.0f} s)")
    if "error" in result:
        raise result["error"]
    return [(np.asarray(v, np.float64), np.asarray(f, np.int64)) for v, f in result["hulls"]]


def face_labels(mesh, hulls: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """(F,) int32: for each face of ``mesh``, the hull containing its centroid most deeply.

    The signed "depth" of a point in a convex hull is its largest facet-plane distance (negative
    inside, and a lower bound of the true distance outside), so the arg-min picks the hull that
    contains the point, or the nearest one.
    """
    centres = np.asarray(mesh.triangles_center, np.float64)
    best = np.full(len(centres), np.inf)
    label = np.zeros(len(centres), np.int32)
    for h, (verts, _faces) in enumerate(hulls):
        try:
            eq = ConvexHull(verts).equations
        except (QhullError, ValueError):
            continue  # a flat hull holds no volume: its faces go to a neighbour
        step = max(1, 4_000_000 // len(eq))
        for s in range(0, len(centres), step):
            d = (centres[s : s + step] @ eq[:, :3].T + eq[:, 3]).max(axis=1)
            better = d < best[s : s + step]
            best[s : s + step][better] = d[better]
            label[s : s + step][better] = h
    return label


def import_coacd():
    """The ``coacd`` module, or a one-line error saying how to get it (or to use the fast method)."""
    try:
        import coacd
    except ImportError as exc:
        raise InputError(
            f"method 'coacd': expected the coacd package (pip install coacd), got {exc}; "
            "or use the fast method"
        ) from None
    return coacd
