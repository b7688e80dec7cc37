//! Bindings of `machscan_core::toolpath`.
use super::convert::{
    count, enter, enter_long, f64_vector, f64_vector_opt, indices_to_numpy, points_to_numpy, to_numpy, Dim, F64Array,
};
use super::error::IntoPy;
use super::mesh::surface;
use machscan_core::mesh::ScanSurface;
use machscan_core::toolpath::bead_chain::{bead_chain as run_bead_chain, Chain};
use machscan_core::toolpath::grinding::{
    grinding_paths as run_grinding_paths, simulate_removal as run_simulate_removal, GrindingOptions, RemovalModel,
    Stock,
};
use machscan_core::toolpath::scallop::{scallop_height, step_over};
use machscan_core::toolpath::{compensate_toolpath as run_compensate, CompensateOptions, Interpolation, Normals};
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
        interpolation: Interpolation::parse(interpolation).py()?,
        normals: Normals::parse(normals).py()?,
        radius,
        max_edge,
    };
    let (tmr, amr, apr) = (tm.rows::<3>()?, am.rows::<3>()?, ap.rows::<3>()?);
    let actual = ScanSurface { points: apr, faces: af.as_deref() };
    let r = enter(py, || run_compensate(&points, axes.as_deref(), tmr, amr, actual, options))?;
    let m = r.points.len();
    let d = PyDict::new(py);
    d.set_item("points", points_to_numpy(py, r.points)?)?;
    d.set_item("axes", points_to_numpy(py, r.axes)?)?;
    d.set_item("inside", to_numpy(py, r.inside, &[m])?)?;
    d.set_item("on_scan", to_numpy(py, r.on_scan, &[m])?)?;
    d.set_item("offsets", to_numpy(py, r.offsets, &[m])?)?;
    Ok(d)
}

/// One of the scallop relations over equally long flat arrays; an error names the element when
/// there is more than one.
fn elementwise<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    c: &Bound<'py, PyAny>,
    names: [&str; 3],
    f: fn(f64, f64, f64) -> machscan_core::Result<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let [a, b, c] = [(a, names[0]), (b, names[1]), (c, names[2])]
        .map(|(x, name)| F64Array::extract(x, name, &[Dim::Any("N")], "(broadcast by machscan)"));
    let (a, b, c) = (a?, b?, c?);
    let (a, b, c) = (a.values()?, b.values()?, c.values()?);
    let n = a.len();
    let out = enter(py, || {
        (0..n)
            .map(|i| {
                f(a[i], b[i], c[i]).map_err(|e| match e {
                    machscan_core::Error::Invalid { name, reason } if n > 1 => {
                        machscan_core::Error::invalid(&name, format!("element {i}: {reason}"))
                    }
                    other => other,
                })
            })
            .collect::<machscan_core::Result<Vec<f64>>>()
    })?;
    to_numpy(py, out, &[n])
}

/// Scallop heights (SPEC P3); ``machscan.scallop_height`` documents it.
#[pyfunction]
fn scallop_heights<'py>(
    py: Python<'py>,
    tool_radius: &Bound<'py, PyAny>,
    curvature_radius: &Bound<'py, PyAny>,
    step: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    elementwise(py, tool_radius, curvature_radius, step, ["tool_radius", "curvature_radius", "step"], scallop_height)
}

/// Step-overs (SPEC P3); ``machscan.step_over`` documents it.
#[pyfunction]
fn step_overs<'py>(
    py: Python<'py>,
    tool_radius: &Bound<'py, PyAny>,
    curvature_radius: &Bound<'py, PyAny>,
    scallop_height: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    elementwise(
        py,
        tool_radius,
        curvature_radius,
        scallop_height,
        ["tool_radius", "curvature_radius", "scallop_height"],
        step_over,
    )
}

/// Bead-chain ordering (SPEC P2); ``machscan.bead_chain`` documents it and wraps the
/// ``_BeadChainArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (points, start, direction, *, method))]
fn bead_chain<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    start: Option<&Bound<'py, PyAny>>,
    direction: Option<&Bound<'py, PyAny>>,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let p = F64Array::points(points, "points")?;
    let start = f64_vector_opt::<3>(start, "start", "(a point x, y, z)")?;
    let direction = f64_vector_opt::<3>(direction, "direction", "(a vector)")?;
    let method = Chain::parse(method).py()?;
    let pr = p.rows::<3>()?;
    let r = enter(py, || run_bead_chain(pr, start, direction, method))?;
    let d = PyDict::new(py);
    d.set_item("order", indices_to_numpy(py, r.order)?)?;
    d.set_item("closed", r.closed)?;
    Ok(d)
}

/// The removal model's parameters as ``machscan.RemovalModel`` hands them over.
type RemovalArgs = (f64, [f64; 3], f64, f64, [f64; 2]);

fn removal_model(args: RemovalArgs) -> machscan_core::Result<RemovalModel> {
    let (c, exponents, belt_speed, force, feed_limits) = args;
    RemovalModel::new(c, exponents, belt_speed, force, feed_limits)
}

fn column<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<F64Array<'py>> {
    F64Array::extract(obj, name, &[Dim::Any("N")], "(one value per point)")
}

/// Grinding paths (SPEC P1–P5); ``machscan.grinding_paths`` documents it and wraps the
/// ``_GrindingPathArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (
    points, normals, allowance, *, tool_radius, scallop_height, section_normal, thickness, spacing, tolerance, fit_radius,
    removal, feed_step
))]
#[allow(clippy::too_many_arguments)]
fn grinding_paths<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: &Bound<'py, PyAny>,
    allowance: &Bound<'py, PyAny>,
    tool_radius: f64,
    scallop_height: f64,
    section_normal: &Bound<'py, PyAny>,
    thickness: Option<f64>,
    spacing: Option<f64>,
    tolerance: Option<f64>,
    fit_radius: Option<f64>,
    removal: Option<RemovalArgs>,
    feed_step: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = F64Array::points(points, "points")?;
    let nn = F64Array::points(normals, "normals")?;
    let a = column(allowance, "allowance")?;
    let section_normal = f64_vector::<3>(section_normal, "section_normal", "(a vector)")?;
    let (pr, nr, av) = (p.rows::<3>()?, nn.rows::<3>()?, a.values()?);
    let r = enter_long(py, || {
        let options = GrindingOptions {
            tool_radius,
            scallop_height,
            section_normal,
            thickness,
            spacing,
            tolerance,
            fit_radius,
            removal: removal.map(removal_model).transpose()?,
            feed_step,
        };
        run_grinding_paths(pr, nr, av, &options)
    })?;
    let (m, rows) = (r.points.len(), r.row_offsets.len());
    let d = PyDict::new(py);
    d.set_item("points", points_to_numpy(py, r.points)?)?;
    d.set_item("normals", points_to_numpy(py, r.normals)?)?;
    d.set_item("row", indices_to_numpy(py, r.row)?)?;
    d.set_item("curvature", to_numpy(py, r.curvature, &[m])?)?;
    d.set_item("allowance", to_numpy(py, r.allowance, &[m])?)?;
    d.set_item("feed", to_numpy(py, r.feed, &[m])?)?;
    d.set_item("tool_fits", to_numpy(py, r.tool_fits, &[m])?)?;
    d.set_item("row_offsets", to_numpy(py, r.row_offsets, &[rows])?)?;
    d.set_item("row_closed", to_numpy(py, r.row_closed, &[rows])?)?;
    d.set_item("without_stock", r.without_stock)?;
    Ok(d)
}

/// `f(model, value)` for every value of a 1-D array under the removal model given.
fn under_model<'py>(
    py: Python<'py>,
    values: &Bound<'py, PyAny>,
    name: &str,
    removal: RemovalArgs,
    f: fn(&RemovalModel, f64) -> machscan_core::Result<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let v = column(values, name)?;
    let vv = v.values()?;
    let out = enter(py, || {
        let model = removal_model(removal)?;
        vv.iter().map(|&x| f(&model, x)).collect::<machscan_core::Result<Vec<f64>>>()
    })?;
    to_numpy(py, out, &[vv.len()])
}

/// Feeds removing the given depths under a removal model; ``machscan.RemovalModel.feed``.
#[pyfunction]
fn removal_feeds<'py>(
    py: Python<'py>,
    depths: &Bound<'py, PyAny>,
    removal: RemovalArgs,
) -> PyResult<Bound<'py, PyAny>> {
    under_model(py, depths, "allowance", removal, |model, depth| Ok(model.feed(depth)))
}

/// Depths removed at the given feeds under a removal model; ``machscan.RemovalModel.removal``.
#[pyfunction]
fn removal_depths<'py>(
    py: Python<'py>,
    feeds: &Bound<'py, PyAny>,
    removal: RemovalArgs,
) -> PyResult<Bound<'py, PyAny>> {
    under_model(py, feeds, "feed", removal, |model, feed| {
        if feed.is_finite() && feed > 0.0 {
            Ok(model.removal(feed))
        } else {
            Err(machscan_core::Error::invalid("feed", format!("must be positive and finite, got {feed}")))
        }
    })
}

/// Removal simulation (SPEC P5 beyond); ``machscan.simulate_removal`` documents it and wraps the
/// ``_RemovalArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (points, normals, allowance, path_points, path_normals, path_allowance, path_row, depths, *, tool_radius))]
#[allow(clippy::too_many_arguments)]
fn simulate_removal<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: &Bound<'py, PyAny>,
    allowance: &Bound<'py, PyAny>,
    path_points: &Bound<'py, PyAny>,
    path_normals: &Bound<'py, PyAny>,
    path_allowance: &Bound<'py, PyAny>,
    path_row: Vec<i64>,
    depths: &Bound<'py, PyAny>,
    tool_radius: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let p = F64Array::points(points, "points")?;
    let nn = F64Array::points(normals, "normals")?;
    let a = column(allowance, "allowance")?;
    let pp = F64Array::points(path_points, "path_points")?;
    let pn = F64Array::points(path_normals, "path_normals")?;
    let pa = column(path_allowance, "path_allowance")?;
    let dd = column(depths, "depths")?;
    let (pr, nr, av) = (p.rows::<3>()?, nn.rows::<3>()?, a.values()?);
    let (ppr, pnr, pav, dv) = (pp.rows::<3>()?, pn.rows::<3>()?, pa.values()?, dd.values()?);
    let blank = Stock { points: pr, normals: nr, allowance: av };
    let path = Stock { points: ppr, normals: pnr, allowance: pav };
    let rows: Vec<usize> = path_row.iter().map(|&r| count("path_row", r)).collect::<PyResult<_>>()?;
    let (left, nearest) = enter(py, || run_simulate_removal(blank, path, &rows, dv, tool_radius))?;
    let d = PyDict::new(py);
    d.set_item("deviation", to_numpy(py, left, &[pr.len()])?)?;
    d.set_item("nearest", indices_to_numpy(py, nearest)?)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("GRINDING_FEED_STEP", machscan_core::toolpath::grinding::DEFAULT_FEED_STEP)?;
    m.add_function(wrap_pyfunction!(grinding_paths, m)?)?;
    m.add_function(wrap_pyfunction!(removal_feeds, m)?)?;
    m.add_function(wrap_pyfunction!(removal_depths, m)?)?;
    m.add_function(wrap_pyfunction!(simulate_removal, m)?)?;
    m.add_function(wrap_pyfunction!(bead_chain, m)?)?;
    m.add_function(wrap_pyfunction!(scallop_heights, m)?)?;
    m.add_function(wrap_pyfunction!(step_overs, m)?)?;
    m.add_function(wrap_pyfunction!(compensate_toolpath, m)?)?;
    Ok(())
}
