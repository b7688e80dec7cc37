//! Bindings of `crate::io`.
use super::convert::{f64_array, to_numpy, to_py_err, Dim};
use crate::error::Error;
use crate::io::{write_ply, PlyScalar};
use numpy::PyUntypedArrayMethods;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Write points (and optional normals and scalar properties) to a PLY, PCD or text file (by the
/// extension; ``binary`` picks binary or ASCII PLY/PCD; text files hold x, y, z only).
///
/// Parameters
/// ----------
/// path : str or os.PathLike
///     Output file (``.ply``).
/// points : array_like, shape (N, 3)
///     Points, mm; written as ``double`` so machine coordinates keep full precision.
/// normals : array_like, shape (N, 3), optional
/// scalars : dict of str to array_like (N,), optional
///     Extra per-point properties, e.g. ``{"frame": frame_index}``.
/// binary : bool
///     Binary little-endian (default) or ASCII.
///
/// Examples
/// --------
/// >>> machscan.write_points("scan.ply", points, scalars={"frame": frame_index})
#[pyfunction]
#[pyo3(signature = (path, points, normals=None, scalars=None, binary=true, compressed=false))]
fn write_points(
    py: Python<'_>,
    path: PathBuf,
    points: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    scalars: Option<&Bound<'_, PyDict>>,
    binary: bool,
    compressed: bool,
) -> PyResult<()> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if !matches!(ext.as_str(), "ply" | "pcd" | "xyz" | "csv" | "txt" | "pts") {
        return Err(PyValueError::new_err(format!(
            "path: {}: machscan writes .ply, .pcd, .xyz, .csv, .txt, .pts, got {ext:?}",
            path.display()
        )));
    }
    let pts = f64_array(points, "points", &[Dim::Any("N"), Dim::Is(3)], "")?;
    let n = pts.shape()[0];
    let nrm = match normals {
        Some(o) if !o.is_none() => Some(f64_array(o, "normals", &[Dim::Is(n), Dim::Is(3)], "(one normal per point)")?),
        _ => None,
    };
    let mut named = Vec::new();
    if let Some(d) = scalars {
        for (k, v) in d.iter() {
            let name: String =
                k.extract().map_err(|_| PyValueError::new_err("scalars: keys must be property names (str)"))?;
            let arr = f64_array(&v, &name, &[Dim::Is(n)], "(one value per point)")?;
            named.push((name, arr));
        }
    }
    let p = pts.as_slice()?;
    let nr = match &nrm {
        Some(a) => Some(a.as_slice()?),
        None => None,
    };
    let slices: Vec<(String, &[f64])> =
        named.iter().map(|(k, a)| Ok((k.clone(), a.as_slice()?))).collect::<PyResult<_>>()?;
    let props: Vec<PlyScalar<'_>> = slices.iter().map(|(k, v)| PlyScalar { name: k, values: v }).collect();
    py.detach(|| match ext.as_str() {
        "ply" => write_ply(&path, p, nr, &props, binary),
        "pcd" => {
            let sc: Vec<(&str, &[f64])> = props.iter().map(|s| (s.name, s.values)).collect();
            let enc = match (binary, compressed) {
                (_, true) => crate::io::PcdEncoding::BinaryCompressed,
                (true, false) => crate::io::PcdEncoding::Binary,
                (false, false) => crate::io::PcdEncoding::Ascii,
            };
            crate::io::write_pcd(&path, p, nr, &sc, enc)
        }
        _ => {
            if nr.is_some() || !props.is_empty() {
                return Err(Error::invalid(
                    "normals",
                    "a text point file holds x, y, z only: write .ply or .pcd to keep normals and scalars",
                ));
            }
            crate::io::write_xyz(&path, p, if ext == "csv" { ',' } else { ' ' })
        }
    })
    .map_err(|e| match e {
        Error::File { .. } => PyOSError::new_err(e.to_string()),
        other => to_py_err(other),
    })
}

fn file_error(e: Error) -> PyErr {
    match e {
        // A file that cannot be opened is an OSError; one whose content is wrong a ValueError.
        Error::File { ref reason, .. } if reason.starts_with("cannot read") || reason.starts_with("cannot write") => {
            PyOSError::new_err(e.to_string())
        }
        other => to_py_err(other),
    }
}

/// Whether a .txt file starts with the `n_vertices n_faces` line of the mesh text format.
fn is_mesh_txt(path: &std::path::Path) -> bool {
    use std::io::BufRead;
    let Ok(f) = std::fs::File::open(path) else { return false };
    let mut first = String::new();
    if std::io::BufReader::new(f).read_line(&mut first).is_err() {
        return false;
    }
    let w: Vec<&str> = first.split_whitespace().collect();
    w.len() == 2 && w.iter().all(|t| t.parse::<usize>().is_ok())
}

/// Read a point cloud file (PLY, PCD, or XYZ/CSV/TXT/PTS text; a .txt starting with
/// `n_vertices n_faces` is read as the geodesic test meshes' format); ``machscan.io.read`` wraps the
/// dict this returns (``points``, ``normals``, ``scalars``, ``triangles``).
#[pyfunction]
#[pyo3(signature = (path, delimiter=None, columns=(0, 1, 2)))]
fn read_cloud<'py>(
    py: Python<'py>,
    path: PathBuf,
    delimiter: Option<char>,
    columns: (i64, i64, i64),
) -> PyResult<Bound<'py, PyDict>> {
    let columns = (
        super::convert::count("columns", columns.0)?,
        super::convert::count("columns", columns.1)?,
        super::convert::count("columns", columns.2)?,
    );
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let (points, normals, scalars, triangles) = match ext.as_str() {
        "ply" => {
            let d = py.detach(|| crate::io::read_ply(&path)).map_err(file_error)?;
            (d.points, d.normals, d.scalars, d.triangles)
        }
        "pcd" => {
            let d = py.detach(|| crate::io::read_pcd(&path)).map_err(file_error)?;
            (d.points, d.normals, d.scalars, Vec::new())
        }
        "txt" if delimiter.is_none() && columns == (0, 1, 2) && is_mesh_txt(&path) => {
            let text = std::fs::read_to_string(&path)
                .map_err(|e| file_error(Error::file(&path, format!("cannot read: {e}"))))?;
            let (p, t) = crate::io::parse_mesh_txt(&path, &text).map_err(file_error)?.unwrap_or_default();
            (p, None, Vec::new(), t)
        }
        "xyz" | "csv" | "txt" | "pts" | "asc" => {
            let cols = [columns.0, columns.1, columns.2];
            let p = py.detach(|| crate::io::read_xyz(&path, delimiter, cols)).map_err(file_error)?;
            (p, None, Vec::new(), Vec::new())
        }
        other => {
            return Err(PyValueError::new_err(format!(
                "path: {}: unknown point file type {other:?}; machscan reads .ply, .pcd, .xyz, .csv, .txt, .pts",
                path.display()
            )))
        }
    };
    let n = points.len() / 3;
    let d = PyDict::new(py);
    d.set_item("points", to_numpy(py, points, &[n, 3])?)?;
    d.set_item(
        "normals",
        match normals {
            Some(v) => to_numpy(py, v, &[n, 3])?,
            None => py.None().into_bound(py),
        },
    )?;
    let sd = PyDict::new(py);
    for (name, v) in scalars {
        sd.set_item(name, to_numpy(py, v, &[n])?)?;
    }
    d.set_item("scalars", sd)?;
    let t = triangles.len();
    d.set_item(
        "triangles",
        to_numpy(py, triangles.into_iter().flatten().map(|v| v as i64).collect::<Vec<_>>(), &[t, 3])?,
    )?;
    Ok(d)
}

/// Read an APT/CL toolpath: GOTO points, tool axes, feeds and segments (a new segment after every
/// RAPID); ``machscan.io.read_toolpath`` wraps the dict.
#[pyfunction]
fn read_toolpath<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let tp = py.detach(|| crate::io::read_apt(&path)).map_err(file_error)?;
    let n = tp.segments.len();
    let d = PyDict::new(py);
    d.set_item("points", to_numpy(py, tp.points, &[n, 3])?)?;
    d.set_item("axes", to_numpy(py, tp.axes, &[n, 3])?)?;
    d.set_item("feeds", to_numpy(py, tp.feeds, &[n])?)?;
    d.set_item("segments", to_numpy(py, tp.segments.into_iter().map(|s| s as i64).collect::<Vec<_>>(), &[n])?)?;
    Ok(d)
}

/// Write an APT/CL toolpath (``GOTO/x,y,z[,i,j,k]``, ``FEDRAT`` when the feed changes,
/// ``RAPID`` between segments).
#[pyfunction]
#[pyo3(signature = (path, points, axes=None, feeds=None, segments=None))]
fn write_toolpath(
    py: Python<'_>,
    path: PathBuf,
    points: &Bound<'_, PyAny>,
    axes: Option<&Bound<'_, PyAny>>,
    feeds: Option<&Bound<'_, PyAny>>,
    segments: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let p = f64_array(points, "points", &[Dim::Any("N"), Dim::Is(3)], "")?;
    let n = p.shape()[0];
    let a = match axes {
        Some(o) if !o.is_none() => Some(f64_array(o, "axes", &[Dim::Is(n), Dim::Is(3)], "(one tool axis per point)")?),
        _ => None,
    };
    let f = match feeds {
        Some(o) if !o.is_none() => Some(f64_array(o, "feeds", &[Dim::Is(n)], "(one feed per point)")?),
        _ => None,
    };
    let s: Option<Vec<u32>> = match segments {
        Some(o) if !o.is_none() => {
            let v = f64_array(o, "segments", &[Dim::Is(n)], "(one segment id per point)")?;
            Some(v.as_slice()?.iter().map(|&x| x.max(0.0) as u32).collect())
        }
        _ => None,
    };
    let (ps, as_, fs) =
        (p.as_slice()?, a.as_ref().map(|x| x.as_slice()).transpose()?, f.as_ref().map(|x| x.as_slice()).transpose()?);
    py.detach(|| crate::io::write_apt(&path, ps, as_, fs, s.as_deref())).map_err(file_error)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_toolpath, m)?)?;
    m.add_function(wrap_pyfunction!(write_toolpath, m)?)?;
    m.add_function(wrap_pyfunction!(write_points, m)?)?;
    m.add_function(wrap_pyfunction!(read_cloud, m)?)?;
    Ok(())
}
