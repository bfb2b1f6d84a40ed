"""Edit stage: part-aware selective scaling (stretch, tile, global) driven by recipes."""

from .recipe import AXES, JSON_SCHEMA, MODES, Edit, Recipe, source_coordinate, tile_count
from .reevaluate import BAND_VOXELS, reevaluate
from .scale import apply_edit, apply_recipe, naive_edit, recipe_from_history, scale

__all__ = [
    "AXES",
    "BAND_VOXELS",
    "JSON_SCHEMA",
    "MODES",
    "Edit",
    "Recipe",
    "apply_edit",
    "apply_recipe",
    "naive_edit",
    "recipe_from_history",
    "reevaluate",
    "scale",
    "source_coordinate",
    "tile_count",
]
