"""Timing shared by the benchmarks. The host is shared and noisy: a figure is the fastest of
several runs (the least disturbed one), and speed is compared as a ratio side by side in one
run, never as an absolute time."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any


def timed(fn: Callable[[], Any], repeat: int = 3) -> tuple[float, float, Any]:
    """Calls `fn` `repeat` times: (fastest seconds, median seconds, the last call's result)."""
    times = []
    out = None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), statistics.median(times), out


def best_time(fn: Callable[[], Any], repeat: int = 3) -> float:
    """The fastest of `repeat` calls of `fn`, seconds."""
    return timed(fn, repeat)[0]
