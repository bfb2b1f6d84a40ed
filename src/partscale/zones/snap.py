"""Snapping a user's zone to the nearest good one for its mode.

- ``tile``: the zone becomes one whole period of the repeat it lies in (the tile candidate whose
  repeat overlaps it most), with its planes at the best phase nearest the given start (in a gap,
  or where the cross-sections at both planes match; for elements found between boundaries, the
  candidate's own boundary-to-boundary zone moved by whole periods) among those that copy whole
  elements where one does (no plane through a knob or a handle, none doubled:
  :func:`~partscale.zones.features.whole_copies`); the destination keeps the given growth
  rounded to whole periods, so every copy is a copy.
- ``stretch``: the planes move inside the constant slab that overlaps the zone most (or the
  nearest one); where less than two voxels of the zone would remain, the zone becomes the slab.
  Slabs are cut around local features, so a snapped zone lies beside them.
  The destination keeps the given change ``DEST - END``.
- ``global``: nothing moves.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..csdf import CSDF
from ..edit import Edit, tile_count, unit_suffix
from ..errors import InputError
from .features import Feature, axis_features, whole_copies
from .profile import Profile, profile
from .suggest import (
    AXES,
    BOUND_TOL,
    Candidate,
    axis_candidates,
    best_phase,
    calm_runs,
    whole_phase,
)


@dataclass(frozen=True)
class Move:
    """One plane moved by snapping.

    Parameters
    ----------
    plane : {'start', 'end', 'to'}
        Which plane.
    before, after : float
        Its world position before and after.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> from partscale.edit import Edit
    >>> edit, moves = zones.snap(bookcase, Edit("y", 0.3, 0.62, 0.95, "tile"))
    >>> moves[0]
    Move(plane='start', before=0.3, after=0.1625)
    """

    plane: str
    before: float
    after: float

    @property
    def by(self) -> float:
        """How far the plane moved: ``after - before``."""
        return self.after - self.before

    def to_json(self) -> dict:
        """The JSON form (what recipes, histories and the editor's API hold)."""
        return {"plane": self.plane, "from": self.before, "to": self.after}


def _overlap(zone: tuple[float, float], c: Candidate) -> float:
    return min(zone[1], c.region[1]) - max(zone[0], c.region[0])


def _from_boundaries(c: Candidate) -> bool:
    """Whether a tile candidate came from the boundary detector (elements between boards or
    gaps, :func:`~partscale.zones.suggest.find_bounded_repeats`), whose reason says so.
    """
    return c.kind == "tile" and "elements between" in c.reason


def _boundary_start(c: Candidate, near: float, p: Profile, features: list[Feature]) -> float:
    """Start (world) of ``c``'s zone moved by whole periods, inside its region, nearest ``near``.

    A bounded repeat's elements need not match layer for layer (mirrored drawers), so a phase
    off the boundaries cuts an element and joins its halves the wrong way round; its own zone,
    one element and one boundary, is the only phase that copies whole elements. A moved zone
    stays within the elements' span to :data:`~partscale.zones.suggest.BOUND_TOL` voxels (the
    elements' own spacing tolerance), further out it copies what lies past the last element
    (an end board, air), and copies whole elements of the axis's local ``features`` (on
    ``c``'s profile ``p``: :func:`~partscale.zones.features.whole_copies`) where one does.
    """
    assert c.period is not None  # a tile candidate has a period
    period = float(c.period)
    h = p.voxel_size
    k = np.arange(-(c.count or 1), (c.count or 1) + 1)
    starts = c.zone[0] + k * period
    slack = BOUND_TOL * h
    ok = (starts >= c.region[0] - slack) & (starts + period <= c.region[1] + slack)
    lo, hi = (float(v) for v in p.index(np.array(c.region)))
    whole = ok & [whole_copies(features, float(p.index(x)), period / h, lo, hi) for x in starts]
    ok = whole if whole.any() else ok
    starts = starts[ok] if ok.any() else np.array([c.zone[0]])
    return float(starts[np.argmin(np.abs(starts - near))])


def snap(
    csdf: CSDF,
    edit: Edit | dict,
    mode: str | None = None,
    *,
    candidates: Sequence[Candidate] | None = None,
    copies: int | None = None,
) -> tuple[Edit, list[Move]]:
    """Snap ``edit``'s planes for ``mode`` (default: the edit's own).

    Parameters
    ----------
    csdf : CSDF
        The object.
    edit : Edit or dict
        The edit as given.
    mode : {'stretch', 'tile', 'global'}, optional
        The mode to snap for.
    copies : int, optional
        Tile: the number of copies in all the user asked for (``scale --copies``), kept when
        the zone snaps to one period: the destination is that many periods from the snapped
        start. None: the growth the edit asks for (``dest - end``) is kept, in whole periods.
    candidates : sequence of Candidate, optional
        ``csdf``'s candidates as :func:`~partscale.zones.suggest` or
        :func:`~partscale.zones.axis_candidates` returned them (those of other axes are
        ignored), where a caller has them already (the editor's server caches them); None:
        found here. Candidates of another object give a wrong snap: they are not checked.

    Returns
    -------
    (Edit, list of Move)
        The snapped edit in world units (on ``csdf``) and the planes that moved (those that
        moved by less than 1e-9 world units are left out).

    Raises
    ------
    InputError
        When the axis has no candidate of the mode's kind (a non-repeating axis for tile).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> from partscale.edit import Edit
    >>> edit, moves = zones.snap(bookcase, Edit("y", 0.3, 0.62, 0.95, "tile"))  # onto one period
    >>> round(edit.end - edit.start, 3), [m.plane for m in moves]
    (0.295, ['start', 'end', 'to'])
    """
    edit = edit if isinstance(edit, Edit) else Edit.parse(edit)
    mode = (mode or edit.mode).lower()
    ax = edit.axis_index
    sb = csdf.surface_bounds()
    s, e, d = edit.resolve(float(sb[0, ax]), float(sb[1, ax]))
    if not s < e:
        raise InputError(f"zone: expected start < end, got [{s:.6g}, {e:.6g}]")
    if mode == "global":
        return Edit(edit.axis, s, e, d, mode), []
    h = float(csdf.voxel_size)  # the profile's voxel size
    p = profile(csdf, ax) if candidates is None else None
    if candidates is None:
        candidates = axis_candidates(csdf, ax, prof=p)
    kind = "tile" if mode == "tile" else "stretch"
    cands = [c for c in candidates if c.kind == kind and c.axis == AXES[ax]]
    if not cands:
        what = "repeated element" if kind == "tile" else "slab of constant cross-section"
        raise InputError(
            f"snap: expected a {what} along {AXES[ax]} to snap a {mode} zone to, found none"
        )
    zone = (s, e)
    best = max(cands, key=lambda c: (_overlap(zone, c), c.score))
    if _overlap(zone, best) <= 0:  # none overlaps: the nearest
        mid = (s + e) / 2
        best = min(cands, key=lambda c: abs((c.region[0] + c.region[1]) / 2 - mid))
    if kind == "tile":
        assert best.period is not None  # a tile candidate has a period
        period = float(best.period)
        p = p if p is not None else profile(csdf, ax)
        feats = axis_features(csdf, ax, calm_runs(p))
        if _from_boundaries(best):
            # elements between boundaries (mirrored drawers): only the candidate's own
            # boundary-to-boundary zone, moved by whole periods, keeps every element whole
            s2 = _boundary_start(best, s, p, feats)
        else:
            lo, hi = (float(v) for v in p.index(np.array(best.region)))
            # the best phase whose copies repeat whole elements (none cut or doubles a knob),
            # where one does
            near = float(p.index(s))
            t = whole_phase(p, period / h, lo, hi, feats, near=near)
            s2 = float(p.world(best_phase(p, period / h, lo, hi, near=near) if t is None else t))
        e2 = s2 + period
        if copies is None:
            copies = tile_count(period, period + (d - e))
        d2 = s2 + copies * period
    else:
        a, b = best.zone
        s2, e2 = max(s, a), min(e, b)
        if e2 - s2 < 2 * h:
            s2, e2 = a, b
        d2 = e2 + (d - e)
    moves = [
        Move(name, before, after)
        for name, before, after in (("start", s, s2), ("end", e, e2), ("to", d, d2))
        if abs(after - before) > 1e-9
    ]
    return Edit(edit.axis, s2, e2, d2, mode), moves


def describe_moves(moves: list[Move], units: str | None) -> str:
    """One line: what snapping moved and by how much (or that nothing moved).

    Parameters
    ----------
    moves : list of Move
        What :func:`snap` returned.
    units : str or None
        The object's units.

    Returns
    -------
    str
        The line.

    Examples
    --------
    >>> from partscale import zones
    >>> zones.describe_moves([zones.Move("start", 0.3, 0.1625), zones.Move("end", 0.62, 0.4575)], "m")
    'snap: moved start 0.3 -> 0.1625 (-0.1375 m), end 0.62 -> 0.4575 (-0.1625 m)'
    >>> zones.describe_moves([], "m")
    'snap: the planes were already at a good position'
    """
    if not moves:
        return "snap: the planes were already at a good position"
    u = unit_suffix(units)
    parts = [f"{m.plane} {m.before:.4g} -> {m.after:.4g} ({m.by:+.4g}{u})" for m in moves]
    return "snap: moved " + ", ".join(parts)


def record_snap(csdf: CSDF, moves: list[Move]) -> CSDF:
    """Note the snapped planes in ``csdf``'s last history entry (``snapped``).

    Parameters
    ----------
    csdf : CSDF
        An object whose last history entry is the snapped edit.
    moves : list of Move
        What :func:`snap` returned.

    Returns
    -------
    CSDF
        The same grid, its history noting the moves.

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> bookcase = shapes.bookcase()
    >>> from partscale.edit import Edit, apply_edit
    >>> edit, moves = zones.snap(bookcase, Edit("y", 0.3, 0.62, 0.95, "tile"))
    >>> taller = zones.record_snap(apply_edit(bookcase, edit), moves)
    >>> taller.meta["history"][-1]["snapped"][0]
    {'plane': 'start', 'from': 0.3, 'to': 0.1625}
    """
    meta = dict(csdf.meta)
    hist = list(meta.get("history", []))  # entries are read-only and shared: replace the last
    if not hist or not isinstance(hist[-1], dict):
        raise InputError("history: expected an edit to record the snapping on, got none")
    hist[-1] = {**hist[-1], "snapped": [m.to_json() for m in moves]}
    meta["history"] = hist
    return csdf.replace(meta=meta)
