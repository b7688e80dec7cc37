"""machscan — on-machine measurement for five-axis machining.

From raw line-laser profiler frames and machine axis positions to workpiece points, and on to
answers: groove width and depth, contour error, part positioning, allowance, toolpaths.
Units are millimetres and radians throughout; points are ``(N, 3)`` float64 arrays and
transforms ``(4, 4)`` homogeneous float64 matrices.

The API is organised by domain, and the everyday names are also here at the top level:

- :mod:`machscan.io` — point, mesh and toolpath files;
- :mod:`machscan.interop` — Open3D and trimesh geometry to and from machscan's;
- :mod:`machscan.cloud` — filters, neighbors, normals, curvature, simplification, clustering;
- :mod:`machscan.kinematics` — frames and poses to points, machine chains, mount calibration;
- :mod:`machscan.scan` — the raw scan container and its files;
- :mod:`machscan.grooves` — the per-frame groove fit;
- :mod:`machscan.contours` — CAD polylines, contour matching and the contour error;
- :mod:`machscan.inspection` — the groove inspection workflow of paper 000;
- :mod:`machscan.registration` — ICP, coarse alignment, locating points, positioning, allowance;
- :mod:`machscan.deviation` — signed distances to the CAD mesh and their statistics per CAD face;
- :mod:`machscan.mesh` — surface meshes (Delaunay of a height field, closest points, insertion, geodesics);
- :mod:`machscan.matching` — isometric matching of a bent skin (mirror milling);
- :mod:`machscan.toolpath` — toolpath compensation onto the bent skin;
- :mod:`machscan.cad` — CAD contours from CSV and APT files;
- :mod:`machscan.dask` — the same on Dask arrays and many files, on a cluster (``machscan[dask]``);
- :mod:`machscan.synth` — synthetic scans and parts with exact ground truth;
- :mod:`machscan.plot` — figures (needs matplotlib);
- :func:`machscan.thread_limit` — how many threads the kernels use from the calling thread.
"""

import importlib as _importlib
import warnings as _warnings

from machscan import (
    cloud,
    contours,
    deviation,
    grooves,
    inspection,
    interop,
    io,
    kinematics,
    matching,
    mesh,
    registration,
    scan,
    toolpath,
)
from machscan._core import __version__
from machscan.cloud import (
    crop_box,
    estimate_normals,
    euclidean_clusters,
    knn_graph,
    nearest_neighbors,
    octree_simplify,
    point_spacing,
    principal_curvatures,
    random_downsample,
    remove_duplicates,
    remove_radius_outliers,
    remove_statistical_outliers,
    surface_variation,
    uniform_downsample,
    voxel_downsample,
)
from machscan.contours import ContourErrorResult, contour_error, match_contours, resample_polyline
from machscan.deviation import FaceStatistics, SignedDistances, signed_distances
from machscan.grooves import (
    FitCriteria,
    GrooveFits,
    GrooveModel,
    GrooveOptions,
    GrooveStatus,
    LevelledFrame,
    fit_grooves,
    level_groove_frame,
)
from machscan.inspection import ContourResult, Decomposition, GrooveReport, InspectionOptions, Tolerance, inspect_grooves
from machscan.io import CloudFile, FileFormatError, TriangleMesh, read_mesh, read_points, write_mesh, write_points
from machscan.kinematics import (
    SENTINEL,
    KinematicChain,
    MountCalibration,
    ab_mirror_support_points,
    ac_head_transforms,
    ac_table_rotate,
    calibrate_mount,
    calibrate_mount_sphere,
    interpolate_poses,
    profile_to_points,
    scan_to_wcs,
)
from machscan.matching import IsometricMatch, isometric_match
from machscan.mesh import (
    ClosestPoints,
    GeodesicSolver,
    InsertedPoints,
    closest_points,
    delaunay_xy,
    geodesic_distances,
    insert_points,
    sample_surface,
)
from machscan.registration import (
    BlankAlignment,
    EnvelopeFit,
    IcpCriteria,
    IcpResult,
    MeshFit,
    PositioningErrors,
    PositioningResult,
    align_blank,
    allowance,
    coarse_align,
    envelope_fit,
    fit_to_mesh,
    icp,
    locating_points,
    position_workpiece,
    positioning_errors,
)
from machscan.scan import Profiler, Scan, read_scan_csv, write_scan_csv
from machscan.threads import thread_limit
from machscan.toolpath import (
    BeadChain,
    CompensatedToolpath,
    GrindingPaths,
    RemovalCheck,
    RemovalModel,
    bead_chain,
    compensate_toolpath,
    grinding_paths,
    scallop_height,
    simulate_removal,
    step_over,
)

__all__ = [
    "SENTINEL",
    "BeadChain",
    "BlankAlignment",
    "ClosestPoints",
    "CloudFile",
    "CompensatedToolpath",
    "ContourErrorResult",
    "ContourResult",
    "Decomposition",
    "EnvelopeFit",
    "FaceStatistics",
    "FileFormatError",
    "FitCriteria",
    "GeodesicSolver",
    "GrindingPaths",
    "GrooveFits",
    "GrooveModel",
    "GrooveOptions",
    "GrooveReport",
    "GrooveStatus",
    "IcpCriteria",
    "IcpResult",
    "InsertedPoints",
    "InspectionOptions",
    "IsometricMatch",
    "KinematicChain",
    "LevelledFrame",
    "MeshFit",
    "MountCalibration",
    "PositioningErrors",
    "PositioningResult",
    "Profiler",
    "RemovalCheck",
    "RemovalModel",
    "Scan",
    "SignedDistances",
    "Tolerance",
    "TriangleMesh",
    "__version__",
    "ab_mirror_support_points",
    "ac_head_transforms",
    "ac_table_rotate",
    "align_blank",
    "allowance",
    "bead_chain",
    "cad",
    "calibrate_mount",
    "calibrate_mount_sphere",
    "closest_points",
    "cloud",
    "coarse_align",
    "compensate_toolpath",
    "contour_error",
    "contours",
    "crop_box",
    "delaunay_xy",
    "deviation",
    "envelope_fit",
    "estimate_normals",
    "euclidean_clusters",
    "fit_grooves",
    "fit_to_mesh",
    "geodesic_distances",
    "grinding_paths",
    "grooves",
    "icp",
    "insert_points",
    "inspect_grooves",
    "inspection",
    "interop",
    "interpolate_poses",
    "io",
    "isometric_match",
    "kinematics",
    "knn_graph",
    "level_groove_frame",
    "locating_points",
    "match_contours",
    "matching",
    "mesh",
    "nearest_neighbors",
    "octree_simplify",
    "plot",
    "point_spacing",
    "position_workpiece",
    "positioning_errors",
    "principal_curvatures",
    "profile_to_points",
    "random_downsample",
    "read_mesh",
    "read_points",
    "read_scan_csv",
    "registration",
    "remove_duplicates",
    "remove_radius_outliers",
    "remove_statistical_outliers",
    "resample_polyline",
    "sample_surface",
    "scallop_height",
    "scan",
    "scan_to_wcs",
    "signed_distances",
    "simulate_removal",
    "step_over",
    "surface_variation",
    "synth",
    "thread_limit",
    "toolpath",
    "uniform_downsample",
    "voxel_downsample",
    "write_mesh",
    "write_points",
    "write_scan_csv",
]

# Imported on first use: demos, tests and figures need them, a plant script does not (plot
# needs matplotlib, dask the optional dependencies machscan[dask]).
_LAZY = ("cad", "dask", "plot", "synth")

# Older spellings, kept importable with a DeprecationWarning that names the new one.
_RENAMED = {
    "statistical_outlier_removal": "remove_statistical_outliers",
    "radius_outlier_removal": "remove_radius_outliers",
    "ContourError": "ContourErrorResult",
}


def __getattr__(name: str) -> object:
    if name in _LAZY:
        return _importlib.import_module(f"machscan.{name}")
    if name in _RENAMED:
        new = _RENAMED[name]
        _warnings.warn(f"machscan.{name} is now machscan.{new}", DeprecationWarning, stacklevel=2)
        return globals()[new]
    raise AttributeError(f"module 'machscan' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | set(_LAZY))
