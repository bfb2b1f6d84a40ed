"""A local batch worker process: ``python -m partscale.batch._worker FD THREADS PARENT_PID``.

Started by :mod:`partscale.batch.local` with the thread variables already in its environment
(numba and BLAS read them at import). It says ``"ready"`` once the pipeline is imported, then
runs one task per message until it gets ``None`` or its parent goes away.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
from multiprocessing.connection import Connection


def _die_with_parent(parent: int) -> None:
    # a SIGKILLed batch must not leave workers writing into OUTDIR while it is rerun
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the parent died before prctl
        os._exit(1)


def main() -> None:
    fd, threads, parent = (int(a) for a in sys.argv[1:4])
    _die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    from .job import execute, limit_threads

    limit_threads(threads)
    # import every stage now, so no object's time or timeout includes it
    from .. import edit, export, ingest, render, segment  # noqa: F401

    conn = Connection(fd)
    conn.send("ready")
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            break
        if task is None:
            break
        conn.send(execute(task))


if __name__ == "__main__":
    main()
