"""Options: one home for checking the option vocabulary every entry point shares.

The command line, recipes, batch manifests, the editor's server and the library functions take
the same options (``res``, yes/no switches, counts, seconds, memory sizes, choices and lists of
choices); each is checked here, once, at the public boundary, and a bad value fails as an
:class:`~partscale.errors.InputError` of one line that names the option (``what``) and says what
was expected and what arrived. Values may come typed (the library, JSON) or, with ``text=True``,
as words (CSV cells, environment variables): ``"64"``, ``"yes"``, ``"off"``, ``"glb,png"``.

:func:`keyword_options` makes an unknown keyword option of a public function fail naming the
ones that exist.
"""

from __future__ import annotations

import functools
import inspect
import math
import numbers
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from .errors import InputError, shown

F = TypeVar("F", bound=Callable)

MIN_RES = 16
"""Smallest ``res``: fewer voxels hold no part."""
MAX_RES = 16384
"""Largest ``res``: far beyond any memory (the guard refuses much less), bounded so that
grid arithmetic never overflows int64."""
OFF_WORDS = ("", "0", "false", "no", "none", "off")
"""Words that switch an option off (a manifest cell ``none``, ``--export none``)."""
ON_WORDS = ("1", "true", "yes", "on")
"""Words that switch a yes/no option on."""
MAX_SECONDS = 1e7
"""Most seconds a time limit may be (about 115 days)."""
MAX_MEMORY = 1 << 50
"""Largest memory size (1024 TiB): beyond any machine."""
_UNITS = {"k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}


def keyword_options(func: F) -> F:
    """Make an unknown keyword option fail with the list of the ones that exist.

    Python's own message ("unexpected keyword argument") does not say what is allowed.
    """
    sig = inspect.signature(func)
    known = [
        n
        for n, p in sig.parameters.items()
        if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and not n.startswith("_")
    ]

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        unknown = [k for k in kwargs if k not in sig.parameters]
        if unknown:
            raise TypeError(
                f"{func.__name__}() got unknown option(s) {', '.join(map(repr, unknown))}; "
                f"options are: {', '.join(known)}"
            )
        return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]  # wraps() keeps func's signature; mypy cannot see it


def is_off(value: Any) -> bool:
    """Whether ``value`` switches an optional option off: None or one of :data:`OFF_WORDS`.

    Examples
    --------
    >>> from partscale._options import is_off
    >>> is_off(None), is_off(" None"), is_off("fast")
    (True, True, False)
    """
    return value is None or (isinstance(value, str) and value.strip().lower() in OFF_WORDS)


def check_res(res: Any, what: str, *, text: bool = False) -> int:
    """Validate a resolution (an int in [16, :data:`MAX_RES`]) before any arithmetic with it.

    Parameters
    ----------
    res : int or float or str
        Voxels along the object's longest side; a float must be whole; with ``text``, a string
        holding an integer.
    what : str
        Its name in the :class:`~partscale.errors.InputError`.
    text : bool
        Whether a string is read (a CSV cell).

    Returns
    -------
    int
        The resolution.

    Examples
    --------
    >>> from partscale.ingest import check_res
    >>> check_res(64, "res"), check_res(" 32", "res", text=True)
    (64, 32)
    >>> check_res(8, "res")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: res: expected res in [16, 16384], got 8
    """
    if text and isinstance(res, str):
        try:
            res = int(res.strip())
        except ValueError:
            pass  # refused below, as given
    if isinstance(res, float) and math.isfinite(res) and res.is_integer():
        res = int(res)
    if isinstance(res, bool) or not isinstance(res, numbers.Integral):
        raise InputError(f"{what}: expected an integer res, got {shown(res)}", params=("res",))
    res = int(res)
    if not MIN_RES <= res <= MAX_RES:
        raise InputError(
            f"{what}: expected res in [{MIN_RES}, {MAX_RES}], got {shown(res, 24)}", params=("res",)
        )
    return res


def yes_no(value: Any, what: str, *, text: bool = False) -> bool:
    """A yes/no option: ``True``/``False`` or, with ``text``, one of :data:`ON_WORDS` or
    :data:`OFF_WORDS` (any case).

    Examples
    --------
    >>> from partscale._options import yes_no
    >>> yes_no(True, "square"), yes_no("No", "square", text=True)
    (True, False)
    >>> yes_no("maybe", "square", text=True)
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: square: expected true or false, got 'maybe'
    """
    if text and isinstance(value, str):
        word = value.strip().lower()
        value = False if word in OFF_WORDS else True if word in ON_WORDS else value
    if not isinstance(value, bool):
        raise InputError(f"{what}: expected true or false, got {shown(value)}")
    return value


def count(value: Any, what: str, *, lo: int = 1, hi: int | None = None) -> int:
    """A count (workers, retries, parts): an int (never a bool or a float) in ``[lo, hi]``.

    Examples
    --------
    >>> from partscale._options import count
    >>> count(2, "workers"), count(0, "retries", lo=0)
    (2, 0)
    >>> count(1.5, "workers")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: workers: expected an integer >= 1, got 1.5
    """
    n = int(value) if isinstance(value, numbers.Integral) and not isinstance(value, bool) else None
    if n is None or n < lo or (hi is not None and n > hi):
        bound = f"in [{lo}, {hi}]" if hi is not None else f">= {lo}"
        raise InputError(f"{what}: expected an integer {bound}, got {shown(value)}")
    return n


def seconds(value: Any, what: str, *, text: bool = False) -> float:
    """A time limit: finite seconds in (0, :data:`MAX_SECONDS`].

    Examples
    --------
    >>> from partscale._options import seconds
    >>> seconds(90, "timeout")
    90.0
    >>> seconds(0, "timeout")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: timeout: expected a finite number in (0, 1e+07], got 0
    """
    from . import _schema

    return _schema.number(value, what, lo=0, hi=MAX_SECONDS, lo_open=True, text=text)


def memory_size(value: Any, what: str = "memory") -> int:
    """A memory size in bytes, from ``'2GiB'``, ``'500M'``, ``'1.5G'`` or a number of bytes.

    A number with an optional K, M, G or T (powers of 1024, with or without ``iB``/``B``), above
    0 and at most :data:`MAX_MEMORY`.

    Examples
    --------
    >>> from partscale._options import memory_size
    >>> memory_size("2GiB"), memory_size("500M"), memory_size(4096)
    (2147483648, 524288000, 4096)
    >>> memory_size("lots")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: memory: expected a size such as 4GiB or 500MiB, got 'lots'
    """
    from . import _schema

    s = str(value)[:64].strip().lower().removesuffix("b").removesuffix("i")
    mult = _UNITS.get(s[-1:], 1)
    try:
        if isinstance(value, int | float) and not isinstance(value, bool):
            n = _schema.number(value, what)
        else:
            n = _schema.number(s[:-1] if mult > 1 else s, what, text=True) * mult
    except InputError:
        n = -1.0
    if not n > 0:
        raise InputError(f"{what}: expected a size such as 4GiB or 500MiB, got {shown(value)}")
    if n > MAX_MEMORY:
        raise InputError(f"{what}: expected at most {MAX_MEMORY >> 40} TiB, got {shown(value)}")
    return int(n)


def preset(value: Any, what: str, allowed: Sequence[int], *, unit: str = "") -> int | None:
    """None, or one of the whole numbers ``allowed`` (a size from a fixed list), as an int;
    ``unit`` names what they count in the error (``"texels"``).

    Examples
    --------
    >>> from partscale._options import preset
    >>> preset(64, "size", (32, 64)), preset(None, "size", (32, 64))
    (64, None)
    >>> preset(48, "atlas", (32, 64), unit="texels")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: atlas: expected one of 32, 64 texels, got 48
    """
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value not in allowed:
        listed = ", ".join(map(str, allowed)) + (f" {unit}" if unit else "")
        raise InputError(f"{what}: expected one of {listed}, got {value!r}")
    return int(value)


def choice(value: Any, what: str, choices: Sequence[str]) -> str:
    """One of ``choices``, compared without case or surrounding blanks; returned as listed.

    Examples
    --------
    >>> from partscale._options import choice
    >>> choice(" Ray", "engine", ("local", "ray"))
    'ray'
    >>> choice("spark", "engine", ("local", "ray"))
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: engine: expected one of local, ray, got 'spark'
    """
    word = value.strip().lower() if isinstance(value, str) else None
    if word not in choices:
        raise InputError(f"{what}: expected one of {', '.join(choices)}, got {shown(value)}")
    return str(word)


def choices(value: Any, what: str, allowed: Sequence[str], *, noun: str = "values") -> list[str]:
    """Several of ``allowed``: a list, or text separated by commas (``"glb, png"``; an
    :data:`OFF_WORDS` word: none); each once, in the order given, a leading dot dropped.
    ``noun`` names them in the error (``"formats"``).

    Examples
    --------
    >>> from partscale._options import choices
    >>> choices("glb,.PNG,glb", "export", ("csdf", "glb", "png")), choices("none", "export", ())
    (['glb', 'png'], [])
    >>> choices("stl", "export", ("csdf", "glb"), noun="formats")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: export: expected formats among csdf, glb, got 'stl'
    """
    if not isinstance(value, str | list | tuple):
        raise InputError(f"{what}: expected {noun} among {', '.join(allowed)}, got {shown(value)}")
    if isinstance(value, str):
        value = [] if value.strip().lower() in OFF_WORDS else value.split(",")
    out: list[str] = []
    for item in value:
        word = str(item).strip().lower().lstrip(".")
        if word not in allowed:
            raise InputError(f"{what}: expected {noun} among {', '.join(allowed)}, got {word!r}")
        if word not in out:
            out.append(word)
    return out
