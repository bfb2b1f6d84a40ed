"""``segment``: split a CSDF into nearly convex parts and label every voxel with its part."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path, parse_json
from .._memory import check_memory
from .._options import count
from ..csdf import CSDF
from ..errors import InputError, PartscaleWarning, one_line
from ..progress import ProgressCallback, resolve, scaled
from ..surface import to_mesh
from . import coacd_method, fast, relief
from .labels import (
    faces_from_voxels,
    join_specks,
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
CACHE_VERSION = 8
"""Bump when a change to the code changes results, so old cache entries are not reused."""
CACHE_MAX_BYTES = 1 << 30
"""Default size cap of the segment cache; the least recently used entries go first."""

_METHOD_PARAMS: dict[str, dict[str, Any]] = {
    "coacd": coacd_method.PARAMS,
    "fast": fast.PARAMS,
}


def default_cache_dir() -> Path:
    """Folder where :func:`segment` caches its results.

    Returns
    -------
    pathlib.Path
        ``$PARTSCALE_CACHE/segment`` if that variable is set, else ``~/.cache/partscale/segment``.

    Examples
    --------
    >>> import os
    >>> from partscale import segment
    >>> os.environ["PARTSCALE_CACHE"] = "cache"
    >>> segment.default_cache_dir()
    PosixPath('cache/segment')
    """
    env = os.environ.get("PARTSCALE_CACHE")
    base = Path(env) if env else Path.home() / ".cache" / "partscale"
    return base / "segment"


def cache_key(csdf: CSDF, method: str, params: dict[str, Any]) -> str:
    """Cache key of a segmentation: sha256 of the grid's content and the method's parameters.

    The grid's content is its shape, ``sdf`` bytes and voxel size (not its origin, colour or
    parts); CoACD's version is included for ``method="coacd"``.

    Parameters
    ----------
    csdf : CSDF
        The object to segment.
    method : str
        One of :data:`METHODS`.
    params : dict
        Every option of the run (JSON-serialisable), as :func:`segment` records them.

    Returns
    -------
    str
        64 hexadecimal digits.

    Examples
    --------
    >>> from partscale import segment, shapes
    >>> b = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1)
    >>> key = segment.cache_key(b, "fast", {"threshold": 0.05})
    >>> len(key), key == segment.cache_key(b, "fast", {"threshold": 0.1})
    (64, False)
    """
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
    """Check a segmentation method's name.

    Parameters
    ----------
    method : str
        The name given.
    what : str
        What to call it in the error (an option's name).

    Returns
    -------
    str
        ``method``, when it is one of :data:`METHODS`.

    Raises
    ------
    partscale.errors.InputError
        Otherwise, naming ``what``, the methods and what was given.

    Examples
    --------
    >>> from partscale import segment
    >>> segment.check_method("fast")
    'fast'
    >>> segment.check_method("vhacd")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: method: expected one of coacd, fast, got 'vhacd'
    """
    if method not in METHODS:
        raise InputError(f"{what}: expected one of {', '.join(METHODS)}, got {method!r}")
    return method


def _check_options(
    method: Any,
    threshold: Any,
    max_parts: Any,
    seed: Any,
    merge_tolerance: Any,
    noise: Any,
    extra: dict,
) -> tuple[str, float, int | None, int, float, float | None, dict]:
    check_method(method)
    try:
        thr = float(threshold)
    except (TypeError, ValueError):
        raise InputError(f"threshold: expected a number in (0, 1], got {threshold!r}") from None
    if not (0 < thr <= 1):
        raise InputError(f"threshold: expected a number in (0, 1], got {threshold!r}")
    if max_parts is not None:
        max_parts = count(max_parts, "max_parts (or None)")
    seed = count(seed, "seed", lo=0)
    tol = float(merge_tolerance)
    if not (np.isfinite(tol) and tol >= 0):
        raise InputError(f"merge_tolerance: expected a number >= 0 (voxels), got {tol}")
    if noise is not None:
        try:
            noise = float(noise)
        except (TypeError, ValueError):
            raise InputError(
                f"noise: expected a number >= 0 (voxels) or None, got {noise!r}"
            ) from None
        if not (np.isfinite(noise) and noise >= 0):
            raise InputError(f"noise: expected a number >= 0 (voxels) or None, got {noise}")
    known = _METHOD_PARAMS[method]
    unknown = sorted(set(extra) - set(known))
    if unknown:
        raise TypeError(
            f"segment() got unknown option(s) {', '.join(map(repr, unknown))} for method "
            f"{method!r}; its options are: {', '.join(known)}"
        )
    check = coacd_method.check_params if method == "coacd" else fast.check_params
    return method, thr, max_parts, seed, tol, noise, check(extra)


def segment(
    csdf: CSDF,
    *,
    method: str = DEFAULT_METHOD,
    threshold: float = 0.05,
    max_parts: int | None = None,
    seed: int = 0,
    merge_tolerance: float = 2.0,
    noise: float | None = None,
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
    noise : float, optional
        The surface's relief RMS in voxels (:func:`partscale.segment.relief.surface_relief`);
        None measures it. A rough surface (a completed scan's) adds its peak-to-valley to every
        concavity a hull measures, so beyond clean geometry's relief the tolerances grow by
        :func:`~partscale.segment.relief.noise_tolerance`, and parts with fewer than the
        method's ``min_voxels`` inside voxels (specks of relief, not parts) join the neighbour
        they touch most. 0 treats the surface as clean. Recorded in the history entry
        (``relief``, ``noise_added``, ``specks``).
    cache : bool
        Reuse (and store) the result for the same grid and parameters. Entries carry a
        checksum; a damaged or inconsistent entry is discarded and recomputed (with a
        :class:`partscale.errors.PartscaleWarning`). The folder is kept under
        :func:`cache_limit` bytes, least recently used entries removed first.
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
        ``hull_volume``, sRGB ``color``), ``meta['segmentation']`` ({method, params, key, relief, noise_added, specks})
        and a history entry.

    Examples
    --------
    Two bars a gap apart are two parts; the table shipped with partscale splits into its top,
    legs and rails:

    >>> from partscale import data, ingest, segment, shapes
    >>> row, _ = shapes.bars(2, width=0.2, gap=0.1, height=0.5, depth=0.3, voxel_size=0.05)
    >>> segment.segment(row).n_parts
    2
    >>> table = segment.segment(ingest.load(data.table(), res=64))
    >>> table.n_parts, table.parts.dtype, sorted(table.meta["parts_info"][0])
    (8, dtype('int16'), ['bbox', 'color', 'hull_volume', 'index', 'voxels'])
    """
    method, thr, max_parts, seed, tol, noise, params = _check_options(
        method, threshold, max_parts, seed, merge_tolerance, noise, method_params
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
        "noise": noise,
        **params,
    }
    key = cache_key(csdf, method, all_params)
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    entry = folder / f"{key}.npz"
    cached = _read_cache(entry, csdf) if cache else None
    if cached is not None:
        labels, info, rough = cached
        report(1.0, "cached")
    else:
        labels, info, rough = _compute(
            csdf, method, thr, max_parts, seed, tol, noise, params, report
        )
        if cache:
            _write_cache(entry, csdf, labels, info, rough)
    meta = dict(csdf.meta)
    meta["parts_info"] = info
    meta["segmentation"] = {"method": method, "params": all_params, "key": key, **rough}
    op = {"op": "segment", "method": method, **all_params, **rough, "parts": len(info)}
    return csdf.with_history(op, parts=labels.astype(np.int16), meta=meta)


def describe_noise(entry: dict) -> list[str]:
    """What :func:`segment` changed for a rough surface, said for the user.

    Parameters
    ----------
    entry : dict
        :func:`segment`'s history entry (``relief``, ``noise``, ``noise_added``, ``specks``).

    Returns
    -------
    list of str
        One line when the tolerances were raised for a rough surface; none when the surface was
        taken as clean.

    Examples
    --------
    >>> from partscale import segment
    >>> segment.describe_noise({"relief": 0.05, "noise_added": 0.0})
    []
    >>> segment.describe_noise({"relief": 0.25, "noise_added": 3.2, "specks": 2})
    ["the surface is rough (measured relief 0.25 voxel RMS, a scan's noise): concavity
    tolerances raised by 3.2 voxels; 2 specks of relief joined to the part they touch most
    (--noise 0 segments it as if smooth)"]
    """
    added = float(entry.get("noise_added") or 0.0)
    if added <= 0:
        return []
    specks = int(entry.get("specks") or 0)
    joined = (
        f"; {specks} speck{'s' if specks != 1 else ''} of relief joined to the part "
        f"{'they touch' if specks != 1 else 'it touches'} most"
        if specks
        else ""
    )
    relief = float(entry["relief"])
    why = (
        f"relief {relief:.2f} voxel RMS, as given"
        if entry.get("noise") is not None
        else f"measured relief {relief:.2f} voxel RMS, a scan's noise"
    )
    return [
        f"the surface is rough ({why}): concavity tolerances raised by {added:.1f} "
        f"voxels{joined} (--noise 0 segments it as if smooth)"
    ]


def _compute(
    csdf: CSDF,
    method: str,
    thr: float,
    max_parts: int | None,
    seed: int,
    tol: float,
    noise: float | None,
    params: dict,
    report: Callable[[float, str], None],
) -> tuple[np.ndarray, list[dict], dict]:
    report(0.0, "marching cubes")
    mesh = to_mesh(csdf)
    if noise is None:
        noise = relief.surface_relief(mesh.vertices, mesh.vertex_normals, csdf.voxel_size)
    added = relief.noise_tolerance(noise)
    if method == "coacd":
        p = dict(params)
        if max_parts is not None:
            p["max_convex_hull"] = max_parts
        # CoACD reads its threshold on the mesh scaled to [-1, 1]: half the largest extent
        extent = float(np.ptp(mesh.vertices, axis=0).max()) / csdf.voxel_size
        hulls = coacd_method.run(
            mesh,
            threshold=min(thr + added / (0.5 * extent), 1.0),
            seed=seed,
            params=p,
            progress=scaled(report, 0.02, 0.85),
        )
        report(0.85, "labelling the surface")
        faces = coacd_method.face_labels(mesh, hulls)
        merge_tol = tol + added
        atoms = None
    else:
        atoms = fast.atoms(
            csdf,
            threshold=thr,
            params=params,
            floor=tol,
            noise=added,
            progress=scaled(report, 0.0, 0.5),
        )
        report(0.5, "labelling the surface")
        faces = faces_from_voxels(csdf, mesh, atoms)
        merge_tol = max(tol, fast.tolerance(csdf, thr, params)) + added
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
            tolerance=max(group_tol + added, merge_tol),
            thickness=params["thin"],
            min_group=params["min_group"],
        )
    specks = 0
    if added > 0:
        least = int(params["min_voxels"] if atoms is not None else fast.PARAMS["min_voxels"])
        labels, specks = join_specks(csdf, labels, least)
    report(0.97, "part facts")
    info = parts_info(csdf, mesh, labels)
    report(1.0, f"{len(info)} parts")
    rough = {"relief": round(float(noise), 4), "noise_added": round(added, 3), "specks": specks}
    return labels, info, rough


def _entry_checksum(parts: np.ndarray, info_text: str, rough_text: str) -> str:
    h = hashlib.sha256(np.ascontiguousarray(parts).tobytes())
    h.update(info_text.encode())
    h.update(rough_text.encode())
    return h.hexdigest()


def _read_cache(entry: Path, csdf: CSDF) -> tuple[np.ndarray, list[dict], dict] | None:
    """The cached labels, part facts (bboxes moved to this grid's origin) and relief facts, or
    None.

    An entry that cannot be read, whose checksum does not match its content, or whose labels
    and part facts disagree (poisoned or from another grid) is removed, with a
    :class:`PartscaleWarning` saying so; the caller recomputes it.
    """
    if not entry.is_file():
        return None
    try:
        with open(entry, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            if "rough" not in z.files:  # an older partscale's entry: recomputed and overwritten
                return None
            labels, info_text, check = z["parts"], str(z["info"]), str(z["check"])
            rough_text = str(z["rough"])
        if check != _entry_checksum(labels, info_text, rough_text):
            raise ValueError("its checksum does not match its content")
        info = parse_json(info_text, what="part facts")
        rough = parse_json(rough_text, what="relief facts")
        _check_entry(labels, info, csdf)
        if not isinstance(rough, dict) or set(rough) != {"relief", "noise_added", "specks"}:
            raise ValueError("its relief facts are not {relief, noise_added, specks}")
    except Exception as exc:  # zip, zlib, npy header, JSON, shapes: all mean "damaged"
        entry.unlink(missing_ok=True)
        warnings.warn(
            f"segment cache entry {entry} was damaged ({one_line(exc)}): discarded, recomputing",
            PartscaleWarning,
            stacklevel=3,
        )
        return None
    with contextlib.suppress(OSError):
        os.utime(entry)  # eviction removes the least recently used entries first
    for d in info:
        d["bbox"] = (np.asarray(d["bbox"]) + csdf.origin).tolist()
    return labels, info, rough


def _check_entry(labels: np.ndarray, info: Any, csdf: CSDF) -> None:
    """ValueError unless ``labels`` and ``info`` are a consistent segmentation of ``csdf``."""
    if labels.dtype != np.int16 or labels.shape != csdf.shape:
        raise ValueError(f"labels {labels.dtype} {labels.shape} for a {csdf.shape} grid")
    if not isinstance(info, list) or not all(isinstance(d, dict) for d in info):
        raise ValueError("part facts are not a list of objects")
    n = len(info)
    if n == 0 or labels.min() < -1 or labels.max() != n - 1:
        raise ValueError(f"labels in [{labels.min()}, {labels.max()}] for {n} parts")
    counts = np.bincount(labels.ravel().astype(np.int64) + 1, minlength=n + 1)[1:]
    for p, d in enumerate(info):
        bbox = np.asarray(d.get("bbox"), dtype=np.float64)
        if d.get("index") != p or d.get("voxels") != int(counts[p]) or bbox.shape != (2, 3):
            raise ValueError(f"part {p}'s facts disagree with its labels")


def _write_cache(
    entry: Path, csdf: CSDF, labels: np.ndarray, info: list[dict], rough: dict
) -> None:
    # bboxes are stored relative to the origin: the key does not include it
    rel = [
        {**d, "bbox": (np.asarray(d["bbox"]) - csdf.origin).tolist()}
        for d in json.loads(json.dumps(info))
    ]
    parts = labels.astype(np.int16)
    text, rough_text = json.dumps(rel), json.dumps(rough, sort_keys=True)
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(entry, suffix=".npz") as tmp:
            np.savez_compressed(
                tmp,
                parts=parts,
                info=np.array(text),
                rough=np.array(rough_text),
                check=np.array(_entry_checksum(parts, text, rough_text)),
            )
    except (OSError, InputError):  # atomic_path reports a refused folder as InputError
        return  # a read-only or full cache folder must not fail the segmentation
    _evict(entry.parent, keep=entry)


def cache_limit() -> int:
    """Bytes the segment cache may hold: ``PARTSCALE_CACHE_MAX`` (bytes) if set, else 1 GiB."""
    env = os.environ.get("PARTSCALE_CACHE_MAX")
    try:
        return max(0, int(float(env))) if env else CACHE_MAX_BYTES
    except ValueError:
        return CACHE_MAX_BYTES


def _evict(folder: Path, *, keep: Path) -> None:
    """Remove the least recently used entries until the folder holds at most :func:`cache_limit`."""
    entries = []
    with contextlib.suppress(OSError):
        for f in folder.glob("*.npz"):
            with contextlib.suppress(OSError):
                st = f.stat()
                entries.append((st.st_mtime, st.st_size, f))
    total = sum(size for _t, size, _f in entries)
    limit = cache_limit()
    for _t, size, f in sorted(entries, key=lambda e: e[0]):
        if total <= limit:
            break
        if f == keep:
            continue
        with contextlib.suppress(OSError):
            f.unlink()
            total -= size
