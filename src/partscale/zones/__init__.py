"""Zones that find themselves: a stage between segment and edit.

Public API
----------
- :func:`suggest` ``(csdf, axis=None) -> list[Candidate]``: zone candidates, best first:
  ``tile`` (one period of a repeated element, planes in the gaps) and ``stretch`` (a slab of
  constant cross-section).
- :func:`snap` ``(csdf, edit, mode=None, *, candidates=None) -> (Edit, list[Move])``: a user's
  planes moved to the nearest good position for the mode (``candidates``: those a caller found
  already, as the editor's server does); :func:`describe_moves`, :func:`record_snap`.
- :func:`fit` ``(csdf, size, *, add=None, allow_deform=False) -> (Recipe, list[str])``: the
  recipe reaching a target extent (tile whole periods or whole elements, absorb the rest in a
  constant slab; refused where only a deformation would reach it, unless ``allow_deform``), or
  adding/removing whole elements (``add={'x': 1}``: :func:`add_axis`).
- :func:`find_radial` ``(csdf, axis='y') -> RadialFrame | None``: a round or regular-polygon
  outline in plan (centre, sides, phase); :func:`radial_zones`: its annuli of constant radial
  section (what a radial zone grows; ``fit`` uses it where x and z grow alike and planes
  across them cannot).
- :func:`find_screws` ``(csdf) -> list[Screw]``: repetition by a diagonal shift (a flight's
  steps: going and rise), with a cut across a tread; ``fit --add y 1`` adds a step along it.
- :func:`find_helices` ``(csdf) -> list[Helix]``: repetition by a turn about the vertical and a
  rise (a spiral stair's steps: angle, rise, axis), with a cut level between two treads;
  ``fit --add y 1`` adds a step along it where nothing repeats straight.
- :func:`warp_candidates` ``(csdf) -> WarpCandidates``: all of the three above at once, each
  with the recipe edit that uses it (what the editor shows and previews).
- :func:`find_rotations` ``(csdf) -> list[Rotation]``: repetition by a turn about the vertical
  (the arms of a star base, chairs about a round table: angle, axis, count, closed ring or open
  arc), with the hub that stays; ``fit --add y 1`` adds an element where nothing repeats along
  y and no stair is found.
- :func:`find_elements` ``(csdf, axis) -> AxisElements``: the object along an axis as elements
  (seats, doors, compartments, steps) and separators, with the groups that repeat (alike up to
  a mirror, a small length change or a colour change); :func:`count_zone`: the zone of whole
  elements a count edit tiles.
- :func:`parse_size`, :func:`parse_length`: ``=``, ``2.1``, ``210cm``, ``2100mm``, ``+20cm``,
  ``-5cm``, ``120%`` (re-exported from :mod:`partscale.edit`, their one home, beside
  :func:`partscale.edit.parse_position`).
- :func:`local_features` ``(csdf, axis, zone) -> [(start, end), ...]``: the knobs, handles,
  hinges, keyholes and colour motifs a stretch of ``zone`` would stretch out of shape;
  :func:`feature_notes` ``(csdf, recipe)``: a line per stretch edit that holds one;
  :func:`axis_features` ``(csdf, axis, calm_runs(profile))`` -> list[Feature]: those of an
  axis's calm runs, which constant slabs are cut around; :func:`whole_copies`: whether a tile
  zone copies whole elements (no plane through a feature, none doubled).
- :func:`profile`, :class:`Profile`: the per-layer cross-sections all of it is built on;
  :func:`find_bounded_repeats` ``(profile) -> list[BoundedRepeat]``: the elements repeated
  between boards or gaps that the weaker of the two tile detectors finds (layer indices).
"""

from ..edit import parse_length, parse_size
from .elements import (
    AxisElements,
    CountZone,
    Element,
    Group,
    Separator,
    count_zone,
    element_phrase,
    find_elements,
)
from .features import Feature, axis_features, feature_notes, local_features, whole_copies
from .fit import add_axis, fit, fit_axis, resolve_counts
from .helix import Helix, find_helices
from .profile import Profile, calm_runs, profile
from .radial import RadialFrame, find_radial, radial_zones
from .rotation import Rotation, find_rotations
from .screw import Screw, find_screws
from .snap import Move, describe_moves, record_snap, snap
from .suggest import (
    AXES,
    SEAM_WINDOW,
    BoundedRepeat,
    Candidate,
    axis_candidates,
    find_bounded_repeats,
    layer_step,
    suggest,
)
from .warps import WarpCandidates, warp_candidates

__all__ = [
    "AXES",
    "SEAM_WINDOW",
    "AxisElements",
    "BoundedRepeat",
    "Candidate",
    "CountZone",
    "Element",
    "Feature",
    "Group",
    "Helix",
    "Move",
    "Profile",
    "RadialFrame",
    "Rotation",
    "Screw",
    "Separator",
    "WarpCandidates",
    "add_axis",
    "axis_candidates",
    "axis_features",
    "calm_runs",
    "count_zone",
    "describe_moves",
    "element_phrase",
    "feature_notes",
    "find_bounded_repeats",
    "find_elements",
    "find_helices",
    "find_radial",
    "find_rotations",
    "find_screws",
    "fit",
    "fit_axis",
    "layer_step",
    "local_features",
    "parse_length",
    "parse_size",
    "profile",
    "radial_zones",
    "record_snap",
    "resolve_counts",
    "snap",
    "suggest",
    "warp_candidates",
    "whole_copies",
]
