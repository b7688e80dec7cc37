"""Octree simplification (paper 002 §2): definition checks, and the measured comparison with
Open3D's voxel grid at the same number of points on a part with steps and a free boundary."""

import numpy as np
import open3d
import pytest
from scipy.interpolate import LinearNDInterpolator
from scipy.spatial import Delaunay

import machscan


def pocket_plate(seed=0, spacing=0.25, noise=0.003):
    """120 × 80 mm plate with a notch in its outline, a 3 mm pocket with vertical walls and a
    boss inside it."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.arange(0, 120, spacing), np.arange(0, 80, spacing))
    x = x.ravel() + rng.uniform(-0.3, 0.3, x.size) * spacing
    y = y.ravel() + rng.uniform(-0.3, 0.3, y.size) * spacing
    keep = ~((x > 90) & (y > 55))
    x, y = x[keep], y[keep]
    z = np.zeros_like(x)
    z[(x > 20) & (x < 70) & (y > 15) & (y < 60)] = -3.0
    z[(x - 45) ** 2 + (y - 37) ** 2 < 64] = -1.0
    return np.column_stack([x, y, z + rng.normal(0, noise, x.size)])


def rebuilt_deviation(kept, full):
    """xy-Delaunay of the kept points, barycentric height at every original point:
    (max |dz|, rms dz, share of original points outside the rebuilt surface)."""
    z = LinearNDInterpolator(Delaunay(kept[:, :2]), kept[:, 2])(full[:, :2])
    inside = np.isfinite(z)
    e = np.abs(z[inside] - full[inside, 2])
    return e.max(), np.sqrt(np.mean(e**2)), 1 - inside.mean()


@pytest.fixture(scope="module")
def plate():
    return pocket_plate()


def test_result_is_sorted_unique_and_smaller(plate):
    keep = machscan.octree_simplify(plate, 2.0, eps1=200, eps2=200)
    assert np.all(np.diff(keep) > 0) and keep[0] >= 0 and keep[-1] < len(plate)
    # At most two points per occupied leaf (edge 120 / 2^6 on the minimum corner) plus two per
    # boundary group.
    cell = 120.0 / 64
    leaves = len(np.unique(np.floor((plate - plate.min(0)) / cell).astype(int), axis=0))
    groups = 2 * int(np.ceil(len(plate) / 200))
    assert len(keep) <= 2 * leaves + 2 * groups
    assert len(keep) >= leaves


def test_boundary_rule_keeps_each_groups_extremes(plate):
    keep = set(machscan.octree_simplify(plate, 2.0, eps1=50, eps2=70).tolist())
    for axis, other, eps in ((0, 1, 50), (1, 0, 70)):
        order = np.lexsort((np.arange(len(plate)), plate[:, axis]))
        for g in np.array_split(order, np.arange(eps, len(order), eps)):
            assert g[np.argmin(plate[g, other])] in keep
            assert g[np.argmax(plate[g, other])] in keep


def test_measured_against_voxel_grid_at_equal_point_count(plate):
    keep = machscan.octree_simplify(plate, 2.0)
    pc = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(plate))
    lo, hi = 0.01, 20.0
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if len(pc.voxel_down_sample(mid).points) > len(keep) else (lo, mid)
    vox = np.asarray(pc.voxel_down_sample(hi).points)
    assert abs(len(vox) - len(keep)) <= 0.02 * len(keep)
    o_max, o_rms, o_out = rebuilt_deviation(plate[keep], plate)
    v_max, v_rms, v_out = rebuilt_deviation(vox, plate)
    # Measured (see the issue note): the octree keeps the free boundary — almost no original
    # point falls outside its rebuilt surface, the voxel grid's centroids pull the outline in.
    assert o_out < 0.001 < v_out
    # Both step errors are bounded by the 3 mm wall; at this resolution the voxel grid's RMS is
    # lower (0.16 vs 0.20 mm): paper 002's advantage does not show in vertical deviation here.
    assert o_max < 3.5 and v_max < 3.5
    assert o_rms < 1.5 * v_rms


@pytest.mark.parametrize(
    "kwargs, name",
    [(dict(d_min=0.0), "d_min"), (dict(d_min=1.0, eps1=0), "eps1"), (dict(d_min=1.0, normals=np.zeros((3, 3))), "normals")],
)
def test_bad_input(plate, kwargs, name):
    with pytest.raises(ValueError) as exc:
        machscan.octree_simplify(plate[:100], **kwargs)
    assert str(exc.value).startswith(name)
