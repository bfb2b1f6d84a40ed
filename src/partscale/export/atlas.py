"""Texture atlases: the surface unwrapped with xatlas and the CSDF's colour baked into a PNG.

Each texel a chart covers holds the CSDF's colour (trilinear ``rgb``, sRGB) at the surface point
it maps to; every other texel takes its nearest covered texel's colour, so bilinear filtering and
mipmaps never mix in colour from outside a chart.
"""

from __future__ import annotations

import numba
import numpy as np

from .._options import preset
from ..csdf import CSDF
from ..errors import InputError

ATLAS_SIZES = (256, 512, 1024, 2048, 4096)
DEFAULT_ATLAS = 1024
#: no chart larger than the surface's area over this
CHART_AREA_DIVISOR = 100


def check_atlas(size: int | None) -> int | None:
    """Validate an atlas size: None, or one of :data:`ATLAS_SIZES` texels a side.

    Parameters
    ----------
    size : int or None
        Texels a side, or None for no atlas.

    Returns
    -------
    int or None
        ``size`` as an int (None stays None).

    Examples
    --------
    >>> from partscale.export import check_atlas
    >>> check_atlas(1024)
    1024
    >>> check_atlas(1000)
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: atlas: expected one of 256, 512, 1024, 2048, 4096 texels, got 1000
    """
    return preset(size, "atlas", ATLAS_SIZES, unit="texels")


@numba.njit(cache=True)
def _rasterise(uv, faces, vertices, size, pos, covered):
    # texel (r, c) has its centre at uv ((c + 0.5) / size, (r + 0.5) / size)
    for f in range(faces.shape[0]):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        ax, ay = uv[a, 0] * size, uv[a, 1] * size
        bx, by = uv[b, 0] * size, uv[b, 1] * size
        cx, cy = uv[c, 0] * size, uv[c, 1] * size
        det = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay)
        if abs(det) < 1e-12:
            continue
        x0 = max(int(np.floor(min(ax, bx, cx))), 0)
        x1 = min(int(np.ceil(max(ax, bx, cx))), size - 1)
        y0 = max(int(np.floor(min(ay, by, cy))), 0)
        y1 = min(int(np.ceil(max(ay, by, cy))), size - 1)
        for r in range(y0, y1 + 1):
            py = r + 0.5
            for col in range(x0, x1 + 1):
                px = col + 0.5
                wb = ((px - ax) * (cy - ay) - (cx - ax) * (py - ay)) / det
                wc = ((bx - ax) * (py - ay) - (px - ax) * (by - ay)) / det
                wa = 1.0 - wb - wc
                if wa < -1e-6 or wb < -1e-6 or wc < -1e-6:
                    continue
                for k in range(3):
                    pos[r, col, k] = wa * vertices[a, k] + wb * vertices[b, k] + wc * vertices[c, k]
                covered[r, col] = True


def unwrap(vertices: np.ndarray, faces: np.ndarray, size: int):
    """Xatlas charts packed into a ``size``² atlas.

    Parameters
    ----------
    vertices : (V, 3) float
        The mesh's vertices.
    faces : (F, 3) int
        Its triangles.
    size : int
        Texels a side of the atlas the charts are packed into.

    Returns
    -------
    vmap : (V',) int64
        Source vertex of each new vertex (vertices are split along chart seams).
    faces : (F, 3) int64
        Triangles over the new vertices, in the input's order.
    uv : (V', 2) float32
        In [0, 1], glTF's convention: v = 0 at the image's top row.

    Examples
    --------
    >>> from partscale import data, export, ingest
    >>> from partscale.surface import to_mesh
    >>> table = ingest.load(data.table(), res=64)
    >>> mesh = export.simplify(to_mesh(table), voxel_size=table.voxel_size, faces=1000)
    >>> vmap, faces, uv = export.unwrap(mesh.vertices, mesh.faces, 256)
    >>> len(faces) == len(mesh.faces), float(uv.min()) >= 0, float(uv.max()) <= 1
    (True, True, True)
    """
    import xatlas

    atlas = xatlas.Atlas()
    atlas.add_mesh(
        np.ascontiguousarray(vertices, np.float32), np.ascontiguousarray(faces, np.uint32)
    )
    pack = xatlas.PackOptions()
    pack.resolution = int(size)
    pack.padding = 2  # texels between charts, so bilinear taps at a border stay in its chart
    pack.bilinear = True
    pack.blockAlign = True  # measured: a quarter faster to pack, same utilisation within 2%
    charts = xatlas.ChartOptions()
    # capping a chart's area bounds xatlas's chart growing, its slowest step: measured 3x faster
    # on the SheenChair at 20k triangles (388 charts instead of 299, same texel density)
    tri = np.asarray(vertices, np.float64)[np.asarray(faces)]
    area = (
        0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    )
    charts.max_chart_area = float(area / CHART_AREA_DIVISOR)
    atlas.generate(charts, pack)
    vmap, idx, uv = atlas[0]
    return vmap.astype(np.int64), idx.astype(np.int64), uv.astype(np.float32)


def bake(
    csdf: CSDF, vertices: np.ndarray, faces: np.ndarray, uv: np.ndarray, size: int
) -> np.ndarray:
    """Bake the CSDF's colour at the surface point under each texel of a UV atlas.

    Parameters
    ----------
    csdf : CSDF
        The object whose colour is baked.
    vertices : (V, 3) float
        World positions of the unwrapped mesh's vertices.
    faces : (F, 3) int
        Its triangles.
    uv : (V, 2) float
        Texture coordinates in [0, 1] (v = 0 at the image's top row), as :func:`unwrap` gives.
    size : int
        Texels a side.

    Returns
    -------
    (size, size, 3) uint8
        sRGB texture; texels no triangle covers take their nearest covered texel's colour.

    Examples
    --------
    >>> from partscale import export, shapes
    >>> from partscale.surface import to_mesh
    >>> box = shapes.box((0, 0, 0), (1.0, 0.5, 0.25), voxel_size=0.05)
    >>> mesh = to_mesh(box)
    >>> vmap, faces, uv = export.unwrap(mesh.vertices, mesh.faces, 256)
    >>> texture = export.bake(box, mesh.vertices[vmap], faces, uv, 256)
    >>> texture.shape, texture[0, 0].tolist()
    ((256, 256, 3), [200, 120, 60])
    """
    from scipy import ndimage

    from ..surface import sample_linear

    pos = np.zeros((size, size, 3), np.float64)
    covered = np.zeros((size, size), np.bool_)
    _rasterise(
        np.ascontiguousarray(uv, np.float64),
        np.ascontiguousarray(faces, np.int64),
        np.ascontiguousarray(vertices, np.float64),
        size,
        pos,
        covered,
    )
    if not covered.any():
        raise InputError("atlas: expected charts covering texels, got none (surface too small?)")
    image = np.zeros((size, size, 3), np.uint8)
    rgb = sample_linear(csdf.rgb, csdf.world_to_index(pos[covered]))
    image[covered] = np.clip(np.rint(rgb), 0, 255).astype(np.uint8)
    # every uncovered texel: the colour of its nearest covered texel (padding to the next chart)
    near = ndimage.distance_transform_edt(~covered, return_distances=False, return_indices=True)
    return image[near[0], near[1]]


def png_bytes(image: np.ndarray) -> bytes:
    """The PNG file's bytes of an (H, W, 3) uint8 image."""
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(image, "RGB").save(buf, format="PNG", optimize=False)
    return buf.getvalue()
