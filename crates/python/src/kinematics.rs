//! Bindings of `machscan_core::kinematics`: profiler frames, machine chains, pose timing, calibration.
use super::convert::{count, enter, f64_vector, f64_vector_opt, points_to_numpy, to_numpy, Dim, F64Array};
use super::error::IntoPy;
use machscan_core::kinematics::{self as kin, KinematicChain, Profiler, Step, StepArg, VENDOR_SENTINEL};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PySequence, PyTuple};

const AC_HEAD_AXES: &str = "with columns X, Y, Z, A, C, C2 (mm, rad)";

/// The `frames (F, N)` argument and the profiler for its N readings.
fn frames_and_profiler<'py>(
    frames: &Bound<'py, PyAny>,
    pitch: f64,
    center: Option<f64>,
    valid_range: Option<&Bound<'py, PyAny>>,
    sentinel: Option<f64>,
) -> PyResult<(F64Array<'py>, Profiler)> {
    let arr = F64Array::extract(frames, "frames", &[Dim::Any("F"), Dim::Any("N")], "")?;
    let valid_range = f64_vector_opt::<2>(valid_range, "valid_range", "(lo, hi) in mm")?.map(|[lo, hi]| (lo, hi));
    let profiler = Profiler::new(pitch, arr.shape()[1], center, valid_range, sentinel).py()?;
    Ok((arr, profiler))
}

fn points_result<'py>(py: Python<'py>, out: kin::ProfilePoints) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let m = out.frame_index.len();
    Ok((to_numpy(py, out.points, &[m, 3])?, to_numpy(py, out.frame_index, &[m])?))
}

/// Profiler frames to points in the sensor coordinate system (SPEC K1, paper 000 eq 5).
///
/// Reading ``i`` of a frame becomes the SCS point ``((i - center) * pitch, 0, d_i)``: the laser
/// line runs along SCS x, ``d_i`` is a height along SCS z (out of the material). Invalid
/// readings are dropped: NaN, the ``sentinel`` ("no reading" code, −99999 by default), and
/// anything outside ``valid_range``.
///
/// Parameters
/// ----------
/// frames : array_like, shape (F, N)
///     Readings in mm, one frame per row.
/// pitch : float
///     Reading spacing along the line, mm.
/// center : float, optional
///     Index of the reading at SCS x = 0; default ``N / 2``.
/// valid_range : (float, float), optional
///     Measuring range ``(lo, hi)`` in mm; readings outside it are invalid.
/// sentinel : float or None
///     The profiler's "no reading" code, mm; default ``machscan.SENTINEL`` (−99999). None when
///     the profiler writes NaN only (−99999 is then still no real height, so the default is safe).
///
/// Returns
/// -------
/// points : ndarray, shape (M, 3)
///     SCS points in mm, frame by frame, readings in order.
/// frame_index : ndarray of int64, shape (M,)
///     Frame of each point. ``frames.size - M`` readings were dropped.
///
/// Examples
/// --------
/// >>> pts, idx = machscan.profile_to_points([[0.1, float("nan"), -99999.0, 0.3]], pitch=0.025)
/// >>> pts.shape
/// (2, 3)
#[pyfunction]
#[pyo3(
    signature = (frames, pitch, *, center=None, valid_range=None, sentinel=Some(VENDOR_SENTINEL)),
    text_signature = "(frames, pitch, *, center=None, valid_range=None, sentinel=-99999.0)"
)]
fn profile_to_points<'py>(
    py: Python<'py>,
    frames: &Bound<'py, PyAny>,
    pitch: f64,
    center: Option<f64>,
    valid_range: Option<&Bound<'py, PyAny>>,
    sentinel: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let (frames, profiler) = frames_and_profiler(frames, pitch, center, valid_range, sentinel)?;
    let (data, n) = (frames.values()?, frames.shape()[1]);
    let out = enter(py, || kin::profile_to_points(data, n, &profiler))?;
    points_result(py, out)
}

/// Frames and AC-head poses to workpiece (WCS) points in one parallel call (SPEC K1–K3, K7).
///
/// Every valid reading of frame ``k`` is mapped by ``ac_head_transforms(axes)[k]``. The work is
/// spread over all cores with the GIL released; the result is identical for any thread count.
///
/// Parameters
/// ----------
/// frames : array_like, shape (F, N)
///     Readings in mm.
/// axes : array_like, shape (F, 6)
///     X, Y, Z (mm), A, C, C2 (rad) at each frame.
/// pitch : float
///     Reading spacing, mm.
/// c2_offset : array_like, shape (3,)
///     (Lx, Ly, Lz) of the C2 axis from the tool tip, mm.
/// mount : array_like, shape (6,)
///     (theta, psi, phi, dx, dy, dz): mount Euler angles (rad) and translation (mm).
/// center, valid_range, sentinel
///     As in :func:`profile_to_points`: invalid readings (NaN, the sentinel −99999 by default,
///     outside ``valid_range``) are dropped.
///
/// Returns
/// -------
/// points : ndarray, shape (M, 3)
///     WCS points, mm.
/// frame_index : ndarray of int64, shape (M,)
///
/// Examples
/// --------
/// >>> pts, idx = machscan.scan_to_wcs(frames, axes, 0.025, (0, 0, 150), (0, 0, 0, 30, 0, -100))
#[pyfunction]
#[pyo3(
    signature = (frames, axes, pitch, c2_offset, mount, *, center=None, valid_range=None, sentinel=Some(VENDOR_SENTINEL)),
    text_signature = "(frames, axes, pitch, c2_offset, mount, *, center=None, valid_range=None, sentinel=-99999.0)"
)]
#[allow(clippy::too_many_arguments)]
fn scan_to_wcs<'py>(
    py: Python<'py>,
    frames: &Bound<'py, PyAny>,
    axes: &Bound<'py, PyAny>,
    pitch: f64,
    c2_offset: &Bound<'py, PyAny>,
    mount: &Bound<'py, PyAny>,
    center: Option<f64>,
    valid_range: Option<&Bound<'py, PyAny>>,
    sentinel: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let chain = ac_head_chain(c2_offset, mount)?;
    scan_points_with(py, &chain, frames, axes, pitch, center, valid_range, sentinel)
}

#[allow(clippy::too_many_arguments)]
fn scan_points_with<'py>(
    py: Python<'py>,
    chain: &KinematicChain,
    frames: &Bound<'py, PyAny>,
    axes: &Bound<'py, PyAny>,
    pitch: f64,
    center: Option<f64>,
    valid_range: Option<&Bound<'py, PyAny>>,
    sentinel: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let (frames, profiler) = frames_and_profiler(frames, pitch, center, valid_range, sentinel)?;
    let axes = poses_array(chain, axes, Some(frames.shape()[0]))?;
    let (data, n, poses) = (frames.values()?, frames.shape()[1], axes.values()?);
    let out = enter(py, || kin::frames_to_points(chain, data, n, poses, &profiler))?;
    points_result(py, out)
}

fn poses_array<'py>(chain: &KinematicChain, axes: &Bound<'py, PyAny>, rows: Option<usize>) -> PyResult<F64Array<'py>> {
    let what = format!("with columns {}", chain.axis_names().join(", "));
    let rows_dim = match rows {
        Some(r) => Dim::Is(r),
        None => Dim::Any("F"),
    };
    F64Array::extract(axes, "axes", &[rows_dim, Dim::Is(chain.n_axes())], &what)
}

fn ac_head_chain(c2_offset: &Bound<'_, PyAny>, mount: &Bound<'_, PyAny>) -> PyResult<KinematicChain> {
    let c2 = f64_vector::<3>(c2_offset, "c2_offset", "(Lx, Ly, Lz) in mm")?;
    let m = f64_vector::<6>(mount, "mount", "(theta, psi, phi, dx, dy, dz) in rad and mm")?;
    KinematicChain::ac_head(c2, m).py()
}

fn transforms_array<'py>(
    py: Python<'py>,
    chain: &KinematicChain,
    axes: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let axes = poses_array(chain, axes, None)?;
    let (f, poses) = (axes.shape()[0], axes.values()?);
    let out = enter(py, || chain.transforms(poses))?;
    to_numpy(py, out, &[f, 4, 4])
}

/// WCS ← SCS transforms of the AC double-swing head with C2 and sensor mount (SPEC K2, K3).
///
/// ``T = [Rz(C)·Rx(A), (X, Y, Z)] · [Rz(C2), (Lx, Ly, Lz)] · [Rz(phi)·Ry(theta)·Rx(psi), (dx, dy, dz)]``.
/// The rotations are the proper ones; paper 000 prints eq (4) and eq (8) with sign errors.
///
/// Parameters
/// ----------
/// axes : array_like, shape (F, 6)
///     X, Y, Z (mm), A, C, C2 (rad) per frame.
/// c2_offset : array_like, shape (3,)
///     (Lx, Ly, Lz), mm.
/// mount : array_like, shape (6,)
///     (theta, psi, phi, dx, dy, dz), rad and mm.
///
/// Returns
/// -------
/// ndarray, shape (F, 4, 4)
///
/// Examples
/// --------
/// >>> T = machscan.ac_head_transforms([[0, 0, 0, 0, 0, 0]], (0, 0, 0), (0, 0, 0, 0, 0, 0))
/// >>> T[0]  # identity
#[pyfunction]
fn ac_head_transforms<'py>(
    py: Python<'py>,
    axes: &Bound<'py, PyAny>,
    c2_offset: &Bound<'py, PyAny>,
    mount: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let chain = ac_head_chain(c2_offset, mount)?;
    transforms_array(py, &chain, axes)
}

/// Tool points of the milling side to workpiece points of the mirror-milling support side
/// (SPEC K5, paper 002 eq 1–6), each point with its own AB-head pose.
///
/// Evaluates the chain ``p1 = p + Lat; p2 = Rx(A)·p1; p3 = p2 + Lba; p4 = Ry(B)·p3;
/// p5 = p4 + (X, Y, Z) − Lba − Lat; W = (−p5x, p5y, −p5z)``, which is paper 002 eq (6).
///
/// Parameters
/// ----------
/// tool_points : array_like, shape (N, 3)
///     Points in the tool frame, mm.
/// axes : array_like, shape (N, 5)
///     X, Y, Z (mm), A, B (rad) for each point.
/// lat, lba : array_like, shape (3,)
///     Tool→A-axis and A→B-axis offsets, mm.
///
/// Returns
/// -------
/// ndarray, shape (N, 3)
///     Support-side points, mm.
///
/// Examples
/// --------
/// >>> machscan.ab_mirror_support_points([[0, 0, 0]], [[0, 0, 0, 0, 0]], (0, 0, 200), (0, 0, 150))
#[pyfunction]
fn ab_mirror_support_points<'py>(
    py: Python<'py>,
    tool_points: &Bound<'py, PyAny>,
    axes: &Bound<'py, PyAny>,
    lat: &Bound<'py, PyAny>,
    lba: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let lat = f64_vector::<3>(lat, "lat", "(x, y, z) in mm")?;
    let lba = f64_vector::<3>(lba, "lba", "(x, y, z) in mm")?;
    let chain = KinematicChain::ab_mirror_support(lat, lba).py()?;
    apply_chain(py, &chain, tool_points, "tool_points", axes, false)
}

fn apply_chain<'py>(
    py: Python<'py>,
    chain: &KinematicChain,
    points: &Bound<'py, PyAny>,
    name: &str,
    axes: &Bound<'py, PyAny>,
    vectors: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let pts = F64Array::points(points, name)?;
    let n = pts.shape()[0];
    let axes = poses_array(chain, axes, Some(n))?;
    let (p, a) = (pts.values()?, axes.values()?);
    let out = enter(py, || chain.apply(p, a, vectors))?;
    to_numpy(py, out, &[n, 3])
}

/// Turn CAD points and normals with an AC cradle table (SPEC K6, paper 003 eq 1).
///
/// ``P' = Rx(a)·Rz(c)·(P − center) + center``, ``n' = Rx(a)·Rz(c)·n`` (C turns first, then A).
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     Points, mm.
/// normals : array_like, shape (N, 3) or None
///     Normals (turned, not moved).
/// a, c : float
///     Table angles, rad.
/// center : array_like, shape (3,)
///     Rotation center in measurement coordinates ``t = O'_w − O_w``, mm.
///
/// Returns
/// -------
/// points : ndarray, shape (N, 3)
/// normals : ndarray, shape (N, 3) or None
///
/// Examples
/// --------
/// >>> p, n = machscan.ac_table_rotate([[1, 0, 0]], [[0, 0, 1]], 0.0, np.pi / 2, (0, 0, 0))
#[pyfunction]
fn ac_table_rotate<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    a: f64,
    c: f64,
    center: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let center = f64_vector::<3>(center, "center", "(x, y, z) in mm")?;
    let pts = F64Array::points(points, "points")?;
    let nrm =
        F64Array::extract_opt(normals, "normals", &[Dim::Is(pts.shape()[0]), Dim::Is(3)], "(one normal per point)")?;
    let (p, n) = (pts.rows::<3>()?, nrm.as_ref().map(|a| a.rows::<3>()).transpose()?);
    let (turned, normals) = enter(py, || kin::ac_table_rotate(p, n, a, c, center))?;
    let normals = match normals {
        Some(v) => points_to_numpy(py, v)?,
        None => py.None().into_bound(py),
    };
    Ok((points_to_numpy(py, turned)?, normals))
}

/// Axis positions at frame times from CNC samples on their own clock (SPEC K7).
///
/// Linear interpolation; rotary columns are unwrapped first (a C axis crossing ±π turns the
/// short way). Frames outside the sampled time span raise: poses are never extrapolated.
///
/// Parameters
/// ----------
/// sample_times : array_like, shape (S,)
///     CNC sample times, s, strictly increasing.
/// samples : array_like, shape (S, n_axes)
///     Axis positions (mm, rad).
/// frame_times : array_like, shape (F,)
///     Profiler frame times on the same clock, s.
/// rotary : sequence of int
///     Columns holding rotary axes in rad; default (3, 4, 5), the A, C, C2 of X, Y, Z, A, C, C2.
///
/// Returns
/// -------
/// ndarray, shape (F, n_axes)
///
/// Examples
/// --------
/// >>> machscan.interpolate_poses([0.0, 1.0], [[0.0], [2.0]], [0.25], rotary=())
/// array([[0.5]])
#[pyfunction]
#[pyo3(
    signature = (sample_times, samples, frame_times, *, rotary=vec![3, 4, 5]),
    text_signature = "(sample_times, samples, frame_times, *, rotary=(3, 4, 5))"
)]
fn interpolate_poses<'py>(
    py: Python<'py>,
    sample_times: &Bound<'py, PyAny>,
    samples: &Bound<'py, PyAny>,
    frame_times: &Bound<'py, PyAny>,
    rotary: Vec<i64>,
) -> PyResult<Bound<'py, PyAny>> {
    let rotary = rotary.into_iter().map(|c| count("rotary", c)).collect::<PyResult<Vec<usize>>>()?;
    let ts = F64Array::extract(sample_times, "sample_times", &[Dim::Any("S")], "")?;
    let s = ts.shape()[0];
    let smp = F64Array::extract(samples, "samples", &[Dim::Is(s), Dim::Any("n_axes")], "(one row per sample time)")?;
    let w = smp.shape()[1];
    let ft = F64Array::extract(frame_times, "frame_times", &[Dim::Any("F")], "")?;
    let f = ft.shape()[0];
    let (a, b, c) = (ts.values()?, smp.values()?, ft.values()?);
    let out = enter(py, || kin::interpolate_poses(a, b, c, &rotary))?;
    to_numpy(py, out, &[f, w])
}

/// Sensor mount calibration from SCS ↔ WCS correspondences (SPEC K4); the Python function
/// ``machscan.calibrate_mount`` wraps the ``MountCalibrationArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (scs_points, wcs_points, *, axes=None, c2_offset=None))]
fn calibrate_mount<'py>(
    py: Python<'py>,
    scs_points: &Bound<'py, PyAny>,
    wcs_points: &Bound<'py, PyAny>,
    axes: Option<&Bound<'py, PyAny>>,
    c2_offset: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let scs = F64Array::points(scs_points, "scs_points")?;
    let n = scs.shape()[0];
    let wcs = F64Array::extract(wcs_points, "wcs_points", &[Dim::Is(n), Dim::Is(3)], "(one point per SCS point)")?;
    let poses = F64Array::extract_opt(axes, "axes", &[Dim::Is(n), Dim::Is(6)], AC_HEAD_AXES)?;
    let c2 = f64_vector_opt::<3>(c2_offset, "c2_offset", "(Lx, Ly, Lz) in mm")?.unwrap_or([0.0; 3]);
    let (s, w, p) = (scs.rows::<3>()?, wcs.rows::<3>()?, poses.as_ref().map(|a| a.values()).transpose()?);
    let cal = enter(py, || kin::calibrate_mount_ac_head(s, w, p, c2))?;
    let d = PyDict::new(py);
    d.set_item("params", to_numpy(py, cal.params.to_vec(), &[6])?)?;
    d.set_item("rms", cal.rms)?;
    d.set_item("std_errors", to_numpy(py, cal.std_errors.to_vec(), &[6])?)?;
    d.set_item("covariance", to_numpy(py, cal.covariance.to_vec(), &[6, 6])?)?;
    d.set_item("residuals", to_numpy(py, cal.residuals, &[n])?)?;
    d.set_item("iterations", cal.iterations)?;
    d.set_item("converged", cal.converged)?;
    Ok(d)
}

/// Sensor mount calibration with a reference sphere (SPEC K4 beyond);
/// ``machscan.calibrate_mount_sphere`` documents it and wraps the arrays this returns.
#[pyfunction]
#[pyo3(signature = (frames, poses, *, pitch, center, valid_range, sentinel, c2_offset, radius, mount, sphere_center))]
#[allow(clippy::too_many_arguments)]
fn calibrate_mount_sphere<'py>(
    py: Python<'py>,
    frames: &Bound<'py, PyAny>,
    poses: &Bound<'py, PyAny>,
    pitch: f64,
    center: Option<f64>,
    valid_range: Option<&Bound<'py, PyAny>>,
    sentinel: Option<f64>,
    c2_offset: &Bound<'py, PyAny>,
    radius: f64,
    mount: &Bound<'py, PyAny>,
    sphere_center: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (arr, profiler) = frames_and_profiler(frames, pitch, center, valid_range, sentinel)?;
    let f = arr.shape()[0];
    let poses = F64Array::extract(poses, "poses", &[Dim::Is(f), Dim::Is(6)], AC_HEAD_AXES)?;
    let c2 = f64_vector::<3>(c2_offset, "c2_offset", "(Lx, Ly, Lz) in mm")?;
    let mount = f64_vector::<6>(mount, "mount", "(theta, psi, phi, dx, dy, dz): the start")?;
    let start = f64_vector_opt::<3>(sphere_center, "sphere_center", "(x, y, z) in mm: the start")?;
    let n = arr.shape()[1];
    let (fr, po) = (arr.values()?, poses.values()?);
    let cal = enter(py, || kin::calibrate_mount_sphere(fr, n, &profiler, po, c2, radius, mount, start))?;
    let d = PyDict::new(py);
    let m = cal.residuals.len();
    d.set_item("params", to_numpy(py, cal.mount.to_vec(), &[6])?)?;
    d.set_item("sphere_center", to_numpy(py, cal.center.to_vec(), &[3])?)?;
    d.set_item("rms", cal.rms)?;
    d.set_item("std_errors", to_numpy(py, cal.std_errors.to_vec(), &[9])?)?;
    d.set_item("covariance", to_numpy(py, cal.covariance.to_vec(), &[9, 9])?)?;
    d.set_item("residuals", to_numpy(py, cal.residuals, &[m])?)?;
    d.set_item("frame_index", to_numpy(py, cal.frame_index, &[m])?)?;
    d.set_item("iterations", cal.iterations)?;
    d.set_item("converged", cal.converged)?;
    Ok(d)
}

/// A machine model: a chain of elementary transforms mapping the last link (sensor, tool,
/// part) into the WCS (SPEC K7).
///
/// Parameters
/// ----------
/// steps : list of tuple
///     Composed left to right, each one of
///     ``("translate", (x, y, z))`` mm;
///     ``("translate_axes", (ix, iy, iz))`` translation by pose columns (None for 0);
///     ``("rotate", "x"|"y"|"z", angle)`` constant angle, rad;
///     ``("rotate_axis", "x"|"y"|"z", column)`` angle from a pose column (index or axis name);
///     ``("rotation", R)`` a constant 3×3 rotation; ``("mirror", (sx, sy, sz))`` with ±1.
/// axis_names : list of str
///     Names of the pose columns, e.g. ``["X", "Y", "Z", "A", "C"]``.
///
/// Examples
/// --------
/// >>> head = machscan.KinematicChain.ac_head((0, 0, 150), (0, 0, 0, 30, 0, -100))
/// >>> T = head.transforms(axes)          # (F, 4, 4)
#[pyclass(name = "KinematicChain", module = "machscan._core", frozen)]
#[derive(Clone)]
pub struct PyKinematicChain {
    inner: KinematicChain,
}

/// A step's argument as the core's `StepArg`: numbers (and arrays of them) as numbers, text as
/// text, None as None, other sequences item by item; what they mean is `Step::parse`'s.
fn step_arg(o: &Bound<'_, PyAny>) -> PyResult<StepArg> {
    if o.is_none() {
        return Ok(StepArg::None);
    }
    if let Ok(text) = o.extract::<String>() {
        return Ok(StepArg::Text(text));
    }
    // A bool is not a number here: True as an angle or a column is a mistake, not 1.
    if o.is_instance_of::<PyBool>() {
        return Ok(StepArg::Text(o.str()?.to_string()));
    }
    if let Ok(x) = o.extract::<f64>() {
        return Ok(StepArg::Number(x));
    }
    let array = o.py().import("numpy")?.call_method1("asarray", (o,));
    if let Ok(array) = array {
        let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
        if matches!(kind.as_str(), "f" | "i" | "u") {
            let shape: Vec<usize> = array.getattr("shape")?.extract()?;
            let values: Vec<f64> = array.call_method0("ravel")?.call_method0("tolist")?.extract()?;
            return Ok(StepArg::Array(values, shape));
        }
    }
    match o.cast::<PySequence>() {
        Ok(seq) => Ok(StepArg::List(seq.try_iter()?.map(|i| step_arg(&i?)).collect::<PyResult<_>>()?)),
        Err(_) => Ok(StepArg::Text(o.str()?.to_string())),
    }
}

/// Step `k` of a chain, a tuple `(kind, *arguments)`; the core parses it.
fn parse_step(item: &Bound<'_, PyAny>, k: usize, names: &[String]) -> PyResult<Step> {
    let bad = |why: &str| PyValueError::new_err(format!("steps: step {k}: {why}"));
    let tup = item.cast::<PyTuple>().map_err(|_| bad("must be a tuple like (\"rotate\", \"z\", 0.5)"))?;
    if tup.is_empty() {
        return Err(bad("empty tuple"));
    }
    let kind: String = tup.get_item(0)?.extract().map_err(|_| bad("the first item must be the step kind (str)"))?;
    let args = tup.iter().skip(1).map(|a| step_arg(&a)).collect::<PyResult<Vec<_>>>()?;
    Step::parse(k, &kind, &args, names).py()
}

#[pymethods]
impl PyKinematicChain {
    #[new]
    fn new(steps: &Bound<'_, PyList>, axis_names: Vec<String>) -> PyResult<Self> {
        let parsed =
            steps.iter().enumerate().map(|(k, s)| parse_step(&s, k, &axis_names)).collect::<PyResult<Vec<_>>>()?;
        Ok(PyKinematicChain { inner: KinematicChain::new(parsed, axis_names).py()? })
    }

    /// AC double-swing head with C2 and sensor mount (SPEC K2, K3); poses X, Y, Z, A, C, C2.
    #[staticmethod]
    fn ac_head(c2_offset: &Bound<'_, PyAny>, mount: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(PyKinematicChain { inner: ac_head_chain(c2_offset, mount)? })
    }

    /// AB head, support side of mirror milling (SPEC K5); poses X, Y, Z, A, B.
    #[staticmethod]
    fn ab_mirror_support(lat: &Bound<'_, PyAny>, lba: &Bound<'_, PyAny>) -> PyResult<Self> {
        let lat = f64_vector::<3>(lat, "lat", "(x, y, z) in mm")?;
        let lba = f64_vector::<3>(lba, "lba", "(x, y, z) in mm")?;
        Ok(PyKinematicChain { inner: KinematicChain::ab_mirror_support(lat, lba).py()? })
    }

    /// AC cradle table about ``center`` (SPEC K6); poses A, C.
    #[staticmethod]
    fn ac_table(center: &Bound<'_, PyAny>) -> PyResult<Self> {
        let center = f64_vector::<3>(center, "center", "(x, y, z) in mm")?;
        Ok(PyKinematicChain { inner: KinematicChain::ac_table(center).py()? })
    }

    /// Number of pose columns.
    #[getter]
    fn n_axes(&self) -> usize {
        self.inner.n_axes()
    }

    /// Names of the pose columns.
    #[getter]
    fn axis_names(&self) -> Vec<String> {
        self.inner.axis_names().to_vec()
    }

    /// 4×4 transforms for poses ``axes (F, n_axes)`` → ``(F, 4, 4)``.
    fn transforms<'py>(&self, py: Python<'py>, axes: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        transforms_array(py, &self.inner, axes)
    }

    /// Points ``(N, 3)``, each with its own pose ``axes (N, n_axes)`` → ``(N, 3)``.
    fn transform_points<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        axes: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        apply_chain(py, &self.inner, points, "points", axes, false)
    }

    /// Directions or normals ``(N, 3)`` with poses ``(N, n_axes)``: turned, not moved.
    fn transform_vectors<'py>(
        &self,
        py: Python<'py>,
        vectors: &Bound<'py, PyAny>,
        axes: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        apply_chain(py, &self.inner, vectors, "vectors", axes, true)
    }

    /// Frames ``(F, N)`` and poses ``(F, n_axes)`` → ``(points (M, 3), frame_index (M,))``.
    /// Invalid readings are dropped as in :func:`machscan.profile_to_points`.
    #[pyo3(
        signature = (frames, axes, pitch, *, center=None, valid_range=None, sentinel=Some(VENDOR_SENTINEL)),
        text_signature = "(self, frames, axes, pitch, *, center=None, valid_range=None, sentinel=-99999.0)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn scan_points<'py>(
        &self,
        py: Python<'py>,
        frames: &Bound<'py, PyAny>,
        axes: &Bound<'py, PyAny>,
        pitch: f64,
        center: Option<f64>,
        valid_range: Option<&Bound<'py, PyAny>>,
        sentinel: Option<f64>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        scan_points_with(py, &self.inner, frames, axes, pitch, center, valid_range, sentinel)
    }

    fn __repr__(&self) -> String {
        format!("KinematicChain(axes=[{}], steps: {})", self.inner.axis_names().join(", "), self.inner.describe())
    }
}

/// Which readings are valid (SPEC K1): finite, not the ``sentinel`` and inside
/// ``valid_range``: the one rule of every function that takes frames; ``Profiler.valid_mask``
/// documents it and reshapes the flat ``readings`` it hands over.
#[pyfunction]
#[pyo3(
    signature = (readings, *, valid_range=None, sentinel=Some(VENDOR_SENTINEL)),
    text_signature = "(readings, *, valid_range=None, sentinel=-99999.0)"
)]
fn valid_readings<'py>(
    py: Python<'py>,
    readings: &Bound<'py, PyAny>,
    valid_range: Option<&Bound<'py, PyAny>>,
    sentinel: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let arr = F64Array::extract(readings, "readings", &[Dim::Any("N")], "(readings, mm)")?;
    let valid_range = f64_vector_opt::<2>(valid_range, "valid_range", "(lo, hi) in mm")?.map(|[lo, hi]| (lo, hi));
    let rule = kin::ValidReadings::new(valid_range, sentinel).py()?;
    let values = arr.values()?;
    let n = values.len();
    to_numpy(py, values.iter().map(|&d| rule.is_valid(d)).collect::<Vec<bool>>(), &[n])
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(valid_readings, m)?)?;
    m.add_function(wrap_pyfunction!(profile_to_points, m)?)?;
    m.add_function(wrap_pyfunction!(scan_to_wcs, m)?)?;
    m.add_function(wrap_pyfunction!(ac_head_transforms, m)?)?;
    m.add_function(wrap_pyfunction!(ab_mirror_support_points, m)?)?;
    m.add_function(wrap_pyfunction!(ac_table_rotate, m)?)?;
    m.add_function(wrap_pyfunction!(interpolate_poses, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate_mount, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate_mount_sphere, m)?)?;
    m.add_class::<PyKinematicChain>()?;
    m.add("SENTINEL", VENDOR_SENTINEL)?;
    Ok(())
}
