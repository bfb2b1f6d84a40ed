"""The Ray engine: the same per-object job as Ray tasks, on a cluster or a local instance.

``address=None`` starts a local Ray instance for the batch (and stops it after); otherwise the
batch joins the cluster at ``address`` (``"auto"``, ``"ray://host:10001"``), whose nodes must
see the inputs and OUTDIR at the same paths (a shared file system). Each object is one task
with one CPU: Ray retries a task whose worker process dies (``retries`` times), never one whose
object failed (that is a result, recorded as such); at most ``workers`` run at once, so a task's
time (and ``timeout``) starts about when it is submitted. The thread caps and the memory guard
reach the workers through the task's runtime environment; Ray's own memory monitor stops a task
that would exhaust a node.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

from ..errors import InputError, one_line
from .job import Task, execute, limit_threads

INSTALL_HINT = "pip install 'partscale[ray]'"
OBJECT_STORE_BYTES = 128 << 20
"""Object store of a local instance: results are a few lines each."""


def require_ray():
    """The ``ray`` module, or :class:`InputError` saying how to install it."""
    try:
        import ray
    except ImportError:
        raise InputError(
            f"engine ray: expected Ray installed ({INSTALL_HINT}), got no module named ray"
        ) from None
    return ray


def _task(task: Task, threads: int) -> dict[str, Any]:
    limit_threads(threads)
    return execute(task)


def run_ray(
    tasks: Sequence[Task],
    *,
    workers: int | None,
    threads: int,
    timeout: float | None,
    env: dict[str, str],
    address: str | None,
    retries: int,
    on_start: Callable[[Task], None],
    on_finish: Callable[[Task, dict[str, Any]], None],
) -> dict[str, float]:
    """Run ``tasks`` as Ray tasks; callbacks as in :func:`partscale.batch.local.run_local`.

    Returns ``{"startup_seconds": ...}``: the time to start or join Ray.
    """
    import logging

    ray = require_ray()
    t0 = time.perf_counter()
    started_here = not ray.is_initialized()
    if started_here:
        kwargs: dict[str, Any] = {
            "include_dashboard": False,
            "log_to_driver": False,
            "logging_level": logging.ERROR,
            "runtime_env": {"env_vars": env},
        }
        if address is None:
            kwargs.update(num_cpus=workers, object_store_memory=OBJECT_STORE_BYTES)
        ray.init(address=address, **kwargs)
    startup = time.perf_counter() - t0
    inflight: dict[Any, tuple[Task, float]] = {}
    try:
        if workers is None:
            workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        remote = ray.remote(_task).options(num_cpus=1, max_retries=retries, retry_exceptions=False)
        pending = list(tasks)[::-1]
        while pending or inflight:
            while pending and len(inflight) < workers:
                task = pending.pop()
                on_start(task)
                inflight[remote.remote(task, threads)] = (task, time.monotonic())
            done, _ = ray.wait(list(inflight), num_returns=1, timeout=0.2)
            for ref in done:
                task, started = inflight.pop(ref)
                try:
                    outcome = ray.get(ref)
                except Exception as exc:  # the worker died past its retries, or was cancelled
                    outcome = _failed(task, started, f"{type(exc).__name__}: {one_line(exc)}")
                on_finish(task, outcome)
            if timeout is not None:
                now = time.monotonic()
                for ref, (task, started) in list(inflight.items()):
                    if now - started > timeout:
                        ray.cancel(ref, force=True)
                        del inflight[ref]
                        on_finish(
                            task,
                            _failed(
                                task, started, f"timed out after {timeout:g} s and was stopped"
                            ),
                        )
    except BaseException:
        for ref in inflight:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started_here:
            ray.shutdown()
    return {"startup_seconds": startup}


def _failed(task: Task, started: float, error: str) -> dict[str, Any]:
    # Ray's messages run over many lines with tracebacks: keep the first line
    return {
        "name": task["name"],
        "ok": False,
        "outputs": [],
        "error": error.split(" Traceback")[0][:500],
        "seconds": time.monotonic() - started,
        "peak_memory": 0,
    }
