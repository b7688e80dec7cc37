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

__all__ = ["Polyline", "read_contours", "read_contours_apt", "read_contours_csv", "write_contours_csv"]

Polyline = NDArray[np.float64]


def read_contours_csv(path: str | os.PathLike[str], *, delimiter: str = ",") -> list[Polyline]:
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
    from machscan.io import read_table

    p = Path(path)
    table = read_table(p, delimiter=delimiter, widths=(2, 3, 4), nan_columns=(), name="path")
    if table.values.shape[0] == 0:
        raise ValueError(f"{p}: no points")
    a, width = table.values, table.values.shape[1]
    header = [c.lower() for c in table.header or ()]
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


def read_contours_apt(path: str | os.PathLike[str], *, split_distance: float = 5.0) -> list[Polyline]:
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
