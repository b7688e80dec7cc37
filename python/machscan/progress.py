"""Progress bars for long calls: frames or files done, rate and time left, on stderr.

Through tqdm when it is installed (it comes with ``machscan[dask]``); without it, or when switched
off, a bar that does nothing. ``progress=None`` means: show it when stderr is a terminal, so logs and
pipes stay clean.
"""

from __future__ import annotations

import sys
from typing import Any

__all__ = ["bar", "wanted"]


class _Silent:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass

    def __enter__(self) -> _Silent:
        return self

    def __exit__(self, *exc: object) -> None:
        pass


def wanted(progress: bool | None) -> bool:
    """Whether to show a bar: as asked, or by default when stderr is a terminal."""
    if progress is None:
        return sys.stderr.isatty()
    if not isinstance(progress, bool):
        raise TypeError(f"progress: expected True, False or None, got {type(progress).__name__}")
    return progress


def bar(total: int, unit: str, progress: bool | None, description: str | None = None) -> Any:
    """A tqdm bar over ``total`` ``unit``s when :func:`wanted`, else one that does nothing."""
    if not wanted(progress):
        return _Silent()
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return _Silent()
    return tqdm(total=total, unit=unit, unit_scale=True, desc=description, file=sys.stderr, dynamic_ncols=True)
