"""k-nearest graph of a cloud's own points (`spatial::CloudNeighbors`) against scipy's cKDTree
and Open3D's nearest-neighbor search on the same points."""

import numpy as np
import open3d
import pytest
from scipy.spatial import cKDTree

import machscan


def surface(n, seed=0, offset=0.0):
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 100, n), rng.uniform(0, 60, n)
    return np.column_stack([x, y, 3 * np.sin(x / 9) + rng.normal(0, 0.05, n)]) + offset


@pytest.mark.parametrize("k", [1, 8, 20, 45])
@pytest.mark.parametrize("offset", [0.0, 3000.0])
def test_equals_scipy(k, offset):
    p = surface(20_000, offset=offset)
    idx, dist = machscan.knn_graph(p, k)
    d_ref, i_ref = cKDTree(p).query(p, k)
    i_ref, d_ref = i_ref.reshape(len(p), k), d_ref.reshape(len(p), k)
    np.testing.assert_array_equal(idx, i_ref)  # random coordinates: no ties
    np.testing.assert_allclose(dist, d_ref, rtol=0, atol=1e-9)


def test_equals_open3d_search():
    p = surface(20_000, seed=1)
    idx, dist = machscan.knn_graph(p, 16)
    nns = open3d.core.nns.NearestNeighborSearch(open3d.core.Tensor(p))
    nns.knn_index()
    i_ref, d2_ref = nns.knn_search(open3d.core.Tensor(p), 16)
    np.testing.assert_array_equal(idx, i_ref.numpy())
    np.testing.assert_allclose(dist**2, d2_ref.numpy(), rtol=1e-12, atol=1e-12)


def test_radius_pads_rows():
    p = surface(5_000, seed=2)
    idx, dist = machscan.knn_graph(p, 30, radius=1.0)
    tree = cKDTree(p)
    d_ref, i_ref = tree.query(p, 30, distance_upper_bound=1.0)
    # scipy keeps d <= bound; ours is strict like Open3D's hybrid search (no exact ties here).
    np.testing.assert_array_equal(idx, np.where(np.isinf(d_ref), -1, i_ref))
    np.testing.assert_array_equal(np.isinf(dist), np.isinf(d_ref))
    assert (idx == -1).any() and (idx[:, 0] == np.arange(len(p))).all()


def test_ties_by_index_on_a_grid():
    g = np.stack(np.meshgrid(np.arange(7.0), np.arange(5.0), [0.0]), -1).reshape(-1, 3)
    idx, _dist = machscan.knn_graph(g, 5)
    d_all = np.linalg.norm(g[:, None] - g[None], axis=2)
    expected = np.lexsort((np.broadcast_to(np.arange(len(g)), d_all.shape), d_all), axis=1)[:, :5]
    np.testing.assert_array_equal(idx, expected)


def test_small_and_bad_input():
    idx, dist = machscan.knn_graph(np.zeros((3, 3)), 3)
    assert idx.shape == (3, 3) and (dist == 0).all()
    assert machscan.knn_graph(np.zeros((0, 3)), 4)[0].shape == (0, 4)
    for kwargs, name in ((dict(k=-1), "k"), (dict(k=3, radius=0.0), "radius"), (dict(k=3, radius=np.nan), "radius")):
        with pytest.raises(ValueError, match=f"^{name}"):
            machscan.knn_graph(np.zeros((3, 3)), **kwargs)
    with pytest.raises(ValueError, match=r"^points"):
        machscan.knn_graph(np.full((3, 3), np.nan), 2)
