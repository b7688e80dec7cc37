"""The public surface: submodules by domain with the everyday names at the top level, one
spelling, one argument order for filters, one rule for neighbor counts, older names kept."""

import inspect
import re
import warnings

import numpy as np
import pytest

import machscan

SUBMODULES = ["io", "interop", "cloud", "kinematics", "scan", "grooves", "contours", "inspection", "cad", "synth", "plot"]

# Names the README and the issues use at the top level: they stay importable there.
TOP_LEVEL = [
    "KinematicChain",
    "Profiler",
    "Scan",
    "ab_mirror_support_points",
    "ac_head_transforms",
    "ac_table_rotate",
    "calibrate_mount",
    "contour_error",
    "crop_box",
    "estimate_normals",
    "euclidean_clusters",
    "fit_grooves",
    "inspect_grooves",
    "interpolate_poses",
    "knn_graph",
    "level_groove_frame",
    "match_contours",
    "nearest_neighbors",
    "octree_simplify",
    "point_spacing",
    "sample_surface",
    "principal_curvatures",
    "profile_to_points",
    "random_downsample",
    "read_points",
    "read_scan_csv",
    "remove_duplicates",
    "resample_polyline",
    "scan_to_wcs",
    "surface_variation",
    "uniform_downsample",
    "voxel_downsample",
    "write_points",
    "write_scan_csv",
    "io",
    "synth",
    "plot",
    "cad",
    "remove_statistical_outliers",
    "remove_radius_outliers",
    "read_mesh",
    "write_mesh",
]


def test_submodules_and_top_level_names():
    for m in SUBMODULES:
        assert m in dir(machscan), m
        assert getattr(machscan, m).__name__ == f"machscan.{m}"
    for name in TOP_LEVEL:
        assert hasattr(machscan, name), name
    for name in machscan.__all__:
        assert hasattr(machscan, name), name
    # The everyday names are the submodules' own objects, not copies.
    assert machscan.voxel_downsample is machscan.cloud.voxel_downsample
    assert machscan.read_points is machscan.io.read_points
    assert machscan.fit_grooves is machscan.grooves.fit_grooves
    assert machscan.scan_to_wcs is machscan.kinematics.scan_to_wcs
    assert machscan.sample_surface is machscan.mesh.sample_surface


def test_older_names_still_work_and_say_the_new_one():
    p = np.random.default_rng(0).random((50, 3))
    for old, new in [
        ("statistical_outlier_removal", "remove_statistical_outliers"),
        ("radius_outlier_removal", "remove_radius_outliers"),
        ("ContourError", "ContourErrorResult"),
    ]:
        with pytest.warns(DeprecationWarning, match=new):
            assert getattr(machscan, old) is getattr(machscan, new)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        np.testing.assert_array_equal(
            machscan.statistical_outlier_removal(p, 5, 2.0), machscan.remove_statistical_outliers(p, 5, 2.0)
        )


def _names_and_parameters():
    for mod in [machscan] + [getattr(machscan, m) for m in SUBMODULES if m != "plot"]:
        for name in getattr(mod, "__all__", dir(mod)):
            obj = getattr(mod, name, None)
            yield f"{mod.__name__}.{name}"
            if callable(obj):
                try:
                    yield from (f"{name}({p})" for p in inspect.signature(obj).parameters)
                except (TypeError, ValueError):
                    pass
            if inspect.isclass(obj):
                yield from (f"{name}.{a}" for a in vars(obj) if not a.startswith("_"))
                yield from (f"{name}.{a}" for a in getattr(obj, "__dataclass_fields__", {}))


def test_one_spelling_the_ecosystems():
    british = re.compile(r"neighbour|centre|colour|normalis|serialis", re.IGNORECASE)
    bad = [n for n in _names_and_parameters() if british.search(n)]
    assert not bad, bad
    assert not any(
        isinstance(v, type) and issubclass(v, Exception) and not k.endswith("Error") for k, v in vars(machscan).items()
    )
    # A result is not named like an exception.
    assert not [n for n in machscan.__all__ if n.endswith("Error") and not issubclass(getattr(machscan, n), Exception)]


FILTERS = [
    "voxel_downsample",
    "remove_statistical_outliers",
    "remove_radius_outliers",
    "remove_duplicates",
    "crop_box",
    "random_downsample",
    "uniform_downsample",
    "octree_simplify",
    "estimate_normals",
    "surface_variation",
    "principal_curvatures",
    "knn_graph",
    "euclidean_clusters",
]


def test_every_filter_takes_the_cloud_first_and_returns_indices_into_it():
    p = np.random.default_rng(1).random((300, 3)) * 10
    for name in FILTERS:
        assert next(iter(inspect.signature(getattr(machscan, name)).parameters)) == "points", name
    for keep in (
        machscan.random_downsample(p, 40, seed=2),
        machscan.uniform_downsample(p, 7),
        machscan.remove_duplicates(p, 0.01),
        machscan.crop_box(p, (0, 0, 0), (5, 5, 5)),
    ):
        assert keep.dtype == np.int64 and (np.diff(keep) > 0).all() and keep.max() < len(p)
    assert len(machscan.random_downsample(p, 1000)) == 300


K_CALLS = {
    "remove_statistical_outliers": lambda p, k: machscan.remove_statistical_outliers(p, k, 2.0),
    "estimate_normals": lambda p, k: machscan.estimate_normals(p, k=k),
    "surface_variation": lambda p, k: machscan.surface_variation(p, k=k),
    "principal_curvatures": lambda p, k: machscan.principal_curvatures(p, k=k),
    "knn_graph": lambda p, k: machscan.knn_graph(p, k),
    "knn_graph hybrid": lambda p, k: machscan.knn_graph(p, k, radius=1.0),
    "euclidean_clusters": lambda p, k: machscan.euclidean_clusters(p, 1.0, k=k),
    "octree_simplify": lambda p, k: machscan.octree_simplify(p, 0.5, k=k),
}


@pytest.mark.parametrize("name", K_CALLS)
def test_k_too_large_or_zero_is_the_same_error_everywhere(name):
    p = np.random.default_rng(2).random((12, 3))
    call = K_CALLS[name]
    for k in (0, 13, 100):
        with pytest.raises(ValueError, match=r"^k: "):
            call(p, k)
    call(p, 6)  # within the cloud: fine
    empty = call(np.zeros((0, 3)), 6)  # an empty cloud gives an empty result
    assert all(len(a) == 0 for a in (empty if isinstance(empty, tuple) else (empty,)))
