"""The local engine: a pool of worker processes on this machine, watched by the batch.

Each worker is a fresh interpreter (:mod:`partscale.batch._worker`) started with numba, BLAS and
OpenMP capped at its share of the cores, so ``N`` workers never run more threads than there are
cores. The batch sends one task at a time to each idle worker and watches every busy one: a
worker past ``timeout`` seconds or above ``memory`` bytes resident is killed, its object recorded
failed with one line, and a new worker takes its place; so is one that dies on its own.
"""

from __future__ import annotations

import collections
import contextlib
import os
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from multiprocessing import Pipe
from multiprocessing import connection as mp_connection
from pathlib import Path
from typing import Any, cast

from .job import thread_env

POLL_SECONDS = 0.1
START_FAILURES = 3
"""Workers that die before they are ready, in a row, before the batch gives up."""

Task = dict[str, Any]
Result = dict[str, Any]


def resident_memory(pid: int) -> int:
    """Resident memory of process ``pid`` in bytes (0 where unknown)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        pass
    return 0


class _Worker:
    def __init__(self, env: dict[str, str], threads: int, log: Path):
        here, there = Pipe()
        self.conn = here
        with open(log, "ab") as fh:
            self.proc = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "partscale.batch._worker",
                    str(there.fileno()),
                    str(threads),
                    str(os.getpid()),
                ],
                env=env,
                pass_fds=(there.fileno(),),
                stdin=subprocess.DEVNULL,
                stdout=fh,
                stderr=fh,
            )
        there.close()
        self.ready = self.dead = False
        self.task: Task | None = None
        self.started = 0.0
        self.peak = 0

    def send(self, task: Task) -> None:
        self.task, self.started, self.peak = task, time.monotonic(), 0
        self.conn.send(task)

    def kill(self) -> None:
        self.dead = True
        with contextlib.suppress(OSError):
            self.proc.kill()
        self.proc.wait()
        self.conn.close()

    def stop(self) -> None:
        with contextlib.suppress(OSError):
            self.conn.send(None)
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.conn.close()


def _died(proc: subprocess.Popen) -> str:
    code = proc.poll()
    if code is not None and code < 0:
        how = f"killed by signal {-code}" + (" (out of memory?)" if -code == 9 else "")
    else:
        how = f"exit code {code}"
    return f"worker process died ({how})"


def worker_env(threads: int, memory: int | None) -> dict[str, str]:
    """The workers' environment: this one, thread caps, partscale importable, the memory guard."""
    import partscale

    env = dict(os.environ)
    env.update(thread_env(threads))
    src = str(Path(partscale.__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (src, env.get("PYTHONPATH")) if p)
    if memory is not None and "PARTSCALE_MAX_MEMORY" not in os.environ:
        # the pipeline's own guard refuses a grid that would not fit, before allocating it
        env["PARTSCALE_MAX_MEMORY"] = str(int(memory))
    return env


def run_local(
    tasks: Sequence[Task],
    *,
    workers: int,
    threads: int,
    timeout: float | None,
    memory: int | None,
    log: Path,
    on_start: Callable[[Task], None],
    on_finish: Callable[[Task, Result], None],
) -> None:
    """Run ``tasks`` on ``workers`` processes; ``on_start``/``on_finish`` as each starts and ends.

    Every task gets exactly one ``on_finish`` unless the batch is interrupted
    (KeyboardInterrupt propagates after the workers are killed; the caller marks what was
    running). Raises RuntimeError when workers cannot start at all (see ``log``).
    """
    pending = collections.deque(tasks)
    if not pending:
        return
    env = worker_env(threads, memory)
    pool = [_Worker(env, threads, log) for _ in range(min(workers, len(pending)))]
    start_failures = 0

    def fail(w: _Worker, error: str) -> None:
        task = w.task
        assert task is not None  # called only for a worker running a task
        result = {
            "name": task["name"],
            "ok": False,
            "outputs": [],
            "error": error,
            "seconds": time.monotonic() - w.started,
            "peak_memory": w.peak,
        }
        w.task = None
        on_finish(task, result)

    try:
        while pending or any(w.task is not None for w in pool):
            for w in pool:
                if w.ready and not w.dead and w.task is None and pending:
                    task = pending.popleft()
                    on_start(task)
                    w.send(task)
            live = {w.conn: w for w in pool if not w.dead}
            # wait() returns some of the objects it was given: our pipe ends
            ready = cast(
                list[mp_connection.Connection], mp_connection.wait(list(live), timeout=POLL_SECONDS)
            )
            for conn in ready:
                w = live[conn]
                try:
                    msg = conn.recv()
                except (EOFError, OSError):
                    continue  # its death is handled below
                if msg == "ready":
                    w.ready, start_failures = True, 0
                else:
                    finished, w.task = w.task, None
                    assert finished is not None  # a worker sends a result only for a task
                    msg["peak_memory"] = max(msg.get("peak_memory", 0), w.peak)
                    on_finish(finished, msg)
            now = time.monotonic()
            for i, w in enumerate(pool):
                if w.dead:
                    continue
                error = None
                if w.proc.poll() is not None:
                    error = _died(w.proc)
                    if not w.ready:
                        start_failures += 1
                        if start_failures >= START_FAILURES:
                            raise RuntimeError(
                                f"batch workers fail to start ({_died(w.proc)}); see {log}"
                            )
                elif w.task is not None:
                    rss = resident_memory(w.proc.pid)
                    w.peak = max(w.peak, rss)
                    if memory is not None and rss > memory:
                        error = (
                            f"worker exceeded the memory limit of {memory / 2**20:.0f} MiB "
                            f"({rss / 2**20:.0f} MiB resident) and was stopped"
                        )
                    elif timeout is not None and now - w.started > timeout:
                        error = f"timed out after {timeout:g} s and was stopped"
                if error is None:
                    continue
                w.kill()
                if w.task is not None:
                    fail(w, error)
                if pending:
                    pool[i] = _Worker(env, threads, log)
    except BaseException:
        for w in pool:
            w.kill()
        raise
    for w in pool:
        if not w.dead:
            w.stop()
