//! Bindings of `machscan_core::cloud`: filters, normals, curvature, simplification. Every filter takes
//! the cloud first and returns the kept indices, so attributes (normals, scalars, frame
//! numbers) are carried along with `array[indices]`.
use super::convert::{
    count, count_opt, enter, f64_vector, f64_vector_opt, indices_to_numpy, points_to_numpy, to_numpy, Dim, F64Array,
};
use super::error::IntoPy;
use machscan_core::cloud::{NeighborSpace, Neighborhood, OctreeOptions, Orientation, VoxelFrame};
use pyo3::prelude::*;
use rayon::prelude::*;

fn neighborhood(k: usize, radius: Option<f64>) -> Neighborhood {
    match radius {
        Some(r) => Neighborhood::Hybrid { radius: r, max_nn: k },
        None => Neighborhood::Knn(k),
    }
}

/// Optional normals `(N, 3)` matching `n` points.
fn normals_arg<'py>(obj: Option<&Bound<'py, PyAny>>, n: usize) -> PyResult<Option<F64Array<'py>>> {
    F64Array::extract_opt(obj, "normals", &[Dim::Is(n), Dim::Is(3)], "(one normal per point)")
}

/// The voxel grid's origin over the bounds ``lo``, ``hi`` (mm), checked to fit the keys:
/// machscan.dask places its chunks' voxels with the in-memory grid (private).
#[pyfunction]
#[pyo3(signature = (lo, hi, *, voxel_size))]
fn voxel_origin<'py>(
    py: Python<'py>,
    lo: &Bound<'py, PyAny>,
    hi: &Bound<'py, PyAny>,
    voxel_size: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let lo = f64_vector::<3>(lo, "lo", "(x, y, z) in mm")?;
    let hi = f64_vector::<3>(hi, "hi", "(x, y, z) in mm")?;
    let grid = VoxelFrame::new(lo, hi, voxel_size).py()?;
    to_numpy(py, grid.origin.to_vec(), &[3])
}

/// The voxel keys and (i, j, k) indices of points within the grid of ``origin`` (from
/// ``voxel_origin``), as ``voxel_downsample`` keys them (private).
#[pyfunction]
#[pyo3(signature = (points, origin, *, voxel_size))]
fn voxel_keys<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    origin: &Bound<'py, PyAny>,
    voxel_size: f64,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let origin = f64_vector::<3>(origin, "origin", "(x, y, z) in mm")?;
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    let grid = VoxelFrame { origin, voxel: voxel_size };
    let (keys, ijk): (Vec<i64>, Vec<[i64; 3]>) =
        enter(py, || Ok(pts.par_iter().map(|p| (grid.key(p) as i64, grid.index(p).map(|i| i as i64))).unzip()))?;
    let n = keys.len();
    Ok((to_numpy(py, keys, &[n])?, to_numpy(py, ijk.into_flattened(), &[n, 3])?))
}

/// Voxel grid: every occupied voxel replaced by the centroid of its points (Open3D's
/// ``voxel_down_sample``: origin at the minimum bound less half a voxel, centroids summed in
/// point order, so the centroids are bit-identical). Voxels come in the order of their first
/// point; keys are 64-bit and relative to the minimum bound (no precision loss far from the
/// origin).
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     mm.
/// voxel_size : float
///     Voxel edge, mm.
/// return_index : bool
///     Also return the voxel of every input point.
///
/// Returns
/// -------
/// centroids : ndarray (M, 3)
/// voxel_of_point : ndarray of int64 (N,), only with ``return_index``
///
/// Examples
/// --------
/// >>> c = machscan.voxel_downsample(pts, 0.5)
#[pyfunction]
#[pyo3(signature = (points, voxel_size, *, return_index=false))]
fn voxel_downsample<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    voxel_size: f64,
    return_index: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    let g = enter(py, || machscan_core::cloud::voxel_downsample(pts, voxel_size))?;
    let c = points_to_numpy(py, g.centroids)?;
    if !return_index {
        return Ok(c);
    }
    let v = indices_to_numpy(py, g.voxel_of_point)?;
    Ok(pyo3::types::PyTuple::new(py, [c, v])?.into_any())
}

/// Statistical outlier removal (Open3D's ``remove_statistical_outlier(nb_neighbors=k,
/// std_ratio)``): the mean distance of each point to its k nearest points (itself included);
/// points whose mean is at least ``mean + std_ratio · std`` over the cloud are dropped
/// (paper 004's "3σ" rule with ``std_ratio = 3``). ``k`` counts the point
/// itself, 1 ≤ k ≤ N.
///
/// Returns
/// -------
/// ndarray of int64: kept indices, ascending.
///
/// Examples
/// --------
/// >>> keep = machscan.remove_statistical_outliers(pts, k=20, std_ratio=2.0)
#[pyfunction]
fn remove_statistical_outliers<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    k: i64,
    std_ratio: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let k = count("k", k)?;
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    indices_to_numpy(py, enter(py, || machscan_core::cloud::remove_statistical_outliers(pts, k, std_ratio))?)
}

/// Radius outlier removal (Open3D's ``remove_radius_outlier(nb_points=min_neighbors,
/// radius)``): a point is kept when more than ``min_neighbors`` points, itself included, lie
/// strictly closer than ``radius`` mm.
///
/// Returns
/// -------
/// ndarray of int64: kept indices, ascending.
///
/// Examples
/// --------
/// >>> keep = machscan.remove_radius_outliers(pts, radius=0.5, min_neighbors=5)
#[pyfunction]
fn remove_radius_outliers<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    radius: f64,
    min_neighbors: i64,
) -> PyResult<Bound<'py, PyAny>> {
    let min_neighbors = count("min_neighbors", min_neighbors)?;
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    indices_to_numpy(py, enter(py, || machscan_core::cloud::remove_radius_outliers(pts, radius, min_neighbors))?)
}

/// Duplicate-point removal (paper 004): in point order, each point not yet removed removes every
/// other point within ``tolerance`` mm; removed points never remove others, so chains of close
/// points do not open holes. Returns the kept indices, ascending.
#[pyfunction]
fn remove_duplicates<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, tolerance: f64) -> PyResult<Bound<'py, PyAny>> {
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    indices_to_numpy(py, enter(py, || machscan_core::cloud::remove_duplicates(pts, tolerance))?)
}

/// The cloud's point spacing, mm, as :func:`machscan.allowance` estimates a blank's by default:
/// the median over up to 20,000 points of r₈·√(π/9), r₈ the distance to the 8th other point
/// (nine points in a disc of radius r₈ at a density of 1/s²); within 1 % through 30 % jitter.
/// A scan of lines much farther apart than their points reads the spacing along the lines.
///
/// Examples
/// --------
/// >>> s = machscan.point_spacing(blank)
#[pyfunction]
fn point_spacing<'py>(py: Python<'py>, points: &Bound<'py, PyAny>) -> PyResult<f64> {
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    enter(py, || {
        if pts.len() < 9 {
            return Err(machscan_core::Error::invalid(
                "points",
                format!(
                    "the spacing is read from each point's 8 nearest: at least 9 points are needed, got {}",
                    pts.len()
                ),
            ));
        }
        let index = machscan_core::spatial::PointIndex::new(pts)?;
        Ok(machscan_core::registration::allowance::point_spacing(pts, &index))
    })
}

/// Indices of the points inside the box ``[min_bound, max_bound]`` (bounds included): crop box /
/// pass-through filter (a pass-through on one axis is a box infinite on the others).
#[pyfunction]
fn crop_box<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    min_bound: &Bound<'py, PyAny>,
    max_bound: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let arr = F64Array::points(points, "points")?;
    let lo = f64_vector::<3>(min_bound, "min_bound", "(x, y, z) in mm")?;
    let hi = f64_vector::<3>(max_bound, "max_bound", "(x, y, z) in mm")?;
    let pts = arr.rows::<3>()?;
    indices_to_numpy(py, enter(py, || machscan_core::cloud::crop_box(pts, lo, hi))?)
}

/// ``count`` points of ``points`` drawn at random without replacement, reproducibly from
/// ``seed``; ascending indices (all of them when ``count`` ≥ N).
///
/// Examples
/// --------
/// >>> keep = machscan.random_downsample(pts, 10_000, seed=1)
#[pyfunction]
#[pyo3(signature = (points, count, *, seed=0))]
fn random_downsample<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    count: i64,
    seed: i64,
) -> PyResult<Bound<'py, PyAny>> {
    let (how_many, seed) = (self::count("count", count)?, self::count("seed", seed)?);
    let n = F64Array::points(points, "points")?.shape()[0];
    indices_to_numpy(py, enter(py, || Ok(machscan_core::cloud::random_downsample(n, how_many, seed as u64)))?)
}

/// Every ``every_k``-th point of ``points`` from the first (Open3D's ``uniform_down_sample``);
/// ascending indices.
///
/// Examples
/// --------
/// >>> keep = machscan.uniform_downsample(pts, 5)
#[pyfunction]
fn uniform_downsample<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, every_k: i64) -> PyResult<Bound<'py, PyAny>> {
    let every_k = count("every_k", every_k)?;
    let n = F64Array::points(points, "points")?.shape()[0];
    indices_to_numpy(py, enter(py, || machscan_core::cloud::uniform_downsample(n, every_k))?)
}

/// PCA normals (SPEC F): the eigenvector of the smallest eigenvalue of each point's
/// neighborhood covariance — the k nearest points, the point itself included (Open3D's
/// ``KDTreeSearchParamKNN(k)``), or with ``radius`` the nearest ``k`` strictly closer than it
/// (``KDTreeSearchParamHybrid(radius, k)``). Unit length.
///
/// Orientation (at most one): ``towards`` a viewpoint (n·(v − p) ≥ 0), ``along`` a direction
/// (n·d ≥ 0), or ``consistent=True``: propagation over a minimum spanning tree of the k-nearest
/// graph from the highest point, turned to +z (Hoppe et al. 1992). Without one the sign is the
/// solver's. A point with fewer than 3 neighbors gets (0, 0, 1), as in Open3D.
///
/// Examples
/// --------
/// >>> n = machscan.estimate_normals(pts, k=20, towards=(0, 0, 500))
#[pyfunction]
#[pyo3(signature = (points, *, k=20, radius=None, towards=None, along=None, consistent=false))]
fn estimate_normals<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    k: i64,
    radius: Option<f64>,
    towards: Option<&Bound<'py, PyAny>>,
    along: Option<&Bound<'py, PyAny>>,
    consistent: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let k = count("k", k)?;
    let towards = f64_vector_opt::<3>(towards, "towards", "(x, y, z) in mm")?;
    let along = f64_vector_opt::<3>(along, "along", "(x, y, z)")?;
    let orientation = Orientation::from_options(towards, along, consistent).py()?;
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    let normals =
        enter(py, || machscan_core::cloud::estimate_oriented_normals(pts, neighborhood(k, radius), orientation))?;
    points_to_numpy(py, normals)
}

/// Surface variation λ0 / (λ0 + λ1 + λ2) of each point's neighborhood covariance (0 on a
/// plane, up to 1/3 for isotropic scatter); neighborhoods as in :func:`estimate_normals`.
#[pyfunction]
#[pyo3(signature = (points, *, k=20, radius=None))]
fn surface_variation<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    k: i64,
    radius: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let k = count("k", k)?;
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    let (_, var, _) = enter(py, || machscan_core::cloud::estimate_normals(pts, neighborhood(k, radius)))?;
    let n = var.len();
    to_numpy(py, var, &[n])
}

/// Principal curvatures and directions from a local quadric fit (SPEC F).
///
/// In each point's frame (tangents u, v; normal n) the neighbors are fitted by
/// ``h = a u² + b uv + c v² + d u + e v + f``; the shape operator at the point gives
/// ``k1 ≥ k2`` (1/mm) and their directions. Signs follow the normals: positive where the
/// surface bends towards the normal (a sphere with outward normals: −1/R). ``normals`` default
/// to :func:`estimate_normals` with the same neighborhood. Points with fewer than 6
/// neighbors get NaN.
///
/// Returns
/// -------
/// curvatures : ndarray (N, 2)
///     k1, k2 in 1/mm.
/// directions : ndarray (N, 2, 3)
///     Unit principal directions.
///
/// Examples
/// --------
/// >>> k, d = machscan.principal_curvatures(pts, k=30)
#[pyfunction]
#[pyo3(signature = (points, normals=None, *, k=20, radius=None))]
fn principal_curvatures<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    k: i64,
    radius: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let k = count("k", k)?;
    let arr = F64Array::points(points, "points")?;
    let n = arr.shape()[0];
    let given = normals_arg(normals, n)?;
    let (pts, given) = (arr.rows::<3>()?, given.as_ref().map(|a| a.rows::<3>()).transpose()?);
    let nbh = neighborhood(k, radius);
    let res = enter(py, || machscan_core::cloud::principal_curvatures(pts, given, nbh))?;
    let curv: Vec<f64> = res.iter().flat_map(|r| r.0).collect();
    let dirs: Vec<f64> = res.iter().flat_map(|r| r.1.into_iter().flatten()).collect();
    Ok((to_numpy(py, curv, &[n, 2])?, to_numpy(py, dirs, &[n, 2, 3])?))
}

/// Octree simplification keeping features and the boundary (SPEC F, paper 002 §2).
///
/// Cube of edge L (the largest extent) on the minimum corner, depth ⌈log2(L/d_min)⌉; each
/// occupied leaf keeps its point of largest feature degree (mean angle between its normal and
/// its ``k`` neighbors' normals, unoriented) and its point nearest the cell center; the x–y
/// boundary points are kept by the paper's group rule (sorted by x, groups of ``eps1`` keep
/// min-y and max-y; sorted by y, groups of ``eps2`` keep min-x and max-x). ``eps1``/``eps2``
/// default to the number of points in a strip ``d_min`` wide.
///
/// Beyond the paper (off by default): ``neighbors="xy"`` takes the neighbors of the normals
/// and the feature degree in the x–y projection, so both sides of a vertical step see each
/// other (height-field scans); ``refine=r`` splits every leaf whose largest feature degree
/// exceeds ``feature_threshold`` r levels deeper, each occupied sub-cell keeping its own two
/// points. On a pocket plate with 3 mm steps the paper's rule rebuilds a worse surface than a
/// voxel grid of the same point count; ``neighbors="xy", refine=2`` a better one
/// (tests/test_octree.py, figures in BENCHMARKS.md).
///
/// Parameters
/// ----------
/// points : array_like (N, 3)
///     mm; z is the cutting depth direction.
/// d_min : float
///     Smallest cell edge, mm.
/// normals : array_like (N, 3), optional
///     Default: :func:`estimate_normals` with ``k``.
/// k : int
///     Neighbors of the feature degree.
/// eps1, eps2 : int, optional
/// neighbors : {"xyz", "xy"}
/// refine : int
///     Extra octree levels on feature leaves (0: the paper's rule).
/// feature_threshold : float
///     Radians; a leaf is a feature leaf when its largest feature degree exceeds it. The
///     default 0.05 (about 3°) is some 4× the 99th percentile of the feature degree of a flat
///     scan with 3 µm noise at 0.25 mm spacing; raise it for noisier scans.
///
/// Returns
/// -------
/// ndarray of int64: kept indices, sorted and unique.
///
/// Examples
/// --------
/// >>> keep = machscan.octree_simplify(pts, d_min=2.0)
#[pyfunction]
#[pyo3(signature = (points, d_min, *, normals=None, k=10, eps1=None, eps2=None, neighbors="xyz", refine=0, feature_threshold=0.05))]
#[allow(clippy::too_many_arguments)]
fn octree_simplify<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    d_min: f64,
    normals: Option<&Bound<'py, PyAny>>,
    k: i64,
    eps1: Option<i64>,
    eps2: Option<i64>,
    neighbors: &str,
    refine: i64,
    feature_threshold: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let (k, eps1, eps2, refine) =
        (count("k", k)?, count_opt("eps1", eps1)?, count_opt("eps2", eps2)?, count("refine", refine)?);
    let neighbors = NeighborSpace::parse(neighbors).py()?;
    let arr = F64Array::points(points, "points")?;
    let given = normals_arg(normals, arr.shape()[0])?;
    let (pts, given) = (arr.rows::<3>()?, given.as_ref().map(|a| a.rows::<3>()).transpose()?);
    let opts = OctreeOptions { d_min, k, eps1, eps2, neighbors, refine, feature_threshold };
    indices_to_numpy(py, enter(py, || machscan_core::cloud::octree_simplify(pts, given, &opts))?)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(octree_simplify, m)?)?;
    m.add_function(wrap_pyfunction!(estimate_normals, m)?)?;
    m.add_function(wrap_pyfunction!(surface_variation, m)?)?;
    m.add_function(wrap_pyfunction!(principal_curvatures, m)?)?;
    m.add_function(wrap_pyfunction!(voxel_downsample, m)?)?;
    m.add_function(wrap_pyfunction!(voxel_origin, m)?)?;
    m.add_function(wrap_pyfunction!(voxel_keys, m)?)?;
    m.add_function(wrap_pyfunction!(remove_statistical_outliers, m)?)?;
    m.add_function(wrap_pyfunction!(remove_radius_outliers, m)?)?;
    m.add_function(wrap_pyfunction!(remove_duplicates, m)?)?;
    m.add_function(wrap_pyfunction!(point_spacing, m)?)?;
    m.add_function(wrap_pyfunction!(crop_box, m)?)?;
    m.add_function(wrap_pyfunction!(random_downsample, m)?)?;
    m.add_function(wrap_pyfunction!(uniform_downsample, m)?)?;
    Ok(())
}
