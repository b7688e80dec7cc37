"""CAD contours from files: CSV polylines and the GOTO points of APT/CL programs.

Paper 000 derives its scan path and its theoretical contours from the engraving program's APT
file; plants also export contours as plain point lists. Both come in as a list of ``(n, 3)``
polylines (mm).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

Polyline = NDArray[np.float64]


def _cells_to_floats(cells: list[str], path: Path, line: int) -> list[float]:
    try:
        return [float(c) for c in cells]
    except ValueError:
        raise ValueError(f"{path}: line {line}: expected numbers, got {cells}") from None


def read_contours_csv(path: str | os.PathLike[str], delimiter: str = ",") -> list[Polyline]:
    """Read contours from a CSV file.

    Layouts (a header line is optional; it decides whether the first column is a contour id):

    - ``contour, x, y, z`` (4 columns, or a header naming ``contour`` first, also with
      ``contour, x, y``): one row per point, contours in order of first appearance;
    - ``x, y, z`` or ``x, y``: the whole file is one contour.

    Parameters
    ----------
    path : str or os.PathLike
    delimiter : str

    Returns
    -------
    list of ndarray (n, 3)
        z = 0 where the file has only x, y.
    """
    p = Path(path)
    rows: list[list[float]] = []
    header: list[str] = []
    with open(p, newline="") as fh:
        for k, cells in enumerate(csv.reader(fh, delimiter=delimiter), start=1):
            cells = [c.strip() for c in cells if c.strip() != ""]
            if not cells or cells[0].startswith("#"):
                continue
            if not rows and not header and not _is_number(cells[0]):
                header = [c.lower() for c in cells]
                continue
            rows.append(_cells_to_floats(cells, p, k))
    if not rows:
        raise ValueError(f"{p}: no points")
    width = len(rows[0])
    if any(len(r) != width for r in rows):
        bad = next(i for i, r in enumerate(rows) if len(r) != width)
        raise ValueError(f"{p}: row {bad + 1} has {len(rows[bad])} values, the first has {width}")
    a = np.array(rows, dtype=np.float64)
    # A contour id column: named in the header, or the first of 4 columns.
    has_id = (bool(header) and header[0] in ("contour", "id", "contour_id")) or (not header and width == 4)
    ids = a[:, 0] if has_id else np.zeros(len(a))
    xyz = a[:, 1:] if has_id else a
    if xyz.shape[1] == 2:
        xyz = np.column_stack([xyz, np.zeros(len(xyz))])
    if xyz.shape[1] != 3:
        raise ValueError(f"{p}: expected x, y[, z] with an optional contour id column first, got {width} columns")
    return _split_by_id(ids, xyz)


def _split_by_id(ids: NDArray[np.float64], pts: NDArray[np.float64]) -> list[Polyline]:
    _, first = np.unique(ids, return_index=True)
    return [pts[ids == ids[i]] for i in sorted(first)]


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def read_contours_apt(path: str | os.PathLike[str], split_distance: float = 5.0) -> list[Polyline]:
    """GOTO points of an APT/CL file as contours (the reader is :func:`machscan.io.read_toolpath`).

    A new contour starts after a ``RAPID`` statement or where consecutive GOTO points are more
    than ``split_distance`` mm apart. Only x, y, z of ``GOTO/x, y, z[, i, j, k]`` are kept.

    Parameters
    ----------
    path : str or os.PathLike
    split_distance : float
        Jump between GOTO points that starts a new contour, mm.
    """
    from machscan.io import read_toolpath

    tp = read_toolpath(path)  # refuses a file without a GOTO
    jumps = np.linalg.norm(np.diff(tp.points, axis=0), axis=1) > split_distance
    breaks = np.nonzero(jumps | (np.diff(tp.segments) != 0))[0] + 1
    return [c for c in np.split(tp.points, breaks) if len(c) > 0]


def read_contours(paths: Iterable[str | os.PathLike[str]]) -> list[Polyline]:
    """Contours from several files: ``.apt``/``.cl``/``.cls`` as APT, anything else as CSV."""
    out: list[Polyline] = []
    for path in paths:
        suffix = Path(path).suffix.lower()
        out += read_contours_apt(path) if suffix in (".apt", ".cl", ".cls", ".aptsource") else read_contours_csv(path)
    return out


def write_contours_csv(path: str | os.PathLike[str], contours: Iterable[Polyline]) -> None:
    """Write contours as ``contour, x, y, z`` rows (the layout :func:`read_contours_csv` reads)."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["contour", "x", "y", "z"])
        for k, c in enumerate(contours):
            for x, y, z in np.asarray(c, dtype=np.float64):
                w.writerow([k, repr(float(x)), repr(float(y)), repr(float(z))])
