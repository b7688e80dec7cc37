"""Count arguments (k, window, …) given a negative int raise ValueError naming the argument,
not pyo3's bare OverflowError."""

import numpy as np
import pytest

import machscan

P = np.random.default_rng(0).random((50, 3))
X = np.linspace(-1, 1, 64)
Z = np.zeros((2, 64))

CALLS = [
    ("k", lambda: machscan.remove_statistical_outliers(P, -1, 2.0)),
    ("min_neighbors", lambda: machscan.remove_radius_outliers(P, 0.5, -2)),
    ("count", lambda: machscan.random_downsample(P, -2)),
    ("seed", lambda: machscan.random_downsample(P, 2, seed=-1)),
    ("every_k", lambda: machscan.uniform_downsample(P, -1)),
    ("k", lambda: machscan.estimate_normals(P, k=-20)),
    ("k", lambda: machscan.surface_variation(P, k=-20)),
    ("k", lambda: machscan.principal_curvatures(P, k=-20)),
    ("k", lambda: machscan.octree_simplify(P, 0.1, k=-3)),
    ("eps1", lambda: machscan.octree_simplify(P, 0.1, eps1=-3)),
    ("refine", lambda: machscan.octree_simplify(P, 0.1, refine=-1)),
    ("refine", lambda: machscan.octree_simplify(P, 0.1, refine=41)),
    ("k", lambda: machscan.euclidean_clusters(P, 0.5, k=-1)),
    ("window", lambda: machscan.fit_grooves(X, Z, window=-10)),
    ("max_iterations", lambda: machscan.fit_grooves(X, Z, criteria=machscan.FitCriteria(max_iterations=-1))),
    ("min_valid", lambda: machscan.level_groove_frame(X, Z[0], min_valid=-1)),
    ("rotary", lambda: machscan.interpolate_poses([0.0, 1.0], [[0.0], [2.0]], [0.5], rotary=(-1,))),
]


@pytest.mark.parametrize("name, call", CALLS, ids=[f"{i}-{n}" for i, (n, _) in enumerate(CALLS)])
def test_negative_count_names_the_argument(name, call):
    with pytest.raises(ValueError) as exc:
        call()
    assert str(exc.value).startswith(name), str(exc.value)


def test_read_cloud_columns(tmp_path):
    path = tmp_path / "p.xyz"
    path.write_text("1 2 3\n4 5 6\n")
    with pytest.raises(ValueError, match=r"^columns"):
        machscan._core.read_cloud(path, columns=(0, -1, 2))
