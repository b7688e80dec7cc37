//! Bindings of `machscan_core::matching`.
use super::convert::{count, enter_long, points_to_numpy, to_numpy, F64Array};
use super::error::IntoPy;
use super::mesh::surface;
use machscan_core::error::Error;
use machscan_core::matching::{isometric_match_points as run_isometric_match, Jacobian, MatchOptions, Meshing};
use machscan_core::mesh::{GeodesicMethod, ScanSurface, Spacing};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Isometric matching (SPEC S4); ``machscan.isometric_match`` documents it and wraps the
/// ``_IsometricMatchArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (
    theoretical_points, theoretical_faces, actual_points, actual_faces, theoretical_locating,
    actual_locating, theoretical_matching, actual_initial, *, jacobian, method, spacing, max_edge, max_iterations,
    tolerance
))]
#[allow(clippy::too_many_arguments)]
fn isometric_match<'py>(
    py: Python<'py>,
    theoretical_points: &Bound<'py, PyAny>,
    theoretical_faces: Option<&Bound<'py, PyAny>>,
    actual_points: &Bound<'py, PyAny>,
    actual_faces: Option<&Bound<'py, PyAny>>,
    theoretical_locating: &Bound<'py, PyAny>,
    actual_locating: &Bound<'py, PyAny>,
    theoretical_matching: &Bound<'py, PyAny>,
    actual_initial: Option<&Bound<'py, PyAny>>,
    jacobian: &str,
    method: &str,
    spacing: &Bound<'py, PyAny>,
    max_edge: Option<f64>,
    max_iterations: i64,
    tolerance: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let (tp, tf) = surface(theoretical_points, theoretical_faces, "theoretical_points")?;
    let (ap, af) = surface(actual_points, actual_faces, "actual_points")?;
    let tl = F64Array::points(theoretical_locating, "theoretical_locating")?;
    let al = F64Array::points(actual_locating, "actual_locating")?;
    let tm = F64Array::points(theoretical_matching, "theoretical_matching")?;
    let ai = actual_initial.map(|a| F64Array::points(a, "actual_initial")).transpose()?;
    let spacing = if spacing.is_none() {
        Spacing::Full
    } else if let Ok(word) = spacing.extract::<String>() {
        Spacing::parse(&word).py()?
    } else {
        let mm = spacing
            .extract::<f64>()
            .map_err(|_| Error::invalid("spacing", "expected 'auto', a spacing in mm or None"))
            .py()?;
        Spacing::Fixed(mm)
    };
    let options = MatchOptions {
        jacobian: Jacobian::parse(jacobian).py()?,
        method: GeodesicMethod::parse(method).py()?,
        max_iterations: count("max_iterations", max_iterations)?,
        tolerance,
    };
    let (tpr, apr, tlr, alr, tmr) =
        (tp.rows::<3>()?, ap.rows::<3>()?, tl.rows::<3>()?, al.rows::<3>()?, tm.rows::<3>()?);
    let air = ai.as_ref().map(|a| a.rows::<3>()).transpose()?;
    let (theoretical, actual) =
        (ScanSurface { points: tpr, faces: tf.as_deref() }, ScanSurface { points: apr, faces: af.as_deref() });
    let meshing = Meshing { max_edge, spacing };
    let r = enter_long(py, || run_isometric_match(theoretical, actual, meshing, tlr, alr, tmr, air, options))?;
    let d = PyDict::new(py);
    let k = r.objective.len();
    d.set_item("points", points_to_numpy(py, r.points)?)?;
    d.set_item("locating", points_to_numpy(py, r.locating.to_vec())?)?;
    d.set_item("objective", to_numpy(py, r.objective, &[k])?)?;
    d.set_item("max_error", to_numpy(py, r.max_error, &[k])?)?;
    let m = r.residuals.len();
    d.set_item("residuals", to_numpy(py, r.residuals, &[m])?)?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("stop", r.stop.name())?;
    d.set_item("converged", r.stop.converged())?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(isometric_match, m)?)?;
    Ok(())
}
