"""The memory guard: refuse a grid whose working set would not fit, before any work is done."""

from __future__ import annotations

import math
import os

from .errors import MemoryLimitError


def available_memory() -> int:
    """Bytes this process may use: ``PARTSCALE_MAX_MEMORY`` if set (bytes, or a size such as
    ``500M`` or ``4GiB``), else MemAvailable, less where the process's address space is capped
    (``ulimit -v``, ``RLIMIT_AS``): the cap less what the process has mapped already.
    """
    env = os.environ.get("PARTSCALE_MAX_MEMORY")
    if env:
        from ._options import memory_size

        return memory_size(env, "PARTSCALE_MAX_MEMORY")
    have = _proc_field("/proc/meminfo", "MemAvailable:")
    have = 8 << 30 if have is None else have
    room = _address_space_room()
    return have if room is None else max(0, min(have, room))


def _proc_field(path: str, key: str) -> int | None:
    """A ``kB`` field of a /proc file in bytes (None where there is no /proc)."""
    try:
        with open(path) as f:
            for line in f:
                if line.startswith(key):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _address_space_room() -> int | None:
    """Bytes left under the address-space cap (RLIMIT_AS), or None where there is none."""
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, OSError, ValueError):
        return None
    if soft == resource.RLIM_INFINITY or soft < 0:
        return None
    mapped = _proc_field("/proc/self/status", "VmSize:")
    return soft - (mapped or 0)


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


def check_memory(
    shape: tuple[int, ...], bytes_per_voxel: float, *, what: str, params: tuple[str, ...] = ()
) -> None:
    """Refuse a grid whose working set would not fit, saying how much it would need.

    Parameters
    ----------
    shape : tuple of int
        Grid shape (X, Y, Z).
    bytes_per_voxel : float
        Peak working bytes per voxel of the operation (all temporaries counted).
    what : str
        The request, for the message (e.g. ``"chair.glb at res 2048"``).
    params : tuple of str
        The parameters ``what`` names (:attr:`partscale.errors.InputError.params`).
    """
    n = 1
    for s in shape:
        n *= int(s)
    check_bytes(n * bytes_per_voxel, what=f"{what}: a {_format_shape(shape)} grid", params=params)


def check_bytes(need: float, *, what: str, params: tuple[str, ...] = ()) -> None:
    """Refuse a request of ``need`` bytes that would not fit; ``what`` starts the message."""
    have = available_memory()
    if not need <= have:  # NaN and infinity too
        amount = f"{format_bytes(need)} of" if math.isfinite(need) else "unbounded"
        raise MemoryLimitError(
            f"{what} would need {amount} memory, only {format_bytes(have)} is available",
            params=params,
        )


#: Largest block glibc serves from (and keeps in) the heap once :func:`reuse_freed_memory` ran:
#: a 256³ grid's arrays (70 MB of distances) are reused; a 512³ one's (512 MB) still come from
#: and go back to the system, so the heap's fragments stay small beside them.
REUSE_BYTES = 256 << 20

# glibc's mallopt parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3


def reuse_freed_memory(limit: int = REUSE_BYTES) -> bool:
    """Keep the memory of freed arrays up to ``limit`` bytes for the next ones (glibc only).

    By default glibc hands every block over 32 MB straight back to the system when it is freed
    and maps fresh pages for the next: the kernel then faults in and zeroes every page of each
    new grid. At 256³ that is most of an edit's time (the bookcase tile: about 100 ms of page
    faults in 200). Serving such blocks from the heap and not trimming it lets the next edit
    reuse the pages. Called by the applications (the CLI, the benchmarks, and each batch job,
    which then releases them with :func:`release_freed_memory`), not on import: the process
    keeps its peak heap.

    Parameters
    ----------
    limit : int
        Freed blocks up to this many bytes stay in the heap for reuse.

    Returns
    -------
    bool
        Whether glibc accepted it (False elsewhere: nothing to tune).

    Examples
    --------
    >>> from partscale import reuse_freed_memory
    >>> isinstance(reuse_freed_memory(), bool)  # True with glibc
    True
    """
    import ctypes

    mallopt = _glibc("mallopt", ctypes.c_int, ctypes.c_int)
    if mallopt is None:
        return False  # not glibc (macOS, musl): nothing to tune
    ok = mallopt(_M_MMAP_THRESHOLD, int(limit)) and mallopt(_M_TRIM_THRESHOLD, int(limit))
    return bool(ok)


def release_freed_memory() -> bool:
    """Hand the heap's free pages back to the system (glibc's ``malloc_trim``; glibc only).

    The counterpart of :func:`reuse_freed_memory` for a process that runs one job after
    another (a batch worker): pages freed within a job are reused by it, and released at its
    end, so the next job's resident memory (and its measured peak) starts from what is really
    in use.

    Returns
    -------
    bool
        Whether glibc did it (False elsewhere).

    Examples
    --------
    >>> from partscale import release_freed_memory
    >>> isinstance(release_freed_memory(), bool)
    True
    """
    import ctypes

    trim = _glibc("malloc_trim", ctypes.c_size_t)
    if trim is None:
        return False
    trim(0)
    return True


def _glibc(name: str, *argtypes):
    """Glibc's function ``name`` with its argument types, or None where there is none (macOS,
    musl). Read from the process's own symbols: libc is loaded already (ctypes.util.find_library
    would run ldconfig, 30 ms at every start of the CLI).
    """
    import ctypes

    try:
        fn = getattr(ctypes.CDLL(None), name)
    except (OSError, AttributeError, TypeError):
        return None
    fn.argtypes = list(argtypes)
    return fn
