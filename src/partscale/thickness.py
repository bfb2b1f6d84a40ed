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

import numba as nb
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


@nb.njit(cache=True, parallel=True)
def _thin_pass(s, h, limit, thickness, counts):
    """One sweep over ``s`` (X, Y, Z) float32, slabs of x in parallel: ``thickness`` (X, Y, Z)
    float32 gets each thin voxel's thickness in voxels (inf elsewhere) and ``counts`` (X, 5)
    int64 per slab: thin solid, thin gap, of those below one voxel (solid, gap), and surface
    voxels (a face neighbour across the zero level).

    A voxel's thickness is the least over the axes of its run's: a run of one same-side voxel
    between two of the other side spans ``max(2 - |sdf| before - |sdf| after, 2 |sdf|)``, of
    two ``max(3 - |sdf| before - |sdf| after, 1)`` (``|sdf|`` in voxels; a run reaching the
    border, or longer, is not thin). It is thin below ``limit``, unless it lies on the surface
    (``|sdf| <= 0.01`` voxel) or a voxel of its 3 x 3 x 3 neighbourhood on its side lies at
    least ``limit / 2`` deep (the rim of a thick body).
    """
    # Complexity 49 (radon), kept in one kernel: the sweep's work is per surface voxel, and
    # its runs along each axis, the rim test and the counts read the same neighbourhood while
    # it is in cache; helpers that numba inlines would only move the branches elsewhere, and
    # helpers it calls would pay a call per voxel of the grid's hottest loop.
    nx, ny, nz = s.shape
    dims = (nx, ny, nz)
    on_surface = np.float32(0.01) * h
    deep = np.float32(limit / 2) * h
    one, two, three = np.float32(1.0), np.float32(2.0), np.float32(3.0)
    inf = np.float32(np.inf)
    lim = np.float32(limit)
    for ip in nb.prange(nx):
        i = np.int64(ip)  # signed: neighbours at i - 1 (a prange index may be unsigned)
        for j in range(ny):
            for k in range(nz):
                v = s[i, j, k]
                inside = v <= 0
                # surface voxels: a face neighbour on the other side. Every run of one or two
                # ends at one, so the rest (most of the grid) stop here
                surf = (
                    (i > 0 and (s[i - 1, j, k] <= 0) != inside)
                    or (i < nx - 1 and (s[i + 1, j, k] <= 0) != inside)
                    or (j > 0 and (s[i, j - 1, k] <= 0) != inside)
                    or (j < ny - 1 and (s[i, j + 1, k] <= 0) != inside)
                    or (k > 0 and (s[i, j, k - 1] <= 0) != inside)
                    or (k < nz - 1 and (s[i, j, k + 1] <= 0) != inside)
                )
                if not surf:
                    continue
                counts[i, 4] += 1
                if not abs(v) > on_surface:
                    continue
                t = inf
                x = (i, j, k)
                for ax in range(3):
                    n = dims[ax]
                    pos = x[ax]
                    # runs of one or two holding this voxel: [lo, hi] with lo - 1 and hi + 1
                    # on the other side, both inside the grid
                    for run in range(3):
                        # run 0: [pos, pos]; run 1: [pos - 1, pos]; run 2: [pos, pos + 1]
                        lo = pos - 1 if run == 1 else pos
                        hi = pos + 1 if run == 2 else pos
                        if lo - 1 < 0 or hi + 1 > n - 1:
                            continue
                        ok = True
                        for q in range(lo, hi + 1):
                            if q == pos:
                                continue
                            if ax == 0:
                                w = s[q, j, k]
                            elif ax == 1:
                                w = s[i, q, k]
                            else:
                                w = s[i, j, q]
                            if (w <= 0) != inside:
                                ok = False
                        if not ok:
                            continue
                        if ax == 0:
                            before, after = s[lo - 1, j, k], s[hi + 1, j, k]
                        elif ax == 1:
                            before, after = s[i, lo - 1, k], s[i, hi + 1, k]
                        else:
                            before, after = s[i, j, lo - 1], s[i, j, hi + 1]
                        if ((before <= 0) == inside) or ((after <= 0) == inside):
                            continue
                        ab = np.float32(abs(before)) / h
                        aa = np.float32(abs(after)) / h
                        if run == 0:
                            r = max(two - ab - aa, two * (np.float32(abs(v)) / h))
                        else:
                            r = max(three - ab - aa, one)
                        if r < t:
                            t = r
                if not t < lim:
                    continue
                rim = False
                for ra in range(i - 1 if i > 0 else 0, i + 2 if i + 2 < nx else nx):
                    for rb in range(max(j - 1, 0), min(j + 2, ny)):
                        for rc in range(max(k - 1, 0), min(k + 2, nz)):
                            w = s[ra, rb, rc]
                            if inside:
                                if w <= 0 and -w >= deep:
                                    rim = True
                            elif w > 0 and w >= deep:
                                rim = True
                if rim:
                    continue
                thickness[i, j, k] = t
                side = 0 if inside else 1
                counts[i, side] += 1
                if t < one:
                    counts[i, 2 + side] += 1


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
    _thin_pass(s, h, float(limit), thickness, counts)
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
