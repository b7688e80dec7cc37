//! Bindings of `crate::groove`: the batch groove fit.
use super::convert::{count, count_opt, f64_array, to_numpy, to_py_err, Dim};
use crate::groove::{fit_frames, level_frame, GrooveOptions, TemplateKind};
use numpy::PyUntypedArrayMethods;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Fit the groove template to every frame (SPEC G); ``machscan.fit_grooves`` wraps the dict of
/// per-frame arrays this returns in a result object.
#[pyfunction]
#[pyo3(signature = (x, z, alpha=20.0, nominal_width=0.5, window=None, window_center=None, fit_alpha=false,
    spike_threshold=Some(0.1), min_depth=0.03, min_valid=12, max_iterations=100, cost_tolerance=0.0,
    step_tolerance=1e-8, gradient_tolerance=1e-13, template="tanh"))]
#[allow(clippy::too_many_arguments)]
fn fit_grooves<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    z: &Bound<'py, PyAny>,
    alpha: f64,
    nominal_width: f64,
    window: Option<i64>,
    window_center: Option<i64>,
    fit_alpha: bool,
    spike_threshold: Option<f64>,
    min_depth: f64,
    min_valid: i64,
    max_iterations: i64,
    cost_tolerance: f64,
    step_tolerance: f64,
    gradient_tolerance: f64,
    template: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let (window, window_center) = (count_opt("window", window)?, count_opt("window_center", window_center)?);
    let (min_valid, max_iterations) = (count("min_valid", min_valid)?, count("max_iterations", max_iterations)?);
    let template = match template {
        "tanh" => TemplateKind::Tanh,
        "v" => TemplateKind::V,
        other => {
            return Err(PyValueError::new_err(format!(
                "template: expected \"tanh\" (paper 000) or \"v\", got {other:?}"
            )))
        }
    };
    let xa = f64_array(x, "x", &[Dim::Any("N")], "(reading abscissae, mm)")?;
    let n = xa.shape()[0];
    let za = f64_array(z, "z", &[Dim::Any("F"), Dim::Is(n)], "(one column per x, mm)")?;
    let f = za.shape()[0];
    let options = GrooveOptions {
        template,
        alpha,
        fit_alpha,
        nominal_width,
        window,
        window_center,
        spike_threshold,
        min_depth,
        min_valid,
        max_iterations,
        cost_tolerance,
        step_tolerance,
        gradient_tolerance,
    };
    let (xs, zs) = (xa.as_slice()?, za.as_slice()?);
    let fits = py.detach(|| fit_frames(xs, zs, &options)).map_err(to_py_err)?;
    let d = PyDict::new(py);
    let column = |get: fn(&crate::groove::GrooveFit) -> f64| fits.iter().map(get).collect::<Vec<f64>>();
    d.set_item("x0", to_numpy(py, column(|g| g.x0), &[f])?)?;
    d.set_item("z0", to_numpy(py, column(|g| g.z0), &[f])?)?;
    d.set_item("depth", to_numpy(py, column(|g| g.depth), &[f])?)?;
    d.set_item("width", to_numpy(py, column(|g| g.width), &[f])?)?;
    d.set_item("alpha", to_numpy(py, column(|g| g.alpha), &[f])?)?;
    d.set_item("rms", to_numpy(py, column(|g| g.rms), &[f])?)?;
    d.set_item("se_depth", to_numpy(py, column(|g| g.se_depth), &[f])?)?;
    d.set_item("se_width", to_numpy(py, column(|g| g.se_width), &[f])?)?;
    d.set_item("tilt", to_numpy(py, column(|g| g.tilt), &[f])?)?;
    d.set_item("iterations", to_numpy(py, fits.iter().map(|g| g.iterations as i32).collect::<Vec<_>>(), &[f])?)?;
    d.set_item("n_used", to_numpy(py, fits.iter().map(|g| g.n_used as i32).collect::<Vec<_>>(), &[f])?)?;
    d.set_item("status", to_numpy(py, fits.iter().map(|g| g.status as u8).collect::<Vec<_>>(), &[f])?)?;
    Ok(d)
}

/// One frame levelled as the fit sees it (SPEC G steps 1–4); ``machscan.level_groove_frame``
/// wraps it. Returns a dict with the levelled ``x``, ``z`` (absolute levelled coordinates),
/// ``tilt``, the initial guess ``start`` (x0, z0, d, w, α) and ``status`` (0 when ready).
#[pyfunction]
#[pyo3(signature = (x, z, alpha=20.0, nominal_width=0.5, window=None, window_center=None, spike_threshold=Some(0.1), min_depth=0.03, min_valid=12))]
#[allow(clippy::too_many_arguments)]
fn level_groove_frame<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    z: &Bound<'py, PyAny>,
    alpha: f64,
    nominal_width: f64,
    window: Option<i64>,
    window_center: Option<i64>,
    spike_threshold: Option<f64>,
    min_depth: f64,
    min_valid: i64,
) -> PyResult<Bound<'py, PyDict>> {
    let (window, window_center) = (count_opt("window", window)?, count_opt("window_center", window_center)?);
    let min_valid = count("min_valid", min_valid)?;
    let xa = f64_array(x, "x", &[Dim::Any("N")], "(reading abscissae, mm)")?;
    let n = xa.shape()[0];
    let za = f64_array(z, "z", &[Dim::Is(n)], "(one frame, one value per x, mm)")?;
    let options = GrooveOptions {
        alpha,
        nominal_width,
        window,
        window_center,
        spike_threshold,
        min_depth,
        min_valid,
        ..GrooveOptions::default()
    };
    options.validate().map_err(to_py_err)?;
    let d = PyDict::new(py);
    match level_frame(xa.as_slice()?, za.as_slice()?, &options) {
        Ok(f) => {
            let (ox, oz) = f.origin;
            let m = f.x.len();
            d.set_item("x", to_numpy(py, f.x.iter().map(|v| v + ox).collect::<Vec<_>>(), &[m])?)?;
            d.set_item("z", to_numpy(py, f.z.iter().map(|v| v + oz).collect::<Vec<_>>(), &[m])?)?;
            d.set_item("tilt", f.tilt)?;
            let st = f.start;
            d.set_item("start", to_numpy(py, vec![st[0] + ox, st[1] + oz, st[2], st[3], st[4]], &[5])?)?;
            d.set_item("status", 0u8)?;
        }
        Err((status, _)) => {
            d.set_item("x", to_numpy(py, Vec::<f64>::new(), &[0])?)?;
            d.set_item("z", to_numpy(py, Vec::<f64>::new(), &[0])?)?;
            d.set_item("tilt", f64::NAN)?;
            d.set_item("start", to_numpy(py, vec![f64::NAN; 5], &[5])?)?;
            d.set_item("status", status as u8)?;
        }
    }
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fit_grooves, m)?)?;
    m.add_function(wrap_pyfunction!(level_groove_frame, m)?)?;
    Ok(())
}
