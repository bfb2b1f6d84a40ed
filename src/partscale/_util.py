"""Small helpers shared by every stage: atomic writes, option checks, memory guards, threads."""

from __future__ import annotations

import colorsys
import contextlib
import functools
import inspect
import json
import os
import tempfile
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TypeVar

from .errors import InputError, MemoryLimitError

F = TypeVar("F", bound=Callable)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    Nothing half-written is ever left: on any exception the temporary file is removed and the
    destination is untouched. The temporary keeps ``path``'s suffix (or ``suffix``) so writers
    that infer the format from the name still work.
    """
    path = Path(path)
    if path.parent and not path.parent.exists():
        raise InputError(f"{path}: expected an existing output folder, got none at {path.parent}")
    suf = suffix if suffix is not None else "".join(path.suffixes)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{suf}", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    # mkstemp creates 0600; a written file should get the usual permissions (umask applied).
    os.chmod(tmp_path, 0o666 & ~_umask())
    try:
        yield tmp_path
        os.replace(tmp_path, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


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
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return f"{n:.1f} TiB"


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
            f"{what}: a {'x'.join(map(str, shape))} grid would need {format_bytes(need)} "
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


def palette_colour(i: int) -> list[int]:
    """sRGB display colour of part ``i``: golden-angle hues, alternating lightness, so parts
    with nearby indices look different."""
    h = (i * 0.618033988749895) % 1.0
    light = 0.55 if i % 2 == 0 else 0.42
    r, g, b = colorsys.hls_to_rgb(h, light, 0.65)
    return [round(r * 255), round(g * 255), round(b * 255)]


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
