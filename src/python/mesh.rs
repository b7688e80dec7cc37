//! Bindings of `crate::mesh`.
use super::convert::{enter, to_numpy, F64Array};
use crate::mesh::delaunay_xy as run_delaunay_xy;
use pyo3::prelude::*;

/// Delaunay triangulation of a surface seen from above (SPEC S1; paper 002 §3.1): the points'
/// xy projection is triangulated (spade, exact predicates) and the triangles lifted back to 3D.
/// For height-field surfaces such as a skin on the machine table.
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     mm.
/// max_edge : float, optional
///     Leave out triangles with an edge longer than this in 3D, mm: the long thin triangles a
///     concave outline leaves along its convex hull.
///
/// Returns
/// -------
/// ndarray of int64, shape (M, 3)
///     Triangles as indices into ``points``, counter-clockwise seen from +z. The same triangles
///     as ``scipy.spatial.Delaunay(points[:, :2])`` for points in general position (with four
///     or more on one circle, one of the valid triangulations).
///
/// Raises
/// ------
/// ValueError
///     Points not finite, all on one line in xy, or fewer than three distinct ones. Points with
///     the same x and y as an earlier one are not an error: they are left out of every triangle
///     (the first one is kept).
///
/// Examples
/// --------
/// >>> faces = machscan.delaunay_xy(scan, max_edge=5.0)
/// >>> machscan.write_mesh("skin.ply", scan, faces)
#[pyfunction]
#[pyo3(signature = (points, max_edge=None))]
fn delaunay_xy<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, max_edge: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    let faces = enter(py, || run_delaunay_xy(pts, max_edge))?;
    let m = faces.len();
    to_numpy(py, faces.into_iter().flat_map(|t| t.map(i64::from)).collect(), &[m, 3])
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(delaunay_xy, m)?)?;
    Ok(())
}
