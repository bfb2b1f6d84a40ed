"""The add-on's work outside Blender: finding partscale, its command lines, reading its answers.

No ``bpy`` here, so this runs (and is tested) in any Python. Blender is Z up, partscale (like
glTF, which the add-on exchanges with it) Y up: Blender's X is partscale's x, Blender's Z is
partscale's y, Blender's Y is partscale's -z. Blender's glTF exporter and importer make that
change on the way out and back; this module maps axes, positions and zones across it.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

#: Blender axis -> (partscale axis, sign of the partscale axis along the Blender one)
AXES = {"X": ("x", 1.0), "Y": ("z", -1.0), "Z": ("y", 1.0)}

#: how long one partscale run may take before the add-on gives up (seconds)
TIMEOUT_S = 900


class PartscaleError(Exception):
    """A one-line message for a Blender report (what went wrong and what to do)."""


def find_partscale(configured: str = "") -> list[str]:
    """The command that runs partscale: the path set in the preferences, else ``partscale`` on PATH.

    A configured path may be the ``partscale`` executable or a Python that has partscale
    installed (run as ``python -m partscale``).
    """
    configured = (configured or "").strip()
    if configured:
        path = Path(os.path.expanduser(configured))
        if not path.is_file() or not os.access(path, os.X_OK):
            raise PartscaleError(
                f"partscale: expected an executable at {path} (add-on preferences), got none"
            )
        if path.name.startswith("python"):
            return [str(path), "-m", "partscale"]
        return [str(path)]
    found = shutil.which("partscale")
    if found is None:
        raise PartscaleError(
            "partscale: not found on PATH; install it (pip install partscale) or set its path "
            "in the add-on's preferences"
        )
    return [found]


def one_line(stderr: str, code: int) -> str:
    """partscale's error line from its stderr (``partscale: error: ...``), else its last line."""
    lines = [ln.strip() for ln in (stderr or "").splitlines() if ln.strip()]
    for ln in reversed(lines):
        if ln.startswith("partscale:"):
            return ln
    last = lines[-1] if lines else "no message"
    return f"partscale: exited with code {code}: {last}"[:400]


def run(command: list[str], *args: str) -> str:
    """Run partscale with ``args``; its stdout on success, else :class:`PartscaleError`."""
    try:
        proc = subprocess.run(
            [*command, *args], capture_output=True, text=True, timeout=TIMEOUT_S, check=False
        )
    except FileNotFoundError:
        raise PartscaleError(f"partscale: could not run {command[0]}") from None
    except subprocess.TimeoutExpired:
        raise PartscaleError(f"partscale: gave no answer in {TIMEOUT_S} s") from None
    if proc.returncode != 0:
        raise PartscaleError(one_line(proc.stderr, proc.returncode))
    return proc.stdout


@dataclass(frozen=True)
class Request:
    """What the panel asks for, in Blender's terms.

    mode : ``ADD`` (``count`` more elements, negative removes), ``SIZE`` (the object's length
    along ``axis`` becomes ``size`` metres), or ``ZONE`` (the zone ``start``..``end`` % of the
    extent along ``axis`` is stretched or tiled so that its end goes to ``to`` %).
    """

    axis: str = "Z"
    mode: str = "ADD"
    count: int = 1
    size: float = 1.0
    start: float = 30.0
    end: float = 70.0
    to: float = 120.0
    zone_mode: str = "stretch"


def _pct(x: float) -> str:
    return f"{x:.6g}%"


def edit_args(req: Request, src: str, dst: str) -> list[str]:
    """partscale's arguments for ``req``, mesh route ``src`` -> ``dst`` (Y-up glTF files)."""
    if req.axis not in AXES:
        raise PartscaleError(f"axis: expected X, Y or Z, got {req.axis!r}")
    ax, sign = AXES[req.axis]
    if req.mode == "ADD":
        if req.count == 0:
            raise PartscaleError("+N elements: expected a count other than 0, got 0")
        return ["fit", src, "-o", dst, "--add", ax, str(int(req.count))]
    if req.mode == "SIZE":
        if not req.size > 0:
            raise PartscaleError(f"target size: expected a length above 0, got {req.size:g}")
        size = ["=", "=", "="]
        size["xyz".index(ax)] = f"{req.size:.6g}m"
        return ["fit", src, "-o", dst, "--size", *size]
    if req.mode == "ZONE":
        start, end, to = req.start, req.end, req.to
        if sign < 0:
            # Blender's Y runs along partscale's -z: the zone mirrors ([100-end, 100-start] %)
            # and grows by the same amount; partscale keeps its start plane, so along Y the
            # part of the object before the zone (towards -Y) is the side that moves
            start, end = 100.0 - req.end, 100.0 - req.start
            to = end + (req.to - req.end)
        return [
            "scale",
            src,
            "-o",
            dst,
            "--axis",
            ax,
            "--zone",
            _pct(start),
            _pct(end),
            "--to",
            _pct(to),
            "--mode",
            req.zone_mode,
        ]
    raise PartscaleError(f"mode: expected ADD, SIZE or ZONE, got {req.mode!r}")


def summarise_suggestions(text: str) -> dict[str, list[str]]:
    """Lines per Blender axis from ``partscale suggest --json``: elements, then zone candidates
    (best first, as partscale ranks them).

    Positions are partscale's (Y up), shown along Blender's axes in metres.
    """
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PartscaleError(f"partscale suggest: expected JSON, got {exc}") from None
    out: dict[str, list[str]] = {}
    for baxis, (ax, sign) in AXES.items():
        lines = []
        per = (data.get("elements") or {}).get(ax) or {}
        elements = per.get("elements") or []
        if elements:
            sizes = sorted(e["length"] for e in elements)
            lines.append(f"{len(elements)} elements, {sizes[0]:.2f}-{sizes[-1]:.2f} m")
        for cand in data.get("candidates") or []:
            if cand.get("axis") != ax:
                continue
            a, b = (sign * v for v in cand["zone"])
            a, b = min(a, b), max(a, b)
            lines.append(f"{cand['kind']} {a:.2f}..{b:.2f} m")
        out[baxis] = lines[:4]
    return out


def element_planes(text: str, baxis: str) -> list[float]:
    """World positions along Blender's ``baxis`` of the element boundaries ``suggest`` found."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError:
        return []
    ax, sign = AXES[baxis]
    per = (data.get("elements") or {}).get(ax) or {}
    out = []
    for e in per.get("elements") or []:
        out += [sign * e["start"], sign * e["end"]]
    return sorted(out)


def zone_planes(lo: float, hi: float, start: float, end: float) -> list[float]:
    """The zone's two planes along an axis whose extent is ``lo``..``hi`` (start, end in %)."""
    return [lo + (hi - lo) * start / 100.0, lo + (hi - lo) * end / 100.0]


def plane_quads(
    lo: tuple[float, float, float], hi: tuple[float, float, float], axis: str, at: list[float]
) -> list[tuple[float, float, float]]:
    """Triangles (3 corners each, flat) of a rectangle across the box ``lo``..``hi`` at each
    position in ``at`` along Blender's ``axis``: the planes the viewport draws."""
    a = "XYZ".index(axis)
    u, v = [i for i in range(3) if i != a]
    tris: list[tuple[float, float, float]] = []
    for p in at:
        corners = []
        for cu, cv in ((lo[u], lo[v]), (hi[u], lo[v]), (hi[u], hi[v]), (lo[u], hi[v])):
            c = [0.0, 0.0, 0.0]
            c[a], c[u], c[v] = p, cu, cv
            corners.append((c[0], c[1], c[2]))
        tris += [corners[0], corners[1], corners[2], corners[0], corners[2], corners[3]]
    return tris
