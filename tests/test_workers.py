"""Worker processes: results in order and the same as in one process, a worker's error reaches
the caller, and no worker outlives its pool."""

from __future__ import annotations

import multiprocessing

import numpy as np
import pytest
from conftest import data_path

from partscale import _workers, ingest
from partscale.segment import segment

pytestmark = pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(),
    reason="worker processes are forked; this platform has no fork (one process is used)",
)


class Scaled:
    """A worker holding state made once per process (here a factor)."""

    def __init__(self, factor: np.ndarray):
        self.factor = factor

    def __call__(self, x: int) -> float:
        if x < 0:
            raise ValueError(f"x: expected >= 0, got {x}")
        return float(self.factor.sum() * x)


@pytest.fixture(params=[1, 2], ids=["one process", "two workers"])
def cores(request, monkeypatch):
    monkeypatch.setattr(_workers.os, "cpu_count", lambda: request.param)
    return request.param


def test_map_keeps_the_order_of_items(cores):
    items = list(range(37))
    with _workers.worker_pool(Scaled, np.full(3, 2.0)) as workers:
        assert workers.map(items) == [6.0 * x for x in items]
        assert workers.map([]) == []
        assert workers.map(items[:3]) == [0.0, 6.0, 12.0]


def test_submitted_items_come_back_with_their_tickets(cores):
    with _workers.worker_pool(Scaled, np.ones(2)) as workers:
        tickets = {workers.submit(x): x for x in (5, 1, 9, 2)}
        got = dict(workers.next_done() for _ in range(4))
    assert got == {t: 2.0 * x for t, x in tickets.items()}


def test_a_workers_error_reaches_the_caller_and_the_workers_stop(cores):
    with pytest.raises(ValueError, match="expected >= 0, got -3"):
        with _workers.worker_pool(Scaled, np.ones(1)) as workers:
            workers.map([1, 2, -3, 4])
    assert multiprocessing.active_children() == []


def test_fast_parts_do_not_depend_on_the_number_of_workers(monkeypatch):
    c = ingest.load(data_path("kenney/chair.glb"), res=64)
    got = []
    for n in (1, 2):
        monkeypatch.setattr(_workers.os, "cpu_count", lambda n=n: n)
        got.append(segment(c, method="fast", cache=False).parts)
    assert got[0].max() >= 3  # a chair: seat, back, legs
    np.testing.assert_array_equal(got[0], got[1])
