//! Array conversion and shape checks shared by every binding.
//!
//! Any array-like NumPy can turn into float64 is accepted; it is made C-contiguous float64
//! (copied only when it is not already), its shape is checked here, and a `ValueError` names the
//! argument, the expected and the actual shape. Kernels then run on plain slices with the GIL
//! released.
use crate::error::Error;
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;

pub fn to_py_err(e: Error) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A count or index argument (k, window, …). Taken from Python as a signed int and checked here:
/// for an unsigned parameter pyo3 refuses a negative int with a bare OverflowError that names
/// no argument.
pub fn count(name: &str, value: i64) -> PyResult<usize> {
    usize::try_from(value).map_err(|_| PyValueError::new_err(format!("{name}: must be a count >= 0, got {value}")))
}

pub fn count_opt(name: &str, value: Option<i64>) -> PyResult<Option<usize>> {
    value.map(|v| count(name, v)).transpose()
}

/// One dimension of an expected shape.
#[derive(Clone, Copy)]
pub enum Dim {
    /// Any length (named in messages, e.g. "F").
    Any(&'static str),
    /// Exactly this length.
    Is(usize),
}

pub fn shape_str(shape: &[usize]) -> String {
    match shape.len() {
        1 => format!("({},)", shape[0]),
        _ => format!("({})", shape.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

fn spec_str(spec: &[Dim]) -> String {
    let parts: Vec<String> = spec
        .iter()
        .map(|d| match d {
            Dim::Any(n) => n.to_string(),
            Dim::Is(k) => k.to_string(),
        })
        .collect();
    match parts.len() {
        1 => format!("({},)", parts[0]),
        _ => format!("({})", parts.join(", ")),
    }
}

fn numpy_module(py: Python<'_>) -> PyResult<&Bound<'_, PyModule>> {
    static NUMPY: PyOnceLock<Py<PyModule>> = PyOnceLock::new();
    NUMPY.get_or_try_init(py, || py.import("numpy").map(Bound::unbind)).map(|m| m.bind(py))
}

/// `obj` as a C-contiguous float64 array of the shape `spec` (with `what` describing the
/// columns for messages, e.g. "with columns X, Y, Z, A, C, C2").
pub fn f64_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    spec: &[Dim],
    what: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    let py = obj.py();
    let np = numpy_module(py)?;
    let expected = if what.is_empty() { spec_str(spec) } else { format!("{} {}", spec_str(spec), what) };
    if obj.is_none() {
        return Err(PyValueError::new_err(format!("{name}: expected an array of shape {expected}, got None")));
    }
    let arr = np.call_method1("asarray", (obj,)).map_err(|e| {
        PyValueError::new_err(format!(
            "{name}: expected an array of shape {expected}, but it cannot be converted to an array ({})",
            e.value(py)
        ))
    })?;
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        let dtype = arr.getattr("dtype")?.str()?.to_string();
        return Err(PyValueError::new_err(format!(
            "{name}: expected real numbers convertible to float64, got dtype {dtype}"
        )));
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", np.getattr("float64")?)?;
    let arr = np.call_method("ascontiguousarray", (arr,), Some(&kwargs))?;
    let arr = arr.cast_into::<PyArrayDyn<f64>>().map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?;
    let shape = arr.shape().to_vec();
    let ok = shape.len() == spec.len()
        && shape.iter().zip(spec).all(|(s, d)| match d {
            Dim::Any(_) => true,
            Dim::Is(k) => s == k,
        });
    if !ok {
        return Err(PyValueError::new_err(format!("{name}: expected shape {expected}, got {}", shape_str(&shape))));
    }
    Ok(arr.readonly())
}

/// A fixed-length vector argument, e.g. a mount (6 values) or an offset (3 values).
pub fn f64_vector<const K: usize>(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<[f64; K]> {
    let arr = f64_array(obj, name, &[Dim::Is(K)], what)?;
    let s = arr.as_slice()?;
    let mut out = [0.0; K];
    out.copy_from_slice(s);
    if let Some(v) = out.iter().find(|v| !v.is_finite()) {
        return Err(PyValueError::new_err(format!("{name}: must be finite, found {v}")));
    }
    Ok(out)
}

/// An optional (lo, hi) range.
pub fn f64_range(obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Option<(f64, f64)>> {
    match obj {
        None => Ok(None),
        Some(o) if o.is_none() => Ok(None),
        Some(o) => {
            let arr = f64_array(o, name, &[Dim::Is(2)], "(lo, hi)")?;
            let s = arr.as_slice()?;
            Ok(Some((s[0], s[1])))
        }
    }
}

/// Row-major values → a new NumPy array of `shape` (no copy of the data).
pub fn to_numpy<'py, T: numpy::Element>(py: Python<'py>, data: Vec<T>, shape: &[usize]) -> PyResult<Bound<'py, PyAny>> {
    let flat = PyArray1::from_vec(py, data);
    if shape.len() == 1 {
        return Ok(flat.into_any());
    }
    Ok(flat.reshape(shape.to_vec())?.into_any())
}
