"""``partscale.batch.run``: the same pipeline over many objects, resumable, on all cores or Ray."""

from __future__ import annotations

import contextlib
import os
import signal
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import _schema
from .._memory import available_memory
from .._options import keyword_options
from ..errors import InputError, shown
from ..progress import ProgressCallback, resolve
from . import status as status_mod
from .inputs import discover, shard
from .job import options_hash, resolve_options

ENGINES = ("local", "ray")
MAX_TIMEOUT = 1e7
"""Most seconds one object may be given (about 115 days)."""
MAX_MEMORY = 1 << 50
"""Largest memory size a worker may be given (1024 TiB): beyond any machine."""


@dataclass
class BatchResult:
    """What a batch did; names are output folder names.

    Attributes
    ----------
    outdir, status : Path
        The output folder and its status table (:data:`STATUS_NAME`).
    done : list of str
        Objects run and written.
    failed : list of (str, str)
        Objects that failed, each with its one-line error.
    skipped : list of str
        Already done with the same input and options.
    not_retried : list of (str, str)
        Failed before with the same input and options (rerun with ``retry_failed=True``).
    interrupted : list of str
        Running when Ctrl-C or SIGTERM stopped the batch.
    seconds : float
        Wall time of the batch.
    slowest : list of (str, float)
        The slowest objects and their seconds.
    peak_memory : int
        The largest resident memory of one object's job, bytes.
    engine_info : dict
        Figures the engine reports: the local engine its start-up, object phase and end
        (``startup_seconds``, ``objects_seconds``, ``end_seconds``) and the objects' CPU
        seconds (``objects_cpu_seconds``); Ray its start-up (``startup_seconds``).

    Examples
    --------
    >>> from pathlib import Path
    >>> from partscale import batch
    >>> result = batch.BatchResult(Path("out"), Path("out/status.csv"), done=["table"])
    >>> result.ok, batch.BatchResult(Path("out"), Path("out/status.csv"), interrupted=["desk"]).ok
    (True, False)
    """

    outdir: Path
    status: Path
    done: list[str] = field(default_factory=list)
    failed: list[tuple[str, str]] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    not_retried: list[tuple[str, str]] = field(default_factory=list)
    interrupted: list[str] = field(default_factory=list)
    seconds: float = 0.0
    slowest: list[tuple[str, float]] = field(default_factory=list)
    peak_memory: int = 0
    engine_info: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when no object failed, was left failed or was interrupted."""
        return not self.failed and not self.not_retried and not self.interrupted


def parse_memory(value: str | int | None) -> int | None:
    """A memory size in bytes, from ``'2GiB'``, ``'500M'``, ``'1.5G'`` or a number of bytes.

    Parameters
    ----------
    value : str or int or None
        A number with an optional K, M, G or T (powers of 1024, with or without ``iB``/``B``),
        or bytes.

    Returns
    -------
    int or None
        Bytes; None stays None.

    Raises
    ------
    partscale.errors.InputError
        For anything else, or a size that is not above 0.

    Examples
    --------
    >>> from partscale import batch
    >>> batch.parse_memory("2GiB"), batch.parse_memory("500M"), batch.parse_memory(None)
    (2147483648, 524288000, None)
    >>> batch.parse_memory("lots")
    Traceback (most recent call last):
    ...
    partscale.errors.InputError: memory: expected a size such as 4GiB or 500MiB, got 'lots'
    """
    if value is None:
        return None
    s = str(value)[:64].strip().lower().removesuffix("b").removesuffix("i")
    mult = {"k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}.get(s[-1:], 1)
    try:
        if isinstance(value, int | float) and not isinstance(value, bool):
            n = _schema.number(value, "memory")
        else:
            n = _schema.number(s[:-1] if mult > 1 else s, "memory", text=True) * mult
    except InputError:
        n = -1.0
    if not n > 0:
        raise InputError(f"memory: expected a size such as 4GiB or 500MiB, got {shown(value)}")
    if n > MAX_MEMORY:
        raise InputError(f"memory: expected at most {MAX_MEMORY >> 40} TiB, got {shown(value)}")
    return int(n)


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM (a scheduler's stop) ends the batch like Ctrl-C: a consistent table."""

    def handler(signum, frame):
        raise KeyboardInterrupt

    try:
        old = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


@keyword_options
def run(
    inputs: Sequence[str | os.PathLike],
    outdir: str | os.PathLike,
    *,
    res: int = 128,
    square: bool = False,
    segment: str | None = None,
    recipe: str | os.PathLike | dict | None = None,
    fit: Sequence[str] | None = None,
    allow_deform: bool = False,
    export: Sequence[str] | str = ("csdf",),
    render: str | None = None,
    engine: str = "local",
    workers: int | None = None,
    timeout: float | None = None,
    memory: str | int | None = None,
    address: str | None = None,
    retries: int = 1,
    rank: int = 0,
    world_size: int = 1,
    retry_failed: bool = False,
    progress: ProgressCallback | None = None,
) -> BatchResult:
    """Run the pipeline on every object of ``inputs``, each into ``outdir/<name>/``.

    Progress and each object's state go to ``outdir/status.csv`` as the batch runs.

    Parameters
    ----------
    inputs : sequence of path
        Files, folders (searched recursively) and ``.csv``/``.jsonl`` manifests; see
        :func:`partscale.batch.discover`.
    outdir : path
        Output folder (created). Rerunning into it skips objects done with the same input
        (content hash of all its files) and options (hash of the spec).
    res, square, segment, recipe, fit, allow_deform, export, render
        The pipeline per object, overridable per object in a manifest: import at ``res`` (a
        mesh turned square about up with ``square``, see :func:`partscale.ingest.load`),
        segment with method ``segment`` (None: no segmentation), then the recipe (a JSON file
        or dict) or ``fit`` (3 sizes, :func:`partscale.zones.fit`; refused where only a
        deformation reaches them unless ``allow_deform``), then write each format of
        ``export`` (``csdf``, ``glb``, ``ply``, ``obj``, ``raw``, ``png``, ``nrrd``) and, with
        ``render`` (a view), a 512² PNG.
    engine : {"local", "ray"}
        Worker processes on this machine, or Ray tasks.
    workers : int, optional
        Processes at once (default: the cores; Ray: the cluster's CPUs).
    timeout : float, optional
        Seconds one object may take; past it its worker is stopped and it is recorded failed.
    memory : size, optional
        Resident memory one worker may use (default: available memory / workers); above it the
        worker is stopped (local engine) and the object recorded failed. Also the pipeline's
        own guard (``PARTSCALE_MAX_MEMORY``, unless set) so a grid that would not fit is
        refused before it is allocated.
    address : str, optional
        Ray cluster to join (``engine="ray"``); default: a local instance for this batch.
    retries : int
        Ray's retries of a task whose worker process died.
    rank, world_size : int
        Run only shard ``rank`` of ``world_size`` (every ``world_size``-th input from ``rank``
        of the sorted list): shards partition the inputs exactly.
    retry_failed : bool
        Rerun objects that failed before with the same input and options.
    progress : callable(fraction, message), optional
        ``fraction`` = objects finished / objects to run.

    Returns
    -------
    BatchResult
        What was done, failed, skipped or interrupted.

    Examples
    --------
    Two objects imported at 32 voxels and written as GLB (a worker process starts: a few
    seconds); run again, both are skipped as done.

    >>> import shutil
    >>> from pathlib import Path
    >>> from partscale import batch, data
    >>> Path("objects").mkdir()
    >>> for name in ("table.glb", "desk.glb"):
    ...     _ = shutil.copy(data.table(), Path("objects") / name)
    >>> result = batch.run(["objects"], "out", res=32, export=["glb"], workers=1)
    >>> result.done, result.ok, sorted(p.name for p in Path("out/table").iterdir())
    (['desk', 'table'], True, ['table.glb'])
    >>> batch.run(["objects"], "out", res=32, export=["glb"], workers=1).skipped
    ['desk', 'table']
    """
    t0 = time.perf_counter()
    if engine not in ENGINES:
        raise InputError(f"engine: expected one of {', '.join(ENGINES)}, got {engine!r}")
    if engine == "ray":
        from .ray_engine import require_ray

        require_ray()
    elif address is not None:
        raise InputError(
            f"address: expected only with engine ray, got it with {engine}", params=("engine",)
        )
    cores = os.cpu_count() or 1
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise InputError(f"workers: expected an integer >= 1, got {workers!r}")
    if timeout is not None:
        _schema.number(timeout, "timeout", lo=0, hi=MAX_TIMEOUT, lo_open=True)
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise InputError(f"retries: expected an integer >= 0, got {retries!r}")
    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise InputError(f"{outdir}: expected an output folder, got a file")
    n_workers = workers or cores
    threads = max(1, cores // n_workers)
    mem = parse_memory(memory)
    if mem is None:
        mem = available_memory() // n_workers
    template = None
    if engine == "local":
        from .local import start_template

        # it imports the pipeline while this process reads and hashes the inputs
        template = start_template(threads, mem)
    batch_opts = {
        "res": res,
        "square": square or None,
        "segment": segment,
        "recipe": recipe,
        "fit": fit,
        "allow_deform": allow_deform or None,
        "export": export,
        "render": render,
    }
    batch_opts = {k: v for k, v in batch_opts.items() if v is not None}
    resolve_options(batch_opts, {}, where="batch")  # the batch's own options, checked once
    items = shard(discover(inputs, exclude=outdir), rank, world_size)
    specs = {it.name: resolve_options(batch_opts, it.options, where=f"{it.path}") for it in items}
    outdir.mkdir(parents=True, exist_ok=True)

    table = status_mod.StatusTable(outdir)
    result = BatchResult(outdir=outdir, status=table.path)
    tasks = []
    for it in items:
        spec = specs[it.name]
        ih, oh = it.content_hash(), options_hash(spec)
        prev = table.previous.get(it.name)
        same = prev is not None and prev["input_hash"] == ih and prev["options_hash"] == oh
        if (
            same
            and prev is not None
            and prev["state"] == "done"
            and all((outdir / o).is_file() for o in prev["outputs"].split(";") if o)
        ):
            result.skipped.append(it.name)
            continue
        if same and prev is not None and prev["state"] == "failed" and not retry_failed:
            result.not_retried.append((it.name, prev["error"]))
            continue
        tasks.append(
            {
                "name": it.name,
                "path": str(it.path),
                "spec": spec,
                "outdir": str(outdir.resolve()),
                "input_hash": ih,
                "options_hash": oh,
                "attempts": int(prev["attempts"] or 0) + 1 if prev else 1,  # checked on read
            }
        )

    report = resolve(progress)
    total = len(tasks)
    finished = 0
    running: set[str] = set()
    report(0.0, f"{total} to run, {len(result.skipped)} already done")

    def on_start(task: dict[str, Any]) -> None:
        running.add(task["name"])
        table.update(
            task["name"],
            input=task["path"],
            state="running",
            seconds="",
            error="",
            input_hash=task["input_hash"],
            options_hash=task["options_hash"],
            outputs="",
            peak_memory_mib="",
            started=status_mod.now(),
            finished="",
            attempts=task["attempts"],
        )

    def on_finish(task: dict[str, Any], res_: dict[str, Any]) -> None:
        nonlocal finished
        running.discard(task["name"])
        finished += 1
        ok = bool(res_["ok"])
        table.update(
            task["name"],
            state="done" if ok else "failed",
            seconds=f"{res_['seconds']:.3f}",
            error=res_["error"],
            outputs=";".join(res_["outputs"]),
            peak_memory_mib=f"{res_['peak_memory'] / 2**20:.1f}" if res_["peak_memory"] else "",
            finished=status_mod.now(),
        )
        if ok:
            result.done.append(task["name"])
        else:
            result.failed.append((task["name"], res_["error"]))
        result.slowest.append((task["name"], float(res_["seconds"])))
        result.peak_memory = max(result.peak_memory, int(res_["peak_memory"] or 0))
        word = "done" if ok else "failed"
        report(finished / max(total, 1), f"{word} {task['name']}")

    try:
        with _sigterm_as_interrupt():
            if engine == "local":
                from .local import run_local

                result.engine_info = run_local(
                    tasks,
                    workers=n_workers,
                    threads=threads,
                    timeout=timeout,
                    memory=mem,
                    log=outdir / status_mod.LOG_NAME,
                    on_start=on_start,
                    on_finish=on_finish,
                    template=template,
                )
            else:
                from .local import worker_env
                from .ray_engine import run_ray

                env = worker_env(threads, mem)
                env = {k: v for k, v in env.items() if k not in os.environ or os.environ[k] != v}
                result.engine_info = run_ray(
                    tasks,
                    workers=workers,
                    threads=threads,
                    timeout=timeout,
                    env=env,
                    address=address,
                    retries=retries,
                    on_start=on_start,
                    on_finish=on_finish,
                )
    except KeyboardInterrupt:
        for name in sorted(running):
            table.update(name, state="interrupted", finished=status_mod.now())
            result.interrupted.append(name)
    result.slowest.sort(key=lambda x: -x[1])
    result.seconds = time.perf_counter() - t0
    return result
