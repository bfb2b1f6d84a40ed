"""``partscale.batch.run``: the same pipeline over many objects, resumable, on all cores or Ray."""

from __future__ import annotations

import contextlib
import os
import signal
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._memory import available_memory
from .._options import count, keyword_options, memory_size, seconds
from ..errors import InputError
from ..progress import ProgressCallback, resolve
from . import status as status_mod
from .inputs import Input, discover, shard
from .job import Spec, Task, batch_spec, object_spec, options_hash, stages

ENGINES = ("local", "ray")


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
    return None if value is None else memory_size(value, "memory")


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


@dataclass(frozen=True)
class Engine:
    """The engine a batch runs on, its options checked (:func:`check_engine`).

    Attributes
    ----------
    name : {"local", "ray"}
    workers : int or None
        Processes at once as asked (None: the cores, or Ray's CPUs).
    processes : int
        Processes at once on this machine (``workers`` or the cores).
    threads : int
        Threads per process: the cores shared by the processes.
    timeout : float or None
        Seconds one object may take.
    memory : int
        Resident bytes one process may use.
    address : str or None
        Ray cluster to join.
    retries : int
        Ray's retries of a task whose worker died.
    """

    name: str
    workers: int | None
    processes: int
    threads: int
    timeout: float | None
    memory: int
    address: str | None = None
    retries: int = 1


def check_outdir(outdir: str | os.PathLike) -> Path:
    """The output folder as a path, refused where a file is in its place (nothing made yet)."""
    path = Path(outdir)
    if path.exists() and not path.is_dir():
        raise InputError(f"{path}: expected an output folder, got a file")
    return path


def check_engine(
    engine: str,
    workers: int | None,
    timeout: float | None,
    memory: str | int | None,
    address: str | None,
    retries: int,
) -> Engine:
    """The engine's options checked once (:mod:`partscale._options`), the workers sized.

    Raises :class:`InputError` for a bad value, for Ray not installed (engine ray) or for an
    address without engine ray.

    Examples
    --------
    >>> from partscale.batch.api import check_engine
    >>> eng = check_engine("local", 2, 60, "1GiB", None, 1)
    >>> eng.processes, eng.timeout, eng.memory
    (2, 60.0, 1073741824)
    """
    if engine not in ENGINES:
        raise InputError(f"engine: expected one of {', '.join(ENGINES)}, got {engine!r}")
    if engine == "ray":
        from .ray_engine import require_ray

        require_ray()
    elif address is not None:
        raise InputError(
            f"address: expected only with engine ray, got it with {engine}", params=("engine",)
        )
    if workers is not None:
        workers = count(workers, "workers")
    if timeout is not None:
        timeout = seconds(timeout, "timeout")
    retries = count(retries, "retries", lo=0)
    cores = os.cpu_count() or 1
    processes = workers or cores
    mem = parse_memory(memory)
    return Engine(
        name=engine,
        workers=workers,
        processes=processes,
        threads=max(1, cores // processes),
        timeout=timeout,
        memory=mem if mem is not None else available_memory() // processes,
        address=address,
        retries=retries,
    )


def _start_template(eng: Engine, options: dict[str, Any]) -> Any:
    """The local engine's worker template, started now (None for Ray), importing the stages
    the batch's ``options`` (as given) use.
    """
    if eng.name != "local":
        return None
    from .local import start_template

    return start_template(eng.threads, eng.memory, stages(options))


def read_inputs(
    inputs: Sequence[str | os.PathLike],
    outdir: Path,
    spec: Spec,
    *,
    rank: int = 0,
    world_size: int = 1,
) -> list[tuple[Input, Spec]]:
    """The inputs of this shard (:func:`discover`, :func:`shard`), each with its checked spec.

    ``spec`` is the batch's (:func:`~partscale.batch.job.batch_spec`); a manifest row's own
    options are laid over it (:func:`~partscale.batch.job.object_spec`). ``outdir`` is never
    read as an input.
    """
    items = shard(discover(inputs, exclude=outdir), rank, world_size)
    return [(it, object_spec(spec, it.options, where=f"{it.path}")) for it in items]


@dataclass
class Plan:
    """What a batch runs (:func:`plan`): its tasks, and the objects it leaves as they are.

    Attributes
    ----------
    tasks : list of dict
        One per object to run (``name``, ``path``, ``spec``, ``outdir``, ``input_hash``,
        ``options_hash``, ``attempts``).
    skipped : list of str
        Done before with the same input and options, outputs present.
    not_retried : list of (str, str)
        Failed before with the same input and options, and their errors.
    """

    tasks: list[Task] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    not_retried: list[tuple[str, str]] = field(default_factory=list)


def plan(
    objects: Sequence[tuple[Input, Spec]],
    outdir: Path,
    previous: dict[str, dict[str, str]],
    *,
    retry_failed: bool = False,
) -> Plan:
    """Compare each object's input and options hashes with its ``previous`` status row.

    An object done before with the same hashes and its outputs present is skipped; one failed
    before with the same hashes is left (unless ``retry_failed``); every other one is a task.
    """
    out = Plan()
    for it, spec in objects:
        ih, oh = it.content_hash(), options_hash(spec)
        prev = previous.get(it.name)
        same = prev is not None and prev["input_hash"] == ih and prev["options_hash"] == oh
        if same and prev is not None and prev["state"] == "done" and _outputs_present(outdir, prev):
            out.skipped.append(it.name)
        elif same and prev is not None and prev["state"] == "failed" and not retry_failed:
            out.not_retried.append((it.name, prev["error"]))
        else:
            out.tasks.append(
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
    return out


def _outputs_present(outdir: Path, row: dict[str, str]) -> bool:
    return all((outdir / o).is_file() for o in row["outputs"].split(";") if o)


class Recorder:
    """Each object's start and end into the status table, the result and the progress callback.

    ``on_start`` and ``on_finish`` are the engines' callbacks; :meth:`interrupted` marks the
    objects still running when the batch was stopped.
    """

    def __init__(
        self,
        table: status_mod.StatusTable,
        result: BatchResult,
        report: Callable[[float, str], None],
        *,
        total: int,
    ):
        self.table, self.result, self.report, self.total = table, result, report, total
        self.finished = 0
        self.running: set[str] = set()

    def on_start(self, task: Task) -> None:
        """Task ``task`` started: its row says running."""
        self.running.add(task["name"])
        self.table.update(
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

    def on_finish(self, task: Task, outcome: dict[str, Any]) -> None:
        """Task ``task`` ended with ``outcome`` (:func:`~partscale.batch.job.execute`'s dict)."""
        name, ok, result = task["name"], bool(outcome["ok"]), self.result
        self.running.discard(name)
        self.finished += 1
        peak = int(outcome["peak_memory"] or 0)
        self.table.update(
            name,
            state="done" if ok else "failed",
            seconds=f"{outcome['seconds']:.3f}",
            error=outcome["error"],
            outputs=";".join(outcome["outputs"]),
            peak_memory_mib=f"{peak / 2**20:.1f}" if peak else "",
            finished=status_mod.now(),
        )
        if ok:
            result.done.append(name)
        else:
            result.failed.append((name, outcome["error"]))
        result.slowest.append((name, float(outcome["seconds"])))
        result.peak_memory = max(result.peak_memory, peak)
        word = "done" if ok else "failed"
        self.report(self.finished / max(self.total, 1), f"objects: {word} {name}")

    def interrupted(self) -> None:
        """Mark the objects still running as interrupted (Ctrl-C or SIGTERM)."""
        for name in sorted(self.running):
            self.table.update(name, state="interrupted", finished=status_mod.now())
            self.result.interrupted.append(name)


def run_engine(
    tasks: list[Task], eng: Engine, outdir: Path, recorder: Recorder, template: Any = None
) -> dict[str, float]:
    """Run ``tasks`` on the engine; what it reports (see :attr:`BatchResult.engine_info`)."""
    if eng.name == "local":
        from .local import run_local

        return run_local(
            tasks,
            workers=eng.processes,
            threads=eng.threads,
            timeout=eng.timeout,
            memory=eng.memory,
            log=outdir / status_mod.LOG_NAME,
            on_start=recorder.on_start,
            on_finish=recorder.on_finish,
            template=template,
        )
    from .local import worker_env
    from .ray_engine import run_ray

    env = worker_env(eng.threads, eng.memory)
    env = {k: v for k, v in env.items() if k not in os.environ or os.environ[k] != v}
    return run_ray(
        tasks,
        workers=eng.workers,
        threads=eng.threads,
        timeout=eng.timeout,
        env=env,
        address=eng.address,
        retries=eng.retries,
        on_start=recorder.on_start,
        on_finish=recorder.on_finish,
    )


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
        ``fraction`` = objects finished / objects to run; ``message`` starts with the step's
        name: ``options``, ``inputs`` (reading and hashing), ``plan`` (``"plan: N to run, M
        already done"``), ``objects`` (``"objects: done NAME"`` as each ends), ``end``.

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
    report = resolve(progress)
    report(0.0, "options: checking")
    outdir = check_outdir(outdir)
    eng = check_engine(engine, workers, timeout, memory, address, retries)
    # the local engine's template imports the pipeline while this process reads the inputs
    options = {
        "res": res,
        "square": square,
        "segment": segment,
        "recipe": recipe,
        "fit": fit,
        "allow_deform": allow_deform,
        "export": export,
        "render": render,
    }
    template = _start_template(eng, options)
    try:
        spec = batch_spec(options)
        report(0.0, "inputs: reading and hashing")
        objects = read_inputs(inputs, outdir, spec, rank=rank, world_size=world_size)
    except BaseException:
        if template is not None:
            template.kill()
        raise
    outdir.mkdir(parents=True, exist_ok=True)
    table = status_mod.StatusTable(outdir)
    todo = plan(objects, outdir, table.previous, retry_failed=retry_failed)
    result = BatchResult(
        outdir=outdir, status=table.path, skipped=todo.skipped, not_retried=todo.not_retried
    )
    report(0.0, f"plan: {len(todo.tasks)} to run, {len(todo.skipped)} already done")
    recorder = Recorder(table, result, report, total=len(todo.tasks))
    try:
        with _sigterm_as_interrupt():
            result.engine_info = run_engine(todo.tasks, eng, outdir, recorder, template)
    except KeyboardInterrupt:
        recorder.interrupted()
    result.slowest.sort(key=lambda x: -x[1])
    result.seconds = time.perf_counter() - t0
    report(1.0, f"end: {len(result.done)} done, {len(result.failed)} failed")
    return result
