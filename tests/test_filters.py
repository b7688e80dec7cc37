"""Filters against Open3D's definitions on the same input: identical index sets (voxel
centroids compared as sets, Open3D returns them in hash-map order)."""

import numpy as np
import open3d
import pytest

import machscan
from paths import DATA


def o3d_cloud(p):
    return open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p))


def clouds():
    rng = np.random.default_rng(0)
    blob = rng.normal(0, 10, (3000, 3))
    outliers = rng.uniform(-80, 80, (60, 3))
    yield "synthetic", np.vstack([blob, outliers])
    plate = np.column_stack([rng.uniform(0, 200, 5000), rng.uniform(0, 200, 5000), rng.normal(0, 0.01, 5000)])
    yield "plate far from origin", plate + [2500.0, -1800.0, 900.0]
    for name in ("bun0.pcd", "bun4.pcd"):
        yield name, machscan.read_points(DATA / "pcl-bunny-icp" / name)


CLOUDS = list(clouds())


@pytest.mark.parametrize("name, p", CLOUDS, ids=[c[0] for c in CLOUDS])
def test_voxel_downsample_equals_open3d(name, p):
    size = np.ptp(p, axis=0).max() / 40
    got = machscan.voxel_downsample(p, size)
    ref = np.asarray(o3d_cloud(p).voxel_down_sample(size).points)
    assert got.shape == ref.shape

    def key(a):
        return a[np.lexsort(a.T[::-1])]

    np.testing.assert_array_equal(key(got), key(ref))
    c, idx = machscan.voxel_downsample(p, size, return_index=True)
    np.testing.assert_allclose(c[idx], p, atol=size * np.sqrt(3))


@pytest.mark.parametrize("name, p", CLOUDS, ids=[c[0] for c in CLOUDS])
@pytest.mark.parametrize("k, ratio", [(10, 1.0), (20, 2.0), (6, 0.5)])
def test_remove_statistical_outliers_equals_open3d(name, p, k, ratio):
    _, ref = o3d_cloud(p).remove_statistical_outlier(nb_neighbors=k, std_ratio=ratio)
    np.testing.assert_array_equal(machscan.remove_statistical_outliers(p, k, ratio), np.asarray(ref))


@pytest.mark.parametrize("name, p", CLOUDS, ids=[c[0] for c in CLOUDS])
@pytest.mark.parametrize("frac, nb", [(0.02, 3), (0.05, 10)])
def test_remove_radius_outliers_equals_open3d(name, p, frac, nb):
    r = np.ptp(p, axis=0).max() * frac
    _, ref = o3d_cloud(p).remove_radius_outlier(nb_points=nb, radius=r)
    np.testing.assert_array_equal(machscan.remove_radius_outliers(p, r, nb), np.asarray(ref))


def test_radius_counts_are_strict_and_include_the_point():
    p = np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)])
    _, ref = o3d_cloud(p).remove_radius_outlier(nb_points=2, radius=1.0 + 1e-9)
    np.testing.assert_array_equal(machscan.remove_radius_outliers(p, 1.0 + 1e-9, 2), np.asarray(ref))
    assert len(machscan.remove_radius_outliers(p, 1.0, 0)) == 5 and len(machscan.remove_radius_outliers(p, 1.0, 1)) == 0


def test_uniform_and_crop_equal_open3d():
    p = CLOUDS[0][1]
    ref = np.asarray(o3d_cloud(p).uniform_down_sample(7).points)
    np.testing.assert_array_equal(p[machscan.uniform_downsample(p, 7)], ref)
    lo, hi = np.array([-5.0, -8, -3]), np.array([6.0, 4, 9])
    box = open3d.geometry.AxisAlignedBoundingBox(lo, hi)
    ref_idx = np.asarray(box.get_point_indices_within_bounding_box(o3d_cloud(p).points))
    np.testing.assert_array_equal(machscan.crop_box(p, lo, hi), np.sort(ref_idx))


def test_duplicates_removed_without_holes():
    rng = np.random.default_rng(3)
    grid = np.stack(np.meshgrid(np.arange(20.0), np.arange(20.0), [0.0]), -1).reshape(-1, 3)
    dup = grid[rng.choice(len(grid), 100, replace=False)] + rng.normal(0, 0.001, (100, 3))
    cloud = np.vstack([grid, dup])
    keep = machscan.remove_duplicates(cloud, 0.05)
    np.testing.assert_array_equal(keep, np.arange(len(grid)))  # every grid point kept, every copy gone


def test_random_downsample_is_reproducible():
    pts = np.zeros((10000, 3))
    a = machscan.random_downsample(pts, 500, seed=3)
    assert len(np.unique(a)) == 500 and np.array_equal(a, machscan.random_downsample(pts, 500, seed=3))


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: machscan.voxel_downsample(np.zeros((5, 3)), 0.0), "voxel_size"),
        (lambda: machscan.voxel_downsample([[0, 0, np.nan]], 1.0), "points"),
        (lambda: machscan.voxel_downsample(np.array([[0, 0, 0], [1e6, 0, 0]]), 1e-3), "voxel_size"),
        (lambda: machscan.remove_statistical_outliers(np.zeros((5, 3)), 0, 1.0), "k"),
        (lambda: machscan.remove_statistical_outliers(np.zeros((5, 3)), 3, -1.0), "std_ratio"),
        (lambda: machscan.remove_radius_outliers(np.zeros((5, 3)), -1.0, 2), "radius"),
        (lambda: machscan.remove_duplicates(np.zeros((5, 3)), 0.0), "tolerance"),
        (lambda: machscan.crop_box(np.zeros((5, 3)), (1, 1, 1), (0, 0, 0)), "min_bound"),
        (lambda: machscan.uniform_downsample(np.zeros((10, 3)), 0), "every_k"),
    ],
)
def test_bad_input(call, name):
    with pytest.raises(ValueError) as exc:
        call()
    assert str(exc.value).startswith(name)
