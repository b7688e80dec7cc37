//! Bindings of `machscan_core::mesh`.
use super::convert::{count, enter, enter_long, points_to_numpy, to_numpy, triangle_indices, Dim, F64Array};
use super::error::IntoPy;
use machscan_core::mesh::{
    closest_points as run_closest_points, delaunay_xy as run_delaunay_xy, face_statistics as run_face_statistics,
    geodesic_distances as run_geodesic_distances, insert_points as run_insert_points,
    signed_distances as run_signed_distances, GeodesicMethod, GeodesicSolver, Landing,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Delaunay triangulation of a surface seen from above (SPEC S1; paper 002 §3.1): the points'
/// xy projection is triangulated (spade, exact predicates) and the triangles lifted back to 3D.
/// For height-field surfaces such as a skin on the machine table.
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     mm.
/// max_edge : float, optional
///     Leave out triangles with an edge longer than this in 3D, mm: the long thin triangles a
///     concave outline leaves along its convex hull.
///
/// Returns
/// -------
/// ndarray of int64, shape (M, 3)
///     Triangles as indices into ``points``, counter-clockwise seen from +z. The same triangles
///     as ``scipy.spatial.Delaunay(points[:, :2])`` for points in general position (with four
///     or more on one circle, one of the valid triangulations).
///
/// Raises
/// ------
/// ValueError
///     Points not finite, all on one line in xy, or fewer than three distinct ones. Points with
///     the same x and y as an earlier one are not an error: they are left out of every triangle
///     (the first one is kept).
///
/// Examples
/// --------
/// >>> faces = machscan.delaunay_xy(scan, max_edge=5.0)
/// >>> machscan.write_mesh("skin.ply", scan, faces)
#[pyfunction]
#[pyo3(signature = (points, *, max_edge=None))]
fn delaunay_xy<'py>(py: Python<'py>, points: &Bound<'py, PyAny>, max_edge: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
    let arr = F64Array::points(points, "points")?;
    let pts = arr.rows::<3>()?;
    let faces = enter(py, || run_delaunay_xy(pts, max_edge))?;
    let m = faces.len();
    to_numpy(py, faces.into_iter().flat_map(|t| t.map(i64::from)).collect(), &[m, 3])
}

/// A mesh argument: vertices and the triangles' vertex indices.
fn mesh<'py>(vertices: &Bound<'py, PyAny>, faces: &Bound<'py, PyAny>) -> PyResult<(F64Array<'py>, Vec<[u32; 3]>)> {
    mesh_named(vertices, faces, "faces")
}

/// A mesh argument whose triangles go by `faces_name` (the comparison with CAD says
/// "triangles", as a CAD mesh's faces are its B-rep faces).
pub(super) fn mesh_named<'py>(
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    faces_name: &str,
) -> PyResult<(F64Array<'py>, Vec<[u32; 3]>)> {
    let v = F64Array::points(vertices, "vertices")?;
    let f = F64Array::indices(faces, faces_name, &[Dim::Any("M"), Dim::Is(3)], "(vertex indices of triangles)")?;
    let tri = triangle_indices(faces_name, f.values()?)?;
    Ok((v, tri))
}

/// A surface argument: points (meshed in the core) or the vertices of a mesh with its faces.
pub(super) fn surface<'py>(
    points: &Bound<'py, PyAny>,
    faces: Option<&Bound<'py, PyAny>>,
    name: &str,
) -> PyResult<(F64Array<'py>, Option<Vec<[u32; 3]>>)> {
    let v = F64Array::points(points, name)?;
    let tri = match faces {
        Some(f) => {
            let f = F64Array::indices(f, name, &[Dim::Any("M"), Dim::Is(3)], "(vertex indices of triangles)")?;
            Some(triangle_indices(name, f.values()?)?)
        }
        None => None,
    };
    Ok((v, tri))
}

/// Closest points on a triangle mesh (SPEC S2); ``machscan.closest_points`` documents it and
/// wraps the ``_ClosestArrays`` this returns.
#[pyfunction]
fn closest_points<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    queries: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let (v, tri) = mesh(vertices, faces)?;
    let q = F64Array::points(queries, "queries")?;
    let (vr, qr) = (v.rows::<3>()?, q.rows::<3>()?);
    let found = enter(py, || run_closest_points(vr, &tri, qr))?;
    let n = found.len();
    let d = PyDict::new(py);
    d.set_item("points", points_to_numpy(py, found.iter().map(|c| c.point).collect())?)?;
    d.set_item("distances", to_numpy(py, found.iter().map(|c| c.distance).collect(), &[n])?)?;
    d.set_item("triangles", to_numpy(py, found.iter().map(|c| c.triangle as i64).collect(), &[n])?)?;
    d.set_item("barycentric", points_to_numpy(py, found.iter().map(|c| c.barycentric).collect())?)?;
    Ok(d)
}

/// Signed distances to a triangle mesh; ``machscan.signed_distances`` documents it and wraps
/// the arrays this returns.
#[pyfunction]
fn signed_distances<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    vertices: &Bound<'py, PyAny>,
    triangles: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let (v, tri) = mesh_named(vertices, triangles, "triangles")?;
    let p = F64Array::points(points, "points")?;
    let (vr, pr) = (v.rows::<3>()?, p.rows::<3>()?);
    let found = enter(py, || run_signed_distances(vr, &tri, pr).map_err(|e| e.renamed("faces", "triangles")))?;
    let n = found.len();
    let d = PyDict::new(py);
    d.set_item("distances", to_numpy(py, found.iter().map(|s| s.distance).collect(), &[n])?)?;
    d.set_item("points", points_to_numpy(py, found.iter().map(|s| s.closest.point).collect())?)?;
    d.set_item("triangles", to_numpy(py, found.iter().map(|s| s.closest.triangle as i64).collect(), &[n])?)?;
    Ok(d)
}

/// Per-face statistics of signed distances; ``machscan.SignedDistances.statistics`` documents
/// it.
#[pyfunction]
#[pyo3(signature = (distances, faces, *, count, lower, upper))]
fn face_statistics<'py>(
    py: Python<'py>,
    distances: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    count: usize,
    lower: f64,
    upper: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let d = F64Array::extract(distances, "distances", &[Dim::Any("N")], "")?;
    let n = d.shape()[0];
    let f = F64Array::indices(faces, "faces", &[Dim::Is(n)], "(the face of each distance)")?;
    let groups: Vec<u32> = f
        .values()?
        .iter()
        .map(|&x| {
            (x >= 0.0 && x < u32::MAX as f64 && x.fract() == 0.0).then_some(x as u32).ok_or_else(|| {
                pyo3::exceptions::PyValueError::new_err(format!("faces: expected face indices, found {x}"))
            })
        })
        .collect::<PyResult<_>>()?;
    let dv = d.values()?;
    let s = enter(py, || run_face_statistics(dv, &groups, count, lower, upper))?;
    let k = s.len();
    let out = PyDict::new(py);
    out.set_item("face", to_numpy(py, s.iter().map(|x| i64::from(x.face)).collect(), &[k])?)?;
    out.set_item("count", to_numpy(py, s.iter().map(|x| x.count as i64).collect(), &[k])?)?;
    out.set_item("min", to_numpy(py, s.iter().map(|x| x.min).collect(), &[k])?)?;
    out.set_item("max", to_numpy(py, s.iter().map(|x| x.max).collect(), &[k])?)?;
    out.set_item("mean", to_numpy(py, s.iter().map(|x| x.mean).collect(), &[k])?)?;
    out.set_item("std", to_numpy(py, s.iter().map(|x| x.std).collect(), &[k])?)?;
    out.set_item("out_of_tolerance", to_numpy(py, s.iter().map(|x| x.out_of_tolerance).collect(), &[k])?)?;
    Ok(out)
}

/// Points inserted into a mesh as vertices (SPEC S2); ``machscan.insert_points`` documents it
/// and wraps the ``_InsertedArrays`` this returns.
#[pyfunction]
#[pyo3(signature = (vertices, faces, points, *, tolerance))]
fn insert_points<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
    tolerance: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let (v, tri) = mesh(vertices, faces)?;
    let p = F64Array::points(points, "points")?;
    let (vr, pr) = (v.rows::<3>()?, p.rows::<3>()?);
    let r = enter(py, || run_insert_points(vr, &tri, pr, tolerance))?;
    let (m, n) = (r.faces.len(), r.indices.len());
    let d = PyDict::new(py);
    d.set_item("vertices", points_to_numpy(py, r.vertices)?)?;
    d.set_item("faces", to_numpy(py, r.faces.into_iter().flat_map(|t| t.map(i64::from)).collect(), &[m, 3])?)?;
    d.set_item("indices", to_numpy(py, r.indices.into_iter().map(i64::from).collect(), &[n])?)?;
    let names: Vec<&str> = r
        .landings
        .iter()
        .map(|l| match l {
            Landing::Vertex => "vertex",
            Landing::Edge => "edge",
            Landing::Face => "face",
        })
        .collect();
    d.set_item("landings", names)?;
    Ok(d)
}

/// Geodesic distances (SPEC S3); ``machscan.geodesic_distances`` documents it.
#[pyfunction]
#[pyo3(signature = (vertices, faces, sources, *, method))]
fn geodesic_distances<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    sources: Vec<i64>,
    method: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let (v, tri) = mesh(vertices, faces)?;
    let n = v.shape()[0];
    let src: Vec<usize> = sources.iter().map(|&s| count("sources", s)).collect::<PyResult<_>>()?;
    let method = GeodesicMethod::parse(method).py()?;
    let vr = v.rows::<3>()?;
    let d = enter_long(py, || run_geodesic_distances(vr, &tri, &src, method))?;
    let k = d.len();
    to_numpy(py, d.into_iter().flatten().collect(), &[k, n])
}

/// A mesh prepared once for geodesic distances (SPEC S3); ``machscan.GeodesicSolver``
/// documents it.
#[pyclass(name = "GeodesicSolver", module = "machscan._core", frozen)]
pub struct PyGeodesicSolver {
    inner: GeodesicSolver,
}

#[pymethods]
impl PyGeodesicSolver {
    #[new]
    #[pyo3(signature = (vertices, faces, *, method))]
    fn new(py: Python<'_>, vertices: &Bound<'_, PyAny>, faces: &Bound<'_, PyAny>, method: &str) -> PyResult<Self> {
        let (v, tri) = mesh(vertices, faces)?;
        let method = GeodesicMethod::parse(method).py()?;
        let vr = v.rows::<3>()?;
        Ok(PyGeodesicSolver { inner: enter(py, || GeodesicSolver::new(vr, &tri, method))? })
    }

    /// The method, ``"exact"``, ``"fmm"`` or ``"heat"``.
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.method().name()
    }

    /// The number of vertices (the length of each row of ``distances``).
    #[getter]
    fn vertex_count(&self) -> usize {
        self.inner.vertex_count()
    }

    /// Distances from each source vertex to every vertex → ``(S, V)``.
    fn distances<'py>(&self, py: Python<'py>, sources: Vec<i64>) -> PyResult<Bound<'py, PyAny>> {
        let src: Vec<usize> = sources.iter().map(|&s| count("sources", s)).collect::<PyResult<_>>()?;
        let d = enter_long(py, || self.inner.distances(&src))?;
        let k = d.len();
        to_numpy(py, d.into_iter().flatten().collect(), &[k, self.inner.vertex_count()])
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGeodesicSolver>()?;
    m.add_function(wrap_pyfunction!(geodesic_distances, m)?)?;
    m.add_function(wrap_pyfunction!(insert_points, m)?)?;
    m.add_function(wrap_pyfunction!(closest_points, m)?)?;
    m.add_function(wrap_pyfunction!(signed_distances, m)?)?;
    m.add_function(wrap_pyfunction!(face_statistics, m)?)?;
    m.add_function(wrap_pyfunction!(delaunay_xy, m)?)?;
    Ok(())
}
