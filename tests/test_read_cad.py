"""STEP and IGES in (``machscan.io.read_cad``): shapes of known geometry made and written by
OpenCASCADE here, read back, and their tessellation's deviation measured analytically (a box, a
cylinder, a sphere); units (mm, inch, m) converted to mm; B-rep faces kept per triangle; the
mesh closed and wound outward, so signed distances run on it; points sampled with normals."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import machscan

pytest.importorskip("OCP")


def _write(shape, path, unit: str = "MM") -> None:
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.IGESControl import IGESControl_Controller, IGESControl_Writer
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    if path.suffix in (".igs", ".iges"):
        IGESControl_Controller.Init_s()
        w = IGESControl_Writer({"INCH": "IN"}.get(unit, unit), 1)
        w.AddShape(shape)
        w.ComputeModel()
        assert w.Write(str(path))
        return
    # The unit of the numbers in the file (the session's geometry is in mm); a global setting of
    # OpenCASCADE (known once a writer exists), put back after.
    w = STEPControl_Writer()
    before = Interface_Static.CVal_s("write.step.unit")
    try:
        assert Interface_Static.SetCVal_s("write.step.unit", unit)
        w.Transfer(shape, STEPControl_AsIs)
        assert w.Write(str(path)) == IFSelect_RetDone
    finally:
        Interface_Static.SetCVal_s("write.step.unit", before)


def _box():
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    return BRepPrimAPI_MakeBox(20.0, 30.0, 40.0).Shape()


def _cylinder():
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder

    return BRepPrimAPI_MakeCylinder(10.0, 30.0).Shape()


def _sphere():
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeSphere

    return BRepPrimAPI_MakeSphere(15.0).Shape()


def _edges_used_twice(t: np.ndarray) -> bool:
    e = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, count = np.unique(e, axis=0, return_counts=True)
    return bool(np.all(count == 2))


def _volume(v: np.ndarray, t: np.ndarray) -> float:
    return float(np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6)


def _segment_distance_2d(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from the origin to each 2D segment ab."""
    ab = b - a
    s = np.clip(-np.einsum("ij,ij->i", a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
    return np.linalg.norm(a + s[:, None] * ab, axis=1)


@pytest.mark.parametrize("unit", ["MM", "INCH", "M"])
def test_a_box_comes_back_exact_in_mm_whatever_the_file_unit(tmp_path, unit):
    path = tmp_path / f"box_{unit}.step"
    _write(_box(), path, unit)
    cad = machscan.io.read_cad(path)
    assert cad.unit.lower() in {"MM": ("millimetre", "mm"), "INCH": ("inch",), "M": ("metre", "m")}[unit]
    np.testing.assert_allclose(cad.vertices.min(axis=0), [0, 0, 0], atol=1e-9)
    np.testing.assert_allclose(cad.vertices.max(axis=0), [20, 30, 40], atol=1e-9)
    assert len(cad.vertices) == 8 and len(cad.triangles) == 12 and cad.face_count == 6
    assert _edges_used_twice(cad.triangles) and _volume(cad.vertices, cad.triangles) == pytest.approx(24000, abs=1e-6)
    assert cad.chordal_deviation < 1e-9
    # Each B-rep face is one side of the box: its triangles' normals are all the same axis.
    v, t = cad.vertices, cad.triangles
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    for face in range(6):
        m = n[cad.cad_faces == face]
        assert len(m) == 2 and np.allclose(m, m[0]) and np.isclose(np.abs(m[0]).max(), 1)


@pytest.mark.parametrize("suffix", [".step", ".igs"])
@pytest.mark.parametrize("tolerance", [0.05, 0.01])
def test_a_sphere_and_a_cylinder_are_within_the_chordal_tolerance_measured_analytically(tmp_path, suffix, tolerance):
    sphere, cylinder = tmp_path / f"sphere{suffix}", tmp_path / f"cylinder{suffix}"
    _write(_sphere(), sphere, "INCH")
    _write(_cylinder(), cylinder)
    cad = machscan.io.read_cad(sphere, tolerance=tolerance)
    v, t = cad.vertices, cad.triangles
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 15.0, atol=1e-6)  # inch → mm through 25.4
    # The largest sag: 15 − the least distance from the centre to a triangle, exactly.
    d = machscan.closest_points(v, t, np.zeros((1, 3))).distances[0]
    sag = 15.0 - d
    assert 0 < sag <= tolerance, sag
    assert sag <= cad.chordal_deviation + 1e-9  # what it measured covers the truth here
    assert _volume(v, t) > 0 and cad.face_count == 1
    np.testing.assert_allclose(cad.vertex_normals, v / 15.0, atol=1e-6)

    cad = machscan.io.read_cad(cylinder, tolerance=tolerance)
    v, t = cad.vertices, cad.triangles
    # The side's triangles: not flat in z (a cap's triangles may have every corner on the rim too).
    lateral = np.ptp(v[t][..., 2], axis=1) > 0
    assert np.all(np.abs(np.hypot(v[t][lateral][..., 0], v[t][lateral][..., 1]) - 10.0) < 1e-9)
    xy = v[t][lateral][..., :2]
    # A side triangle projects onto a chord of the circle: its nearest point to the axis is on an edge.
    least = np.min([_segment_distance_2d(xy[:, i], xy[:, (i + 1) % 3]) for i in range(3)], axis=0)
    assert 0 < 10.0 - least.min() <= tolerance
    assert cad.face_count == 3 and _edges_used_twice(t)
    assert _volume(v, t) == pytest.approx(np.pi * 100 * 30, rel=2 * tolerance / 10)


def test_signed_distances_run_on_the_cad_mesh_and_name_its_faces(tmp_path):
    path = tmp_path / "cylinder.step"
    _write(_cylinder(), path)
    cad = machscan.io.read_cad(path, tolerance=0.005)
    rng = np.random.default_rng(0)
    phi, z = rng.uniform(0, 2 * np.pi, 2000), rng.uniform(1, 29, 2000)
    r = 10 + rng.uniform(-0.3, 0.3, 2000)
    q = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    d = machscan.signed_distances(q, cad.vertices, cad.triangles, cad_faces=cad.cad_faces)
    np.testing.assert_allclose(d.distances, r - 10, atol=0.005)
    stats = d.statistics(0.1)
    assert len(stats) == 1  # every point lands on the side face
    assert stats.mean[0] == pytest.approx(np.mean(r - 10), abs=0.005)


def test_points_sampled_on_the_cad_are_even_and_carry_its_normals(tmp_path):
    path = tmp_path / "sphere.step"
    _write(_sphere(), path)
    cad = machscan.io.read_cad(path, tolerance=0.005)
    points, normals = cad.sample(1.0, seed=3)
    radius = np.linalg.norm(points, axis=1)
    assert np.all(radius <= 15 + 1e-9) and np.all(radius >= 15 - 0.005)
    np.testing.assert_allclose(np.einsum("ij,ij->i", normals, points / radius[:, None]), 1.0, atol=1e-4)
    from scipy.spatial import cKDTree

    gaps, _ = cKDTree(points).query(points, k=2)
    assert gaps[:, 1].min() > 1.0 and np.median(gaps[:, 1]) < 1.6
    # About one point per disk of 1 mm packed at Poisson-disk density over 4π·15² mm².
    assert 1500 < len(points) < 3000
    assert np.array_equal(cad.sample(1.0, seed=3)[0], points)


def test_bad_files_and_arguments_are_refused_by_name(tmp_path, monkeypatch):
    with pytest.raises(FileNotFoundError):
        machscan.io.read_cad(tmp_path / "missing.step")
    junk = tmp_path / "junk.step"
    junk.write_text("ISO-10303-21;\nnot a step file\n")
    with pytest.raises(machscan.io.FileFormatError, match=r"junk\.step"):
        machscan.io.read_cad(junk)
    with pytest.raises(ValueError, match="tolerance"):
        machscan.io.read_cad(junk, tolerance=0.0)
    with pytest.raises(ValueError, match=r"path: .* is not STEP or IGES"):
        machscan.io.read_cad(tmp_path / "part.stl")
    monkeypatch.setitem(sys.modules, "OCP", None)
    with pytest.raises(ImportError, match=r"machscan\[cad\]"):
        machscan.io.read_cad(junk)
