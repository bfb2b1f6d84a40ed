"""Segment stage: nearly convex parts of a CSDF, one label per voxel.

``fast`` (the default) cuts the voxel solid at its concave creases and merges convex neighbours;
CoACD on the marching-cubes surface is the reference method it is measured against. Results are cached by grid content and parameters, so each object is
segmented once, never per edit. :func:`absorb_slivers`: the step that joins pieces below a
minimum size to their neighbour (the fast method's, usable on any label grid).
:func:`surface_relief`: how rough the surface is (a completed scan's noise), which widens the
tolerances so a bumpy board stays one part.
"""

from .api import (
    DEFAULT_METHOD,
    METHODS,
    cache_key,
    check_method,
    default_cache_dir,
    describe_noise,
    segment,
)
from .concavity import concavity, hull_concavity, part_concavities
from .fast import absorb_slivers
from .relief import noise_tolerance, relief_of, surface_relief

__all__ = [
    "DEFAULT_METHOD",
    "METHODS",
    "absorb_slivers",
    "cache_key",
    "check_method",
    "concavity",
    "default_cache_dir",
    "describe_noise",
    "hull_concavity",
    "noise_tolerance",
    "part_concavities",
    "relief_of",
    "segment",
    "surface_relief",
]
