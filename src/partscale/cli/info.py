"""``partscale info``: what a CSDF file holds."""

from __future__ import annotations

import json
from typing import Annotated

import typer

from ..csdf import CSDF, load
from ..orient import csdf_turn, off_square_message
from ..progress import ProgressCallback, resolve, scaled
from ..thickness import ThinFeatures, thin_features
from . import _common
from ._common import CsdfIn


def summary(
    c: CSDF, thin: ThinFeatures | None = None, progress: ProgressCallback | None = None
) -> dict:
    """A JSON-serialisable summary of a CSDF (what ``info --json`` prints); ``thin``: its thin
    features when already measured. The measures take seconds at 256 voxels and more:
    ``progress`` hears of each."""
    report = resolve(progress)
    if thin is None:
        report(0.0, "thin features")
        thin = thin_features(c)
    report(0.5, "surface relief")
    relief = _relief(c)
    report(0.9, "walls")
    turn = csdf_turn(c)
    report(1.0, "done")
    try:
        sb = c.surface_bounds()
        solid = {"min": sb[0].tolist(), "max": sb[1].tolist(), "size": (sb[1] - sb[0]).tolist()}
    except Exception:
        solid = None
    gb = c.grid_bounds
    return {
        "shape": list(c.shape),
        "voxel_size": c.voxel_size,
        "origin": c.origin.tolist(),
        "units": c.meta.get("units", "m"),
        "grid_extent": (gb[1] - gb[0]).tolist(),
        "solid_bounds": solid,
        "parts": c.n_parts,
        "source": c.meta.get("source"),
        "history": c.meta.get("history", []),
        "completion": _completion(c.meta.get("completion")),
        "thin_features": thin.to_json(),
        "relief": relief,
        # the turn about up that would square the walls (None: square, or no clear direction)
        "off_square_deg": None if turn is None else round(turn, 2),
    }


def _completion(comp) -> dict | None:
    """A completion's shares of the surface by kind, where its guard kept the scan as observed
    or was overruled, why (``guard_reason``), and what makes it look broken (``caveats``: pieces
    apart, running out of the camera's frame, standing above the floor); None for a CSDF not
    made by completion.
    """
    if not isinstance(comp, dict):
        return None
    out = {k: v for k, v in comp.items() if k in ("observed", "mirrored", "guessed")}
    guard = comp.get("guard")
    if isinstance(guard, dict) and guard.get("reason"):
        out["guard_reason"] = guard["reason"]
    if isinstance(guard, dict) and guard.get("caveats"):
        out["caveats"] = list(guard["caveats"])
    return out


def _relief(c: CSDF) -> dict | None:
    """The surface's relief (voxels RMS) and what it adds to segment's tolerances; None without
    a surface."""
    from ..segment import noise_tolerance, relief_of

    if not ((c.sdf <= 0).any() and (c.sdf > 0).any()):
        return None
    r = relief_of(c)
    return {
        "rms_voxels": round(r, 4),
        "segment_tolerance_added_voxels": round(noise_tolerance(r), 3),
    }


def info(
    path: CsdfIn,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print JSON instead of text (for scripts).")
    ] = False,
) -> None:
    """Show shape, voxel size, extent in world units, number of parts, the edit history, and a
    warning when features thinner than ~1.5 voxels need a finer resolution."""
    c = load(path)
    with _common.progress_bar("info") as bar:
        bar(0.0, "thin features")
        thin = thin_features(c)
        s = summary(c, thin, progress=scaled(bar, 0.2, 1.0))
    if as_json:
        typer.echo(json.dumps(s, indent=2))
        return
    units = s["units"]
    typer.echo(f"file:        {path}")
    typer.echo(
        f"grid:        {' x '.join(map(str, s['shape']))} voxels of {s['voxel_size']:.6g} {units}"
    )
    typer.echo(f"grid extent: {' x '.join(f'{v:.4g}' for v in s['grid_extent'])} {units}")
    if s["solid_bounds"]:
        size = s["solid_bounds"]["size"]
        typer.echo(f"solid:       {' x '.join(f'{v:.4g}' for v in size)} {units}")
    else:
        typer.echo("solid:       none (no voxel inside)")
    typer.echo(f"parts:       {s['parts'] or 'not segmented'}")
    typer.echo(f"source:      {s['source']}")
    if s["completion"]:
        k = s["completion"]
        typer.echo(
            f"completion:  surface {k['observed']:.0%} observed, {k['mirrored']:.0%} mirrored, "
            f"{k['guessed']:.0%} guessed"
        )
        if k.get("guard_reason"):
            typer.echo(f"completion:  {k['guard_reason']}")
        for line in k.get("caveats", []):
            typer.echo(f"completion:  {line}")
    if s["relief"]:
        r = s["relief"]
        added = r["segment_tolerance_added_voxels"]
        rough = (
            f"rough, a scan's noise: segment widens its concavity tolerances by {added:.1f} voxels"
            if added > 0
            else "smooth"
        )
        typer.echo(f"relief:      {r['rms_voxels']:.2f} voxel RMS ({rough})")
    warning = thin.message(c.voxel_size, units)
    if warning:
        typer.echo(f"warning:     thin features: {warning}")
    if s["off_square_deg"] is not None:
        typer.echo(f"warning:     {off_square_message(s['off_square_deg'], c)}")
    typer.echo(f"history:     {len(s['history'])} operation(s)")
    for i, op in enumerate(s["history"]):
        typer.echo(f"  {i + 1}. {json.dumps(op)}")
