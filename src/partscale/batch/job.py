"""The per-object job, the same in every engine: an input and its options -> its outputs.

:func:`batch_spec` checks the batch's options once into a *spec*, a plain JSON-able dict whose
hash (:func:`options_hash`) decides whether a finished object is current; :func:`object_spec`
lays a manifest row's own options over it (through :mod:`partscale._options`, the vocabulary
every entry point shares).
:func:`run_job` is pure: it reads the input, writes every output atomically under
``OUTDIR/<name>/`` and returns their paths; the same input and spec give the same bytes.
:func:`execute` wraps it for a worker: never raises, measures time and peak memory.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
import traceback
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, TypedDict, cast

from .. import __version__, release_freed_memory, reuse_freed_memory
from .._files import staged_writes
from .._options import ON_WORDS, check_res, choice, choices, is_off, yes_no
from ..csdf import SUFFIX as CSDF_SUFFIX
from ..errors import InputError, one_line, shown

DEFAULT_EXPORT = ("csdf",)
MESH_FORMATS = ("glb", "ply", "obj")
TEXTURE_FORMATS = ("raw", "png", "nrrd")
EXPORT_FORMATS = ("csdf", *MESH_FORMATS, *TEXTURE_FORMATS)
"""``--export`` choices: the CSDF itself, a mesh (:func:`partscale.export.export_mesh`) or a 3D
texture (:func:`partscale.export.export_texture`); each written as ``<name>.<format>``."""
RENDER_SIZE = 512
THREAD_VARIABLES = (
    "NUMBA_NUM_THREADS",
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "PYTHON_CPU_COUNT",  # Python >= 3.13's os.cpu_count(); older ones get patched in the worker
)


class Spec(TypedDict):
    """One object's pipeline, checked and canonical (JSON-able; :func:`options_hash` hashes it)."""

    version: str
    res: int
    square: bool
    segment: str | None
    recipe: Any
    """The recipe's canonical JSON (or as given, where its lengths carry a unit); None: none."""
    fit: list[str] | None
    allow_deform: bool
    export: list[str]
    render: str | None


class Task(TypedDict):
    """One object to run, as every engine gets it (made by :func:`partscale.batch.api.plan`)."""

    name: str
    path: str
    spec: Spec
    outdir: str
    input_hash: str
    options_hash: str
    attempts: int


def batch_spec(options: Mapping[str, Any], *, where: str = "batch") -> Spec:
    """The batch's own options checked once into the spec every object starts from.

    Parameters
    ----------
    options : mapping
        Any of ``res``, ``square``, ``segment``, ``recipe``, ``fit``, ``allow_deform``,
        ``export``, ``render`` (typed, or as manifest text); the others take their defaults.
    where : str
        Names them in error messages.

    Returns
    -------
    Spec
        The checked, canonical spec (the recipe's content, not its path).

    Examples
    --------
    >>> from partscale.batch.job import batch_spec
    >>> spec = batch_spec({"res": "64", "export": "glb,png", "render": True})
    >>> spec["res"], spec["export"], spec["render"], spec["segment"]
    (64, ['glb', 'png'], 'iso', None)
    """
    base: Spec = {
        "version": __version__,
        "res": 128,
        "square": False,
        "segment": None,
        "recipe": None,
        "fit": None,
        "allow_deform": False,
        "export": list(DEFAULT_EXPORT),
        "render": None,
    }
    return object_spec(base, options, where=where)


def object_spec(base: Spec, row: Mapping[str, Any], *, where: str) -> Spec:
    """One object's spec: ``base`` (see :func:`batch_spec`) with its manifest row's options.

    Only the row's own values are read (the batch's were checked once); values may come as CSV
    text (``"64"``, ``"glb,png"``, ``"false"``, ``"none"``). ``where`` names the object in error
    messages. Raises :class:`InputError` for a bad value, for a recipe and a size together, or
    for no output at all.
    """
    spec = cast(Spec, dict(base))
    for key, value in row.items():
        if key not in OPTION_CHECKS:
            raise InputError(
                f"{where}: unknown option {key!r}; options are {', '.join(OPTION_CHECKS)}"
            )
        spec[key] = OPTION_CHECKS[key](value, where)  # type: ignore[literal-required]
    if spec["recipe"] is not None and spec["fit"] is not None:
        raise InputError(f"{where}: expected a recipe or a size (fit), got both")
    if not spec["export"] and spec["render"] is None:
        raise InputError(
            f"{where}: expected at least one output (export or render), got none",
            params=("export", "render"),
        )
    return spec


def _segment(value: Any, where: str) -> str | None:
    if isinstance(value, bool):
        return "fast" if value else None
    if is_off(value):
        return None
    from ..segment import check_method

    return check_method(str(value).strip().lower(), what=f"{where}: segment")


def _recipe(value: Any, where: str) -> Any:
    return None if is_off(value) else _recipe_json(value)


def _size(value: Any, where: str) -> list[str] | None:
    if is_off(value):
        return None
    if not isinstance(value, str | list | tuple):
        raise InputError(f"{where}: size: expected 3 sizes (X Y Z), got {shown(value)}")
    size = value.split() if isinstance(value, str) else list(value)
    if len(size) != 3:
        raise InputError(f"{where}: size: expected 3 sizes (X Y Z), got {value!r}")
    return [str(s) for s in size]


def _render(value: Any, where: str) -> str | None:
    if isinstance(value, bool):
        return "iso" if value else None
    if is_off(value):
        return None
    if isinstance(value, str) and value.strip().lower() in ON_WORDS:
        return "iso"
    from ..render import VIEWS

    return choice(value, f"{where}: render", VIEWS)


OPTION_CHECKS: dict[str, Callable[[Any, str], Any]] = {
    "res": lambda v, where: check_res(v, f"{where}: res", text=True),  # import's own bounds
    "square": lambda v, where: yes_no(v, f"{where}: square", text=True),
    "segment": _segment,
    "recipe": _recipe,
    "fit": _size,
    "allow_deform": lambda v, where: yes_no(v, f"{where}: allow_deform", text=True),
    "export": lambda v, where: choices(v, f"{where}: export", EXPORT_FORMATS, noun="formats"),
    "render": _render,
}
"""Each option of a spec: its check, ``(value, where) -> canonical value``."""


def _recipe_json(recipe: Any) -> Any:
    """A recipe (a file's path or its JSON) checked, as the spec holds it: canonical JSON, or as
    given where it has lengths with a unit (``"30cm"``), which only each object's units convert
    (in :func:`run_job`; an object not in metres refuses them there).
    """
    from .._files import read_json
    from ..edit import Recipe

    if not isinstance(recipe, str | os.PathLike | dict):
        raise InputError(
            f"recipe: expected a recipe file's path or a recipe object, got {shown(recipe)}"
        )
    path = Path(recipe) if isinstance(recipe, str | os.PathLike) else None
    raw = read_json(path, what="a recipe JSON file") if path is not None else recipe
    try:
        try:
            return Recipe.parse(raw).to_json()
        except InputError:
            Recipe.parse(raw, units="m")  # valid for an object in metres: kept as given
            return raw
    except InputError as exc:
        raise InputError(f"{path}: {exc}" if path is not None else str(exc)) from None


def stages(options: Mapping[str, Any]) -> list[str]:
    """The stages (packages of ``partscale``) a job with these options imports, in order.

    ``options`` is a spec or options as given (unchecked: a value that is not off counts as
    asked); the local engine's template imports these before its workers fork. Every job
    imports ``ingest`` and ``edit`` (whose units the import reads).

    Examples
    --------
    >>> from partscale.batch.job import stages
    >>> stages({"segment": "fast", "export": "glb"}), stages({"export": ["csdf"], "fit": None})
    (['ingest', 'edit', 'segment', 'export'], ['ingest', 'edit'])
    """
    asked = [
        ("segment", not _off(options.get("segment"))),
        ("zones", not (_off(options.get("recipe")) and _off(options.get("fit")))),
        ("export", any(f != "csdf" for f in _words(options.get("export", DEFAULT_EXPORT)))),
        ("render", not _off(options.get("render"))),
    ]
    return ["ingest", "edit", *(name for name, yes in asked if yes)]


def _off(value: Any) -> bool:
    return value is False or is_off(value)


def _words(value: Any) -> list[str]:
    """Formats as given (a list, or text separated by commas), lower case."""
    items = (
        value.split(",")
        if isinstance(value, str)
        else value
        if isinstance(value, list | tuple)
        else []
    )
    return [str(f).strip().lower().lstrip(".") for f in items if not is_off(f)]


def options_hash(spec: Spec) -> str:
    """SHA-256 (hex) of the spec's canonical JSON."""
    return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()


def run_job(path: str | os.PathLike, name: str, spec: Spec, outdir: str | os.PathLike) -> list[str]:
    """Import, segment, edit and write one object; the outputs' paths relative to ``outdir``.

    Segmentation bypasses the segment cache, so results never depend on what earlier runs left
    there. Raises what the stages raise (:class:`InputError` for bad input).
    """
    from ..csdf import load as load_csdf
    from ..ingest import load

    path, outdir = Path(path), Path(outdir)
    folder = outdir / name
    is_csdf = path.name.lower().endswith(CSDF_SUFFIX)
    if is_csdf and spec["square"]:
        raise InputError(f"{path}: expected a mesh for square, got a CSDF")
    folder.mkdir(parents=True, exist_ok=True)
    if is_csdf:
        c = load_csdf(path)
    else:
        c = load(path, res=spec["res"], square=spec["square"])
    if spec["segment"]:
        from ..segment import segment

        c = segment(c, method=spec["segment"], cache=False)
    if spec["recipe"]:
        # parsed with the object's units; counts ("copies": "+1") made zone edits on it
        from ..edit import Recipe, apply_recipe
        from ..zones import resolve_counts

        recipe, _ = resolve_counts(c, Recipe.parse(spec["recipe"], units=c.meta.get("units")))
        c = apply_recipe(c, recipe)
    if spec["fit"]:
        c = _fit(c, spec["fit"], spec.get("allow_deform", False))
    written: list[Path] = []
    with staged_writes():  # the object's outputs are renamed into place all together, or none
        for fmt in spec["export"]:
            if fmt == "csdf":
                written.append(save_csdf(c, folder / f"{name}{CSDF_SUFFIX}"))
            elif fmt in MESH_FORMATS:
                from ..export import export_mesh

                written.append(export_mesh(c, folder / f"{name}.{fmt}"))
            else:
                from ..export import export_texture

                written += export_texture(c, folder / f"{name}.{fmt}")
        if spec["render"]:
            from ..render import render, save_png

            image = render(c, view=spec["render"], size=RENDER_SIZE)
            written.append(save_png(image, folder / f"{name}.render-{spec['render']}.png"))
    return [Path(p).resolve().relative_to(outdir.resolve()).as_posix() for p in written]


def _fit(c, size, allow_deform=False):
    # partscale.zones.fit gives the recipe that brings the object to ``size`` (refused, this
    # object failing in one line, where only a deformation would, unless ``allow_deform``)
    from ..edit import apply_recipe
    from ..zones import fit

    recipe, _why = fit(c, size, allow_deform=allow_deform)
    return apply_recipe(c, recipe) if recipe.edits else c


def save_csdf(c, path: Path) -> Path:
    """:func:`partscale.csdf.save`: the same CSDF gives the same bytes whenever it is written."""
    from ..csdf import save

    return save(c, path)


# -- in a worker ------------------------------------------------------------------------------


def thread_env(threads: int) -> dict[str, str]:
    """Environment capping numba, BLAS and OpenMP at ``threads`` threads (set before import)."""
    return dict.fromkeys(THREAD_VARIABLES, str(max(1, int(threads))))


def limit_threads(threads: int) -> None:
    """In a worker: make partscale's own thread and process pools use ``threads`` cores.

    They size themselves by ``os.cpu_count()``, which Python before 3.13 has no variable for.
    """
    n = max(1, int(threads))
    os.environ.update(thread_env(n))
    os.cpu_count = lambda: n  # only in this worker process


def _reset_peak() -> bool:
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")  # resets VmHWM, the peak resident set, to the current one
        return True
    except OSError:
        return False


def peak_memory() -> int:
    """Peak resident memory of this process in bytes (since the last reset, where possible)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _cpu_seconds() -> float:
    """CPU seconds of this process and its finished children (forked helpers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def execute(task: Mapping[str, Any]) -> dict[str, Any]:
    """Run one task (``path``, ``name``, ``spec``, ``outdir``); never raises.

    Returns ``{"name", "ok", "outputs", "error", "seconds", "cpu_seconds", "peak_memory"}``;
    ``error`` is one line (an :class:`InputError`'s message, else the exception's type and
    message); ``cpu_seconds`` counts this process and the helpers it forked.
    """
    # within the job, freed grids' pages serve the next grid (at 256³ an edit's output is
    # otherwise faulted in and zeroed anew); they are released when it ends (below), so the
    # next job's peak is its own
    reuse_freed_memory()
    _reset_peak()
    t0, cpu0 = time.perf_counter(), _cpu_seconds()
    out: dict[str, Any] = {"name": task["name"], "ok": True, "outputs": [], "error": ""}
    try:
        out["outputs"] = run_job(task["path"], task["name"], task["spec"], task["outdir"])
    except InputError as exc:
        out.update(ok=False, error=one_line(exc))
    except MemoryError:
        out.update(ok=False, error="out of memory (MemoryError)")
    except Exception as exc:
        tb = traceback.extract_tb(exc.__traceback__)
        at = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        out.update(ok=False, error=f"{type(exc).__name__}: {one_line(exc)}{at}")
    out["seconds"] = time.perf_counter() - t0
    out["cpu_seconds"] = _cpu_seconds() - cpu0
    out["peak_memory"] = peak_memory()
    release_freed_memory()
    return out
