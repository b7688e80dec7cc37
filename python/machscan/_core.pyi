"""Type stubs of the compiled core ``machscan._core`` (kept in step with ``src/python/``;
checked by ``python -m mypy.stubtest machscan._core`` in the test command)."""

from os import PathLike
from typing import Any, Sequence, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "__version__",
    "KinematicChain",
    "ab_mirror_support_points",
    "ac_head_transforms",
    "ac_table_rotate",
    "calibrate_mount",
    "contour_error",
    "crop_box",
    "estimate_normals",
    "euclidean_clusters",
    "fit_grooves",
    "interpolate_poses",
    "level_groove_frame",
    "match_contours",
    "nearest_neighbors",
    "octree_simplify",
    "principal_curvatures",
    "profile_to_points",
    "radius_outlier_removal",
    "random_downsample",
    "read_cloud",
    "read_toolpath",
    "remove_duplicates",
    "resample_polyline",
    "scan_to_wcs",
    "statistical_outlier_removal",
    "surface_variation",
    "uniform_downsample",
    "voxel_downsample",
    "write_points",
    "write_toolpath",
]

__version__: str

def profile_to_points(
    frames: ArrayLike,
    pitch: float,
    center: float | None = None,
    valid_range: ArrayLike | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Profiler frames to points in the sensor coordinate system (SPEC K1, paper 000 eq 5).

    Reading ``i`` of a frame becomes the SCS point ``((i - center) * pitch, 0, d_i)``: the laser
    line runs along SCS x, ``d_i`` is a height along SCS z (out of the material). Invalid
    readings (NaN, the vendor sentinel, anything outside ``valid_range``) are dropped.

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

    Returns
    -------
    points : ndarray, shape (M, 3)
        SCS points in mm, frame by frame, readings in order.
    frame_index : ndarray of int64, shape (M,)
        Frame of each point. ``frames.size - M`` readings were dropped.
    """

def scan_to_wcs(
    frames: ArrayLike,
    axes: ArrayLike,
    pitch: float,
    c2_offset: ArrayLike,
    mount: ArrayLike,
    center: float | None = None,
    valid_range: ArrayLike | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Frames and AC-head poses to workpiece (WCS) points in one parallel call (SPEC K1–K3, K7).

    Every valid reading of frame ``k`` is mapped by ``ac_head_transforms(axes)[k]``; the GIL is
    released and the result is identical for any thread count. ``axes (F, 6)``: X, Y, Z (mm),
    A, C, C2 (rad); ``c2_offset`` (Lx, Ly, Lz) mm; ``mount`` (theta, psi, phi, dx, dy, dz).
    Returns ``(points (M, 3) WCS mm, frame_index (M,))``.
    """

def ac_head_transforms(axes: ArrayLike, c2_offset: ArrayLike, mount: ArrayLike) -> NDArray[np.float64]:
    """WCS ← SCS transforms ``(F, 4, 4)`` of the AC double-swing head with C2 and sensor mount.

    ``T = [Rz(C)·Rx(A), (X, Y, Z)] · [Rz(C2), (Lx, Ly, Lz)] · [Rz(phi)·Ry(theta)·Rx(psi), (dx, dy, dz)]``
    (SPEC K2, K3; paper 000 prints eq 4 and eq 8 with sign errors). ``axes (F, 6)``: X, Y, Z, A, C, C2.
    """

def ab_mirror_support_points(
    tool_points: ArrayLike, axes: ArrayLike, lat: ArrayLike, lba: ArrayLike
) -> NDArray[np.float64]:
    """Tool points ``(N, 3)`` to support-side workpiece points of mirror milling (paper 002 eq 6).

    ``axes (N, 5)``: X, Y, Z (mm), A, B (rad) per point; ``lat``, ``lba``: tool→A and A→B offsets, mm.
    """

def ac_table_rotate(
    points: ArrayLike, normals: ArrayLike | None, a: float, c: float, center: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Turn points and normals with an AC cradle table (paper 003 eq 1).

    ``P' = Rx(a)·Rz(c)·(P − center) + center``, ``n' = Rx(a)·Rz(c)·n``; angles in rad, mm.
    """

def interpolate_poses(
    sample_times: ArrayLike,
    samples: ArrayLike,
    frame_times: ArrayLike,
    rotary: Sequence[int] = ...,
) -> NDArray[np.float64]:
    """Axis positions ``(F, n_axes)`` at frame times from CNC samples on their own clock.

    Linear; rotary columns (default 3, 4, 5) unwrapped first; no extrapolation (ValueError).
    """

def calibrate_mount(
    scs_points: ArrayLike,
    wcs_points: ArrayLike,
    axes: ArrayLike | None = None,
    c2_offset: ArrayLike | None = None,
) -> dict[str, Any]:
    """Sensor mount calibration (SPEC K4); ``machscan.calibrate_mount`` wraps the dict it returns."""

def fit_grooves(
    x: ArrayLike,
    z: ArrayLike,
    alpha: float = 20.0,
    nominal_width: float = 0.5,
    window: int | None = None,
    window_center: int | None = None,
    fit_alpha: bool = False,
    spike_threshold: float | None = ...,
    min_depth: float = 0.03,
    min_valid: int = 12,
    max_iterations: int = 100,
    cost_tolerance: float = 0.0,
    step_tolerance: float = 1e-8,
    gradient_tolerance: float = 1e-13,
    template: str = "tanh",
) -> dict[str, Any]:
    """Fit the groove template to every frame (SPEC G); ``machscan.fit_grooves`` wraps the dict
    of per-frame arrays this returns in a result object."""

def level_groove_frame(
    x: ArrayLike,
    z: ArrayLike,
    alpha: float = 20.0,
    nominal_width: float = 0.5,
    window: int | None = None,
    window_center: int | None = None,
    spike_threshold: float | None = ...,
    min_depth: float = 0.03,
    min_valid: int = 12,
) -> dict[str, Any]:
    """One frame levelled as the fit sees it (SPEC G steps 1–4); ``machscan.level_groove_frame``
    wraps it. Returns a dict with the levelled ``x``, ``z`` (absolute levelled coordinates),
    ``tilt``, the initial guess ``start`` (x0, z0, d, w, α) and ``status`` (0 when ready)."""

def euclidean_clusters(points: ArrayLike, radius: float, k: int | None = None) -> NDArray[np.int64]:
    """Euclidean clustering (SPEC C1, paper 000 §2.2): points closer than ``radius`` share a cluster.

    Clusters are the connected components of the neighbour graph: every neighbour within
    ``radius`` (the same partition as Open3D's ``cluster_dbscan(eps=radius, min_points=1)``), or
    with ``k`` the paper's form, the k nearest within ``radius`` (made symmetric so the result
    does not depend on the seed order). Returns labels ``(N,)`` 0..n_clusters−1 numbered in the
    order of their first point. Memory O(N); queries in parallel.
    """

def nearest_neighbors(points: ArrayLike, queries: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """Nearest point of ``points (N, 3)`` for every query ``(M, 3)``: ``(index (M,), distance (M,))``, mm."""

def contour_error(theoretical: ArrayLike, actual: ArrayLike, delta1: float = 1.0, delta2: float = 1.0) -> dict[str, Any]:
    """Contour error of one contour (SPEC C3–C5); ``machscan.contour_error`` wraps the dict."""

def resample_polyline(vertices: ArrayLike, spacing: float, closed: bool = True) -> NDArray[np.float64]:
    """Points along a polyline ``(n, 3)`` every ``spacing`` mm (corners kept), ``(M, 3)``."""

def match_contours(
    actual_centroids: ArrayLike, theoretical_centroids: ArrayLike, max_distance: float = ...
) -> NDArray[np.int64]:
    """One-to-one matching of actual to theoretical contour centroids (minimal summed distance);
    indices into the theoretical centroids, −1 where none lies within ``max_distance`` mm."""

def read_cloud(
    path: str | PathLike[str], delimiter: str | None = None, columns: tuple[int, int, int] = ...
) -> dict[str, Any]:
    """Read a point cloud file (PLY, PCD, or XYZ/CSV/TXT/PTS text); ``machscan.io.read`` wraps the
    dict this returns (``points``, ``normals``, ``scalars``, ``triangles``)."""

def read_toolpath(path: str | PathLike[str]) -> dict[str, Any]:
    """Read an APT/CL toolpath (points, axes, feeds, segments); ``machscan.io.read_toolpath`` wraps it."""

def write_toolpath(
    path: str | PathLike[str],
    points: ArrayLike,
    axes: ArrayLike | None = None,
    feeds: ArrayLike | None = None,
    segments: ArrayLike | None = None,
) -> None:
    """Write an APT/CL toolpath (GOTO per point, FEDRAT on feed changes, RAPID between segments)."""

def write_points(
    path: str | PathLike[str],
    points: ArrayLike,
    normals: ArrayLike | None = None,
    scalars: dict[str, ArrayLike] | None = None,
    binary: bool = True,
    compressed: bool = False,
) -> None:
    """Write points (mm), optional normals and named scalars to ``.ply``, ``.pcd`` (``compressed``:
    binary_compressed) or x, y, z to ``.xyz``/``.csv``/``.txt``/``.pts``."""

def voxel_downsample(points: ArrayLike, voxel_size: float, return_index: bool = False) -> Any:
    """Voxel grid (Open3D's ``voxel_down_sample`` definition, bit-identical centroids); voxels in
    the order of their first point. Returns ``centroids (M, 3)``, or ``(centroids,
    voxel_of_point (N,))`` with ``return_index``."""

def statistical_outlier_removal(points: ArrayLike, k: int, std_ratio: float) -> NDArray[np.int64]:
    """Kept indices of Open3D's ``remove_statistical_outlier(nb_neighbors=k, std_ratio)``."""

def radius_outlier_removal(points: ArrayLike, radius: float, min_neighbors: int) -> NDArray[np.int64]:
    """Kept indices of Open3D's ``remove_radius_outlier(nb_points=min_neighbors, radius)``."""

def remove_duplicates(points: ArrayLike, tolerance: float) -> NDArray[np.int64]:
    """Kept indices after duplicate removal without chain deletion (paper 004)."""

def crop_box(points: ArrayLike, min_bound: ArrayLike, max_bound: ArrayLike) -> NDArray[np.int64]:
    """Indices of the points inside ``[min_bound, max_bound]`` (bounds included)."""

def random_downsample(n_points: int, count: int, seed: int = 0) -> NDArray[np.int64]:
    """``count`` indices drawn without replacement from ``n_points``, reproducibly; ascending."""

def uniform_downsample(n_points: int, every_k: int) -> NDArray[np.int64]:
    """Every ``every_k``-th index from 0 (Open3D's ``uniform_down_sample``)."""

def estimate_normals(
    points: ArrayLike,
    k: int = 20,
    radius: float | None = None,
    towards: ArrayLike | None = None,
    along: ArrayLike | None = None,
    consistent: bool = False,
) -> NDArray[np.float64]:
    """PCA normals ``(N, 3)``: smallest eigenvector of each k-nearest (itself included) or hybrid
    radius neighbourhood covariance; oriented ``towards`` a viewpoint, ``along`` a direction,
    or ``consistent`` (MST propagation from the highest point, turned to +z)."""

def surface_variation(points: ArrayLike, k: int = 20, radius: float | None = None) -> NDArray[np.float64]:
    """λ0 / (λ0 + λ1 + λ2) of each neighbourhood covariance, ``(N,)``."""

def principal_curvatures(
    points: ArrayLike, normals: ArrayLike | None = None, k: int = 20, radius: float | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Principal curvatures ``(N, 2)`` (1/mm, k1 ≥ k2, signed along the normals) and directions
    ``(N, 2, 3)`` from a local quadric fit."""

def octree_simplify(
    points: ArrayLike,
    d_min: float,
    normals: ArrayLike | None = None,
    k: int = 10,
    eps1: int | None = None,
    eps2: int | None = None,
    neighbours: str = "xyz",
    refine: int = 0,
    feature_threshold: float = 0.05,
) -> NDArray[np.int64]:
    """Octree simplification keeping features and the x–y boundary (paper 002 §2); sorted unique
    kept indices. ``neighbours="xy"`` and ``refine`` go beyond the paper (feature leaves split
    deeper)."""

@final
class KinematicChain:
    """A machine model: a chain of elementary transforms mapping the last link into the WCS.

    Steps, composed left to right: ``("translate", (x, y, z))``, ``("translate_axes", (ix, iy, iz))``,
    ``("rotate", "x"|"y"|"z", angle)``, ``("rotate_axis", "x"|"y"|"z", column)``,
    ``("rotation", R)``, ``("mirror", (sx, sy, sz))``.
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
    def transforms(self, axes: ArrayLike) -> NDArray[np.float64]:
        """4×4 transforms for poses ``axes (F, n_axes)`` → ``(F, 4, 4)``."""
    def transform_points(self, points: ArrayLike, axes: ArrayLike) -> NDArray[np.float64]:
        """Points ``(N, 3)``, each with its own pose ``axes (N, n_axes)`` → ``(N, 3)``."""
    def transform_vectors(self, vectors: ArrayLike, axes: ArrayLike) -> NDArray[np.float64]:
        """Directions or normals ``(N, 3)`` with poses ``(N, n_axes)``: turned, not moved."""
    def scan_points(
        self,
        frames: ArrayLike,
        axes: ArrayLike,
        pitch: float,
        center: float | None = None,
        valid_range: ArrayLike | None = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Frames ``(F, N)`` and poses ``(F, n_axes)`` → ``(points (M, 3), frame_index (M,))``."""
