//! Bindings of `crate::groove`: the batch groove fit. The defaults of every option are
//! `GrooveOptions::default()`, handed to Python by `groove_defaults` (the one source the Python
//! signatures read), so the fit functions here take every option as a required keyword.
use super::convert::{count, count_opt, enter, to_numpy, Dim, F64Array};
use crate::groove::{fit_frames, level_frame, GrooveOptions, TemplateKind};
use pyo3::prelude::*;
use pyo3::types::PyDict;

#[allow(clippy::too_many_arguments)]
fn options(
    template: &str,
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
) -> PyResult<GrooveOptions> {
    Ok(GrooveOptions {
        template: TemplateKind::parse(template)?,
        alpha,
        fit_alpha,
        nominal_width,
        window: count_opt("window", window)?,
        window_center: count_opt("window_center", window_center)?,
        spike_threshold,
        min_depth,
        min_valid: count("min_valid", min_valid)?,
        max_iterations: count("max_iterations", max_iterations)?,
        cost_tolerance,
        step_tolerance,
        gradient_tolerance,
    })
}

/// The defaults of the groove fit options (``GrooveOptions::default()`` in the core), by name.
#[pyfunction]
fn groove_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let o = GrooveOptions::default();
    let d = PyDict::new(py);
    d.set_item("template", o.template.name())?;
    d.set_item("alpha", o.alpha)?;
    d.set_item("fit_alpha", o.fit_alpha)?;
    d.set_item("nominal_width", o.nominal_width)?;
    d.set_item("window", o.window)?;
    d.set_item("window_center", o.window_center)?;
    d.set_item("spike_threshold", o.spike_threshold)?;
    d.set_item("min_depth", o.min_depth)?;
    d.set_item("min_valid", o.min_valid)?;
    d.set_item("max_iterations", o.max_iterations)?;
    d.set_item("cost_tolerance", o.cost_tolerance)?;
    d.set_item("step_tolerance", o.step_tolerance)?;
    d.set_item("gradient_tolerance", o.gradient_tolerance)?;
    Ok(d)
}

/// Fit the groove template to every frame (SPEC G); ``machscan.fit_grooves`` documents it and
/// wraps the ``GrooveFitArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (x, z, *, template, alpha, nominal_width, window, window_center, fit_alpha, spike_threshold,
    min_depth, min_valid, max_iterations, cost_tolerance, step_tolerance, gradient_tolerance))]
#[allow(clippy::too_many_arguments)]
fn fit_grooves<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    z: &Bound<'py, PyAny>,
    template: &str,
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
) -> PyResult<Bound<'py, PyDict>> {
    let o = options(
        template,
        alpha,
        nominal_width,
        window,
        window_center,
        fit_alpha,
        spike_threshold,
        min_depth,
        min_valid,
        max_iterations,
        cost_tolerance,
        step_tolerance,
        gradient_tolerance,
    )?;
    let xa = F64Array::extract(x, "x", &[Dim::Any("N")], "(reading abscissae, mm)")?;
    let n = xa.shape()[0];
    let za = F64Array::extract(z, "z", &[Dim::Any("F"), Dim::Is(n)], "(one column per x, mm)")?;
    let f = za.shape()[0];
    let (xs, zs) = (xa.values()?, za.values()?);
    let fits = enter(py, || fit_frames(xs, zs, &o))?;
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
/// wraps the ``LevelledFrameArrays`` this returns: the levelled ``x``, ``z`` (absolute levelled
/// coordinates), ``tilt``, the initial guess ``start`` (x0, z0, d, w, α) and ``status`` (0 when
/// ready).
#[pyfunction]
#[pyo3(signature = (x, z, *, alpha, nominal_width, window, window_center, spike_threshold, min_depth, min_valid))]
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
    let o = GrooveOptions {
        alpha,
        nominal_width,
        window: count_opt("window", window)?,
        window_center: count_opt("window_center", window_center)?,
        spike_threshold,
        min_depth,
        min_valid: count("min_valid", min_valid)?,
        ..GrooveOptions::default()
    };
    let xa = F64Array::extract(x, "x", &[Dim::Any("N")], "(reading abscissae, mm)")?;
    let n = xa.shape()[0];
    let za = F64Array::extract(z, "z", &[Dim::Is(n)], "(one frame, one value per x, mm)")?;
    let (xs, zs) = (xa.values()?, za.values()?);
    let frame = enter(py, || {
        o.validate()?;
        Ok(level_frame(xs, zs, &o))
    })?;
    let d = PyDict::new(py);
    match frame {
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
    m.add_function(wrap_pyfunction!(groove_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(fit_grooves, m)?)?;
    m.add_function(wrap_pyfunction!(level_groove_frame, m)?)?;
    Ok(())
}
