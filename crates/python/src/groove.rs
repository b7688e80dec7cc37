//! Bindings of `machscan_core::groove`: the batch groove fit and the view of one frame. The options
//! travel as one dict with exactly the keys of `groove_defaults()` (the `_GrooveOptions`
//! TypedDict of the stub), so they are spelled and defaulted in one place each: here from
//! `GrooveOptions::default()`, and by the Python signatures that read `groove_defaults()`.
use super::convert::{count, enter, f64_vector_opt, to_numpy, Dim, F64Array};
use super::error::IntoPy;
use machscan_core::groove::{
    fit_frames, view_frame, FitCriteria, GrooveFit, GrooveOptions, TemplateKind, SECTION_CRITERIA, TANH_CRITERIA,
};
use machscan_core::kinematics::ValidReadings;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

const KEYS: [&str; 15] = [
    "template",
    "alpha",
    "nominal_width",
    "window",
    "window_center",
    "fit_alpha",
    "spike_threshold",
    "min_depth",
    "min_valid",
    "max_iterations",
    "cost_tolerance",
    "step_tolerance",
    "gradient_tolerance",
    "sentinel",
    "valid_range",
];

/// `GrooveOptions` from the options dict; a missing or unknown key is an error naming it.
fn options(d: &Bound<'_, PyDict>) -> PyResult<GrooveOptions> {
    for k in d.keys() {
        let k: String = k.extract()?;
        if !KEYS.contains(&k.as_str()) {
            return Err(PyValueError::new_err(format!("options: unknown groove option {k:?}")));
        }
    }
    let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(k)?.ok_or_else(|| PyValueError::new_err(format!("options: {k:?} is missing")))
    };
    let typed = |k: &str, what: &str| PyValueError::new_err(format!("{k}: expected {what}"));
    let float = |k: &str| -> PyResult<f64> { get(k)?.extract().map_err(|_| typed(k, "a number")) };
    let opt_float = |k: &str| -> PyResult<Option<f64>> { get(k)?.extract().map_err(|_| typed(k, "a number or None")) };
    let int = |k: &str| -> PyResult<i64> { get(k)?.extract().map_err(|_| typed(k, "an integer")) };
    let opt_count = |k: &str| -> PyResult<Option<usize>> {
        let v: Option<i64> = get(k)?.extract().map_err(|_| typed(k, "an integer or None"))?;
        v.map(|v| count(k, v)).transpose()
    };
    let template: String = get("template")?.extract().map_err(|_| typed("template", "a str"))?;
    Ok(GrooveOptions {
        template: TemplateKind::parse(&template).py()?,
        alpha: float("alpha")?,
        fit_alpha: get("fit_alpha")?.extract().map_err(|_| typed("fit_alpha", "a bool"))?,
        nominal_width: float("nominal_width")?,
        window: opt_count("window")?,
        window_center: opt_count("window_center")?,
        spike_threshold: opt_float("spike_threshold")?,
        min_depth: float("min_depth")?,
        min_valid: count("min_valid", int("min_valid")?)?,
        criteria: FitCriteria {
            max_iterations: opt_count("max_iterations")?,
            cost_tolerance: opt_float("cost_tolerance")?,
            step_tolerance: opt_float("step_tolerance")?,
            gradient_tolerance: opt_float("gradient_tolerance")?,
        },
        valid: ValidReadings::new(
            f64_vector_opt::<2>(Some(&get("valid_range")?), "valid_range", "(lo, hi) in mm")?.map(|[lo, hi]| (lo, hi)),
            opt_float("sentinel")?,
        )
        .py()?,
    })
}

/// The defaults of the groove options (``GrooveOptions::default()`` in the core), by name; the
/// fit criteria are None (each method's own), whose values ``fit_criteria_defaults`` gives.
#[pyfunction]
fn groove_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let o = GrooveOptions::default();
    let d = PyDict::new(py);
    d.set_item("template", o.template.name())?;
    d.set_item("alpha", o.alpha)?;
    d.set_item("nominal_width", o.nominal_width)?;
    d.set_item("window", o.window)?;
    d.set_item("window_center", o.window_center)?;
    d.set_item("fit_alpha", o.fit_alpha)?;
    d.set_item("spike_threshold", o.spike_threshold)?;
    d.set_item("min_depth", o.min_depth)?;
    d.set_item("min_valid", o.min_valid)?;
    d.set_item("max_iterations", o.criteria.max_iterations)?;
    d.set_item("cost_tolerance", o.criteria.cost_tolerance)?;
    d.set_item("step_tolerance", o.criteria.step_tolerance)?;
    d.set_item("gradient_tolerance", o.criteria.gradient_tolerance)?;
    d.set_item("sentinel", o.valid.sentinel)?;
    let range = (o.valid.lo, o.valid.hi);
    d.set_item("valid_range", (range.0.is_finite() || range.1.is_finite()).then_some(range))?;
    Ok(d)
}

/// The fit criteria each method uses when they are left at None: ``{"tanh": {...},
/// "section": {...}}`` with ``max_iterations``, ``cost_tolerance``, ``step_tolerance``,
/// ``gradient_tolerance``.
#[pyfunction]
fn fit_criteria_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    let t = PyDict::new(py);
    t.set_item("max_iterations", TANH_CRITERIA.max_iterations)?;
    t.set_item("cost_tolerance", TANH_CRITERIA.cost_tolerance)?;
    t.set_item("step_tolerance", TANH_CRITERIA.step_tolerance)?;
    t.set_item("gradient_tolerance", TANH_CRITERIA.gradient_tolerance)?;
    out.set_item("tanh", t)?;
    let s = PyDict::new(py);
    s.set_item("max_iterations", SECTION_CRITERIA.max_iterations)?;
    s.set_item("cost_tolerance", SECTION_CRITERIA.cost_tolerance)?;
    s.set_item("step_tolerance", SECTION_CRITERIA.step_tolerance)?;
    s.set_item("gradient_tolerance", SECTION_CRITERIA.gradient_tolerance)?;
    out.set_item("section", s)?;
    Ok(out)
}

/// Sets the per-frame arrays of `fits` into `d` (the `_GrooveFitArrays` keys).
fn fit_arrays(py: Python<'_>, d: &Bound<'_, PyDict>, fits: &[GrooveFit]) -> PyResult<()> {
    let f = fits.len();
    let column = |get: fn(&GrooveFit) -> f64| fits.iter().map(get).collect::<Vec<f64>>();
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
    d.set_item("model", to_numpy(py, fits.iter().map(|g| g.model.code()).collect::<Vec<_>>(), &[f])?)?;
    Ok(())
}

/// Measure the groove of every frame (SPEC G); ``machscan.fit_grooves`` documents it and wraps
/// the ``_GrooveFitArrays`` this returns.
#[pyfunction]
fn fit_grooves<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    z: &Bound<'py, PyAny>,
    options: &Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    let o = self::options(options)?;
    let xa = F64Array::extract(x, "x", &[Dim::Any("N")], "(reading abscissae, mm)")?;
    let n = xa.shape()[0];
    let za = F64Array::extract(z, "z", &[Dim::Any("F"), Dim::Is(n)], "(one column per x, mm)")?;
    let (xs, zs) = (xa.values()?, za.values()?);
    let fits = enter(py, || fit_frames(xs, zs, &o))?;
    let d = PyDict::new(py);
    fit_arrays(py, &d, &fits)?;
    Ok(d)
}

/// One frame as the fit sees it: the levelled readings ``x``, ``z``, the fitted shape
/// ``shape_x``, ``shape_z`` (evaluated here, so figures draw exactly what was fitted), the
/// ``tilt`` and the fit of that frame (``_GrooveFitArrays`` of length 1);
/// ``machscan.level_groove_frame`` wraps the ``_FrameViewArrays`` this returns.
#[pyfunction]
fn view_groove_frame<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    z: &Bound<'py, PyAny>,
    options: &Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    let o = self::options(options)?;
    let xa = F64Array::extract(x, "x", &[Dim::Any("N")], "(reading abscissae, mm)")?;
    let n = xa.shape()[0];
    let za = F64Array::extract(z, "z", &[Dim::Is(n)], "(one frame, one value per x, mm)")?;
    let (xs, zs) = (xa.values()?, za.values()?);
    let view = enter(py, || view_frame(xs, zs, &o))?;
    let d = PyDict::new(py);
    let (m, k) = (view.x.len(), view.shape_x.len());
    d.set_item("x", to_numpy(py, view.x, &[m])?)?;
    d.set_item("z", to_numpy(py, view.z, &[m])?)?;
    d.set_item("shape_x", to_numpy(py, view.shape_x, &[k])?)?;
    d.set_item("shape_z", to_numpy(py, view.shape_z, &[k])?)?;
    d.set_item("tilt", view.tilt)?;
    let fit = PyDict::new(py);
    fit_arrays(py, &fit, &[view.fit])?;
    d.set_item("fit", fit)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(groove_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(fit_criteria_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(fit_grooves, m)?)?;
    m.add_function(wrap_pyfunction!(view_groove_frame, m)?)?;
    Ok(())
}
