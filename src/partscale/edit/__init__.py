"""Edit stage: part-aware selective scaling (stretch, tile, global) driven by recipes.

Public API
----------
- :func:`apply_edit` ``(csdf, edit, *, progress=None) -> CSDF``: one zone edit, re-evaluated.
- :func:`apply_recipe` ``(csdf, recipe, *, progress=None) -> CSDF``: edits in order.
- :func:`scale` ``(csdf, *, axis, zone, to, mode="stretch", progress=None) -> CSDF``.
- :func:`naive_edit` ``(csdf, edit) -> CSDF``: the BASELINE (per-column resampling, plain
  concatenation of tiles, no re-evaluation) that evaluations and benchmarks compare against.
- :func:`reevaluate` ``(csdf, mask=None, *, band=partscale.csdf.BAND_VOXELS) -> CSDF``:
  re-evaluated distances (to the grid's marching-cubes surface) near the surface, on its own.
- :func:`recipe_from_history` ``(csdf, *, after=None) -> Recipe``: the replayable recipe.
- :func:`check_recipe_memory` ``(csdf, recipe, what=...)``: refuse a recipe whose result would not
  fit in memory, before any work.
- :func:`recipe_shape` ``(csdf, recipe) -> (X, Y, Z)``: the grid shape a recipe gives, predicted
  without computing it (the editor refuses an apply its page could not show, before computing).
- :data:`MAX_EDITS`: most edits one recipe may hold.
- :class:`RadialZone`, :class:`ObliqueZone`, :func:`apply_radial`, :func:`apply_oblique`: zones
  that are not slabs across an axis (an annulus about an axis; a slab between two planes
  square to any direction), resampled and re-evaluated (:mod:`partscale.edit.warp`); recipes
  hold them too (``{"radial": {...}, "zone": [R0, R1], "to": R}``, ``{"normal": [...], ...}``);
  :func:`warp_source`: the map of any warp zone on points (what the editor's shader previews);
  :func:`screw_ground`: the floor a flight's steps are kept on.
- :class:`ScrewZone`, :func:`apply_screw`; :class:`HelixZone`, :func:`apply_helix`: steps added
  to or removed from a flight that repeats by a diagonal shift, or a spiral stair that repeats
  by a turn about the vertical and a rise; :class:`RotationZone`, :func:`apply_rotation`:
  elements added to or removed from a ring (or arc) that repeats by a turn about the vertical.
- :func:`resolve_edit` ``(csdf, edit) -> ResolvedEdit``: an edit validated on an object, in world
  units and snapped to whole voxels, as :func:`apply_edit` performs it (:class:`ResolvedEdit`
  also maps coordinates across the edit and lists its seams).
- :class:`Edit`, :class:`Recipe`, :data:`JSON_SCHEMA`, :func:`parse_position`,
  :func:`source_coordinate`, :func:`forward_coordinate`, :func:`tile_count`: the recipe schema
  and the 1D maps the web editor's shader shares. ``parse_position(value, what, units=None)``
  also takes lengths with a unit (``'30cm'``) where ``units`` is ``'m'``.
- :func:`parse_length`, :func:`parse_size`, :data:`SUFFIXES`: designer lengths (``2.1``,
  ``210cm``, ``+20cm``, ``120%``, ``=``), the one unit table.

Semantics
---------
- ``DEST - END`` is snapped to whole voxels (length exact to half a voxel); content outside the
  zone is then an exact copy of the original voxels (translated beyond the zone). The grid grows
  or shrinks along the axis; origin and voxel size never change.
- stretch: the slab is resampled linearly (sdf, sRGB); parts stay crisp (nearest source voxel,
  boundary at the zero crossing where the surface passes between two differently labelled
  voxels). Where the slab is compressed, an element (or gap) thinner than the compression that
  linear resampling would skip keeps one voxel with its source distance, colour and part.
- tile: ``tile_count`` copies each scaled to fit; across each internal seam the two copies'
  continuations are cross-faded over ``SEAM_VOXELS`` voxels either side, except where that would
  flip the side of the copy the layer belongs to against the other copy's field more than a
  voxel away (a thin shelf next to a zone plane stays whole in its copy); the sliver a zone plane
  cuts off a board is left out at the inner seams, but a cut gap is never filled, so a seam
  closes no cavity (air between a radiator's sections stays open); copies ``m >= 1`` of parts
  lying wholly inside the zone get new indices after the existing ones (``meta['parts_info']``
  gains entries with ``copy_of``); parts crossing the zone's planes keep their index. A tile to
  the zone's start (``DEST == START``) makes 0 copies: the zone is cut out (whole voxels, its
  start snapped from its end) and the layers either side join at START, unblended.
- global: the whole solid scaled along the axis about its min to the same final length.
- After each edit, every voxel within ``partscale.csdf.BAND_VOXELS`` voxels of the surface whose
  distance could have changed (next to a tile seam: whose distance ball reaches the voxels the
  blend changed or the cells beside them) holds its distance to the edited zero level set *as the grid
  represents it* (sign and surface kept) and the colour and part of its nearest surface point.
  That surface is the piecewise-linear one through the sdf's linear zero crossings along grid
  edges (marching cubes):
  exact for flat surface and close to it for gently curved surface, but it cuts sharp edges and
  corners, so there a recomputed distance can differ from the true object's by up to about 0.9
  voxel (near the edges and corners of an axis-aligned box sampled off the grid).
"""

from .notes import describe_changes, edit_label, unit_suffix
from .recipe import (
    AXES,
    JSON_SCHEMA,
    MAX_EDITS,
    MODES,
    CountEdit,
    Edit,
    HelixZone,
    ObliqueZone,
    RadialZone,
    Recipe,
    RotationZone,
    ScrewZone,
    forward_coordinate,
    parse_edit,
    parse_position,
    source_coordinate,
    tile_count,
)
from .reevaluate import reevaluate
from .resample import SEAM_VOXELS
from .resolved import ResolvedEdit, resolve_edit
from .scale import (
    apply_edit,
    apply_recipe,
    check_recipe_memory,
    naive_edit,
    recipe_from_history,
    recipe_shape,
    scale,
)
from .units import SUFFIXES, parse_length, parse_size
from .warp import (
    apply_helix,
    apply_oblique,
    apply_radial,
    apply_rotation,
    apply_screw,
    apply_warp,
    gauge,
    radial_extent,
    screw_ground,
    warp_source,
)

__all__ = [
    "AXES",
    "JSON_SCHEMA",
    "MAX_EDITS",
    "MODES",
    "SEAM_VOXELS",
    "SUFFIXES",
    "CountEdit",
    "Edit",
    "HelixZone",
    "ObliqueZone",
    "RadialZone",
    "Recipe",
    "ResolvedEdit",
    "RotationZone",
    "ScrewZone",
    "apply_edit",
    "apply_helix",
    "apply_oblique",
    "apply_radial",
    "apply_recipe",
    "apply_rotation",
    "apply_screw",
    "apply_warp",
    "check_recipe_memory",
    "describe_changes",
    "edit_label",
    "forward_coordinate",
    "gauge",
    "naive_edit",
    "parse_edit",
    "parse_length",
    "parse_position",
    "parse_size",
    "radial_extent",
    "recipe_from_history",
    "recipe_shape",
    "reevaluate",
    "resolve_edit",
    "scale",
    "screw_ground",
    "source_coordinate",
    "tile_count",
    "unit_suffix",
    "warp_source",
]
