"""partscale: part-aware resizing of completed 3D objects as coloured signed distance fields.

The pipeline, one package per stage::

    ingest (mesh/grid -> CSDF) -> segment (parts) -> zones (where to resize) -> edit
        -> export (mesh, 3D texture) / render (PNG) / serve (browser editor)

The top level offers the pipeline's main functions and every stage's package, each imported
on first use (``import partscale`` loads none of numba, trimesh or scipy):

- files: :func:`import_file` (a mesh or SDF grid -> :class:`CSDF`), :func:`complete_file` (a
  scan -> :class:`CSDF`), :func:`load` and :func:`save` (the ``.csdf.npz`` file), :func:`make`;
- resizing: :func:`fit` (the recipe for a size), :func:`suggest` (zone candidates),
  :func:`apply_recipe`, :func:`scale` (one edit);
- output: :func:`export_mesh`; :func:`partscale.render.render` and
  :func:`partscale.segment.segment` live in their stage's package, under the stage's name;
- :class:`PartscaleError` and :class:`InputError` (bad input, with expected vs got).

The CSDF type and its file live in :mod:`partscale.csdf`; :mod:`partscale.thickness` measures
the features thinner than the grid holds well (``partscale info`` warns about them).
:func:`reuse_freed_memory` lets a process reuse freed grids' pages (the CLI calls it; so
should an application that edits large grids in a loop); :func:`release_freed_memory` hands
them back (each batch job does both).

Examples
--------
>>> import partscale
>>> partscale.fit  # doctest: +ELLIPSIS
<function fit at ...>
"""

import ast
import importlib
from pathlib import Path
from typing import Any

# first: a writable place for numba's compiled kernels, before any module with one is imported
from . import _jit  # noqa: F401


def _read_stub() -> dict[str, tuple[str, str | None]]:
    """Name -> (module, attribute or None for the module itself), from ``__init__.pyi``."""
    names: dict[str, tuple[str, str | None]] = {}
    tree = ast.parse(Path(__file__).with_suffix(".pyi").read_text())
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                name = alias.asname or alias.name
                if node.module is None:
                    names[name] = (f"{__name__}.{alias.name}", None)
                else:
                    names[name] = (f"{__name__}.{node.module}", alias.name)
    return names


_LAZY = _read_stub()
__version__ = "0.1.0"
__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    """Import the module behind a top-level name on first use, then keep the name."""
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, attr = _LAZY[name]
    value = importlib.import_module(module)
    if attr is not None:
        value = getattr(value, attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The top level's names (:data:`__all__`) and the module's own."""
    return sorted({*__all__, *globals()})
