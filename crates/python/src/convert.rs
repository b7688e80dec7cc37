//! The seam between Python and the core, shared by every binding:
//!
//! 1. **extract** — `F64Array::extract` takes any array-like NumPy can turn into float64 (lists,
//!    integer arrays, big-endian or misaligned buffers from `np.frombuffer`, shared memory or
//!    Dask workers), copies it only when it is not already aligned, C-contiguous float64, and
//!    checks its shape, naming the argument, the expected and the actual shape;
//! 2. **enter** — `enter` runs the kernel with the GIL released, maps its error to the Python
//!    exception once (`error.rs`) and lets a Ctrl-C pressed meanwhile through;
//! 3. **return** — `to_numpy` hands the kernel's `Vec` to NumPy without a copy.
//!
//! Value checks (finite, positive, in range) are the core's, so they hold for Rust callers too.
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;

use super::error::IntoPy;
use std::cell::Cell;
use std::sync::{Arc, Mutex};

/// Runs `kernel` with the GIL released — on the calling thread's limit of threads
/// (`set_thread_limit`), else on all cores — then raises its error as the Python exception, or a
/// `KeyboardInterrupt` when Ctrl-C was pressed while it ran.
pub fn enter<T, F>(py: Python<'_>, kernel: F) -> PyResult<T>
where
    F: FnOnce() -> machscan_core::Result<T> + Send,
    T: Send,
{
    let out = match limited_pool()? {
        Some(pool) => py.detach(|| pool.install(kernel)),
        None => py.detach(kernel),
    };
    py.check_signals()?;
    out.py()
}

/// How often a long kernel's caller looks for a Ctrl-C while it waits (`enter_long`).
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// `enter` for the kernels that can run for seconds (exact geodesics, the isometric match,
/// grinding paths): the kernel runs on a thread of its own while this one waits for it, looking
/// for a Ctrl-C every `SIGNAL_POLL` (Python runs its signal handlers only on the main thread,
/// with the GIL). A Ctrl-C asks the kernel to stop (`machscan_core::interrupt`); it returns at
/// its next check and the `KeyboardInterrupt` is raised. The wait never changes what the kernel
/// computes, only how soon a Ctrl-C is seen.
pub fn enter_long<T, F>(py: Python<'_>, kernel: F) -> PyResult<T>
where
    F: FnOnce() -> machscan_core::Result<T> + Send,
    T: Send,
{
    let pool = limited_pool()?;
    let watch = machscan_core::interrupt::Watch::new();
    let mut interrupt: Option<PyErr> = None;
    let out = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = std::sync::mpsc::channel();
            scope.spawn(move || {
                let out = match pool {
                    Some(pool) => pool.install(kernel),
                    None => kernel(),
                };
                // The waiting thread may have left already (it never does before this send).
                let _ = done.send(out);
            });
            loop {
                match finished.recv_timeout(SIGNAL_POLL) {
                    Ok(out) => return out,
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                        return Err(machscan_core::Error::Interrupted);
                    }
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                        if interrupt.is_none() {
                            if let Err(e) = Python::attach(|py| py.check_signals()) {
                                interrupt = Some(e);
                                machscan_core::interrupt::request();
                            }
                        }
                    }
                }
            }
        })
    });
    drop(watch);
    if let Some(e) = interrupt {
        return Err(e);
    }
    py.check_signals()?;
    out.py()
}

/// What to pass instead of an Open3D or trimesh object given where an array is taken: NumPy
/// turns those into an object array, which says nothing of the conversion the user needs.
fn foreign_geometry(obj: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    let t = obj.get_type();
    let module: String = t.getattr("__module__")?.extract().unwrap_or_default();
    let name: String = t.getattr("__name__")?.extract().unwrap_or_default();
    let tensor = module.contains(".t.") || module.ends_with(".t");
    let hint = match (module.split('.').next().unwrap_or(""), name.as_str()) {
        ("open3d", "PointCloud") if tensor => {
            "an Open3D tensor PointCloud: pass cloud.point.positions.numpy(), or machscan.interop.from_open3d(cloud)"
        }
        ("open3d", "PointCloud") => {
            "an Open3D PointCloud: pass np.asarray(cloud.points), or machscan.interop.from_open3d(cloud)"
        }
        ("open3d", "TriangleMesh") => {
            "an Open3D TriangleMesh: pass np.asarray(mesh.vertices) and np.asarray(mesh.triangles), or machscan.interop.from_open3d(mesh)"
        }
        ("trimesh", "Trimesh") => {
            "a trimesh Trimesh: pass mesh.vertices and mesh.faces, or machscan.interop.from_trimesh(mesh)"
        }
        ("trimesh", "PointCloud") => "a trimesh PointCloud: pass cloud.vertices",
        ("open3d" | "trimesh", _) => return Ok(Some(format!("a {module}.{name}, not an array"))),
        _ => return Ok(None),
    };
    Ok(Some(hint.to_string()))
}

/// The largest thread limit taken: far beyond any machine's cores, short of a typo's millions.
const MAX_THREADS: usize = 1024;

thread_local! {
    /// The calling Python thread's thread limit for the kernels; 0: all cores (rayon's global pool).
    static THREAD_LIMIT: Cell<usize> = const { Cell::new(0) };
}

/// One rayon pool per limit asked for, kept for the life of the process: a Dask worker runs
/// thousands of tasks, each entering the core on its thread's limit.
static POOLS: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());

fn limited_pool() -> PyResult<Option<Arc<rayon::ThreadPool>>> {
    let limit = THREAD_LIMIT.with(Cell::get);
    if limit == 0 {
        return Ok(None);
    }
    let mut pools = POOLS.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some((_, pool)) = pools.iter().find(|(n, _)| *n == limit) {
        return Ok(Some(pool.clone()));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(limit)
        .thread_name(move |i| format!("machscan-{limit}-{i}"))
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("threads: could not start a pool of {limit} threads ({e})")))?;
    let pool = Arc::new(pool);
    pools.push((limit, pool.clone()));
    Ok(Some(pool))
}

/// Sets the number of threads the kernels called from this Python thread run on (0: all cores)
/// and returns the previous setting; `machscan.thread_limit` is the public face. The kernels'
/// results do not depend on it.
#[pyfunction]
pub fn set_thread_limit(threads: i64) -> PyResult<i64> {
    let n = count("threads", threads)?;
    if n > MAX_THREADS {
        return Err(PyValueError::new_err(format!("threads: at most {MAX_THREADS}, got {n}")));
    }
    Ok(THREAD_LIMIT.with(|t| t.replace(n)) as i64)
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

/// A float64 array argument: aligned, C-contiguous, of a checked shape.
pub struct F64Array<'py> {
    array: PyReadonlyArrayDyn<'py, f64>,
}

impl<'py> F64Array<'py> {
    /// An array of vertex indices (faces, triangles): as `extract`, but booleans are refused — a
    /// mask given where indices belong would silently become vertices 0 and 1.
    pub fn indices(obj: &Bound<'py, PyAny>, name: &str, spec: &[Dim], what: &str) -> PyResult<Self> {
        let py = obj.py();
        if let Ok(arr) = numpy_module(py)?.call_method1("asarray", (obj,)) {
            if arr.getattr("dtype")?.getattr("kind")?.extract::<String>()? == "b" {
                return Err(PyValueError::new_err(format!("{name}: expected vertex indices, got booleans (a mask?)")));
            }
            return Self::extract(&arr, name, spec, what);
        }
        Self::extract(obj, name, spec, what)
    }

    /// `obj` as float64 of the shape `spec`; `what` describes the columns in messages (e.g. "with
    /// columns X, Y, Z, A, C, C2").
    pub fn extract(obj: &Bound<'py, PyAny>, name: &str, spec: &[Dim], what: &str) -> PyResult<Self> {
        let py = obj.py();
        let np = numpy_module(py)?;
        let expected = if what.is_empty() { spec_str(spec) } else { format!("{} {}", spec_str(spec), what) };
        if obj.is_none() {
            return Err(PyValueError::new_err(format!("{name}: expected an array of shape {expected}, got None")));
        }
        if let Some(hint) = foreign_geometry(obj)? {
            return Err(PyValueError::new_err(format!("{name}: expected an array of shape {expected}, got {hint}")));
        }
        let arr = np.call_method1("asarray", (obj,)).map_err(|e| {
            PyValueError::new_err(format!(
                "{name}: expected an array of shape {expected}, but it cannot be converted to an array ({})",
                e.value(py)
            ))
        })?;
        // Numbers only: NumPy would also turn strings and complex numbers into floats, which
        // hides a wrong argument rather than converting a right one.
        let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
        if !matches!(kind.as_str(), "f" | "i" | "u" | "b") {
            let dtype = arr.getattr("dtype")?.str()?.to_string();
            return Err(PyValueError::new_err(format!(
                "{name}: expected real numbers convertible to float64, got dtype {dtype}"
            )));
        }
        // `require` copies only what is not already aligned, C-contiguous, native float64.
        let kwargs = PyDict::new(py);
        kwargs.set_item("dtype", np.getattr("float64")?)?;
        kwargs.set_item("requirements", "CA")?;
        let arr = np.call_method("require", (arr,), Some(&kwargs))?;
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
        Ok(F64Array { array: arr.readonly() })
    }

    /// An optional argument: `None` stays `None`.
    pub fn extract_opt(
        obj: Option<&Bound<'py, PyAny>>,
        name: &str,
        spec: &[Dim],
        what: &str,
    ) -> PyResult<Option<Self>> {
        match obj {
            Some(o) if !o.is_none() => Ok(Some(Self::extract(o, name, spec, what)?)),
            _ => Ok(None),
        }
    }

    /// Points or vectors `(N, 3)`.
    pub fn points(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Self> {
        Self::extract(obj, name, &[Dim::Any("N"), Dim::Is(3)], "")
    }

    pub fn shape(&self) -> &[usize] {
        self.array.shape()
    }

    /// The values, row-major.
    pub fn values(&self) -> PyResult<&[f64]> {
        Ok(self.array.as_slice()?)
    }

    /// The rows of a `(N, K)` array, without a copy.
    pub fn rows<const K: usize>(&self) -> PyResult<&[[f64; K]]> {
        let (rows, rest) = self.values()?.as_chunks::<K>();
        if !rest.is_empty() {
            return Err(PyValueError::new_err(format!("expected rows of {K} values, got {}", shape_str(self.shape()))));
        }
        Ok(rows)
    }
}

/// A fixed-length vector argument, e.g. a mount (6 values) or an offset (3 values).
pub fn f64_vector<const K: usize>(obj: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<[f64; K]> {
    let arr = F64Array::extract(obj, name, &[Dim::Is(K)], what)?;
    let mut out = [0.0; K];
    out.copy_from_slice(arr.values()?);
    Ok(out)
}

pub fn f64_vector_opt<const K: usize>(
    obj: Option<&Bound<'_, PyAny>>,
    name: &str,
    what: &str,
) -> PyResult<Option<[f64; K]>> {
    match obj {
        Some(o) if !o.is_none() => Ok(Some(f64_vector::<K>(o, name, what)?)),
        _ => Ok(None),
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

/// Points `(M, 3)` → a NumPy array (no copy).
pub fn points_to_numpy<'py>(py: Python<'py>, points: Vec<[f64; 3]>) -> PyResult<Bound<'py, PyAny>> {
    let m = points.len();
    to_numpy(py, points.into_flattened(), &[m, 3])
}

/// Indices → int64 NumPy array (what NumPy indexing takes).
pub fn indices_to_numpy<'py, I: Copy + TryInto<i64>>(py: Python<'py>, v: Vec<I>) -> PyResult<Bound<'py, PyAny>> {
    let n = v.len();
    let v: Vec<i64> = v.into_iter().map(|i| i.try_into().unwrap_or(-1)).collect();
    to_numpy(py, v, &[n])
}

/// Triangle vertex indices given as numbers: whole, ≥ 0 and below 2^32 − 1. Checked in one
/// tight pass over all values first (meshes of a million faces are common), the offending row
/// named in the message.
pub fn triangle_indices(name: &str, values: &[f64]) -> PyResult<Vec<[u32; 3]>> {
    let index = |v: f64| v >= 0.0 && v < u32::MAX as f64 && (v as u32) as f64 == v;
    if let Some(i) = values.iter().position(|&v| !index(v)) {
        return Err(PyValueError::new_err(format!(
            "{name}: row {} holds {}, which is not a vertex index",
            i / 3,
            values[i]
        )));
    }
    let (rows, _) = values.as_chunks::<3>();
    Ok(rows.iter().map(|t| t.map(|v| v as u32)).collect())
}
