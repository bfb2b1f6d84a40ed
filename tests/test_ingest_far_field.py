"""The import's far field: the nearest band voxel is scipy's Euclidean feature transform's.

``partscale.ingest._far_field.far_field`` computes the transform itself (in parallel, fused with
the fill); users rely on imports being the same voxel for voxel as with scipy's transform.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from partscale.ingest import _distance, _far_field


def _reference(band, origin, h, tris, win, offset, sign, floor, sdf, rgb):
    """The fill from scipy's feature transform, in numpy (what the kernel replaced)."""
    ft = ndimage.distance_transform_edt(~band, return_distances=False, return_indices=True)
    far = np.flatnonzero(~band)
    src = tuple(f.ravel()[far] for f in ft)
    t = win[src].astype(np.int64)
    pts = origin + np.stack(np.unravel_index(far, band.shape), axis=1) * h
    d, _ = _distance.closest_points(pts, tris, t)
    s = sign.ravel()[far]
    d = np.where(s > 0, d - offset[t], -d)
    sdf.ravel()[far] = s * np.maximum(np.abs(d), floor)
    rgb.reshape(-1, 3)[far] = rgb[src]


@pytest.mark.parametrize(
    ("shape", "density", "seed"),
    [
        ((23, 17, 19), 0.02, 0),
        ((9, 31, 14), 0.3, 1),
        ((16, 16, 16), 0.001, 2),
        ((5, 7, 40), 0.9, 3),
    ],
)
def test_far_field_matches_scipy_feature_transform(shape, density, seed):
    rng = np.random.default_rng(seed)
    band = rng.random(shape) < density
    band.ravel()[rng.integers(band.size)] = True  # at least one band voxel
    tris = rng.random((12, 3, 3)) * np.array(shape) * 0.5
    win = rng.integers(0, len(tris), shape).astype(np.int32)
    offset = rng.random(len(tris)) * 0.5
    sign = np.where(rng.random(shape) < 0.5, 1, -1).astype(np.int8)
    origin, h, floor = np.array([0.1, -0.2, 0.3]), 0.5, 1.5
    sdf0 = rng.random(shape).astype(np.float32)
    rgb0 = rng.integers(0, 256, (*shape, 3)).astype(np.uint8)
    got_sdf, got_rgb = sdf0.copy(), rgb0.copy()
    _far_field.far_field(band, origin, h, tris, win, offset, sign, floor, got_sdf, got_rgb)
    ref_sdf, ref_rgb = sdf0.copy(), rgb0.copy()
    _reference(band, origin, h, tris, win, offset, sign, floor, ref_sdf, ref_rgb)
    np.testing.assert_array_equal(got_sdf, ref_sdf)
    np.testing.assert_array_equal(got_rgb, ref_rgb)
