"""partscale: part-aware resizing of completed 3D objects as coloured signed distance fields.

The pipeline, one module per stage::

    ingest (mesh/grid -> CSDF) -> segment (parts) -> edit (stretch/tile/global)
        -> export (mesh, 3D texture) / render (PNG) / serve (browser editor)

The CSDF type and its file live in :mod:`partscale.csdf`; :mod:`partscale.thickness` measures
the features thinner than the grid holds well (``partscale info`` warns about them).
"""

from .csdf import CSDF, load, make, save
from .errors import InputError, PartscaleError

__version__ = "0.1.0"
__all__ = ["CSDF", "InputError", "PartscaleError", "load", "make", "save"]
