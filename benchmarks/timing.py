"""The benchmarks' CPU timers and repeat helpers (one copy for every benchmark).

``cpu_self``: CPU seconds of this process (``time.process_time``, user + system);
``cpu_children``: of its finished child processes (``RUSAGE_CHILDREN``, e.g. AUTO's
executables or a forked peer); ``cpu_total``: both. ``median_time`` and ``min_time``
repeat a call after one untimed warm-up.
"""

from __future__ import annotations

import math
import resource
import statistics
import time
from collections.abc import Callable
from typing import Any


def cpu_self() -> float:
    """CPU seconds (user + system) of this process."""
    return time.process_time()


def cpu_children() -> float:
    """CPU seconds (user + system) of this process's finished children."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_total() -> float:
    """CPU seconds (user + system) of this process and its finished children."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    return me.ru_utime + me.ru_stime + cpu_children()


def median_time(fn: Callable[[], Any], repeats: int) -> tuple[float, float, Any]:
    """``(median CPU s, median wall s, result)`` of ``fn`` after one untimed warm-up."""
    out = fn()  # warm-up (and the result)
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = cpu_self(), time.perf_counter()
        fn()
        cpu.append(cpu_self() - c0)
        wall.append(time.perf_counter() - w0)
    return statistics.median(cpu), statistics.median(wall), out


def min_time(fn: Callable[[], Any], repeats: int = 5) -> float:
    """Least CPU s of ``repeats`` runs of ``fn`` after one warm-up (the least time is the
    least disturbed by other load)."""
    fn()
    best = math.inf
    for _ in range(repeats):
        c0 = cpu_self()
        fn()
        best = min(best, cpu_self() - c0)
    return best


__all__ = ["cpu_children", "cpu_self", "cpu_total", "median_time", "min_time"]
