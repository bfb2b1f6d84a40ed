"""Small helpers shared by every stage: atomic writes, option checks, memory guards, threads and
worker processes."""

from __future__ import annotations

import collections
import contextlib
import functools
import inspect
import json
import multiprocessing
import os
import signal
import tempfile
import warnings
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from multiprocessing import connection as mp_connection
from pathlib import Path
from typing import TypeVar

from .errors import InputError, MemoryLimitError

F = TypeVar("F", bound=Callable)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    Nothing half-written is ever left: on any exception the temporary file is removed and the
    destination is untouched. The temporary keeps ``path``'s suffix (or ``suffix``) so writers
    that infer the format from the name still work. A destination the file system refuses
    (read-only folder, a directory in the way) is an :class:`InputError` naming ``path``;
    errors raised inside the ``with`` block propagate unchanged.
    """
    path = Path(path)
    if not path.parent.exists():
        raise InputError(f"{path}: expected an existing output folder, got none at {path.parent}")
    if path.is_dir():  # refused before the caller does any work
        raise InputError(f"{path}: expected a writable file, got a directory")
    suf = suffix if suffix is not None else "".join(path.suffixes)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suf}", dir=path.parent)
    except OSError as exc:
        raise _unwritable(path, exc) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        # mkstemp creates 0600; a written file should get the usual permissions (umask applied).
        os.chmod(tmp_path, 0o666 & ~_umask())
        yield tmp_path
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise
    try:
        os.replace(tmp_path, path)
    except OSError as exc:
        tmp_path.unlink(missing_ok=True)
        raise _unwritable(path, exc) from None


def _unwritable(path: Path, exc: OSError) -> InputError:
    return InputError(f"{path}: expected a writable file, got {exc.strerror or exc}")


def _umask() -> int:
    """The process umask, read without changing it where possible.

    Setting and restoring it (the portable way) would briefly give files created by other threads
    (the editor's server saves from a worker thread) world-writable permissions.
    """
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def keyword_options(func: F) -> F:
    """Make an unknown keyword option fail with the list of the ones that exist.

    Python's own message ("unexpected keyword argument") does not say what is allowed.
    """
    sig = inspect.signature(func)
    known = [
        n
        for n, p in sig.parameters.items()
        if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and not n.startswith("_")
    ]

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        unknown = [k for k in kwargs if k not in sig.parameters]
        if unknown:
            raise TypeError(
                f"{func.__name__}() got unknown option(s) {', '.join(map(repr, unknown))}; "
                f"options are: {', '.join(known)}"
            )
        return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def available_memory() -> int:
    """Bytes this process may use: ``PARTSCALE_MAX_MEMORY`` if set, else MemAvailable."""
    env = os.environ.get("PARTSCALE_MAX_MEMORY")
    if env:
        return int(float(env))
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 8 << 30


def format_bytes(n: float) -> str:
    """``1536 -> '1.5 KiB'``; beyond exbibytes in scientific notation (absurd requests)."""
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if abs(n) < 1024 or unit == "EiB":
            break
        n /= 1024
    if unit == "B":
        return f"{int(n)} B"
    return f"{n:.1f} {unit}" if abs(n) < 1e4 else f"{n:.2e} {unit}"


def _format_shape(shape: tuple[int, ...]) -> str:
    # a mistyped size (--to 1e300) would otherwise print hundreds of digits
    return "x".join(str(s) if s < 10**7 else f"{float(s):.2e}" for s in shape)


def check_memory(shape: tuple[int, ...], bytes_per_voxel: float, *, what: str) -> None:
    """Refuse a grid whose working set would not fit, saying how much it would need.

    Parameters
    ----------
    shape : tuple of int
        Grid shape (X, Y, Z).
    bytes_per_voxel : float
        Peak working bytes per voxel of the operation (all temporaries counted).
    what : str
        The request, for the message (e.g. ``"import at --res 2048"``).
    """
    n = 1
    for s in shape:
        n *= int(s)
    need = n * bytes_per_voxel
    have = available_memory()
    if need > have:
        raise MemoryLimitError(
            f"{what}: a {_format_shape(shape)} grid would need {format_bytes(need)} "
            f"of memory, only {format_bytes(have)} is available"
        )


def read_json(path: Path, *, what: str):
    """Parse a JSON file, or raise :class:`InputError` naming the file (missing, not JSON)."""
    if not path.is_file():
        raise InputError(f"{path}: expected {what}, got no such file")
    try:
        return json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: expected JSON ({what}), got {exc}") from None


_POOL: ThreadPoolExecutor | None = None


def thread_map(fn: Callable, items: Iterable) -> list:
    """``[fn(x) for x in items]`` on a thread per core, results in the order of ``items``.

    For work that releases the GIL (qhull, KD-tree searches, ``nogil`` numba kernels). One pool
    serves the whole process; ``fn`` must not call :func:`thread_map` itself (the pool could be
    waiting on its own workers).
    """
    global _POOL
    items = list(items)
    if len(items) < 2 or (os.cpu_count() or 1) < 2:
        return [fn(x) for x in items]
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=os.cpu_count(), thread_name_prefix="partscale")
    return list(_POOL.map(fn, items))


class Workers:
    """What :func:`worker_pool` yields: ``map`` a batch, or ``submit`` items one at a time and
    take results with ``next_done`` as they finish.

    Each worker process talks to this one over its own pipe, so a batch of a few items costs a
    pipe round trip each, not an executor's queues and threads (about 0.2 ms against 0.8 ms
    per batch of four). A worker gets its next item only once it has sent its last result: with
    two in flight, both sides could block writing to a full pipe (a large mask one way, its
    pieces the other).
    """

    def __init__(self, worker: Callable | None = None, conns: list | None = None):
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
            self._done.append((ticket, [self._worker(x) for x in chunk]))
        else:
            self._todo.append((ticket, chunk))
            self._dispatch()
        return ticket

    def next_done(self) -> tuple[int, object]:
        """(ticket, result) of a finished item, waiting for one; re-raises a worker's error."""
        ticket, results = self._next_chunk()
        return ticket, results[0]

    def _next_chunk(self) -> tuple[int, list]:
        if self._done:
            return self._done.popleft()
        busy = [c for c, n in self._busy.items() if n]
        if not busy:
            raise RuntimeError("next_done: nothing was submitted")
        conn = mp_connection.wait(busy)[0]
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
        out = {}
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
