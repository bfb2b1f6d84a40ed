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


def test_a_library_session_that_imports_then_segments_prints_no_numba_fork_note(tmp_path):
    # import runs numba's parallel kernels on the thread pool, segment then forks its workers:
    # numba's TBB layer, launched from a pool thread, printed "Attempted to fork from a
    # non-main thread" for every worker
    import subprocess
    import sys

    if (os.cpu_count() or 1) < 2:
        pytest.skip("needs two cores: with one, neither the thread pool nor forks are used")
    code = (
        "from partscale import data, ingest\n"
        "from partscale.segment import segment\n"
        "c = segment(ingest.load(data.table(), res=48), cache=False)\n"
        "print(c.n_parts)\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=600, cwd=tmp_path
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert int(proc.stdout.split()[-1]) >= 2
    assert "fork" not in proc.stderr, proc.stderr[-2000:]


def test_thread_map_called_from_its_own_threads_runs_the_items_in_turn(monkeypatch):
    # a function mapped on the pool that maps again would wait on the pool's own threads: the
    # inner map runs in turn on the thread it was called from, and every result comes back
    import threading

    from partscale import _workers

    monkeypatch.setattr(_workers.os, "cpu_count", lambda: 2)
    _workers.reset_pools()
    try:
        inner_threads: list[str] = []

        def inner(x):
            inner_threads.append(threading.current_thread().name)
            return x * x

        def outer(x):
            return sum(_workers.thread_map(inner, range(x)))

        # more outer items than threads: each pool thread holds one and maps again (on a thread
        # of the test's own, so that a pool waiting on itself fails the test, not hangs it)
        got: list = []
        t = threading.Thread(
            target=lambda: got.extend(_workers.thread_map(outer, range(2, 8))), daemon=True
        )
        t.start()
        t.join(timeout=60)
        assert not t.is_alive(), "the pool waits on its own threads"
        assert got == [sum(i * i for i in range(n)) for n in range(2, 8)]
        assert all(name.startswith(_workers._PREFIX) for name in inner_threads)
    finally:
        _workers.reset_pools()


def test_thread_soon_runs_beside_the_caller_and_inline_on_the_pools_own_threads(monkeypatch):
    # started at once on a pool thread, while the caller goes on; the result (or its error)
    # comes back when asked for; from a pool thread it runs on that thread when asked for
    import threading

    from partscale import _workers

    monkeypatch.setattr(_workers.os, "cpu_count", lambda: 2)
    _workers.reset_pools()
    try:
        started = threading.Event()

        def work():
            started.set()
            return threading.current_thread().name

        later = _workers.thread_soon(work)
        # it started before the caller asked for it
        assert started.wait(timeout=60), "thread_soon did not start its work"
        assert later().startswith(_workers._PREFIX)

        def fails():
            raise ValueError("expected in the caller")

        with pytest.raises(ValueError, match="expected in the caller"):
            _workers.thread_soon(fails)()

        def from_pool(_):
            inner = _workers.thread_soon(lambda: threading.current_thread().name)
            return inner(), threading.current_thread().name

        (inner_name, outer_name), _ = _workers.thread_map(from_pool, range(2))
        assert inner_name == outer_name
    finally:
        _workers.reset_pools()
