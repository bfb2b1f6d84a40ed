"""NRRD (``.nrrd``): the SDF alone (float32, world units) with space origin and spacing, for
ParaView and 3D Slicer. Through pynrrd.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._files import atomic_path
from ..csdf import CSDF, make
from ..errors import InputError


def write_nrrd(csdf: CSDF, path: Path) -> list[Path]:
    """Write ``csdf.sdf`` as a gzip NRRD volume (x fastest); returns ``[path]``."""
    import nrrd  # pynrrd (absolute import: not this module)

    header = {
        "type": "float",
        "dimension": 3,
        "space dimension": 3,
        "space directions": np.eye(3) * csdf.voxel_size,
        "space origin": csdf.origin.astype(float),
        "kinds": ["domain", "domain", "domain"],
        "space units": [csdf.meta.get("units", "m")] * 3,
        "encoding": "gzip",
        "content": "partscale signed distance, negative inside, iso level 0",
    }
    with atomic_path(path) as tmp:
        nrrd.write(str(tmp), csdf.sdf, header, index_order="F")
    return [path]


def read_nrrd(path: Path) -> CSDF:
    """Read an NRRD volume with cubic voxels as a CSDF (no colour: mid grey; parts all -1)."""
    import nrrd

    try:
        data, header = nrrd.read(str(path), index_order="F")
        origin = np.asarray(header["space origin"], dtype=np.float64)
        spacing = np.diag(np.asarray(header["space directions"], dtype=np.float64))
    except Exception as exc:  # pynrrd raises several unrelated types on bad files
        raise InputError(f"{path}: expected an NRRD volume, got {exc}") from None
    if not np.allclose(spacing, spacing[0]):
        raise InputError(f"{path}: expected cubic voxels, got spacing {spacing.tolist()}")
    return make(
        data.astype(np.float32), None, None, origin, float(spacing[0]), {"source": str(path)}
    )
