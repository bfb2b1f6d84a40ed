"""An edit resolved on the CSDF it applies to: world positions, validated, snapped to whole voxels.

:func:`resolve_edit` is the one place an :class:`~partscale.edit.Edit` is checked against an
object; the scaling stage performs exactly the :class:`ResolvedEdit` it returns, the evaluation
judges the result against it, and a fit solver can try positions with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._memory import check_memory
from ..csdf import CSDF
from ..errors import InputError
from .notes import unit_suffix
from .recipe import AXES, Edit, tile_count

#: Peak working bytes per output voxel of an edit (output arrays, float temporaries, masks).
BYTES_PER_VOXEL = 64  # 48, plus up to 16 where every voxel is re-evaluated (index, old value, flag)


@dataclass(frozen=True)
class ResolvedEdit:
    """One zone edit in world units on a given object.

    Parameters
    ----------
    axis : int
        0, 1, 2 for x, y, z.
    start, end : float
        The zone ``[start, end]`` before the edit.
    dest : float
        Where ``end`` goes: the given position snapped to ``end`` plus a whole number of voxels,
        which is what the scaling stage performs (grids keep their voxel size).
    lo, hi : float
        The original solid's extent along ``axis`` (what ``%`` positions refer to).
    mode : {'stretch', 'tile', 'global'}
        How the zone changes.
    given_dest : float or None
        ``dest`` as given, before snapping (recorded in the history); ``dest`` if not given.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import Edit, resolve_edit
    >>> r = resolve_edit(bar, Edit("x", "30%", "60%", "80%"))
    >>> r.start, r.end, r.dest, r.lo, r.hi
    (0.3, 0.6, 0.8, 0.0, 1.0)
    """

    axis: int
    start: float
    end: float
    dest: float
    lo: float
    hi: float
    mode: str = "stretch"
    given_dest: float | None = None

    def __post_init__(self) -> None:
        if self.given_dest is None:
            object.__setattr__(self, "given_dest", self.dest)

    @property
    def axis_name(self) -> str:
        """The axis as ``'x'``, ``'y'`` or ``'z'``."""
        return AXES[self.axis]

    @property
    def shift(self) -> float:
        """How far content beyond the zone moves: ``dest - end``."""
        return self.dest - self.end

    @property
    def target_length(self) -> float:
        """The solid's length along the axis after the edit."""
        return self.hi - self.lo + self.shift

    @property
    def factor(self) -> float:
        """Scale factor of the whole solid along the axis in ``global`` mode."""
        return self.target_length / (self.hi - self.lo)

    @property
    def n_copies(self) -> int:
        """Copies of the zone a ``tile`` makes (:func:`~partscale.edit.tile_count`; 0: removed)."""
        return tile_count(self.end - self.start, self.dest - self.start)

    def shift_voxels(self, voxel_size: float) -> int:
        """Whole voxels the grid grows (shrinks, if negative) along the axis."""
        return round(self.shift / voxel_size)

    def to_source(self, y: ArrayLike) -> np.ndarray:
        """Map coordinates after the edit back to before, for rigid content and for ``global``."""
        y = np.asarray(y, dtype=np.float64)
        if self.mode == "global":
            return self.lo + (y - self.lo) / self.factor
        return np.where(y <= self.start, y, y - self.shift)

    def to_result(self, x: ArrayLike) -> np.ndarray:
        """Map coordinates before the edit to after (inverse of :meth:`to_source` outside)."""
        x = np.asarray(x, dtype=np.float64)
        if self.mode == "global":
            return self.lo + (x - self.lo) * self.factor
        return np.where(x <= self.start, x, x + self.shift)

    def seams(self) -> list[tuple[float, float | None]]:
        """Seam planes in the result, each with the original plane it continues (None: a join).

        The zone's two planes, and for ``tile`` the joins between consecutive copies; a removed
        zone (tile, 0 copies) is one join at START, where the content before START meets the
        content after END.
        """
        if self.mode == "global":
            return [
                (float(self.to_result(self.start)), self.start),
                (float(self.to_result(self.end)), self.end),
            ]
        if self.mode == "tile" and self.n_copies == 0:
            return [(self.start, None)]
        out: list[tuple[float, float | None]] = [(self.start, self.start), (self.dest, self.end)]
        if self.mode == "tile":
            n = self.n_copies
            step = (self.dest - self.start) / n
            out += [(self.start + m * step, None) for m in range(1, n)]
        return out


def _fmt(v: float) -> str:
    return f"{v:.6g}"


def _shown(given: object, world: float, units: str | None) -> str:
    """A position as the user gave it, with its world value when that differs (``10% (0.2 m)``)."""
    w = _fmt(world) + unit_suffix(units)
    return f"{given} ({w})" if isinstance(given, str) else w


def resolve_edit(csdf: CSDF, edit: Edit, *, given: Edit | None = None) -> ResolvedEdit:
    """Validate ``edit`` against ``csdf`` and resolve it to world units.

    ``%`` positions refer to the solid's extent along the axis; ``dest`` is snapped to whole
    voxels. A ``tile`` with ``dest`` equal to the start makes 0 copies: the zone is cut out and
    the sides join (its start snaps to whole voxels from its end, as a destination does, so the
    content beyond moves by whole voxels).

    Parameters
    ----------
    csdf : CSDF
        The object.
    edit : Edit
        The edit.
    given : Edit, optional
        The edit as the user wrote it (a recipe step before its planes were carried to world
        units), whose positions the messages echo beside the world values.

    Returns
    -------
    ResolvedEdit
        The edit in world units.

    Raises
    ------
    InputError
        A zone outside the solid or thinner than two voxels, a destination not beyond the start
        (for stretch and global; before it for tile), or an output grid too large for memory.

    Examples
    --------
    >>> from partscale import shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> from partscale.edit import Edit, resolve_edit
    >>> resolve_edit(bar, Edit("x", 0.3, 0.6, 0.83)).dest
    0.85
    """
    ax = edit.axis_index
    h = csdf.voxel_size
    sb = csdf.surface_bounds()
    lo, hi = float(sb[0, ax]), float(sb[1, ax])
    s, e, d = edit.resolve(lo, hi)
    units = csdf.meta.get("units")

    def shown(which: str, world: float) -> str:
        return _shown(getattr(given or edit, which), world, units)

    if not all(map(math.isfinite, (s, e, d, (d - e) / h))):
        raise InputError(
            f"zone, to: expected finite positions, got zone [{_fmt(s)}, {_fmt(e)}], to {_fmt(d)}"
        )
    name = AXES[ax]
    if not s < e:
        raise InputError(
            f"zone: expected start < end, got start {shown('start', s)} >= end {shown('end', e)}"
        )
    # tile to the zone's start: 0 copies, the zone cut out. "At the start" within a millionth
    # of a voxel: a recipe read back from a history (or any float round trip) may put DEST an
    # ulp before START
    same = abs(d - s) <= 1e-6 * h
    remove = edit.mode == "tile" and same
    if not (d > s or remove):
        if same:
            raise InputError(
                f"to: expected DEST > START {shown('start', s)} for {edit.mode}, got DEST == "
                "START (to remove the zone use mode tile, whose DEST == START makes 0 copies)"
            )
        raise InputError(f"to: expected DEST > START {shown('start', s)}, got {shown('dest', d)}")
    tol = h / 2
    if s < lo - tol or e > hi + tol:
        raise InputError(
            f"zone: expected inside the solid's extent [{_fmt(lo)}, {_fmt(hi)}] along {name}, "
            f"got [{shown('start', s)}, {shown('end', e)}]"
        )
    if e - s < 2 * h - 1e-6 * h:  # rounding slack: 0.6 - 0.4 at h = 0.1 is two voxels
        raise InputError(
            f"zone: expected at least two voxels thick ({_fmt(2 * h)}), got {_fmt(e - s)}"
        )
    shift = round((d - e) / h)
    d_snap = e + shift * h
    if remove:
        # the zone removed is whole voxels: its start snaps with the destination (under half a
        # voxel), so DEST == START exactly and everything beyond END moves by whole voxels
        s = d_snap
    elif d_snap - s < h:
        raise InputError(
            f"to: expected DEST at least one voxel ({_fmt(h)}) beyond START {shown('start', s)}, "
            f"got {shown('dest', d)}"
        )
    shape = list(csdf.shape)
    shape[ax] += shift
    check_memory(tuple(shape), BYTES_PER_VOXEL, what=f"scale along {name} to {shown('dest', d)}")
    return ResolvedEdit(ax, s, e, d_snap, lo, hi, edit.mode, given_dest=d)
