"""Compile partscale's numba kernels ahead of first use: ``python -m partscale.warmup``.

The first command on a machine otherwise spends tens of seconds compiling the kernels it needs
(numba compiles on first call and caches the result, see :mod:`partscale._jit`). This runs the
pipeline once on small objects so that every common kernel is compiled and cached: the import of
the shipped table (:func:`partscale.data.table`), then segment, the three edit modes, fit,
suggest, render, the mesh and texture exports and the mesh route on a table of boxes. Two
processes share the work (the import's kernels in one, the rest in the other): about a minute on
two cores, once. ``./dev.sh setup`` runs it; so can a Dockerfile after ``pip install``.
"""

from __future__ import annotations

import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

__all__ = ["WarmupResult", "warmup"]


@dataclass(frozen=True)
class WarmupResult:
    """What :func:`warmup` did: wall seconds, and the kernels each part compiled.

    Attributes
    ----------
    seconds : float
        Wall seconds of the whole warm-up.
    compiled : dict of str to int
        Per part (``"import"``, ``"edit"``), how many of partscale's kernels numba compiled;
        0 where the cache already held them all.

    Examples
    --------
    >>> from partscale.warmup import WarmupResult
    >>> result = WarmupResult(1.5, {"import": 0, "edit": 0})
    >>> sum(result.compiled.values())
    0
    """

    seconds: float
    compiled: dict[str, int]


def _count_compiles() -> list[str]:
    """A list that gathers the names of partscale's kernels as numba starts compiling them."""
    from numba.core import event

    names: list[str] = []

    class _Count(event.Listener):
        def on_start(self, ev) -> None:
            fn = getattr((ev.data or {}).get("dispatcher"), "py_func", None)
            if fn is not None and fn.__module__.startswith("partscale."):
                names.append(f"{fn.__module__}.{fn.__qualname__}")

        def on_end(self, ev) -> None:
            pass

    event.register("numba:compile", _Count())
    return names


def _import_part() -> int:
    """``partscale import`` of the shipped table and ``partscale info``'s measures."""
    names = _count_compiles()
    from . import data, ingest
    from .cli.info import summary

    c = ingest.load(data.table(), res=48)
    summary(c)
    return len(set(names))


def _box_table():
    """A table of boxes (top, four legs), a CSDF in metres, coloured by height."""
    import numpy as np

    from . import shapes

    top = ((0.0, 0.70, 0.0), (1.2, 0.76, 0.6))
    legs = [((x, 0.0, z), (x + 0.06, 0.70, z + 0.06)) for x in (0.02, 1.12) for z in (0.02, 0.52)]
    boxes = [top, *legs]
    c = shapes.grid(
        lambda p: shapes.boxes_sdf(p, boxes),
        ((0.0, 0.0, 0.0), (1.2, 0.76, 0.6)),
        voxel_size=0.02,
        color=lambda p: np.where(p[:, 1:2] > 0.7, [200, 150, 100], [120, 80, 50]).astype(np.uint8),
    )
    return c.replace(meta={**c.meta, "units": "m"})


def _edit_part() -> int:
    """segment, scale (stretch, tile, global), fit, suggest, render, export, the mesh route."""
    names = _count_compiles()
    from . import data, edit, export, render, segment, zones
    from .meshedit import edit_mesh_file

    c = segment.segment(_box_table(), method="fast", cache=False)
    for mode in ("stretch", "tile", "global"):
        edit.apply_recipe(c, edit.Recipe((edit.Edit("x", "30%", "70%", "90%", mode),)))
    recipe, _why = zones.fit(c, ["120%", "=", "="])
    edit.apply_recipe(c, recipe)
    zones.suggest(c, None)
    render.render(c, size=64)
    render.render(c, size=64, parts=True)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for suffix in (".glb", ".ply", ".obj"):
            export.export_mesh(c, folder / f"t{suffix}")
        for suffix in (".raw", ".png", ".nrrd"):
            export.export_texture(export.resize_grid(c, 32), folder / f"t{suffix}")
        stretch = edit.Recipe((edit.Edit("x", "35%", "65%", "80%", "stretch"),))
        edit_mesh_file(data.table(), folder / "m.glb", stretch)
    return len(set(names))


def warmup(*, workers: int = 2) -> WarmupResult:
    """Compile (or load from the cache) the kernels of the commonly used commands.

    Parameters
    ----------
    workers : int
        Processes to share the work: 2 (the import in one, the rest in the other) or 1.

    Returns
    -------
    WarmupResult
        Wall seconds and the kernels each part compiled.

    Examples
    --------
    >>> from partscale.warmup import warmup
    >>> result = warmup()  # doctest: +SKIP
    >>> result.compiled  # doctest: +SKIP
    {'import': 18, 'edit': 31}
    """
    t0 = time.perf_counter()
    parts = {"import": _import_part, "edit": _edit_part}
    if workers <= 1:
        compiled = {name: fn() for name, fn in parts.items()}
    else:
        with ProcessPoolExecutor(max_workers=2, mp_context=get_context("spawn")) as pool:
            futures = {name: pool.submit(fn) for name, fn in parts.items()}
            compiled = {name: f.result() for name, f in futures.items()}
    return WarmupResult(time.perf_counter() - t0, compiled)


def main() -> int:
    sys.stderr.write(
        "partscale: compiling its numba kernels for this machine (once; about a minute on two "
        "cores)\n"
    )
    result = warmup()
    n = sum(result.compiled.values())
    sys.stderr.write(
        f"partscale: {n} kernels compiled and cached in {result.seconds:.0f} s"
        + (" (all were cached already)" if n == 0 else "")
        + "\n"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
