"""Selective scaling on analytic shapes: exactness, length, rigidity, true distances, replay.

Tolerances are in voxels and one-sided; truths are closed-form SDFs (boxes, bars) or a dense
parametric sampling of the edited sphere.
"""

from __future__ import annotations

import numpy as np
import pytest

from partscale import shapes
from partscale.edit import (
    scale,
)

H = 0.02  # voxel size of the analytic shapes (metres)


def world_grid(c):
    axes = [c.axis_coords(a) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)


@pytest.fixture(scope="module")
def box():
    return shapes.box((0.0, 0.0, 0.0), (1.0, 0.5, 0.3), voxel_size=H)


@pytest.fixture(scope="module")
def ball():
    return shapes.sphere((0.0, 0.0, 0.0), 0.5, voxel_size=H)


# -- exactness on a box ------------------------------------------------------------------------


@pytest.mark.parametrize(("dest", "new_len"), [(0.9, 1.3), (0.46, 0.86)])
def test_box_stretched_in_its_middle_is_a_longer_box(box, dest, new_len):
    out = scale(box, axis="x", zone=(0.3, 0.6), to=dest)
    truth = shapes.box_sdf(world_grid(out), (0, 0, 0), (new_len, 0.5, 0.3))
    band = np.abs(truth) <= 3 * H
    err = np.abs(out.sdf - truth)[band] / H
    assert np.percentile(err, 99) <= 0.05, np.percentile(err, [50, 99, 100])
    assert out.voxel_size == box.voxel_size
    assert out.shape[0] == box.shape[0] + round((dest - 0.6) / H)


# -- length ------------------------------------------------------------------------------------


@pytest.mark.parametrize("mode", ["stretch", "tile", "global"])
@pytest.mark.parametrize("dest", [0.373, -0.043])
def test_extent_changes_by_dest_minus_end(ball, mode, dest):
    start, end = -0.2, 0.1
    before = ball.surface_bounds()[:, 1]
    out = scale(ball, axis="y", zone=(start, end), to=dest, mode=mode)
    after = out.surface_bounds()[:, 1]
    change = (after[1] - after[0]) - (before[1] - before[0])
    assert abs(change - (dest - end)) <= 0.5 * H, (change, dest - end)
    assert out.meta["history"][-1]["edit"]["mode"] == mode
