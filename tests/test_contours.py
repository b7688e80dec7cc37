"""Clustering against Open3D, contour error against a brute-force transcription of paper 000
eq (21)–(23), matching against scipy's assignment."""

import numpy as np
import open3d
import pytest
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

import machscan
from paths import DATA


def canonical(labels):
    """Relabel clusters 0, 1, ... in order of first appearance."""
    _, first = np.unique(labels, return_index=True)
    order = np.argsort(first)
    remap = np.empty(len(order), dtype=np.int64)
    remap[order] = np.arange(len(order))
    return remap[np.unique(labels, return_inverse=True)[1]]


def contour_like_cloud(seed, n_per=3000):
    rng = np.random.default_rng(seed)
    pts = []
    for _ in range(12):
        t = rng.uniform(0, 2 * np.pi, n_per)
        r = rng.uniform(5, 20)
        cx, cy = rng.uniform(-200, 200, 2)
        pts.append(np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t), rng.normal(0, 0.05, n_per)]))
    p = np.vstack(pts)
    return p[rng.permutation(len(p))]


@pytest.mark.parametrize("seed, eps", [(0, 0.5), (1, 1.5), (2, 5.0)])
def test_radius_clusters_equal_open3d_dbscan_min_points_1(seed, eps):
    p = contour_like_cloud(seed)
    pcd = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p))
    ref = np.asarray(pcd.cluster_dbscan(eps=eps, min_points=1))
    got = machscan.euclidean_clusters(p, eps)
    assert got.min() == 0 and got.max() == ref.max()
    np.testing.assert_array_equal(got, canonical(ref))
    np.testing.assert_array_equal(canonical(got), got)


def _read_pcd_xyz(path):
    return np.asarray(open3d.io.read_point_cloud(str(path)).points, dtype=np.float64)


@pytest.mark.parametrize("name, eps", [("bun0.pcd", 0.004), ("bun4.pcd", 0.006)])
def test_radius_clusters_on_real_scans_equal_open3d(name, eps):
    p = _read_pcd_xyz(DATA / "pcl-bunny-icp" / name)
    ref = np.asarray(open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p)).cluster_dbscan(eps=eps, min_points=1))
    got = machscan.euclidean_clusters(p, eps)
    assert got.max() > 0  # the threshold does split the scan
    np.testing.assert_array_equal(got, canonical(ref))


def test_k_nearest_form_is_the_symmetric_knn_graph():
    p = contour_like_cloud(3, n_per=800)
    k, r = 5, 1.0
    d, j = cKDTree(p).query(p, k=k + 1, distance_upper_bound=r)
    i = np.repeat(np.arange(len(p)), k + 1)
    ok = np.isfinite(d.ravel()) & (j.ravel() != i)
    g = coo_matrix((np.ones(ok.sum()), (i[ok], j.ravel()[ok])), shape=(len(p), len(p)))
    _, ref = connected_components(g, directed=True, connection="weak")
    got = machscan.euclidean_clusters(p, r, k=k)
    np.testing.assert_array_equal(got, canonical(ref))


def brute_contour_error(P, Q, d1=1.0, d2=1.0):
    E = P.mean(0) - Q.mean(0)
    Qs = Q + E
    D = np.linalg.norm(P[:, None, :] - Qs[None, :, :], axis=2)  # (a, b)
    j = D.argmin(1)  # M_P
    mq = D.argmin(0)  # M_Q
    e = np.empty(len(P))
    for i in range(len(P)):
        dist = D[i, j[i]]
        ks = np.nonzero(mq == i)[0]
        if len(ks):
            dist = max(dist, D[i, ks].max())
        e[i] = d1 * np.linalg.norm(E) + d2 * dist
    return E, e


@pytest.mark.parametrize("seed", range(4))
def test_contour_error_equals_brute_force_eq_21_23(seed):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    P = np.column_stack([30 * np.cos(t), 18 * np.sin(t), np.zeros_like(t)])
    s = np.sort(rng.uniform(0, 2 * np.pi, 700))
    Q = np.column_stack([30 * np.cos(s), 18 * np.sin(s), 0.2 * np.sin(3 * s)])
    Q += rng.normal(0, 0.03, Q.shape) + [0.05, -0.08, 0.3]
    Q[::97] += rng.normal(0, 0.5, Q[::97].shape)  # strays
    E, e = brute_contour_error(P, Q, 1.0, 0.7)
    r = machscan.contour_error(P, Q, delta1=1.0, delta2=0.7, cad_spacing=None, actual_spacing=None)
    np.testing.assert_allclose(r.offset, E, atol=1e-12)
    np.testing.assert_allclose(r.errors, e, atol=1e-12)
    assert r.mean == pytest.approx(e.mean()) and r.std == pytest.approx(e.std()) and r.max == pytest.approx(e.max())
    assert set(np.unique(r.cases)) <= {1, 2, 3} and (r.cases == 3).any()


def test_match_contours_equals_scipy_assignment():
    rng = np.random.default_rng(7)
    theo = rng.uniform(-100, 100, (15, 3))
    act = theo[rng.permutation(15)][:12] + rng.normal(0, 3, (12, 3))
    cost = np.linalg.norm(act[:, None] - theo[None], axis=2)
    rows, cols = linear_sum_assignment(cost)
    got = machscan.match_contours(act, theo)
    np.testing.assert_array_equal(got[rows], cols)
    stray = np.vstack([act, [[1000.0, 0, 0]]])
    assert machscan.match_contours(stray, theo, max_distance=20.0)[-1] == -1


def test_resample_polyline():
    sq = np.array([[0, 0, 0], [10, 0, 0], [10, 4, 0], [0, 4, 0.0]])
    pts = machscan.resample_polyline(sq, 0.5, closed=True)
    assert len(pts) == 56
    steps = np.linalg.norm(np.diff(np.vstack([pts, pts[:1]]), axis=0), axis=1)
    assert steps.max() <= 0.5 + 1e-12
    assert any((pts == [10, 4, 0]).all(1))


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: machscan.euclidean_clusters(np.zeros((5, 2)), 1.0), "points"),
        (lambda: machscan.euclidean_clusters(np.zeros((5, 3)), -1.0), "radius"),
        (lambda: machscan.euclidean_clusters(np.zeros((5, 3)), 1.0, k=0), "k"),
        (lambda: machscan.euclidean_clusters([[0, 0, np.nan]], 1.0), "points"),
        (lambda: machscan.contour_error(np.zeros((0, 3)), np.zeros((4, 3))), "theoretical"),
        (lambda: machscan.contour_error(np.zeros((4, 3)), np.zeros((4, 2))), "actual"),
        (lambda: machscan.contour_error(np.zeros((4, 3)), [[np.inf, 0, 0]]), "actual"),
        (lambda: machscan.resample_polyline(np.zeros((2, 3)), 0.5, closed=True), "vertices"),
        (lambda: machscan.resample_polyline(np.zeros((4, 3)), 0.0), "spacing"),
        (lambda: machscan.match_contours(np.zeros((2, 3)), np.zeros((2, 3)), max_distance=-1), "max_distance"),
    ],
)
def test_bad_input_raises_value_error(call, name):
    with pytest.raises(ValueError) as exc:
        call()
    assert str(exc.value).startswith(name), str(exc.value)


def test_empty_cloud_gives_no_clusters():
    assert machscan.euclidean_clusters(np.zeros((0, 3)), 1.0).shape == (0,)


def test_radius_is_strict_like_open3d():
    p = np.column_stack([np.arange(6.0), np.zeros(6), np.zeros(6)])  # 1 mm apart
    ref = np.asarray(open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p)).cluster_dbscan(eps=1.0, min_points=1))
    np.testing.assert_array_equal(machscan.euclidean_clusters(p, 1.0), ref)
    assert machscan.euclidean_clusters(p, 1.0 + 1e-9).max() == 0
