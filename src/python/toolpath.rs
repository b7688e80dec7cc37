//! Bindings of `crate::toolpath`.
use super::convert::{enter, points_to_numpy, to_numpy, Dim, F64Array};
use super::mesh::surface;
use crate::mesh::surface_faces;
use crate::toolpath::{compensate_toolpath as run_compensate, CompensateOptions, Interpolation, Normals};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Toolpath compensation (SPEC S5); ``machscan.compensate_toolpath`` documents it and wraps the
/// ``_CompensatedArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (
    tool_points, theoretical_matching, actual_matching, actual_points, actual_faces, *, interpolation, normals, radius,
    max_edge
))]
#[allow(clippy::too_many_arguments)]
fn compensate_toolpath<'py>(
    py: Python<'py>,
    tool_points: &Bound<'py, PyAny>,
    theoretical_matching: &Bound<'py, PyAny>,
    actual_matching: &Bound<'py, PyAny>,
    actual_points: &Bound<'py, PyAny>,
    actual_faces: Option<&Bound<'py, PyAny>>,
    interpolation: &str,
    normals: &str,
    radius: Option<f64>,
    max_edge: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let tools =
        F64Array::extract(tool_points, "tool_points", &[Dim::Any("M"), Dim::Any("3 or 6")], "(x, y, z[, i, j, k])")?;
    let width = tools.shape()[1];
    if width != 3 && width != 6 {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "tool_points: expected (M, 3) points or (M, 6) points and tool axes, got {} columns",
            width
        )));
    }
    let values = tools.values()?;
    let points: Vec<[f64; 3]> = values.chunks_exact(width).map(|r| [r[0], r[1], r[2]]).collect();
    let axes: Option<Vec<[f64; 3]>> =
        (width == 6).then(|| values.chunks_exact(6).map(|r| [r[3], r[4], r[5]]).collect());
    let tm = F64Array::points(theoretical_matching, "theoretical_matching")?;
    let am = F64Array::points(actual_matching, "actual_matching")?;
    let (ap, af) = surface(actual_points, actual_faces, "actual_surface")?;
    let options = CompensateOptions {
        interpolation: Interpolation::parse(interpolation)?,
        normals: Normals::parse(normals)?,
        radius,
    };
    let (tmr, amr, apr) = (tm.rows::<3>()?, am.rows::<3>()?, ap.rows::<3>()?);
    let r = enter(py, || {
        let af = surface_faces("actual_surface", apr, af, max_edge)?;
        run_compensate(&points, axes.as_deref(), tmr, amr, apr, &af, options)
    })?;
    let m = r.points.len();
    let d = PyDict::new(py);
    d.set_item("points", points_to_numpy(py, r.points)?)?;
    d.set_item("axes", points_to_numpy(py, r.axes)?)?;
    d.set_item("inside", to_numpy(py, r.inside, &[m])?)?;
    d.set_item("offsets", to_numpy(py, r.offsets, &[m])?)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(compensate_toolpath, m)?)?;
    Ok(())
}
