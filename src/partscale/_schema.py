"""Typed readers of structured input: each value checked before numpy, pathlib or ``int()``.

Every reader of structured input (intrinsics and views JSON, batch manifests and status rows,
recipes, editor request bodies, option text such as ``--box``) takes its values through these
functions, so each value is checked once for its type, range, size and finiteness, and a bad
one fails as an :class:`~partscale.errors.InputError` of one line that names it (``what``) and
says what was expected and what arrived. JSON text itself is parsed by
:func:`partscale._files.parse_json` (size, nesting depth, digits, finite numbers).

Numbers are Python or numpy reals, never booleans (``true`` is not 1 in a recipe); text is
taken where ``text=True`` (CSV cells and command-line words).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError, shown

MAX_TEXT = 4096
"""Longest string a structured input may hold where no other bound is stated (a path, a name)."""
MAX_DIGITS = 30
"""Most digits of an integer given as text (int64 has 19)."""
MAX_ITEMS = 100_000
"""Most items of a list read from structured input where no other bound is stated."""


def _range_text(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    if lo is not None and hi is not None:
        return f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
    if lo is not None:
        return f"{'>' if lo_open else '>='} {lo:g}"
    if hi is not None:
        return f"{'<' if hi_open else '<='} {hi:g}"
    return ""


def _in_range(x: float, lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> bool:
    if lo is not None and (x <= lo if lo_open else x < lo):
        return False
    return not (hi is not None and (x >= hi if hi_open else x > hi))


def number(
    value: Any,
    what: str,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
    text: bool = False,
) -> float:
    """A finite real number within ``[lo, hi]`` (bounds open where asked), as a float.

    Parameters
    ----------
    value : object
        The value as read: a number, or with ``text`` a string holding one.
    what : str
        Its name in the error message.
    lo, hi : float, optional
        Bounds, inclusive unless ``lo_open`` / ``hi_open``.
    text : bool
        Whether a string holding a number is accepted (CSV cells, option words).

    Returns
    -------
    float
        ``value`` as a float, within the bounds.

    Examples
    --------
    >>> from partscale._schema import number
    >>> number(2, "fx", lo=0, lo_open=True), number(" 1.5", "seconds", text=True)
    (2.0, 1.5)
    >>> number([500], "fx")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: fx: expected a number, got [500]
    """
    bounds = _range_text(lo, hi, lo_open, hi_open)
    expected = f"a finite number {bounds}".rstrip() if bounds else "a finite number"
    x: float
    if isinstance(value, bool | np.bool_):
        raise InputError(f"{what}: expected a number, got {shown(value)}")
    if isinstance(value, numbers.Real):
        try:
            x = float(value)
        except OverflowError:  # an int beyond the float range
            raise InputError(f"{what}: expected {expected}, got {shown(value)}") from None
    elif text and isinstance(value, str) and len(value) <= MAX_TEXT:
        try:
            x = float(value.strip())
        except ValueError:
            raise InputError(f"{what}: expected a number, got {shown(value)}") from None
    else:
        raise InputError(f"{what}: expected a number, got {shown(value)}")
    if not math.isfinite(x) or not _in_range(x, lo, hi, lo_open, hi_open):
        raise InputError(f"{what}: expected {expected}, got {shown(value)}")
    return x


def integer(
    value: Any, what: str, *, lo: int | None = None, hi: int | None = None, text: bool = False
) -> int:
    """A whole number within ``[lo, hi]``, as an int.

    Integers (Python or numpy) and, with ``text``, strings of digits with an optional sign;
    never floats (``1.5``, ``nan``), booleans or digit strings longer than :data:`MAX_DIGITS`.

    Examples
    --------
    >>> from partscale._schema import integer
    >>> integer(3, "attempts", lo=0), integer("12", "attempts", lo=0, text=True)
    (3, 12)
    >>> integer("1.5", "attempts", lo=0, text=True)
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: attempts: expected a whole number >= 0, got '1.5'
    """
    expected = f"a whole number {_range_text(lo, hi, False, False)}".rstrip()
    n: int | None = None
    if isinstance(value, bool | np.bool_):
        n = None
    elif isinstance(value, int | np.integer):
        n = int(value)
    elif text and isinstance(value, str):
        s = value.strip()
        digits = s[1:] if s[:1] in "+-" else s
        if digits.isascii() and digits.isdigit() and len(digits) <= MAX_DIGITS:
            n = int(s)
    if n is None or not _in_range(n, lo, hi, False, False):
        raise InputError(f"{what}: expected {expected}, got {shown(value)}")
    return n


def string(
    value: Any,
    what: str,
    *,
    max_len: int = MAX_TEXT,
    empty: bool = False,
    choices: Sequence[str] | None = None,
) -> str:
    """A string of at most ``max_len`` characters without control characters (NUL, newline).

    With ``choices``, one of them (compared as given). ``empty`` allows ``""``.

    Examples
    --------
    >>> from partscale._schema import string
    >>> string("d.png", "depth")
    'd.png'
    >>> string(5, "depth")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: depth: expected a string, got 5
    """
    if not isinstance(value, str):
        raise InputError(f"{what}: expected a string, got {shown(value)}")
    if len(value) > max_len:
        raise InputError(f"{what}: expected at most {max_len} characters, got {len(value)}")
    if not value and not empty:
        raise InputError(f"{what}: expected a non-empty string, got ''")
    if any(ord(ch) < 32 or ord(ch) == 127 for ch in value):
        raise InputError(f"{what}: expected text without control characters, got {shown(value)}")
    if choices is not None and value not in choices:
        raise InputError(f"{what}: expected one of {', '.join(choices)}, got {shown(value)}")
    return value


def path(value: Any, what: str, *, base: Path | None = None) -> Path:
    """A file path from a string (no NUL or control characters), relative to ``base``.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale._schema import path
    >>> path("d.png", "depth", base=Path("scans"))
    PosixPath('scans/d.png')
    """
    p = Path(string(value, what))
    return base / p if base is not None and not p.is_absolute() else p


def mapping(
    value: Any,
    what: str,
    *,
    keys: Sequence[str] | None = None,
    required: Sequence[str] = (),
) -> dict[str, Any]:
    """A JSON object (dict with string keys); with ``keys``, no other key; ``required`` present.

    Examples
    --------
    >>> from partscale._schema import mapping
    >>> mapping({"fx": 1}, "intrinsics", keys=("fx", "fy"))
    {'fx': 1}
    >>> mapping([1], "intrinsics")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: intrinsics: expected an object, got [1]
    """
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise InputError(f"{what}: expected an object, got {shown(value)}")
    if keys is not None:
        unknown = sorted(set(value) - set(keys))
        if unknown:
            raise InputError(f"{what}: unknown key(s) {shown(unknown)}; keys are {', '.join(keys)}")
    missing = [k for k in required if k not in value]
    if missing:
        raise InputError(
            f"{what}: expected key(s) {', '.join(missing)}, got {shown(sorted(value))}"
        )
    return dict(value)


def sequence(
    value: Any, what: str, *, length: int | None = None, lo: int = 0, hi: int = MAX_ITEMS
) -> list[Any]:
    """A list (or tuple) of ``length`` items, or of ``lo`` to ``hi`` items.

    Examples
    --------
    >>> from partscale._schema import sequence
    >>> sequence((1, 2), "zone", length=2)
    [1, 2]
    """
    if not isinstance(value, list | tuple):
        raise InputError(f"{what}: expected a list, got {shown(value)}")
    if length is not None and len(value) != length:
        raise InputError(f"{what}: expected a list of {length}, got {shown(value)}")
    if not lo <= len(value) <= hi:
        raise InputError(f"{what}: expected a list of {lo} to {hi} items, got {len(value)}")
    return list(value)


def matrix(
    value: Any,
    what: str,
    shape: tuple[int, ...],
    *,
    lo: float | None = None,
    hi: float | None = None,
) -> np.ndarray:
    """A float64 array of ``shape`` from nested lists of that shape or one flat list, each item
    a finite number (:func:`number`) in ``[lo, hi]``; checked before numpy sees it.

    Examples
    --------
    >>> from partscale._schema import matrix
    >>> matrix([[1, 0], [0, 1]], "K", (2, 2)).tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    >>> matrix([1, 0, 0, [1]], "K", (2, 2))
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: K[3]: expected a number, got [1]
    """
    if isinstance(value, np.ndarray):
        value = value.tolist() if value.size <= MAX_ITEMS else value
    size = math.prod(shape)
    flat: list[float] = []

    def walk(v: Any, dims: tuple[int, ...], where: str) -> None:
        if not dims:
            flat.append(number(v, where, lo=lo, hi=hi))
            return
        items = sequence(v, where, length=dims[0])
        for i, item in enumerate(items):
            walk(item, dims[1:], f"{where}[{i}]")

    if isinstance(value, list | tuple) and len(value) == size and size != shape[0]:
        walk(value, (size,), what)  # one flat list
    else:
        if not isinstance(value, list | tuple) or len(value) != shape[0]:
            raise InputError(
                f"{what}: expected {' x '.join(map(str, shape))} numbers (nested or flat), got "
                f"{shown(value)}"
            )
        walk(value, shape, what)
    return np.asarray(flat, np.float64).reshape(shape)


def numbers_text(
    text: str, n: int, what: str, *, lo: float | None = None, hi: float | None = None
) -> list[float]:
    """``n`` finite numbers in ``[lo, hi]`` from option text (``"0,0,10,10"`` or space-separated).

    Examples
    --------
    >>> from partscale._schema import numbers_text
    >>> numbers_text("0, 0,10 10", 4, "box")
    [0.0, 0.0, 10.0, 10.0]
    """
    parts = text.replace(",", " ").split()
    if len(parts) != n:
        raise InputError(
            f"{what}: expected {n} numbers separated by commas (or spaces, in quotes), "
            f"got {shown(text)}"
        )
    return [number(p, what, lo=lo, hi=hi, text=True) for p in parts]


def whole(x: float, what: str, *, limit: float = 2.0**53) -> int:
    """``round(x)`` for a computed float, refusing NaN, infinities and magnitudes over ``limit``
    (where ``int()`` would raise or make a number no grid could hold).

    Examples
    --------
    >>> from partscale._schema import whole
    >>> whole(2.6, "copies")
    3
    """
    if not (math.isfinite(x) and abs(x) <= limit):
        raise InputError(f"{what}: expected a count of at most {limit:.3g}, got {x:.6g}")
    return round(x)
