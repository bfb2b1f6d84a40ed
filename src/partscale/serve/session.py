"""The editing session behind the web editor: one CSDF, its undo/redo stacks, save and export.

The session is the only state the server holds. It knows the one file it was started with and
derives every path it writes from that file (never from a request).
"""

from __future__ import annotations

import math
import tempfile
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import numba
import numpy as np

from .._options import count
from ..csdf import CSDF, SUFFIX, load, save
from ..errors import InputError, shown
from ..progress import ProgressCallback

T = TypeVar("T")

#: Most undo steps kept, and the most memory they may hold together (the oldest go first; one
#: step is always kept). A 128³ CSDF is ~20 MiB, a 256³ one ~150 MiB.
MAX_UNDO = 48
UNDO_BYTES = 2 << 30
#: Encodings kept (current, previous and next object, grid and parts each, and the deltas).
CACHED_ENCODINGS = 8
#: Revisions whose objects a page may name as the base of a delta (the one it shows is
#: normally the last but one).
SHOWN_REVISIONS = 4


def edited_path(path: Path) -> Path:
    """``NAME.csdf.npz`` -> ``NAME.edited.csdf.npz`` (beside it): where Save writes by default.

    Parameters
    ----------
    path : Path
        The file being edited.

    Returns
    -------
    Path
        In the same folder: the name without ``.csdf.npz`` (or without its last suffix), then
        ``.edited.csdf.npz``.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale.serve import edited_path
    >>> edited_path(Path("chairs/chair.csdf.npz")).as_posix()
    'chairs/chair.edited.csdf.npz'
    """
    name = path.name
    stem = name[: -len(SUFFIX)] if name.endswith(SUFFIX) else path.stem
    return path.with_name(f"{stem}.edited{SUFFIX}")


#: Bytes a voxel takes in :func:`encode_grid`: a float16 distance and three sRGB bytes.
GRID_BYTES_PER_VOXEL = 5
#: The grid protocol's version, in the state's ``encoding`` (1: RGBA float16, whole grids; 2:
#: float16 distance + sRGB bytes, deltas); the page refuses another.
GRID_FORMAT = 2


@numba.njit(cache=True, nogil=True, inline="always")
def _half_bits(f):  # pragma: no cover - compiled
    # float32 bits -> float16 bits, round half to even: numpy's npy_floatbits_to_halfbits
    h_sgn = (f & 0x80000000) >> 16
    f_exp = f & 0x7F800000
    if f_exp >= 0x47800000:  # overflow, inf, nan
        if f_exp == 0x7F800000 and (f & 0x007FFFFF) != 0:
            ret = 0x7C00 + ((f & 0x007FFFFF) >> 13)
            return h_sgn + (ret + 1 if ret == 0x7C00 else ret)
        return h_sgn + 0x7C00
    if f_exp <= 0x38000000:  # subnormal half or zero
        if f_exp < 0x33000000:
            return h_sgn
        f_sig = (0x00800000 + (f & 0x007FFFFF)) >> (113 - (f_exp >> 23))
        if (f_sig & 0x00003FFF) != 0x00001000 or (f & 0x000007FF) != 0:
            f_sig += 0x00001000
        return h_sgn + (f_sig >> 13)
    f_sig = f & 0x007FFFFF
    if (f_sig & 0x00003FFF) != 0x00001000:
        f_sig += 0x00001000
    return h_sgn + (f_sig >> 13) + ((f_exp - 0x38000000) >> 13)


@numba.njit(cache=True, nogil=True)
def _encode_half(sdf, scale, out):  # pragma: no cover - compiled
    # out (flat, C order of the box) = float16 bits of float32(sdf * scale), in one pass over a
    # possibly strided box: no scaled copy, no gather
    one = np.empty(1, np.float32)
    bits = one.view(np.uint32)
    n = 0
    for i in range(sdf.shape[0]):
        for j in range(sdf.shape[1]):
            for k in range(sdf.shape[2]):
                one[0] = sdf[i, j, k] * scale
                out[n] = _half_bits(bits[0])
                n += 1


def _layers(axis: int, start: int, stop: int) -> tuple[slice, ...]:
    return tuple(slice(start, stop) if a == axis else slice(None) for a in range(3))


def _frozen(a: np.ndarray) -> memoryview:
    # the array's own bytes, read-only: a copy into ``bytes`` costs as much as the encoding
    a.flags.writeable = False
    return a.data


def encode_slab(c: CSDF, axis: int, start: int, stop: int) -> memoryview:
    """Layers ``start:stop`` of ``c`` along ``axis`` as :func:`encode_grid` encodes the grid.

    The box is ``c``'s grid cut to those layers (shape ``S``, its own C order); the bytes are
    the two planes of :func:`encode_grid` for that box.

    Parameters
    ----------
    c : CSDF
        The object.
    axis : int
        0, 1 or 2 (x, y, z).
    start, stop : int
        The layers ``start:stop`` along ``axis``.

    Returns
    -------
    memoryview
        Read-only bytes: ``prod(S)`` float16 distances in voxels, then ``prod(S) * 3`` sRGB
        bytes (:data:`GRID_BYTES_PER_VOXEL` a voxel).

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.serve import GRID_BYTES_PER_VOXEL, encode_slab
    >>> box = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1)
    >>> box.shape
    (17, 12, 12)
    >>> len(encode_slab(box, 0, 2, 5)) == 3 * 12 * 12 * GRID_BYTES_PER_VOXEL
    True
    """
    box = _layers(axis, start, stop)
    sdf, rgb = c.sdf[box], c.rgb[box]
    n = sdf.size
    out = np.empty(n * GRID_BYTES_PER_VOXEL, dtype=np.uint8)
    _encode_half(sdf, np.float32(1.0 / c.voxel_size), out[: 2 * n].view("<u2"))
    out[2 * n :].reshape(rgb.shape)[...] = rgb
    return _frozen(out)


def encode_grid(c: CSDF) -> memoryview:
    """The grid for the page's 3D textures (read-only bytes): two planes, each ``(X, Y, Z)``.

    That is the grid's own order, z fastest: the page uploads them as ``Z x Y x X`` textures and
    samples them at ``uvw.zyx``, so no transpose is ever made (it would cost more than the rest).
    First ``X * Y * Z`` float16 little-endian: sdf / voxel_size, the signed distance in voxels
    (negative inside), which keeps float16's relative precision near the surface whatever the
    object's units; bit-identical to numpy's ``astype(float16)``, in one compiled pass. Then
    ``X * Y * Z * 3`` bytes: the stored 8-bit sRGB colour (r, g, b), as it is (not linearised).
    :data:`GRID_BYTES_PER_VOXEL` bytes a voxel in all.

    Parameters
    ----------
    c : CSDF
        The object.

    Returns
    -------
    memoryview
        Read-only bytes, ``X * Y * Z * GRID_BYTES_PER_VOXEL`` of them.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import shapes
    >>> from partscale.serve import encode_grid
    >>> box = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1)
    >>> data = encode_grid(box)
    >>> len(data), data.readonly
    (12240, True)
    >>> voxels = np.frombuffer(data, "<f2", count=box.sdf.size).reshape(box.shape)
    >>> float(voxels.min()), float(box.sdf.min() / box.voxel_size)
    (-2.0, -2.0)
    >>> np.frombuffer(data, np.uint8, offset=2 * box.sdf.size).reshape(*box.shape, 3)[0, 0, 0]
    array([200, 120,  60], dtype=uint8)
    """
    return encode_slab(c, 0, 0, c.shape[0])


@dataclass(frozen=True)
class GridDelta:
    """How one grid follows from another along one axis: the rest is copied.

    The new grid's first ``head`` layers along ``axis`` are the base's first ``head``, its last
    ``tail`` are the base's last ``tail`` (shifted when the length changed); only the layers
    between, ``head : shape[axis] - tail``, are new. The other two axes have the base's length.

    Attributes
    ----------
    axis : int
        0, 1 or 2 (x, y, z).
    head, tail : int
        Layers at the start and at the end along ``axis`` that the new grid shares with the
        base.

    Examples
    --------
    >>> from partscale.serve import GridDelta
    >>> GridDelta(0, 8, 7).header()
    '0,8,7'
    """

    axis: int
    head: int
    tail: int

    def header(self) -> str:
        """``"axis,head,tail"``, as the ``X-Partscale-Delta`` header says it."""
        return f"{self.axis},{self.head},{self.tail}"


@numba.njit(cache=True, nogil=True)
def _same_layers(sdf_a, sdf_b, rgb_a, rgb_b, parts_a, parts_b, limit):  # pragma: no cover
    # how many leading layers (first axis) are equal in all three arrays (sdf as bits), at most
    # limit; stops at the first difference
    for i in range(limit):
        for j in range(sdf_a.shape[1]):
            for k in range(sdf_a.shape[2]):
                if (
                    sdf_a[i, j, k] != sdf_b[i, j, k]
                    or parts_a[i, j, k] != parts_b[i, j, k]
                    or rgb_a[i, j, k, 0] != rgb_b[i, j, k, 0]
                    or rgb_a[i, j, k, 1] != rgb_b[i, j, k, 1]
                    or rgb_a[i, j, k, 2] != rgb_b[i, j, k, 2]
                ):
                    return i
    return limit


def grid_delta(base: CSDF, new: CSDF) -> GridDelta | None:
    """The layers ``new`` shares with ``base`` at its start and end, or None when it cannot.

    An edit along one axis keeps what lies outside its zone and shifts it: those layers are
    found by comparing the arrays exactly (distances bit for bit, colours, parts), so whatever
    the edit re-evaluated is sent again. None when the voxel sizes or two axes differ.

    Parameters
    ----------
    base : CSDF
        The object the page holds.
    new : CSDF
        The object to send.

    Returns
    -------
    GridDelta or None
        The axis along which the two differ (0 when their shapes are the same) and the layers
        at its start and end that ``new`` shares with ``base``; None when they cannot be
        compared layer by layer.

    Examples
    --------
    A box stretched along x keeps its ends:

    >>> from partscale import edit, shapes
    >>> from partscale.serve import grid_delta
    >>> box = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1)
    >>> longer = edit.apply_recipe(box, edit.Recipe((edit.Edit("x", "30%", "70%", "90%"),)))
    >>> box.shape, longer.shape
    ((17, 12, 12), (19, 12, 12))
    >>> grid_delta(box, longer)
    GridDelta(axis=0, head=8, tail=7)
    """
    if base.voxel_size != new.voxel_size:
        return None
    differ = [a for a in range(3) if base.shape[a] != new.shape[a]]
    if len(differ) > 1:
        return None
    axis = differ[0] if differ else 0
    limit = min(base.shape[axis], new.shape[axis])

    def arrays(c: CSDF, flip: bool) -> list[np.ndarray]:
        # bit patterns: -0.0 is not 0.0 to the page
        out = [np.moveaxis(x, axis, 0) for x in (c.sdf.view(np.uint32), c.rgb, c.parts)]
        return [x[::-1] for x in out] if flip else out

    def same(flip: bool, most: int) -> int:
        a, b = arrays(base, flip), arrays(new, flip)
        return int(_same_layers(a[0], b[0], a[1], b[1], a[2], b[2], most))

    head = same(False, limit)
    tail = same(True, limit - head)
    return GridDelta(axis, head, tail)


def encode_parts(c: CSDF, axis: int = 0, start: int = 0, stop: int | None = None) -> memoryview:
    """``(X, Y, Z)`` int16 little-endian part indices (read-only bytes), C order, -1 where none.

    C order is z fastest. With ``axis``, ``start``, ``stop``: only those layers (as
    :func:`encode_slab`).

    Parameters
    ----------
    c : CSDF
        The object.
    axis : int
        0, 1 or 2: the axis ``start`` and ``stop`` count along.
    start, stop : int
        The layers ``start:stop`` (default: all of them).

    Returns
    -------
    memoryview
        Read-only bytes, 2 a voxel.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.serve import encode_parts
    >>> box = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1)
    >>> len(encode_parts(box)) == 2 * box.sdf.size, set(encode_parts(box, 0, 0, 1).cast("h"))
    (True, {-1})
    """
    box = _layers(axis, start, c.shape[axis] if stop is None else stop)
    return _frozen(np.array(c.parts[box], dtype="<i2", order="C")).cast("B")


@dataclass(frozen=True)
class Encoding:
    """What ``GET /api/grid`` or ``/api/parts`` sends: an object's bytes, whole or as a delta.

    Attributes
    ----------
    csdf : CSDF
        The object encoded (describe the bytes from it, not from the session's current one).
    revision : int
        The session revision that showed it: what the page names as ``?base=`` next time.
    data : memoryview
        Read-only bytes: the whole encoding, or with ``delta`` only its layers ``head : shape[axis] - tail``.
    delta : GridDelta or None
        How the rest follows from the base the page named; None for the whole object.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.serve import EditSession
    >>> box = shapes.box((0, 0, 0), (1, 0.5, 0.5), voxel_size=0.1)
    >>> sent = EditSession("box.csdf.npz", box).encoded("grid")
    >>> sent.revision, sent.delta, len(sent.data)
    (0, None, 12240)
    """

    csdf: CSDF
    revision: int
    data: memoryview
    delta: GridDelta | None = None


def header(c: CSDF) -> dict[str, Any]:
    """JSON description of ``c`` for the page: grid geometry, solid bounds, parts, history."""
    try:
        solid = c.surface_bounds().tolist()
    except InputError:
        solid = None
    parts_info = c.meta.get("parts_info")
    return {
        "shape": list(c.shape),
        "origin": c.origin.tolist(),
        "voxel_size": c.voxel_size,
        "grid_bounds": c.grid_bounds.tolist(),
        "solid_bounds": solid,
        "units": c.meta.get("units", "m"),
        "n_parts": c.n_parts,
        "parts_info": parts_info if isinstance(parts_info, list) else [],
        "history": c.meta.get("history", []),
        "encoding": {
            "version": GRID_FORMAT,
            "grid": "(X, Y, Z) float16 little-endian sdf/voxel_size, then (X, Y, Z, 3) uint8 "
            "sRGB; C order (z fastest); with X-Partscale-Delta only the changed layers",
            "parts": "(X, Y, Z) int16 little-endian, C order (z fastest); -1 = none",
        },
    }


@dataclass(frozen=True)
class PageLimits:
    """What the page can show, as it tells the server with each apply (JSON ``limits``).

    Attributes
    ----------
    max_voxels_per_axis : int or None
        Largest grid along any axis (the page's GPU ``MAX_3D_TEXTURE_SIZE``).
    max_voxels : int or None
        Most voxels in all.

    Examples
    --------
    >>> from partscale.serve import PageLimits
    >>> limits = PageLimits.parse({"max_voxels_per_axis": 16})
    >>> limits
    PageLimits(max_voxels_per_axis=16, max_voxels=None)
    >>> limits.check((20, 8, 8), "apply")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: apply: expected at most 16 voxels per axis (what this page's GPU can show), got 20 × 8 × 8
    """

    max_voxels_per_axis: int | None = None
    max_voxels: int | None = None

    @classmethod
    def parse(cls, obj: Any) -> PageLimits:
        """From ``{"max_voxels_per_axis": N, "max_voxels": M}`` (either may be left out).

        Parameters
        ----------
        obj : dict
            The page's JSON ``limits``.

        Returns
        -------
        PageLimits
            The limits given; None for those left out.

        Raises
        ------
        InputError
            Not such an object, another key, or a value that is not an integer in [2, 2**53].
        """
        names = ("max_voxels_per_axis", "max_voxels")
        if not isinstance(obj, dict) or set(obj) - set(names):
            raise InputError(f"limits: expected an object with keys {names}, got {shown(obj)}")
        # at most 2**53: the page's numbers are JavaScript doubles
        return cls(
            **{name: count(v, f"limits.{name}", lo=2, hi=1 << 53) for name, v in obj.items()}
        )

    def check(self, shape: tuple[int, ...], what: str) -> None:
        """Raise :class:`InputError` unless a grid of ``shape`` fits.

        Parameters
        ----------
        shape : tuple of int
            The grid's (X, Y, Z).
        what : str
            The request, for the message.
        """
        got = " × ".join(map(str, shape))
        if self.max_voxels_per_axis is not None and max(shape) > self.max_voxels_per_axis:
            raise InputError(
                f"{what}: expected at most {self.max_voxels_per_axis} voxels per axis (what "
                f"this page's GPU can show), got {got}"
            )
        if self.max_voxels is not None and math.prod(shape) > self.max_voxels:
            raise InputError(
                f"{what}: expected at most {self.max_voxels} voxels (what this page can show), "
                f"got {got} = {math.prod(shape)}"
            )


class EditSession:
    """One object being edited: current CSDF, undo and redo stacks, where to save.

    All mutating methods take the session lock, so concurrent requests apply one at a time and
    never interleave an apply with an undo.

    Parameters
    ----------
    path : Path
        The file edited: what Save writes beside (:func:`edited_path`) or over.
    csdf : CSDF
        The object as it is now (:meth:`open` loads it from ``path``).

    Examples
    --------
    The shipped table at 32 voxels, stretched along x, undone and saved:

    >>> from partscale import data, edit, ingest, save
    >>> from partscale.serve import EditSession
    >>> path = save(ingest.load(data.table(), res=32), "table.csdf.npz")
    >>> session = EditSession.open("table.csdf.npz")
    >>> session.state()["shape"], session.state()["revision"]
    ([43, 24, 29], 0)
    >>> after = session.apply(edit.Recipe((edit.Edit("x", "30%", "70%", "90%"),)))
    >>> after["shape"], after["revision"], after["can_undo"]
    ([49, 24, 29], 1, True)
    >>> session.undo()["shape"]
    [43, 24, 29]
    >>> session.save().name
    'table.edited.csdf.npz'
    """

    def __init__(self, path: Path, csdf: CSDF):
        self.path = Path(path)
        self.current = csdf
        self.undo_stack: list[CSDF] = []
        self.redo_stack: list[CSDF] = []
        self.revision = 0
        self.saved_revision = 0
        self.lock = threading.Lock()
        self._cache: OrderedDict[tuple, tuple] = OrderedDict()
        # the objects of the last few revisions, so a page may name the one it shows as the
        # base of a delta (an undo's revision holds an older object: revisions are not objects)
        self._shown: OrderedDict[int, CSDF] = OrderedDict({0: csdf})

    @classmethod
    def open(cls, path: str | Path) -> EditSession:
        """A session on the ``.csdf.npz`` at ``path`` (loaded and validated now)."""
        path = Path(path)
        return cls(path, load(path))

    # -- state ----------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """Header of the current object plus the session's own state, all of one revision."""
        with self.lock:
            snap = self._snapshot()
        return self._describe(snap)

    def _snapshot(self) -> tuple[CSDF, dict[str, Any]]:
        # call with the lock held: the object and the session's state of one revision
        return self.current, {
            "revision": self.revision,
            "can_undo": bool(self.undo_stack),
            "can_redo": bool(self.redo_stack),
            "unsaved": self.revision != self.saved_revision,
        }

    def _describe(self, snap: tuple[CSDF, dict[str, Any]]) -> dict[str, Any]:
        # outside the lock: the CSDF is immutable, so its header is that revision's
        c, own = snap
        h = header(c)
        h.update(own, name=self.path.name, save_as=edited_path(self.path).name)
        return h

    def encoded(self, kind: str, base: int | None = None) -> Encoding:
        """The current object encoded (``'grid'``: :func:`encode_grid`, or ``'parts'``).

        ``base``: the revision whose object the page holds; when the session still knows it
        and the two differ along one axis only (:func:`grid_delta`), only the changed layers
        are encoded. Otherwise, or for an unknown base, the whole object.
        """
        if kind not in ("grid", "parts"):
            raise InputError(f"encoding: expected 'grid' or 'parts', got {kind!r}")
        with self.lock:
            c, rev = self.current, self.revision
            old = self._shown.get(base) if base is not None else None
        delta = None if old is None else self._delta(old, c)
        if delta is None:
            whole = encode_grid if kind == "grid" else encode_parts
            return Encoding(c, rev, self._cached((kind, c), whole, c))
        stop = c.shape[delta.axis] - delta.tail
        layers = encode_slab if kind == "grid" else encode_parts
        return Encoding(c, rev, layers(c, delta.axis, delta.head, stop), delta)

    def _delta(self, a: CSDF, b: CSDF) -> GridDelta | None:
        # grid_delta is symmetric: an undo's delta is its apply's, found once
        pair = (a, b) if id(a) <= id(b) else (b, a)
        return self._cached(("delta", *pair), grid_delta, *pair)

    def _cached(self, key: tuple, fn: Callable[..., T], *args: Any) -> T:
        # Encoding a 256³ grid takes a few hundred ms: keep the last few results, so a second
        # fetch, an undo or a redo costs nothing. Keyed by the CSDF objects themselves (they
        # are immutable; the entry holds them, so their ids cannot be reused while cached).
        ident = tuple(id(k) if isinstance(k, CSDF) else k for k in key)
        with self.lock:
            hit = self._cache.get(ident)
            if hit is not None:
                self._cache.move_to_end(ident)
                return hit[1]
        value = fn(*args)
        with self.lock:
            self._cache[ident] = (key, value)
            while len(self._cache) > CACHED_ENCODINGS:
                self._cache.popitem(last=False)
        return value

    def _record(self) -> None:
        # call with the lock held, after the current object or the revision changed
        self._shown[self.revision] = self.current
        while len(self._shown) > SHOWN_REVISIONS:
            self._shown.popitem(last=False)

    def _push(self, new: CSDF) -> None:
        self.undo_stack.append(self.current)
        del self.undo_stack[:-MAX_UNDO]
        while len(self.undo_stack) > 1 and sum(map(_nbytes, self.undo_stack)) > UNDO_BYTES:
            del self.undo_stack[0]
        self.redo_stack.clear()
        self.current = new
        self.revision += 1
        self._record()

    # -- edits ----------------------------------------------------------------------------
    def apply(
        self,
        recipe: Any,
        *,
        limits: PageLimits | None = None,
        progress: ProgressCallback | None = None,
    ) -> dict[str, Any]:
        """Bake ``recipe`` (a Recipe or its JSON dict) into the current object (undoable).

        With ``limits``, a recipe whose result the page could not show is refused
        (:class:`InputError`) before anything is computed (its shape predicted by
        :func:`~partscale.edit.recipe_shape`), and the result is checked again before it is
        kept, so the session never holds an object the page cannot show. Returns the state
        (:meth:`state`) of the revision this apply made, whatever lands after it, with
        ``notes``: what the edit stage changed from what was asked
        (:func:`~partscale.edit.describe_changes`; whole-voxel destinations, cut slivers) and
        the knobs or handles a stretch zone held (:func:`~partscale.zones.feature_notes`).
        """
        from ..edit import Recipe, apply_recipe, describe_changes, recipe_shape
        from ..zones import feature_notes, resolve_counts

        units = self.current.meta.get("units")  # for positions with a unit ("30cm")
        parsed = recipe if isinstance(recipe, Recipe) else Recipe.parse(recipe, units=units)
        with self.lock:
            parsed, _ = resolve_counts(self.current, parsed)  # "copies": "+1" on this object
            if limits is not None:
                limits.check(recipe_shape(self.current, parsed), "apply")
            new = apply_recipe(self.current, parsed, progress=progress)
            if limits is not None:
                limits.check(new.shape, "apply")
            old = self.current
            self._push(new)
            snap = self._snapshot()
        # the page asks next for what changed since the object it shows: find it while still
        # in the worker thread
        self._delta(old, new)
        entries = new.meta.get("history", [])[-len(parsed.edits) :]
        notes = describe_changes(entries, new) + feature_notes(old, parsed)
        return {**self._describe(snap), "notes": notes}

    def undo(self) -> dict[str, Any] | None:
        """Restore the object before the last apply exactly (the same arrays); None if none.

        Returns the state of the revision this undo made.
        """
        return self._step(self.undo_stack, self.redo_stack)

    def redo(self) -> dict[str, Any] | None:
        """Re-apply the last undone edit (the same arrays); None if none (else as undo)."""
        return self._step(self.redo_stack, self.undo_stack)

    def _step(self, source: list[CSDF], other: list[CSDF]) -> dict[str, Any] | None:
        with self.lock:
            if not source:
                return None
            other.append(self.current)
            self.current = source.pop()
            self.revision += 1
            self._record()
            snap = self._snapshot()
        return self._describe(snap)

    # -- output ---------------------------------------------------------------------------
    def save(self, *, overwrite: bool = False, revision: int | None = None) -> Path:
        """Write the current object to ``NAME.edited.csdf.npz``, or over the input file.

        ``revision``: the one the page shows; another current revision is refused
        (:class:`InputError`), so what is saved is what the user saw.
        """
        with self.lock:
            c, rev = self.current, self.revision
        if revision is not None and revision != rev:
            raise InputError(
                f"save: expected the object shown (revision {revision}), got revision {rev} "
                "on the server; reload the page to see it"
            )
        target = self.path if overwrite else edited_path(self.path)
        save(c, target)
        with self.lock:
            self.saved_revision = rev
        return target

    def export(self, kind: str) -> tuple[bytes, str, str]:
        """Export the current object; returns ``(data, filename, media type)``.

        ``kind`` is ``'mesh'`` (binary glTF with vertex colours) or ``'texture'`` (the 3D
        texture file written by :func:`partscale.export.export_texture`).
        """
        from .. import export as export_mod

        with self.lock:
            c = self.current
        stem = edited_path(self.path).name[: -len(SUFFIX)]
        if kind == "mesh":
            name, media = f"{stem}.glb", "model/gltf-binary"
            writer: Callable[[CSDF, Path], object] = export_mod.export_mesh
        elif kind == "texture":
            name, media = f"{stem}{TEXTURE_SUFFIX}", "application/octet-stream"
            writer = export_mod.export_texture
        else:
            raise InputError(f"export: expected 'mesh' or 'texture', got {kind!r}")
        try:
            tmp_dir = tempfile.TemporaryDirectory(prefix="partscale-export-")
        except OSError as exc:  # atomic_path covers the file itself, not this folder
            raise InputError(
                f"export: expected a writable temporary folder, got {exc.strerror or exc}"
            ) from None
        with tmp_dir as tmp:
            out = Path(tmp) / name
            writer(c, out)
            files = sorted(p for p in Path(tmp).iterdir() if p.is_file())
            if len(files) == 1:
                return files[0].read_bytes(), files[0].name, media
            return _zip(files), f"{stem}.texture.zip", "application/zip"
        raise AssertionError("unreachable")  # pragma: no cover


def _nbytes(c: CSDF) -> int:
    return c.sdf.nbytes + c.rgb.nbytes + c.parts.nbytes


#: Suffix asked of export_texture; it writes the format its suffix names.
TEXTURE_SUFFIX = ".nrrd"


def _zip(files: list[Path]) -> bytes:
    # export_texture may write a sidecar (e.g. a JSON header next to raw data): ship them together.
    import io
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for f in files:
            z.write(f, f.name)
    return buf.getvalue()
