"""partscale: part-aware resizing of completed 3D objects as coloured signed distance fields.

The pipeline, one module per stage::

    ingest (mesh/grid -> CSDF) -> segment (parts) -> edit (stretch/tile/global)
        -> export (mesh, 3D texture) / render (PNG) / serve (browser editor)

The CSDF type and its file live in :mod:`partscale.csdf`; :mod:`partscale.thickness` measures
the features thinner than the grid holds well (``partscale info`` warns about them).
:func:`reuse_freed_memory` lets a process reuse freed grids' pages (the CLI calls it; so
should an application that edits large grids in a loop); :func:`release_freed_memory` hands
them back (each batch job does both).
"""

# first: a writable place for numba's compiled kernels, before any module with one is imported
from . import _jit  # noqa: F401
from ._memory import release_freed_memory, reuse_freed_memory
from .csdf import CSDF, load, make, save
from .errors import InputError, PartscaleError

__version__ = "0.1.0"
__all__ = [
    "CSDF",
    "InputError",
    "PartscaleError",
    "load",
    "make",
    "release_freed_memory",
    "reuse_freed_memory",
    "save",
]
