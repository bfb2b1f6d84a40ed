"""Timing helper shared by the benchmark scripts (bench/ is on sys.path when one is run)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")


def timed(fn: Callable[[], T], repeat: int) -> tuple[float, T]:
    """(median seconds of ``repeat`` calls of ``fn``, the last call's result)."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def timed_cpu(fn: Callable[[], object], repeat: int) -> tuple[float, float]:
    """(median wall seconds, median process CPU seconds) of the same ``repeat`` calls of ``fn``.

    CPU time beside wall time: other jobs share this machine's two cores, and a parallel
    kernel's CPU time exceeds its wall time.
    """
    wall, cpu = [], []
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return statistics.median(wall), statistics.median(cpu)
