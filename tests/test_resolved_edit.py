"""ResolvedEdit's coordinate maps, against the edit's analytic definition: content before the
zone stays, content after it moves by ``dest - end``; ``global`` scales about the solid's low
end; ``to_source`` undoes ``to_result`` outside the zone."""

from __future__ import annotations

import numpy as np
import pytest

from partscale.edit import ResolvedEdit


@pytest.mark.parametrize("mode", ["stretch", "tile"])
def test_to_source_moves_content_after_the_zone_back(mode):
    """After a zone [0.3, 0.6] -> [0.3, 0.8]: a point at 0.1 stays, one at 0.9 came from 0.7."""
    r = ResolvedEdit(axis=0, start=0.3, end=0.6, dest=0.8, lo=0.0, hi=1.0, mode=mode)
    assert np.allclose(r.to_source([0.1, 0.3, 0.9, 1.2]), [0.1, 0.3, 0.7, 1.0], atol=1e-12)
    outside = np.array([0.0, 0.1, 0.25, 0.61, 0.75, 1.0])  # before the edit, not in the zone
    assert np.allclose(r.to_source(r.to_result(outside)), outside, atol=1e-12)


def test_to_source_of_a_global_edit_scales_back_about_the_low_end():
    """A solid 0.5 .. 1.5 made 1.5 long (factor 1.5): the result's 2.0 came from 1.5."""
    r = ResolvedEdit(axis=1, start=0.5, end=1.5, dest=2.0, lo=0.5, hi=1.5, mode="global")
    assert r.factor == pytest.approx(1.5, abs=1e-12)
    assert np.allclose(r.to_source([0.5, 1.25, 2.0]), [0.5, 1.0, 1.5], atol=1e-12)
    x = np.linspace(0.5, 1.5, 11)
    assert np.allclose(r.to_source(r.to_result(x)), x, atol=1e-12)
