"""Is the scan in metres? The non-metric guard and the ``scale`` option.

The completion's tolerances are metric (the floor's inlier distance, what counts as one object,
a column's and a strut's radius), so a scan in other units (millimetres, a depth image read with
the wrong depth scale, a reconstruction of arbitrary scale) would be completed with tolerances
wrong by the same factor. Two measurements say whether a scan can be furniture in metres:

- its **extent**: the object's largest side lies within :data:`EXTENT_M` (a 5 cm box to a 4 m
  sofa or table; larger is a room, which the isolation does not take for an object);
- its **point spacing**: the median distance from an observed point to its nearest neighbour
  lies within :data:`SPACING_M` (a structured-light scanner up close reads points about
  0.2 mm apart, a depth camera at its 5 m range 1-2 cm, a LiDAR 3-5 cm); where no object is
  found, the first frame's pixel footprint at its median depth stands for it.

A scan outside either gets one warning naming the ``scale`` option (``--scale``). Where a power
of ten brings both measurements into their ranges (millimetres, centimetres, decimetres; the one
that makes it nearest :data:`TYPICAL_EXTENT_M` where several do), the scan is completed at that
scale, and the warning and the CSDF's history say so; otherwise (or where no object is found at
that scale) it is completed as it is. Given ``scale``, the
scan's coordinates are multiplied by it and nothing is guessed.

A scan whose size is wrong by a small factor (a chair scanned 2 m tall) lies within both ranges,
as a bookcase 2 m tall does: neither measurement can tell them apart, and none is flagged (the
completion's relative tolerances make it complete plausibly at that size).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .. import _schema
from .scan import Frame

EXTENT_M = (0.05, 4.0)
"""Metres: the range of an object's largest side that is plausible furniture."""
SPACING_M = (0.0002, 0.05)
"""Metres: the range of the median nearest-neighbour spacing of points a depth sensor reads."""
TYPICAL_SPACING_M = 0.005
"""Metres: a depth camera's point spacing on furniture 1-2 m away (the guess aims at it where
no object was found)."""
TYPICAL_EXTENT_M = 1.0
"""Metres: the size of furniture the guess aims at."""
MAX_POWER = 4
"""Largest power of ten a guessed scale may be (a scan in tenths of a millimetre)."""


@dataclass(frozen=True)
class Plausibility:
    """The scan's ``extent`` (largest side) and point ``spacing`` (median nearest neighbour) in
    its own units, or None where not measured; whether each is plausible in metres.
    """

    extent: float | None
    spacing: float

    @property
    def plausible(self) -> bool:
        """Both measurements within their metric ranges."""
        ok = SPACING_M[0] <= self.spacing <= SPACING_M[1]
        if self.extent is not None:
            ok &= EXTENT_M[0] <= self.extent <= EXTENT_M[1]
        return bool(ok)

    def scaled(self, factor: float) -> Plausibility:
        """The measurements of the scan with its coordinates multiplied by ``factor``."""
        ext = None if self.extent is None else self.extent * factor
        return Plausibility(ext, self.spacing * factor)

    def guess(self) -> float | None:
        """The power of ten (not 1) that makes both measurements plausible, the one that brings
        the extent nearest :data:`TYPICAL_EXTENT_M` (without an extent: the spacing nearest
        :data:`TYPICAL_SPACING_M`), or None.
        """
        if self.spacing <= 0:
            return None
        fits = [
            10.0**k
            for k in range(-MAX_POWER, MAX_POWER + 1)
            if k != 0 and self.scaled(10.0**k).plausible
        ]
        if not fits:
            return None
        extent = self.extent
        if extent is not None:
            return min(fits, key=lambda f: abs(math.log10(extent * f / TYPICAL_EXTENT_M)))
        return min(fits, key=lambda f: abs(math.log10(self.spacing * f / TYPICAL_SPACING_M)))

    def describe(self) -> str:
        """The measurements in words (for the warning)."""
        ext = "" if self.extent is None else f"an object {self.extent:.3g} units across with "
        return f"{ext}points {self.spacing:.3g} units apart"


def check_scale(scale) -> float:
    """``scale`` (metres per unit of the scan) as a float > 0."""
    return _schema.number(scale, "scale", lo=0.0, lo_open=True)


def scale_frames(frames: list[Frame], factor: float) -> list[Frame]:
    """The frames with their coordinates multiplied by ``factor``: depths and camera positions
    (the intrinsics and the colours are unchanged).
    """
    out = []
    for f in frames:
        pose = f.pose.copy()
        pose[:3, 3] *= factor
        out.append(replace(f, depth=(f.depth * factor).astype(np.float32), pose=pose))
    return out


def of_points(points: np.ndarray, U: np.ndarray) -> Plausibility:
    """The plausibility of an object's observed ``points`` (N, 3) world, upright by ``U`` (4, 4):
    its largest upright side and its points' median nearest-neighbour spacing.
    """
    from scipy.spatial import cKDTree

    up = points @ U[:3, :3].T
    extent = float((up.max(axis=0) - up.min(axis=0)).max())
    d, _ = cKDTree(points).query(points, k=2, workers=2)
    return Plausibility(extent, float(np.median(d[:, 1])))


def of_frame(frame: Frame) -> Plausibility:
    """The plausibility of a frame where no object was found: its pixel footprint at its median
    depth (the spacing of neighbouring readings), no extent.
    """
    z = frame.depth[frame.depth > 0]
    if len(z) == 0:
        return Plausibility(None, 0.0)
    f = float(np.sqrt(abs(frame.K[0, 0] * frame.K[1, 1])))
    return Plausibility(None, float(np.median(z)) / f)


def warning(p: Plausibility, source: str, factor: float | None) -> str:
    """The one line that says the scan may not be in metres, and what was done about it."""
    head = (
        f"{source}: expected furniture in metres ({EXTENT_M[0]:g}-{EXTENT_M[1]:g} m across, "
        f"points {1e3 * SPACING_M[0]:g}-{1e3 * SPACING_M[1]:g} mm apart), got {p.describe()}"
    )
    if factor is None:
        return f"{head}; completed as it is: if it is not in metres, give its metres per unit with --scale"
    return (
        f"{head}; completed as if in units of {factor:g} m (--scale {factor:g}): give its "
        "metres per unit with --scale if that is wrong"
    )
