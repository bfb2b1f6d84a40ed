"""The memory guard: refuse a grid whose working set would not fit, before any work is done."""

from __future__ import annotations

import os

from .errors import MemoryLimitError


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
