"""Open3D and trimesh geometry to and from machscan's (issue #34 §5), and the error that names
the conversion when such an object is passed where an array is taken."""

from __future__ import annotations

import numpy as np
import pytest

import machscan
from machscan import interop
from machscan.io import CloudFile, TriangleMesh

o3d = pytest.importorskip("open3d")
trimesh = pytest.importorskip("trimesh")


def tetrahedron() -> TriangleMesh:
    v = np.array([[0.0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]])
    t = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    n = v - v.mean(axis=0)
    return TriangleMesh(vertices=v, triangles=t, normals=n / np.linalg.norm(n, axis=1, keepdims=True))


def cloud() -> CloudFile:
    rng = np.random.default_rng(0)
    p = rng.uniform(-5, 5, (200, 3))
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    return CloudFile(points=p, normals=n, scalars={"allowance": rng.normal(0.3, 0.01, 200)})


def test_open3d_round_trips_legacy_and_tensor():
    c = cloud()
    back = interop.from_open3d(interop.to_open3d(c))
    np.testing.assert_array_equal(back.points, c.points)
    np.testing.assert_array_equal(back.normals, c.normals)
    t = interop.from_open3d(interop.to_open3d(c, tensor=True))
    np.testing.assert_array_equal(t.points, c.points)
    np.testing.assert_array_equal(t.normals, c.normals)
    np.testing.assert_array_equal(t.scalars["allowance"], c.scalars["allowance"])
    m = tetrahedron()
    for tensor in (False, True):
        mb = interop.from_open3d(interop.to_open3d(m, tensor=tensor))
        np.testing.assert_array_equal(mb.vertices, m.vertices)
        np.testing.assert_array_equal(mb.triangles, m.triangles)
        np.testing.assert_array_equal(mb.normals, m.normals)
    # What Open3D computes on the converted mesh is what it computes on its own.
    own = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(m.vertices), o3d.utility.Vector3iVector(m.triangles))
    assert interop.to_open3d(m).get_surface_area() == own.get_surface_area()


def test_trimesh_round_trips():
    m = tetrahedron()
    tm = interop.to_trimesh(m)
    assert all(a.flags.writeable for a in (m.vertices, m.triangles, m.normals))  # the caller's arrays untouched
    assert tm.is_watertight and tm.volume == pytest.approx(1000 / 6, rel=1e-12)
    back = interop.from_trimesh(tm)
    np.testing.assert_array_equal(back.vertices, m.vertices)
    np.testing.assert_array_equal(back.triangles, m.triangles)
    np.testing.assert_array_equal(back.normals, m.normals)
    bare = interop.from_trimesh(trimesh.Trimesh(m.vertices, m.triangles, process=False))
    assert bare.normals is None  # not computed on machscan's behalf
    pc = interop.from_trimesh(interop.to_trimesh(cloud()))
    np.testing.assert_array_equal(pc.points, cloud().points)


def test_foreign_objects_where_arrays_are_taken_name_the_conversion():
    c = cloud()
    with pytest.raises(ValueError, match=r"points: .*Open3D PointCloud.*np\.asarray\(cloud\.points\).*from_open3d"):
        machscan.estimate_normals(interop.to_open3d(c), k=10)
    with pytest.raises(ValueError, match=r"points: .*tensor PointCloud.*positions\.numpy\(\)"):
        machscan.voxel_downsample(interop.to_open3d(c, tensor=True), 1.0)
    m = tetrahedron()
    with pytest.raises(ValueError, match=r"vertices: .*trimesh Trimesh.*mesh\.faces.*from_trimesh"):
        machscan.closest_points(interop.to_trimesh(m), m.triangles, c.points)
    with pytest.raises(ValueError, match=r"Open3D TriangleMesh"):
        machscan.closest_points(interop.to_open3d(m), m.triangles, c.points)
    with pytest.raises(ValueError, match="geometry: expected an Open3D"):
        interop.from_open3d(c.points)
    with pytest.raises(ValueError, match="data: expected a CloudFile"):
        interop.to_open3d(np.zeros((3, 2)))
