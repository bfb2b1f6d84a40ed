"""What an edit changed from what was asked, in words: one home for the CLI, fit and the editor.

Every line reads the history entries :func:`~partscale.edit.apply_recipe` wrote (``to_snapped``
beside the ``edit.to`` given; ``slivers_left_out`` where a zone plane cut an element), so what is
said is exactly what was recorded.
"""

from __future__ import annotations

from typing import Any

from ..csdf import CSDF

#: A destination moved by less than this share of a voxel, or by float32 rounding of its own
#: size, is not reported: positions resolved on the float32 grid (a percentage) land within
#: float32 rounding of whole voxels though nothing was snapped ("0.937002 -> 0.937002 m").
SNAP_QUIET_VOXELS = 1e-4


def describe_changes(entries: list[Any], out: CSDF) -> list[str]:
    """One line per change the edit stage made to the edits of ``entries`` (history dicts).

    Parameters
    ----------
    entries : list of dict
        The history entries of the edits just applied (the last ``len(recipe.edits)``).
    out : CSDF
        The edited object (its voxel size and units word the lines).

    Returns
    -------
    list of str
        Removed zones (tile, 0 copies) first, then whole-voxel destinations, then zone planes
        that cut an element.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import apply_edit, describe_changes
    >>> out = apply_edit(bar, {"axis": "x", "zone": [0.3, 0.6], "to": 0.83})
    >>> describe_changes(out.meta["history"][-1:], out)
    ['destination 0.83 -> 0.85 m (+0.02 m): lengths change by whole voxels of 0.05 m (recorded in the history)']
    """
    return (
        _warps(entries, out)
        + _removed(entries, out)
        + _voxel_snaps(entries, out)
        + _slivers(entries, out)
    )


def _warps(entries: list[Any], out: CSDF) -> list[str]:
    """A line per radial or oblique zone: what grew, and by how much."""
    u = unit_suffix(out.meta.get("units"))
    lines = []
    for i, h in enumerate(entries):
        if not isinstance(h, dict) or h.get("op") not in ("radial", "oblique"):
            continue
        (a, b), to = h["zone"], h["to"]
        if h["op"] == "radial":
            spec = h["radial"]
            shape = "round" if not spec.get("sides") else f"{spec['sides']}-sided"
            what = (
                f"radial zone {a:.4g}..{b:.4g}{u} ({shape}) about the {spec['axis']} axis "
                f"through {spec['center'][0]:.4g}, {spec['center'][1]:.4g}{u}"
            )
        else:
            nx, ny, nz = h["normal"]
            what = f"oblique zone {a:.4g}..{b:.4g}{u} along ({nx:.3g}, {ny:.3g}, {nz:.3g})"
        lines.append(
            f"{edit_label(i, len(entries))}{what}: its outer end moved by {to - b:+.4g}{u}, "
            f"{h.get('reevaluated_voxels', 0)} voxels re-evaluated"
        )
    return lines


def unit_suffix(units: str | None) -> str:
    """What follows a length in a message.

    Parameters
    ----------
    units : str or None
        The object's units.

    Returns
    -------
    str
        ``" m"`` (a space, then the units), or nothing for an object without units.

    Examples
    --------
    >>> from partscale.edit import unit_suffix
    >>> unit_suffix("m"), unit_suffix(None)
    (' m', '')
    """
    return f" {units}" if units else ""


def edit_label(i: int, n: int) -> str:
    """What starts a message about edit ``i`` (from 0) of ``n``.

    Parameters
    ----------
    i : int
        The edit's place in its recipe, from 0.
    n : int
        The number of edits in the recipe.

    Returns
    -------
    str
        ``"edit 2: "``, or nothing when the recipe has one edit.

    Examples
    --------
    >>> from partscale.edit import edit_label
    >>> edit_label(1, 3), edit_label(0, 1)
    ('edit 2: ', '')
    """
    return f"edit {i + 1}: " if n > 1 else ""


def _removed(entries: list[Any], out: CSDF) -> list[str]:
    """A line per tile edit with 0 copies (``to`` at the zone's start): the zone was cut out."""
    u = unit_suffix(out.meta.get("units"))
    lines = []
    for i, h in enumerate(entries):
        if not isinstance(h, dict) or h.get("copies") != 0:
            continue
        a, b = h["edit"]["zone"]
        lines.append(
            f"{edit_label(i, len(entries))}tile 0 copies: zone removed ({a:.6g}..{b:.6g}{u} along "
            f"{h['edit']['axis']}), the content beyond it moved by {a - b:+.6g}{u} to join"
        )
    return lines


def _voxel_snaps(entries: list[Any], out: CSDF) -> list[str]:
    """A line per edit whose destination moved to whole voxels (the history keeps both:
    ``edit.to`` as given and ``to_snapped``), saying by how much.
    """
    u = unit_suffix(out.meta.get("units"))
    lines = []
    for i, h in enumerate(entries):
        given = h.get("edit", {}).get("to") if isinstance(h, dict) else None
        snapped = h.get("to_snapped") if isinstance(h, dict) else None
        if (
            given is None
            or snapped is None
            or abs(snapped - given) <= max(SNAP_QUIET_VOXELS * out.voxel_size, 1e-6 * abs(given))
        ):
            continue
        # a removal (0 copies) snaps its zone's start with its destination: say so in its terms
        what, why = (
            ("zone start and destination", "the removed length is")
            if h.get("copies") == 0
            else ("destination", "lengths change by")
        )
        lines.append(
            f"{edit_label(i, len(entries))}{what} {given:.6g} -> {snapped:.6g}{u} "
            f"({snapped - given:+.4g}{u}): {why} whole voxels of "
            f"{out.voxel_size:.4g}{u} (recorded in the history)"
        )
    return lines


def _slivers(entries: list[Any], out: CSDF) -> list[str]:
    """A line per tile edit whose zone plane cut an element: the sliver it cut off was left out
    at the inner seams (history: ``slivers_left_out``, voxels per plane).
    """
    u = unit_suffix(out.meta.get("units"))
    lines = []
    for i, h in enumerate(entries):
        cut = h.get("slivers_left_out") if isinstance(h, dict) else None
        if not cut:
            continue
        zone = h["edit"]["zone"]
        planes = " and ".join(
            f"{p.upper()} plane ({zone[p == 'end']:.6g}{u})" for p in sorted(cut, reverse=True)
        )
        # after a snap, no plane of the period avoids every element: no hint then
        hint = "" if "snapped" in h else "; --snap puts the planes in gaps"
        lines.append(
            f"{edit_label(i, len(entries))}the zone's {planes} cut{'s' if len(cut) == 1 else ''} an "
            f"element: the sliver cut off ({sum(cut.values())} voxels) is left out at the inner "
            f"tile seams, the element stays whole once, beside the copies (recorded in the "
            f"history{hint})"
        )
    return lines
