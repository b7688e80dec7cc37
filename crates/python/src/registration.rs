//! Bindings of `machscan_core::registration`. Every option is a required keyword here: the Python
//! signatures give the defaults (ICP's read from `icp_defaults()`, which reads `IcpOptions::new`
//! in the core), so each default is written once.
use super::convert::{count, enter, f64_vector, indices_to_numpy, to_numpy, Dim, F64Array};
use super::error::IntoPy;
use machscan_core::registration::{
    align_blank as run_align_blank, allowance as run_allowance, allowance::PLANE_POINTS, cloud_locating_points,
    coarse_align as run_coarse_align, envelope_fit as run_envelope_fit, grid_locating_points, icp as run_icp,
    icp::NORMAL_NEIGHBORS, positioning_errors as run_positioning_errors, probe_fit as run_probe_fit, BlankOptions,
    BlankSurface, IcpMethod, IcpOptions, IcpResult, ProbePattern, Robust, RobustKernel,
};
use machscan_core::registration::{fit_to_mesh as run_fit_to_mesh, Dof, MeshFitOptions, RotaryAxis};
use nalgebra::Matrix4;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The defaults of the ICP options (``IcpOptions::new`` in the core), by name.
#[pyfunction]
fn icp_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let o = IcpOptions::new(f64::NAN);
    let d = PyDict::new(py);
    d.set_item("method", o.method.name())?;
    d.set_item("max_iterations", o.max_iterations)?;
    d.set_item("relative_fitness", o.relative_fitness)?;
    d.set_item("relative_rmse", o.relative_rmse)?;
    d.set_item("mse_threshold", o.mse_threshold)?;
    d.set_item("robust", o.robust.map(|r| r.kernel.name()))?;
    d.set_item("trim", o.trim)?;
    d.set_item("normal_neighbors", NORMAL_NEIGHBORS)?;
    Ok(d)
}

/// A 4×4 transform argument, the identity when omitted.
fn transform_opt(obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Matrix4<f64>> {
    let a = F64Array::extract_opt(obj, name, &[Dim::Is(4), Dim::Is(4)], "(a 4×4 rigid transform)")?;
    match &a {
        Some(a) => Ok(Matrix4::from_row_slice(a.values()?)),
        None => Ok(Matrix4::identity()),
    }
}

/// Model points and their normals, one per point.
fn model_with_normals<'py>(
    model_points: &Bound<'py, PyAny>,
    model_normals: &Bound<'py, PyAny>,
) -> PyResult<(F64Array<'py>, F64Array<'py>)> {
    let model = F64Array::points(model_points, "model_points")?;
    let n = model.shape()[0];
    let normals =
        F64Array::extract(model_normals, "model_normals", &[Dim::Is(n), Dim::Is(3)], "(one normal per model point)")?;
    Ok((model, normals))
}

/// A 4×4 transform as a NumPy array.
fn transform_to_numpy<'py>(py: Python<'py>, t: &Matrix4<f64>) -> PyResult<Bound<'py, PyAny>> {
    to_numpy(py, t.transpose().as_slice().to_vec(), &[4, 4])
}

/// Iterative closest point (SPEC R2) with Open3D's definitions; ``machscan.icp`` documents it
/// and wraps the ``_IcpArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (source, target, max_distance, *, init, target_normals, method, max_iterations,
    relative_fitness, relative_rmse, robust, robust_scale, trim, mse_threshold))]
#[allow(clippy::too_many_arguments)]
fn icp<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    target: &Bound<'py, PyAny>,
    max_distance: f64,
    init: Option<&Bound<'py, PyAny>>,
    target_normals: Option<&Bound<'py, PyAny>>,
    method: &str,
    max_iterations: i64,
    relative_fitness: f64,
    relative_rmse: f64,
    robust: Option<&str>,
    robust_scale: Option<f64>,
    trim: f64,
    mse_threshold: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let src = F64Array::points(source, "source")?;
    let tgt = F64Array::points(target, "target")?;
    let m = tgt.shape()[0];
    let normals = F64Array::extract_opt(
        target_normals,
        "target_normals",
        &[Dim::Is(m), Dim::Is(3)],
        "(one normal per target point)",
    )?;
    let init = transform_opt(init, "init")?;
    let options = IcpOptions {
        max_distance,
        method: IcpMethod::parse(method).py()?,
        max_iterations: count("max_iterations", max_iterations)?,
        relative_fitness,
        relative_rmse,
        mse_threshold,
        robust: robust.map(RobustKernel::parse).transpose().py()?.map(|kernel| Robust { kernel, scale: robust_scale }),
        trim,
    };
    let (s, t) = (src.rows::<3>()?, tgt.rows::<3>()?);
    let n = normals.as_ref().map(|a| a.rows::<3>()).transpose()?;
    let r = enter(py, || run_icp(s, t, n, &init, &options))?;
    icp_arrays(py, &r)
}

/// The ``_IcpArrays`` of an ICP result (also the first keys of the fit to a mesh).
fn icp_arrays<'py>(py: Python<'py>, r: &IcpResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("transformation", transform_to_numpy(py, &r.transformation)?)?;
    d.set_item("fitness", r.fitness)?;
    d.set_item("rmse", r.rmse)?;
    d.set_item("correspondences", r.correspondences)?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("converged", r.converged)?;
    let k = r.history.len();
    d.set_item("history_fitness", to_numpy(py, r.history.iter().map(|h| h.fitness).collect(), &[k])?)?;
    d.set_item("history_rmse", to_numpy(py, r.history.iter().map(|h| h.rmse).collect(), &[k])?)?;
    Ok(d)
}

/// The fit of a scan to a mesh in chosen motions; ``machscan.fit_to_mesh`` documents it and
/// wraps the arrays this returns.
#[pyfunction]
#[pyo3(signature = (points, vertices, triangles, max_distance, *, init, dof, axis_point, axis_direction,
    max_iterations, relative_fitness, relative_rmse))]
#[allow(clippy::too_many_arguments)]
fn fit_to_mesh<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    vertices: &Bound<'py, PyAny>,
    triangles: &Bound<'py, PyAny>,
    max_distance: f64,
    init: Option<&Bound<'py, PyAny>>,
    dof: &str,
    axis_point: Option<&Bound<'py, PyAny>>,
    axis_direction: Option<&Bound<'py, PyAny>>,
    max_iterations: i64,
    relative_fitness: f64,
    relative_rmse: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let p = F64Array::points(points, "points")?;
    let (v, tri) = super::mesh::mesh_named(vertices, triangles, "triangles")?;
    let init = transform_opt(init, "init")?;
    let axis = match (axis_point, axis_direction) {
        (Some(point), Some(direction)) => Some(RotaryAxis {
            point: f64_vector::<3>(point, "axis", "(the axis point, mm)")?,
            direction: f64_vector::<3>(direction, "axis", "(the axis direction)")?,
        }),
        _ => None,
    };
    let options = MeshFitOptions {
        max_distance,
        max_iterations: count("max_iterations", max_iterations)?,
        relative_fitness,
        relative_rmse,
        dof: Dof::parse(dof).py()?,
        axis,
    };
    let (pr, vr) = (p.rows::<3>()?, v.rows::<3>()?);
    let r = enter(py, || run_fit_to_mesh(pr, vr, &tri, &init, &options).map_err(|e| e.renamed("faces", "triangles")))?;
    let d = icp_arrays(py, &r.icp)?;
    d.set_item("motion", r.motion.to_vec())?;
    d.set_item("undetermined", r.undetermined)?;
    Ok(d)
}

/// Coarse alignment (SPEC R3, paper 004): the rigid transform (4×4, applied to the source) that
/// puts the source's principal frame (centroid and covariance axes) on the target's, trying the
/// four proper sign choices of the axes and keeping the one whose moved source lies closest to
/// the target. A start for :func:`machscan.icp` from any orientation, on a part without
/// symmetry.
///
/// Parameters
/// ----------
/// source, target : array_like, shape (N, 3), (M, 3)
///     mm; at least 4 points each.
///
/// Returns
/// -------
/// ndarray, shape (4, 4)
///
/// Examples
/// --------
/// >>> init = machscan.coarse_align(measured, model)
/// >>> r = machscan.icp(measured, model, 1.0, init)
#[pyfunction]
fn coarse_align<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    target: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let src = F64Array::points(source, "source")?;
    let tgt = F64Array::points(target, "target")?;
    let (s, t) = (src.rows::<3>()?, tgt.rows::<3>()?);
    let m = enter(py, || run_coarse_align(s, t))?;
    transform_to_numpy(py, &m)
}

/// Probe points on the flattest share of a cloud (SPEC R4): surface variation over the k
/// nearest points; ``machscan.locating_points`` documents it.
#[pyfunction]
#[pyo3(signature = (points, *, m, keep, k, seed, normals, pattern))]
#[allow(clippy::too_many_arguments)]
fn locating_points_cloud<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    m: i64,
    keep: f64,
    k: i64,
    seed: u64,
    normals: Option<&Bound<'py, PyAny>>,
    pattern: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let (m, k, pattern) = (count("m", m)?, count("k", k)?, ProbePattern::parse(pattern).py()?);
    let arr = F64Array::points(points, "points")?;
    let n = arr.shape()[0];
    let normals = F64Array::extract_opt(normals, "normals", &[Dim::Is(n), Dim::Is(3)], "(one normal per point)")?;
    let pts = arr.rows::<3>()?;
    let nv = normals.as_ref().map(|a| a.rows::<3>()).transpose()?;
    let chosen = enter(py, || cloud_locating_points(pts, nv, m, keep, k, seed, pattern))?;
    indices_to_numpy(py, chosen)
}

/// Probe points on the flattest share of a gridded scan ``(nu, nv, 3)`` (SPEC R4): U-direction
/// line curvature; ``machscan.locating_points`` documents it.
#[pyfunction]
#[pyo3(signature = (points, *, m, keep, seed, normals, pattern))]
fn locating_points_grid<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    m: i64,
    keep: f64,
    seed: u64,
    normals: Option<&Bound<'py, PyAny>>,
    pattern: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let (m, pattern) = (count("m", m)?, ProbePattern::parse(pattern).py()?);
    let arr = F64Array::extract(points, "points", &[Dim::Any("nu"), Dim::Any("nv"), Dim::Is(3)], "(a gridded scan)")?;
    let (nu, nv) = (arr.shape()[0], arr.shape()[1]);
    let normals = F64Array::extract_opt(
        normals,
        "normals",
        &[Dim::Is(nu), Dim::Is(nv), Dim::Is(3)],
        "(one normal per grid point)",
    )?;
    let pts = arr.rows::<3>()?;
    let normal_rows = normals.as_ref().map(|a| a.rows::<3>()).transpose()?;
    let chosen = enter(py, || grid_locating_points(pts, nu, nv, normal_rows, m, keep, seed, pattern))?;
    indices_to_numpy(py, chosen)
}

/// The blank's surface options as ``machscan.allowance`` and ``machscan.envelope_fit`` take them.
fn blank_options(surface: &str, k: Option<i64>, spacing: Option<f64>) -> PyResult<BlankOptions> {
    Ok(BlankOptions { surface: BlankSurface::parse(surface).py()?, k: k.map(|k| count("k", k)).transpose()?, spacing })
}

/// Machining allowance (SPEC R7); ``machscan.allowance`` documents it (with the plane's default
/// ``k``, ``ALLOWANCE_NEIGHBORS``).
#[pyfunction]
#[pyo3(signature = (model_points, model_normals, blank_points, *, surface, k, spacing))]
fn allowance<'py>(
    py: Python<'py>,
    model_points: &Bound<'py, PyAny>,
    model_normals: &Bound<'py, PyAny>,
    blank_points: &Bound<'py, PyAny>,
    surface: &str,
    k: Option<i64>,
    spacing: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let options = blank_options(surface, k, spacing)?;
    let (model, normals) = model_with_normals(model_points, model_normals)?;
    let n = model.shape()[0];
    let blank = F64Array::points(blank_points, "blank_points")?;
    let (m, v, b) = (model.rows::<3>()?, normals.rows::<3>()?, blank.rows::<3>()?);
    let a = enter(py, || run_allowance(m, v, b, &options))?;
    to_numpy(py, a, &[n])
}

/// Positioning errors (SPEC R5); ``machscan.positioning_errors`` documents it and wraps the
/// ``(N, 3)`` per-axis errors this returns.
#[pyfunction]
#[pyo3(signature = (measured, model_points, *, model_normals))]
fn positioning_errors<'py>(
    py: Python<'py>,
    measured: &Bound<'py, PyAny>,
    model_points: &Bound<'py, PyAny>,
    model_normals: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let meas = F64Array::points(measured, "measured")?;
    let model = F64Array::points(model_points, "model_points")?;
    let n = model.shape()[0];
    let normals = F64Array::extract_opt(
        model_normals,
        "model_normals",
        &[Dim::Is(n), Dim::Is(3)],
        "(one normal per model point)",
    )?;
    let (p, q) = (meas.rows::<3>()?, model.rows::<3>()?);
    let nv = normals.as_ref().map(|a| a.rows::<3>()).transpose()?;
    let e = enter(py, || run_positioning_errors(p, q, nv))?;
    super::convert::points_to_numpy(py, e)
}

/// The pose of a part from one round of touch-probe points (SPEC R6, paper 003 §4);
/// ``machscan.position_workpiece`` runs the rounds and documents it.
#[pyfunction]
#[pyo3(signature = (measured, model_points, model_normals, *, probe_radius, init))]
fn probe_fit<'py>(
    py: Python<'py>,
    measured: &Bound<'py, PyAny>,
    model_points: &Bound<'py, PyAny>,
    model_normals: &Bound<'py, PyAny>,
    probe_radius: f64,
    init: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (model, normals) = model_with_normals(model_points, model_normals)?;
    let n = model.shape()[0];
    let meas = F64Array::extract(measured, "measured", &[Dim::Is(n), Dim::Is(3)], "(one probe point per model point)")?;
    let init = transform_opt(init, "init")?;
    let (p, q, v) = (meas.rows::<3>()?, model.rows::<3>()?, normals.rows::<3>()?);
    let fit = enter(py, || run_probe_fit(p, q, v, probe_radius, &init))?;
    let d = PyDict::new(py);
    d.set_item("transformation", transform_to_numpy(py, &fit.transformation)?)?;
    d.set_item("residuals", to_numpy(py, fit.residuals, &[n])?)?;
    d.set_item("iterations", fit.iterations)?;
    Ok(d)
}

/// The balanced envelope fit of a blank (SPEC R8); ``machscan.envelope_fit`` documents it.
#[pyfunction]
#[pyo3(signature = (model_points, model_normals, blank_points, *, min_allowance, surface, k, spacing, init))]
#[allow(clippy::too_many_arguments)]
fn envelope_fit<'py>(
    py: Python<'py>,
    model_points: &Bound<'py, PyAny>,
    model_normals: &Bound<'py, PyAny>,
    blank_points: &Bound<'py, PyAny>,
    min_allowance: f64,
    surface: &str,
    k: Option<i64>,
    spacing: Option<f64>,
    init: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let options = blank_options(surface, k, spacing)?;
    let (model, normals) = model_with_normals(model_points, model_normals)?;
    let blank = F64Array::points(blank_points, "blank_points")?;
    let init = transform_opt(init, "init")?;
    let (m, v, b) = (model.rows::<3>()?, normals.rows::<3>()?, blank.rows::<3>()?);
    let fit = enter(py, || run_envelope_fit(m, v, b, min_allowance, &options, &init))?;
    envelope_dict(py, fit)
}

/// The envelope fit's arrays (the ``_EnvelopeFitArrays`` keys).
fn envelope_dict<'py>(py: Python<'py>, fit: machscan_core::registration::EnvelopeFit) -> PyResult<Bound<'py, PyDict>> {
    let n = fit.allowance.len();
    let d = PyDict::new(py);
    d.set_item("transformation", transform_to_numpy(py, &fit.transformation)?)?;
    d.set_item("allowance", to_numpy(py, fit.allowance, &[n])?)?;
    d.set_item("feasible", fit.feasible)?;
    d.set_item("iterations", fit.iterations)?;
    d.set_item("converged", fit.converged)?;
    Ok(d)
}

/// The blank found from where a plant starts: coarse alignment, ICP, the envelope fit;
/// ``machscan.align_blank`` documents it and wraps the ``_BlankAlignmentArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (model_points, model_normals, blank_points, *, min_allowance, surface, k, spacing, init))]
#[allow(clippy::too_many_arguments)]
fn align_blank<'py>(
    py: Python<'py>,
    model_points: &Bound<'py, PyAny>,
    model_normals: &Bound<'py, PyAny>,
    blank_points: &Bound<'py, PyAny>,
    min_allowance: f64,
    surface: &str,
    k: Option<i64>,
    spacing: Option<f64>,
    init: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let options = blank_options(surface, k, spacing)?;
    let (model, normals) = model_with_normals(model_points, model_normals)?;
    let n = model.shape()[0];
    let blank = F64Array::points(blank_points, "blank_points")?;
    let init = transform_opt(init, "init")?;
    let (m, v, b) = (model.rows::<3>()?, normals.rows::<3>()?, blank.rows::<3>()?);
    let r = enter(py, || run_align_blank(m, v, b, min_allowance, &options, &init))?;
    let stages = pyo3::types::PyList::empty(py);
    for stage in r.stages {
        let d = PyDict::new(py);
        d.set_item("name", stage.name)?;
        d.set_item("transformation", transform_to_numpy(py, &stage.transformation)?)?;
        d.set_item("fitness", stage.fitness)?;
        d.set_item("rmse", stage.rmse)?;
        d.set_item("allowance", to_numpy(py, stage.allowance, &[n])?)?;
        stages.append(d)?;
    }
    let d = PyDict::new(py);
    d.set_item("stages", stages)?;
    d.set_item("fit", envelope_dict(py, r.fit)?)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(align_blank, m)?)?;
    m.add("ALLOWANCE_NEIGHBORS", PLANE_POINTS)?;
    m.add_function(wrap_pyfunction!(probe_fit, m)?)?;
    m.add_function(wrap_pyfunction!(envelope_fit, m)?)?;
    m.add_function(wrap_pyfunction!(positioning_errors, m)?)?;
    m.add_function(wrap_pyfunction!(allowance, m)?)?;
    m.add_function(wrap_pyfunction!(locating_points_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(locating_points_grid, m)?)?;
    m.add_function(wrap_pyfunction!(coarse_align, m)?)?;
    m.add_function(wrap_pyfunction!(icp_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(icp, m)?)?;
    m.add_function(wrap_pyfunction!(fit_to_mesh, m)?)?;
    Ok(())
}
