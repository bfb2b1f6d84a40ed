"""The local engine's process template: ``python -m partscale.batch._worker FD PARENT_PID [STAGE...]``.

Started once per batch by :mod:`partscale.batch.local` (numba's fork-safe ``workqueue`` threading
layer and the thread caps already in its environment), with the stages the batch uses as further
arguments (``ingest segment export``...). It imports them, says ``"ready"`` and then serves
requests on its pipe:

- ``("import", stages)``: import these stages too (a manifest row asked for them).
- ``("fork", None)`` followed by a pipe end (sent with ``send_handle``): fork a worker that runs
  tasks on that pipe; the reply is the worker's pid. A forked worker starts in milliseconds and
  shares the template's imported modules and loaded kernels.
- ``("warm", task)``: run ``task`` here (a tiny object through the batch's stages into a scratch
  folder), so the kernels it needs are loaded (or compiled, once per machine) before the workers
  that fork afterwards; the reply is ``"warm"``.
- ``("log", path)``: write this process's output, and its workers', to ``path`` (appended).
- ``("reap", pid)``: wait for that worker to end; the reply is its wait status.
- ``None`` (or the batch going away): reap every worker and exit.

A worker runs one task per message (``task["threads"]`` sets numba's and partscale's own thread
counts for it) until it gets ``None`` or the template goes away; it then exits at once, without
the interpreter's teardown.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
from multiprocessing.connection import Connection
from multiprocessing.reduction import recv_handle

STAGES = ("ingest", "segment", "edit", "zones", "export", "render")
"""The stages a job may import; the template imports those it is given (all by default)."""


def _die_with_parent(parent: int) -> None:
    # a SIGKILLed batch must not leave workers writing into OUTDIR while it is rerun
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the parent died before prctl
        os._exit(1)


def _set_threads(threads: int) -> None:
    """Numba's threads and partscale's pools (sized by ``os.cpu_count()``) for the next task.

    The thread variables stay as the template had them: numba rereads them whenever it
    compiles, and refuses a ``NUMBA_NUM_THREADS`` other than the one its threads started with.
    """
    import numba

    from .. import _workers

    most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    n = max(1, min(int(threads), most))
    if os.cpu_count() != n:
        os.cpu_count = lambda: n  # only in this worker process
        _workers.reset_pools()
    numba.set_num_threads(n)


def _serve_tasks(conn: Connection) -> None:  # pragma: no cover - in a forked worker
    from .job import execute

    conn.send("ready")
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            return
        if task is None:
            return
        _set_threads(task.get("threads", 1))
        conn.send(execute(task))


def _fork(ctl: Connection) -> None:
    fd = recv_handle(ctl)
    pid = os.fork()
    if pid:
        os.close(fd)
        ctl.send(pid)
        return
    try:  # pragma: no cover - the forked worker
        ctl.close()
        _die_with_parent(os.getppid())
        from .. import _workers

        _workers.reset_pools()  # the template's thread pool has no threads in this process
        _serve_tasks(Connection(fd))
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)


def _warm(task: dict) -> None:
    """Run ``task`` for the kernels it loads; its outcome does not matter."""
    import shutil
    import tempfile

    from .job import execute

    scratch = tempfile.mkdtemp(prefix="partscale-warm-")
    try:
        execute({**task, "outdir": scratch})
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _import(stages: list[str]) -> None:
    """Import the pipeline's ``stages`` (and the job), once, so no worker's start, object time
    or timeout includes it.
    """
    import importlib

    from . import job  # noqa: F401

    for stage in stages:
        if stage in STAGES:
            importlib.import_module(f"partscale.{stage}")


def main() -> None:
    fd, parent = (int(a) for a in sys.argv[1:3])
    _die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    _import(sys.argv[3:] or list(STAGES))

    ctl = Connection(fd)
    ctl.send("ready")
    while True:
        try:
            msg = ctl.recv()
        except (EOFError, OSError):
            break
        if msg is None:
            break
        kind, arg = msg
        if kind == "fork":
            _fork(ctl)
        elif kind == "import":
            _import(arg)
        elif kind == "warm":
            _warm(arg)
            ctl.send("warm")
        elif kind == "log":
            with open(arg, "ab") as fh:
                os.dup2(fh.fileno(), 1)
                os.dup2(fh.fileno(), 2)
        elif kind == "reap":
            try:
                ctl.send(os.waitpid(arg, 0)[1])
            except ChildProcessError:
                ctl.send(None)
    with contextlib.suppress(ChildProcessError):
        while True:
            os.wait()  # every worker: their CPU time then counts in the batch's own
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


if __name__ == "__main__":
    main()
