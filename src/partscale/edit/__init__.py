"""Edit stage: part-aware selective scaling (stretch, tile, global) driven by recipes."""

from .recipe import AXES, JSON_SCHEMA, MODES, Edit, Recipe, source_coordinate, tile_count

__all__ = ["AXES", "JSON_SCHEMA", "MODES", "Edit", "Recipe", "source_coordinate", "tile_count"]
