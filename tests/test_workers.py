"""Worker processes, seen through the fast segmentation that runs in them: the same parts as in
one process, a worker's error reaches the caller, and no worker outlives its call."""

from __future__ import annotations

import multiprocessing
import os

import numpy as np
import pytest
from conftest import data_path

from partscale import ingest
from partscale.segment import fast, segment

pytestmark = pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(),
    reason="worker processes are forked; this platform has no fork (one process is used)",
)


@pytest.fixture(params=[1, 2], ids=["one process", "two workers"])
def cores(request, monkeypatch):
    # the worker pool starts a process per core
    monkeypatch.setattr(os, "cpu_count", lambda: request.param)
    return request.param


@pytest.fixture(scope="module")
def chair():
    return ingest.load(data_path("kenney/chair.glb"), res=64)


def test_fast_parts_do_not_depend_on_the_number_of_workers(chair, monkeypatch):
    # results come back in the order of their items: parts numbered the same either way
    got = []
    for n in (1, 2):
        monkeypatch.setattr(os, "cpu_count", lambda n=n: n)
        got.append(segment(chair, method="fast", cache=False).parts)
        assert multiprocessing.active_children() == []  # no worker outlives its call
    assert got[0].max() >= 3  # a chair: seat, back, legs
    np.testing.assert_array_equal(got[0], got[1])


def test_a_workers_error_reaches_the_caller_and_the_workers_stop(chair, cores, monkeypatch):
    # the fast method's regions are cut in worker processes (forked: they see this patch)
    def broken(*args, **kwargs):
        raise ValueError("points: expected a hull, got -3")

    monkeypatch.setattr(fast, "hull_concavity", broken)
    with pytest.raises(ValueError, match="expected a hull, got -3"):
        segment(chair, method="fast", cache=False)
    assert multiprocessing.active_children() == []
