"""Type stubs of the compiled core ``machscan._core`` (kept in step with ``crates/python/src/``;
checked by ``python -m mypy.stubtest machscan._core`` in the test command, and the docstrings by
``scripts/sync_stub_docs.py``).

Functions that hand back several arrays return a ``TypedDict`` declared here, whose keys the
Python layer's result classes take (``tests/test_seam.py`` checks they agree)."""

from os import PathLike
from typing import Any, Literal, Sequence, TypedDict, final, overload

from machscan.grooves import GrooveOptions

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "__version__",
    "SENTINEL",
    "ALLOWANCE_NEIGHBORS",
    "GRINDING_FEED_STEP",
    "ROUNDING_POOLED_FRAMES",
    "FileFormatError",
    "KinematicChain",
    "ab_mirror_support_points",
    "ac_head_transforms",
    "ac_table_rotate",
    "align_blank",
    "allowance",
    "calibrate_mount",
    "calibrate_mount_sphere",
    "closest_points",
    "signed_distances",
    "face_statistics",
    "coarse_align",
    "compensate_toolpath",
    "valid_readings",
    "contour_error",
    "crop_box",
    "delaunay_xy",
    "estimate_normals",
    "envelope_fit",
    "euclidean_clusters",
    "fit_criteria_defaults",
    "fit_grooves",
    "groove_defaults",
    "icp",
    "fit_to_mesh",
    "geodesic_distances",
    "GeodesicSolver",
    "icp_defaults",
    "insert_points",
    "interpolate_poses",
    "bead_chain",
    "grinding_paths",
    "removal_depths",
    "removal_feeds",
    "simulate_removal",
    "scallop_heights",
    "step_overs",
    "isometric_match",
    "locating_points_cloud",
    "locating_points_grid",
    "positioning_errors",
    "knn_graph",
    "match_contours",
    "nearest_neighbors",
    "octree_simplify",
    "point_spacing",
    "principal_curvatures",
    "probe_fit",
    "profile_to_points",
    "random_downsample",
    "read_cloud",
    "read_toolpath",
    "readable_formats",
    "remove_duplicates",
    "remove_radius_outliers",
    "remove_statistical_outliers",
    "resample_polyline",
    "scan_to_wcs",
    "set_thread_limit",
    "surface_variation",
    "uniform_downsample",
    "view_groove_frame",
    "voxel_downsample",
    "writable_formats",
    "write_cloud",
    "write_toolpath",
    "fit_bending_surface",
    "bending_surface_at",
    "read_table",
    "read_profiles",
    "voxel_origin",
    "voxel_keys",
]

__version__: str
SENTINEL: float
ALLOWANCE_NEIGHBORS: int
GRINDING_FEED_STEP: float
ROUNDING_POOLED_FRAMES: int

_Path = str | PathLike[str]
_F64 = NDArray[np.float64]
_I64 = NDArray[np.int64]

def set_thread_limit(threads: int) -> int:
    """Sets the number of threads the kernels called from this Python thread run on (0: all cores)
    and returns the previous setting; `machscan.thread_limit` is the public face. The kernels'
    results do not depend on it."""

class FileFormatError(ValueError):
    """A file's content does not follow its format (truncated data, a header that promises more than there is, a number that is not one, ...). A ``ValueError``; ``filename`` names the file."""

# ---- results ----------------------------------------------------------------------------------

class _IcpArrays(TypedDict):
    transformation: _F64
    fitness: float
    rmse: float
    correspondences: int
    iterations: int
    converged: bool
    history_fitness: _F64
    history_rmse: _F64

class _MeshFitArrays(TypedDict):
    transformation: _F64
    fitness: float
    rmse: float
    correspondences: int
    iterations: int
    converged: bool
    history_fitness: _F64
    history_rmse: _F64
    motion: list[float]
    undetermined: str

class _SphereCalibrationArrays(TypedDict):
    params: _F64
    sphere_center: _F64
    rms: float
    std_errors: _F64
    covariance: _F64
    residuals: _F64
    frame_index: _I64
    iterations: int
    converged: bool

class _ProbeFitArrays(TypedDict):
    transformation: _F64
    residuals: _F64
    iterations: int

class _EnvelopeFitArrays(TypedDict):
    transformation: _F64
    allowance: _F64
    feasible: bool
    iterations: int
    converged: bool

class _AlignmentStageArrays(TypedDict):
    name: str
    transformation: _F64
    fitness: float
    rmse: float
    allowance: _F64

class _BlankAlignmentArrays(TypedDict):
    stages: list[_AlignmentStageArrays]
    fit: _EnvelopeFitArrays

class _ClosestArrays(TypedDict):
    points: _F64
    distances: _F64
    triangles: _I64
    barycentric: _F64

class _SignedArrays(TypedDict):
    distances: _F64
    points: _F64
    triangles: _I64

class _FaceStatisticsArrays(TypedDict):
    face: _I64
    count: _I64
    min: _F64
    max: _F64
    mean: _F64
    std: _F64
    out_of_tolerance: _F64

class _ProfileArrays(TypedDict):
    layout: str
    x: _F64
    heights: _F64
    y: _F64 | None
    time: _F64 | None
    encoder: _F64 | None
    frame: _F64 | None
    x_resolution: float | None
    y_resolution: float | None
    model: str | None
    serial: str | None

class _InsertedArrays(TypedDict):
    vertices: _F64
    faces: _I64
    indices: _I64
    landings: list[Literal["vertex", "edge", "face"]]

class _IsometricMatchArrays(TypedDict):
    points: _F64
    locating: _F64
    objective: _F64
    max_error: _F64
    residuals: _F64
    iterations: int
    stop: Literal["tolerance", "step", "stalled", "max_iterations"]
    converged: bool

class _CompensatedArrays(TypedDict):
    points: _F64
    axes: _F64
    inside: NDArray[np.bool_]
    on_scan: NDArray[np.bool_]
    offsets: _F64

class _BeadChainArrays(TypedDict):
    order: _I64
    closed: bool

class _GrindingPathArrays(TypedDict):
    points: _F64
    normals: _F64
    row: _I64
    curvature: _F64
    allowance: _F64
    feed: _F64
    tool_fits: NDArray[np.bool_]
    row_offsets: _F64
    row_closed: NDArray[np.bool_]
    without_stock: int

class _RemovalArrays(TypedDict):
    deviation: _F64
    nearest: _I64

_RemovalArgs = tuple[float, tuple[float, float, float], float, float, tuple[float, float]]

class _IcpDefaults(TypedDict):
    method: Literal["point_to_point", "point_to_plane"]
    max_iterations: int
    relative_fitness: float
    relative_rmse: float
    mse_threshold: float | None
    robust: Literal["huber", "tukey"] | None
    trim: float
    normal_neighbors: int

class _MountCalibrationArrays(TypedDict):
    params: _F64
    rms: float
    std_errors: _F64
    covariance: _F64
    residuals: _F64
    iterations: int
    converged: bool

class _CloudArrays(TypedDict):
    points: _F64
    normals: _F64 | None
    scalars: dict[str, _F64]
    triangles: _I64
    dropped: int

class _ToolpathArrays(TypedDict):
    points: _F64
    axes: _F64
    feeds: _F64
    segments: _I64

class _GrooveFitArrays(TypedDict):
    x0: _F64
    z0: _F64
    depth: _F64
    width: _F64
    alpha: _F64
    rms: _F64
    se_depth: _F64
    se_width: _F64
    flank_angle_left: _F64
    flank_angle_right: _F64
    area: _F64
    bottom_radius: _F64
    step: _F64
    se_x0: _F64
    se_z0: _F64
    se_flank_angle_left: _F64
    se_flank_angle_right: _F64
    se_area: _F64
    se_bottom_radius: _F64
    se_step: _F64
    tilt: _F64
    iterations: NDArray[np.int32]
    n_used: NDArray[np.int32]
    status: NDArray[np.uint8]
    model: NDArray[np.uint8]
    groove: NDArray[np.int32]
    frame: NDArray[np.int32]
    rounding_prior: tuple[float, float] | None
    misfit: dict[str, float] | None

class _FrameViewArrays(TypedDict):
    x: _F64
    z: _F64
    shape_x: _F64
    shape_z: _F64
    tilt: float
    fit: _GrooveFitArrays

_Template = Literal["auto", "trapezoid", "v", "round", "u", "ellipse", "tanh"]
_Select = Literal["deepest", "left", "right", "nearest", "all"]

class _GrooveOptions(TypedDict):
    template: _Template
    alpha: float
    nominal_width: float
    window: int | None
    window_center: int | None
    fit_alpha: bool
    spike_threshold: float | None
    min_depth: float
    min_valid: int
    max_iterations: int | None
    cost_tolerance: float | None
    step_tolerance: float | None
    gradient_tolerance: float | None
    sentinel: float | None
    valid_range: tuple[float, float] | None
    select: _Select
    index: int
    near: float | None
    min_width: float | None
    max_width: float | None
    max_depth: float | None
    rounding: Literal["pooled", "frame"]
    misfit: Literal["pooled", "none"]

class _Criteria(TypedDict):
    max_iterations: int
    cost_tolerance: float
    step_tolerance: float
    gradient_tolerance: float

class _CriteriaDefaults(TypedDict):
    tanh: _Criteria
    section: _Criteria

class _ContourErrorArrays(TypedDict):
    offset: _F64
    errors: _F64
    deviations: _F64
    matched: _I64
    cases: NDArray[np.uint8]
    mean: float
    std: float
    max: float

class _TableArrays(TypedDict):
    values: _F64
    lines: _I64
    header: list[str] | None

class _BendingSurfaceArrays(TypedDict):
    degree: int
    exponents: _I64
    coefficients: _F64
    center: _F64
    scale: float
    rms_residual: float

# ---- kinematics -------------------------------------------------------------------------------

def valid_readings(
    readings: ArrayLike, *, valid_range: ArrayLike | None = None, sentinel: float | None = -99999.0
) -> NDArray[np.bool_]:
    """Which readings are valid (SPEC K1): finite, not the ``sentinel`` and inside
    ``valid_range``: the one rule of every function that takes frames; ``Profiler.valid_mask``
    documents it and reshapes the flat ``readings`` it hands over.
    """

def profile_to_points(
    frames: ArrayLike,
    pitch: float,
    *,
    center: float | None = None,
    valid_range: ArrayLike | None = None,
    sentinel: float | None = -99999.0,
) -> tuple[_F64, _I64]:
    """Profiler frames to points in the sensor coordinate system (SPEC K1, paper 000 eq 5).

    Reading ``i`` of a frame becomes the SCS point ``((i - center) * pitch, 0, d_i)``: the laser
    line runs along SCS x, ``d_i`` is a height along SCS z (out of the material). Invalid
    readings are dropped: NaN, the ``sentinel`` ("no reading" code, −99999 by default), and
    anything outside ``valid_range``.

    Parameters
    ----------
    frames : array_like, shape (F, N)
        Readings in mm, one frame per row.
    pitch : float
        Reading spacing along the line, mm.
    center : float, optional
        Index of the reading at SCS x = 0; default ``N / 2``.
    valid_range : (float, float), optional
        Measuring range ``(lo, hi)`` in mm; readings outside it are invalid.
    sentinel : float or None
        The profiler's "no reading" code, mm; default ``machscan.SENTINEL`` (−99999). None when
        the profiler writes NaN only (−99999 is then still no real height, so the default is safe).

    Returns
    -------
    points : ndarray, shape (M, 3)
        SCS points in mm, frame by frame, readings in order.
    frame_index : ndarray of int64, shape (M,)
        Frame of each point. ``frames.size - M`` readings were dropped.

    Examples
    --------
    >>> pts, idx = machscan.profile_to_points([[0.1, float("nan"), -99999.0, 0.3]], pitch=0.025)
    >>> pts.shape
    (2, 3)
    """
def scan_to_wcs(
    frames: ArrayLike,
    axes: ArrayLike,
    pitch: float,
    c2_offset: ArrayLike,
    mount: ArrayLike,
    *,
    center: float | None = None,
    valid_range: ArrayLike | None = None,
    sentinel: float | None = -99999.0,
) -> tuple[_F64, _I64]:
    """Frames and AC-head poses to workpiece (WCS) points in one parallel call (SPEC K1–K3, K7).

    Every valid reading of frame ``k`` is mapped by ``ac_head_transforms(axes)[k]``. The work is
    spread over all cores with the GIL released; the result is identical for any thread count.

    Parameters
    ----------
    frames : array_like, shape (F, N)
        Readings in mm.
    axes : array_like, shape (F, 6)
        X, Y, Z (mm), A, C, C2 (rad) at each frame.
    pitch : float
        Reading spacing, mm.
    c2_offset : array_like, shape (3,)
        (Lx, Ly, Lz) of the C2 axis from the tool tip, mm.
    mount : array_like, shape (6,)
        (theta, psi, phi, dx, dy, dz): mount Euler angles (rad) and translation (mm).
    center, valid_range, sentinel
        As in :func:`profile_to_points`: invalid readings (NaN, the sentinel −99999 by default,
        outside ``valid_range``) are dropped.

    Returns
    -------
    points : ndarray, shape (M, 3)
        WCS points, mm.
    frame_index : ndarray of int64, shape (M,)

    Examples
    --------
    >>> pts, idx = machscan.scan_to_wcs(frames, axes, 0.025, (0, 0, 150), (0, 0, 0, 30, 0, -100))
    """
def ac_head_transforms(axes: ArrayLike, c2_offset: ArrayLike, mount: ArrayLike) -> _F64:
    """WCS ← SCS transforms of the AC double-swing head with C2 and sensor mount (SPEC K2, K3).

    ``T = [Rz(C)·Rx(A), (X, Y, Z)] · [Rz(C2), (Lx, Ly, Lz)] · [Rz(phi)·Ry(theta)·Rx(psi), (dx, dy, dz)]``.
    The rotations are the proper ones; paper 000 prints eq (4) and eq (8) with sign errors.

    Parameters
    ----------
    axes : array_like, shape (F, 6)
        X, Y, Z (mm), A, C, C2 (rad) per frame.
    c2_offset : array_like, shape (3,)
        (Lx, Ly, Lz), mm.
    mount : array_like, shape (6,)
        (theta, psi, phi, dx, dy, dz), rad and mm.

    Returns
    -------
    ndarray, shape (F, 4, 4)

    Examples
    --------
    >>> T = machscan.ac_head_transforms([[0, 0, 0, 0, 0, 0]], (0, 0, 0), (0, 0, 0, 0, 0, 0))
    >>> T[0]  # identity
    """
def ab_mirror_support_points(tool_points: ArrayLike, axes: ArrayLike, lat: ArrayLike, lba: ArrayLike) -> _F64:
    """Tool points of the milling side to workpiece points of the mirror-milling support side
    (SPEC K5, paper 002 eq 1–6), each point with its own AB-head pose.

    Evaluates the chain ``p1 = p + Lat; p2 = Rx(A)·p1; p3 = p2 + Lba; p4 = Ry(B)·p3;
    p5 = p4 + (X, Y, Z) − Lba − Lat; W = (−p5x, p5y, −p5z)``, which is paper 002 eq (6).

    Parameters
    ----------
    tool_points : array_like, shape (N, 3)
        Points in the tool frame, mm.
    axes : array_like, shape (N, 5)
        X, Y, Z (mm), A, B (rad) for each point.
    lat, lba : array_like, shape (3,)
        Tool→A-axis and A→B-axis offsets, mm.

    Returns
    -------
    ndarray, shape (N, 3)
        Support-side points, mm.

    Examples
    --------
    >>> machscan.ab_mirror_support_points([[0, 0, 0]], [[0, 0, 0, 0, 0]], (0, 0, 200), (0, 0, 150))
    """
def ac_table_rotate(
    points: ArrayLike, normals: ArrayLike | None, a: float, c: float, center: ArrayLike
) -> tuple[_F64, _F64 | None]:
    """Turn CAD points and normals with an AC cradle table (SPEC K6, paper 003 eq 1).

    ``P' = Rx(a)·Rz(c)·(P − center) + center``, ``n' = Rx(a)·Rz(c)·n`` (C turns first, then A).

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Points, mm.
    normals : array_like, shape (N, 3) or None
        Normals (turned, not moved).
    a, c : float
        Table angles, rad.
    center : array_like, shape (3,)
        Rotation center in measurement coordinates ``t = O'_w − O_w``, mm.

    Returns
    -------
    points : ndarray, shape (N, 3)
    normals : ndarray, shape (N, 3) or None

    Examples
    --------
    >>> p, n = machscan.ac_table_rotate([[1, 0, 0]], [[0, 0, 1]], 0.0, np.pi / 2, (0, 0, 0))
    """
def interpolate_poses(
    sample_times: ArrayLike, samples: ArrayLike, frame_times: ArrayLike, *, rotary: Sequence[int] = (3, 4, 5)
) -> _F64:
    """Axis positions at frame times from CNC samples on their own clock (SPEC K7).

    Linear interpolation; rotary columns are unwrapped first (a C axis crossing ±π turns the
    short way). Frames outside the sampled time span raise: poses are never extrapolated.

    Parameters
    ----------
    sample_times : array_like, shape (S,)
        CNC sample times, s, strictly increasing.
    samples : array_like, shape (S, n_axes)
        Axis positions (mm, rad).
    frame_times : array_like, shape (F,)
        Profiler frame times on the same clock, s.
    rotary : sequence of int
        Columns holding rotary axes in rad; default (3, 4, 5), the A, C, C2 of X, Y, Z, A, C, C2.

    Returns
    -------
    ndarray, shape (F, n_axes)

    Examples
    --------
    >>> machscan.interpolate_poses([0.0, 1.0], [[0.0], [2.0]], [0.25], rotary=())
    array([[0.5]])
    """
def allowance(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    blank_points: ArrayLike,
    *,
    surface: Literal["stock", "quadric", "plane"],
    k: int | None,
    spacing: float | None,
) -> _F64:
    """Machining allowance (SPEC R7); ``machscan.allowance`` documents it (with the plane's default
    ``k``, ``ALLOWANCE_NEIGHBORS``).
    """

def coarse_align(source: ArrayLike, target: ArrayLike) -> _F64:
    """Coarse alignment (SPEC R3, paper 004): the rigid transform (4×4, applied to the source) that
    puts the source's principal frame (centroid and covariance axes) on the target's, trying the
    four proper sign choices of the axes and keeping the one whose moved source lies closest to
    the target. A start for :func:`machscan.icp` from any orientation, on a part without
    symmetry.

    Parameters
    ----------
    source, target : array_like, shape (N, 3), (M, 3)
        mm; at least 4 points each.

    Returns
    -------
    ndarray, shape (4, 4)

    Examples
    --------
    >>> init = machscan.coarse_align(measured, model)
    >>> r = machscan.icp(measured, model, 1.0, init)
    """

def locating_points_cloud(
    points: ArrayLike,
    *,
    m: int,
    keep: float,
    k: int,
    seed: int,
    normals: ArrayLike | None,
    pattern: Literal["random", "optimal"],
) -> _I64:
    """Probe points on the flattest share of a cloud (SPEC R4): surface variation over the k
    nearest points; ``machscan.locating_points`` documents it.
    """

def locating_points_grid(
    points: ArrayLike, *, m: int, keep: float, seed: int, normals: ArrayLike | None, pattern: Literal["random", "optimal"]
) -> _I64:
    """Probe points on the flattest share of a gridded scan ``(nu, nv, 3)`` (SPEC R4): U-direction
    line curvature; ``machscan.locating_points`` documents it.
    """

def positioning_errors(measured: ArrayLike, model_points: ArrayLike, *, model_normals: ArrayLike | None) -> _F64:
    """Positioning errors (SPEC R5); ``machscan.positioning_errors`` documents it and wraps the
    ``(N, 3)`` per-axis errors this returns.
    """

def closest_points(vertices: ArrayLike, faces: ArrayLike, queries: ArrayLike) -> _ClosestArrays:
    """Closest points on a triangle mesh (SPEC S2); ``machscan.closest_points`` documents it and
    wraps the ``_ClosestArrays`` this returns.
    """

def signed_distances(points: ArrayLike, vertices: ArrayLike, triangles: ArrayLike) -> _SignedArrays:
    """Signed distances to a triangle mesh; ``machscan.signed_distances`` documents it and wraps
    the arrays this returns.
    """

def face_statistics(
    distances: ArrayLike, faces: ArrayLike, *, count: int, lower: float, upper: float
) -> _FaceStatisticsArrays:
    """Per-face statistics of signed distances; ``machscan.SignedDistances.statistics`` documents
    it.
    """

def insert_points(vertices: ArrayLike, faces: ArrayLike, points: ArrayLike, *, tolerance: float) -> _InsertedArrays:
    """Points inserted into a mesh as vertices (SPEC S2); ``machscan.insert_points`` documents it
    and wraps the ``_InsertedArrays`` this returns.
    """

def geodesic_distances(vertices: ArrayLike, faces: ArrayLike, sources: Sequence[int], *, method: str) -> _F64:
    """Geodesic distances (SPEC S3); ``machscan.geodesic_distances`` documents it."""

@final
class GeodesicSolver:
    """A mesh prepared once for geodesic distances (SPEC S3); ``machscan.GeodesicSolver``
    documents it."""

    def __new__(cls, vertices: ArrayLike, faces: ArrayLike, *, method: str) -> GeodesicSolver: ...
    @property
    def method(self) -> str:
        """The method, ``"exact"``, ``"fmm"`` or ``"heat"``."""
    @property
    def vertex_count(self) -> int:
        """The number of vertices (the length of each row of ``distances``)."""
    def distances(self, sources: Sequence[int]) -> _F64:
        """Distances from each source vertex to every vertex → ``(S, V)``."""

def isometric_match(
    theoretical_points: ArrayLike,
    theoretical_faces: ArrayLike | None,
    actual_points: ArrayLike,
    actual_faces: ArrayLike | None,
    theoretical_locating: ArrayLike,
    actual_locating: ArrayLike,
    theoretical_matching: ArrayLike,
    actual_initial: ArrayLike | None,
    *,
    jacobian: str,
    method: str,
    spacing: float | str | None,
    max_edge: float | None,
    max_iterations: int,
    tolerance: float,
) -> _IsometricMatchArrays:
    """Isometric matching (SPEC S4); ``machscan.isometric_match`` documents it and wraps the
    ``_IsometricMatchArrays`` this returns.
    """

def compensate_toolpath(
    tool_points: ArrayLike,
    theoretical_matching: ArrayLike,
    actual_matching: ArrayLike,
    actual_points: ArrayLike,
    actual_faces: ArrayLike | None,
    *,
    interpolation: str,
    normals: str,
    radius: float | None,
    max_edge: float | None,
) -> _CompensatedArrays:
    """Toolpath compensation (SPEC S5); ``machscan.compensate_toolpath`` documents it and wraps the
    ``_CompensatedArrays`` this returns.
    """

def bead_chain(
    points: ArrayLike, start: ArrayLike | None, direction: ArrayLike | None, *, method: str
) -> _BeadChainArrays:
    """Bead-chain ordering (SPEC P2); ``machscan.bead_chain`` documents it and wraps the
    ``_BeadChainArrays`` this returns.
    """

def grinding_paths(
    points: ArrayLike,
    normals: ArrayLike,
    allowance: ArrayLike,
    *,
    tool_radius: float,
    scallop_height: float,
    section_normal: ArrayLike,
    thickness: float | None,
    spacing: float | None,
    tolerance: float | None,
    fit_radius: float | None,
    removal: _RemovalArgs | None,
    feed_step: float | None,
) -> _GrindingPathArrays:
    """Grinding paths (SPEC P1–P5); ``machscan.grinding_paths`` documents it and wraps the
    ``_GrindingPathArrays`` this returns.
    """

def removal_feeds(depths: ArrayLike, removal: _RemovalArgs) -> _F64:
    """Feeds removing the given depths under a removal model; ``machscan.RemovalModel.feed``."""

def removal_depths(feeds: ArrayLike, removal: _RemovalArgs) -> _F64:
    """Depths removed at the given feeds under a removal model; ``machscan.RemovalModel.removal``."""

def simulate_removal(
    points: ArrayLike,
    normals: ArrayLike,
    allowance: ArrayLike,
    path_points: ArrayLike,
    path_normals: ArrayLike,
    path_allowance: ArrayLike,
    path_row: Sequence[int] | NDArray[np.int64],
    depths: ArrayLike,
    *,
    tool_radius: float,
) -> _RemovalArrays:
    """Removal simulation (SPEC P5 beyond); ``machscan.simulate_removal`` documents it and wraps the
    ``_RemovalArrays`` this returns.
    """

def scallop_heights(tool_radius: ArrayLike, curvature_radius: ArrayLike, step: ArrayLike) -> _F64:
    """Scallop heights (SPEC P3); ``machscan.scallop_height`` documents it."""

def step_overs(tool_radius: ArrayLike, curvature_radius: ArrayLike, scallop_height: ArrayLike) -> _F64:
    """Step-overs (SPEC P3); ``machscan.step_over`` documents it."""

def delaunay_xy(points: ArrayLike, *, max_edge: float | None = None) -> _I64:
    """Delaunay triangulation of a surface seen from above (SPEC S1; paper 002 §3.1): the points'
    xy projection is triangulated (spade, exact predicates) and the triangles lifted back to 3D.
    For height-field surfaces such as a skin on the machine table.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        mm.
    max_edge : float, optional
        Leave out triangles with an edge longer than this in 3D, mm: the long thin triangles a
        concave outline leaves along its convex hull.

    Returns
    -------
    ndarray of int64, shape (M, 3)
        Triangles as indices into ``points``, counter-clockwise seen from +z. The same triangles
        as ``scipy.spatial.Delaunay(points[:, :2])`` for points in general position (with four
        or more on one circle, one of the valid triangulations).

    Raises
    ------
    ValueError
        Points not finite, all on one line in xy, or fewer than three distinct ones. Points with
        the same x and y as an earlier one are not an error: they are left out of every triangle
        (the first one is kept).

    Examples
    --------
    >>> faces = machscan.delaunay_xy(scan, max_edge=5.0)
    >>> machscan.write_mesh("skin.ply", scan, faces)
    """

def probe_fit(
    measured: ArrayLike, model_points: ArrayLike, model_normals: ArrayLike, *, probe_radius: float, init: ArrayLike | None
) -> _ProbeFitArrays:
    """The pose of a part from one round of touch-probe points (SPEC R6, paper 003 §4);
    ``machscan.position_workpiece`` runs the rounds and documents it.
    """

def envelope_fit(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    blank_points: ArrayLike,
    *,
    min_allowance: float,
    surface: Literal["stock", "quadric", "plane"],
    k: int | None,
    spacing: float | None,
    init: ArrayLike | None,
) -> _EnvelopeFitArrays:
    """The balanced envelope fit of a blank (SPEC R8); ``machscan.envelope_fit`` documents it."""

def align_blank(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    blank_points: ArrayLike,
    *,
    min_allowance: float,
    surface: Literal["stock", "quadric", "plane"],
    k: int | None,
    spacing: float | None,
    init: ArrayLike | None,
) -> _BlankAlignmentArrays:
    """The blank found from where a plant starts: coarse alignment, ICP, the envelope fit;
    ``machscan.align_blank`` documents it and wraps the ``_BlankAlignmentArrays`` this returns.
    """

def icp_defaults() -> _IcpDefaults:
    """The defaults of the ICP options (``IcpOptions::new`` in the core), by name."""

def icp(
    source: ArrayLike,
    target: ArrayLike,
    max_distance: float,
    *,
    init: ArrayLike | None,
    target_normals: ArrayLike | None,
    method: Literal["point_to_point", "point_to_plane"],
    max_iterations: int,
    relative_fitness: float,
    relative_rmse: float,
    robust: Literal["huber", "tukey"] | None,
    robust_scale: float | None,
    trim: float,
    mse_threshold: float | None,
) -> _IcpArrays:
    """Iterative closest point (SPEC R2) with Open3D's definitions; ``machscan.icp`` documents it
    and wraps the ``_IcpArrays`` this returns.
    """

def fit_to_mesh(
    points: ArrayLike,
    vertices: ArrayLike,
    triangles: ArrayLike,
    max_distance: float,
    *,
    init: ArrayLike | None,
    dof: str,
    axis_point: ArrayLike | None,
    axis_direction: ArrayLike | None,
    max_iterations: int,
    relative_fitness: float,
    relative_rmse: float,
) -> _MeshFitArrays:
    """The fit of a scan to a mesh in chosen motions; ``machscan.fit_to_mesh`` documents it and
    wraps the arrays this returns.
    """

def calibrate_mount_sphere(
    frames: ArrayLike,
    poses: ArrayLike,
    *,
    pitch: float,
    center: float | None,
    valid_range: ArrayLike | None,
    sentinel: float | None,
    c2_offset: ArrayLike,
    radius: float,
    mount: ArrayLike,
    sphere_center: ArrayLike | None,
) -> _SphereCalibrationArrays:
    """Sensor mount calibration with a reference sphere (SPEC K4 beyond);
    ``machscan.calibrate_mount_sphere`` documents it and wraps the arrays this returns.
    """

def calibrate_mount(
    scs_points: ArrayLike, wcs_points: ArrayLike, *, axes: ArrayLike | None = None, c2_offset: ArrayLike | None = None
) -> _MountCalibrationArrays:
    """Sensor mount calibration from SCS ↔ WCS correspondences (SPEC K4); the Python function
    ``machscan.calibrate_mount`` wraps the ``MountCalibrationArrays`` this returns.
    """
@final
class KinematicChain:
    """A machine model: a chain of elementary transforms mapping the last link (sensor, tool,
    part) into the WCS (SPEC K7).

    Parameters
    ----------
    steps : list of tuple
        Composed left to right, each one of
        ``("translate", (x, y, z))`` mm;
        ``("translate_axes", (ix, iy, iz))`` translation by pose columns (None for 0);
        ``("rotate", "x"|"y"|"z", angle)`` constant angle, rad;
        ``("rotate_axis", "x"|"y"|"z", column)`` angle from a pose column (index or axis name);
        ``("rotation", R)`` a constant 3×3 rotation; ``("mirror", (sx, sy, sz))`` with ±1.
    axis_names : list of str
        Names of the pose columns, e.g. ``["X", "Y", "Z", "A", "C"]``.

    Examples
    --------
    >>> head = machscan.KinematicChain.ac_head((0, 0, 150), (0, 0, 0, 30, 0, -100))
    >>> T = head.transforms(axes)          # (F, 4, 4)
    """
    def __new__(cls, steps: list[Any], axis_names: Sequence[str]) -> KinematicChain: ...
    @staticmethod
    def ac_head(c2_offset: ArrayLike, mount: ArrayLike) -> KinematicChain:
        """AC double-swing head with C2 and sensor mount (SPEC K2, K3); poses X, Y, Z, A, C, C2."""
    @staticmethod
    def ab_mirror_support(lat: ArrayLike, lba: ArrayLike) -> KinematicChain:
        """AB head, support side of mirror milling (SPEC K5); poses X, Y, Z, A, B."""
    @staticmethod
    def ac_table(center: ArrayLike) -> KinematicChain:
        """AC cradle table about ``center`` (SPEC K6); poses A, C."""
    @property
    def n_axes(self) -> int:
        """Number of pose columns."""
    @property
    def axis_names(self) -> list[str]:
        """Names of the pose columns."""
    def transforms(self, axes: ArrayLike) -> _F64:
        """4×4 transforms for poses ``axes (F, n_axes)`` → ``(F, 4, 4)``."""
    def transform_points(self, points: ArrayLike, axes: ArrayLike) -> _F64:
        """Points ``(N, 3)``, each with its own pose ``axes (N, n_axes)`` → ``(N, 3)``."""
    def transform_vectors(self, vectors: ArrayLike, axes: ArrayLike) -> _F64:
        """Directions or normals ``(N, 3)`` with poses ``(N, n_axes)``: turned, not moved."""
    def scan_points(
        self,
        frames: ArrayLike,
        axes: ArrayLike,
        pitch: float,
        *,
        center: float | None = None,
        valid_range: ArrayLike | None = None,
        sentinel: float | None = -99999.0,
    ) -> tuple[_F64, _I64]:
        """Frames ``(F, N)`` and poses ``(F, n_axes)`` → ``(points (M, 3), frame_index (M,))``.
        Invalid readings are dropped as in :func:`machscan.profile_to_points`.
        """

# ---- io ---------------------------------------------------------------------------------------

def read_profiles(path: _Path) -> _ProfileArrays:
    """A line-profiler export (Gocator CSV, Keyence height rows) as its arrays;
    ``machscan.io.read_profiles`` documents it and builds the ``Scan``.
    """

def read_table(
    path: _Path,
    *,
    name: str,
    delimiter: str | None = None,
    widths: Sequence[int] | None = None,
    nan_columns: Sequence[int] | None = None,
    max_rows: int | None = None,
) -> _TableArrays:
    """A numeric table (CSV, TSV, whitespace) by machscan's one set of rules (header, comments,
    encodings; see ``machscan.io.read_table``); the ``_TableArrays`` keys ``values`` (R, C),
    ``lines`` (R,) and ``header`` (list of str, or None).
    """
def read_cloud(
    path: _Path,
    *,
    delimiter: str | None = None,
    columns: tuple[int, int, int] = (0, 1, 2),
    apply_pose: bool = True,
) -> _CloudArrays:
    """Read a point or mesh file by its extension (see ``machscan.io.read``); returns the
    ``CloudArrays`` ``points``, ``normals`` (or None), ``scalars`` and ``triangles``.
    """
def write_cloud(
    path: _Path,
    points: ArrayLike,
    *,
    normals: ArrayLike | None = None,
    scalars: dict[str, ArrayLike] | None = None,
    triangles: ArrayLike | None = None,
    binary: bool | None = None,
    compressed: bool = False,
    dtype: Literal["float32", "float64"] | None = None,
    scale: float | None = None,
) -> None:
    """Write points, optional normals, named scalars and triangles by the file's extension (see
    ``machscan.io.write_points`` and ``machscan.io.write_mesh``). ``binary``, ``dtype``: None
    for the format's default.
    """
def readable_formats() -> list[str]:
    """The extensions ``machscan.io.read`` reads, e.g. ``("ply", "pcd", ...)``."""
def writable_formats() -> list[str]:
    """The extensions ``machscan.io.write_points`` and ``write_mesh`` write."""
def read_toolpath(path: _Path) -> _ToolpathArrays:
    """Read an APT/CL toolpath: GOTO points, tool axes, feeds and segments (a new segment after every
    RAPID); ``machscan.io.read_toolpath`` wraps the ``ToolpathArrays`` this returns.
    """
def write_toolpath(
    path: _Path,
    points: ArrayLike,
    *,
    axes: ArrayLike | None = None,
    feeds: ArrayLike | None = None,
    segments: ArrayLike | None = None,
) -> None:
    """Write an APT/CL toolpath (``GOTO/x,y,z[,i,j,k]``, ``FEDRAT`` when the feed changes,
    ``RAPID`` between segments); ``machscan.io.write_toolpath`` documents it.
    """

# ---- grooves ----------------------------------------------------------------------------------

def groove_defaults() -> _GrooveOptions:
    """The defaults of the groove options (``GrooveOptions::default()`` in the core), by name; the
    fit criteria are None (each method's own), whose values ``fit_criteria_defaults`` gives.
    """
def fit_criteria_defaults() -> _CriteriaDefaults:
    """The fit criteria each method uses when they are left at None: ``{"tanh": {...},
    "section": {...}}`` with ``max_iterations``, ``cost_tolerance``, ``step_tolerance``,
    ``gradient_tolerance``.
    """
def fit_grooves(x: ArrayLike, z: ArrayLike, options: GrooveOptions) -> _GrooveFitArrays:
    """Measure the groove of every frame (SPEC G); ``machscan.fit_grooves`` documents it and wraps
    the ``_GrooveFitArrays`` this returns.
    """
def view_groove_frame(x: ArrayLike, z: ArrayLike, options: GrooveOptions) -> _FrameViewArrays:
    """One frame as the fit sees it: the levelled readings ``x``, ``z``, the fitted shape
    ``shape_x``, ``shape_z`` (evaluated here, so figures draw exactly what was fitted), the
    ``tilt`` and the fit of that frame (``_GrooveFitArrays`` of length 1);
    ``machscan.level_groove_frame`` wraps the ``_FrameViewArrays`` this returns.
    """

# ---- spatial and contours ---------------------------------------------------------------------

def euclidean_clusters(points: ArrayLike, radius: float, *, k: int | None = None) -> _I64:
    """Euclidean clustering (SPEC C1, paper 000 §2.2): points closer than ``radius`` share a cluster.

    Clusters are the connected components of the neighbor graph: every neighbor within
    ``radius`` (the same partition as Open3D's ``cluster_dbscan(eps=radius, min_points=1)``), or
    with ``k`` the paper's form, the k nearest other points within ``radius`` (made symmetric so
    the result does not depend on the seed order). Memory is O(N); queries run in parallel.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Points, mm.
    radius : float
        Neighbor distance threshold, mm (paper: 5 mm).
    k : int, optional
        Number of nearest other points considered (paper: 5), 1 ≤ k ≤ N − 1; default all
        within ``radius``.

    Returns
    -------
    ndarray of int64, shape (N,)
        Cluster of every point, 0..n_clusters−1, numbered in the order of their first point.

    Examples
    --------
    >>> labels = machscan.euclidean_clusters(centers, radius=5.0, k=5)
    """
def nearest_neighbors(points: ArrayLike, queries: ArrayLike) -> tuple[_I64, _F64]:
    """Nearest point of ``points`` for every query (kd-tree, parallel over queries).

    Parameters
    ----------
    points : array_like, shape (N, 3)
        The cloud searched, mm.
    queries : array_like, shape (M, 3)
        Query points, mm.

    Returns
    -------
    index : ndarray of int64, shape (M,)
    distance : ndarray, shape (M,)
        Euclidean distance, mm.

    Examples
    --------
    >>> idx, dist = machscan.nearest_neighbors(model, measured)
    """
def knn_graph(points: ArrayLike, k: int, *, radius: float | None = None) -> tuple[_I64, _F64]:
    """The k nearest points of every point of a cloud (its k-nearest graph), the point itself
    included and first unless an exact duplicate with a lower index precedes it; nearest first,
    ties by index. With ``radius`` only neighbors strictly closer than it (Open3D's hybrid
    search), the rows padded with index −1 and distance ``inf``.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        mm.
    k : int
        Neighbors per point, 1 ≤ k ≤ N (the point counts as its own neighbor).
    radius : float, optional
        mm.

    Returns
    -------
    index : ndarray of int64, shape (N, k)
    distance : ndarray, shape (N, k)
        Euclidean distance, mm.

    Examples
    --------
    >>> idx, dist = machscan.knn_graph(pts, k=20)
    >>> spacing = np.median(dist[:, 1])
    """
def contour_error(
    theoretical: ArrayLike, actual: ArrayLike, *, delta1: float = 1.0, delta2: float = 1.0
) -> _ContourErrorArrays:
    """Contour error of one contour (SPEC C3–C5); ``machscan.contour_error`` wraps the
    ``ContourErrorArrays`` this returns.
    """
def resample_polyline(vertices: ArrayLike, spacing: float, *, closed: bool = True) -> _F64:
    """Points along a polyline every ``spacing`` mm at most (equal steps over the whole polyline),
    ``(M, 3)``.

    Parameters
    ----------
    vertices : array_like, shape (n, 3)
        Polyline vertices, mm.
    spacing : float
        Largest distance between consecutive points, mm.
    closed : bool
        Add the segment from the last vertex back to the first.

    Examples
    --------
    >>> pts = machscan.resample_polyline(cad_vertices, spacing=0.5, closed=True)
    """
def match_contours(
    actual_centroids: ArrayLike, theoretical_centroids: ArrayLike, *, max_distance: float | None = None
) -> _I64:
    """Match actual contour centroids to theoretical ones one to one (minimal summed distance);
    ``(n_actual,)`` indices into the theoretical centroids, −1 where none lies within
    ``max_distance`` mm (``None``: no limit).

    Examples
    --------
    >>> idx = machscan.match_contours(actual_centroids, cad_centroids, max_distance=10.0)
    """

def fit_bending_surface(x: ArrayLike, y: ArrayLike, dz: ArrayLike, *, degree: int) -> _BendingSurfaceArrays:
    """The bending surface of the error decomposition (SPEC C6), fitted in the core; the
    ``_BendingSurfaceArrays`` keys (private: ``inspect_grooves`` wraps it in ``Decomposition``).
    """
def bending_surface_at(
    exponents: ArrayLike, coefficients: ArrayLike, center: ArrayLike, scale: float, x: ArrayLike, y: ArrayLike
) -> _F64:
    """B(x, y) of a bending surface from ``fit_bending_surface``'s arrays, mm (private)."""

# ---- cloud ------------------------------------------------------------------------------------

def voxel_origin(lo: ArrayLike, hi: ArrayLike, *, voxel_size: float) -> _F64:
    """The voxel grid's origin over the bounds ``lo``, ``hi`` (mm), checked to fit the keys:
    machscan.dask places its chunks' voxels with the in-memory grid (private).
    """
def voxel_keys(points: ArrayLike, origin: ArrayLike, *, voxel_size: float) -> tuple[_I64, _I64]:
    """The voxel keys and (i, j, k) indices of points within the grid of ``origin`` (from
    ``voxel_origin``), as ``voxel_downsample`` keys them (private).
    """

@overload
def voxel_downsample(points: ArrayLike, voxel_size: float, *, return_index: Literal[False] = False) -> _F64:
    """Voxel grid: every occupied voxel replaced by the centroid of its points (Open3D's
    ``voxel_down_sample``: origin at the minimum bound less half a voxel, centroids summed in
    point order, so the centroids are bit-identical). Voxels come in the order of their first
    point; keys are 64-bit and relative to the minimum bound (no precision loss far from the
    origin).

    Parameters
    ----------
    points : array_like, shape (N, 3)
        mm.
    voxel_size : float
        Voxel edge, mm.
    return_index : bool
        Also return the voxel of every input point.

    Returns
    -------
    centroids : ndarray (M, 3)
    voxel_of_point : ndarray of int64 (N,), only with ``return_index``

    Examples
    --------
    >>> c = machscan.voxel_downsample(pts, 0.5)
    """
@overload
def voxel_downsample(points: ArrayLike, voxel_size: float, *, return_index: Literal[True]) -> tuple[_F64, _I64]:
    """Voxel grid: every occupied voxel replaced by the centroid of its points (Open3D's
    ``voxel_down_sample``: origin at the minimum bound less half a voxel, centroids summed in
    point order, so the centroids are bit-identical). Voxels come in the order of their first
    point; keys are 64-bit and relative to the minimum bound (no precision loss far from the
    origin).

    Parameters
    ----------
    points : array_like, shape (N, 3)
        mm.
    voxel_size : float
        Voxel edge, mm.
    return_index : bool
        Also return the voxel of every input point.

    Returns
    -------
    centroids : ndarray (M, 3)
    voxel_of_point : ndarray of int64 (N,), only with ``return_index``

    Examples
    --------
    >>> c = machscan.voxel_downsample(pts, 0.5)
    """
def remove_statistical_outliers(points: ArrayLike, k: int, std_ratio: float) -> _I64:
    """Statistical outlier removal (Open3D's ``remove_statistical_outlier(nb_neighbors=k,
    std_ratio)``): the mean distance of each point to its k nearest points (itself included);
    points whose mean is at least ``mean + std_ratio · std`` over the cloud are dropped
    (paper 004's "3σ" rule with ``std_ratio = 3``). ``k`` counts the point
    itself, 1 ≤ k ≤ N.

    Returns
    -------
    ndarray of int64: kept indices, ascending.

    Examples
    --------
    >>> keep = machscan.remove_statistical_outliers(pts, k=20, std_ratio=2.0)
    """
def remove_radius_outliers(points: ArrayLike, radius: float, min_neighbors: int) -> _I64:
    """Radius outlier removal (Open3D's ``remove_radius_outlier(nb_points=min_neighbors,
    radius)``): a point is kept when more than ``min_neighbors`` points, itself included, lie
    strictly closer than ``radius`` mm.

    Returns
    -------
    ndarray of int64: kept indices, ascending.

    Examples
    --------
    >>> keep = machscan.remove_radius_outliers(pts, radius=0.5, min_neighbors=5)
    """
def remove_duplicates(points: ArrayLike, tolerance: float) -> _I64:
    """Duplicate-point removal (paper 004): in point order, each point not yet removed removes every
    other point within ``tolerance`` mm; removed points never remove others, so chains of close
    points do not open holes. Returns the kept indices, ascending.
    """
def point_spacing(points: ArrayLike) -> float:
    """The cloud's point spacing, mm, as :func:`machscan.allowance` estimates a blank's by default:
    the median over up to 20,000 points of r₈·√(π/9), r₈ the distance to the 8th other point
    (nine points in a disc of radius r₈ at a density of 1/s²); within 1 % through 30 % jitter.
    A scan of lines much farther apart than their points reads the spacing along the lines.

    Examples
    --------
    >>> s = machscan.point_spacing(blank)
    """
def crop_box(points: ArrayLike, min_bound: ArrayLike, max_bound: ArrayLike) -> _I64:
    """Indices of the points inside the box ``[min_bound, max_bound]`` (bounds included): crop box /
    pass-through filter (a pass-through on one axis is a box infinite on the others).
    """
def random_downsample(points: ArrayLike, count: int, *, seed: int = 0) -> _I64:
    """``count`` points of ``points`` drawn at random without replacement, reproducibly from
    ``seed``; ascending indices (all of them when ``count`` ≥ N).

    Examples
    --------
    >>> keep = machscan.random_downsample(pts, 10_000, seed=1)
    """
def uniform_downsample(points: ArrayLike, every_k: int) -> _I64:
    """Every ``every_k``-th point of ``points`` from the first (Open3D's ``uniform_down_sample``);
    ascending indices.

    Examples
    --------
    >>> keep = machscan.uniform_downsample(pts, 5)
    """
def estimate_normals(
    points: ArrayLike,
    *,
    k: int = 20,
    radius: float | None = None,
    towards: ArrayLike | None = None,
    along: ArrayLike | None = None,
    consistent: bool = False,
) -> _F64:
    """PCA normals (SPEC F): the eigenvector of the smallest eigenvalue of each point's
    neighborhood covariance — the k nearest points, the point itself included (Open3D's
    ``KDTreeSearchParamKNN(k)``), or with ``radius`` the nearest ``k`` strictly closer than it
    (``KDTreeSearchParamHybrid(radius, k)``). Unit length.

    Orientation (at most one): ``towards`` a viewpoint (n·(v − p) ≥ 0), ``along`` a direction
    (n·d ≥ 0), or ``consistent=True``: propagation over a minimum spanning tree of the k-nearest
    graph from the highest point, turned to +z (Hoppe et al. 1992). Without one the sign is the
    solver's. A point with fewer than 3 neighbors gets (0, 0, 1), as in Open3D.

    Examples
    --------
    >>> n = machscan.estimate_normals(pts, k=20, towards=(0, 0, 500))
    """
def surface_variation(points: ArrayLike, *, k: int = 20, radius: float | None = None) -> _F64:
    """Surface variation λ0 / (λ0 + λ1 + λ2) of each point's neighborhood covariance (0 on a
    plane, up to 1/3 for isotropic scatter); neighborhoods as in :func:`estimate_normals`.
    """
def principal_curvatures(
    points: ArrayLike, normals: ArrayLike | None = None, *, k: int = 20, radius: float | None = None
) -> tuple[_F64, _F64]:
    """Principal curvatures and directions from a local quadric fit (SPEC F).

    In each point's frame (tangents u, v; normal n) the neighbors are fitted by
    ``h = a u² + b uv + c v² + d u + e v + f``; the shape operator at the point gives
    ``k1 ≥ k2`` (1/mm) and their directions. Signs follow the normals: positive where the
    surface bends towards the normal (a sphere with outward normals: −1/R). ``normals`` default
    to :func:`estimate_normals` with the same neighborhood. Points with fewer than 6
    neighbors get NaN.

    Returns
    -------
    curvatures : ndarray (N, 2)
        k1, k2 in 1/mm.
    directions : ndarray (N, 2, 3)
        Unit principal directions.

    Examples
    --------
    >>> k, d = machscan.principal_curvatures(pts, k=30)
    """
def octree_simplify(
    points: ArrayLike,
    d_min: float,
    *,
    normals: ArrayLike | None = None,
    k: int = 10,
    eps1: int | None = None,
    eps2: int | None = None,
    neighbors: Literal["xyz", "xy"] = "xyz",
    refine: int = 0,
    feature_threshold: float = 0.05,
) -> _I64:
    """Octree simplification keeping features and the boundary (SPEC F, paper 002 §2).

    Cube of edge L (the largest extent) on the minimum corner, depth ⌈log2(L/d_min)⌉; each
    occupied leaf keeps its point of largest feature degree (mean angle between its normal and
    its ``k`` neighbors' normals, unoriented) and its point nearest the cell center; the x–y
    boundary points are kept by the paper's group rule (sorted by x, groups of ``eps1`` keep
    min-y and max-y; sorted by y, groups of ``eps2`` keep min-x and max-x). ``eps1``/``eps2``
    default to the number of points in a strip ``d_min`` wide.

    Beyond the paper (off by default): ``neighbors="xy"`` takes the neighbors of the normals
    and the feature degree in the x–y projection, so both sides of a vertical step see each
    other (height-field scans); ``refine=r`` splits every leaf whose largest feature degree
    exceeds ``feature_threshold`` r levels deeper, each occupied sub-cell keeping its own two
    points. On a pocket plate with 3 mm steps the paper's rule rebuilds a worse surface than a
    voxel grid of the same point count; ``neighbors="xy", refine=2`` a better one
    (tests/test_octree.py, figures in BENCHMARKS.md).

    Parameters
    ----------
    points : array_like (N, 3)
        mm; z is the cutting depth direction.
    d_min : float
        Smallest cell edge, mm.
    normals : array_like (N, 3), optional
        Default: :func:`estimate_normals` with ``k``.
    k : int
        Neighbors of the feature degree.
    eps1, eps2 : int, optional
    neighbors : {"xyz", "xy"}
    refine : int
        Extra octree levels on feature leaves (0: the paper's rule).
    feature_threshold : float
        Radians; a leaf is a feature leaf when its largest feature degree exceeds it. The
        default 0.05 (about 3°) is some 4× the 99th percentile of the feature degree of a flat
        scan with 3 µm noise at 0.25 mm spacing; raise it for noisier scans.

    Returns
    -------
    ndarray of int64: kept indices, sorted and unique.

    Examples
    --------
    >>> keep = machscan.octree_simplify(pts, d_min=2.0)
    """
