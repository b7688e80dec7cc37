//! Bindings of `machscan_core::io`: one reader and one writer for point and mesh files, and APT/CL
//! toolpaths. The Python layer (`machscan.io`) turns the arrays into `CloudFile`,
//! `TriangleMesh` and `Toolpath` objects.
use super::convert::{count, count_opt, enter, to_numpy, triangle_indices, Dim, F64Array};
use super::error::IntoPy;
use machscan_core::io::{
    read_table as read_table_core, CloudRef, Dtype, FileFormat, TableOptions, TextColumns, WriteOptions,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A numeric table (CSV, TSV, whitespace) by machscan's one set of rules (header, comments,
/// encodings; see ``machscan.io.read_table``); the ``_TableArrays`` keys ``values`` (R, C),
/// ``lines`` (R,) and ``header`` (list of str, or None).
#[pyfunction]
#[pyo3(signature = (path, *, name, delimiter=None, widths=None, nan_columns=None, max_rows=None))]
fn read_table<'py>(
    py: Python<'py>,
    path: PathBuf,
    name: &str,
    delimiter: Option<char>,
    widths: Option<Vec<i64>>,
    nan_columns: Option<Vec<i64>>,
    max_rows: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let max_rows = count_opt("max_rows", max_rows)?;
    let widths: Vec<usize> =
        widths.unwrap_or_default().into_iter().map(|w| count("widths", w)).collect::<PyResult<_>>()?;
    let nan: Option<Vec<usize>> =
        nan_columns.map(|c| c.into_iter().map(|j| count("nan_columns", j)).collect::<PyResult<_>>()).transpose()?;
    let options = TableOptions { name, delimiter, widths: &widths, nan_columns: nan.as_deref(), max_rows };
    let t = enter(py, || read_table_core(&path, &options))?;
    let (rows, columns) = (t.rows(), t.columns);
    let d = PyDict::new(py);
    d.set_item("values", to_numpy(py, t.values, &[rows, columns])?)?;
    d.set_item("lines", to_numpy(py, t.lines.into_iter().map(|l| l as i64).collect(), &[rows])?)?;
    d.set_item("header", t.header)?;
    Ok(d)
}

/// A line-profiler export (Gocator CSV, Keyence height rows) as its arrays;
/// ``machscan.io.read_profiles`` documents it and builds the ``Scan``.
#[pyfunction]
fn read_profiles<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let p = enter(py, || machscan_core::io::read_profiles(&path))?;
    let n = p.heights.len().checked_div(p.frames).unwrap_or(0);
    let d = PyDict::new(py);
    d.set_item("layout", p.layout)?;
    let k = p.x.len();
    d.set_item("x", to_numpy(py, p.x, &[k])?)?;
    d.set_item("heights", to_numpy(py, p.heights, &[p.frames, n])?)?;
    for (name, v) in [("y", p.y), ("time", p.time), ("encoder", p.encoder), ("frame", p.frame)] {
        match v {
            Some(v) => {
                let k = v.len();
                d.set_item(name, to_numpy(py, v, &[k])?)?
            }
            None => d.set_item(name, py.None())?,
        }
    }
    d.set_item("x_resolution", p.x_resolution)?;
    d.set_item("y_resolution", p.y_resolution)?;
    d.set_item("model", p.model)?;
    d.set_item("serial", p.serial)?;
    Ok(d)
}

/// Read a point or mesh file by its extension (see ``machscan.io.read``); returns the
/// ``CloudArrays`` ``points``, ``normals`` (or None), ``scalars`` and ``triangles``.
#[pyfunction]
#[pyo3(
    signature = (path, *, delimiter=None, columns=(0, 1, 2), apply_pose=true),
    text_signature = "(path, *, delimiter=None, columns=(0, 1, 2), apply_pose=True)"
)]
fn read_cloud<'py>(
    py: Python<'py>,
    path: PathBuf,
    delimiter: Option<char>,
    columns: (i64, i64, i64),
    apply_pose: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let columns = [count("columns", columns.0)?, count("columns", columns.1)?, count("columns", columns.2)?];
    let text = TextColumns { delimiter, columns };
    let file = enter(py, || machscan_core::io::read_file_with(&path, text, apply_pose))?;
    let n = file.points.len() / 3;
    let d = PyDict::new(py);
    d.set_item("points", to_numpy(py, file.points, &[n, 3])?)?;
    d.set_item(
        "normals",
        match file.normals {
            Some(v) => to_numpy(py, v, &[n, 3])?,
            None => py.None().into_bound(py),
        },
    )?;
    let scalars = PyDict::new(py);
    for (name, v) in file.scalars {
        scalars.set_item(name, to_numpy(py, v, &[n])?)?;
    }
    d.set_item("scalars", scalars)?;
    let t = file.triangles.len();
    let tri: Vec<i64> = file.triangles.into_iter().flatten().map(i64::from).collect();
    d.set_item("triangles", to_numpy(py, tri, &[t, 3])?)?;
    d.set_item("dropped", file.dropped)?;
    Ok(d)
}

/// Write points, optional normals, named scalars and triangles by the file's extension (see
/// ``machscan.io.write_points`` and ``machscan.io.write_mesh``). ``binary``, ``dtype``: None
/// for the format's default.
#[pyfunction]
#[pyo3(signature = (path, points, *, normals=None, scalars=None, triangles=None, binary=None, compressed=false, dtype=None, scale=None))]
#[allow(clippy::too_many_arguments)]
fn write_cloud(
    py: Python<'_>,
    path: PathBuf,
    points: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    scalars: Option<&Bound<'_, PyDict>>,
    triangles: Option<&Bound<'_, PyAny>>,
    binary: Option<bool>,
    compressed: bool,
    dtype: Option<&str>,
    scale: Option<f64>,
) -> PyResult<()> {
    // The extension first: a wrong one is the first thing to say.
    FileFormat::of(&path, true).py()?;
    let dtype = dtype.map(Dtype::parse).transpose().py()?;
    let pts = F64Array::points(points, "points")?;
    let n = pts.shape()[0];
    let nrm = F64Array::extract_opt(normals, "normals", &[Dim::Is(n), Dim::Is(3)], "(one normal per point)")?;
    let mut named: Vec<(String, F64Array<'_>)> = Vec::new();
    if let Some(d) = scalars {
        for (k, v) in d.iter() {
            let name: String =
                k.extract().map_err(|_| PyValueError::new_err("scalars: keys must be field names (str)"))?;
            let arr = F64Array::extract(&v, &format!("scalars[{name:?}]"), &[Dim::Is(n)], "(one value per point)")?;
            named.push((name, arr));
        }
    }
    let tri = F64Array::extract_opt(triangles, "triangles", &[Dim::Any("T"), Dim::Is(3)], "(vertex indices)")?;
    let tri: Option<Vec<[u32; 3]>> = tri.map(|t| triangle_indices("triangles", t.values()?)).transpose()?;
    let values: Vec<(&str, &[f64])> =
        named.iter().map(|(k, a)| Ok((k.as_str(), a.values()?))).collect::<PyResult<_>>()?;
    let data = CloudRef {
        points: pts.values()?,
        normals: nrm.as_ref().map(|a| a.values()).transpose()?,
        scalars: &values,
        triangles: tri.as_deref(),
    };
    let options = WriteOptions { binary, compressed, dtype, scale };
    enter(py, || machscan_core::io::write_file(&path, &data, options))
}

/// The extensions ``machscan.io.read`` reads, e.g. ``("ply", "pcd", ...)``.
#[pyfunction]
fn readable_formats() -> Vec<&'static str> {
    FileFormat::ALL.iter().map(|(e, _)| *e).collect()
}

/// The extensions ``machscan.io.write_points`` and ``write_mesh`` write.
#[pyfunction]
fn writable_formats() -> Vec<&'static str> {
    FileFormat::ALL.iter().map(|(e, _)| *e).collect()
}

/// Read an APT/CL toolpath: GOTO points, tool axes, feeds and segments (a new segment after every
/// RAPID); ``machscan.io.read_toolpath`` wraps the ``ToolpathArrays`` this returns.
#[pyfunction]
fn read_toolpath<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let tp = enter(py, || machscan_core::io::read_apt(&path))?;
    let n = tp.segments.len();
    let d = PyDict::new(py);
    d.set_item("points", to_numpy(py, tp.points, &[n, 3])?)?;
    d.set_item("axes", to_numpy(py, tp.axes, &[n, 3])?)?;
    d.set_item("feeds", to_numpy(py, tp.feeds, &[n])?)?;
    d.set_item("segments", to_numpy(py, tp.segments.into_iter().map(i64::from).collect::<Vec<_>>(), &[n])?)?;
    Ok(d)
}

/// Write an APT/CL toolpath (``GOTO/x,y,z[,i,j,k]``, ``FEDRAT`` when the feed changes,
/// ``RAPID`` between segments); ``machscan.io.write_toolpath`` documents it.
#[pyfunction]
#[pyo3(signature = (path, points, *, axes=None, feeds=None, segments=None))]
fn write_toolpath(
    py: Python<'_>,
    path: PathBuf,
    points: &Bound<'_, PyAny>,
    axes: Option<&Bound<'_, PyAny>>,
    feeds: Option<&Bound<'_, PyAny>>,
    segments: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let p = F64Array::points(points, "points")?;
    let n = p.shape()[0];
    let a = F64Array::extract_opt(axes, "axes", &[Dim::Is(n), Dim::Is(3)], "(one tool axis per point)")?;
    let f = F64Array::extract_opt(feeds, "feeds", &[Dim::Is(n)], "(one feed per point)")?;
    let s = F64Array::extract_opt(segments, "segments", &[Dim::Is(n)], "(one segment label per point)")?;
    let (ps, av, fv, sv) = (
        p.values()?,
        a.as_ref().map(|x| x.values()).transpose()?,
        f.as_ref().map(|x| x.values()).transpose()?,
        s.as_ref().map(|x| x.values()).transpose()?,
    );
    enter(py, || machscan_core::io::write_apt(&path, ps, av, fv, sv))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_table, m)?)?;
    m.add_function(wrap_pyfunction!(read_profiles, m)?)?;
    m.add_function(wrap_pyfunction!(read_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(write_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(readable_formats, m)?)?;
    m.add_function(wrap_pyfunction!(writable_formats, m)?)?;
    m.add_function(wrap_pyfunction!(read_toolpath, m)?)?;
    m.add_function(wrap_pyfunction!(write_toolpath, m)?)?;
    m.add("FileFormatError", m.py().get_type::<super::error::FileFormatError>())?;
    Ok(())
}
