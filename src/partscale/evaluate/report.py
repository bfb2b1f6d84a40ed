"""The evaluation's tables: metrics (CSV and Markdown) and a summary of who wins and who fails."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

from .._files import atomic_path
from .metrics import METRICS


# What the tables read of a run, as protocols: :class:`partscale.evaluate.SuiteResult` and its
# objects match them, and this module need not import the suite that imports it.
class _EntryLike(Protocol):
    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> str | None: ...


class _ObjectLike(Protocol):
    @property
    def entry(self) -> _EntryLike: ...
    @property
    def rows(self) -> list[dict[str, Any]]: ...
    @property
    def error(self) -> str | None: ...
    @property
    def timings(self) -> dict[str, float]: ...


class _SuiteLike(Protocol):
    @property
    def objects(self) -> Sequence[_ObjectLike]: ...
    @property
    def out_dir(self) -> Path: ...
    @property
    def res(self) -> int: ...
    @property
    def elapsed_s(self) -> float: ...


COLUMNS = (
    "object",
    "kind",
    "voxels",
    "mode",
    *METRICS,
    "elements",
    "elements_expected",
    "element_change",
    "feature_shape",
    "copies",
    "time_s",
    "error",
)

#: metric -> (what it measures with its unit, tie tolerance, failure threshold). Lower is better
#: for all; ``pieces`` is judged by its change from the original.
CRITERIA: dict[str, tuple[str, float, float]] = {
    "length_err": ("length error (vox)", 0.5, 1.0),
    "rigid_err": ("rigidity error outside the zone, p99 (vox)", 0.25, 1.0),
    "prop_out": ("thickness change outside the zone (rel.)", 0.02, 0.10),
    "prop_in": ("thickness change inside the zone (rel.)", 0.02, 0.10),
    "spacing_err": ("spacing change of repeated elements (rel.)", 0.02, 0.10),
    "sdf_err_mean": ("distance-field error in the zone, mean (vox)", 0.02, 0.05),
    "seam_color": ("seam colour jump (sRGB levels)", 2.0, 20.0),
    "seam_shape": ("seam shape jump (vox)", 0.1, 0.5),
    "pieces": ("pieces beyond the expected count", 0.0, 0.5),
    "elements": ("elements off the count asked for", 0.0, 0.5),
    "element_change": ("length change of the elements (rel.)", 0.02, 0.10),
    "feature_shape": ("length change of knobs, handles, motifs (rel.)", 0.02, 0.10),
}
SHORT = {
    "length_err": "length",
    "rigid_err": "rigidity",
    "prop_out": "prop. out",
    "prop_in": "prop. in",
    "spacing_err": "spacing",
    "sdf_err_mean": "distance",
    "seam_color": "seam colour",
    "seam_shape": "seam shape",
    "pieces": "pieces",
    "elements": "elements",
    "element_change": "element length",
    "feature_shape": "hardware",
}


def _num(v: Any) -> float:
    if isinstance(v, bool):
        return float(v)
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if math.isnan(v):
            return ""
        return f"{v:.3g}" if abs(v) < 1000 else f"{v:.0f}"
    try:
        f = float(v)
        if isinstance(v, int) or (f.is_integer() and not isinstance(v, str)):
            return str(int(f))
        return f"{f:.3g}"
    except (TypeError, ValueError):
        return str(v)


def _rows(result: _SuiteLike) -> list[dict[str, Any]]:
    return [row for obj in result.objects for row in obj.rows]


def metric_score(metric: str, row: dict[str, Any], original: dict[str, Any]) -> float:
    """One result's score on ``metric`` (a :data:`CRITERIA` key), as the suite compares modes.

    Parameters
    ----------
    metric : str
        A key of :data:`CRITERIA`.
    row : dict
        One result's metrics (a row of :attr:`SuiteResult.objects`, or
        :func:`evaluate`'s dict).
    original : dict
        The original's row (its ``pieces`` is the expected count where ``row`` has none).

    Returns
    -------
    float
        Lower is better; NaN where not measured, and for a mode that failed to run (never
        wins). ``pieces`` scores the pieces beyond those expected.

    Examples
    --------
    >>> from partscale import evaluate
    >>> evaluate.metric_score("pieces", {"pieces": 5}, {"pieces": 3})
    2.0
    >>> evaluate.metric_score("length_err", {"error": "zone outside the solid"}, {})
    nan
    """
    if row.get("error"):
        return math.nan
    if metric == "elements":  # the designer's count, where the entry states one
        return abs(_num(row.get("elements")) - _num(row.get("elements_expected")))
    if metric == "pieces":
        expected = row.get("pieces_expected", original.get("pieces"))
        extra = _num(row.get("pieces")) - _num(expected)
        # max(0.0, nan) is 0.0: an unmeasured count must stay NaN, not score perfectly
        return max(0.0, extra) if math.isfinite(extra) else math.nan
    return _num(row.get(metric))


def failures_of(row: dict[str, Any], original: dict[str, Any]) -> list[str]:
    """The metrics on which one result fails (value above its threshold), as short names.

    Parameters
    ----------
    row : dict
        One result's metrics (as :func:`metric_score`'s).
    original : dict
        The original's row: the distance error is judged above the import's own.

    Returns
    -------
    list of str
        Short names (``"length"``, ``"rigidity"``, ``"seam colour"``...) in :data:`CRITERIA`'s
        order, then ``"not watertight"``; ``["error"]`` for a mode that failed to run.

    Examples
    --------
    >>> from partscale import evaluate
    >>> row = {"length_err": 0.2, "rigid_err": 3.0, "watertight": False}
    >>> evaluate.failures_of(row, {"pieces": 1})
    ['rigidity', 'not watertight']
    """
    if row.get("error"):
        return ["error"]
    out = []
    for metric, (_, _, threshold) in CRITERIA.items():
        v = metric_score(metric, row, original)
        if metric == "sdf_err_mean":  # judged against what the import itself achieved
            v = v - _num(original.get("sdf_err_mean"))
        if math.isfinite(v) and v > threshold:
            out.append(SHORT[metric])
    if row.get("watertight") is False:
        out.append("not watertight")
    return out


def winners(rows: list[dict[str, Any]], metric: str, original: dict[str, Any]) -> list[str]:
    """Modes whose score is within the metric's tie tolerance (or 10 %) of the best.

    Parameters
    ----------
    rows : list of dict
        One row per mode (each with ``mode`` and its metrics).
    metric : str
        A key of :data:`CRITERIA` (its tie tolerance is the second value).
    original : dict
        The original's row (as :func:`metric_score`'s).

    Returns
    -------
    list of str
        The best modes, in ``rows``' order; none where no mode was measured.

    Examples
    --------
    >>> from partscale import evaluate
    >>> rows = [{"mode": "stretch", "length_err": 0.1}, {"mode": "tile", "length_err": 0.4},
    ...         {"mode": "global", "length_err": 2.0}]
    >>> evaluate.winners(rows, "length_err", {})
    ['stretch', 'tile']
    """
    tol = CRITERIA[metric][1]
    scores = {r["mode"]: metric_score(metric, r, original) for r in rows}
    finite = {m: s for m, s in scores.items() if math.isfinite(s)}
    if not finite:
        return []
    best = min(finite.values())
    return [m for m, s in finite.items() if s <= best + max(tol, 0.1 * abs(best))]


def _md_table(header: list[str], body: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(c.replace("|", "/") for c in row) + " |" for row in body]
    return "\n".join(lines) + "\n"


def metrics_csv(result: _SuiteLike) -> str:
    """The suite's metrics, one row per object and mode, as CSV text."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for row in _rows(result):
        w.writerow({k: _cell(row.get(k)) for k in COLUMNS})
    return buf.getvalue()


def metrics_markdown(result: _SuiteLike) -> str:
    """The suite's metrics as a Markdown table with a legend."""
    cols = [c for c in COLUMNS if c not in ("kind", "voxels")]
    body = [[_cell(row.get(c)) for c in cols] for row in _rows(result)]
    legend = "\n".join(f"- `{m}`: {CRITERIA[m][0]}" for m in CRITERIA if m != "pieces")
    return (
        f"# Metrics (import at {result.res} voxels along the longest side)\n\n"
        + _md_table(cols, body)
        + "\n"
        + legend
        + "\n- `sdf_err_p99`: distance-field error, 99th percentile (vox); `pieces`: connected"
        " surfaces; `copies`: tile copies; `time_s`: edit time (s). `naive-*` is the baseline"
        " without re-evaluation.\n"
    )


def _expectation(obj_rows: list[dict[str, Any]], kind: str) -> tuple[str, str]:
    by = {r["mode"]: r for r in obj_rows}
    orig = by.get("original", {})
    st, ti = by.get("stretch"), by.get("tile")
    if not st and not ti:
        return "n/a", "no stretch and tile of one edit to compare (a recipe entry)"
    if not st or not ti or st.get("error") or ti.get("error"):
        return "n/a", "a mode failed to run"
    if ti.get("copies") == 1:
        return "n/a", "one copy: tiling is stretching here"
    fs, ft = set(failures_of(st, orig)), set(failures_of(ti, orig))
    if kind == "repeating":
        keys = ("prop_in", "spacing_err")
        s = [_num(st.get(k)) for k in keys]
        t = [_num(ti.get(k)) for k in keys]
        # stretch fails on a metric where it is at least twice as far off as tile; a tile value
        # that was never measured is no evidence either way
        fails = [
            (k, a, b)
            for k, a, b in zip(keys, s, t, strict=True)
            if math.isfinite(a) and a > CRITERIA[k][2]
        ]
        worse = [k for k, a, b in fails if math.isfinite(b) and a >= 2 * b + CRITERIA[k][1]]
        unmeasured = [SHORT[k] for k, a, b in fails if not math.isfinite(b)]
        detail = (
            f"stretch prop. in {_cell(s[0])}, spacing {_cell(s[1])}; "
            f"tile {_cell(t[0])}, {_cell(t[1])}"
        )
        if worse:
            return "held", detail
        if unmeasured:
            return "n/a", f"tile not measured on {', '.join(unmeasured)}; {detail}"
        if not any(math.isfinite(a) for a in s):
            return "n/a", "stretch not measured (no repeated elements found along the axis)"
        return "not held", detail
    extra = sorted(ft - fs)
    detail = "tile fails on: " + (", ".join(extra) if extra else "nothing stretch passes")
    return ("held" if extra else "not held"), detail


def summary_markdown(result: _SuiteLike) -> str:
    """The suite's summary in Markdown: best modes, failures, the paper's expectations, times."""
    objs = result.objects
    ok = [o for o in objs if not o.error]
    lines = [
        "# Evaluation summary",
        "",
        f"{len(ok)} of {len(objs)} object(s) ran, imported at {result.res} voxels along the "
        f"longest side, in {result.elapsed_s:.0f} s. Modes: global, stretch, tile, and the "
        "baseline naive-stretch / naive-tile (no re-evaluation, plain concatenation).",
        "",
    ]
    if len(ok) < len(objs):
        lines += ["## Entries that could not run", ""]
        lines += [f"- {o.error}" for o in objs if o.error]
        lines.append("")
    metric_keys = list(CRITERIA)
    lines += [
        "## Best mode per metric",
        "",
        "Modes within the metric's tolerance of the best are all listed; blank: not measurable "
        "(e.g. no repeated elements along the axis).",
        "",
    ]
    body = []
    for o in ok:
        orig = o.rows[0]
        edits = [r for r in o.rows[1:]]
        body.append(
            [o.entry.name]
            + [
                ("all" if len(w := winners(edits, m, orig)) == len(edits) else ", ".join(w))
                for m in metric_keys
            ]
        )
    lines.append(_md_table(["object", *[SHORT[m] for m in metric_keys]], body))
    lines += [
        "## Where each mode fails",
        "",
        "Thresholds: "
        + "; ".join(f"{SHORT[m]} > {CRITERIA[m][2]:g}" for m in metric_keys)
        + " (distance: above the import's own error). `ok`: no failure.",
        "",
    ]
    # every mode any object ran, in first-seen order (a recipe entry runs only its recipe)
    modes = list(dict.fromkeys(r["mode"] for o in ok for r in o.rows[1:]))
    body = []
    for o in ok:
        orig = o.rows[0]
        by = {r["mode"]: r for r in o.rows}
        body.append(
            [o.entry.name]
            + [", ".join(failures_of(by[m], orig)) or "ok" if m in by else "" for m in modes]
        )
    lines.append(_md_table(["object", *modes], body))
    lines += [_failure_counts(ok, modes), ""]
    lines += [
        "## The paper's expectations",
        "",
        "Stretch should fail on repeating structures (shelves, cushions, balusters): held when "
        "stretch fails on thickness inside the zone or spacing and is at least twice as far off "
        "as tile there. Tiling should fail on shapes with no repeatable part: held when tile "
        "fails on a metric stretch passes (typically a seam).",
        "",
    ]
    body = []
    for o in ok:
        kind = o.entry.kind
        if not kind:
            continue
        expect = "stretch fails" if kind == "repeating" else "tile fails"
        verdict, detail = _expectation(o.rows, kind)
        body.append([o.entry.name, kind, expect, verdict, detail])
    if body:
        lines.append(_md_table(["object", "kind", "expected", "verdict", "measured"], body))
        held = sum(1 for b in body if b[3] == "held")
        judged = sum(1 for b in body if b[3] in ("held", "not held"))
        lines.append(f"Held on {held} of {judged} object(s) where it can be judged.\n")
    lines.append(_timings(result))
    return "\n".join(lines)


def _failure_counts(ok: list, modes: list[str]) -> str:
    """One line per mode: on how many objects it fails, and on what most often."""
    out = []
    for mode in modes:
        failed, ran = 0, 0
        reasons: dict[str, int] = {}
        for o in ok:
            by = {r["mode"]: r for r in o.rows}
            if mode not in by:
                continue
            ran += 1
            f = failures_of(by[mode], o.rows[0])
            failed += bool(f)
            for x in f:
                reasons[x] = reasons.get(x, 0) + 1
        top = ", ".join(f"{k} ({v})" for k, v in sorted(reasons.items(), key=lambda kv: -kv[1]))
        out.append(
            f"- **{mode}** fails on {failed} of {ran} object(s)" + (f": {top}" if top else "")
        )
    return "\n".join(out) + "\n"


def _timings(result: _SuiteLike) -> str:
    stages = [
        k
        for k in ("import", "segment", "reference", "edit", "metrics", "figure")
        if any(k in o.timings for o in result.objects)
    ]
    body = []
    for o in result.objects:
        if o.error:
            continue
        t = o.timings
        body.append(
            [o.entry.name, o.rows[0].get("voxels", "")]
            + [f"{t[k]:.1f}" if k in t else "" for k in stages]
            + [f"{sum(t.values()):.1f}"]
        )
    return (
        "## Time (s)\n\n`edit`: the five edits together; `metrics`: measuring them; "
        "`reference`: the original's mesh and runs.\n\n"
        + _md_table(["object", "voxels", *stages, "total"], body)
    )


def write(result: _SuiteLike) -> dict[str, Path]:
    """Write ``metrics.csv``, ``metrics.md`` and ``summary.md`` into ``result.out_dir``."""
    files = {}
    for key, name, text in (
        ("metrics_csv", "metrics.csv", metrics_csv(result)),
        ("metrics_md", "metrics.md", metrics_markdown(result)),
        ("summary", "summary.md", summary_markdown(result)),
    ):
        path = result.out_dir / name
        with atomic_path(path) as tmp:
            tmp.write_text(text)
        files[key] = path
    return files
