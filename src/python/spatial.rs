//! Bindings of `crate::spatial`.
use super::convert::{f64_array, to_numpy, to_py_err, Dim};
use numpy::PyUntypedArrayMethods;
use pyo3::prelude::*;

pub(crate) fn as_points(s: &[f64]) -> Vec<[f64; 3]> {
    s.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect()
}

/// Euclidean clustering (SPEC C1, paper 000 §2.2): points closer than ``radius`` share a cluster.
///
/// Clusters are the connected components of the neighbor graph: every neighbor within
/// ``radius`` (the same partition as Open3D's ``cluster_dbscan(eps=radius, min_points=1)``), or
/// with ``k`` the paper's form, the k nearest within ``radius`` (made symmetric so the result
/// does not depend on the seed order). Memory is O(N); queries run in parallel.
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     Points, mm.
/// radius : float
///     Neighbor distance threshold, mm (paper: 5 mm).
/// k : int, optional
///     Number of nearest neighbors considered (paper: 5); default all within ``radius``.
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
#[pyo3(signature = (points, radius, k=None))]
fn euclidean_clusters<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    radius: f64,
    k: Option<i64>,
) -> PyResult<Bound<'py, PyAny>> {
    let k = super::convert::count_opt("k", k)?;
    let arr = f64_array(points, "points", &[Dim::Any("N"), Dim::Is(3)], "")?;
    let n = arr.shape()[0];
    let pts = as_points(arr.as_slice()?);
    let labels = py.detach(|| crate::spatial::euclidean_clusters(&pts, radius, k)).map_err(to_py_err)?;
    to_numpy(py, labels.into_iter().map(|l| l as i64).collect::<Vec<_>>(), &[n])
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
    use rayon::prelude::*;
    let p = f64_array(points, "points", &[Dim::Any("N"), Dim::Is(3)], "")?;
    let q = f64_array(queries, "queries", &[Dim::Any("M"), Dim::Is(3)], "")?;
    if p.shape()[0] == 0 {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "points: expected at least one point to search, got (0, 3)",
        ));
    }
    let m = q.shape()[0];
    let (pp, qq) = (as_points(p.as_slice()?), as_points(q.as_slice()?));
    crate::error::check_finite("queries", q.as_slice()?, 3).map_err(to_py_err)?;
    let (idx, dist): (Vec<i64>, Vec<f64>) = py
        .detach(|| -> crate::Result<_> {
            let index = crate::spatial::PointIndex::new(&pp)?;
            Ok(qq
                .par_iter()
                .map(|x| {
                    let (i, d) = index.nearest(x);
                    (i as i64, d)
                })
                .unzip())
        })
        .map_err(to_py_err)?;
    Ok((to_numpy(py, idx, &[m])?, to_numpy(py, dist, &[m])?))
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
///     Neighbors per point (at most N).
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
#[pyo3(signature = (points, k, radius=None))]
fn knn_graph<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    k: i64,
    radius: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let k = super::convert::count("k", k)?;
    if let Some(r) = radius {
        if !(r.is_finite() && r > 0.0) {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "radius: must be a positive distance in mm, got {r}"
            )));
        }
    }
    let p = f64_array(points, "points", &[Dim::Any("N"), Dim::Is(3)], "")?;
    let n = p.shape()[0];
    let k = k.min(n);
    let pp = as_points(p.as_slice()?);
    let (idx, dist): (Vec<i64>, Vec<f64>) = py
        .detach(|| -> crate::Result<_> {
            use rayon::prelude::*;
            let (index, dist2) = crate::spatial::CloudNeighbors::new(&pp)?.knn_graph(k, radius);
            let idx = index.par_iter().map(|&j| if j == u32::MAX { -1 } else { j as i64 }).collect();
            Ok((idx, dist2.par_iter().map(|d| d.sqrt()).collect()))
        })
        .map_err(to_py_err)?;
    Ok((to_numpy(py, idx, &[n, k])?, to_numpy(py, dist, &[n, k])?))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(knn_graph, m)?)?;
    m.add_function(wrap_pyfunction!(euclidean_clusters, m)?)?;
    m.add_function(wrap_pyfunction!(nearest_neighbors, m)?)?;
    Ok(())
}
