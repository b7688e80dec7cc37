"""CAD from files: contours (CSV polylines and the GOTO points of APT/CL programs) and solids
(STEP and IGES, tessellated within a chordal tolerance, each triangle keeping its B-rep face).

Paper 000 derives its scan path and its theoretical contours from the engraving program's APT
file; plants also export contours as plain point lists. Both come in as a list of ``(n, 3)``
polylines (mm).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "CAD_SUFFIXES",
    "CadMesh",
    "Polyline",
    "read_cad",
    "read_contours",
    "read_contours_apt",
    "read_contours_csv",
    "write_contours_csv",
]

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


# ---------------------------------------------------------------------------------------------
# Solids: STEP and IGES through OpenCASCADE (``machscan[cad]``).
#
# cadquery-ocp-novtk was measured against gmsh for this (BENCHMARKS.md, "CAD in"): the same
# OpenCASCADE mesher gives the fewest triangles for a chordal tolerance, it reports the file's
# length unit (gmsh converts without saying from what), it needs two system libraries against
# gmsh's eleven, and it is LGPL (gmsh is GPL, which an optional import would pass on).

#: What ``read_cad`` reads.
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs")

_CAD_MISSING = (
    "reading STEP and IGES needs OpenCASCADE's Python binding: pip install machscan[cad] "
    "(cadquery-ocp-novtk; cadquery or build123d bring it too)"
)

#: Halvings of the mesher's deflection tried before a tolerance is given up: OpenCASCADE's
#: mesher overshoots the deflection asked by up to 2.1× on spheres, so the deviation is
#: measured and the mesh made again, finer, until it holds.
_CAD_REFINEMENTS = 4


@dataclass(frozen=True, eq=False)
class CadMesh:
    """A CAD model tessellated within a chordal tolerance (:func:`read_cad`), in mm.

    Attributes
    ----------
    vertices : ndarray, shape (V, 3)
        mm, welded: a vertex on the edge between two CAD faces is one vertex, so the mesh is
        closed where the B-rep is.
    triangles : ndarray of int64, shape (M, 3)
        Counter-clockwise seen from outside the material.
    cad_faces : ndarray of int64, shape (M,)
        The B-rep face each triangle lies on (0-based, in the file's face order).
    vertex_normals : ndarray, shape (V, 3)
        The B-rep's outward unit normal at each vertex (exact, from the surface; at a vertex on
        an edge between faces, that of the first face).
    unit : str
        The length unit the file was written in (converted to mm here).
    tolerance : float
        The chordal tolerance asked, mm.
    chordal_deviation : float
        The largest distance measured between a triangle and its B-rep face, mm (at each
        triangle's centroid and edge midpoints): ≤ ``tolerance``.
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    cad_faces: NDArray[np.int64]
    vertex_normals: NDArray[np.float64]
    unit: str
    tolerance: float
    chordal_deviation: float

    @property
    def face_count(self) -> int:
        """Number of B-rep faces with triangles."""
        return int(self.cad_faces.max()) + 1 if len(self.cad_faces) else 0

    def sample(self, spacing: float, *, seed: int = 0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Points with normals spread evenly over the CAD surface, about ``spacing`` mm apart
        (Poisson-disk by elimination: a dense random sample thinned so that no two kept points
        are closer than ``spacing``), for positioning and allowance. Points lie on the triangles
        (within the chordal tolerance of the B-rep); normals are the B-rep's vertex normals
        interpolated and normalised (exact at the vertices).

        Returns
        -------
        points, normals : ndarray, shape (K, 3)
        """
        from machscan.mesh import sample_surface

        return sample_surface(self.vertices, self.triangles, spacing, normals=self.vertex_normals, seed=seed)


def read_cad(path: str | os.PathLike[str], *, tolerance: float = 0.01) -> CadMesh:
    """A STEP or IGES model as a triangle mesh within ``tolerance`` of its B-rep (``machscan[cad]``).

    OpenCASCADE reads the file (its length unit — mm, inch, m, … — converted to mm) and meshes
    every face; the distance of each triangle from its face is then measured at the triangle's
    centroid and edge midpoints, and the model meshed again with half the deflection while it
    exceeds ``tolerance`` (OpenCASCADE's mesher overshoots by up to 2.1×). Triangles are wound
    outward (reversed faces turned), vertices on the edges between faces welded, and each
    triangle keeps its B-rep face, so deviations can be reported per face.

    Parameters
    ----------
    path : str or os.PathLike
        ``.step``/``.stp`` or ``.iges``/``.igs``.
    tolerance : float
        Largest chordal deviation of the mesh from the B-rep, mm.

    Returns
    -------
    CadMesh
        ``.vertices``, ``.triangles``, ``.cad_faces``, ``.vertex_normals``, ``.unit``,
        ``.chordal_deviation``; ``.sample(spacing)`` for points with normals.

    Raises
    ------
    ImportError
        Without ``machscan[cad]``, naming the extra to install.
    FileNotFoundError
        The file does not exist.
    machscan.io.FileFormatError
        OpenCASCADE cannot read it, or it holds no surface.

    Examples
    --------
    >>> cad = machscan.io.read_cad("blade.step", tolerance=0.005)
    >>> d = machscan.signed_distances(scan, cad.vertices, cad.triangles, cad_faces=cad.cad_faces)
    """
    from machscan.io import FileFormatError

    p = Path(path)
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance: must be a positive distance, got {tolerance}")
    if p.suffix.lower() not in CAD_SUFFIXES:
        raise ValueError(f"path: {p} is not STEP or IGES (expected one of {', '.join(CAD_SUFFIXES)})")
    if not p.is_file():
        raise FileNotFoundError(2, "No such file or directory", str(p))
    try:
        import OCP  # noqa: F401
    except ImportError as e:
        raise ImportError(_CAD_MISSING) from e
    shape, unit = _read_brep(p)
    deflection = tolerance
    for _ in range(_CAD_REFINEMENTS + 1):
        mesh = _tessellate(shape, deflection)
        if mesh is None:
            raise FileFormatError(f"{p}: holds no surface to mesh")
        vertices, triangles, faces, normals, deviation = mesh
        if deviation <= tolerance:
            break
        deflection /= 2
    else:
        raise FileFormatError(
            f"{p}: the mesh stays {deviation:.4g} mm from the B-rep after {_CAD_REFINEMENTS} refinements "
            f"(tolerance {tolerance} mm)"
        )
    vertices, triangles, normals, kept = _weld(vertices, triangles, normals)
    return CadMesh(vertices, triangles, faces[kept], normals, unit, float(tolerance), float(deviation))


def _read_brep(path: Path) -> tuple[Any, str]:
    """The file's shape (in mm: OpenCASCADE converts to its session unit, mm) and its unit.
    OpenCASCADE's console messages below failures are silenced while it reads (its IGES reader
    prints entity counts), and its level restored after."""
    from OCP.Message import Message, Message_Gravity

    printers = Message.DefaultMessenger_s().Printers()
    printer = printers.First() if printers.Size() else None
    level = printer.GetTraceLevel() if printer is not None else None
    if printer is not None:
        printer.SetTraceLevel(Message_Gravity.Message_Fail)
    try:
        return _read_brep_quiet(path)
    finally:
        if printer is not None:
            printer.SetTraceLevel(level)


def _read_brep_quiet(path: Path) -> tuple[Any, str]:
    from OCP.IFSelect import IFSelect_RetDone

    from machscan.io import FileFormatError

    if path.suffix.lower() in (".step", ".stp"):
        from OCP.STEPControl import STEPControl_Reader

        reader: Any = STEPControl_Reader()
        if reader.ReadFile(str(path)) != IFSelect_RetDone:
            raise FileFormatError(f"{path}: OpenCASCADE cannot read it as STEP")
        units, angles, solids = (_ascii_sequence() for _ in range(3))
        reader.FileUnits(units, angles, solids)
        unit = units.Value(1).ToCString() if units.Length() else "unknown"
    else:
        from OCP.IGESControl import IGESControl_Reader

        reader = IGESControl_Reader()
        if reader.ReadFile(str(path)) != IFSelect_RetDone:
            raise FileFormatError(f"{path}: OpenCASCADE cannot read it as IGES")
        unit = reader.IGESModel().GlobalSection().UnitName().ToCString()
    if reader.TransferRoots() == 0:
        raise FileFormatError(f"{path}: holds no shape OpenCASCADE can transfer")
    return reader.OneShape(), str(unit)


def _ascii_sequence() -> Any:
    try:  # OCP >= 8.0 moved the collection instantiations
        from OCP.collections import Sequence_TCollection_AsciiString

        return Sequence_TCollection_AsciiString()
    except ImportError:  # pragma: no cover - OCP 7.x
        from OCP.TColStd import TColStd_SequenceOfAsciiString

        return TColStd_SequenceOfAsciiString()


def _face_map() -> Any:
    try:
        from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher

        return IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher()
    except ImportError:  # pragma: no cover - OCP 7.x
        from OCP.TopTools import TopTools_IndexedMapOfShape

        return TopTools_IndexedMapOfShape()


def _tessellate(shape: Any, deflection: float) -> tuple[Any, ...] | None:
    """Vertices, triangles, B-rep face per triangle, vertex normals and the largest measured
    chordal deviation of ``shape`` meshed with ``deflection``; None without any triangle."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.gp import gp_Pnt, gp_Vec
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    to_face = getattr(TopoDS, "Face_s", None) or TopoDS.Face
    # A triangulation already in the shape is reused when it is finer than asked: drop it so
    # the deflection asked is the one meshed.
    BRepTools.Clean_s(shape)
    # Angular deflection 0.5 rad: the chordal tolerance governs; parallel off, so the mesh
    # does not depend on the thread count.
    BRepMesh_IncrementalMesh(shape, deflection, False, 0.5, False)
    faces = _face_map()
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    vs, ts, fs, ns, worst, offset = [], [], [], [], 0.0, 0
    for i in range(1, faces.Extent() + 1):
        face = to_face(faces.FindKey(i))
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face, loc)
        if tri is None or tri.NbTriangles() == 0:
            continue
        trsf = loc.Transformation()
        reversed_ = face.Orientation() == TopAbs_REVERSED
        surface = BRepAdaptor_Surface(face)  # in the face's placement: the shape's coordinates
        n, m = tri.NbNodes(), tri.NbTriangles()
        v = np.empty((n, 3))
        uv = np.empty((n, 2))
        normal = np.empty((n, 3))
        p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
        for k in range(n):
            node = tri.Node(k + 1).Transformed(trsf)
            v[k] = node.X(), node.Y(), node.Z()
            u_, v_ = tri.UVNode(k + 1).X(), tri.UVNode(k + 1).Y()
            uv[k] = u_, v_
            surface.D1(u_, v_, p, du, dv)
            nv = du.Crossed(dv)
            length = nv.Magnitude()
            normal[k] = (nv.X() / length, nv.Y() / length, nv.Z() / length) if length > 0 else (np.nan,) * 3
        t = np.array([tri.Triangle(k + 1).Get() for k in range(m)], dtype=np.int64) - 1
        if reversed_:
            t = t[:, ::-1]
            normal = -normal
        # The chordal deviation, measured: how far each triangle's centroid and edge midpoints
        # lie off the surface, along the surface's normal at their mean parameters (the normal
        # part only: the parameters' mean is not the foot of the point, least of all near a
        # pole, and the tangential offset is no deviation).
        for w in ((1 / 3, 1 / 3, 1 / 3), (0.5, 0.5, 0), (0, 0.5, 0.5), (0.5, 0, 0.5)):
            at_uv = w[0] * uv[t[:, 0]] + w[1] * uv[t[:, 1]] + w[2] * uv[t[:, 2]]
            on_tri = w[0] * v[t[:, 0]] + w[1] * v[t[:, 1]] + w[2] * v[t[:, 2]]
            for j in range(m):
                surface.D1(at_uv[j, 0], at_uv[j, 1], p, du, dv)
                nv = du.Crossed(dv)
                length = nv.Magnitude()
                if length > 0:
                    off = on_tri[j] - (p.X(), p.Y(), p.Z())
                    worst = max(worst, abs(float(off @ (nv.X(), nv.Y(), nv.Z()))) / length)
        vs.append(v)
        ts.append(t + offset)
        fs.append(np.full(m, i - 1, dtype=np.int64))
        ns.append(normal)
        offset += n
    if not ts:
        return None
    return np.vstack(vs), np.vstack(ts), np.concatenate(fs), np.vstack(ns), worst


def _weld(
    vertices: NDArray[np.float64], triangles: NDArray[np.int64], normals: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64], NDArray[np.bool_]]:
    """One vertex where the faces' meshes put several at exactly the same point (OpenCASCADE
    meshes each face on its own, sharing the edges' nodes), keeping the first one's normal;
    triangles that collapse (a sphere's pole) are dropped."""
    unique, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    # Keep the file's vertex order: number the unique vertices by first appearance.
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    t = rank[inverse][triangles]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    return unique[order], t[keep], normals[first[order]], keep
