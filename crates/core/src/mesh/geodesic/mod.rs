//! Geodesic distances on a triangle mesh (SPEC S3; paper 002 §3.2): fast marching from a set of
//! source vertices to every vertex.
//!
//! The update of a vertex C from a triangle ABC whose A and B are known is the virtual-source
//! update: the point s in the triangle's plane, beyond AB, with |sA| = T_A and |sB| = T_B is
//! where a point source would lie; if the straight line from s to C crosses AB, T_C = |sC|
//! (exact for a source on a flat part), otherwise the front reaches C along an edge:
//! min(T_A + |AC|, T_B + |BC|). Obtuse triangles need no unfolding this way: where the line
//! misses AB the edge update is taken, which is what the neighbouring triangle's update then
//! improves on.
mod exact;
mod heat;
mod intrinsic;

use crate::error::{check_finite_points, Error, Result};
pub use exact::geodesic_exact;
pub use heat::{geodesic_heat, HeatSolver};
use nalgebra::Vector3;
use rayon::prelude::*;

/// The marching front: the vertices reached but not yet accepted, in a 4-ary heap keyed by
/// their tentative distance, each vertex at most once (its slot in `at`): a better distance
/// moves the vertex up in place instead of queueing it again, so the heap stays as small as
/// the front and each vertex is taken out once. (std's BinaryHeap has no decrease-key; with
/// one entry per improvement it held three times the entries and its pops were a quarter of
/// the time.) Ties go to the smaller vertex index, so the order is the same on every run.
struct Front {
    heap: Vec<(f64, u32)>,
    at: Vec<u32>,
}

impl Front {
    fn new(n: usize) -> Self {
        Front { heap: Vec::new(), at: vec![NOWHERE; n] }
    }

    fn before(a: (f64, u32), b: (f64, u32)) -> bool {
        a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
    }

    /// Queues `v` at `d`, or moves it to `d` if it is queued (d only ever decreases).
    fn set(&mut self, v: u32, d: f64) {
        let i = match self.at[v as usize] {
            NOWHERE => {
                self.heap.push((d, v));
                self.heap.len() - 1
            }
            i => {
                self.heap[i as usize].0 = d;
                i as usize
            }
        };
        self.up(i);
    }

    fn pop(&mut self) -> Option<u32> {
        let top = *self.heap.first()?;
        let last = self.heap.pop()?;
        self.at[top.1 as usize] = NOWHERE;
        if !self.heap.is_empty() {
            self.heap[0] = last;
            self.down(0);
        }
        Some(top.1)
    }

    /// Puts `item` in slot i and records where its vertex is.
    fn place(&mut self, i: usize, item: (f64, u32)) {
        self.heap[i] = item;
        self.at[item.1 as usize] = i as u32;
    }

    fn up(&mut self, mut i: usize) {
        let item = self.heap[i];
        while i > 0 {
            let parent = (i - 1) / 4;
            if !Self::before(item, self.heap[parent]) {
                break;
            }
            self.place(i, self.heap[parent]);
            i = parent;
        }
        self.place(i, item);
    }

    fn down(&mut self, mut i: usize) {
        let item = self.heap[i];
        let n = self.heap.len();
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let mut best = first;
            for c in first + 1..(first + 4).min(n) {
                if Self::before(self.heap[c], self.heap[best]) {
                    best = c;
                }
            }
            if !Self::before(self.heap[best], item) {
                break;
            }
            self.place(i, self.heap[best]);
            i = best;
        }
        self.place(i, item);
    }
}

/// `Front::at` of a vertex not in the front.
const NOWHERE: u32 = u32::MAX;

/// The faces around each vertex, as one flat list with offsets (vertex v's faces are
/// `faces[start[v]..start[v + 1]]`): one allocation instead of one per vertex.
pub(super) struct Around {
    start: Vec<u32>,
    faces: Vec<u32>,
}

impl Around {
    pub(super) fn new(vertices: usize, faces: &[[u32; 3]]) -> Self {
        let mut start = vec![0u32; vertices + 1];
        for f in faces {
            for &v in f {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..vertices {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; 3 * faces.len()];
        for (t, f) in faces.iter().enumerate() {
            for &v in f {
                list[fill[v as usize] as usize] = t as u32;
                fill[v as usize] += 1;
            }
        }
        Around { start, faces: list }
    }

    pub(super) fn of(&self, v: usize) -> &[u32] {
        &self.faces[self.start[v] as usize..self.start[v + 1] as usize]
    }
}

/// A face as the updates across it see it, computed once per call for every source: its edge
/// lengths (`len[k]` the edge opposite corner k) and twice its area. Precomputed because each
/// face is crossed a dozen times per source, and lengths cost square roots.
#[derive(Clone, Copy)]
struct FaceGeometry {
    len: [f64; 3],
    double_area: f64,
}

impl FaceGeometry {
    fn new(vertices: &[[f64; 3]], face: &[u32; 3]) -> Self {
        let p = face.map(|v| Vector3::from(vertices[v as usize]));
        let len = [0, 1, 2].map(|k| (p[(k + 2) % 3] - p[(k + 1) % 3]).norm());
        let double_area = (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        FaceGeometry { len, double_area }
    }

    /// The distance at corner k from the other two, a = corner k + 1 and b = corner k + 2,
    /// known at `ta` and `tb`.
    fn update(&self, k: usize, ta: f64, tb: f64) -> f64 {
        let (along, ac, bc) = (self.len[k], self.len[(k + 2) % 3], self.len[(k + 1) % 3]);
        let by_edges = (ta + ac).min(tb + bc);
        if along == 0.0 {
            return by_edges;
        }
        // C in the triangle's 2D frame: A at the origin, B at (along, 0), C above.
        let cy = self.double_area / along;
        if cy == 0.0 {
            return by_edges;
        }
        let cx = (ac * ac + along * along - bc * bc) / (2.0 * along);
        let sx = (ta * ta - tb * tb + along * along) / (2.0 * along);
        let sy2 = ta * ta - sx * sx;
        if sy2 < 0.0 {
            return by_edges;
        }
        let sy = -sy2.sqrt();
        // Where the line from s to C crosses y = 0.
        let x = sx + (cx - sx) * (-sy) / (cy - sy);
        if (0.0..=along).contains(&x) {
            ((cx - sx).powi(2) + (cy - sy).powi(2)).sqrt().min(by_edges)
        } else {
            by_edges
        }
    }
}

/// Distances from `source` to every vertex; `inf` where no face leads.
fn march(faces: &[[u32; 3]], geometry: &[FaceGeometry], around: &Around, n: usize, source: u32) -> Vec<f64> {
    let mut t = vec![f64::INFINITY; n];
    let mut known = vec![false; n];
    let mut front = Front::new(n);
    t[source as usize] = 0.0;
    front.set(source, 0.0);
    while let Some(v) = front.pop() {
        let vi = v as usize;
        known[vi] = true;
        for &f in around.of(vi) {
            let (face, g) = (faces[f as usize], &geometry[f as usize]);
            for k in 0..3 {
                let ci = face[k] as usize;
                if known[ci] {
                    continue;
                }
                let (a, b) = (face[(k + 1) % 3] as usize, face[(k + 2) % 3] as usize);
                let candidate = match (known[a], known[b]) {
                    (true, true) => g.update(k, t[a], t[b]),
                    (true, false) => t[a] + g.len[(k + 2) % 3],
                    (false, true) => t[b] + g.len[(k + 1) % 3],
                    (false, false) => continue,
                };
                if candidate < t[ci] {
                    t[ci] = candidate;
                    front.set(face[k], candidate);
                }
            }
        }
    }
    t
}

/// A mesh prepared once for fast marching: the faces around each vertex and each face's
/// lengths.
struct Marching {
    n: usize,
    faces: Vec<[u32; 3]>,
    around: Around,
    geometry: Vec<FaceGeometry>,
}

impl Marching {
    fn new(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Self {
        Marching {
            n: vertices.len(),
            faces: faces.to_vec(),
            around: Around::new(vertices.len(), faces),
            geometry: faces.par_iter().map(|f| FaceGeometry::new(vertices, f)).collect(),
        }
    }

    fn distances(&self, sources: &[usize]) -> Vec<Vec<f64>> {
        sources
            .par_iter()
            .map(|&s| {
                if self.around.of(s).is_empty() {
                    unreached(self.n, s)
                } else {
                    march(&self.faces, &self.geometry, &self.around, self.n, s as u32)
                }
            })
            .collect()
    }
}

/// Fast-marching geodesic distances from each source vertex to every vertex, one row per
/// source, sources in parallel. A vertex that no face uses, or that no face path reaches, is
/// `inf`.
pub fn geodesic_fmm(vertices: &[[f64; 3]], faces: &[[u32; 3]], sources: &[usize]) -> Result<Vec<Vec<f64>>> {
    check_input(vertices, faces, sources)?;
    Ok(Marching::new(vertices, faces).distances(sources))
}

/// The checks shared by every geodesic method: finite vertices, faces naming them, sources
/// among them.
pub(super) fn check_input(vertices: &[[f64; 3]], faces: &[[u32; 3]], sources: &[usize]) -> Result<()> {
    check_sources(vertices.len(), sources)?;
    check_finite_points("vertices", vertices)?;
    crate::mesh::check_faces(vertices.len(), faces)
}

/// Sources among the `n` vertices.
fn check_sources(n: usize, sources: &[usize]) -> Result<()> {
    match sources.iter().find(|&&s| s >= n) {
        Some(&s) => Err(Error::invalid("sources", format!("vertex {s} is beyond the {n} given"))),
        None => Ok(()),
    }
}

/// How geodesic distances are computed (`method=` in Python).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GeodesicMethod {
    /// Exact polyhedral geodesics (window propagation, MMP family): what matching needs.
    Exact,
    /// Fast marching: first order, ~0.2 % on scanned meshes, the fastest.
    Fmm,
    /// The heat method: two prefactored sparse solves per source, ~0.5 % on scanned meshes;
    /// the fastest for many sources on one mesh.
    Heat,
}

impl GeodesicMethod {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "exact" => Ok(GeodesicMethod::Exact),
            "fmm" => Ok(GeodesicMethod::Fmm),
            "heat" => Ok(GeodesicMethod::Heat),
            _ => Err(Error::invalid("method", format!("expected 'exact', 'fmm' or 'heat', got {name:?}"))),
        }
    }

    /// The name `parse` reads.
    pub fn name(self) -> &'static str {
        match self {
            GeodesicMethod::Exact => "exact",
            GeodesicMethod::Fmm => "fmm",
            GeodesicMethod::Heat => "heat",
        }
    }
}

/// A mesh prepared once for geodesic distances by one method, for any number of calls: the
/// exact method's layout and buffers, fast marching's adjacency and lengths, the heat method's
/// factored operators. `Sync`: calls may come from several threads.
pub struct GeodesicSolver {
    n: usize,
    method: GeodesicMethod,
    prepared: Prepared,
}

enum Prepared {
    Exact(Box<exact::ExactGeodesics>),
    Fmm(Marching),
    Heat(Box<HeatSolver>),
}

impl GeodesicSolver {
    /// Prepares the mesh. Errors name `vertices` (not finite) or `faces` (beyond the vertices).
    pub fn new(vertices: &[[f64; 3]], faces: &[[u32; 3]], method: GeodesicMethod) -> Result<Self> {
        check_input(vertices, faces, &[])?;
        let prepared = match method {
            GeodesicMethod::Exact => Prepared::Exact(Box::new(exact::ExactGeodesics::new(vertices, faces))),
            GeodesicMethod::Fmm => Prepared::Fmm(Marching::new(vertices, faces)),
            GeodesicMethod::Heat => Prepared::Heat(Box::new(HeatSolver::build(vertices, faces)?)),
        };
        Ok(GeodesicSolver { n: vertices.len(), method, prepared })
    }

    pub fn method(&self) -> GeodesicMethod {
        self.method
    }

    pub fn vertex_count(&self) -> usize {
        self.n
    }

    /// Distances from each source vertex to every vertex, one row per source, sources in
    /// parallel; `inf` at vertices no face uses or no face path reaches. Errors name `sources`
    /// beyond the vertices.
    pub fn distances(&self, sources: &[usize]) -> Result<Vec<Vec<f64>>> {
        check_sources(self.n, sources)?;
        match &self.prepared {
            Prepared::Exact(exact) => exact.distances(sources),
            Prepared::Fmm(marching) => Ok(marching.distances(sources)),
            Prepared::Heat(heat) => heat.distances_from(sources),
        }
    }
}

/// Geodesic distances from each source vertex to every vertex by `method`, one row per source:
/// a `GeodesicSolver` used once (the sources checked before the mesh is prepared).
pub fn geodesic_distances(
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    sources: &[usize],
    method: GeodesicMethod,
) -> Result<Vec<Vec<f64>>> {
    check_sources(vertices.len(), sources)?;
    if sources.is_empty() {
        // Nothing to compute: no mesh to prepare (the heat method would factor its operators).
        check_input(vertices, faces, sources)?;
        return Ok(Vec::new());
    }
    GeodesicSolver::new(vertices, faces, method)?.distances(sources)
}

/// A source that no face uses reaches only itself.
pub(super) fn unreached(n: usize, s: usize) -> Vec<f64> {
    let mut t = vec![f64::INFINITY; n];
    t[s] = 0.0;
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::mesh::test_meshes::grid;

    #[test]
    fn distances_on_a_flat_grid_are_euclidean() {
        let (v, f) = grid(21, 0.5);
        let d = geodesic_fmm(&v, &f, &[0, 220]).unwrap();
        for (row, &s) in d.iter().zip(&[0usize, 220]) {
            let worst = row
                .iter()
                .zip(&v)
                .map(|(t, p)| (t - (Vector3::from(*p) - Vector3::from(v[s])).norm()).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-9, "source {s}: worst {worst}");
        }
    }

    #[test]
    fn the_front_takes_vertices_out_by_distance_once_each_after_moves() {
        // Against a reference: the vertex of least (distance, index) among those queued and not
        // yet taken out, by brute force. Vertices are queued, moved down in place (a third of
        // them) and added in between the pops, as marching does.
        let n = 600;
        let mut d = vec![f64::INFINITY; n];
        let mut queued = vec![false; n];
        let mut front = Front::new(n);
        fn set(front: &mut Front, d: &mut [f64], queued: &mut [bool], v: usize, x: f64) {
            d[v] = x;
            queued[v] = true;
            front.set(v as u32, x);
        }
        for v in 0..n / 2 {
            set(&mut front, &mut d, &mut queued, v, ((v * 7919) % 101) as f64);
        }
        let mut next = n / 2;
        for step in 0..n {
            let expected = (0..n).filter(|&v| queued[v]).min_by(|&a, &b| d[a].total_cmp(&d[b]).then(a.cmp(&b)));
            let got = front.pop();
            assert_eq!(got.map(|v| v as usize), expected, "step {step}");
            let Some(v) = got else { break };
            queued[v as usize] = false;
            // Lower a queued vertex (never below the one just taken out) and queue a new one.
            if let Some(u) = (0..n).filter(|&u| queued[u]).nth(step % 7) {
                if step % 3 == 0 {
                    let lower = d[v as usize].max(d[u] - ((step * 31) % 17) as f64 - 0.5);
                    if lower < d[u] {
                        set(&mut front, &mut d, &mut queued, u, lower);
                    }
                }
            }
            if next < n {
                let x = d[v as usize] + ((next * 13) % 29) as f64;
                set(&mut front, &mut d, &mut queued, next, x);
                next += 1;
            }
        }
        assert!(front.pop().is_none() && queued.iter().all(|&q| !q));
    }

    #[test]
    fn unreached_vertices_are_inf_and_bad_input_is_refused_by_name() {
        let (mut v, f) = grid(3, 1.0);
        v.push([9.0, 9.0, 9.0]); // used by no face
        let d = geodesic_fmm(&v, &f, &[0, 9]).unwrap();
        assert!(d[0][9].is_infinite() && d[1][0].is_infinite() && d[1][9] == 0.0);
        assert!(geodesic_fmm(&v, &f, &[10]).unwrap_err().to_string().contains("sources"));
        assert!(geodesic_fmm(&v, &[[0, 1, 12]], &[0]).unwrap_err().to_string().contains("faces"));
    }
}
