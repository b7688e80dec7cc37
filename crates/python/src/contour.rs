//! Bindings of `machscan_core::contour`.
use super::convert::{count, enter, f64_vector, indices_to_numpy, points_to_numpy, to_numpy, Dim, F64Array};
use machscan_core::contour::BendingSurface;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Contour error of one contour (SPEC C3–C5); ``machscan.contour_error`` wraps the
/// ``ContourErrorArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (theoretical, actual, *, delta1=1.0, delta2=1.0))]
fn contour_error<'py>(
    py: Python<'py>,
    theoretical: &Bound<'py, PyAny>,
    actual: &Bound<'py, PyAny>,
    delta1: f64,
    delta2: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let p = F64Array::points(theoretical, "theoretical")?;
    let q = F64Array::points(actual, "actual")?;
    let (a, pp, qq) = (p.shape()[0], p.rows::<3>()?, q.rows::<3>()?);
    let r = enter(py, || machscan_core::contour::contour_error(pp, qq, delta1, delta2))?;
    let d = PyDict::new(py);
    d.set_item("offset", to_numpy(py, r.offset.to_vec(), &[3])?)?;
    d.set_item("errors", to_numpy(py, r.errors, &[a])?)?;
    d.set_item("deviations", to_numpy(py, r.deviations, &[a])?)?;
    d.set_item("matched", indices_to_numpy(py, r.matched)?)?;
    d.set_item("cases", to_numpy(py, r.cases.into_iter().map(|c| c as u8).collect::<Vec<_>>(), &[a])?)?;
    d.set_item("mean", r.mean)?;
    d.set_item("std", r.std)?;
    d.set_item("max", r.max)?;
    Ok(d)
}

/// Points along a polyline every ``spacing`` mm at most (equal steps over the whole polyline),
/// ``(M, 3)``.
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
#[pyo3(signature = (vertices, spacing, *, closed=true))]
fn resample_polyline<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    spacing: f64,
    closed: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let v = F64Array::points(vertices, "vertices")?;
    let vv = v.rows::<3>()?;
    let out = enter(py, || machscan_core::contour::resample_polyline(vv, spacing, closed))?;
    points_to_numpy(py, out)
}

/// Match actual contour centroids to theoretical ones one to one (minimal summed distance);
/// ``(n_actual,)`` indices into the theoretical centroids, −1 where none lies within
/// ``max_distance`` mm (``None``: no limit).
///
/// Examples
/// --------
/// >>> idx = machscan.match_contours(actual_centroids, cad_centroids, max_distance=10.0)
#[pyfunction]
#[pyo3(signature = (actual_centroids, theoretical_centroids, *, max_distance=None))]
fn match_contours<'py>(
    py: Python<'py>,
    actual_centroids: &Bound<'py, PyAny>,
    theoretical_centroids: &Bound<'py, PyAny>,
    max_distance: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let a = F64Array::points(actual_centroids, "actual_centroids")?;
    let t = F64Array::points(theoretical_centroids, "theoretical_centroids")?;
    let (aa, tt) = (a.rows::<3>()?, t.rows::<3>()?);
    let out = enter(py, || machscan_core::contour::match_contours(aa, tt, max_distance))?;
    let n = out.len();
    to_numpy(py, out.into_iter().map(|o| o.map_or(-1, |v| v as i64)).collect::<Vec<_>>(), &[n])
}

/// A flat float64 argument of `n` values (any array-like).
fn values<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<F64Array<'py>> {
    F64Array::extract(obj, name, &[Dim::Any("N")], "")
}

/// The bending surface of the error decomposition (SPEC C6), fitted in the core; the
/// ``_BendingSurfaceArrays`` keys (private: ``inspect_grooves`` wraps it in ``Decomposition``).
#[pyfunction]
#[pyo3(signature = (x, y, dz, *, degree))]
fn fit_bending_surface<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
    dz: &Bound<'py, PyAny>,
    degree: i64,
) -> PyResult<Bound<'py, PyDict>> {
    let degree = count("degree", degree)?;
    let (xa, ya, za) = (values(x, "x")?, values(y, "y")?, values(dz, "dz")?);
    let (xv, yv, zv) = (xa.values()?, ya.values()?, za.values()?);
    let b = enter(py, || BendingSurface::fit(xv, yv, zv, degree))?;
    let terms = b.exponents.len();
    let d = PyDict::new(py);
    d.set_item("degree", b.degree)?;
    d.set_item("exponents", to_numpy(py, b.exponents.iter().flatten().map(|&e| e as i64).collect(), &[terms, 2])?)?;
    d.set_item("coefficients", to_numpy(py, b.coefficients, &[terms])?)?;
    d.set_item("center", to_numpy(py, b.center.to_vec(), &[2])?)?;
    d.set_item("scale", b.scale)?;
    d.set_item("rms_residual", b.rms_residual)?;
    Ok(d)
}

/// B(x, y) of a bending surface from ``fit_bending_surface``'s arrays, mm (private).
#[pyfunction]
#[pyo3(signature = (exponents, coefficients, center, scale, x, y))]
fn bending_surface_at<'py>(
    py: Python<'py>,
    exponents: &Bound<'py, PyAny>,
    coefficients: &Bound<'py, PyAny>,
    center: &Bound<'py, PyAny>,
    scale: f64,
    x: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let c = values(coefficients, "coefficients")?;
    let e = F64Array::extract(exponents, "exponents", &[Dim::Is(c.shape()[0]), Dim::Is(2)], "(i, j) per coefficient")?;
    let exponents = e.rows::<2>()?.iter().map(|&[i, j]| [i as u32, j as u32]).collect();
    let center = f64_vector::<2>(center, "center", "(x, y) in mm")?;
    let b = BendingSurface {
        degree: 0,
        exponents,
        coefficients: c.values()?.to_vec(),
        center,
        scale,
        rms_residual: f64::NAN,
    };
    let (xa, ya) = (values(x, "x")?, values(y, "y")?);
    let (xv, yv) = (xa.values()?, ya.values()?);
    if xv.len() != yv.len() {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "y: expected shape ({},) as x, got ({},)",
            xv.len(),
            yv.len()
        )));
    }
    let out: Vec<f64> = xv.iter().zip(yv).map(|(&x, &y)| b.at(x, y)).collect();
    to_numpy(py, out, &[xv.len()])
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(contour_error, m)?)?;
    m.add_function(wrap_pyfunction!(resample_polyline, m)?)?;
    m.add_function(wrap_pyfunction!(match_contours, m)?)?;
    m.add_function(wrap_pyfunction!(fit_bending_surface, m)?)?;
    m.add_function(wrap_pyfunction!(bending_surface_at, m)?)?;
    Ok(())
}
