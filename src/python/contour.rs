//! Bindings of `crate::contour`.
use super::convert::{f64_array, to_numpy, to_py_err, Dim};
use super::spatial::as_points;
use numpy::PyUntypedArrayMethods;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Contour error of one contour (SPEC C3–C5); ``machscan.contour_error`` wraps the dict.
#[pyfunction]
#[pyo3(signature = (theoretical, actual, delta1=1.0, delta2=1.0))]
fn contour_error<'py>(
    py: Python<'py>,
    theoretical: &Bound<'py, PyAny>,
    actual: &Bound<'py, PyAny>,
    delta1: f64,
    delta2: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let p = f64_array(theoretical, "theoretical", &[Dim::Any("a"), Dim::Is(3)], "")?;
    let q = f64_array(actual, "actual", &[Dim::Any("b"), Dim::Is(3)], "")?;
    let a = p.shape()[0];
    let (pp, qq) = (as_points(p.as_slice()?), as_points(q.as_slice()?));
    let r = py.detach(|| crate::contour::contour_error(&pp, &qq, delta1, delta2)).map_err(to_py_err)?;
    let d = PyDict::new(py);
    d.set_item("offset", to_numpy(py, r.offset.to_vec(), &[3])?)?;
    d.set_item("errors", to_numpy(py, r.errors, &[a])?)?;
    d.set_item("deviations", to_numpy(py, r.deviations, &[a])?)?;
    d.set_item("matched", to_numpy(py, r.matched.into_iter().map(|v| v as i64).collect::<Vec<_>>(), &[a])?)?;
    d.set_item("cases", to_numpy(py, r.cases.into_iter().map(|c| c as u8).collect::<Vec<_>>(), &[a])?)?;
    d.set_item("mean", r.mean)?;
    d.set_item("std", r.std)?;
    d.set_item("max", r.max)?;
    Ok(d)
}

/// Points along a polyline every ``spacing`` mm (corners kept), ``(M, 3)``.
///
/// Parameters
/// ----------
/// vertices : array_like, shape (n, 3)
///     Polyline vertices, mm.
/// spacing : float
///     Largest distance between consecutive points, mm.
/// closed : bool
///     Add the segment from the last vertex back to the first.
///
/// Examples
/// --------
/// >>> pts = machscan.resample_polyline(cad_vertices, spacing=0.5, closed=True)
#[pyfunction]
#[pyo3(signature = (vertices, spacing, closed=true))]
fn resample_polyline<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    spacing: f64,
    closed: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let v = f64_array(vertices, "vertices", &[Dim::Any("n"), Dim::Is(3)], "")?;
    let out = crate::contour::resample_polyline(&as_points(v.as_slice()?), spacing, closed).map_err(to_py_err)?;
    let m = out.len();
    to_numpy(py, out.into_iter().flatten().collect::<Vec<_>>(), &[m, 3])
}

/// Match actual contour centroids to theoretical ones one to one (minimal summed distance);
/// ``(n_actual,)`` indices into the theoretical centroids, −1 where none lies within
/// ``max_distance`` mm.
///
/// Examples
/// --------
/// >>> idx = machscan.match_contours(actual_centroids, cad_centroids, max_distance=10.0)
#[pyfunction]
#[pyo3(signature = (actual_centroids, theoretical_centroids, max_distance=f64::INFINITY))]
fn match_contours<'py>(
    py: Python<'py>,
    actual_centroids: &Bound<'py, PyAny>,
    theoretical_centroids: &Bound<'py, PyAny>,
    max_distance: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let a = f64_array(actual_centroids, "actual_centroids", &[Dim::Any("n"), Dim::Is(3)], "")?;
    let t = f64_array(theoretical_centroids, "theoretical_centroids", &[Dim::Any("m"), Dim::Is(3)], "")?;
    if max_distance.is_nan() || max_distance < 0.0 {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "max_distance: must be >= 0 mm, got {max_distance}"
        )));
    }
    let (aa, tt) = (as_points(a.as_slice()?), as_points(t.as_slice()?));
    for (name, pts) in [("actual_centroids", &aa), ("theoretical_centroids", &tt)] {
        crate::error::check_finite(name, &pts.iter().flatten().copied().collect::<Vec<_>>(), 3).map_err(to_py_err)?;
    }
    let out = crate::contour::assign_one_to_one(&aa, &tt, max_distance);
    let n = out.len();
    to_numpy(py, out.into_iter().map(|o| o.map_or(-1, |v| v as i64)).collect::<Vec<_>>(), &[n])
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(contour_error, m)?)?;
    m.add_function(wrap_pyfunction!(resample_polyline, m)?)?;
    m.add_function(wrap_pyfunction!(match_contours, m)?)?;
    Ok(())
}
