//! Bindings of `machscan_core::groove`: the batch groove fit and the view of one frame. The options
//! come as `machscan.GrooveOptions`, read by attribute (`Options`); its defaults are the core's
//! `GrooveOptions::default()`, handed to Python by `groove_defaults()`.
use super::convert::{count, count_opt, enter, to_numpy, Dim, F64Array};
use super::error::IntoPy;
use machscan_core::groove::{
    fit_frames, view_frame, FitCriteria, GrooveFit, GrooveLimits, GrooveOptions, GrooveSelect, MisfitPrior, MisfitRule,
    RoundingPrior, RoundingRule, SectionModel, StretchMisfit, TemplateKind, POOLED_FRAMES, SECTION_CRITERIA,
    STRETCH_MEASURES, TANH_CRITERIA,
};
use machscan_core::kinematics::ValidReadings;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `machscan.FitCriteria`, read by attribute.
#[derive(FromPyObject)]
struct Criteria {
    max_iterations: Option<i64>,
    cost_tolerance: Option<f64>,
    step_tolerance: Option<f64>,
    gradient_tolerance: Option<f64>,
}

/// `machscan.GrooveOptions` (a frozen dataclass whose defaults `groove_defaults` gives), read by
/// attribute; the core parses and checks the values.
#[derive(FromPyObject)]
struct Options {
    template: String,
    alpha: f64,
    nominal_width: f64,
    window: Option<i64>,
    window_center: Option<i64>,
    fit_alpha: bool,
    spike_threshold: Option<f64>,
    min_depth: f64,
    min_valid: i64,
    criteria: Criteria,
    sentinel: Option<f64>,
    valid_range: Option<(f64, f64)>,
    select: String,
    index: i64,
    near: Option<f64>,
    min_width: Option<f64>,
    max_width: Option<f64>,
    max_depth: Option<f64>,
    rounding: Py<PyAny>,
    misfit: Py<PyAny>,
}

/// The `rounding` option: "pooled", "frame" or a prior (share, r_max mm).
fn rounding_rule(py: Python<'_>, value: &Py<PyAny>) -> PyResult<RoundingRule> {
    let v = value.bind(py);
    if let Ok(name) = v.extract::<String>() {
        return RoundingRule::parse(&name).py();
    }
    if let Ok((share, r_max)) = v.extract::<(f64, f64)>() {
        return Ok(RoundingRule::Given(RoundingPrior { share, r_max }));
    }
    Err(PyValueError::new_err(format!(
        "rounding: expected \"pooled\", \"frame\" or (share, r_max) with r_max in mm, got {}",
        v.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
    )))
}

/// The `misfit` option: "pooled", "none" or variances by model name (mm²) and by "u:" and a
/// measure (its unit squared) ((name, variance)
/// pairs, as `machscan.GrooveOptions` keeps a mapping).
fn misfit_rule(py: Python<'_>, value: &Py<PyAny>) -> PyResult<MisfitRule> {
    let v = value.bind(py);
    if let Ok(name) = v.extract::<String>() {
        return MisfitRule::parse(&name).py();
    }
    let Ok(pairs) = v.extract::<Vec<(String, f64)>>() else {
        return Err(PyValueError::new_err(format!(
            "misfit: expected \"pooled\", \"none\" or variances by model name (mm²), got {}",
            v.repr().map_or_else(|_| "?".to_string(), |r| r.to_string())
        )));
    };
    let mut prior = MisfitPrior::default();
    for (name, variance) in pairs {
        // "u:<measure>" its variance, "u:<measure>:bias" its mean (either alone: the other 0).
        let stretch = name.strip_prefix("u:").map(|m| m.strip_suffix(":bias").map_or((m, false), |m| (m, true)));
        if let Some((k, bias)) =
            stretch.and_then(|(m, bias)| Some((STRETCH_MEASURES.iter().position(|s| *s == m)?, bias)))
        {
            let s = prior.stretch[k].get_or_insert_with(StretchMisfit::default);
            *(if bias { &mut s.bias } else { &mut s.variance }) = variance;
            continue;
        }
        let Some(model) = SectionModel::ALL.iter().find(|m| m.name() == name) else {
            let names: Vec<&str> = SectionModel::ALL.iter().map(|m| m.name()).collect();
            return Err(PyValueError::new_err(format!(
                "misfit: {name:?} is no section model (expected one of {}) nor \"u:\" and a measure ({}), with \":bias\" or without",
                names.join(", "),
                STRETCH_MEASURES.join(", ")
            )));
        };
        prior.variance[model.index()] = Some(variance);
    }
    Ok(MisfitRule::Given(prior))
}

/// Misfit variances by model name, mm² (the models they were estimated or given for); None
/// for none.
fn misfit_dict<'py>(py: Python<'py>, prior: Option<&MisfitPrior>) -> PyResult<Option<Bound<'py, PyDict>>> {
    let Some(prior) = prior else { return Ok(None) };
    let d = PyDict::new(py);
    for m in SectionModel::ALL {
        if let Some(v) = prior.variance[m.index()] {
            d.set_item(m.name(), v)?;
        }
    }
    for (name, s) in STRETCH_MEASURES.iter().zip(prior.stretch) {
        if let Some(s) = s {
            d.set_item(format!("u:{name}"), s.variance)?;
            d.set_item(format!("u:{name}:bias"), s.bias)?;
        }
    }
    Ok(Some(d))
}

impl Options {
    fn core(self, py: Python<'_>) -> PyResult<GrooveOptions> {
        let rounding = rounding_rule(py, &self.rounding)?;
        let misfit = misfit_rule(py, &self.misfit)?;
        let c = self.criteria;
        Ok(GrooveOptions {
            template: TemplateKind::parse(&self.template).py()?,
            alpha: self.alpha,
            fit_alpha: self.fit_alpha,
            nominal_width: self.nominal_width,
            window: count_opt("window", self.window)?,
            window_center: count_opt("window_center", self.window_center)?,
            spike_threshold: self.spike_threshold,
            min_depth: self.min_depth,
            min_valid: count("min_valid", self.min_valid)?,
            criteria: FitCriteria {
                max_iterations: count_opt("max_iterations", c.max_iterations)?,
                cost_tolerance: c.cost_tolerance,
                step_tolerance: c.step_tolerance,
                gradient_tolerance: c.gradient_tolerance,
            },
            valid: ValidReadings::new(self.valid_range, self.sentinel).py()?,
            select: GrooveSelect::parse(&self.select, count("index", self.index)?, self.near).py()?,
            limits: GrooveLimits { min_width: self.min_width, max_width: self.max_width, max_depth: self.max_depth },
            rounding,
            misfit,
        })
    }
}

/// The options argument: a `GrooveOptions`, or an error naming it.
fn options(obj: &Bound<'_, PyAny>) -> PyResult<GrooveOptions> {
    obj.extract::<Options>()
        .map_err(|e| {
            PyValueError::new_err(format!("options: expected a machscan.GrooveOptions ({})", e.value(obj.py())))
        })?
        .core(obj.py())
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
    d.set_item("select", o.select.name())?;
    let index = match o.select {
        GrooveSelect::Left(k) | GrooveSelect::Right(k) => k,
        _ => 0,
    };
    d.set_item("index", index)?;
    d.set_item("near", None::<f64>)?;
    d.set_item("min_width", o.limits.min_width)?;
    d.set_item("max_width", o.limits.max_width)?;
    d.set_item("max_depth", o.limits.max_depth)?;
    d.set_item("rounding", o.rounding.name())?;
    d.set_item("misfit", o.misfit.name())?;
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

/// Sets the per-row arrays of `fits` and their `frames` into `d` (the `_GrooveFitArrays` keys).
fn fit_arrays(py: Python<'_>, d: &Bound<'_, PyDict>, fits: &[GrooveFit], frames: &[u32]) -> PyResult<()> {
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
    d.set_item("flank_angle_left", to_numpy(py, column(|g| g.flank_angle_left), &[f])?)?;
    d.set_item("flank_angle_right", to_numpy(py, column(|g| g.flank_angle_right), &[f])?)?;
    d.set_item("area", to_numpy(py, column(|g| g.area), &[f])?)?;
    d.set_item("bottom_radius", to_numpy(py, column(|g| g.bottom_radius), &[f])?)?;
    d.set_item("step", to_numpy(py, column(|g| g.step), &[f])?)?;
    d.set_item("se_x0", to_numpy(py, column(|g| g.se_x0), &[f])?)?;
    d.set_item("se_z0", to_numpy(py, column(|g| g.se_z0), &[f])?)?;
    d.set_item("se_flank_angle_left", to_numpy(py, column(|g| g.se_flank_angle_left), &[f])?)?;
    d.set_item("se_flank_angle_right", to_numpy(py, column(|g| g.se_flank_angle_right), &[f])?)?;
    d.set_item("se_area", to_numpy(py, column(|g| g.se_area), &[f])?)?;
    d.set_item("se_bottom_radius", to_numpy(py, column(|g| g.se_bottom_radius), &[f])?)?;
    d.set_item("se_step", to_numpy(py, column(|g| g.se_step), &[f])?)?;
    d.set_item("tilt", to_numpy(py, column(|g| g.tilt), &[f])?)?;
    d.set_item("iterations", to_numpy(py, fits.iter().map(|g| g.iterations as i32).collect::<Vec<_>>(), &[f])?)?;
    d.set_item("n_used", to_numpy(py, fits.iter().map(|g| g.n_used as i32).collect::<Vec<_>>(), &[f])?)?;
    d.set_item("status", to_numpy(py, fits.iter().map(|g| g.status as u8).collect::<Vec<_>>(), &[f])?)?;
    d.set_item("model", to_numpy(py, fits.iter().map(|g| g.model.code()).collect::<Vec<_>>(), &[f])?)?;
    d.set_item("groove", to_numpy(py, fits.iter().map(|g| g.groove).collect::<Vec<_>>(), &[f])?)?;
    d.set_item("frame", to_numpy(py, frames.iter().map(|&v| v as i32).collect::<Vec<_>>(), &[f])?)?;
    Ok(())
}

/// Measure the groove of every frame (SPEC G); ``machscan.fit_grooves`` documents it and wraps
/// the ``_GrooveFitArrays`` this returns.
#[pyfunction]
fn fit_grooves<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    z: &Bound<'py, PyAny>,
    options: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let o = self::options(options)?;
    let xa = F64Array::extract(x, "x", &[Dim::Any("N")], "(reading abscissae, mm)")?;
    let n = xa.shape()[0];
    let za = F64Array::extract(z, "z", &[Dim::Any("F"), Dim::Is(n)], "(one column per x, mm)")?;
    let (xs, zs) = (xa.values()?, za.values()?);
    let rows = enter(py, || fit_frames(xs, zs, &o))?;
    let d = PyDict::new(py);
    fit_arrays(py, &d, &rows.fits, &rows.frame)?;
    d.set_item("rounding_prior", rows.rounding_prior.map(|p| (p.share, p.r_max)))?;
    d.set_item("misfit", misfit_dict(py, rows.misfit.as_ref())?)?;
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
    options: &Bound<'py, PyAny>,
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
    fit_arrays(py, &fit, &[view.fit], &[0])?;
    let given = match o.rounding {
        RoundingRule::Given(p) => Some((p.share, p.r_max)),
        _ => None,
    };
    fit.set_item("rounding_prior", given)?;
    let given = match &o.misfit {
        MisfitRule::Given(p) => Some(p),
        _ => None,
    };
    fit.set_item("misfit", misfit_dict(py, given)?)?;
    d.set_item("fit", fit)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(groove_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(fit_criteria_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(fit_grooves, m)?)?;
    m.add_function(wrap_pyfunction!(view_groove_frame, m)?)?;
    m.add("ROUNDING_POOLED_FRAMES", POOLED_FRAMES)?;
    Ok(())
}
