# The top level's names, read by partscale/__init__.py at import (each loaded on first use)
# and by type checkers. One line per name: `from .MODULE import NAME [as ALIAS]` or
# `from . import MODULE`; __all__ lists them all (a test holds the two to agree).

from . import batch as batch
from . import color as color
from . import complete as complete
from . import csdf as csdf
from . import data as data
from . import edit as edit
from . import errors as errors
from . import evaluate as evaluate
from . import export as export
from . import ingest as ingest
from . import meshedit as meshedit
from . import orient as orient
from . import progress as progress
from . import render as render
from . import segment as segment
from . import serve as serve
from . import shapes as shapes
from . import surface as surface
from . import thickness as thickness
from . import zones as zones
from ._memory import release_freed_memory as release_freed_memory
from ._memory import reuse_freed_memory as reuse_freed_memory
from .complete import complete_file as complete_file
from .csdf import CSDF as CSDF
from .csdf import load as load
from .csdf import make as make
from .csdf import save as save
from .edit import apply_recipe as apply_recipe
from .edit import scale as scale
from .errors import InputError as InputError
from .errors import PartscaleError as PartscaleError
from .export import export_mesh as export_mesh
from .ingest import load as import_file
from .zones import fit as fit
from .zones import suggest as suggest

__version__: str
__all__ = [
    "CSDF",
    "InputError",
    "PartscaleError",
    "apply_recipe",
    "batch",
    "color",
    "complete",
    "complete_file",
    "csdf",
    "data",
    "edit",
    "errors",
    "evaluate",
    "export",
    "export_mesh",
    "fit",
    "import_file",
    "ingest",
    "load",
    "make",
    "meshedit",
    "orient",
    "progress",
    "release_freed_memory",
    "render",
    "reuse_freed_memory",
    "save",
    "scale",
    "segment",
    "serve",
    "shapes",
    "suggest",
    "surface",
    "thickness",
    "zones",
]
