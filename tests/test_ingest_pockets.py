"""The import's bubble fill: enclosed pockets of the thin outside shell, as ``ndimage.label`` finds them.

``partscale.ingest._sign.shell_pockets`` labels only the shell's voxels; users rely on
imports being the same voxel for voxel as with the full-grid labelling it replaced.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from partscale.ingest import _sign


def _reference(sdf, lim):
    """Pockets from ``ndimage.label`` of the whole grid (what the kernel replaced)."""
    labels, n = ndimage.label((sdf > 0) & (sdf <= lim))
    idx = np.flatnonzero(labels)
    lab = labels.ravel()[idx]
    open_ = np.zeros(n + 1, bool)
    coords = np.unravel_index(idx, sdf.shape)
    for ax in range(3):
        for step in (-1, 1):
            c = coords[ax] + step
            border = (c < 0) | (c >= sdf.shape[ax])
            open_[lab[border]] = True
            ok = ~border
            nb = tuple(c[ok] if a == ax else coords[a][ok] for a in range(3))
            open_[lab[ok][sdf[nb] > lim]] = True
    return idx[~open_[lab]]


@pytest.mark.parametrize("seed", range(6))
def test_shell_pockets_match_full_grid_labels(seed):
    rng = np.random.default_rng(seed)
    values = np.array([-1.0, 0.2, 0.3, 0.5, 0.7, 2.0], np.float32)
    found = 0
    for _ in range(80):
        shape = tuple(int(s) for s in rng.integers(1, 14, 3))
        sdf = rng.choice(values, size=shape, p=rng.dirichlet(np.ones(6)))
        want = _reference(sdf, np.float32(0.5))
        got = _sign.shell_pockets(sdf, np.float32(0.5))
        np.testing.assert_array_equal(got, want)
        found += len(want) > 0
    assert found > 0  # the draws do contain enclosed pockets


def test_shell_pocket_enclosed_by_solid_is_found_and_open_one_is_not():
    sdf = np.full((7, 7, 7), -1.0, np.float32)
    sdf[3, 3, 3] = 0.3  # enclosed: every neighbour inside
    sdf[0, 5, 5] = 0.3  # on the border: open
    got = _sign.shell_pockets(sdf, np.float32(0.5))
    np.testing.assert_array_equal(got, [np.ravel_multi_index((3, 3, 3), sdf.shape)])
