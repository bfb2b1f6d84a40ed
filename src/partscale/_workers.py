"""Parallel work: a thread pool for GIL-free work, forked worker processes for the rest."""

from __future__ import annotations

import collections
import contextlib
import multiprocessing
import os
import signal
import warnings
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from multiprocessing import connection as mp_connection
from typing import Any, cast

_POOL: ThreadPoolExecutor | None = None
_PREFIX = "partscale-pool"
"""The names of the pool's threads begin so (:func:`thread_map` knows its own)."""


def thread_map(fn: Callable, items: Iterable) -> list:
    """``[fn(x) for x in items]`` on a thread per core, results in the order of ``items``.

    For work that releases the GIL (qhull, KD-tree searches, ``nogil`` numba kernels, ndimage).
    One pool serves the whole process; called from one of its own threads (``fn`` calling
    :func:`thread_map` again) it runs the items in turn, as the pool could otherwise be waiting
    on its own workers.
    """
    items = list(items)
    pool = _pool() if len(items) >= 2 else None
    if pool is None:
        return [fn(x) for x in items]
    return list(pool.map(fn, items))


def thread_soon(fn: Callable[[], Any]) -> Callable[[], Any]:
    """``fn()`` started now on the pool, beside the caller's own work (for work that releases
    the GIL, as :func:`thread_map`); returns a callable that waits for and returns its result.
    With one core, or from one of the pool's own threads, ``fn`` runs when that is called.

    Examples
    --------
    >>> from partscale._workers import thread_soon
    >>> later = thread_soon(lambda: sum(range(10)))
    >>> later()
    45
    """
    pool = _pool()
    return fn if pool is None else pool.submit(fn).result


def _pool() -> ThreadPoolExecutor | None:
    """The process's thread pool (made on first use), or None where work runs in the caller's
    thread: one core, or the caller is one of the pool's threads.
    """
    import threading

    global _POOL
    if (os.cpu_count() or 1) < 2 or threading.current_thread().name.startswith(_PREFIX):
        return None
    if _POOL is None:
        launch_numba_threads()
        _POOL = ThreadPoolExecutor(max_workers=os.cpu_count(), thread_name_prefix=_PREFIX)
    return _POOL


def launch_numba_threads() -> None:
    """Start numba's parallel threads from the main thread, before the pool's threads run kernels.

    numba's TBB layer remembers the thread that first launched it; launched from a pool thread,
    every later fork (:func:`worker_pool`, from the main thread) prints "Numba: Attempted to fork
    from a non-main thread, the TBB library may be in an invalid state in the child process" on
    stderr, which a library user sees after ``load`` then ``segment``. Call it before handing
    parallel kernels to any thread of one's own (:func:`thread_map` does).
    """
    import threading

    if threading.current_thread() is not threading.main_thread():
        return
    import numba

    numba.get_num_threads()  # launches numba's threads first, in this thread


def reset_pools() -> None:
    """Forget the thread pool (in a forked process, where its threads do not exist, or after
    ``os.cpu_count()`` changed); the next :func:`thread_map` makes a new one."""
    global _POOL
    _POOL = None


class Workers:
    """What :func:`worker_pool` yields: ``map`` a batch, or ``submit`` items one at a time and
    take results with ``next_done`` as they finish.

    Each worker process talks to this one over its own pipe, so a batch of a few items costs a
    pipe round trip each, not an executor's queues and threads (about 0.2 ms against 0.8 ms
    per batch of four). A worker gets its next item only once it has sent its last result: with
    two in flight, both sides could block writing to a full pipe (a large mask one way, its
    pieces the other).
    """

    def __init__(
        self, worker: Callable | None = None, conns: list[mp_connection.Connection] | None = None
    ):
        self._worker, self._conns = worker, conns or []
        self._todo: collections.deque = collections.deque()
        self._busy = {c: 0 for c in self._conns}
        self._done: collections.deque = collections.deque()
        self._next = 0

    def submit(self, item) -> int:
        """Queue ``worker(item)``; returns its ticket (0, 1, 2, ... in submission order)."""
        return self._submit([item])

    def _submit(self, chunk: list) -> int:
        # a chunk of items travels as one message; its result is the list of their results
        ticket, self._next = self._next, self._next + 1
        if not self._conns:
            assert self._worker is not None  # made without pipes, it runs the worker here
            self._done.append((ticket, [self._worker(x) for x in chunk]))
        else:
            self._todo.append((ticket, chunk))
            self._dispatch()
        return ticket

    def next_done(self) -> tuple[int, Any]:
        """(ticket, result) of a finished item, waiting for one; re-raises a worker's error."""
        ticket, results = self._next_chunk()
        return ticket, results[0]

    def _next_chunk(self) -> tuple[int, list]:
        if self._done:
            return self._done.popleft()
        busy = [c for c, n in self._busy.items() if n]
        if not busy:
            raise RuntimeError("next_done: nothing was submitted")
        # wait() returns some of the objects it was given: our pipe ends
        conn = cast(mp_connection.Connection, mp_connection.wait(busy)[0])
        try:
            ticket, ok, value = conn.recv()
        except EOFError:
            raise RuntimeError("a worker process died (out of memory?)") from None
        self._busy[conn] = 0
        self._dispatch()
        if not ok:
            raise value
        return ticket, value

    def map(self, items: Iterable) -> list:
        """``[worker(x) for x in items]``, in the order of ``items``."""
        items = list(items)
        # a few chunks per worker: fewer round trips, and still balanced
        size = max(1, -(-len(items) // (4 * max(len(self._conns), 1))))
        tickets = [self._submit(items[i : i + size]) for i in range(0, len(items), size)]
        out: dict[int, list] = {}
        while len(out) < len(tickets):
            t, r = self._next_chunk()
            out[t] = r
        return [r for t in tickets for r in out[t]]

    def _dispatch(self) -> None:
        for conn in self._conns:
            if self._todo and not self._busy[conn]:
                conn.send(self._todo.popleft())
                self._busy[conn] = 1


def _serve(conn, factory: Callable, args: tuple) -> None:  # pragma: no cover - in a worker
    """A worker process's loop: (ticket, item) in, (ticket, ok, result or error) out."""
    # Ctrl-C reaches the whole process group: the parent stops its workers itself
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    worker = factory(*args)
    while (msg := conn.recv()) is not None:
        ticket, chunk = msg
        try:
            conn.send((ticket, True, [worker(x) for x in chunk]))
        except Exception as exc:  # the parent re-raises it
            conn.send((ticket, False, exc))


@contextlib.contextmanager
def worker_pool(factory: Callable, *args) -> Iterator[Workers]:
    """Yield :class:`Workers` running ``worker = factory(*args)`` on a process per core, the
    worker made once in each process.

    For work that holds the GIL too much for :func:`thread_map` (the Python around qhull and
    tree searches scales about 1.3x on two threads, 1.9x on two processes). Workers are forked,
    so ``args`` (grids, point buffers) are inherited without copying or pickling; items and
    results are pickled, so keep them small. Where fork is unavailable or there is one core,
    one ``worker`` runs in this process, item by item as submitted.
    """
    cores = os.cpu_count() or 1
    if cores < 2 or "fork" not in multiprocessing.get_all_start_methods():
        yield Workers(factory(*args))
        return
    ctx = multiprocessing.get_context("fork")
    procs, conns = [], []
    try:
        for _ in range(cores):
            here, there = ctx.Pipe()
            proc = ctx.Process(target=_serve, args=(there, factory, args), daemon=True)
            with warnings.catch_warnings():
                # Python 3.12+ warns on any fork of a process with threads (our thread pool,
                # numba's). The workers only compute on inherited arrays and talk over their
                # pipe; they take no lock another thread could hold at the fork.
                warnings.filterwarnings(
                    "ignore",
                    message=r".*fork\(\) may lead to deadlocks",
                    category=DeprecationWarning,
                )
                proc.start()
            there.close()
            procs.append(proc)
            conns.append(here)
        yield Workers(conns=conns)
    finally:
        for conn in conns:
            with contextlib.suppress(OSError):
                conn.send(None)
        for proc in procs:
            proc.join(timeout=5)
            if proc.is_alive():
                proc.terminate()
                proc.join()
        for conn in conns:
            conn.close()
