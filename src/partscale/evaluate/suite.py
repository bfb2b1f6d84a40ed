"""The evaluation suite: real objects, each with one plausible edit, run in every mode and measured.

A suite file is JSON::

    {"version": 1,
     "res": 128,                      # import resolution (longest side, voxels); optional
     "data": "path/to/data",          # folder the object paths are relative to; optional
     "objects": [
        {"name": "table-longer",      # a plain file name (not contact_sheet): figure NAME.png
         "path": "kenney/table.glb",
         "edit": {"axis": "x", "zone": ["20%", "80%"], "to": "105%"},
         "kind": "solid" | "repeating",   # what the paper expects: optional
         "view": "iso" | "front" | "side" | "top",  # optional, default iso
         "elements": {"axis": "x", "count": 3},   # what the designer asked: optional
         "hardware": true,                # its knobs and handles judged too: optional
         "note": "..."}, ...]}

``elements`` states the intent in the designer's unit: the count of the repeated element (seats,
doors, shelf rows: :func:`partscale.zones.find_elements`' best group) along ``axis`` after the
edit. Every result is then counted too (column ``elements``); a result off that count fails its
entry (a sofa made wider with two fat seats, where a third was asked for), and so does one whose
elements changed length (``element_change``: a seat stretched, an element cut). ``"hardware":
true`` (with ``elements``) also judges the local features along that axis (``feature_shape``:
a knob or handle drawn out, or lost).

An entry may hold ``"recipe": {"edits": [...]}`` (the recipe schema of :mod:`partscale.edit`,
several zones and axes, each edit with its mode) instead of ``"edit"``: it runs as given, one
row, mode ``recipe``, scored on every zone (zones read from the result's history).
``path`` may also name a ``.csdf.npz`` file (used as is, no import). The data folder is, in order:
the ``data`` argument, ``PARTSCALE_DATA``, the suite's ``data`` key (relative to the suite file),
``../shared/data`` from the working directory, ``../../shared/data`` from the suite file.

Each entry's edit runs in every mode of :data:`COMPARED_MODES`: ``global``, ``stretch``,
``tile`` and the labelled baseline ``naive-stretch`` / ``naive-tile`` (per-column linear
resampling of the slab, no re-evaluation, plain concatenation for repeats: what the paper's
public prototype does).
Then each mode of :data:`RECIPE_MODES` runs: a function of the original and the entry giving
the recipe to apply (None: the mode does not apply to this entry); the result is scored on the
zones its history records.
An entry that cannot run (bad name, missing file, bad edit, zone outside the solid, a figure
that cannot be written) is reported with one line and the others still run.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path, check_writable, read_json
from .._options import choice, count, keyword_options, yes_no
from ..csdf import CSDF, SUFFIX, load
from ..edit import Edit, Recipe, apply_edit, apply_recipe, naive_edit, resolve_edit
from ..errors import InputError
from ..progress import ProgressCallback, resolve, scaled
from ..render import VIEWS, render
from ..zones import fit
from . import figures, metrics, report

#: The modes every edit runs in (the stage's, and the baseline's), in figure order.
COMPARED_MODES = ("global", "stretch", "tile", "naive-stretch", "naive-tile")
LABELS = {
    "original": "original",
    "global": "global",
    "stretch": "stretch",
    "tile": "tile",
    "naive-stretch": "naive stretch*",
    "naive-tile": "naive tile*",
    "fit": "fit (own zones)",
}
#: Modes whose recipe comes from a function ``(original, entry) -> Recipe | None`` (None: not
#: for this entry), run after :data:`COMPARED_MODES` and scored on the zones the result's history
#: records. A mode that chooses its own zones (``fit``) is one more entry here.
RECIPE_MODES: dict[str, Callable[[CSDF, Entry], Recipe | None]] = {
    "recipe": lambda original, entry: entry.recipe,
    "fit": lambda original, entry: fit_recipe(original, entry),
}
KINDS = ("solid", "repeating")
DEFAULT_RES = 128
MIN_SUITE_RES, MAX_SUITE_RES = 8, 1024
"""The ``res`` a suite (and its run) may ask for."""
PANEL = 256


@dataclass(frozen=True)
class Entry:
    """One suite object; ``error`` is set when the entry itself is malformed."""

    name: str
    path: str
    edit: Edit | None
    kind: str | None = None
    view: str = "iso"
    note: str = ""
    error: str | None = None
    recipe: Recipe | None = None
    elements: tuple[str, int] | None = None
    hardware: bool = False

    def describe(self) -> str:
        """The entry's edit (or recipe) in one line, for tables and figures."""
        if self.recipe is not None:
            return "; ".join(
                f"{e.axis}: zone [{e.start}, {e.end}] to {e.dest} {e.mode}"
                if isinstance(e, Edit)
                else str(e.to_json())
                for e in self.recipe.edits
            )
        if self.edit is None:
            return ""
        e = self.edit
        return f"{e.axis}: zone [{e.start}, {e.end}] to {e.dest}"


@dataclass
class Suite:
    """A suite file, read and validated (:func:`load_suite`).

    Attributes
    ----------
    entries : list of Entry
        One per object; a malformed one carries its ``error`` (the others still run).
    res : int
        Import resolution, voxels along the longest side.
    data : Path, optional
        The suite's ``data`` folder (relative to the suite file).
    source : Path, optional
        The file it was read from.

    Examples
    --------
    >>> from partscale import evaluate
    >>> suite = evaluate.Suite([], res=64)
    >>> suite.res, suite.data
    (64, None)
    """

    entries: list[Entry]
    res: int = DEFAULT_RES
    data: Path | None = None
    source: Path | None = None


#: The contact sheet's file stem: no entry may take it (its NAME.png would be overwritten).
CONTACT_SHEET = "contact_sheet"


def fit_recipe(original: CSDF, entry: Entry) -> Recipe | None:
    """The recipe :func:`partscale.zones.fit` chooses for the entry's target size: along the
    edit's axis the length the edit reaches (the extent plus ``dest - end``, as the stage
    snaps it), the other axes unchanged. None for a recipe entry (no single target).
    """
    if entry.edit is None:
        return None
    r = resolve_edit(original, entry.edit)
    size: list[str | float] = ["=", "=", "="]
    size[r.axis] = r.target_length
    return fit(original, size)[0]


def _plain_name(name: str) -> bool:
    # the name becomes the figure's file name inside the output folder: never a path ('..'
    # needs a separator or a leading '.' to be one); lower(): case-insensitive file systems
    return (
        bool(name)
        and not (name.startswith(".") or "/" in name or "\\" in name)
        and name.isprintable()
        and name.lower() != CONTACT_SHEET
    )


def _entry(obj: Any, i: int) -> Entry:
    where = f"objects[{i}]"
    if not isinstance(obj, dict):
        return Entry(where, "", None, error=f"{where}: expected an object, got {obj!r}")
    name = where if obj.get("name") is None else str(obj["name"])
    if not _plain_name(name):
        return Entry(
            name,
            str(obj.get("path", "")),
            None,
            error=f"{where}: name: expected a plain file name (not empty, no '/', '\\', leading "
            f"'.', control characters or {CONTACT_SHEET}), got {name!r}",
        )
    try:
        keys = {"name", "path", "edit", "recipe", "kind", "view", "note", "elements", "hardware"}
        unknown = set(obj) - keys
        if unknown:
            raise InputError(
                f"unknown key(s) {sorted(unknown)}; keys are name, path, edit, recipe, kind, "
                "view, note, elements, hardware"
            )
        elements = _elements(obj.get("elements"))
        hardware = yes_no(obj.get("hardware", False), "hardware")
        if hardware and elements is None:
            raise InputError("hardware: expected it with elements (the axis it is judged along)")
        path = obj.get("path")
        if not isinstance(path, str) or not path:
            raise InputError(f"path: expected a file path, got {path!r}")
        if ("edit" in obj) == ("recipe" in obj):
            got = "both" if "edit" in obj else "neither"
            raise InputError(f"expected an edit or a recipe (one), got {got}")
        view = choice(obj.get("view", "iso"), "view", VIEWS)
        kind = obj.get("kind")
        kind = None if kind is None else choice(kind, "kind", KINDS)
        if "recipe" in obj:
            edit, recipe = None, _recipe(obj["recipe"])
        else:
            edit, recipe = _edit(obj.get("edit")), None
        return Entry(
            name,
            path,
            edit,
            kind,
            view,
            str(obj.get("note", "")),
            recipe=recipe,
            elements=elements,
            hardware=hardware,
        )
    except InputError as exc:
        return Entry(name, str(obj.get("path", "")), None, error=f"{name}: {exc}")


def _recipe(obj: Any) -> Recipe:
    """An entry's ``recipe`` key, parsed; errors name the key."""
    try:
        return Recipe.parse(obj)
    except InputError as exc:
        raise InputError(f"recipe: {exc}") from None


def _edit(obj: Any) -> Edit:
    """An entry's ``edit`` key, parsed: no ``mode`` (the suite runs every mode)."""
    if isinstance(obj, dict) and "mode" in obj:
        raise InputError("edit.mode: expected none (the suite runs every mode), got one")
    return Edit.parse(obj, where="edit")


def _elements(obj: Any) -> tuple[str, int] | None:
    """An entry's ``elements`` key: ``{"axis": "x", "count": N}`` (N >= 1), or None."""
    if obj is None:
        return None
    if (
        not isinstance(obj, dict)
        or set(obj) != {"axis", "count"}
        or obj["axis"] not in ("x", "y", "z")
        or not isinstance(obj["count"], int)
        or isinstance(obj["count"], bool)
        or obj["count"] < 1
    ):
        raise InputError(f'elements: expected {{"axis": "x|y|z", "count": N >= 1}}, got {obj!r}')
    return obj["axis"], obj["count"]


def count_elements(c: CSDF, axis: str) -> int:
    """The elements of the repeat group a designer counts along ``axis`` (1 where none repeats:
    the whole row is one element).
    """
    from ..zones import find_elements

    g = find_elements(c, axis).best
    return 1 if g is None else len(g.members)


def parse_suite(obj: Any, *, source: Path | None = None) -> Suite:
    """Validate a suite's JSON. Malformed entries are kept, marked with their error."""
    where = str(source) if source else "suite"
    if not isinstance(obj, dict) or not isinstance(obj.get("objects"), list):
        raise InputError(f"{where}: expected {{'objects': [...]}}, got {str(obj)[:60]!r}")
    unknown = set(obj) - {"version", "description", "res", "data", "objects"}
    if unknown:
        raise InputError(
            f"{where}: unknown key(s) {sorted(unknown)}; keys are version, description, res, "
            "data, objects"
        )
    if obj.get("version", 1) != 1:
        raise InputError(f"{where}: expected version 1, got {obj['version']!r}")
    res = count(obj.get("res", DEFAULT_RES), f"{where}: res", lo=MIN_SUITE_RES, hi=MAX_SUITE_RES)
    entries = [_entry(o, i) for i, o in enumerate(obj["objects"])]
    if not entries:
        raise InputError(f"{where}: expected at least one object, got none")
    names = [e.name for e in entries]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f"{where}: expected unique object names, got {', '.join(dup)} twice")
    data = None
    if obj.get("data"):
        data = Path(obj["data"])
        if source is not None and not data.is_absolute():
            data = source.parent / data
    return Suite(entries, res, data, source)


def load_suite(path: str | os.PathLike) -> Suite:
    """Read a suite file (see the module docstring for its keys).

    Parameters
    ----------
    path : str or os.PathLike
        The suite JSON file.

    Returns
    -------
    Suite
        Validated; a malformed entry is kept with its one-line ``error``.

    Raises
    ------
    partscale.errors.InputError
        For a file that cannot be read or is not a suite (unknown keys, no objects, names
        twice).

    Examples
    --------
    >>> import json
    >>> from pathlib import Path
    >>> from partscale import evaluate
    >>> entry = {"name": "longer", "path": "table.glb",
    ...          "edit": {"axis": "x", "zone": ["30%", "70%"], "to": "120%"}}
    >>> suite = {"res": 32, "objects": [entry, {"name": "bad"}]}
    >>> _ = Path("suite.json").write_text(json.dumps(suite))
    >>> suite = evaluate.load_suite("suite.json")
    >>> suite.res, [e.name for e in suite.entries], suite.entries[1].error
    (32, ['longer', 'bad'], 'bad: path: expected a file path, got None')
    """
    path = Path(path)
    obj = read_json(path, what="a suite JSON file")
    return parse_suite(obj, source=path)


def data_folder(suite: Suite, data: str | os.PathLike | None = None) -> Path | None:
    """Where the suite's object paths are relative to (see module docstring); None if nowhere."""
    candidates: list[Path] = []
    if data is not None:
        return Path(data)
    if os.environ.get("PARTSCALE_DATA"):
        candidates.append(Path(os.environ["PARTSCALE_DATA"]))
    if suite.data is not None:
        candidates.append(suite.data)
    candidates.append(Path.cwd().parent / "shared" / "data")
    if suite.source is not None:
        candidates.append(suite.source.resolve().parent.parent.parent / "shared" / "data")
    for c in candidates:
        if c.is_dir():
            return c
    return None


# -- running --------------------------------------------------------------------------------


@dataclass
class ObjectResult:
    """What one entry produced: rows of metrics (one per mode, plus the original), or an error."""

    entry: Entry
    rows: list[dict[str, Any]] = field(default_factory=list)
    error: str | None = None
    figure: Path | None = None
    #: seconds spent per stage: import, reference, edit, metrics, figure
    timings: dict[str, float] = field(default_factory=dict)


@dataclass
class SuiteResult:
    """What :func:`run_suite` produced.

    Attributes
    ----------
    objects : list of ObjectResult
        Per entry: its ``rows`` (the original's, then one per mode), ``error``, ``figure`` and
        ``timings``.
    out_dir : Path
        The folder written.
    res : int
        Import resolution used.
    files : dict of str to Path
        ``contact_sheet``, ``metrics_csv``, ``metrics_md``, ``summary``.
    elapsed_s : float
        Wall time of the run.

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale import evaluate
    >>> evaluate.SuiteResult([], Path("out"), 128).failures
    []
    """

    objects: list[ObjectResult]
    out_dir: Path
    res: int
    files: dict[str, Path] = field(default_factory=dict)
    elapsed_s: float = math.nan

    @property
    def failures(self) -> list[str]:
        """The one-line errors of the entries that could not run."""
        return [o.error for o in self.objects if o.error]


def _load_object(path: Path, res: int, progress: ProgressCallback) -> CSDF:
    if path.name.endswith(SUFFIX):
        return load(path)
    from .. import ingest

    return ingest.load(path, res=res, progress=progress)


def _failed(base: dict[str, Any], mode: str, exc: Exception) -> tuple[dict[str, Any], str]:
    """The table row and the message of a mode that raised ``exc``."""
    msg = str(exc) if isinstance(exc, InputError) else f"{type(exc).__name__}: {exc}"
    return {**base, "mode": mode, "error": msg}, msg


def _run_mode(c: CSDF, edit: Edit, mode: str) -> CSDF:
    if mode.startswith("naive-"):
        return naive_edit(c, Edit(edit.axis, edit.start, edit.end, edit.dest, mode[6:]))
    return apply_edit(c, Edit(edit.axis, edit.start, edit.end, edit.dest, mode))


def _render(c: CSDF, view: str, frame: np.ndarray, size: int, *, parts: bool = False) -> np.ndarray:
    return render(c, view=view, size=size, frame=frame, scale_bar=True, parts=parts)


def _fmt(v: Any, digits: int = 2) -> str:
    if isinstance(v, bool):
        return "yes" if v else "NO"
    if isinstance(v, float | np.floating):
        return "n/a" if math.isnan(v) else f"{v:.{digits}f}"
    return str(v)


def _check_segment(method: str) -> None:
    """Refuse an unknown method once, before any object is imported."""
    from ..segment import check_method

    check_method(method, what="segment")


def _segment(c: CSDF, method: str, progress: ProgressCallback) -> CSDF:
    from ..segment import segment

    return segment(c, method=method, cache=True, progress=progress)


def _run_entry(
    entry: Entry,
    data: Path | None,
    res: int,
    out_dir: Path,
    panel: int,
    progress: ProgressCallback,
    segment: str | None = None,
) -> ObjectResult:
    result = ObjectResult(entry)
    name = entry.name
    if entry.error:
        result.error = entry.error
        return result
    path = Path(entry.path)
    if not path.is_absolute():
        if data is None:
            result.error = (
                f"{name}: {entry.path}: expected a data folder to find it in "
                "(set PARTSCALE_DATA or the suite's data key), got none"
            )
            return result
        path = data / path
    if not path.exists():
        result.error = f"{name}: {path}: expected an object file, got no such file"
        return result
    try:
        progress(0.0, f"{name}: import")
        t0 = time.perf_counter()
        original = _load_object(path, res, scaled(progress, 0.0, 0.3))
        result.timings["import"] = time.perf_counter() - t0
        geo0 = resolve_edit(original, entry.edit) if entry.edit is not None else None
    except InputError as exc:
        result.error = f"{name}: {exc}"
        return result
    except Exception as exc:  # a bug in a stage must not stop the rest of the suite
        result.error = f"{name}: import failed: {type(exc).__name__}: {exc}"
        return result

    if segment:
        progress(0.25, f"{name}: segment")
        t0 = time.perf_counter()
        try:
            original = _segment(original, segment, scaled(progress, 0.25, 0.3))
            result.timings["segment"] = time.perf_counter() - t0
        except InputError as exc:
            result.error = f"{name}: {exc}"
            return result

    progress(0.3, f"{name}: reference")
    t0 = time.perf_counter()
    ref = metrics.Reference(original)
    result.timings["reference"] = time.perf_counter() - t0
    result.timings["edit"] = result.timings["metrics"] = 0.0
    base = {"object": name, "kind": entry.kind or "", "voxels": "x".join(map(str, original.shape))}
    original_row = {"mode": "original", "time_s": math.nan}
    result.rows.append({**base, **original_row})
    if geo0 is not None:
        result.rows[0].update(metrics.evaluate_original(ref, geo0))
    results: dict[str, CSDF | str] = {}
    for i, mode in enumerate(COMPARED_MODES if entry.edit is not None else ()):
        progress(0.35 + 0.4 * i / len(COMPARED_MODES), f"{name}: {mode}")
        assert geo0 is not None
        geo = replace(geo0, mode=mode.removeprefix("naive-"))
        try:
            t0 = time.perf_counter()
            assert entry.edit is not None
            b = _run_mode(original, entry.edit, mode)
            dt = time.perf_counter() - t0
            m = metrics.evaluate(ref, b, geo)
            result.timings["edit"] += dt
            result.timings["metrics"] += time.perf_counter() - t0 - dt
            row = {**base, "mode": mode, **m, "time_s": dt, **_counted(b, entry, original)}
            if geo.mode == "tile":
                row["copies"] = geo.n_copies
            results[mode] = b
        except Exception as exc:  # recorded in the tables; the other modes still run
            row, results[mode] = _failed(base, mode, exc)
        result.rows.append(row)
    for mode, recipe_of in RECIPE_MODES.items():
        progress(0.75, f"{name}: {mode}")
        try:
            recipe = recipe_of(original, entry)
            if recipe is None:
                continue
            t0 = time.perf_counter()
            b = apply_recipe(original, recipe)
            dt = time.perf_counter() - t0
            zones = metrics.zones_from_history(b, original)
            m = metrics.evaluate(ref, b, zones)
            result.timings["edit"] += dt
            result.timings["metrics"] += time.perf_counter() - t0 - dt
            row = {**base, "mode": mode, **m, "time_s": dt, **_counted(b, entry, original)}
            copies = [z.n_copies for z in zones.zones if z.mode == "tile"]
            if copies:
                row["copies"] = "+".join(map(str, copies))
            if geo0 is None and "sdf_err_mean" not in result.rows[0]:
                result.rows[0].update(metrics.evaluate_original(ref, zones))
            results[mode] = b
        except Exception as exc:  # recorded in the tables; the other modes still run
            row, results[mode] = _failed(base, mode, exc)
        result.rows.append(row)
    if geo0 is None and "sdf_err_mean" not in result.rows[0]:
        result.rows[0].update(metrics.evaluate_original(ref))

    progress(0.8, f"{name}: figure")
    t0 = time.perf_counter()
    try:
        result.figure = _figure(entry, original, results, result.rows, out_dir, panel)
        result.timings["figure"] = time.perf_counter() - t0
    except InputError as exc:  # this entry fails (its rows are kept); the others still run
        result.error = f"{name}: figure: {exc}"
    except Exception as exc:  # a bug in a stage must not stop the rest of the suite
        result.error = f"{name}: figure failed: {type(exc).__name__}: {exc}"
    return result


def _counted(c: CSDF, entry: Entry, original: CSDF | None = None) -> dict[str, Any]:
    """Where the entry states what the designer asked (``elements``): the count on ``c``
    (``elements``, beside ``elements_expected``), the largest relative length change of its
    elements against the original's nearest (``element_change``: a seat stretched fat, an
    element cut) and of its local features along the axis (``feature_shape``: a knob drawn
    out, :func:`feature_change`).
    """
    if entry.elements is None:
        return {}
    axis, want = entry.elements
    out: dict[str, Any] = {"elements": count_elements(c, axis), "elements_expected": want}
    if original is not None:
        out["element_change"] = element_change(original, c, axis)
        if entry.hardware:
            out["feature_shape"] = feature_change(original, c, axis)
    return out


def element_change(a: CSDF, b: CSDF, axis: str) -> float:
    """Largest relative length change of ``b``'s elements along ``axis`` (its best repeat
    group's) against the nearest in length of ``a``'s; 0 where either has no repeat.
    """
    from ..zones import find_elements

    def lengths(c: CSDF) -> list[float]:
        f = find_elements(c, axis)
        return [] if f.best is None else [f.elements[i].length for i in f.best.members]

    la, lb = lengths(a), lengths(b)
    if not la or not lb:
        return 0.0
    return float(max(min(abs(x / y - 1) for y in la) for x in lb))


def feature_change(a: CSDF, b: CSDF, axis: str) -> float:
    """Largest relative change, beyond a layer, of a local feature's length along ``axis`` (knobs, handles,
    motifs: :func:`partscale.zones.axis_features`) from ``a`` to ``b``: each of ``a``'s matched
    to the features of ``b`` whose extent across the axis overlaps its own by half (IoU; a
    one-axis edit keeps it), the one of nearest length; one with no match counts as changed by
    1 (gone, or merged into another); 0 where ``a`` has none.
    """
    from ..zones import axis_features, calm_runs, profile

    ax = AXES_INDEX[axis]

    def feats(c: CSDF):
        return axis_features(c, ax, calm_runs(profile(c, ax)))

    def iou(f, g) -> float:  # of their extents across the axis (inclusive index ranges)
        inter = union = 1
        for (a0, a1), (b0, b1) in zip(f.across, g.across, strict=True):
            inter *= max(0, min(a1, b1) - max(a0, b0) + 1)
            union *= max(a1, b1) - min(a0, b0) + 1
        return inter / union

    fa, fb = feats(a), feats(b)
    worst = 0.0
    for f in fa:
        la = f.last - f.first + 1
        same = [g.last - g.first + 1 for g in fb if iou(f, g) >= 0.5]
        # beyond a layer of quantisation (a 2-layer knob read as 3 is not drawn out)
        worst = max(worst, min((max(0, abs(lb - la) - 1) / la for lb in same), default=1.0))
    return float(worst)


AXES_INDEX = {"x": 0, "y": 1, "z": 2}


def _figure(
    entry: Entry,
    original: CSDF,
    results: dict[str, CSDF | str],
    rows: list[dict[str, Any]],
    out_dir: Path,
    panel: int,
) -> Path:
    done = [c for c in results.values() if isinstance(c, CSDF)]
    bounds = [c.surface_bounds() for c in [original, *done]]
    frame = np.stack([np.min([b[0] for b in bounds], 0), np.max([b[1] for b in bounds], 0)])
    by_mode = {r["mode"]: r for r in rows}
    panels = [
        (
            "original",
            f"{_fmt(by_mode['original']['pieces'])} piece(s)",
            _render(original, entry.view, frame, panel),
        )
    ]
    for mode in results:
        r = by_mode[mode]
        res = results[mode]
        if isinstance(res, str):
            panels.append((LABELS.get(mode, mode), "", figures.failed_panel(panel, res)))
            continue
        note = (
            f"prop {_fmt(r['prop_in'])}/{_fmt(r['prop_out'])} "
            f"space {_fmt(r['spacing_err'])} seam {_fmt(r['seam_shape'], 1)}/"
            f"{_fmt(r['seam_color'], 0)}"
        )
        panels.append((LABELS.get(mode, mode), note, _render(res, entry.view, frame, panel)))
    # ASCII only: the built-in font has no dashes
    subtitle = f"{entry.path}  |  {entry.describe()}"
    if entry.note:
        subtitle += f"  |  {entry.note}"
    legend = (
        "* baseline: no re-evaluation, plain concatenation.  Notes: prop = thickness change "
        "in/out of the zone, space = spacing change (relative); seam = jump shape (vox)/colour"
    )
    fig = figures.object_figure(entry.name, subtitle, panels, legend=legend)
    if original.n_parts > 0:  # segmented: a second row coloured by part
        parts_row = [("original parts", f"{original.n_parts} parts", None)] + [
            (LABELS.get(m, m), "", None) for m in results if isinstance(results[m], CSDF)
        ]
        sources = [original] + [c for c in results.values() if isinstance(c, CSDF)]
        row = [
            (label, note, _render(c, entry.view, frame, panel, parts=True))
            for (label, note, _), c in zip(parts_row, sources, strict=True)
        ]
        fig = figures.contact_sheet(
            [fig, figures.object_figure("parts", "one colour per part", row)], width=fig.width
        )
    path = out_dir / f"{entry.name}.png"
    with atomic_path(path) as tmp:
        fig.save(tmp, format="PNG")
    return path


@keyword_options
def run_suite(
    suite: Suite | str | os.PathLike,
    out_dir: str | os.PathLike,
    *,
    res: int | None = None,
    only: str | None = None,
    data: str | os.PathLike | None = None,
    panel: int = PANEL,
    segment: str | None = None,
    progress: ProgressCallback | None = None,
) -> SuiteResult:
    """Run every suite entry in every mode; write figures, metrics tables and a summary.

    Parameters
    ----------
    suite : Suite or path of a suite JSON file
        The objects and their edits (:func:`load_suite`).
    out_dir : path
        Created if missing. Receives ``NAME.png`` per object, ``contact_sheet.png``,
        ``metrics.csv``, ``metrics.md`` and ``summary.md``.
    res : int, optional
        Import resolution (voxels along the longest side); default the suite's ``res`` (128).
    only : str, optional
        Run only the entry of this name.
    data : path, optional
        Folder the object paths are relative to (see module docstring).
    panel : int
        Size in pixels of each render in the figures.
    segment : str, optional
        Segment each object first with this method of :mod:`partscale.segment` (results are
        cached by that stage): tile copies then become distinct parts and the figures get a row
        coloured by part. The metrics do not use parts. Off by default (a few seconds an object
        with ``"fast"`` on first run, tens of seconds with ``"coacd"``). An unknown method
        raises :class:`InputError` before any object is read.

    Returns
    -------
    SuiteResult
        Per-object rows and errors (entries that could not run carry a one-line ``error``).

    Examples
    --------
    The table shipped with partscale made longer in every mode, at a coarse 32 voxels (a few
    seconds):

    >>> import json
    >>> from pathlib import Path
    >>> from partscale import data, evaluate
    >>> entry = {"name": "longer", "path": "table.glb",
    ...          "edit": {"axis": "x", "zone": ["30%", "70%"], "to": "120%"}}
    >>> _ = Path("suite.json").write_text(json.dumps({"res": 32, "objects": [entry]}))
    >>> result = evaluate.run_suite("suite.json", "eval", data=data.table().parent, panel=64)
    >>> [row["mode"] for row in result.objects[0].rows]
    ['original', 'global', 'stretch', 'tile', 'naive-stretch', 'naive-tile', 'fit']
    >>> sorted(p.name for p in result.files.values())
    ['contact_sheet.png', 'metrics.csv', 'metrics.md', 'summary.md']
    """
    t_start = time.perf_counter()
    if not isinstance(suite, Suite):
        suite = load_suite(suite)
    res = suite.res if res is None else count(res, "res", lo=MIN_SUITE_RES, hi=MAX_SUITE_RES)
    if segment is not None:
        _check_segment(segment)
    entries = suite.entries
    if only is not None:
        entries = [e for e in entries if e.name == only]
        if not entries:
            names = ", ".join(e.name for e in suite.entries)
            raise InputError(f"only: expected one of {names}, got {only!r}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: expected an output folder, got a file")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(
            f"{out}: expected a folder that can be created, got {exc.strerror}"
        ) from None
    check_writable(out / "metrics.csv")  # before any object is imported
    folder = data_folder(suite, data)
    progress = resolve(progress)
    objects = []
    for i, entry in enumerate(entries):
        sub = scaled(progress, i / len(entries), (i + 1) / len(entries))
        objects.append(_run_entry(entry, folder, res, out, panel, sub, segment))
    result = SuiteResult(objects, out, res)
    progress(1.0, "tables")
    sheet = [o.figure for o in objects if o.figure is not None]
    if sheet:
        from PIL import Image

        images = []
        for p in sheet:
            with Image.open(p) as im:
                images.append(im.convert("RGB"))
        path = out / f"{CONTACT_SHEET}.png"
        with atomic_path(path) as tmp:
            figures.contact_sheet(images).save(tmp, format="PNG")
        result.files["contact_sheet"] = path
    result.elapsed_s = time.perf_counter() - t_start
    result.files.update(report.write(result))
    return result
