"""Edit recipes: the one schema shared by the library, the CLI and the web editor.

A recipe is a JSON object ``{"version": 1, "edits": [EDIT, ...]}``; edits apply in order, each to
the result of the previous one, but **all positions in one recipe refer to the input object as
given** (zones are drawn on the original): before edit ``k`` applies, its planes are carried
through the edits before it on the same axis (:func:`forward_coordinate`: a plane beyond an
earlier zone moves with that zone's end, one inside it follows its stretch, or its first copy for
tile), and its destination keeps its change ``DEST - END``. An EDIT is::

    {"axis": "x" | "y" | "z",
     "zone": [START, END],          # the slab to change, START < END
     "to": DEST,                    # where END goes; DEST > START (tile: DEST == START removes
                                    # the zone); DEST < END shrinks
     "mode": "stretch" | "tile" | "global"}

or a zone that is not a slab across an axis (:mod:`partscale.edit.warp`)::

    {"radial": {"axis": "y", "center": [X, Z], "sides": 0, "phase": 0},
     "zone": [R0, R1], "to": R}        # the annulus R0..R1 about the axis becomes R0..R
    {"normal": [NX, NY, NZ], "zone": [S0, S1], "to": S}   # the slab S0 <= p . n <= S1
    {"helix": {"center": [X, Z], "angle": DEG, "rise": R, "cut": Y}, "copies": N}
                                       # N more steps of a spiral stair (above Y turns and rises)
    {"rotation": {"center": [X, Z], "angle": DEG, "phase": DEG, "count": K, "closed": true,
                  "hub": R0, "radius": R1, "span": [Y0, Y1]}, "copies": N}
                                       # N more elements of a ring (or arc) about the vertical

Their positions are lengths (numbers or with a unit, no ``%``) on the object they apply to; a
recipe holding one holds no zone across an axis it moves content along. And a count::

    {"axis": "x", "copies": "+1"}     # one more element (seat, door, shelf row, step)

resolved on the object into the zone edits that make it (:func:`partscale.zones.resolve_counts`)
before the recipe applies.

Positions are numbers in the object's units (metres for glTF) or strings with a ``%`` suffix:
percent of the object's extent along that axis, measured on the solid's bounding box
(``"0%"`` = its min, ``"100%"`` = its max) of the recipe's input; or lengths with a unit
(``"30cm"``, ``"2.1m"``, ``"300mm"``, as the CLI's ``--zone``/``--to`` read them), converted to
object units when the recipe is parsed for an object in metres (``units='m'``) and refused
otherwise.

The 1D maps below (world coordinate after the edit -> world coordinate before) define the modes;
the Python resampler and the web editor's shader both implement exactly these.
"""

from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .. import _schema
from .._files import read_json
from ..errors import InputError, shown
from .units import has_unit, parse_length

AXES = ("x", "y", "z")
MODES = ("stretch", "tile", "global")
RECIPE_VERSION = 1

Position = float | str
Mode = Literal["stretch", "tile", "global"]

#: Most edits one recipe may hold. Each edit's planes are carried through the earlier ones on
#: its axis and every edit re-evaluates the grid, so a recipe's cost grows with its length;
#: real recipes hold a few (the editor sends at most 4), hostile ones thousands.
MAX_EDITS = 64
#: Most copies a count edit (steps, elements) may add or remove: beyond it no grid could hold
#: the result, and the count is refused before anything multiplies by it.
MAX_COPIES = 100_000


def _ref(name: str) -> dict[str, Any]:
    """A JSON Schema reference to ``$defs/NAME`` of :data:`JSON_SCHEMA`."""
    return {"$ref": f"#/$defs/{name}"}


def _array(items: dict[str, Any], n: int) -> dict[str, Any]:
    """A JSON Schema array of exactly ``n`` ``items``."""
    return {"type": "array", "minItems": n, "maxItems": n, "items": items}


def _object(
    properties: dict[str, Any], required: list[str], description: str | None = None
) -> dict[str, Any]:
    """A JSON Schema object with these ``properties``, ``required`` ones and no others."""
    head = {} if description is None else {"description": description}
    return {
        **head,
        "type": "object",
        "required": required,
        "additionalProperties": False,
        "properties": properties,
    }


def _copies_edit(key: str, description: str, spec: dict[str, Any]) -> dict[str, Any]:
    """A JSON Schema edit ``{KEY: SPEC, "copies": N}`` (screw, helix, rotation)."""
    return _object({key: spec, "copies": {"type": "integer"}}, [key, "copies"], description)


def _about_vertical(properties: dict[str, Any]) -> dict[str, Any]:
    """JSON Schema properties of a turn by ``angle`` degrees about the vertical through
    ``center`` (helix, rotation), then ``properties``.
    """
    return {"center": _array(_ref("length"), 2), "angle": {"type": "number"}, **properties}


_LENGTH_PATTERN = r"^\s*[-+]?[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?\s*(mm|cm|m)\s*$"

#: JSON Schema (draft 2020-12) of a recipe file; ``partscale scale --recipe`` and the web editor
#: both produce and accept it.
JSON_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "partscale recipe",
    "description": (
        "Edits apply in order. All positions (numbers in object units, or percent of the solid's "
        "extent along the axis) refer to the recipe's input object as given, not to the result "
        "of the previous edit: an edit's planes are carried through the earlier edits on the "
        "same axis, and its destination keeps its change to - end."
    ),
    **_object(
        {
            "version": {"const": RECIPE_VERSION},
            "edits": {
                "type": "array",
                "minItems": 1,
                "maxItems": MAX_EDITS,
                "items": {
                    "oneOf": [
                        _object(
                            {
                                "axis": {"enum": list(AXES)},
                                "zone": _ref("zone"),
                                "to": _ref("position"),
                                "mode": {"enum": list(MODES), "default": "stretch"},
                            },
                            ["axis", "zone", "to"],
                        ),
                        _object(
                            {
                                "radial": _object(
                                    {
                                        "axis": {"enum": list(AXES), "default": "y"},
                                        "center": _array(_ref("length"), 2),
                                        "sides": {"type": "integer", "default": 0},
                                        "phase": {"type": "number", "default": 0},
                                        "span": _ref("lengths"),
                                    },
                                    ["center"],
                                ),
                                "zone": _ref("lengths"),
                                "to": _ref("length"),
                            },
                            ["radial", "zone", "to"],
                            "a radial zone: the annulus R0..R1 about the axis "
                            "through center becomes R0..to",
                        ),
                        _object(
                            {
                                "axis": {"enum": list(AXES)},
                                "copies": {
                                    "oneOf": [
                                        {"type": "integer"},
                                        {"type": "string", "pattern": r"^\s*[-+]?[0-9]+\s*$"},
                                    ]
                                },
                            },
                            ["axis", "copies"],
                            "whole elements more or fewer along an axis (one more "
                            "seat); resolved on the object into zone edits before it applies",
                        ),
                        _copies_edit(
                            "screw",
                            "steps of a diagonal repetition: what lies beyond the "
                            "plane cut across axis moves by copies times step",
                            _object(
                                {
                                    "axis": {"enum": list(AXES)},
                                    "step": _array(_ref("length"), 3),
                                    "cut": _ref("length"),
                                },
                                ["axis", "step", "cut"],
                            ),
                        ),
                        _copies_edit(
                            "helix",
                            "steps of a helix (a spiral stair): what lies above the "
                            "level cut turns by copies times angle (degrees, from x toward z) "
                            "about the vertical through center and rises by copies times rise",
                            _object(
                                _about_vertical({"rise": _ref("length"), "cut": _ref("length")}),
                                ["center", "angle", "rise", "cut"],
                            ),
                        ),
                        _copies_edit(
                            "rotation",
                            "elements repeated by a turn about the vertical (arms of "
                            "a star base, chairs about a round table): count elements, the first "
                            "at phase degrees and each next turned by angle degrees (from x toward "
                            "z) about the vertical through center, between the radii hub and "
                            "radius and the levels span; copies more (or fewer) of them, evenly "
                            "spaced on a closed ring, continued along an open arc",
                            _object(
                                _about_vertical(
                                    {
                                        "phase": {"type": "number"},
                                        "count": {"type": "integer", "minimum": 2},
                                        "closed": {"type": "boolean"},
                                        "hub": _ref("length"),
                                        "radius": _ref("length"),
                                        "span": _ref("lengths"),
                                    }
                                ),
                                [
                                    "center",
                                    "angle",
                                    "phase",
                                    "count",
                                    "closed",
                                    "hub",
                                    "radius",
                                    "span",
                                ],
                            ),
                        ),
                        _object(
                            {
                                "normal": _array({"type": "number"}, 3),
                                "zone": _ref("lengths"),
                                "to": _ref("length"),
                                "mode": {"const": "stretch"},
                            },
                            ["normal", "zone", "to"],
                            "an oblique zone: the slab between the planes "
                            "p . normal = START and = END becomes START..to",
                        ),
                    ]
                },
            },
        },
        ["edits"],
    ),
    "$defs": {
        "zone": _array(_ref("position"), 2),
        "lengths": _array(_ref("length"), 2),
        "length": {"oneOf": [{"type": "number"}, {"type": "string", "pattern": _LENGTH_PATTERN}]},
        "position": {
            "oneOf": [
                {"type": "number"},
                {"type": "string", "pattern": r"^-?[0-9]+(\.[0-9]+)?%$"},
                {"type": "string", "pattern": _LENGTH_PATTERN},
            ]
        },
    },
}


def parse_position(value: Any, what: str, units: str | None = None) -> Position:
    """Parse a position: a finite number (object units) or a string (a number, ``'NN%'``, a length).

    Numbers are any real number (Python or numpy scalars) but not booleans; strings hold a
    number, a percentage, or a length with a unit (``'30cm'``, ``'300mm'``, ``'0.3m'``: converted
    to object units, so only where ``units`` is ``'m'``; see :mod:`.units`). Non-finite values
    (``inf``, ``nan``, ``'1e400%'``) are refused.

    Parameters
    ----------
    value : float or str
        The position as given.
    what : str
        Its name in the :class:`InputError`.
    units : str, optional
        The object's units.

    Returns
    -------
    float or str
        A number in object units, or the ``'NN%'`` string (resolved on an object later).

    Examples
    --------
    >>> from partscale.edit import parse_position
    >>> parse_position("30%", "zone"), parse_position("30cm", "zone", units="m"), parse_position(0.3, "zone")
    ('30%', 0.3, 0.3)
    """
    if isinstance(value, bool | np.bool_):
        raise InputError(
            f"{what}: expected a number or a percentage like '30%', got {shown(value)}"
        )
    if isinstance(value, numbers.Real):
        v = float(value)
        if not math.isfinite(v):
            raise InputError(f"{what}: expected a finite number, got {shown(value)}")
        return v
    if isinstance(value, str):
        s = value.strip()
        try:
            v = float(s[:-1] if s.endswith("%") else s)
        except ValueError:
            if has_unit(s):
                return parse_length(s, units=units, what=what)
        else:
            if not math.isfinite(v):
                kind = "percentage" if s.endswith("%") else "number"
                raise InputError(f"{what}: expected a finite {kind}, got {shown(value)}")
            return s if s.endswith("%") else v
    raise InputError(f"{what}: expected a number or a percentage like '30%', got {shown(value)}")


@dataclass(frozen=True)
class Edit:
    """One zone edit between two planes across an axis.

    Parameters
    ----------
    axis : {'x', 'y', 'z'}
        The axis the zone lies along.
    start, end : float or str
        The zone's planes: object units, or ``'NN%'`` of the solid's extent along the axis.
    dest : float or str
        Where ``end`` goes, in the same terms.
    mode : {'stretch', 'tile', 'global'}
        How the zone changes (see :mod:`partscale.edit`).

    Examples
    --------
    >>> from partscale.edit import Edit
    >>> Edit("x", "30%", "60%", "80%", "tile").to_json()
    {'axis': 'x', 'zone': ['30%', '60%'], 'to': '80%', 'mode': 'tile'}
    """

    axis: str
    start: Position
    end: Position
    dest: Position
    mode: str = "stretch"

    @classmethod
    def parse(cls, obj: Any, *, where: str = "edit", units: str | None = None) -> Edit:
        """Validate a JSON-like edit (see module docstring); ``units``: the object's
        (``meta['units']``), for lengths with a unit (:func:`parse_position`).
        """
        if not isinstance(obj, dict):
            raise InputError(
                f"{where}: expected an object with axis, zone, to, mode; got {shown(obj)}"
            )
        unknown = set(obj) - {"axis", "zone", "to", "mode"}
        if unknown:
            raise InputError(
                f"{where}: unknown key(s) {shown(sorted(unknown))}; keys are axis, zone, to, mode"
            )
        for k in ("axis", "zone", "to"):
            if k not in obj:
                raise InputError(f"{where}: expected key {k!r}, got keys {shown(sorted(obj))}")
        axis = str(obj["axis"]).lower()
        if axis not in AXES:
            raise InputError(f"{where}.axis: expected one of x, y, z, got {shown(obj['axis'])}")
        mode = str(obj.get("mode", "stretch")).lower()
        if mode not in MODES:
            raise InputError(
                f"{where}.mode: expected one of {', '.join(MODES)}, got {shown(obj['mode'])}"
            )
        zone = obj["zone"]
        start, end = _pair(zone, where)
        return cls(
            axis=axis,
            start=parse_position(start, f"{where}.zone[0]", units),
            end=parse_position(end, f"{where}.zone[1]", units),
            dest=parse_position(obj["to"], f"{where}.to", units),
            mode=mode,
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {
            "axis": self.axis,
            "zone": [self.start, self.end],
            "to": self.dest,
            "mode": self.mode,
        }

    @property
    def axis_index(self) -> int:
        """The axis as 0, 1 or 2."""
        return AXES.index(self.axis)

    def resolve(self, lo: float, hi: float) -> tuple[float, float, float]:
        """World ``(start, end, dest)`` given the solid's extent ``[lo, hi]`` along the axis."""

        def world(p: Position) -> float:
            if isinstance(p, str):
                return lo + float(p.rstrip("%")) / 100.0 * (hi - lo)
            return float(p)

        return world(self.start), world(self.end), world(self.dest)


def _keys(obj: Any, allowed: set[str], required: set[str], where: str) -> None:
    if not isinstance(obj, dict):
        raise InputError(f"{where}: expected an object, got {shown(obj)}")
    unknown = set(obj) - allowed
    if unknown:
        raise InputError(
            f"{where}: unknown key(s) {shown(sorted(unknown))}; keys are {', '.join(sorted(allowed))}"
        )
    missing = required - set(obj)
    if missing:
        raise InputError(
            f"{where}: expected key(s) {', '.join(sorted(missing))}, got {shown(sorted(obj))}"
        )


def _pair(zone: Any, where: str) -> tuple[Any, Any]:
    # no numpy here: np.ndim of a ragged list ([[0.1], 0.2]) raises; each end is checked as a
    # position (a number or a string) by its reader
    if not isinstance(zone, list | tuple | np.ndarray) or len(zone) != 2:
        raise InputError(f"{where}.zone: expected [START, END], got {shown(zone)}")
    return zone[0], zone[1]


def _number(v: Any, what: str, units: str | None) -> float:
    """A finite number, or a length with a unit in object units (no %)."""
    p = parse_position(v, what, units)
    if isinstance(p, str):
        raise InputError(f"{what}: expected a number or a length (30cm), got {shown(v)}")
    return p


@dataclass(frozen=True)
class RadialZone:
    """An annulus about a line parallel to ``axis`` through ``center`` (world units).

    Parameters
    ----------
    axis : {'x', 'y', 'z'}
        The axis the annulus turns about (``'y'``: a table's vertical).
    center : (float, float)
        The line's position on the two other axes, in order (for ``'y'``: x, z).
    r0, r1 : float
        The annulus' radii before the edit, ``0 <= r0 < r1``.
    to : float
        ``r1`` after the edit, ``> r0``.
    sides : int
        0 for round; 3 or more: the gauge of a regular polygon (see module).
    phase : float
        Degrees: the direction of the first face normal, from the first other axis toward the
        second.
    span : (float, float) or None
        Positions along ``axis`` between which the zone applies (None: everywhere).

    Examples
    --------
    >>> from partscale.edit import RadialZone
    >>> RadialZone("y", (0.0, 0.0), 0.1, 0.4, 0.5).to_json()
    {'radial': {'axis': 'y', 'center': [0.0, 0.0], 'sides': 0, 'phase': 0.0}, 'zone': [0.1, 0.4], 'to': 0.5}
    """

    axis: str
    center: tuple[float, float]
    r0: float
    r1: float
    to: float
    sides: int = 0
    phase: float = 0.0
    span: tuple[float, float] | None = None

    @classmethod
    def parse(cls, obj: Any, *, where: str = "edit", units: str | None = None) -> RadialZone:
        """Validate a JSON-like radial edit ``{"radial": {"axis", "center", "sides", "phase"},
        "zone": [R0, R1], "to": R1'}`` (radii: numbers or lengths with a unit).
        """
        _keys(obj, {"radial", "zone", "to"}, {"radial", "zone", "to"}, where)
        spec = obj["radial"]
        if not isinstance(spec, dict):
            raise InputError(f"{where}.radial: expected an object, got {shown(spec)}")
        unknown = set(spec) - {"axis", "center", "sides", "phase", "span"}
        if unknown or "center" not in spec:
            raise InputError(
                f"{where}.radial: expected keys center (and axis, sides, phase), got "
                f"{shown(sorted(spec))}"
            )
        axis = str(spec.get("axis", "y")).lower()
        if axis not in AXES:
            raise InputError(
                f"{where}.radial.axis: expected one of x, y, z, got {shown(spec['axis'])}"
            )
        center = _vector(spec, "center", "A, B", f"{where}.radial")
        sides = spec.get("sides", 0)
        if isinstance(sides, bool) or not isinstance(sides, int):
            raise InputError(f"{where}.radial.sides: expected a whole number, got {shown(sides)}")
        zone = _pair(obj["zone"], where)
        vals = [_number(v, f"{where}.radial.center", units) for v in center]
        span = spec.get("span")
        if span is not None:
            a, b = _pair(span, f"{where}.radial.span")
            span = (
                _number(a, f"{where}.radial.span", units),
                _number(b, f"{where}.radial.span", units),
            )
        return cls(
            axis,
            (vals[0], vals[1]),
            _number(zone[0], f"{where}.zone[0]", units),
            _number(zone[1], f"{where}.zone[1]", units),
            _number(obj["to"], f"{where}.to", units),
            sides,
            _number(spec.get("phase", 0.0), f"{where}.radial.phase", None),
            span,
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        spec: dict[str, Any] = {
            "axis": self.axis,
            "center": [self.center[0], self.center[1]],
            "sides": self.sides,
            "phase": self.phase,
        }
        if self.span is not None:
            spec["span"] = [self.span[0], self.span[1]]
        return {"radial": spec, "zone": [self.r0, self.r1], "to": self.to}

    @property
    def shift(self) -> float:
        """How far the outer radius moves: ``to - r1``."""
        return self.to - self.r1


@dataclass(frozen=True)
class ObliqueZone:
    """The slab between two planes square to the unit vector ``normal``.

    Parameters
    ----------
    normal : (float, float, float)
        Unit vector (world axes).
    s0, s1 : float
        The planes ``p . normal = s0`` and ``= s1`` (world units), ``s0 < s1``.
    to : float
        Where the plane ``s1`` goes, ``> s0``.

    Examples
    --------
    >>> from partscale.edit import ObliqueZone
    >>> ObliqueZone((1.0, 0.0, 0.0), 0.3, 0.6, 0.8).to_json()
    {'normal': [1.0, 0.0, 0.0], 'zone': [0.3, 0.6], 'to': 0.8}
    """

    normal: tuple[float, float, float]
    s0: float
    s1: float
    to: float

    @classmethod
    def parse(cls, obj: Any, *, where: str = "edit", units: str | None = None) -> ObliqueZone:
        """Validate a JSON-like oblique edit ``{"normal": [NX, NY, NZ], "zone": [S0, S1],
        "to": S1'}`` (positions along the normal: numbers or lengths with a unit).
        """
        _keys(obj, {"normal", "zone", "to", "mode"}, {"normal", "zone", "to"}, where)
        if obj.get("mode", "stretch") != "stretch":
            raise InputError(
                f"{where}.mode: expected stretch (oblique zones), got {shown(obj['mode'])}"
            )
        n = obj["normal"]
        if not isinstance(n, list | tuple) or len(n) != 3:
            raise InputError(f"{where}.normal: expected [NX, NY, NZ], got {shown(n)}")
        zone = _pair(obj["zone"], where)
        nv = [_number(v, f"{where}.normal", None) for v in n]
        return cls(
            (nv[0], nv[1], nv[2]),
            _number(zone[0], f"{where}.zone[0]", units),
            _number(zone[1], f"{where}.zone[1]", units),
            _number(obj["to"], f"{where}.to", units),
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {"normal": list(self.normal), "zone": [self.s0, self.s1], "to": self.to}

    @property
    def shift(self) -> float:
        """How far the plane ``s1`` moves: ``to - s1``."""
        return self.to - self.s1


@dataclass(frozen=True)
class ScrewZone:
    """Steps added to (or removed from) a flight that repeats by a diagonal shift.

    ``copies`` more steps of a repetition by a diagonal shift (a straight flight): what lies
    beyond the plane ``cut`` across ``axis`` moves by ``copies`` times ``step``
    (:func:`partscale.edit.apply_screw`); ``copies < 0`` removes steps.

    Parameters
    ----------
    axis : {'x', 'y', 'z'}
        The axis the cut plane lies across (the flight's horizontal direction).
    step : (float, float, float)
        The shift carrying one step onto the next (world units).
    cut : float
        The cut plane's position along ``axis`` (world units).
    copies : int
        Steps added (negative: removed), not 0.

    Examples
    --------
    >>> from partscale.edit import ScrewZone
    >>> ScrewZone("x", (0.2, 0.2, 0.0), 0.5, 1).to_json()
    {'screw': {'axis': 'x', 'step': [0.2, 0.2, 0.0], 'cut': 0.5}, 'copies': 1}
    """

    axis: str
    step: tuple[float, float, float]
    cut: float
    copies: int

    @classmethod
    def parse(cls, obj: Any, *, where: str = "edit", units: str | None = None) -> ScrewZone:
        """Validate ``{"screw": {"axis", "step": [X, Y, Z], "cut": C}, "copies": N}``."""
        spec = _count_spec(obj, "screw", ("axis", "step", "cut"), where)
        axis = str(spec["axis"]).lower()
        if axis not in AXES:
            raise InputError(
                f"{where}.screw.axis: expected one of x, y, z, got {shown(spec['axis'])}"
            )
        _vector(spec, "step", "X, Y, Z", f"{where}.screw")
        n = _copies(obj, where)
        sv = [_number(v, f"{where}.screw.step", units) for v in spec["step"]]
        return cls(
            axis, (sv[0], sv[1], sv[2]), _number(spec["cut"], f"{where}.screw.cut", units), n
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return _count_json(self, "screw")


def _count_json(edit: Any, key: str) -> dict[str, Any]:
    """A count edit's JSON form: ``{key: {its fields but copies, tuples as lists}, "copies": N}``
    (the fields in their declared order).
    """
    spec = {}
    for f in fields(edit):
        value = getattr(edit, f.name)
        spec[f.name] = list(value) if isinstance(value, tuple) else value
    copies = spec.pop("copies")
    return {key: spec, "copies": copies}


def _count_spec(obj: Any, key: str, fields: tuple[str, ...], where: str) -> dict[str, Any]:
    """A count edit's ``{key: {fields...}, "copies": N}``: its spec, with exactly ``fields``."""
    _keys(obj, {key, "copies"}, {key, "copies"}, where)
    spec = obj[key]
    if not isinstance(spec, dict) or set(spec) != set(fields):
        raise InputError(f"{where}.{key}: expected keys {', '.join(fields)}, got {shown(spec)}")
    return spec


def _vector(spec: dict[str, Any], name: str, form: str, where: str) -> list[Any] | tuple[Any, ...]:
    """``spec[name]``, a list of as many values as ``form`` names (``"X, Z"``), unconverted."""
    value = spec[name]
    if not isinstance(value, list | tuple) or len(value) != form.count(",") + 1:
        raise InputError(f"{where}.{name}: expected [{form}], got {shown(value)}")
    return value


def _copies(obj: dict[str, Any], where: str, what: str = "a whole number") -> int:
    """A count edit's ``copies``: a whole number other than 0, at most :data:`MAX_COPIES` either
    way (an int, or a string with its sign).
    """
    n = obj["copies"]
    try:
        n = _schema.integer(n, f"{where}.copies", lo=-MAX_COPIES, hi=MAX_COPIES, text=True)
    except InputError:
        n = 0
    if n == 0:
        raise InputError(
            f"{where}.copies: expected {what} other than 0 (+1, -2), at most {MAX_COPIES} either "
            f"way, got {shown(obj['copies'])}"
        )
    return n


@dataclass(frozen=True)
class HelixZone:
    """Steps added to (or removed from) a stair that repeats by a turn and a rise (a spiral).

    ``copies`` more steps of a helical repetition: what lies above the level ``cut`` turns by
    ``copies`` times ``angle`` about the vertical through ``center`` and rises by ``copies``
    times ``rise`` (:func:`partscale.edit.apply_helix`); ``copies < 0`` removes steps. The cut
    is a level between two treads, where everything it crosses (the column, the handrail, the
    air between turns) repeats: the two sides agree there.

    Parameters
    ----------
    center : (float, float)
        The vertical axis' place on x and z (world units).
    angle : float
        Degrees one step turns, from x toward z (negative: from z toward x).
    rise : float
        World units one step rises.
    cut : float
        The cut's height (world y).
    copies : int
        Steps added (negative: removed), not 0.

    Examples
    --------
    >>> from partscale.edit import HelixZone
    >>> HelixZone((0.0, 0.0), 30.0, 0.15, 0.8, 1).to_json()
    {'helix': {'center': [0.0, 0.0], 'angle': 30.0, 'rise': 0.15, 'cut': 0.8}, 'copies': 1}
    """

    center: tuple[float, float]
    angle: float
    rise: float
    cut: float
    copies: int

    @classmethod
    def parse(cls, obj: Any, *, where: str = "edit", units: str | None = None) -> HelixZone:
        """Validate ``{"helix": {"center": [X, Z], "angle": DEG, "rise": R, "cut": Y},
        "copies": N}`` (lengths: numbers or with a unit; the angle in degrees).
        """
        spec = _count_spec(obj, "helix", ("center", "angle", "rise", "cut"), where)
        _vector(spec, "center", "X, Z", f"{where}.helix")
        n = _copies(obj, where)
        cv = [_number(v, f"{where}.helix.center", units) for v in spec["center"]]
        return cls(
            (cv[0], cv[1]),
            _number(spec["angle"], f"{where}.helix.angle", None),
            _number(spec["rise"], f"{where}.helix.rise", units),
            _number(spec["cut"], f"{where}.helix.cut", units),
            n,
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return _count_json(self, "helix")


@dataclass(frozen=True)
class RotationZone:
    """Elements added to (or removed from) a ring or arc that repeats by a turn about the vertical.

    ``count`` elements (the arms of a star base, the blades of a fan, chairs about a round
    table) lie between the radii ``hub`` and ``radius`` about the vertical through ``center``
    and between the levels ``span``: the first at ``phase`` degrees, each next turned by
    ``angle`` degrees (from x toward z) from the one before. ``copies`` more of them
    (:func:`partscale.edit.apply_rotation`; ``copies < 0``: fewer): on a closed ring
    (``closed``: ``count`` times ``angle`` is a whole turn) the ``count + copies`` elements are
    spaced evenly, each one of the old ones turned rigidly about the axis; on an open arc the
    new ones continue it (the last one turned by ``angle`` each), or the last ones go. What lies
    within ``hub`` (a column, a table's top), or outside ``span``, stays as it is.

    Parameters
    ----------
    center : (float, float)
        The vertical axis' place on x and z (world units).
    angle : float
        Degrees from one element to the next.
    phase : float
        Degrees: the first element's direction from the axis.
    count : int
        Elements now (at least 2).
    closed : bool
        A whole ring (else an open arc).
    hub, radius : float
        The radii the elements lie between (world units).
    span : (float, float)
        The levels (world y) they lie between.
    copies : int
        Elements added (negative: removed), not 0.

    Examples
    --------
    >>> from partscale.edit import RotationZone
    >>> z = RotationZone((0.0, 0.0), 72.0, 0.0, 5, True, 0.05, 0.4, (0.0, 0.1), 1)
    >>> z.to_json()["rotation"]["count"], z.to_json()["copies"]
    (5, 1)
    """

    center: tuple[float, float]
    angle: float
    phase: float
    count: int
    closed: bool
    hub: float
    radius: float
    span: tuple[float, float]
    copies: int

    @classmethod
    def parse(cls, obj: Any, *, where: str = "edit", units: str | None = None) -> RotationZone:
        """Validate ``{"rotation": {"center": [X, Z], "angle", "phase", "count", "closed",
        "hub", "radius", "span": [Y0, Y1]}, "copies": N}`` (lengths: numbers or with a unit;
        angles in degrees).
        """
        keys = ("angle", "center", "closed", "count", "hub", "phase", "radius", "span")
        spec = _count_spec(obj, "rotation", keys, where)
        _vector(spec, "center", "X, Z", f"{where}.rotation")
        count = spec["count"]
        if isinstance(count, bool) or not isinstance(count, int) or count < 2:
            raise InputError(
                f"{where}.rotation.count: expected a whole number >= 2, got {shown(count)}"
            )
        if not isinstance(spec["closed"], bool):
            raise InputError(
                f"{where}.rotation.closed: expected true or false, got {shown(spec['closed'])}"
            )
        n = _copies(obj, where)
        cv = [_number(v, f"{where}.rotation.center", units) for v in spec["center"]]
        span = _vector(spec, "span", "Y0, Y1", f"{where}.rotation")
        return cls(
            (cv[0], cv[1]),
            _number(spec["angle"], f"{where}.rotation.angle", None),
            _number(spec["phase"], f"{where}.rotation.phase", None),
            count,
            spec["closed"],
            _number(spec["hub"], f"{where}.rotation.hub", units),
            _number(spec["radius"], f"{where}.rotation.radius", units),
            (
                _number(span[0], f"{where}.rotation.span[0]", units),
                _number(span[1], f"{where}.rotation.span[1]", units),
            ),
            n,
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return _count_json(self, "rotation")


@dataclass(frozen=True)
class CountEdit:
    """Whole elements more or fewer along an axis: "one more seat" in a recipe.

    ``{"axis": "x", "copies": "+1"}`` holds no zone: the object's own repeat gives it. It is
    resolved on the object into the zone edits that make it
    (:func:`partscale.zones.resolve_counts`) before the recipe applies.

    Parameters
    ----------
    axis : {'x', 'y', 'z'}
    copies : int
        Elements added; negative: removed. Not 0.

    Examples
    --------
    >>> from partscale.edit import CountEdit
    >>> CountEdit.parse({"axis": "x", "copies": "+1"})
    CountEdit(axis='x', copies=1)
    """

    axis: str
    copies: int

    @classmethod
    def parse(cls, obj: Any, *, where: str = "edit") -> CountEdit:
        """Validate ``{"axis": "x", "copies": "+1"}`` (an int, or a string with its sign)."""
        _keys(obj, {"axis", "copies"}, {"axis", "copies"}, where)
        axis = str(obj["axis"]).lower()
        if axis not in AXES:
            raise InputError(f"{where}.axis: expected one of x, y, z, got {shown(obj['axis'])}")
        return cls(axis, _copies(obj, where, "+N or -N elements"))

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes hold): ``{"axis": "x", "copies": "+1"}``."""
        return {"axis": self.axis, "copies": f"{self.copies:+d}"}


@dataclass(frozen=True)
class Recipe:
    """An ordered list of edits; serialises to the JSON schema :data:`JSON_SCHEMA`.

    All positions refer to the recipe's input object as given (see the module).

    Parameters
    ----------
    edits : tuple of Edit, RadialZone, ObliqueZone, ScrewZone, HelixZone or RotationZone
        The edits, applied in order.

    Examples
    --------
    >>> from partscale.edit import Recipe
    >>> recipe = Recipe.parse({"version": 1, "edits": [{"axis": "x", "zone": ["30%", "60%"], "to": "80%"}]})
    >>> recipe.to_json()
    {'version': 1, 'edits': [{'axis': 'x', 'zone': ['30%', '60%'], 'to': '80%', 'mode': 'stretch'}]}
    """

    edits: tuple[
        Edit | RadialZone | ObliqueZone | ScrewZone | HelixZone | RotationZone | CountEdit, ...
    ] = field(default_factory=tuple)

    @classmethod
    def parse(cls, obj: Any, *, units: str | None = None) -> Recipe:
        """Validate a JSON-like recipe (see module docstring); ``units``: the object's
        (``meta['units']``) where positions with a unit (``'30cm'``) are to be converted.
        """
        if isinstance(obj, list):
            obj = {"edits": obj}
        if not isinstance(obj, dict) or "edits" not in obj:
            raise InputError(f"recipe: expected {{'edits': [...]}}, got {shown(obj)}")
        unknown = set(obj) - {"version", "edits"}
        if unknown:
            raise InputError(
                f"recipe: unknown key(s) {shown(sorted(unknown))}; keys are version, edits"
            )
        if obj.get("version", RECIPE_VERSION) != RECIPE_VERSION:
            raise InputError(
                f"recipe: expected version {RECIPE_VERSION}, got {shown(obj['version'])}"
            )
        edits = obj["edits"]
        if not isinstance(edits, list) or not edits:
            raise InputError(f"recipe: expected a non-empty list of edits, got {shown(edits)}")
        if len(edits) > MAX_EDITS:
            raise InputError(f"recipe: expected at most {MAX_EDITS} edits, got {len(edits)}")
        return cls(
            tuple(parse_edit(e, where=f"edits[{i}]", units=units) for i, e in enumerate(edits))
        )

    @classmethod
    def load(cls, path: str | os.PathLike, *, units: str | None = None) -> Recipe:
        """Read and validate a recipe JSON file (:meth:`parse`); errors name the file."""
        path = Path(path)
        obj = read_json(path, what="a recipe JSON file")
        try:
            return cls.parse(obj, units=units)
        except InputError as exc:
            raise InputError(f"{path}: {exc}") from None

    def to_json(self) -> dict[str, Any]:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {"version": RECIPE_VERSION, "edits": [e.to_json() for e in self.edits]}


def parse_edit(
    obj: Any, *, where: str = "edit", units: str | None = None
) -> Edit | RadialZone | ObliqueZone | ScrewZone | HelixZone | RotationZone | CountEdit:
    """Parse one recipe edit of any kind.

    A radial zone has a ``"radial"`` key, an oblique one ``"normal"``, steps ``"screw"`` (a
    helix's ``"helix"``, elements about the vertical ``"rotation"``), a count
    ``"copies"`` and no zone (:class:`CountEdit`); anything else is a zone between planes across an
    axis (:class:`Edit`).

    Parameters
    ----------
    obj : dict or Edit
        The edit in its JSON form (an edit object is returned as it is).
    where : str
        Where it is, for messages (``"edits[2]"``).
    units : str, optional
        The object's units; lengths with a unit (``'30cm'``) are taken only where it is ``'m'``.

    Returns
    -------
    Edit, RadialZone, ObliqueZone, ScrewZone, HelixZone, RotationZone or CountEdit
        The edit.

    Examples
    --------
    >>> from partscale.edit import parse_edit
    >>> parse_edit({"axis": "x", "zone": ["30%", "60%"], "to": 0.8})
    Edit(axis='x', start='30%', end='60%', dest=0.8, mode='stretch')
    """
    if isinstance(obj, dict) and "radial" in obj:
        return RadialZone.parse(obj, where=where, units=units)
    if isinstance(obj, dict) and "normal" in obj:
        return ObliqueZone.parse(obj, where=where, units=units)
    if isinstance(obj, dict) and "screw" in obj:
        return ScrewZone.parse(obj, where=where, units=units)
    if isinstance(obj, dict) and "helix" in obj:
        return HelixZone.parse(obj, where=where, units=units)
    if isinstance(obj, dict) and "rotation" in obj:
        return RotationZone.parse(obj, where=where, units=units)
    if isinstance(obj, dict) and "copies" in obj and "zone" not in obj:
        return CountEdit.parse(obj, where=where)
    return Edit.parse(obj, where=where, units=units)


# -- the 1D maps: output coordinate -> source coordinate --------------------------------------


def tile_count(length: float, target: float) -> int:
    """Number of copies for tiling a slab of ``length`` to ``target``.

    Number of copies for tiling a slab of ``length`` to ``target``: ``max(1, round(L'/L))``,
    and 0 for ``target == 0`` exactly (the zone removed: DEST == START).

    Half-way cases round up (1.5 -> 2) so growing by one and a half periods adds a copy. A ratio
    within ``1e-9`` below a half counts as the half: ``0.3 / 0.2`` is ``1.4999999999999998`` in
    floating point. Rounding never gives 0 copies (a tile to 30% of its length is one copy);
    only a zero destination length does. The web editor's ``tileCount`` (web/src/recipe.ts) is
    the same expression.

    Parameters
    ----------
    length : float
        The zone's length.
    target : float
        Its length after the edit.

    Returns
    -------
    int
        The number of copies.

    Examples
    --------
    >>> from partscale.edit import tile_count
    >>> tile_count(0.2, 0.5), tile_count(0.2, 0.3), tile_count(0.2, 0.0)
    (3, 2, 0)
    """
    if target == 0:
        return 0
    return max(1, math.floor(target / length + 0.5 + 1e-9))


def _global_factor(lo: float | None, hi: float | None, shift: float) -> tuple[float, float]:
    """The ``global`` mode's fixed point ``lo`` and its scale factor (the length grows by ``shift``)."""
    if lo is None or hi is None:
        raise ValueError("global mode needs the solid's extent lo, hi")
    return lo, (hi - lo + shift) / (hi - lo)


def source_coordinate(
    y: np.ndarray,
    *,
    mode: str,
    start: float,
    end: float,
    dest: float,
    lo: float | None = None,
    hi: float | None = None,
) -> np.ndarray:
    """Map output world coordinates ``y`` along the edit axis to source coordinates.

    Parameters
    ----------
    y : (N,) float64
        Coordinates after the edit.
    mode : {'stretch', 'tile', 'global'}
    start, end, dest : float
        World zone ``[start, end]`` and the new position of ``end``.
    lo, hi : float
        The solid's extent along the axis before the edit (``global`` only): it is scaled about
        ``lo`` so that its length changes by ``dest - end``.

    Returns
    -------
    (N,) float64
        For ``tile``, copy ``m`` of ``n`` maps ``[start + m L'/n, start + (m+1) L'/n]`` onto
        ``[start, end]``; the resampler additionally blends across seams (the map does not).
        With 0 copies (``dest == start``) the zone is cut out: ``y >= start`` reads ``y - shift``.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.edit import source_coordinate
    >>> source_coordinate(np.array([0.2, 0.5, 1.1]), mode="stretch", start=0.3, end=0.6, dest=0.8)
    array([0.2 , 0.42, 0.9 ])
    """
    y = np.asarray(y, dtype=np.float64)
    shift = dest - end
    if mode == "global":
        lo, factor = _global_factor(lo, hi, shift)
        return lo + (y - lo) / factor
    length, target = end - start, dest - start
    x = np.where(y < start, y, y - shift)
    if mode == "tile" and tile_count(length, target) == 0:
        return x
    inside = (y >= start) & (y <= dest)
    t = (y[inside] - start) / target  # 0..1 across the new zone
    if mode == "stretch":
        x[inside] = start + t * length
    elif mode == "tile":
        n = tile_count(length, target)
        u = t * n
        k = np.minimum(np.floor(u), n - 1)
        x[inside] = start + (u - k) * length
    else:
        raise ValueError(f"mode: expected one of {MODES}, got {mode!r}")
    return x


def forward_coordinate(
    x: np.ndarray,
    *,
    mode: str,
    start: float,
    end: float,
    dest: float,
    lo: float | None = None,
    hi: float | None = None,
) -> np.ndarray:
    """Where planes at source coordinates ``x`` lie after an edit (world units along its axis).

    The inverse of :func:`source_coordinate` outside the zone; inside it, a plane follows the
    stretch (``stretch``), the first copy (``tile``) or the scaling about ``lo`` (``global``).
    Recipes use it to carry positions given on their input through their earlier edits.

    Parameters
    ----------
    x : (N,) float64
        Coordinates before the edit.
    mode, start, end, dest, lo, hi
        The edit, as :func:`source_coordinate` takes it.

    Returns
    -------
    (N,) float64
        The coordinates after the edit.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale.edit import forward_coordinate, source_coordinate
    >>> edit = dict(mode="stretch", start=0.3, end=0.6, dest=0.8)
    >>> planes = forward_coordinate(np.array([0.2, 0.5, 0.9]), **edit)
    >>> planes
    array([0.2       , 0.63333333, 1.1       ])
    >>> source_coordinate(planes, **edit)  # and back
    array([0.2, 0.5, 0.9])
    """
    x = np.asarray(x, dtype=np.float64)
    if mode == "global":
        lo, factor = _global_factor(lo, hi, dest - end)
        return lo + (x - lo) * factor
    shift = dest - end
    if mode == "stretch":
        scale = (dest - start) / (end - start)
    elif mode == "tile":
        n = tile_count(end - start, dest - start)
        # 0 copies: planes inside a removed zone collapse onto its start
        scale = (dest - start) / (n * (end - start)) if n else 0.0
    else:
        raise ValueError(f"mode: expected one of {MODES}, got {mode!r}")
    return np.where(x <= start, x, np.where(x >= end, x + shift, start + (x - start) * scale))
