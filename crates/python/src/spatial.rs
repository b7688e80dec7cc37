//! Bindings of `machscan_core::spatial`.
use super::convert::{count, count_opt, enter, indices_to_numpy, to_numpy, F64Array};
use pyo3::prelude::*;

/// Euclidean clustering (SPEC C1, paper 000 §2.2): points closer than ``radius`` share a cluster.
///
/// Clusters are the connected components of the neighbor graph: every neighbor within
/// ``radius`` (the same partition as Open3D's ``cluster_dbscan(eps=radius, min_points=1)``), or
/// with ``k`` the paper's form, the k nearest other points within ``radius`` (made symmetric so
/// the result does not depend on the seed order). Memory is O(N); queries run in parallel.
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     Points, mm.
/// radius : float
///     Neighbor distance threshold, mm (paper: 5 mm).
/// k : int, optional
///     Number of nearest other points considered (paper: 5), 1 ≤ k ≤ N − 1; default all
///     within ``radius``.
///
/// Returns
/// -------
/// ndarray of int64, shape (N,)
///     Cluster of every point, 0..n_clusters−1, numbered in the order of their first point.
///
/// Examples
/// --------
/// >>> labels = machscan.euclidean_clusters(centers, radius=5.0, k=5)
#[pyfunction]
#[pyo3(signature = (points, radius, *, k=None))]
fn euclidean_clusters<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    radius: f64,
    k: Option<i64>,
) -> PyResult<Bound<'py, PyAny>> {
    let k = count_opt("k", k)?;
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    let labels = enter(py, || machscan_core::spatial::euclidean_clusters(pts, radius, k))?;
    indices_to_numpy(py, labels)
}

/// Nearest point of ``points`` for every query (kd-tree, parallel over queries).
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     The cloud searched, mm.
/// queries : array_like, shape (M, 3)
///     Query points, mm.
///
/// Returns
/// -------
/// index : ndarray of int64, shape (M,)
/// distance : ndarray, shape (M,)
///     Euclidean distance, mm.
///
/// Examples
/// --------
/// >>> idx, dist = machscan.nearest_neighbors(model, measured)
#[pyfunction]
fn nearest_neighbors<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    queries: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let p = F64Array::points(points, "points")?;
    let q = F64Array::points(queries, "queries")?;
    let (pp, qq) = (p.rows::<3>()?, q.rows::<3>()?);
    let (idx, dist) = enter(py, || machscan_core::spatial::nearest_neighbors(pp, qq))?;
    let m = dist.len();
    Ok((indices_to_numpy(py, idx)?, to_numpy(py, dist, &[m])?))
}

/// The k nearest points of every point of a cloud (its k-nearest graph), the point itself
/// included and first unless an exact duplicate with a lower index precedes it; nearest first,
/// ties by index. With ``radius`` only neighbors strictly closer than it (Open3D's hybrid
/// search), the rows padded with index −1 and distance ``inf``.
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     mm.
/// k : int
///     Neighbors per point, 1 ≤ k ≤ N (the point counts as its own neighbor).
/// radius : float, optional
///     mm.
///
/// Returns
/// -------
/// index : ndarray of int64, shape (N, k)
/// distance : ndarray, shape (N, k)
///     Euclidean distance, mm.
///
/// Examples
/// --------
/// >>> idx, dist = machscan.knn_graph(pts, k=20)
/// >>> spacing = np.median(dist[:, 1])
#[pyfunction]
#[pyo3(signature = (points, k, *, radius=None))]
fn knn_graph<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    k: i64,
    radius: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let k = count("k", k)?;
    let p = F64Array::points(points, "points")?;
    let (n, pts) = (p.shape()[0], p.rows::<3>()?);
    let (idx, dist) = enter(py, || machscan_core::spatial::knn_graph(pts, k, radius))?;
    let idx: Vec<i64> = idx.into_iter().map(|j| j.map_or(-1, |j| j as i64)).collect();
    Ok((to_numpy(py, idx, &[n, k])?, to_numpy(py, dist, &[n, k])?))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(knn_graph, m)?)?;
    m.add_function(wrap_pyfunction!(euclidean_clusters, m)?)?;
    m.add_function(wrap_pyfunction!(nearest_neighbors, m)?)?;
    Ok(())
}
