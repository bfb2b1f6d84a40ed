"""The local engine: worker processes on this machine, forked from one template, watched by the
batch.

One template process (:mod:`partscale.batch._worker`) imports the pipeline once, while the batch
reads and hashes its inputs; workers fork from it in milliseconds. With more than two workers,
the first forks at once, and while it starts on the largest object the template runs a tiny
object through the batch's stages, so that the kernels are loaded (or compiled, once per
machine) before the other workers fork from it: two loads instead of one per worker. Each
worker starts its first object before the next one forks. A worker left idle once nothing is
pending is told to stop; a worker exits at once, without tearing its interpreter down, so the
end waits for no worker after another.

The scheduler sends the largest objects first (voxels, then input bytes), one task at a time to
each idle worker, with threads for that task from the cores not in use: every worker runs one
thread while there are more objects than workers, the last objects get the cores their
finished neighbours left (up to one thread per :data:`VOXELS_PER_THREAD` voxels). The next tasks
go out before the status table records what started and ended, so no worker waits for the
table's writes. It watches every busy worker: a worker past ``timeout`` seconds or above
``memory`` bytes resident is killed, its object recorded failed with one line, and a new worker
takes its place; so is one that dies on its own.
"""

from __future__ import annotations

import collections
import contextlib
import os
import signal
import subprocess
import sys
import tempfile
import time
import weakref
from collections.abc import Callable, Sequence
from multiprocessing import Pipe
from multiprocessing import connection as mp_connection
from multiprocessing.reduction import send_handle
from pathlib import Path
from typing import Any, cast

from .job import Spec, Task, thread_env
from .job import stages as job_stages

POLL_SECONDS = 0.1
START_FAILURES = 3
"""Templates that die before they are ready, in a row, before the batch gives up."""
VOXELS_PER_THREAD = 1 << 21
"""An object gets at most one thread per this many voxels of its grid (128³ voxels: one)."""
WARM_RES = 24
WARM_FROM = 3
"""Workers from which the template loads the kernels once before forking all but the first:
fewer load them each, side by side (the same wall time, and no warm-up object to run)."""
"""Grid size of the tiny object the template runs to load the kernels."""

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


class _Template:
    """The process the workers fork from (see :mod:`partscale.batch._worker`)."""

    def __init__(self, env: dict[str, str], stages: Sequence[str]):
        here, there = Pipe()
        self.conn = here
        # its output goes here until the batch's log is known (:meth:`attach_log`)
        self.early = tempfile.TemporaryFile()
        self.copied = 0
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "partscale.batch._worker",
                str(there.fileno()),
                str(os.getpid()),
                *stages,
            ],
            env=env,
            pass_fds=(there.fileno(),),
            stdin=subprocess.DEVNULL,
            stdout=self.early,
            stderr=self.early,
        )
        there.close()
        self.stages = set(stages)
        self.warming = self.warm = False
        self.log: Path | None = None
        # dropped unused (the batch refused its inputs), it is stopped and its file closed
        self._end = weakref.finalize(self, _end_template, self.proc, self.conn, self.early)

    def attach_log(self, log: Path) -> None:
        """Send the template's output, and its workers', to ``log`` from now on."""
        self.log = log
        self._copy_early()
        with contextlib.suppress(OSError):
            self.conn.send(("log", str(log)))

    def _copy_early(self) -> None:
        if self.log is None:
            return
        self.early.seek(self.copied)
        text = self.early.read()
        self.copied += len(text)
        if text:
            with open(self.log, "ab") as fh:
                fh.write(text)

    def wait_ready(self) -> bool:
        """Wait for the template to have imported the pipeline; False if it died first."""
        try:
            return bool(self.conn.recv() == "ready")
        except (EOFError, OSError):
            self.proc.wait()
            self._copy_early()  # what it said as it died
            return False

    def _reply(self) -> Any:
        """The next reply, taking the warm-up's (which may come first) on the way."""
        while True:
            try:
                reply = self.conn.recv()
            except (EOFError, OSError):
                raise RuntimeError(
                    f"the batch's worker template died ({_died(_status(self.proc.wait()))})"
                ) from None
            if reply != "warm":
                return reply
            self.warming, self.warm = False, True

    def poll_warm(self) -> None:
        """Take the warm-up's reply, waiting on the pipe (nothing else comes unasked)."""
        try:
            self.conn.recv()
        except (EOFError, OSError):
            raise RuntimeError(
                f"the batch's worker template died ({_died(_status(self.proc.wait()))})"
            ) from None
        self.warming, self.warm = False, True

    def fork(self) -> tuple[int, mp_connection.Connection]:
        """A new worker: its pid and our end of its pipe."""
        here, there = Pipe()
        self.conn.send(("fork", None))
        send_handle(self.conn, there.fileno(), self.proc.pid)
        there.close()
        return int(self._reply()), here

    def import_stages(self, stages: Sequence[str]) -> None:
        """Have it import ``stages`` too (a manifest row asked for more), before the next fork."""
        more = [s for s in stages if s not in self.stages]
        if more:
            self.conn.send(("import", more))
            self.stages.update(more)

    def start_warm(self, task: Task) -> None:
        self.conn.send(("warm", task))
        self.warming = True

    def reap(self, pid: int) -> int | None:
        """The wait status of worker ``pid`` once it has ended."""
        self.conn.send(("reap", pid))
        return cast("int | None", self._reply())

    def stop(self) -> None:
        """Stop it once its workers have been told to stop (it waits for them)."""
        with contextlib.suppress(OSError):
            self.conn.send(None)
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
        self._end()

    def kill(self) -> None:
        self._end()


def _end_template(proc: subprocess.Popen, conn: mp_connection.Connection, early: Any) -> None:
    with contextlib.suppress(OSError):
        proc.kill()
    proc.wait()
    conn.close()
    early.close()


class _Worker:
    def __init__(self, template: _Template):
        self.pid, self.conn = template.fork()
        self.dead = self.gone = False
        self.task: Task | None = None
        self.threads = 0
        self.started = 0.0
        self.peak = 0

    def send(self, task: Task, threads: int) -> None:
        self.task, self.threads, self.started, self.peak = task, threads, time.monotonic(), 0
        self.conn.send({**task, "threads": threads})

    def done(self, outcome: Result) -> tuple[Task, Result]:
        """Its task ended with ``outcome``: the task, and the outcome with its peak memory."""
        task, self.task, self.threads = self.task, None, 0
        assert task is not None  # a worker sends an outcome only for a task
        outcome["peak_memory"] = max(outcome.get("peak_memory", 0), self.peak)
        return task, outcome

    def kill(self, template: _Template) -> int | None:
        self.dead = True
        with contextlib.suppress(OSError):
            os.kill(self.pid, signal.SIGKILL)
        self.conn.close()
        return template.reap(self.pid)


def _status(returncode: int | None) -> int | None:
    """A wait status from a :class:`subprocess.Popen` return code (negative: a signal)."""
    if returncode is None:
        return None
    return -returncode if returncode < 0 else returncode << 8


def _died(status: int | None) -> str:
    if status is not None and os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        how = f"killed by signal {sig}" + (" (out of memory?)" if sig == 9 else "")
    else:
        how = f"exit code {os.WEXITSTATUS(status) if status is not None else 'unknown'}"
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


def _template_env(threads: int, memory: int | None) -> dict[str, str]:
    env = worker_env(threads, memory)
    # numba may use every core (each task sets its own count); its OpenMP and TBB layers do not
    # survive a fork, its workqueue layer does
    env["NUMBA_NUM_THREADS"] = str(os.cpu_count() or 1)
    env["NUMBA_THREADING_LAYER"] = "workqueue"
    return env


def task_size(task: Task) -> tuple[int, int]:
    """What orders the tasks, largest first: the grid's voxels, then the input's bytes."""
    res = int(task["spec"].get("res", 128))
    try:
        size = Path(task["path"]).stat().st_size
    except OSError:
        size = 0
    return res**3, size


def _threads_for(task: Task, free: int, idle: int, pending: int, base: int) -> int:
    """Threads for ``task``: the cores not in use shared by the tasks that can start now."""
    share = free // max(1, min(idle, pending))
    cap = max(1, task_size(task)[0] // VOXELS_PER_THREAD)
    return max(1, base, min(share, cap))


def _warm_task(task: Task) -> Task:
    """``task``'s stages on the shipped table at :data:`WARM_RES` voxels (the template's warm-up)."""
    from ..data import table

    spec: Spec = {**task["spec"], "res": WARM_RES, "fit": None}
    return {**task, "name": "warm", "path": str(table()), "spec": spec}


def start_template(threads: int, memory: int | None, stages: Sequence[str]) -> _Template:
    """Start the process the workers fork from; it imports the pipeline's ``stages`` (see
    :func:`~partscale.batch.job.stages`) while the batch reads its inputs. Pass it to
    :func:`run_local` (dropped unused, it exits when its pipe closes).
    """
    return _Template(_template_env(threads, memory), stages)


def _ready_template(
    template: _Template | None, env: dict[str, str], log: Path, stages: Sequence[str]
) -> _Template:
    """``template`` (or a new one) once it has imported ``stages``; a few tries."""
    status: int | None = None
    for _ in range(START_FAILURES):
        template = template or _Template(env, stages)
        template.attach_log(log)
        if template.wait_ready():
            template.import_stages(stages)
            return template
        status, template = _status(template.proc.returncode), None
    raise RuntimeError(f"batch workers fail to start ({_died(status)}); see {log}")


def _check(w: _Worker, timeout: float | None, memory: int | None, now: float) -> str | None:
    """Why worker ``w`` must be stopped or is gone (None: it is fine)."""
    if w.gone:
        return "died"
    if w.task is None:
        return None
    rss = resident_memory(w.pid)
    w.peak = max(w.peak, rss)
    if memory is not None and rss > memory:
        return (
            f"worker exceeded the memory limit of {memory / 2**20:.0f} MiB "
            f"({rss / 2**20:.0f} MiB resident) and was stopped"
        )
    if timeout is not None and now - w.started > timeout:
        return f"timed out after {timeout:g} s and was stopped"
    return None


class _Clock:
    """The phases of a run: start-up, object phase, end; and the objects' CPU seconds."""

    def __init__(self) -> None:
        self.t0 = time.perf_counter()
        self.first = self.last = self.cpu = 0.0

    def started(self) -> None:
        """Tasks started: the object phase begins (at the first)."""
        self.first = self.first or time.perf_counter()

    def finished(self, outcome: Result) -> None:
        """Count a task's CPU seconds (taken out of its outcome)."""
        self.cpu += float(outcome.pop("cpu_seconds", 0.0))

    def recorded(self) -> None:
        """A task's end is recorded: the object phase lasts at least until now."""
        self.last = time.perf_counter()

    def figures(self) -> dict[str, float]:
        first = self.first or self.t0
        last = max(self.last, first)
        return {
            "startup_seconds": first - self.t0,
            "objects_seconds": last - first,
            "end_seconds": time.perf_counter() - last,
            "objects_cpu_seconds": self.cpu,
        }


class _Pool:
    """The workers forked from ``template``: forked and given tasks, read, watched, stopped."""

    def __init__(
        self,
        template: _Template,
        size: int,
        threads: int,
        timeout: float | None,
        memory: int | None,
    ):
        self.template, self.size, self.threads = template, size, threads
        self.timeout, self.memory = timeout, memory
        self.cores = os.cpu_count() or 1
        self.workers: list[_Worker] = []
        self.retired: list[_Worker] = []

    def busy(self) -> bool:
        """Whether a worker has a task."""
        return any(w.task is not None for w in self.workers)

    def fill(self, pending: collections.deque[Task]) -> list[Task]:
        """Send pending tasks, largest first, to the idle workers, then to workers forked one at
        a time (each starts its task before the next is forked); the tasks started.

        The first worker forks at once; from :data:`WARM_FROM` workers, the others once the
        template has loaded the kernels (up to then they would load them side by side, at no
        more cost). Once nothing is pending, the idle workers are told to stop.
        """
        template = self.template
        self.workers = [w for w in self.workers if not w.dead]
        warm_first = self.size >= WARM_FROM and not template.warm
        room = (1 if warm_first else self.size) - len(self.workers)
        idle = [w for w in self.workers if w.task is None]
        busy = sum(w.threads for w in self.workers)
        started = []
        while pending and (idle or room > 0):
            if idle:
                w = idle.pop(0)
            else:
                w, room = _Worker(template), room - 1
                self.workers.append(w)
            task = pending.popleft()
            can_start = len(idle) + max(room, 0) + 1  # this worker, the idle, the ones to fork
            k = _threads_for(task, self.cores - busy, can_start, len(pending) + 1, self.threads)
            w.send(task, k)
            busy += k
            started.append(task)
        if warm_first and not template.warming and pending:
            template.start_warm(_warm_task(pending[0]))
        if not pending:
            self._retire_idle()
        return started

    def _retire_idle(self) -> None:
        """Tell the idle workers to stop now that nothing is pending: they exit while the last
        objects run, so the end does not wait for them.
        """
        for w in [w for w in self.workers if w.task is None and not w.dead]:
            with contextlib.suppress(OSError):
                w.conn.send(None)
            self.workers.remove(w)
            self.retired.append(w)

    def collect(self) -> list[tuple[Task, Result]]:
        """The tasks that ended (waiting up to :data:`POLL_SECONDS` while any runs), then the
        ones stopped for their time or memory, or whose worker died.
        """
        wait = POLL_SECONDS if self.busy() or self.template.warming else 0.0
        conns: dict[Any, _Worker | None] = {w.conn: w for w in self.workers}
        conns[self.template.conn] = None
        ended: list[tuple[Task, Result]] = []
        for conn in mp_connection.wait(list(conns), timeout=wait):
            who = conns[conn]
            if who is None:
                self.template.poll_warm()
                continue
            try:
                msg = cast(mp_connection.Connection, conn).recv()
            except (EOFError, OSError):
                who.gone = True  # its death is handled below
                continue
            if msg != "ready":
                ended.append(who.done(msg))
        return ended + self._watch()

    def _watch(self) -> list[tuple[Task, Result]]:
        """Stop the workers past their time or memory, replace the dead; their tasks failed."""
        now = time.monotonic()
        ended = []
        for w in self.workers:
            error = _check(w, self.timeout, self.memory, now)
            if error is None:
                continue
            status = w.kill(self.template)
            if w.task is not None:
                error = _died(status) if error == "died" else error
                ended.append(w.done(_failed(w, error)))
        return ended

    def stop(self) -> None:
        """Tell every worker to stop; a worker exits at once, without tearing its interpreter
        down, and the template waits for them all.
        """
        for w in self.workers:
            with contextlib.suppress(OSError):
                w.conn.send(None)
        self.template.stop()
        for w in self.workers + self.retired:
            w.conn.close()

    def kill(self) -> None:
        """Kill every worker and the template (the batch was interrupted or failed)."""
        for w in self.workers + self.retired:
            with contextlib.suppress(OSError):
                os.kill(w.pid, signal.SIGKILL)
        self.template.kill()


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
    template: _Template | None = None,
) -> dict[str, float]:
    """Run ``tasks`` on ``workers`` processes; ``on_start``/``on_finish`` as each starts and ends.

    Every task gets exactly one ``on_finish`` unless the batch is interrupted
    (KeyboardInterrupt propagates after the workers are killed; the caller marks what was
    running). Raises RuntimeError when workers cannot start at all (see ``log``).
    ``template``: one :func:`start_template` started early (else one is started here). The
    next tasks are sent before the callbacks record what started and ended, so no worker
    waits for the status table.

    Returns
    -------
    dict
        ``startup_seconds`` (until the first object starts), ``objects_seconds`` (first object
        started to last finished), ``end_seconds`` (the rest: stopping the workers) and
        ``objects_cpu_seconds`` (CPU time of the objects' jobs).
    """
    clock = _Clock()
    pending = collections.deque(sorted(tasks, key=task_size, reverse=True))
    if not pending:
        if template is not None:
            template.kill()
        return {}
    stages = list(dict.fromkeys(s for t in pending for s in job_stages(t["spec"])))
    template = _ready_template(template, _template_env(threads, memory), log, stages)
    pool = _Pool(template, min(workers, len(pending)), threads, timeout, memory)
    try:
        while pending or pool.busy():
            ended = pool.collect()
            started = pool.fill(pending)
            if started:
                clock.started()
            for task in started:
                on_start(task)
            for task, outcome in ended:
                clock.finished(outcome)
                on_finish(task, outcome)
                clock.recorded()
    except BaseException:
        pool.kill()
        raise
    pool.stop()
    return clock.figures()


def _failed(w: _Worker, error: str) -> Result:
    assert w.task is not None
    return {
        "name": w.task["name"],
        "ok": False,
        "outputs": [],
        "error": error,
        "seconds": time.monotonic() - w.started,
        "peak_memory": w.peak,
    }
