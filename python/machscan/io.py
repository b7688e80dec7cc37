"""Point cloud, mesh and toolpath files.

Formats, by extension (:data:`READ_FORMATS`, :data:`WRITE_FORMATS`):

- ``.ply`` — ASCII and binary little/big-endian; any scalar vertex properties; faces.
- ``.pcd`` — ``ascii``, ``binary`` and ``binary_compressed`` (PCL).
- ``.stl`` — binary and ASCII; corners with equal coordinates become one vertex.
- ``.obj`` — ``v``, ``vn`` and ``f`` (any of ``v``, ``v/vt``, ``v//vn``, ``v/vt/vn``).
- ``.xyz``, ``.csv``, ``.txt``, ``.pts``, ``.asc`` — text, one point per line. A ``.txt`` whose
  first line is ``n_vertices n_faces`` is the mesh text format of the geodesic test meshes
  (pygeodesic): that many ``x y z`` lines, then that many lines of three 0-based vertex indices.
- ``.las``, ``.laz`` — LAS 1.0–1.4 and its LASzip compression: the coordinates as stored
  (X·scale + offset), every point field as a scalar named as laspy names it, the extra bytes by
  their names; written as LAS 1.4 (point format 6, or 7 with ``red``, ``green``, ``blue``).

- ``.e57`` — ASTM E2807: every scan, poses applied, Cartesian or spherical, in mm (E57 stores
  metres); invalid points dropped and counted (``CloudFile.dropped``); written as one scan.

Line-profiler exports (LMI Gocator CSV, Keyence height rows) come in as a :class:`machscan.Scan`
through :func:`read_profiles`.

CAD solids (``.step``/``.stp``, ``.iges``/``.igs``) come in through :func:`read_cad` as a mesh within
a chordal tolerance, each triangle keeping its B-rep face (``machscan[cad]``).

PLY, PCD, LAS/LAZ and E57 files are read by their signature whatever their extension (a LAZ file
named ``.las`` reads as LAZ).

Readers and writers are in Rust; this module is their Python face. Files machscan writes with
the default options open in Open3D (legacy and tensor readers), PCL and trimesh: PLY, PCD and
STL hold float32 values by default, as those libraries write them (``dtype="float64"`` keeps
full precision in PLY, PCD and the text formats).

Errors: a file that cannot be opened raises the ``OSError`` of its cause
(``FileNotFoundError``, ``PermissionError``, ``IsADirectoryError``, ...); a file whose content
is not what its format says raises :class:`FileFormatError` (a ``ValueError``) naming the file;
bad arguments raise ``ValueError`` naming the argument.

The formats and their papers: ``docs/clouds.md``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan.cad import CadMesh, read_cad
from machscan.scan import read_profiles

__all__ = [
    "READ_FORMATS",
    "WRITE_FORMATS",
    "CadMesh",
    "CloudFile",
    "FileFormatError",
    "Table",
    "Toolpath",
    "TriangleMesh",
    "read",
    "read_cad",
    "read_mesh",
    "read_points",
    "read_profiles",
    "read_table",
    "read_toolpath",
    "write_mesh",
    "write_points",
    "write_toolpath",
]

#: A file's content does not follow its format (a ``ValueError``; ``.filename`` names the file).
FileFormatError = _core.FileFormatError

#: Extensions :func:`read` reads.
READ_FORMATS: tuple[str, ...] = tuple(_core.readable_formats())
#: Extensions :func:`write_points` and :func:`write_mesh` write.
WRITE_FORMATS: tuple[str, ...] = tuple(_core.writable_formats())

Dtype = Literal["float32", "float64"]


@dataclass(frozen=True, eq=False, repr=False)
class CloudFile:
    """What a point or mesh file holds.

    Attributes
    ----------
    points : ndarray (N, 3)
        float64 coordinates as stored (float32 values are widened exactly).
    normals : ndarray (N, 3) or None
        PLY nx, ny, nz; PCD normal_x, normal_y, normal_z; OBJ vn given per vertex.
    scalars : dict of str to ndarray (N,)
        Every other per-point property by name (curvature, intensity, allowance, ...).
    triangles : ndarray of int64 (T, 3)
        Faces, polygons fanned into triangles; empty for clouds.
    dropped : int
        Points the file marks invalid (E57), left out of ``points``.
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64] | None
    scalars: dict[str, NDArray[np.float64]]
    triangles: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    dropped: int = 0

    def __len__(self) -> int:
        return len(self.points)

    def select(self, index: ArrayLike) -> CloudFile:
        """The points picked by ``index`` (kept indices from a filter, or a boolean mask) with
        their normals and scalars; triangles whose three vertices are all kept, renumbered.

        Examples
        --------
        >>> cloud = machscan.io.read("scan.ply")
        >>> clean = cloud.select(machscan.remove_statistical_outliers(cloud.points, 20, 2.0))
        """
        idx = np.asarray(index)
        if idx.dtype == bool:
            if idx.shape != (len(self.points),):
                raise ValueError(f"index: expected a boolean mask of shape ({len(self.points)},), got {idx.shape}")
            idx = np.flatnonzero(idx)
        elif idx.dtype.kind not in "iu":
            raise ValueError(f"index: expected integer indices or a boolean mask, got dtype {idx.dtype}")
        idx = idx.astype(np.int64, copy=False)
        if idx.size and (idx.min() < -len(self.points) or idx.max() >= len(self.points)):
            raise ValueError(f"index: indices must lie in [0, {len(self.points)}), got {idx.min()}..{idx.max()}")
        idx = np.where(idx < 0, idx + len(self.points), idx)
        new_of_old = np.full(len(self.points), -1, dtype=np.int64)
        new_of_old[idx] = np.arange(len(idx))
        tri = new_of_old[self.triangles] if len(self.triangles) else self.triangles
        tri = tri[(tri >= 0).all(axis=1)] if len(tri) else tri
        return CloudFile(
            points=self.points[idx],
            normals=None if self.normals is None else self.normals[idx],
            scalars={k: v[idx] for k, v in self.scalars.items()},
            triangles=tri,
            dropped=self.dropped,
        )

    def __repr__(self) -> str:
        extra = ", normals" if self.normals is not None else ""
        extra += f", scalars {sorted(self.scalars)}" if self.scalars else ""
        extra += f", {len(self.triangles)} triangles" if len(self.triangles) else ""
        extra += f", {self.dropped} invalid dropped" if self.dropped else ""
        return f"CloudFile({len(self.points)} points{extra})"


@dataclass(frozen=True, eq=False, repr=False)
class TriangleMesh:
    """A triangle mesh: shared vertices and triangles of vertex indices.

    Attributes
    ----------
    vertices : ndarray (V, 3)
        mm.
    triangles : ndarray of int64 (T, 3)
        Vertex indices, counter-clockwise seen from outside (the right-hand rule gives the
        outward normal).
    normals : ndarray (V, 3) or None
        Vertex normals when the file has them.
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    normals: NDArray[np.float64] | None = None

    def __repr__(self) -> str:
        return f"TriangleMesh({len(self.vertices)} vertices, {len(self.triangles)} triangles)"


def read(
    path: str | os.PathLike[str],
    *,
    delimiter: str | None = None,
    columns: tuple[int, int, int] = (0, 1, 2),
    apply_pose: bool = True,
) -> CloudFile:
    """Read a point or mesh file, choosing the reader by its signature or extension (see the
    module).

    Parameters
    ----------
    path : str or os.PathLike
    delimiter : str, optional
        Text files: the cell separator; None splits on whitespace and commas. Header lines (a
        first cell that is not a number) are skipped.
    columns : (int, int, int)
        Text files: the 0-based columns of x, y, z.
    apply_pose : bool
        E57: put every scan in the file's frame by its pose (default); False leaves each in its
        own (the ``scan`` scalar tells them apart when there are several).

    Returns
    -------
    CloudFile
        ``points``, ``normals``, ``scalars``, ``triangles``.

    Raises
    ------
    FileNotFoundError, PermissionError, OSError
        The file cannot be opened.
    FileFormatError
        The content is not what the format says (truncated data, a header that promises more
        than there is, an unknown property type, a bad LZF stream), naming the file.
    ValueError
        An unknown extension (the message lists :data:`READ_FORMATS`).

    Examples
    --------
    >>> cloud = machscan.io.read("data/pcl-bunny-icp/bun0.pcd")
    >>> cloud.points.shape
    (397, 3)
    """
    cx, cy, cz = columns
    return CloudFile(**_core.read_cloud(path, delimiter=delimiter, columns=(cx, cy, cz), apply_pose=apply_pose))


def read_points(path: str | os.PathLike[str]) -> NDArray[np.float64]:
    """The ``(N, 3)`` float64 points of any supported file (see :func:`machscan.io.read`).

    Examples
    --------
    >>> pts = machscan.read_points("data/pcl-bunny-icp/bun0.pcd")
    """
    return read(path).points


def read_mesh(path: str | os.PathLike[str]) -> TriangleMesh:
    """A triangle mesh from a ``.ply``, ``.stl``, ``.obj`` or mesh ``.txt`` file.

    STL files hold a soup of triangles: corners with equal coordinates become one vertex, in
    order of first use (what trimesh does too). Raises :class:`FileFormatError` when the file
    has no faces.

    Examples
    --------
    >>> mesh = machscan.io.read_mesh("data/stanford-bunny-mesh/stanford_bunny.ply")
    >>> mesh.vertices.shape, mesh.triangles.shape
    """
    c = read(path)
    if len(c.triangles) == 0:
        err = FileFormatError(f"{os.fspath(path)}: holds no faces; read it with machscan.io.read as a point cloud")
        err.filename = os.fspath(path)  # type: ignore[attr-defined]  # set on the instance, as the core does
        raise err
    return TriangleMesh(vertices=c.points, triangles=c.triangles, normals=c.normals)


def write_points(
    path: str | os.PathLike[str],
    points: ArrayLike,
    normals: ArrayLike | None = None,
    *,
    scalars: dict[str, ArrayLike] | None = None,
    binary: bool | None = None,
    compressed: bool = False,
    dtype: Dtype | None = None,
    scale: float | None = None,
) -> None:
    """Write points (mm), optional normals and named scalars; the format follows the extension.

    Parameters
    ----------
    path : str or os.PathLike
        ``.ply``, ``.pcd``, ``.las``, ``.laz``, ``.e57``, or a text format (``.xyz``, ``.csv``, ``.txt``,
        ``.pts``, ``.asc``: x, y, z per line only).
    points : array_like, shape (N, 3)
    normals : array_like, shape (N, 3), optional
    scalars : dict of str to array_like (N,), optional
        Extra per-point fields, e.g. ``{"frame": frame_index}``; names are words (letters,
        digits, _) other than the fields machscan writes itself (x, y, z, nx, ny, nz,
        normal_x, normal_y, normal_z).
    binary : bool, optional
        PLY and PCD: binary little-endian (the default) or ASCII. Text formats refuse True,
        LAS refuses False.
    compressed : bool
        PCD only: ``binary_compressed`` (LZF). Refused for other formats (LAS is compressed by
        naming the file ``.laz``) and with ``binary=False``.
    dtype : {"float32", "float64"}, optional
        Number type of every field. Default float32 for PLY and PCD (what Open3D and PCL read
        everywhere; Open3D's legacy PCD reader reads 8-byte coordinates as zeros), full
        float64 precision for text; LAS/LAZ: the type of the extra bytes (default float64).
    scale : float, optional
        LAS/LAZ only: the step the coordinates are stored in, mm (default 0.0001, i.e. 0.1 µm;
        the offset is the whole mm below the cloud). A cloud spanning more than 2³¹ steps is
        refused. LAS point fields (``intensity``, ``classification``, ``gps_time``, ``red``,
        ...) given as scalars fill those fields and must fit them; other scalars and the
        normals (``normal_x/y/z``) become extra bytes.

    Examples
    --------
    >>> machscan.write_points("cloud.ply", pts, scalars={"allowance": a})
    >>> machscan.write_points("cloud.pcd", pts, compressed=True, dtype="float64")
    """
    _core.write_cloud(
        path, points, normals=normals, scalars=scalars, binary=binary, compressed=compressed, dtype=dtype, scale=scale
    )


def write_mesh(
    path: str | os.PathLike[str],
    vertices: ArrayLike,
    triangles: ArrayLike,
    *,
    normals: ArrayLike | None = None,
    binary: bool | None = None,
    dtype: Dtype | None = None,
) -> None:
    """Write a triangle mesh: ``.ply`` (vertices, optional vertex normals, faces), ``.stl``
    (binary by default or ASCII; facet normals from the right-hand rule; float32 only) or
    ``.obj`` (text; ``v``, ``vn``, ``f``).

    Parameters
    ----------
    path : str or os.PathLike
    vertices : array_like, shape (V, 3)
        mm.
    triangles : array_like of int, shape (T, 3)
        Vertex indices.
    normals : array_like, shape (V, 3), optional
        Vertex normals (PLY, OBJ).
    binary : bool, optional
        PLY and STL: binary (default) or ASCII.
    dtype : {"float32", "float64"}, optional
        Default float32 for PLY and STL, float64 for OBJ.

    Examples
    --------
    >>> machscan.io.write_mesh("part.stl", mesh.vertices, mesh.triangles)
    """
    _core.write_cloud(path, vertices, normals=normals, triangles=triangles, binary=binary, dtype=dtype)


write = write_points


@dataclass(frozen=True, eq=False, repr=False)
class Table:
    """A numeric table as :func:`read_table` reads it.

    Attributes
    ----------
    values : ndarray (R, C)
        The numbers, one row per data line.
    lines : ndarray of int64 (R,)
        The file's line (1-based) of each row, for messages.
    header : tuple of str or None
        The header's cells, when the file has one.
    """

    values: NDArray[np.float64]
    lines: NDArray[np.int64]
    header: tuple[str, ...] | None

    def __repr__(self) -> str:
        return f"Table({self.values.shape[0]} rows × {self.values.shape[1]} columns, header={self.header})"


def read_table(
    path: str | os.PathLike[str],
    *,
    delimiter: str | None = None,
    widths: tuple[int, ...] | None = None,
    nan_columns: tuple[int, ...] | None = None,
    max_rows: int | None = None,
    name: str | None = None,
) -> Table:
    """Read a numeric table (CSV, TSV or whitespace-separated) by machscan's one set of rules.

    Blank lines are skipped; ``#`` starts a comment anywhere on a line, ``//`` at its start. The
    first line left is a header when one of its cells is not a number and it holds a letter; any
    other line that is not numbers is an error. A line that is not UTF-8 is read as Latin-1, so
    a header or comment written in cp1252 (µ, °) reads. Every data row has as many cells as the
    first. Every table machscan reads (scan exports, probe plans, locating and matching points,
    contours) goes through this reader.

    Parameters
    ----------
    path : str or os.PathLike
    delimiter : str, optional
        One character; by default cells split on runs of whitespace and commas. With a delimiter
        cells are trimmed and an empty one is an error.
    widths : tuple of int, optional
        The column counts taken; by default any.
    nan_columns : tuple of int, optional
        The columns (0-based) that may hold NaN or inf (missing values); by default every column.
        ``()`` requires every value to be finite.
    max_rows : int, optional
        Read at most this many data rows (the rest of the file is not read); default all.
    name : str, optional
        The argument the file is named by in messages (default ``"path"``).

    Returns
    -------
    Table

    Raises
    ------
    FileFormatError
        A rule broken, naming the file, the line (and column) and ``name``.
    OSError
        The file cannot be read (``FileNotFoundError``, ``PermissionError``, ...).

    Examples
    --------
    >>> t = machscan.io.read_table("plan.csv", delimiter=",", widths=(6,), nan_columns=())  # doctest: +SKIP
    >>> t.values.shape, t.header
    ((24, 6), ('x', 'y', 'z', 'nx', 'ny', 'nz'))
    """
    if delimiter is not None and len(delimiter) != 1:
        raise ValueError(f"delimiter: expected one character or None, got {delimiter!r}")
    arrays = _core.read_table(
        os.fspath(path),
        name=name or "path",
        delimiter=delimiter,
        widths=None if widths is None else list(widths),
        nan_columns=None if nan_columns is None else list(nan_columns),
        max_rows=max_rows,
    )
    header = arrays["header"]
    return Table(values=arrays["values"], lines=arrays["lines"], header=None if header is None else tuple(header))


@dataclass(frozen=True, eq=False, repr=False)
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
    skipped. Errors name the file and line, also for values no machine can take (``nan``, ``inf``,
    1e400, a feed ≤ 0).

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
    ``FEDRAT`` whenever the feed changes, ``RAPID`` where the segment label changes. Feeds are
    positive; NaN only before the first feed (as :func:`read_toolpath` gives points before any
    ``FEDRAT``). A row of ``axes`` that is all NaN writes its point without a tool axis (as
    :func:`read_toolpath` gives a ``GOTO/x,y,z``), so what it reads is written back as it was; any
    other axis must be finite and not (0, 0, 0).

    Examples
    --------
    >>> machscan.io.write_toolpath("path.cl", pts, axes=normals, feeds=f)
    """
    _core.write_toolpath(path, points, axes=axes, feeds=feeds, segments=segments)
