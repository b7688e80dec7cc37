"""Normals against Open3D's estimate_normals on the same neighborhoods; curvature against
spheres and cylinders of known radius."""

import numpy as np
import open3d
import pytest

import machscan
from paths import DATA

RNG = np.random.default_rng(0)


def sphere(n=20000, r=20.0):
    u = RNG.normal(size=(n, 3))
    return r * u / np.linalg.norm(u, axis=1, keepdims=True)


def cylinder(n=20000, r=15.0):
    t = RNG.uniform(0, 2 * np.pi, n)
    return np.column_stack([r * np.cos(t), r * np.sin(t), RNG.uniform(-30, 30, n)])


def o3d_normals(p, param):
    pc = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p))
    pc.estimate_normals(param)
    return np.asarray(pc.normals)


CLOUDS = [
    ("sphere", sphere()),
    ("cylinder", cylinder()),
    ("bun0", machscan.read_points(DATA / "pcl-bunny-icp" / "bun0.pcd")),
    ("bunny mesh vertices", machscan.read_points(DATA / "stanford-bunny-mesh" / "stanford_bunny.ply")),
]


@pytest.mark.parametrize("name, p", CLOUDS, ids=[c[0] for c in CLOUDS])
def test_knn_normals_equal_open3d_up_to_sign(name, p):
    n = machscan.estimate_normals(p, k=20)
    ref = o3d_normals(p, open3d.geometry.KDTreeSearchParamKNN(20))
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    assert np.abs(np.sum(n * ref, axis=1)).min() >= 0.9999


@pytest.mark.parametrize("name, p", CLOUDS[:2], ids=[c[0] for c in CLOUDS[:2]])
def test_hybrid_normals_equal_open3d_up_to_sign(name, p):
    n = machscan.estimate_normals(p, k=30, radius=2.0)
    ref = o3d_normals(p, open3d.geometry.KDTreeSearchParamHybrid(radius=2.0, max_nn=30))
    assert np.abs(np.sum(n * ref, axis=1)).min() >= 0.9999


def test_orientations():
    p = sphere(5000)
    out = machscan.estimate_normals(p, k=15, towards=(0, 0, 0))
    assert (np.sum(out * p, axis=1) < 0).all()  # all inward
    up = machscan.estimate_normals(p, k=15, along=(0, 0, 1))
    assert (up[:, 2] >= 0).all()
    cons = machscan.estimate_normals(p, k=15, consistent=True)
    assert (np.sum(cons * p, axis=1) > 0).all()  # one consistent side: outward from the top point
    with pytest.raises(ValueError, match="at most one"):
        machscan.estimate_normals(p, towards=(0, 0, 0), consistent=True)


def test_surface_variation_plane_and_noise():
    plane = np.column_stack([RNG.uniform(0, 10, 3000), RNG.uniform(0, 10, 3000), np.zeros(3000)])
    assert machscan.surface_variation(plane, k=15).max() < 1e-12
    blob = RNG.normal(size=(3000, 3))
    v = machscan.surface_variation(blob, k=30)
    assert 0.1 < np.median(v) <= 1 / 3


@pytest.mark.parametrize("shape, r, expect", [("sphere", 20.0, (1 / 20, 1 / 20)), ("cylinder", 15.0, (1 / 15, 0.0))])
def test_principal_curvatures_within_1_percent(shape, r, expect):
    p = sphere(r=r) if shape == "sphere" else cylinder(r=r)
    inward = machscan.estimate_normals(p, k=20, towards=(0, 0, 0) if shape == "sphere" else None)
    if shape == "cylinder":
        inward = inward * np.sign(np.sum(inward * -p * [1, 1, 0], axis=1))[:, None]
    k, d = machscan.principal_curvatures(p, inward, k=40)
    k1, k2 = np.median(k[:, 0]), np.median(k[:, 1])
    assert abs(k1 - expect[0]) <= 0.01 * expect[0]
    assert abs(k2 - expect[1]) <= 0.01 * max(expect[0], 1e-9) + (0.01 * expect[1])
    if shape == "cylinder":
        # Minimal curvature runs along the axis.
        assert np.median(np.abs(d[:, 1, 2])) > 0.99


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: machscan.estimate_normals(np.zeros((5, 3)), k=2), "k"),
        (lambda: machscan.estimate_normals(np.zeros((5, 3)), radius=-1.0), "radius"),
        (lambda: machscan.estimate_normals(np.zeros((5, 2))), "points"),
        (lambda: machscan.estimate_normals([[0, 0, np.inf]]), "points"),
        (lambda: machscan.principal_curvatures(np.zeros((5, 3)), np.zeros((4, 3))), "normals"),
        (lambda: machscan.estimate_normals(np.zeros((5, 3)), along=(0, 0)), "along"),
    ],
)
def test_bad_input(call, name):
    with pytest.raises(ValueError) as exc:
        call()
    assert str(exc.value).startswith(name)
