"""``segment``: split a CSDF into nearly convex parts and label every voxel with its part."""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path
from .._memory import check_memory
from ..csdf import CSDF
from ..errors import InputError
from ..progress import ProgressCallback, resolve, scaled
from ..surface import to_mesh
from . import coacd_method, fast
from .labels import (
    faces_from_voxels,
    make_connected,
    merge_across_junctions,
    merge_convex,
    merge_planar_groups,
    parts_info,
    voxels_from_faces,
)

METHODS = ("coacd", "fast")
DEFAULT_METHOD = "fast"
"""The fast method: it matched CoACD's quality within the 5 s target on every benchmark object
(figures in :mod:`partscale.segment.fast`)."""
CACHE_VERSION = 7
"""Bump when a change to the code changes results, so old cache entries are not reused."""

_METHOD_PARAMS: dict[str, dict[str, Any]] = {
    "coacd": coacd_method.PARAMS,
    "fast": fast.PARAMS,
}


def default_cache_dir() -> Path:
    """``$PARTSCALE_CACHE/segment`` if set, else ``~/.cache/partscale/segment``."""
    env = os.environ.get("PARTSCALE_CACHE")
    base = Path(env) if env else Path.home() / ".cache" / "partscale"
    return base / "segment"


def cache_key(csdf: CSDF, method: str, params: dict[str, Any]) -> str:
    """sha256 of the grid's content (shape, sdf bytes, voxel size) and the method's parameters."""
    h = hashlib.sha256()
    h.update(f"partscale.segment/{CACHE_VERSION}/{method}".encode())
    h.update(np.asarray(csdf.shape, np.int64).tobytes())
    h.update(np.ascontiguousarray(csdf.sdf).tobytes())
    h.update(np.float64(csdf.voxel_size).tobytes())
    h.update(json.dumps(params, sort_keys=True).encode())
    if method == "coacd":
        coacd = coacd_method.import_coacd()
        h.update(str(getattr(coacd, "__version__", "")).encode())
    return h.hexdigest()


def check_method(method: str, *, what: str = "method") -> str:
    """``method`` if it is one of :data:`METHODS`, else an InputError naming ``what``."""
    if method not in METHODS:
        raise InputError(f"{what}: expected one of {', '.join(METHODS)}, got {method!r}")
    return method


def _check_options(
    method: Any, threshold: Any, max_parts: Any, seed: Any, merge_tolerance: Any, extra: dict
) -> tuple[str, float, int | None, int, float, dict]:
    check_method(method)
    try:
        thr = float(threshold)
    except (TypeError, ValueError):
        raise InputError(f"threshold: expected a number in (0, 1], got {threshold!r}") from None
    if not (0 < thr <= 1):
        raise InputError(f"threshold: expected a number in (0, 1], got {threshold!r}")
    if max_parts is not None:
        if isinstance(max_parts, bool) or not isinstance(max_parts, int | np.integer):
            raise InputError(f"max_parts: expected an integer >= 1 or None, got {max_parts!r}")
        if max_parts < 1:
            raise InputError(f"max_parts: expected an integer >= 1 or None, got {max_parts}")
        max_parts = int(max_parts)
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InputError(f"seed: expected an integer >= 0, got {seed!r}")
    tol = float(merge_tolerance)
    if not (np.isfinite(tol) and tol >= 0):
        raise InputError(f"merge_tolerance: expected a number >= 0 (voxels), got {tol}")
    known = _METHOD_PARAMS[method]
    unknown = sorted(set(extra) - set(known))
    if unknown:
        raise TypeError(
            f"segment() got unknown option(s) {', '.join(map(repr, unknown))} for method "
            f"{method!r}; its options are: {', '.join(known)}"
        )
    check = coacd_method.check_params if method == "coacd" else fast.check_params
    return method, thr, max_parts, int(seed), tol, check(extra)


def segment(
    csdf: CSDF,
    *,
    method: str = DEFAULT_METHOD,
    threshold: float = 0.05,
    max_parts: int | None = None,
    seed: int = 0,
    merge_tolerance: float = 2.0,
    cache: bool = True,
    cache_dir: str | os.PathLike | None = None,
    progress: ProgressCallback | None = None,
    **method_params: Any,
) -> CSDF:
    """Split the object into nearly convex parts and label every voxel with its part.

    Marching cubes of the CSDF (:func:`partscale.surface.to_mesh`), a decomposition of that
    surface by ``method``, then each voxel near or inside the surface takes the part of its
    nearest surface point (voxels more than :data:`partscale.csdf.BAND_VOXELS` voxels outside
    stay -1; the fast method cuts the grid itself, so its inside voxels keep their piece). Parts
    are made 26-connected, touching parts whose union is convex within ``merge_tolerance`` voxels
    are merged, and parts are numbered 0..P-1, largest first.

    Parameters
    ----------
    csdf : CSDF
        The object; its ``sdf`` decides everything, existing ``parts`` are replaced.
    method : {"fast", "coacd"}
        ``"fast"`` (the default): cuts at concave creases of the voxel grid, then convex
        merging; as convex as CoACD's parts on the benchmark objects, about 19x faster (see
        :mod:`partscale.segment.fast`). ``"coacd"``: CoACD on the surface mesh (the
        reference; tens of seconds at 128³).
    threshold : float in (0, 1]
        Concavity allowed in a part, relative to the object's size (CoACD's meaning).
    max_parts : int, optional
        Upper bound on the number of parts (CoACD's ``max_convex_hull``, then the least
        concave merges). Separate pieces are never joined, so an object with more separate
        pieces keeps one part per piece.
    seed : int
        Random seed of the method; the same seed gives the same parts.
    merge_tolerance : float
        Touching parts whose union has at most this concavity (voxels) become one; 0 disables.
    cache : bool
        Reuse (and store) the result for the same grid and parameters.
    cache_dir : path, optional
        Where results are cached; default :func:`default_cache_dir`.
    progress : callable (fraction, message), optional
    **method_params
        The method's own options: for CoACD ``preprocess_mode``, ``preprocess_resolution``,
        ``resolution``, ``mcts_nodes``, ``mcts_iterations``, ``mcts_max_depth``,
        ``max_convex_hull``, ``merge``; for fast see :data:`fast.PARAMS`.

    Returns
    -------
    CSDF
        With ``parts`` (X, Y, Z) int16 filled, ``meta['parts_info']`` (per part: ``index``,
        ``voxels`` labelled, world ``bbox`` [[min], [max]] of its boundary, world
        ``hull_volume``, sRGB ``color``), ``meta['segmentation']`` ({method, params, key})
        and a history entry.
    """
    method, thr, max_parts, seed, tol, params = _check_options(
        method, threshold, max_parts, seed, merge_tolerance, method_params
    )
    if not (csdf.sdf <= 0).any() or not (csdf.sdf > 0).any():
        raise InputError(
            "segment: expected an object with a surface (some sdf <= 0 and some > 0), got none"
        )
    # peak working set: labels and masks, a feature transform (3 int64 per voxel), the mesh
    check_memory(csdf.shape, 64, what="segment")
    report = resolve(progress)
    all_params = {
        "threshold": thr,
        "max_parts": max_parts,
        "seed": seed,
        "merge_tolerance": tol,
        **params,
    }
    key = cache_key(csdf, method, all_params)
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    entry = folder / f"{key}.npz"
    cached = _read_cache(entry, csdf) if cache else None
    if cached is not None:
        labels, info = cached
        report(1.0, "cached")
    else:
        labels, info = _compute(csdf, method, thr, max_parts, seed, tol, params, report)
        if cache:
            _write_cache(entry, csdf, labels, info)
    meta = dict(csdf.meta)
    meta["parts_info"] = info
    meta["segmentation"] = {"method": method, "params": all_params, "key": key}
    op = {"op": "segment", "method": method, **all_params, "parts": len(info)}
    return csdf.with_history(op, parts=labels.astype(np.int16), meta=meta)


def _compute(
    csdf: CSDF,
    method: str,
    thr: float,
    max_parts: int | None,
    seed: int,
    tol: float,
    params: dict,
    report: Callable[[float, str], None],
) -> tuple[np.ndarray, list[dict]]:
    report(0.0, "marching cubes")
    mesh = to_mesh(csdf)
    if method == "coacd":
        p = dict(params)
        if max_parts is not None:
            p["max_convex_hull"] = max_parts
        hulls = coacd_method.run(
            mesh, threshold=thr, seed=seed, params=p, progress=scaled(report, 0.02, 0.85)
        )
        report(0.85, "labelling the surface")
        faces = coacd_method.face_labels(mesh, hulls)
        merge_tol = tol
        atoms = None
    else:
        atoms = fast.atoms(
            csdf, threshold=thr, params=params, floor=tol, progress=scaled(report, 0.0, 0.5)
        )
        report(0.5, "labelling the surface")
        faces = faces_from_voxels(csdf, mesh, atoms)
        merge_tol = max(tol, fast.tolerance(csdf, thr, params))
    report(0.88, "labelling voxels")
    # the fast method cuts the grid itself: inside voxels keep their piece exactly (the
    # nearest surface point would let a piece bleed across a crease into its neighbour)
    labels = make_connected(voxels_from_faces(csdf, mesh, faces, inside=atoms))
    report(0.9, "merging convex neighbours")
    if merge_tol > 0 or max_parts is not None:
        labels = merge_convex(csdf, mesh, labels, tolerance=merge_tol, max_parts=max_parts)
    if atoms is not None and merge_tol > 0:
        labels = merge_across_junctions(csdf, mesh, labels, tolerance=merge_tol)
        group_tol = fast.tolerance(csdf, thr, {**params, "scale": params["group_scale"]})
        labels = merge_planar_groups(
            csdf,
            mesh,
            labels,
            tolerance=max(group_tol, merge_tol),
            thickness=params["thin"],
            min_group=params["min_group"],
        )
    report(0.97, "part facts")
    info = parts_info(csdf, mesh, labels)
    report(1.0, f"{len(info)} parts")
    return labels, info


def _read_cache(entry: Path, csdf: CSDF) -> tuple[np.ndarray, list[dict]] | None:
    """The cached labels and part facts (bboxes moved to this grid's origin), or None."""
    try:
        with open(entry, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            labels = z["parts"]
            info = json.loads(str(z["info"]))
    except (OSError, ValueError, KeyError, EOFError):
        return None  # absent or unreadable: recompute (and overwrite)
    if labels.shape != csdf.shape:
        return None
    for d in info:
        d["bbox"] = (np.asarray(d["bbox"]) + csdf.origin).tolist()
    return labels, info


def _write_cache(entry: Path, csdf: CSDF, labels: np.ndarray, info: list[dict]) -> None:
    # bboxes are stored relative to the origin: the key does not include it
    rel = [
        {**d, "bbox": (np.asarray(d["bbox"]) - csdf.origin).tolist()}
        for d in json.loads(json.dumps(info))
    ]
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(entry, suffix=".npz") as tmp:
            np.savez_compressed(tmp, parts=labels.astype(np.int16), info=np.array(json.dumps(rel)))
    except (OSError, InputError):  # atomic_path reports a refused folder as InputError
        pass  # a read-only or full cache folder must not fail the segmentation
