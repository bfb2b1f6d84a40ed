"""Zones that find themselves: a stage between segment and edit.

Public API
----------
- :func:`suggest` ``(csdf, axis=None) -> list[Candidate]``: zone candidates, best first:
  ``tile`` (one period of a repeated element, planes in the gaps) and ``stretch`` (a slab of
  constant cross-section).
- :func:`snap` ``(csdf, edit, mode=None, *, candidates=None) -> (Edit, list[Move])``: a user's
  planes moved to the nearest good position for the mode (``candidates``: those a caller found
  already, as the editor's server does); :func:`describe_moves`, :func:`record_snap`.
- :func:`fit` ``(csdf, size) -> (Recipe, list[str])``: the recipe reaching a target extent
  (tile whole periods, absorb the rest in a constant slab, global only as a last resort).
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
from .features import Feature, axis_features, feature_notes, local_features, whole_copies
from .fit import fit, fit_axis
from .profile import Profile, profile
from .snap import Move, describe_moves, record_snap, snap
from .suggest import (
    AXES,
    BoundedRepeat,
    Candidate,
    axis_candidates,
    calm_runs,
    find_bounded_repeats,
    suggest,
)

__all__ = [
    "AXES",
    "BoundedRepeat",
    "Candidate",
    "Feature",
    "Move",
    "Profile",
    "axis_candidates",
    "axis_features",
    "calm_runs",
    "describe_moves",
    "feature_notes",
    "find_bounded_repeats",
    "fit",
    "fit_axis",
    "local_features",
    "parse_length",
    "parse_size",
    "profile",
    "record_snap",
    "snap",
    "suggest",
    "whole_copies",
]
