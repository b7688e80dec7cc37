"""machscan — on-machine measurement for five-axis machining.

From raw line-laser profiler frames and machine axis positions to workpiece points, and on to
answers: groove width and depth, contour error, part positioning, allowance, toolpaths.
Units are millimetres and radians throughout; points are ``(N, 3)`` float64 arrays and
transforms ``(4, 4)`` homogeneous float64 matrices.
"""

from machscan._core import (
    KinematicChain,
    __version__,
    ab_mirror_support_points,
    ac_head_transforms,
    ac_table_rotate,
    crop_box,
    estimate_normals,
    euclidean_clusters,
    interpolate_poses,
    knn_graph,
    match_contours,
    nearest_neighbors,
    octree_simplify,
    principal_curvatures,
    profile_to_points,
    radius_outlier_removal,
    random_downsample,
    remove_duplicates,
    resample_polyline,
    scan_to_wcs,
    statistical_outlier_removal,
    surface_variation,
    uniform_downsample,
    voxel_downsample,
)
from machscan.contours import ContourError, contour_error
from machscan.grooves import GrooveFits, GrooveStatus, LevelledFrame, fit_grooves, level_groove_frame
from machscan.io import CloudFile, read_points, write_points
from machscan.inspection import ContourResult, Decomposition, GrooveReport, inspect_grooves
from machscan.kinematics import MountCalibration, calibrate_mount
from machscan.scan import Profiler, Scan, read_scan_csv, write_scan_csv

__all__ = [
    "__version__",
    "CloudFile",
    "ContourError",
    "ContourResult",
    "Decomposition",
    "GrooveFits",
    "GrooveReport",
    "GrooveStatus",
    "KinematicChain",
    "LevelledFrame",
    "MountCalibration",
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
    "io",
    "level_groove_frame",
    "knn_graph",
    "match_contours",
    "nearest_neighbors",
    "octree_simplify",
    "plot",
    "principal_curvatures",
    "profile_to_points",
    "radius_outlier_removal",
    "random_downsample",
    "read_points",
    "read_scan_csv",
    "remove_duplicates",
    "resample_polyline",
    "scan_to_wcs",
    "statistical_outlier_removal",
    "surface_variation",
    "synth",
    "uniform_downsample",
    "voxel_downsample",
    "write_points",
    "write_scan_csv",
]


def __getattr__(name: str) -> object:
    # `machscan.synth` and `machscan.plot` are imported on first use: demos, tests and figures
    # need them, a plant script does not (and plot needs matplotlib).
    if name in ("synth", "plot"):
        import importlib

        return importlib.import_module(f"machscan.{name}")
    raise AttributeError(f"module 'machscan' has no attribute {name!r}")
