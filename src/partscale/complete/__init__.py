"""Completion: partial scans (range meshes, point clouds, RGB-D frames) -> watertight CSDFs.

Public API: :func:`complete` (frames -> CSDF), :func:`complete_file` (files -> CSDF),
:func:`provenance` and :func:`completion_colors` (what ``render --completion`` shows), the readers
:func:`read_frame`, :func:`read_intrinsics`, :func:`read_points`, :func:`read_views`,
:func:`frame_from_points` and :class:`Frame`. The virtual scanner that the examples use to make a
scan of the shipped table (:func:`partscale.evaluate.virtual_scan`) and the scores of a
completion (:func:`partscale.evaluate.chamfer_fscore`) are evaluation tools, in
:mod:`partscale.evaluate`.

Modules: ``scan`` (frames and readers), ``floor`` (RANSAC floor, clusters), ``carve`` (free
space), ``symmetry`` (mirror planes, rotations), ``fuse`` (the solid, distances, colours),
``column`` (a turning base's guessed column), ``strut`` (pieces left apart joined by guessed
struts), ``tidy`` (specks, manifold voxels), ``guard`` (the completion or the scan as observed),
``metric`` (is the scan in metres; its ``scale``), ``api`` (orchestration: named steps from the
observation to the CSDF).
"""

from __future__ import annotations

from .api import complete, complete_file, completion_colors, provenance
from .fuse import GUESSED, KIND_COLORS, KINDS, MIRRORED, OBSERVED
from .scan import (
    DEPTH_SCALE,
    MAX_COORDINATE,
    MAX_PIXEL,
    Frame,
    frame_from_points,
    read_frame,
    read_intrinsics,
    read_points,
    read_views,
)

__all__ = [
    "DEPTH_SCALE",
    "GUESSED",
    "KINDS",
    "KIND_COLORS",
    "MAX_COORDINATE",
    "MAX_PIXEL",
    "MIRRORED",
    "OBSERVED",
    "Frame",
    "complete",
    "complete_file",
    "completion_colors",
    "frame_from_points",
    "provenance",
    "read_frame",
    "read_intrinsics",
    "read_points",
    "read_views",
]
