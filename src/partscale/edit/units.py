"""Lengths and positions a designer types: ``2.1``, ``210cm``, ``2100mm``, ``8in``, ``+20cm``,
``120%``, ``=``.

The one home of the unit table (:data:`SUFFIXES`): recipe positions
(:func:`partscale.edit.parse_position`), ``scale``'s options, ``fit``'s sizes and the importer's
``units`` (:func:`partscale.ingest.load`) all read it. Bare numbers are in the object's units
(``meta['units']``; metres for glTF). Lengths with a unit need an object in metres: where its
units are anything else (an SDF grid, an OBJ of unknown scale), a suffixed length is refused
rather than guessed.
"""

from __future__ import annotations

import math
import re

from ..errors import InputError

#: Metres per unit suffix: the units a length may carry and a mesh may be imported from.
SUFFIXES = {"mm": 0.001, "cm": 0.01, "m": 1.0, "in": 0.0254}

MAX_GROWTH = 1e9
"""Most a target size may be, as a multiple of the current extent: beyond it a size is a
mistake whose grid overflows the counts made of it (below it, the memory guard says what the
size would need)."""

_NUMBER = r"[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?"
_LENGTH = re.compile(rf"^(?P<sign>[-+]?)(?P<num>{_NUMBER})\s*(?P<unit>[a-zA-Z%]*)$")


def _split(spec: str, what: str) -> tuple[str, float, str]:
    m = _LENGTH.match(spec.strip())
    if spec.strip().lstrip("+-").rstrip("%").lower() in ("inf", "infinity", "nan"):
        raise InputError(f"{what}: expected a finite number, got {spec!r}")
    if m is None:
        raise InputError(
            f"{what}: expected a number with an optional unit or % (2.1, 210cm, 2100mm, 8in, "
            f"+20cm, 120%), got {spec!r}"
        )
    value = float(m["num"])
    if not math.isfinite(value):
        kind = "percentage" if m["unit"] == "%" else "number"
        raise InputError(f"{what}: expected a finite {kind}, got {spec!r}")
    return m["sign"], value, m["unit"].lower()


def has_unit(spec: str) -> bool:
    """Whether ``spec`` reads as a number followed by a unit word (``'30cm'``, ``'2ft'``)."""
    m = _LENGTH.match(spec.strip())
    return m is not None and m["unit"] not in ("", "%")


def _to_object_units(value: float, unit: str, units: str | None, spec: str, what: str) -> float:
    if unit == "":
        return value
    if unit not in SUFFIXES:
        raise InputError(
            f"{what}: expected a unit of {', '.join(SUFFIXES)} or %, got {unit!r} in {spec!r}"
        )
    if units != "m":
        raise InputError(
            f"{what}: expected a bare number (the object's units are {units or 'unknown'}, not "
            f"metres, so {unit} cannot be converted), got {spec!r}"
        )
    return value * SUFFIXES[unit]


def parse_length(spec: str | float, *, units: str | None, what: str = "length") -> float:
    """Parse a signed length in object units from ``'20cm'``, ``'-5cm'`` or ``0.2`` (no ``%``).

    Parameters
    ----------
    spec : str or float
        The length; a unit suffix (:data:`SUFFIXES`) only for an object in metres.
    units : str or None
        The object's units.
    what : str
        Its name in the :class:`~partscale.errors.InputError`.

    Returns
    -------
    float
        The length in object units.

    Examples
    --------
    >>> from partscale.edit import parse_length
    >>> parse_length("20cm", units="m"), parse_length("-5cm", units="m"), parse_length(0.2, units=None)
    (0.2, -0.05, 0.2)
    """
    if isinstance(spec, int | float) and not isinstance(spec, bool):
        if not math.isfinite(spec):
            raise InputError(f"{what}: expected a finite length, got {spec!r}")
        return float(spec)
    sign, value, unit = _split(str(spec), what)
    if unit == "%":
        raise InputError(f"{what}: expected a length (2.1, 20cm), got a percentage {spec!r}")
    v = _to_object_units(value, unit, units, str(spec), what)
    return -v if sign == "-" else v


def parse_size(spec: str | float, *, extent: float, units: str | None, what: str = "size") -> float:
    """Parse a target length along an axis (object units) for ``fit``.

    ``'='`` keeps ``extent``; ``'2.1'``, ``'210cm'``, ``'2100mm'`` are absolute; ``'+20cm'`` and
    ``'-5cm'`` change it; ``'120%'`` is a percentage of ``extent``.

    Parameters
    ----------
    spec : str or float
        The target.
    extent : float
        The current extent along the axis.
    units : str or None
        The object's units: a unit suffix is taken only for ``'m'``, as by :func:`parse_length`.
    what : str
        Its name in errors, as for :func:`parse_length`.

    Returns
    -------
    float
        The target length, > 0.

    Raises
    ------
    InputError
        A target that is not positive, or a unit the object's units do not allow.

    Examples
    --------
    >>> from partscale.edit import parse_size
    >>> [parse_size(s, extent=2.0, units="m") for s in ("=", "120%", "+20cm", "210cm")]
    [2.0, 2.4, 2.2, 2.1]
    """
    s = str(spec).strip()
    if s == "=":
        return float(extent)
    sign, value, unit = _split(s, what)
    if unit == "%":
        if sign:
            raise InputError(f"{what}: expected a percentage like 120%, got {spec!r}")
        target = extent * value / 100.0
    else:
        v = _to_object_units(value, unit, units, s, what)
        target = extent + v if sign == "+" else extent - v if sign == "-" else v
    if not target > 0:
        raise InputError(f"{what}: expected a positive length, got {spec!r} ({target:.6g})")
    if not target <= MAX_GROWTH * extent:  # finite but huge: no grid holds it, int() overflows
        raise InputError(
            f"{what}: expected at most {MAX_GROWTH:g} times the current extent "
            f"({MAX_GROWTH * extent:.4g}), got {spec!r} ({target:.4g})"
        )
    return float(target)
