"""Point cloud files: PLY (ASCII, binary little/big endian; any scalar properties; faces),
PCD (ascii, binary, binary_compressed), and XYZ/CSV text. Readers and writers are in Rust;
these functions are their Python face.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core


@dataclass(frozen=True, repr=False)
class CloudFile:
    """What a point file holds.

    Attributes
    ----------
    points : ndarray (N, 3)
        float64 coordinates as stored (PLY float32 coordinates are widened exactly).
    normals : ndarray (N, 3) or None
        PLY nx, ny, nz or PCD normal_x, normal_y, normal_z.
    scalars : dict of str to ndarray (N,)
        Every other per-point property by name (curvature, intensity, allowance, ...).
    triangles : ndarray of int64 (T, 3)
        PLY faces, polygons fanned into triangles; empty for clouds.
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64] | None
    scalars: dict[str, NDArray[np.float64]]
    triangles: NDArray[np.int64]

    def __repr__(self) -> str:
        extra = ", normals" if self.normals is not None else ""
        extra += f", scalars {sorted(self.scalars)}" if self.scalars else ""
        extra += f", {len(self.triangles)} triangles" if len(self.triangles) else ""
        return f"CloudFile({len(self.points)} points{extra})"


def read(path: str | os.PathLike[str], *, delimiter: str | None = None, columns: tuple[int, int, int] = (0, 1, 2)) -> CloudFile:
    """Read a point file, choosing the reader by the extension.

    ``.ply``, ``.pcd``, ``.las``/``.laz`` (through laspy, an optional dependency), and text
    files ``.xyz``, ``.csv``, ``.txt``, ``.pts``, ``.asc`` (one point per line; ``columns`` picks x, y, z, 0-based; ``delimiter`` None splits on
    whitespace and commas; header lines are skipped).

    Bad files raise ``ValueError`` naming the file and what is wrong (truncated data, a header
    that promises more than there is, an unknown property type, a bad LZF stream); a file that
    cannot be opened raises ``OSError``.

    Examples
    --------
    >>> cloud = machscan.io.read("scan.pcd")
    >>> cloud.points.shape, cloud.scalars.keys()
    """
    if os.fspath(path).lower().endswith((".las", ".laz")):
        return _read_las(path)
    return CloudFile(**_core.read_cloud(path, delimiter, tuple(columns)))


def _read_las(path: str | os.PathLike[str]) -> CloudFile:
    """LAS/LAZ through laspy (optional: ``pip install laspy``; LAZ also needs ``lazrs``).
    Coordinates are the scaled ones (x·scale + offset); every other dimension is a scalar."""
    try:
        import laspy
    except ImportError:
        raise ImportError("reading LAS needs laspy: pip install laspy (and lazrs for .laz)") from None
    try:
        las = laspy.read(os.fspath(path))
    except Exception as e:  # laspy raises its own error types for bad files
        raise ValueError(f"{os.fspath(path)}: not a readable LAS file ({e})") from None
    pts = np.column_stack([np.asarray(las.x, dtype=np.float64), np.asarray(las.y, dtype=np.float64), np.asarray(las.z, dtype=np.float64)])
    scalars = {}
    for name in las.point_format.dimension_names:
        if name.lower() in ("x", "y", "z"):
            continue
        scalars[name] = np.asarray(las[name], dtype=np.float64)
    return CloudFile(points=pts, normals=None, scalars=scalars, triangles=np.zeros((0, 3), dtype=np.int64))


def read_points(path: str | os.PathLike[str]) -> NDArray[np.float64]:
    """The ``(N, 3)`` float64 points of any supported point file (see :func:`read`).

    Examples
    --------
    >>> pts = machscan.read_points("bunny.pcd")
    """
    return read(path).points


def write_points(
    path: str | os.PathLike[str],
    points: ArrayLike,
    normals: ArrayLike | None = None,
    binary: bool = True,
    *,
    scalars: dict[str, ArrayLike] | None = None,
    compressed: bool = False,
) -> None:
    """Write points (mm), optional normals and named scalars; the format follows the extension.

    ``.ply`` and ``.pcd``: coordinates, normals and scalars as ``double`` so machine coordinates
    keep full precision; binary (little-endian) by default, ASCII with ``binary=False``
    (shortest round-trip text); ``compressed=True`` writes PCD ``binary_compressed``.
    ``.xyz``/``.csv``/``.txt``/``.pts``: x, y, z per line only.

    Examples
    --------
    >>> machscan.write_points("cloud.ply", pts, scalars={"allowance": a})
    """
    _core.write_points(path, points, normals, scalars, binary, compressed)


write = write_points


@dataclass(frozen=True, repr=False)
class Toolpath:
    """An APT/CL toolpath.

    Attributes
    ----------
    points : ndarray (N, 3)
        GOTO points, mm.
    axes : ndarray (N, 3)
        Tool axes (i, j, k) where the GOTO gave them, NaN otherwise.
    feeds : ndarray (N,)
        Feed in force at each point (NaN before the first FEDRAT).
    segments : ndarray of int64 (N,)
        Segment of each point; a new segment starts after every RAPID.
    """

    points: NDArray[np.float64]
    axes: NDArray[np.float64]
    feeds: NDArray[np.float64]
    segments: NDArray[np.int64]

    def __repr__(self) -> str:
        n_seg = int(self.segments.max()) + 1 if len(self.segments) else 0
        return f"Toolpath({len(self.points)} points in {n_seg} segments)"


def read_toolpath(path: str | os.PathLike[str]) -> Toolpath:
    """Read an APT/CL file: ``GOTO/x, y, z[, i, j, k]`` points, ``FEDRAT`` feeds, segments split
    at ``RAPID``; ``$`` continues a statement, ``$$`` starts a comment, other statements are
    skipped. Errors name the file and line.

    Examples
    --------
    >>> tp = machscan.io.read_toolpath("engraving.apt")
    """
    return Toolpath(**_core.read_toolpath(path))


def write_toolpath(
    path: str | os.PathLike[str],
    points: ArrayLike,
    axes: ArrayLike | None = None,
    feeds: ArrayLike | None = None,
    segments: ArrayLike | None = None,
) -> None:
    """Write an APT/CL toolpath: ``GOTO/x,y,z[,i,j,k]`` per point (shortest round-trip numbers),
    ``FEDRAT`` whenever the feed changes, ``RAPID`` between segments.

    Examples
    --------
    >>> machscan.io.write_toolpath("path.cl", pts, axes=normals, feeds=f)
    """
    _core.write_toolpath(path, points, axes, feeds, segments)
