"""Thin features: solids and gaps the grid holds with fewer than ~1.5 voxels across.

A feature's thickness is measured along the grid axes from the distances themselves: a run of one
or two inside (or outside) voxels along an axis ends where its neighbours' distances say (run
length + 1 minus both neighbours' ``|sdf|``, in voxels), exact for a flat sheet square to the axis (and at most
``sqrt(3)`` times too thick for an oblique one, whose best axis is taken). Thicker runs are not
thin, nor is a short run with a voxel at least ``limit / 2`` deep on its side among its 26
neighbours (the rim of a thick body). Used by ``partscale info`` (a warning and the resolution that would hold them) and by the
import (what lies below one voxel).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .csdf import CSDF

#: Features thinner than this many voxels are reported as thin.
THIN_VOXELS = 1.5


@dataclass(frozen=True)
class ThinFeatures:
    """What :func:`thin_features` found.

    Attributes
    ----------
    solid_voxels, gap_voxels : int
        Inside (solid) and outside (gap) voxels lying in runs thinner than ``limit`` voxels.
    below_one_solid, below_one_gap : int
        Of those, the ones thinner than one voxel.
    typical : float
        Median thickness in voxels of the thin features (``nan`` if none): what a finer
        grid must resolve.
    surface_voxels : int
        Voxels with a zero crossing to a face neighbour (the scale of the counts).
    resolution : int
        Voxels along the solid's longest side now.
    limit : float
        The thickness in voxels below which a feature counts as thin.
    imported : dict
        What the mesh import recorded about closed pieces thinner than the grid holds (it
        thickens them to ``sheet_half_thickness_voxels`` either side, so the grid no longer
        shows how thin they were): ``thin_piece_triangles``, ``thin_piece_thickness_voxels``
        (min, median), ``below_one_voxel_triangles``; empty for other sources.

    Examples
    --------
    A sheet one voxel thick:

    >>> from partscale import shapes
    >>> from partscale.thickness import thin_features
    >>> sheet = shapes.grid(
    ...     lambda p: shapes.box_sdf(p, (0, -0.01, 0), (0.5, 0.01, 0.5)),
    ...     [(0, -0.1, 0), (0.5, 0.1, 0.5)],
    ...     voxel_size=0.02,
    ... )
    >>> found = thin_features(sheet)
    >>> found.solid_voxels, found.typical, found.worth_warning, found.needed_resolution
    (576, 1.0, True, 64)
    >>> found.message(sheet.voxel_size)
    '576 voxels of solid and 0 of gap lie in features thinner than 1.5 voxels ... would hold them'
    """

    solid_voxels: int
    gap_voxels: int
    below_one_solid: int
    below_one_gap: int
    typical: float
    surface_voxels: int
    resolution: int
    limit: float
    imported: dict = field(default_factory=dict)

    @property
    def fraction(self) -> float:
        """Thin voxels (solid and gap) per surface voxel."""
        return (self.solid_voxels + self.gap_voxels) / max(self.surface_voxels, 1)

    def _needed(self, thickness: float) -> int | None:
        if not math.isfinite(thickness) or thickness <= 0:
            return None
        return int(math.ceil(self.resolution * self.limit / thickness / 64.0) * 64)

    @property
    def needed_resolution(self) -> int | None:
        """Voxels along the longest side at which the median thin feature spans ``limit`` voxels.

        The median of the grid's thin features and of the pieces the import thickened, rounded
        up to a multiple of 64; None when there are none.
        """
        needed = [self._needed(self.typical)]
        thin = self.imported.get("thin_piece_thickness_voxels")
        if isinstance(thin, dict):
            needed.append(self._needed(float(thin.get("median", math.nan))))
        got = [g for g in needed if g is not None]
        return max(got) if got else None

    @property
    def worth_warning(self) -> bool:
        """Enough thin voxels to matter, or pieces the import had to thicken.

        Enough: at least 50 and 0.1 % of the surface voxels.
        """
        n = self.solid_voxels + self.gap_voxels
        return (n >= 50 and n >= 0.001 * self.surface_voxels) or bool(
            self.imported.get("thin_piece_triangles")
        )

    def message(self, voxel_size: float, units: str = "m") -> str | None:
        """One line for users: how much is thin, how thin, and the resolution that would hold it.

        Parameters
        ----------
        voxel_size : float
            The grid's voxel edge, to say the median thickness in world units.
        units : str
            The world units' name.

        Returns
        -------
        str or None
            The line; None unless :attr:`worth_warning`.
        """
        if not self.worth_warning:
            return None
        said = []
        if self.solid_voxels + self.gap_voxels:
            size = f"{self.typical * voxel_size:.3g} {units}"
            said.append(
                f"{self.solid_voxels} voxels of solid and {self.gap_voxels} of gap lie in "
                f"features thinner than {self.limit:g} voxels ({self.below_one_solid} and "
                f"{self.below_one_gap} below one voxel; median {self.typical:.2f} voxel = {size})"
            )
        n = self.imported.get("thin_piece_triangles")
        thin = self.imported.get("thin_piece_thickness_voxels")
        if n and isinstance(thin, dict):
            said.append(
                f"{n} triangles of closed pieces {thin['median']:.2f} voxel thick (median; "
                f"thinnest {thin['min']:.2f}, {self.imported.get('below_one_voxel_triangles', 0)}"
                f" below one voxel) were thickened at import to hold them"
            )
        return "; ".join(said) + (
            f"; --res {self.needed_resolution} (now {self.resolution}) would hold them"
        )

    def to_json(self) -> dict:
        """The counts as a JSON-ready dict (``partscale info --json``'s ``thin_features``)."""
        return {
            "limit_voxels": self.limit,
            "solid_voxels": self.solid_voxels,
            "gap_voxels": self.gap_voxels,
            "below_one_voxel": {"solid": self.below_one_solid, "gap": self.below_one_gap},
            "median_thickness_voxels": None if math.isnan(self.typical) else round(self.typical, 3),
            "surface_voxels": self.surface_voxels,
            "resolution": self.resolution,
            "needed_resolution": self.needed_resolution,
            "imported": self.imported,
        }


def thin_features(csdf: CSDF, *, limit: float = THIN_VOXELS) -> ThinFeatures:
    """Solids and gaps thinner than ``limit`` voxels in ``csdf`` (see the module docstring).

    One parallel numba sweep over the grid: six face neighbours read per voxel, the runs and the
    26 neighbours only at the surface; and one float32 array the size of the grid for the
    thicknesses whose median is reported.

    Parameters
    ----------
    csdf : CSDF
        The object.
    limit : float
        Features thinner than this many voxels count as thin.

    Returns
    -------
    ThinFeatures
        The counts, the median thickness and the resolution that would hold it.

    Examples
    --------
    >>> from partscale import shapes
    >>> from partscale.thickness import thin_features
    >>> found = thin_features(shapes.box((0, 0, 0), (0.5, 0.3, 0.5), voxel_size=0.02))
    >>> found.solid_voxels + found.gap_voxels, found.message(0.02)
    (0, None)
    """
    s = np.ascontiguousarray(csdf.sdf, np.float32)
    h = np.float32(csdf.voxel_size)
    thickness = np.full(s.shape, np.inf, np.float32)
    counts = np.zeros((s.shape[0], 5), np.int64)
    from ._thickness_kernel import thin_pass  # numba: loaded on first use

    thin_pass(s, h, float(limit), thickness, counts)
    n = counts.sum(axis=0)
    thick = thickness[np.isfinite(thickness)]
    typical = float(np.quantile(thick, 0.5)) if thick.size else math.nan
    try:
        sb = csdf.surface_bounds()
        res = round(float((sb[1] - sb[0]).max()) / csdf.voxel_size)
    except Exception:  # no voxel inside: nothing to resolve
        res = max(csdf.shape)
    return ThinFeatures(
        solid_voxels=int(n[0]),
        gap_voxels=int(n[1]),
        below_one_solid=int(n[2]),
        below_one_gap=int(n[3]),
        typical=typical,
        surface_voxels=int(n[4]),
        resolution=res,
        limit=float(limit),
        imported=_import_record(csdf),
    )


def _import_record(csdf: CSDF) -> dict:
    keys = ("thin_piece_triangles", "thin_piece_thickness_voxels", "below_one_voxel_triangles")
    for op in csdf.meta.get("history", []):
        if isinstance(op, dict) and op.get("op") == "import":
            return {k: op[k] for k in keys if k in op and op.get("thin_piece_triangles")}
    return {}


__all__ = ["THIN_VOXELS", "ThinFeatures", "thin_features"]
