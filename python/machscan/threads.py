"""How many threads machscan's kernels use.

Every kernel runs in parallel on all cores by default, with the GIL released, and its result does
not depend on the thread count. Where something else already runs calls side by side — Dask
workers, a thread pool of your own — each call should use only its share of the cores, or the
machine is oversubscribed (workers × threads > cores) and everything slows down. :func:`thread_limit`
sets that share for the calls made from the current thread.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from machscan import _core

__all__ = ["thread_limit"]


@contextmanager
def thread_limit(threads: int | None) -> Iterator[None]:
    """Run the kernels called from this thread on ``threads`` threads within the ``with`` block.

    The limit belongs to the calling thread (other threads keep theirs) and the previous one is
    restored on leaving the block, also on an exception. ``machscan.dask`` wraps each task in it.

    Parameters
    ----------
    threads : int or None
        Threads per call, ≥ 1; None: all cores (the default outside any block).

    Examples
    --------
    >>> import numpy as np, machscan
    >>> with machscan.thread_limit(1):
    ...     c = machscan.voxel_downsample(np.random.default_rng(0).random((1000, 3)), 0.1)
    """
    if threads is None:
        n = 0
    else:
        if isinstance(threads, bool) or not isinstance(threads, int):
            raise TypeError(f"threads: expected an int or None, got {type(threads).__name__}")
        if threads < 1:
            raise ValueError(f"threads: must be >= 1 (or None for all cores), got {threads}")
        n = threads
    previous = _core.set_thread_limit(n)
    try:
        yield
    finally:
        _core.set_thread_limit(previous)
