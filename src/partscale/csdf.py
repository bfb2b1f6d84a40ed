"""The coloured signed distance field (CSDF) and its file, ``.csdf.npz``.

Conventions (used everywhere in partscale)
------------------------------------------
- Sign: ``sdf`` is negative inside the solid, zero on its surface, positive outside; world units.
- Index order: array index ``(i, j, k)`` is world ``(x, y, z)``; arrays are C-ordered, so ``k``
  (z) varies fastest in memory. Textures written for engines reorder to x fastest (see export).
- Sample positions: voxel ``(i, j, k)``'s centre is at ``origin + (i, j, k) * voxel_size``.
  The grid spans ``[origin - voxel_size / 2, origin + (shape - 1/2) * voxel_size]``.
- Colour space: ``rgb`` is 8-bit sRGB, the colour of the nearest surface point. Linear colour only
  appears where a format demands it (glTF ``COLOR_0``).
- Parts: ``parts`` is the index of the part at the nearest surface point, -1 where there is none
  (everything is -1 until the object is segmented).
- Narrow band: within :data:`BAND_VOXELS` voxels of the surface the distances are exact (to the
  surface the grid represents); farther out they are bounds that keep the sign. Import computes
  them exactly there, edits re-evaluate them there, parts label voxels out to it, and the
  evaluation judges distances in it.

A CSDF is immutable: its arrays are read-only and functions return new CSDFs. Its history
(``meta['history']``) is a :class:`History`: read-only entries, shared between a CSDF and the
CSDFs made from it, so an edit costs the same whatever the history's length.
"""

from __future__ import annotations

import copy
import io
import os
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._files import atomic_path, check_input_file, dumps_json, parse_json
from ._memory import check_bytes
from .errors import InputError, one_line, shown

FORMAT = "partscale.csdf"
FORMAT_VERSION = 1
SUFFIX = ".csdf.npz"
BAND_VOXELS = 3
"""Half-width, in voxels, of the narrow band around the surface where distances are exact."""
VOXEL_SIZE_RANGE = (1e-9, 1e6)
"""Voxel sizes :func:`make` accepts, world units (a nanometre to a thousand kilometres)."""
WORLD_LIMIT = 1e9
"""Largest world coordinate of a voxel centre :func:`make` accepts (either sign)."""
SDF_LIMIT_VOXELS = 1e9
"""Largest ``|sdf|`` :func:`make` accepts, in voxel sizes: beyond it squares and products of
distances leave float32 and vertices leave float64 precision (all values are finite but absurd)."""
_NAMES = ("sdf", "rgb", "parts", "origin", "voxel_size", "meta")
COMPACT_VERSION = 2
"""The format version of compact files (the band exact, the far field as coarse bounds)."""
_COMPACT_NAMES = (
    "shape",
    "band",
    "inside",
    "sdf",
    "rgb",
    "parts",
    "far",
    "far_rgb",
    "far_parts",
    "origin",
    "voxel_size",
    "meta",
)
COMPACT_VOXELS = 1 << 24
"""Grids with more voxels than this (256³) are written compact unless told otherwise."""
FILE_BAND_VOXELS = 8
"""Half-width, in voxels, of the band a compact file holds exactly: the widest band any stage
reads distances from (the 3D textures' distance channel)."""
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)  # the earliest a zip can say
_DEFLATE_SAMPLE = 1 << 18
"""Bytes of each of up to four spread samples of an array deflated to judge it (:func:`save`)."""
_DEFLATE_CHUNK = 1 << 22
"""Bytes of an array member deflated as one piece; pieces deflate in parallel (:func:`save`)."""
_DEFLATE_GAIN = 0.8
"""An array is deflated when its samples shrink below this share of their size. Exact float
distances do not (SheenChair's sdf at 256: to 90 % in 1.6 s, 0.3 s more to read): they are
stored; colours (11 %) and parts (0.1 %) are deflated."""


def _read_only(self, *args: Any, **kwargs: Any) -> Any:
    raise TypeError(
        "a CSDF's history is read-only: expected a new entry (CSDF.with_history), got a change"
    )


class _FrozenDict(dict):
    """A dict that refuses changes; copying it returns itself (it is never changed)."""

    __slots__ = ()
    __setitem__ = __delitem__ = __ior__ = _read_only
    clear = pop = popitem = setdefault = update = _read_only

    def __copy__(self) -> _FrozenDict:
        return self

    def __deepcopy__(self, memo: dict) -> _FrozenDict:
        return self

    def __reduce__(self) -> tuple:
        return (type(self), (dict(self),))


class _FrozenList(list):
    """A list that refuses changes; copying it returns itself (it is never changed)."""

    __slots__ = ()
    __setitem__ = __delitem__ = __iadd__ = __imul__ = _read_only
    append = extend = insert = remove = pop = clear = sort = reverse = _read_only

    def __copy__(self) -> _FrozenList:
        return self

    def __deepcopy__(self, memo: dict) -> _FrozenList:
        return self

    def __reduce__(self) -> tuple:
        return (type(self), (list(self),))


def _freeze(x: Any) -> Any:
    """``x`` with every dict and list (tuples become lists) replaced by a read-only copy."""
    if isinstance(x, _FrozenDict | _FrozenList):
        return x
    if isinstance(x, dict):
        return _FrozenDict((k, _freeze(v)) for k, v in x.items())
    if isinstance(x, list | tuple):
        return _FrozenList(_freeze(v) for v in x)
    return x


class History(_FrozenList):
    """``meta['history']``: the list of operations, oldest first, each a read-only dict.

    Compares, indexes and serialises like the list of dicts it holds; changing it (or an entry)
    raises ``TypeError``. :meth:`appended` makes a new history sharing every entry, so neither
    copying a CSDF's meta nor recording an operation copies the entries already there. Made
    from an iterable of dicts, the operations, by :meth:`of` (which checks them).

    Examples
    --------
    >>> from partscale.csdf import History
    >>> h = History.of([{"op": "import"}]).appended({"op": "scale", "axis": "x"})
    >>> [e["op"] for e in h]
    ['import', 'scale']
    >>> h[0]["op"] = "changed"
    Traceback (most recent call last):
    ...
    TypeError: ...
    """

    __slots__ = ()

    @classmethod
    def of(cls, entries: Any) -> History:
        """``entries`` (a list of JSON objects) as a History; a History is returned as is."""
        if isinstance(entries, History):
            return entries
        if not isinstance(entries, list) or not all(isinstance(h, dict) for h in entries):
            raise InputError(f"meta history: expected a list of objects, got {shown(entries)}")
        return cls(_entry(h) for h in entries)

    def appended(self, operation: dict[str, Any]) -> History:
        """A new history: these entries (shared, not copied) and then ``operation``."""
        if not isinstance(operation, dict):
            raise InputError(f"history entry: expected an object, got {shown(operation)}")
        return History([*self, _entry(operation)])


def _entry(operation: dict[str, Any]) -> _FrozenDict:
    # an entry is checked once, when it joins a history; afterwards it is shared, never re-checked
    if isinstance(operation, _FrozenDict):
        return operation
    try:
        dumps_json(operation)
    except (TypeError, ValueError) as exc:
        raise InputError(f"meta history: expected JSON-serialisable entries, got {exc}") from None
    return _freeze(operation)


def _frozen(a: np.ndarray) -> np.ndarray:
    # A read-only array is already ours to share; a writeable one may belong to the caller, so it
    # is copied rather than frozen in place (freezing would change the caller's array).
    if not a.flags.writeable and a.flags.c_contiguous:
        return a
    a = np.array(a, order="C", copy=True)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class CSDF:
    """A coloured signed distance field on a regular grid of cubic voxels.

    Parameters
    ----------
    sdf : (X, Y, Z) float32
        Signed distance in world units, negative inside.
    rgb : (X, Y, Z, 3) uint8
        sRGB colour of the nearest surface point.
    parts : (X, Y, Z) int16
        Part index of the nearest surface point, -1 where none.
    origin : (3,) float64
        World position of voxel (0, 0, 0)'s centre.
    voxel_size : float
        Edge length of a voxel in world units (> 0).
    meta : dict
        JSON-serialisable: ``units``, ``source``, ``history`` (a read-only :class:`History` of
        operations), ``parts_info``...

    Notes
    -----
    Construct through :func:`make` (which validates and converts) unless the arrays are already
    known to be right. A CSDF is immutable: every operation returns a new one.

    Examples
    --------
    >>> from partscale import shapes
    >>> c = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1)
    >>> c.shape
    (17, 12, 12)
    >>> c.surface_bounds().round(2).tolist()
    [[0.0, 0.0, 0.0], [1.0, 0.5, 0.5]]
    """

    sdf: np.ndarray
    rgb: np.ndarray
    parts: np.ndarray
    origin: np.ndarray
    voxel_size: float
    meta: dict[str, Any] = field(default_factory=dict)

    # -- geometry of the grid -------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int, int]:
        """(X, Y, Z) number of voxels along x, y, z."""
        nx, ny, nz = self.sdf.shape
        return int(nx), int(ny), int(nz)

    @property
    def grid_bounds(self) -> np.ndarray:
        """(2, 3) float64: world min and max corner of the region the voxels cover."""
        lo = self.origin - self.voxel_size / 2
        hi = self.origin + (np.asarray(self.shape) - 0.5) * self.voxel_size
        return np.stack([lo, hi])

    def axis_coords(self, axis: int) -> np.ndarray:
        """(N,) float64: world coordinate of the voxel centres along ``axis`` (0, 1, 2)."""
        return self.origin[axis] + np.arange(self.shape[axis]) * self.voxel_size

    def world_to_index(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) float64 continuous voxel indices of world points (centres at integers)."""
        return (np.asarray(points, dtype=np.float64) - self.origin) / self.voxel_size

    def index_to_world(self, index: np.ndarray) -> np.ndarray:
        """(N, 3) float64 world points of (continuous) voxel indices."""
        return self.origin + np.asarray(index, dtype=np.float64) * self.voxel_size

    def surface_bounds(self) -> np.ndarray:
        """(2, 3) float64: world bounding box of the solid (zero level), to sub-voxel accuracy.

        Along each axis, the extreme inside voxel is refined by the linear zero crossing to its
        outside neighbour. Raises :class:`InputError` if the CSDF has no inside voxel. Computed
        once per CSDF (its arrays never change); each call returns a new array.
        """
        got = self.__dict__.get("_surface_bounds")
        if got is None:
            got = self._find_surface_bounds()
            object.__setattr__(self, "_surface_bounds", got)  # a cache, not a field
        return got.copy()

    def _find_surface_bounds(self) -> np.ndarray:
        inside = self.sdf <= 0
        # occupancy along each axis from two reductions over the grid (not one per axis)
        occ_xy = np.any(inside, axis=2)
        occupied = (occ_xy.any(axis=1), occ_xy.any(axis=0), np.any(inside, axis=(0, 1)))
        if not occupied[0].any():
            raise InputError("CSDF: expected a surface (some sdf <= 0), got none")
        out = np.empty((2, 3))
        h = self.voxel_size
        for ax in range(3):
            idx = np.nonzero(occupied[ax])[0]
            for side, i in ((0, idx[0]), (1, idx[-1])):
                step = -1 if side == 0 else 1
                j = i + step
                pos = self.origin[ax] + i * h
                if 0 <= j < self.shape[ax]:
                    # smallest |sdf| crossing among the inside voxels of that slice
                    sl_in = np.take(self.sdf, i, axis=ax)
                    sl_out = np.take(self.sdf, j, axis=ax)
                    m = sl_in <= 0
                    a, b = sl_in[m].astype(np.float64), sl_out[m].astype(np.float64)
                    t = np.where(b > a, -a / np.maximum(b - a, 1e-12), 0.0)
                    pos += step * h * float(np.clip(t, 0.0, 1.0).max())
                out[side, ax] = pos
        return out

    # -- functional updates ---------------------------------------------------------------
    def replace(self, **changes: Any) -> CSDF:
        """Return a new CSDF with some fields replaced (validated through :func:`make`)."""
        return self._replaced(changes, trusted=False)

    def with_history(self, operation: dict[str, Any], **changes: Any) -> CSDF:
        """Return a new CSDF with ``operation`` appended to ``meta['history']``.

        ``changes['meta']``, when given, replaces the meta (its history is the one extended).
        The entries already there are shared, not copied: recording an operation costs the same
        whatever the history's length.
        """
        return self._replaced(self._history_changes(operation, changes), trusted=False)

    def with_trusted_history(self, operation: dict[str, Any], **changes: Any) -> CSDF:
        """:meth:`with_history` for a pipeline stage's own arrays, their values not scanned again.

        For stages (an edit, its baseline) whose new ``sdf``/``rgb``/``parts`` are computed
        from this CSDF, which :func:`make` already validated, by steps that keep its value
        invariants: every distance finite with ``|sdf|`` within :data:`SDF_LIMIT_VOXELS` voxel
        sizes, every part index in ``[-1, 32767]``. Only those whole-grid value scans are
        skipped (a stage that made the arrays need not pay for them twice); shapes, dtypes,
        origin, voxel size and meta are still checked. Never for arrays that come from outside
        the package (files, users, callbacks): those go through :meth:`with_history`.
        """
        return self._replaced(self._history_changes(operation, changes), trusted=True)

    def _history_changes(self, operation: dict[str, Any], changes: dict[str, Any]) -> dict:
        meta = dict(changes.pop("meta", self.meta))
        meta["history"] = History.of(meta.get("history", [])).appended(operation)
        return {**changes, "meta": meta}

    def _replaced(self, changes: dict[str, Any], *, trusted: bool) -> CSDF:
        fields = {n: getattr(self, n) for n in ("sdf", "rgb", "parts", "origin", "voxel_size")}
        fields["meta"] = self.meta  # make() copies it (the history is shared, not copied)
        unknown = set(changes) - set(fields)
        if unknown:
            raise TypeError(
                f"replace() got unknown field(s) {sorted(unknown)}; fields are {_NAMES}"
            )
        fields.update(changes)
        return _make(**fields, trusted=trusted)

    @property
    def n_parts(self) -> int:
        """Number of distinct parts (0 when not segmented)."""
        return int(self.parts.max()) + 1 if self.parts.size and self.parts.max() >= 0 else 0

    def __repr__(self) -> str:
        ext = (np.asarray(self.shape) * self.voxel_size).round(4).tolist()
        return (
            f"CSDF(shape={self.shape}, voxel_size={self.voxel_size:.6g}, extent={ext}, "
            f"parts={self.n_parts})"
        )


def _real_array(x: Any) -> np.ndarray | None:
    # real numbers only: bools, strings and objects are refused rather than converted
    try:
        a = np.asarray(x)
    except (TypeError, ValueError):  # ragged sequences
        return None
    return a if a.dtype.kind in "iuf" else None


def check_origin(x: Any, what: str) -> np.ndarray:
    """Check a grid origin: three finite real numbers.

    Parameters
    ----------
    x : array_like
        The origin as given.
    what : str
        Its name in the :class:`InputError` (``"origin"``, ``"<file>: grid origin"``).

    Returns
    -------
    (3,) float64
        The origin.

    Examples
    --------
    >>> from partscale.csdf import check_origin
    >>> check_origin([0, 1, 2], "origin")
    array([0., 1., 2.])
    >>> check_origin([0, 1], "origin")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: origin: expected 3 finite numbers, got [0, 1]
    """
    a = _real_array(x)
    if a is None or a.shape != (3,) or not np.isfinite(a).all():
        raise InputError(f"{what}: expected 3 finite numbers, got {shown(x)}")
    return a.astype(np.float64)


def check_number(x: Any, what: str) -> float:
    """Check one finite real number (a scalar or a size-1 array).

    Parameters
    ----------
    x : scalar or array_like of size 1
        The number as given.
    what : str
        Its name in the :class:`InputError`.

    Returns
    -------
    float
        ``x`` as a Python float.

    Examples
    --------
    >>> from partscale.csdf import check_number
    >>> check_number([2.5], "iso")
    2.5
    """
    a = _real_array(x)
    if a is None or a.size != 1 or not np.isfinite(a).all():
        raise InputError(f"{what}: expected one finite number, got {shown(x)}")
    return float(a.reshape(()))


def check_voxel_size(x: Any, what: str) -> float:
    """Check a voxel edge length: one finite real number > 0 in :data:`VOXEL_SIZE_RANGE`.

    Parameters
    ----------
    x : scalar or array_like of size 1
        The voxel size as given.
    what : str
        Its name in the :class:`InputError`.

    Returns
    -------
    float
        The voxel size.

    Examples
    --------
    >>> from partscale.csdf import check_voxel_size
    >>> check_voxel_size(0.01, "voxel_size")
    0.01
    >>> check_voxel_size(0, "voxel_size")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: voxel_size: expected a finite number > 0, got 0.0
    """
    a = _real_array(x)
    if a is None or a.size != 1:
        raise InputError(f"{what}: expected one number, got {shown(x)}")
    h = float(a.reshape(()))
    if not (np.isfinite(h) and h > 0):
        raise InputError(f"{what}: expected a finite number > 0, got {h}")
    lo, hi = VOXEL_SIZE_RANGE
    if not lo <= h <= hi:
        raise InputError(f"{what}: expected a voxel size in [{lo:g}, {hi:g}], got {h:g}")
    return h


def make(
    sdf: Any,
    rgb: Any = None,
    parts: Any = None,
    origin: Any = (0.0, 0.0, 0.0),
    voxel_size: float = 1.0,
    meta: dict[str, Any] | None = None,
) -> CSDF:
    """Validate and convert arrays into a :class:`CSDF` (the one public constructor).

    Parameters
    ----------
    sdf : (X, Y, Z) array_like of float
        Signed distance, world units, negative inside. Must be finite.
    rgb : (X, Y, Z, 3) array_like of uint8, optional
        sRGB colour; mid grey when omitted.
    parts : (X, Y, Z) array_like of int, optional
        Part index, -1 where none; all -1 when omitted.
    origin : (3,) array_like of float
        World position of voxel (0, 0, 0)'s centre.
    voxel_size : float
        Voxel edge length, > 0.
    meta : dict, optional
        JSON-serialisable metadata, copied; ``format``/``version``/``history`` are filled in,
        and a given ``history`` must be a list of objects (operations). It is stored as a
        read-only :class:`History` (a History given is shared as it is, not copied).

    Returns
    -------
    CSDF
        The arrays, converted (float32, uint8, int16) and made read-only.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import make
    >>> x, y, z = np.mgrid[-1:1:21j, -1:1:21j, -1:1:21j]
    >>> ball = make(np.sqrt(x**2 + y**2 + z**2) - 0.5, origin=(-1, -1, -1), voxel_size=0.1)
    >>> ball.shape, ball.sdf.dtype, ball.rgb[0, 0, 0].tolist()
    ((21, 21, 21), dtype('float32'), [128, 128, 128])
    """
    return _make(sdf, rgb, parts, origin, voxel_size, meta, trusted=False)


def _make(
    sdf: Any,
    rgb: Any,
    parts: Any,
    origin: Any,
    voxel_size: Any,
    meta: dict[str, Any] | None,
    *,
    trusted: bool,
) -> CSDF:
    """:func:`make`; ``trusted``: see :meth:`CSDF.with_trusted_history`."""
    sdf = np.asarray(sdf)
    if sdf.ndim != 3 or min(sdf.shape) < 2:
        raise InputError(
            f"sdf: expected a 3D grid with >= 2 voxels per axis, got shape {sdf.shape}"
        )
    if not np.issubdtype(sdf.dtype, np.floating):
        raise InputError(f"sdf: expected floating point values, got dtype {sdf.dtype}")
    sdf = sdf.astype(np.float32, copy=False)
    if not trusted and not np.isfinite(sdf).all():
        bad = int((~np.isfinite(sdf)).sum())
        raise InputError(f"sdf: expected finite values, got {bad} NaN/inf voxel(s)")
    shape = sdf.shape
    if rgb is None:
        rgb = np.full((*shape, 3), 128, np.uint8)
    rgb = np.asarray(rgb)
    if rgb.shape != (*shape, 3):
        raise InputError(f"rgb: expected shape {(*shape, 3)}, got {rgb.shape}")
    if rgb.dtype != np.uint8:
        raise InputError(f"rgb: expected dtype uint8 (sRGB), got {rgb.dtype}")
    if parts is None:
        parts = np.full(shape, -1, np.int16)
    parts = np.asarray(parts)
    if parts.shape != shape:
        raise InputError(f"parts: expected shape {shape}, got {parts.shape}")
    if not np.issubdtype(parts.dtype, np.integer):
        raise InputError(f"parts: expected integer part indices, got dtype {parts.dtype}")
    if not trusted and parts.size and (parts.min() < -1 or parts.max() > np.iinfo(np.int16).max):
        raise InputError(
            f"parts: expected indices in [-1, 32767], got [{parts.min()}, {parts.max()}]"
        )
    parts = parts.astype(np.int16, copy=False)
    origin = check_origin(origin, "origin")
    voxel_size = check_voxel_size(voxel_size, "voxel_size")
    far = np.abs(np.stack([origin, origin + (np.asarray(shape) - 1) * voxel_size])).max()
    if far > WORLD_LIMIT:
        raise InputError(
            f"origin: expected voxel centres within +-{WORLD_LIMIT:g} world units, got {far:.3g}"
        )
    if (
        not trusted
        and sdf.size
        and max(-float(sdf.min()), float(sdf.max())) > SDF_LIMIT_VOXELS * voxel_size
    ):
        big = max(-float(sdf.min()), float(sdf.max()))
        raise InputError(
            f"sdf: expected |values| <= {SDF_LIMIT_VOXELS:g} voxel sizes "
            f"({SDF_LIMIT_VOXELS * voxel_size:.3g}), got {big:.3g}"
        )
    if meta is None:
        meta = {}
    if not isinstance(meta, dict):
        raise InputError(f"meta: expected a JSON object, got {type(meta).__name__}")
    # the history is immutable and shared; everything else is copied (and checked) here, so a
    # CSDF never shares a mutable object with its caller
    history = History.of(meta.get("history", []))
    meta = {k: history if k == "history" else copy.deepcopy(v) for k, v in meta.items()}
    meta.setdefault("history", history)
    meta["format"] = FORMAT
    meta["version"] = FORMAT_VERSION
    meta.setdefault("units", "m")
    try:
        dumps_json({k: v for k, v in meta.items() if k != "history"})
    except (TypeError, ValueError) as exc:
        raise InputError(f"meta: expected JSON-serialisable metadata, got {exc}") from None
    return CSDF(
        sdf=_frozen(sdf),
        rgb=_frozen(rgb),
        parts=_frozen(parts),
        origin=_frozen(origin),
        voxel_size=voxel_size,
        meta=meta,
    )


def save(
    csdf: CSDF, path: str | os.PathLike, *, compress: bool = True, compact: bool | None = None
) -> Path:
    """Write ``csdf`` to a ``.csdf.npz`` file atomically (a temporary file, then a rename).

    The zip members carry a fixed time, so the same CSDF always gives the same bytes (numpy's
    ``savez`` stamps the current time). Any zip reader, and ``np.load``, reads the file.

    Parameters
    ----------
    csdf : CSDF
        What to write.
    path : str or os.PathLike
        The file (``.csdf.npz`` by convention).
    compress : bool
        Deflate each array where that pays (colours, parts), store it where it does not (the
        distances).
    compact : bool, optional
        Write the band (:data:`FILE_BAND_VOXELS` voxels either side of the surface) exactly and
        beyond it one distance, colour and part per block of 4³ voxels: every distance there
        a bound no larger than the CSDF's, sign kept (the far field's promise). Its size
        follows the surface: SheenChair at 512 voxels is about 52 MiB, against 337 MiB written
        whole. Default: compact above :data:`COMPACT_VOXELS` voxels, whole below. See
        ``docs/file-format.md``.

    Returns
    -------
    pathlib.Path
        ``path``, now holding the CSDF.

    Examples
    --------
    >>> from partscale import load, save, shapes
    >>> box = shapes.box((0, 0, 0), (1, 1, 1), voxel_size=0.1)
    >>> save(box, "box.csdf.npz")
    PosixPath('box.csdf.npz')
    >>> load("box.csdf.npz").shape == box.shape
    True
    """
    path = Path(path)
    if compact is None:
        compact = csdf.sdf.size > COMPACT_VOXELS
    meta = dict(csdf.meta)
    level = None
    if compact:
        from ._compact import encode

        arrays = encode(csdf.sdf, csdf.rgb, csdf.parts, csdf.voxel_size, FILE_BAND_VOXELS)
        meta["version"] = COMPACT_VERSION
        level = 1  # fast: what remains is small, and mostly the band's noisy distances
    else:
        arrays = {"sdf": csdf.sdf, "rgb": csdf.rgb, "parts": csdf.parts}
    arrays |= {
        "origin": csdf.origin,
        "voxel_size": np.asarray(np.float64(csdf.voxel_size)),
        "meta": np.array(_readable_meta(meta, path)),
    }
    with (
        atomic_path(path, suffix=".npz") as tmp,
        zipfile.ZipFile(tmp, "w", compresslevel=level) as zf,
    ):
        for name, a in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_TIME)
            deflate = compress and _deflates(a)
            info.compress_type = zipfile.ZIP_DEFLATED if deflate else zipfile.ZIP_STORED
            with zf.open(info, "w", force_zip64=True) as f:  # as savez: sizes unknown up front
                if deflate:
                    _write_deflated(f, a, 6 if level is None else level)
                else:
                    np.lib.format.write_array(f, a, allow_pickle=False)
    return path


class _Deflated:
    """Stands in for a zip member's compressor: the deflate stream is made ahead (in parallel),
    zipfile still counts the plain bytes and their CRC as they pass through.
    """

    def __init__(self, stream: bytes):
        self.stream = stream

    def compress(self, data: Any) -> bytes:
        return b""

    def flush(self) -> bytes:
        return self.stream


def _deflate(chunks: list[memoryview], level: int) -> bytes:
    """One raw deflate stream of the chunks in order, deflated at once on the cores: each chunk
    ends on a byte boundary (a sync flush), the last one ends the stream (as pigz does). The
    chunks are fixed, so the same data give the same bytes on any machine.
    """
    from ._workers import thread_map

    def one(i: int) -> bytes:
        z = zlib.compressobj(level, zlib.DEFLATED, -15)
        end = zlib.Z_FINISH if i == len(chunks) - 1 else zlib.Z_SYNC_FLUSH
        return z.compress(chunks[i]) + z.flush(end)

    return b"".join(thread_map(one, range(len(chunks))))


def _write_deflated(f: Any, a: np.ndarray, level: int) -> None:
    """``a`` as a ``.npy`` (what ``np.lib.format.write_array`` writes) into zip member ``f``,
    opened for writing deflated; chunks of :data:`_DEFLATE_CHUNK` bytes deflate in parallel.
    """
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, np.lib.format.header_data_from_array_1_0(a))
    head = buf.getvalue()
    body = np.ascontiguousarray(a).reshape(-1).view(np.uint8).data
    k = max(0, _DEFLATE_CHUNK - len(head))
    chunks = [memoryview(head + bytes(body[:k]))]
    chunks += [body[s : s + _DEFLATE_CHUNK] for s in range(k, len(body), _DEFLATE_CHUNK)]
    # zipfile counts the plain bytes and their CRC as they pass; the stream is ours
    f._compressor = _Deflated(_deflate(chunks, level))
    for c in chunks:
        f.write(c)


def _readable_meta(meta: dict, path: Path) -> str:
    """``meta`` as the JSON text :func:`load` will read back, checked by that reader before
    anything is written (a number beyond its limits would give a file partscale refuses).
    """
    text = dumps_json(meta)
    try:
        parse_json(text, what="meta")
    except InputError as exc:
        raise InputError(f"{path}: expected meta partscale can read back, got {exc}") from None
    return text


def _deflates(a: np.ndarray) -> bool:
    """Whether deflate shrinks ``a`` (any array) below ``_DEFLATE_GAIN`` of its bytes, judged on
    up to four samples spread over it (a few ms: the data alone decides, so the bytes written
    stay the same for the same CSDF).
    """
    b = np.ascontiguousarray(a).reshape(-1).view(np.uint8)
    n = len(b)
    if n <= 4 * _DEFLATE_SAMPLE:
        return len(zlib.compress(b.tobytes(), 1)) < _DEFLATE_GAIN * max(n, 1)
    starts = np.linspace(0, n - _DEFLATE_SAMPLE, 4).astype(np.int64)
    packed = sum(len(zlib.compress(b[s : s + _DEFLATE_SAMPLE].tobytes(), 1)) for s in starts)
    return packed < _DEFLATE_GAIN * 4 * _DEFLATE_SAMPLE


def load(path: str | os.PathLike) -> CSDF:
    """Read and validate a ``.csdf.npz`` file.

    Parameters
    ----------
    path : str or os.PathLike
        The file, as :func:`save` writes it.

    Returns
    -------
    CSDF
        Its arrays (read-only) and meta.

    Raises
    ------
    InputError
        Naming the file and the problem: missing file, not an npz, truncated or damaged data,
        missing or extra arrays, wrong shapes or dtypes, non-finite values, meta that is not a
        JSON object, wrong format or version (reported before anything else :func:`make`
        checks: origin, voxel size, history).

    Examples
    --------
    >>> from partscale import load, save, shapes
    >>> _ = save(shapes.sphere((0, 0, 0), 0.5, voxel_size=0.1), "ball.csdf.npz")
    >>> ball = load("ball.csdf.npz")
    >>> ball.meta["source"], ball.voxel_size
    ('sphere', 0.1)
    """
    path = check_input_file(path, what="an existing .csdf.npz file")
    try:
        # one zip, opened once: the headers are checked before any array is read
        with zipfile.ZipFile(path) as zf:
            members = {i.filename.removesuffix(".npy"): i for i in zf.infolist()}
            _check_declared(path, zf)
            names = _COMPACT_NAMES if "far.npy" in zf.namelist() else _NAMES
            missing = [n for n in names if n not in members]
            extra = sorted(set(members) - set(names))
            if missing or extra:
                got = "; ".join(
                    ([f"missing {', '.join(missing)}"] if missing else [])
                    + ([f"extra {', '.join(extra)}"] if extra else [])
                )
                raise InputError(
                    f"{path}: expected exactly the arrays {', '.join(names)}, got {got}"
                )
            data: dict[str, Any] = {}
            for n in names:
                with zf.open(members[n]) as f:
                    data[n] = np.lib.format.read_array(f, allow_pickle=False)
    except InputError:
        raise
    except Exception as exc:  # zipfile, zlib, numpy's header parser: many kinds on damaged data
        # another kind of file (a mesh where a CSDF is read): the way from one to the other
        hint = "" if path.suffix.lower() == ".npz" else "; partscale import makes one from a mesh"
        raise InputError(
            f"{path}: expected a .csdf.npz (zip of .npy arrays{hint}), got {one_line(exc)}"
        ) from None
    compact = names is _COMPACT_NAMES
    for a in data.values():
        a.flags.writeable = False  # ours alone: make() keeps them instead of copying
    m = data["meta"]
    if m.shape != () or m.dtype.kind != "U":
        raise InputError(
            f"{path}: expected meta to be one JSON string, got dtype {m.dtype} shape {m.shape}"
        )
    meta = parse_json(str(m), what=f"{path}: meta")
    if not isinstance(meta, dict):
        raise InputError(f"{path}: expected meta to be a JSON object, got {type(meta).__name__}")
    if meta.get("format") != FORMAT:
        raise InputError(f"{path}: expected meta format {FORMAT!r}, got {meta.get('format')!r}")
    version = meta.get("version")
    want = COMPACT_VERSION if compact else FORMAT_VERSION
    if isinstance(version, bool) or version != want:
        raise InputError(f"{path}: expected format version {want}, got {version!r}")
    if compact:
        from ._compact import check, decode

        problem = check(data)
        if problem is not None:
            raise InputError(f"{path}: {problem}")
        voxels = int(np.prod(data["shape"]))
        check_bytes(voxels * 11 * 1.25, what=f"{path}: reading it")  # grids and 2 masks
        data["sdf"], data["rgb"], data["parts"] = decode(data)
        for name in ("sdf", "rgb", "parts"):
            data[name].flags.writeable = False
    exact = {"sdf": np.float32, "rgb": np.uint8, "parts": np.int16}
    for name, dt in exact.items():
        if data[name].dtype != dt:
            raise InputError(
                f"{path}: expected {name} of dtype {np.dtype(dt)}, got {data[name].dtype}"
            )
    try:
        return make(
            data["sdf"], data["rgb"], data["parts"], data["origin"], data["voxel_size"], meta
        )
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None


def _check_declared(path: Path, zf: zipfile.ZipFile) -> None:
    """Refuse, before reading any array, a file whose declared arrays would not fit in memory."""
    need = 0
    for info in zf.infolist():
        with zf.open(info) as f:
            version = np.lib.format.read_magic(f)
            read = (
                np.lib.format.read_array_header_1_0
                if version == (1, 0)
                else np.lib.format.read_array_header_2_0
            )
            shape, _fortran, dtype = read(f)
        n = 1
        for d in shape:
            n *= int(d)
        need += n * dtype.itemsize
    # the arrays themselves, plus a byte per voxel for the finiteness check
    check_bytes(need * 1.25, what=f"{path}: reading it")
