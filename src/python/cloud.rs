//! Bindings of `crate::cloud`: filters. Every filter returns the kept indices, so attributes
//! (normals, scalars, frame numbers) can be carried along with `array[indices]`.
use super::convert::{f64_array, to_numpy, to_py_err, Dim};
use super::spatial::as_points;
use pyo3::prelude::*;

fn points_arg(obj: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 3]>> {
    let a = f64_array(obj, "points", &[Dim::Any("N"), Dim::Is(3)], "")?;
    let pts = as_points(a.as_slice()?);
    crate::error::check_finite("points", a.as_slice()?, 3).map_err(to_py_err)?;
    Ok(pts)
}

fn indices<'py>(py: Python<'py>, v: Vec<usize>) -> PyResult<Bound<'py, PyAny>> {
    let n = v.len();
    to_numpy(py, v.into_iter().map(|i| i as i64).collect::<Vec<_>>(), &[n])
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
#[pyo3(signature = (points, voxel_size, return_index=false))]
fn voxel_downsample<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, voxel_size: f64, return_index: bool) -> PyResult<Bound<'py, PyAny>> {
    let pts = points_arg(points)?;
    let g = py.detach(|| crate::cloud::voxel_downsample(&pts, voxel_size)).map_err(to_py_err)?;
    let m = g.centroids.len();
    let c = to_numpy(py, g.centroids.into_iter().flatten().collect::<Vec<_>>(), &[m, 3])?;
    if !return_index {
        return Ok(c);
    }
    let n = g.voxel_of_point.len();
    let v = to_numpy(py, g.voxel_of_point.into_iter().map(|x| x as i64).collect::<Vec<_>>(), &[n])?;
    Ok(pyo3::types::PyTuple::new(py, [c, v])?.into_any())
}

/// Statistical outlier removal (Open3D's ``remove_statistical_outlier(nb_neighbors=k,
/// std_ratio)``): the mean distance of each point to its k nearest points (itself included);
/// points whose mean is at least ``mean + std_ratio · std`` over the cloud are dropped
/// (paper 004's "3σ" rule with ``std_ratio = 3``).
///
/// Returns
/// -------
/// ndarray of int64: kept indices, ascending.
///
/// Examples
/// --------
/// >>> keep = machscan.statistical_outlier_removal(pts, k=20, std_ratio=2.0)
#[pyfunction]
fn statistical_outlier_removal<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, k: usize, std_ratio: f64) -> PyResult<Bound<'py, PyAny>> {
    let pts = points_arg(points)?;
    let keep = py.detach(|| crate::cloud::statistical_outlier_removal(&pts, k, std_ratio)).map_err(to_py_err)?;
    indices(py, keep)
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
/// >>> keep = machscan.radius_outlier_removal(pts, radius=0.5, min_neighbors=5)
#[pyfunction]
fn radius_outlier_removal<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, radius: f64, min_neighbors: usize) -> PyResult<Bound<'py, PyAny>> {
    let pts = points_arg(points)?;
    let keep = py.detach(|| crate::cloud::radius_outlier_removal(&pts, radius, min_neighbors)).map_err(to_py_err)?;
    indices(py, keep)
}

/// Duplicate-point removal (paper 004): in point order, each point not yet removed removes every
/// other point within ``tolerance`` mm; removed points never remove others, so chains of close
/// points do not open holes. Returns the kept indices, ascending.
#[pyfunction]
fn remove_duplicates<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, tolerance: f64) -> PyResult<Bound<'py, PyAny>> {
    let pts = points_arg(points)?;
    let keep = py.detach(|| crate::cloud::remove_duplicates(&pts, tolerance)).map_err(to_py_err)?;
    indices(py, keep)
}

/// Indices of the points inside the box ``[min_bound, max_bound]`` (bounds included): crop box /
/// pass-through filter (a pass-through on one axis is a box infinite on the others).
#[pyfunction]
fn crop_box<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, min_bound: &Bound<'py, PyAny>, max_bound: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let a = f64_array(points, "points", &[Dim::Any("N"), Dim::Is(3)], "")?;
    let pts = as_points(a.as_slice()?);
    let lo = f64_array(min_bound, "min_bound", &[Dim::Is(3)], "(x, y, z) in mm")?;
    let hi = f64_array(max_bound, "max_bound", &[Dim::Is(3)], "(x, y, z) in mm")?;
    let (lo, hi) = (lo.as_slice()?, hi.as_slice()?);
    let keep = crate::cloud::crop_box(&pts, [lo[0], lo[1], lo[2]], [hi[0], hi[1], hi[2]]).map_err(to_py_err)?;
    indices(py, keep)
}

/// ``count`` points drawn at random without replacement, reproducibly from ``seed``; ascending
/// indices.
#[pyfunction]
#[pyo3(signature = (n_points, count, seed=0))]
fn random_downsample<'py>(py: Python<'py>, n_points: usize, count: usize, seed: u64) -> PyResult<Bound<'py, PyAny>> {
    indices(py, crate::cloud::random_downsample(n_points, count, seed))
}

/// Every ``every_k``-th point from the first (Open3D's ``uniform_down_sample``).
#[pyfunction]
fn uniform_downsample<'py>(py: Python<'py>, n_points: usize, every_k: usize) -> PyResult<Bound<'py, PyAny>> {
    indices(py, crate::cloud::uniform_downsample(n_points, every_k).map_err(to_py_err)?)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(voxel_downsample, m)?)?;
    m.add_function(wrap_pyfunction!(statistical_outlier_removal, m)?)?;
    m.add_function(wrap_pyfunction!(radius_outlier_removal, m)?)?;
    m.add_function(wrap_pyfunction!(remove_duplicates, m)?)?;
    m.add_function(wrap_pyfunction!(crop_box, m)?)?;
    m.add_function(wrap_pyfunction!(random_downsample, m)?)?;
    m.add_function(wrap_pyfunction!(uniform_downsample, m)?)?;
    Ok(())
}
