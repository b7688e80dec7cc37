//! Geodesic distances by the heat method (SPEC S3): Crane, Weischedel & Wardetzky, "Geodesics in
//! heat", ACM TOG 32(5), 2013, and "The heat method for distance computation", CACM 60(11),
//! 2017.
//!
//! Varadhan: for short times t, −4t log kₜ(x, y) → d(x, y)², so the heat flowing out of a source
//! for a short time points, at every point, straight away from it. The method therefore
//!
//! 1. integrates the heat flow u̇ = Δu for one backward-Euler step of length t from a unit
//!    impulse at the source: (M + t L) u = δₛ, with L the cotangent Laplacian (positive
//!    semidefinite, Lᵢⱼ = −½(cot αᵢⱼ + cot βᵢⱼ)) and M the lumped (barycentric) mass;
//! 2. takes X = −∇u / |∇u| per triangle: a unit field along the direction of increasing
//!    distance. Only the direction of ∇u matters, which is why one implicit step suffices: its
//!    solution decays like exp(−d/√t) rather than exp(−d²/4t), so it stays representable up to
//!    ~700 mean edge lengths from the source (beyond, u underflows to 0, X is undefined and the
//!    distances there are only the Poisson solution's smooth continuation);
//! 3. finds the φ whose gradient is closest to X in L², the Poisson problem L φ = b with
//!    bᵢ = ∫ ∇ψᵢ · X (ψᵢ the hat function of vertex i; this is −1 × the integrated divergence
//!    of the papers, as L here is the positive operator);
//! 4. shifts φ so that the source is 0; the result is d up to the discretisation error, first
//!    order in h for t = h², h the mean edge length (the papers' choice: a larger t smooths the
//!    distance, a smaller one lets the mesh's anisotropy through).
//!
//! Both systems depend on the mesh only, so they are factored once (sparse Cholesky with a
//! fill-reducing ordering, `faer`) and every source costs two or three triangular solve pairs
//! and one pass over the faces. L is singular (the constants of each connected component); one
//! vertex of each component is held at 0 instead, which leaves the other equations unchanged
//! because b sums to zero over a component (the divergence theorem holds exactly for ψᵢ, whose
//! sum is 1).
//!
//! Robustness (Sharp & Crane, "A Laplacian for nonmanifold triangle meshes", SGP 2020):
//! - Intrinsic mollification: ε = max(0, maxₜᵣᵢ (δ − (lᵢ + lⱼ − lₖ))) is added to every edge
//!   length, δ = 10⁻⁵ h, so that every triangle inequality holds by δ: degenerate and
//!   zero-area triangles get a small positive area instead of infinite cotangents.
//! - Intrinsic Delaunay triangulation (Bobenko & Springborn 2007; Sharp, Soliman & Crane,
//!   "Navigating intrinsic triangulations", 2019): an edge whose opposite angles sum to more
//!   than π is flipped within the surface, on edge lengths alone (the two triangles are laid
//!   out in the plane and the new diagonal measured), until every edge is Delaunay. The
//!   surface, hence its geodesics, is unchanged; the cotangent weights all become ≥ 0, so L is
//!   an M-matrix and the heat is never negative. The Laplacian, the gradient and the
//!   divergence all use the intrinsic triangles: the gradient of the piecewise-linear u on an
//!   intrinsic triangle is computed in its own 2D layout. On an open mesh this runs on Sharp &
//!   Crane's tufted cover (`Intrinsic::tufted`: the faces twice, glued front to back along the
//!   boundary) so that boundary edges are flipped too, as potpourri3d does; a non-manifold or
//!   inconsistently oriented edge is never flipped and simply couples its faces.
//!
//! Boundaries: the heat flow with Neumann conditions (natural for L). The papers suggest
//! averaging the Neumann and the Dirichlet (u = 0 on the boundary) solutions; measured against
//! exact polyhedral distances that lost on every source (docs/mesh.md), so it is not offered.
use super::intrinsic::{area, Intrinsic, NONE};
use super::{check_input, unreached};
use crate::error::{check_finite_points, Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;

/// The heat method's operators for one mesh, factored once: `distances` then costs a few
/// triangular solves per source. Built by `HeatSolver::new`; `Sync`, so sources can run in
/// parallel on one solver.
pub struct HeatSolver {
    n: usize,
    /// The mean edge length: the solver works in units of it (no overflow or underflow from
    /// the mesh's unit) and scales the distances back.
    scale: f64,
    /// Component of each vertex (faces sharing a vertex are one component); NONE for a vertex
    /// used by no face.
    component: Vec<u32>,
    /// Intrinsic triangles, their areas and the gradients of their hat functions in each
    /// triangle's own 2D layout: ∇u = Σₖ u[tri[k]] grad[k].
    tri: Vec<[u32; 3]>,
    area: Vec<f64>,
    grad: Vec<[[f64; 2]; 3]>,
    /// Vertices held at 0 in the Poisson system.
    poisson_pin: Vec<bool>,
    /// One symbolic factorization (the two matrices share one sparsity pattern) and the
    /// numeric factors of the heat (Neumann) and Poisson systems.
    symbolic: Option<SymbolicCholesky<usize>>,
    heat: Vec<f64>,
    poisson: Vec<f64>,
}

/// The lower triangle of a symmetric n × n pattern in compressed columns (the diagonal first in
/// each column, rows ascending).
struct Pattern {
    col_ptr: Vec<usize>,
    row: Vec<usize>,
    sym: SymbolicSparseColMat<usize>,
}

impl Pattern {
    fn new(n: usize, tri: &[[u32; 3]]) -> Self {
        let mut pairs: Vec<(u32, u32)> = (0..n as u32).map(|v| (v, v)).collect();
        for t in tri {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                pairs.push((a.min(b), a.max(b)));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        for &(c, _) in &pairs {
            col_ptr[c as usize + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row: Vec<usize> = pairs.iter().map(|&(_, r)| r as usize).collect();
        let sym = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row.clone());
        Pattern { col_ptr, row, sym }
    }

    /// The slot of entry (max(a, b), min(a, b)).
    fn slot(&self, a: u32, b: u32) -> usize {
        let (c, r) = (a.min(b) as usize, a.max(b) as usize);
        let rows = &self.row[self.col_ptr[c]..self.col_ptr[c + 1]];
        // Present by construction: every face edge and every diagonal is in the pattern.
        self.col_ptr[c] + rows.binary_search(&r).unwrap_or(0)
    }

    /// `values` with the rows and columns of `pinned` vertices replaced by the identity's.
    fn pinned(&self, values: &[f64], pinned: &[bool]) -> Vec<f64> {
        let mut out = values.to_vec();
        for (c, w) in self.col_ptr.windows(2).enumerate() {
            for (x, &r) in out[w[0]..w[1]].iter_mut().zip(&self.row[w[0]..w[1]]) {
                if pinned[r] || pinned[c] {
                    *x = if r == c { 1.0 } else { 0.0 };
                }
            }
        }
        out
    }
}

/// |pq|, scaled so that no square overflows or underflows.
fn distance(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    let m = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * ((d[0] / m).powi(2) + (d[1] / m).powi(2) + (d[2] / m).powi(2)).sqrt()
}

/// The gradients of the three hat functions of a triangle with side lengths `l` (l[k] from
/// corner k to k + 1), in its layout p₀ = 0, p₁ = (l₀, 0), p₂ above: ∇ψₖ = J eₖ / 2A, eₖ the
/// edge opposite corner k, J the quarter turn. None for a degenerate triangle.
fn hat_gradients(l: [f64; 3]) -> Option<([[f64; 2]; 3], f64)> {
    // A positive area implies three positive sides.
    let a = area(l[0], l[1], l[2]);
    if a <= 0.0 {
        return None;
    }
    let p1 = [l[0], 0.0];
    let p2 = [(l[0] * l[0] + l[2] * l[2] - l[1] * l[1]) / (2.0 * l[0]), 2.0 * a / l[0]];
    let e = [[p2[0] - p1[0], p2[1] - p1[1]], [-p2[0], -p2[1]], p1];
    Some((e.map(|e| [-e[1] / (2.0 * a), e[0] / (2.0 * a)]), a))
}

/// Face-connected components by union-find; NONE for vertices of no face.
fn components(n: usize, faces: &[[u32; 3]]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    let mut used = vec![false; n];
    for f in faces {
        for k in 0..3 {
            used[f[k] as usize] = true;
            let (a, b) = (root(&mut parent, f[k]), root(&mut parent, f[(k + 1) % 3]));
            // The smaller index as root: each component is named by its smallest vertex.
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    (0..n as u32).map(|v| if used[v as usize] { root(&mut parent, v) } else { NONE }).collect()
}

/// The numeric Cholesky factor of the matrix `values` on `pattern`; sequential, so that the
/// factor does not depend on the thread count. A pivot that rounding made non-positive is
/// regularised on a second try rather than failing the mesh.
fn factor(symbolic: &SymbolicCholesky<usize>, pattern: &Pattern, values: &[f64]) -> Result<Vec<f64>> {
    let n = pattern.col_ptr.len() - 1;
    let a = SparseColMatRef::new(pattern.sym.as_ref(), values);
    let biggest = (0..n).map(|c| values[pattern.col_ptr[c]].abs()).fold(0.0f64, f64::max);
    let mut l = vec![0.0; symbolic.len_val()];
    let mut mem = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
    for reg in [
        LltRegularization::default(),
        LltRegularization {
            dynamic_regularization_delta: 1e-10 * biggest,
            dynamic_regularization_epsilon: 1e-13 * biggest,
        },
    ] {
        let stack = MemStack::new(&mut mem);
        if symbolic.factorize_numeric_llt(&mut l, a, Side::Lower, reg, Par::Seq, stack, Default::default()).is_ok() {
            return Ok(l);
        }
    }
    Err(Error::invalid("faces", "the mesh's Laplacian could not be factored (non-finite geometry?)"))
}

impl HeatSolver {
    /// Builds and factors the heat method's operators of a mesh. Errors name `vertices` (not
    /// finite, or too large for their edge lengths to be represented) or `faces` (beyond the
    /// vertices).
    pub fn new(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<Self> {
        check_finite_points("vertices", vertices)?;
        crate::mesh::check_faces(vertices.len(), faces)?;
        Self::build(vertices, faces)
    }

    /// `new` on input its caller has checked (`check_input`).
    pub(super) fn build(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<Self> {
        let n = vertices.len();
        let nh = 3 * faces.len();
        let mut len: Vec<f64> = (0..nh)
            .map(|h| {
                let f = faces[h / 3];
                distance(&vertices[f[h % 3] as usize], &vertices[f[(h + 1) % 3] as usize])
            })
            .collect();
        // Halfedges grouped by their edge: twins, boundary vertices and the mean edge length.
        let mut keys: Vec<(u32, u32, u32)> = (0..nh)
            .filter_map(|h| {
                let f = faces[h / 3];
                let (a, b) = (f[h % 3], f[(h + 1) % 3]);
                (a != b).then(|| (a.min(b), a.max(b), h as u32))
            })
            .collect();
        keys.sort_unstable();
        let mut twin = vec![NONE; nh];
        let mut boundary_half = Vec::new();
        let longest = len.iter().fold(0.0f64, |m, &l| m.max(l));
        let (mut sum, mut edges) = (0.0f64, 0usize);
        for group in keys.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
            let h = group[0].2;
            if longest > 0.0 {
                sum += len[h as usize] / longest;
            }
            edges += 1;
            match group {
                [_] => boundary_half.push(h as usize),
                [(_, _, p), (_, _, q)] => {
                    let (p, q) = (*p as usize, *q as usize);
                    let from = |h: usize| faces[h / 3][h % 3];
                    if p / 3 != q / 3 && from(p) != from(q) {
                        twin[p] = q as u32;
                        twin[q] = p as u32;
                    }
                }
                _ => {}
            }
        }
        if !longest.is_finite() {
            return Err(Error::invalid("vertices", "coordinates too large: an edge length overflows"));
        }
        let scale = if edges > 0 { longest * (sum / edges as f64) } else { 0.0 };
        let component = components(n, faces);
        let mut solver = HeatSolver {
            n,
            scale,
            component,
            tri: faces.to_vec(),
            area: Vec::new(),
            grad: Vec::new(),
            poisson_pin: vec![false; n],
            symbolic: None,
            heat: Vec::new(),
            poisson: Vec::new(),
        };
        // All edges of zero length: each component is a single point, nothing to solve.
        if scale == 0.0 {
            return Ok(solver);
        }
        for l in &mut len {
            *l /= scale;
        }
        // Mollification: δ = 10⁻⁵ h, and h = 1 in the solver's unit.
        let delta = 1e-5;
        let eps = len
            .chunks_exact(3)
            .flat_map(|l| (0..3).map(move |k| delta - (l[k] + l[(k + 1) % 3] - l[(k + 2) % 3])))
            .fold(0.0f64, f64::max);
        if eps > 0.0 {
            for l in &mut len {
                *l += eps;
            }
        }
        let mut it = Intrinsic { tri: faces.to_vec(), len, twin };
        // Each face of the tufted cover stands for half of one of the mesh's faces.
        let mut share = 1.0;
        if !boundary_half.is_empty() {
            it = it.tufted(&boundary_half);
            share = 0.5;
        }
        it.flip_to_delaunay();
        let geometry: Vec<([[f64; 2]; 3], f64)> = it
            .len
            .chunks_exact(3)
            .map(|l| hat_gradients([l[0], l[1], l[2]]).map_or(([[0.0; 2]; 3], 0.0), |(g, a)| (g, share * a)))
            .collect();
        solver.grad = geometry.iter().map(|g| g.0).collect();
        solver.area = geometry.iter().map(|g| g.1).collect();
        solver.tri = it.tri;

        // Stiffness (cotangent Laplacian, Lᵢⱼ = ∫ ∇ψᵢ·∇ψⱼ) and lumped mass.
        let pattern = Pattern::new(n, &solver.tri);
        let mut stiffness = vec![0.0; pattern.row.len()];
        let mut mass = vec![0.0; n];
        for (t, (g, a)) in solver.tri.iter().zip(&geometry) {
            for k in 0..3 {
                mass[t[k] as usize] += a / 3.0;
                for m in k..3 {
                    let w = a * (g[k][0] * g[m][0] + g[k][1] * g[m][1]);
                    // A vertex twice in one (intrinsic) face gets both orders on its diagonal.
                    let w = if m != k && t[k] == t[m] { 2.0 * w } else { w };
                    stiffness[pattern.slot(t[k], t[m])] += w;
                }
            }
        }
        let unused: Vec<bool> = solver.component.iter().map(|&c| c == NONE).collect();
        // t = h², and h = 1 in the solver's unit.
        let mut heat = stiffness.clone();
        for v in 0..n {
            heat[pattern.col_ptr[v]] += mass[v];
        }
        let heat = pattern.pinned(&heat, &unused);
        // The first vertex of each component holds the Poisson solution's constant.
        solver.poisson_pin = (0..n).map(|v| unused[v] || solver.component[v] == v as u32).collect();
        let poisson = pattern.pinned(&stiffness, &solver.poisson_pin);

        let symbolic = factorize_symbolic_cholesky(
            pattern.sym.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| Error::invalid("faces", format!("the mesh's Laplacian could not be analysed: {e:?}")))?;
        let (heat, poisson) =
            rayon::join(|| factor(&symbolic, &pattern, &heat), || factor(&symbolic, &pattern, &poisson));
        solver.heat = heat?;
        solver.poisson = poisson?;
        solver.symbolic = Some(symbolic);
        Ok(solver)
    }

    /// Distances from vertex `source` to every vertex; `inf` for vertices in another component
    /// and vertices used by no face. Errors name `source` beyond the vertices.
    pub fn distances(&self, source: usize) -> Result<Vec<f64>> {
        if source >= self.n {
            return Err(Error::invalid("source", format!("vertex {source} is beyond the {} given", self.n)));
        }
        Ok(self.block(&[source]).remove(0))
    }

    /// `distances` of each source, one row per source, in parallel blocks of `BLOCK` sources.
    /// The blocks do not depend on the thread count, so neither do the results; a row may
    /// differ in the last bits from the same source's row in another block (another width).
    /// Errors name `sources` beyond the vertices.
    pub fn distances_from(&self, sources: &[usize]) -> Result<Vec<Vec<f64>>> {
        if let Some(&s) = sources.iter().find(|&&s| s >= self.n) {
            return Err(Error::invalid("sources", format!("vertex {s} is beyond the {} given", self.n)));
        }
        let blocks: Vec<Vec<Vec<f64>>> = sources.par_chunks(BLOCK).map(|b| self.block(b)).collect();
        Ok(blocks.into_iter().flatten().collect())
    }

    /// Solves in place for the columns of `rhs` (column-major, n rows).
    fn solve(&self, factor: &[f64], rhs: &mut [f64]) {
        let Some(symbolic) = &self.symbolic else { return };
        let k = rhs.len() / self.n;
        let mut mem = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(k, Par::Seq));
        LltRef::new(symbolic, factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, self.n, k),
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }

    /// b for the Poisson system from the heat u: bᵢ = Σ_faces A ∇ψᵢ · X, X = −∇u / |∇u|.
    fn poisson_rhs(&self, u: &[f64], b: &mut [f64]) {
        for ((t, g), a) in self.tri.iter().zip(&self.grad).zip(&self.area) {
            let (u0, u1, u2) = (u[t[0] as usize], u[t[1] as usize], u[t[2] as usize]);
            let gx = u0 * g[0][0] + u1 * g[1][0] + u2 * g[2][0];
            let gy = u0 * g[0][1] + u1 * g[1][1] + u2 * g[2][1];
            // Scaled first: far from the source u is tiny (it decays like exp(−d/h)) and its
            // squares would underflow. Where u underflowed to a constant there is no direction.
            let m = gx.abs().max(gy.abs());
            if m.is_nan() || m == 0.0 {
                continue;
            }
            let (gx, gy) = (gx / m, gy / m);
            let norm = (gx * gx + gy * gy).sqrt();
            let (x, y) = (-gx / norm, -gy / norm);
            for k in 0..3 {
                b[t[k] as usize] += a * (g[k][0] * x + g[k][1] * y);
            }
        }
        for (b, &p) in b.iter_mut().zip(&self.poisson_pin) {
            if p {
                *b = 0.0;
            }
        }
    }

    /// The rows of a block of sources: each solve serves the whole block in one pass over its
    /// factor, which is what a triangular solve's time goes to.
    fn block(&self, sources: &[usize]) -> Vec<Vec<f64>> {
        let n = self.n;
        let solved: Vec<usize> =
            sources.iter().copied().filter(|&s| self.component[s] != NONE && self.symbolic.is_some()).collect();
        let k = solved.len();
        let mut u = vec![0.0; n * k];
        for (j, &s) in solved.iter().enumerate() {
            u[j * n + s] = 1.0;
        }
        if k > 0 {
            self.solve(&self.heat, &mut u);
        }
        let mut b = vec![0.0; n * k];
        for (u, b) in u.chunks_exact(n).zip(b.chunks_exact_mut(n)) {
            self.poisson_rhs(u, b);
        }
        if k > 0 {
            self.solve(&self.poisson, &mut b);
        }
        let mut phi = b.chunks_exact(n);
        sources
            .iter()
            .map(|&s| {
                let c = self.component[s];
                if c == NONE {
                    return unreached(n, s);
                }
                let mut d: Vec<f64> =
                    self.component.iter().map(|&k| if k == c { 0.0 } else { f64::INFINITY }).collect();
                // No column without a factor: every edge of zero length, each component a point.
                if let Some(phi) = phi.next() {
                    for (v, d) in d.iter_mut().enumerate() {
                        if *d == 0.0 && v != s {
                            // Slightly negative next to the source where the approximation
                            // undershoots.
                            *d = ((phi[v] - phi[s]) * self.scale).max(0.0);
                        }
                    }
                }
                d
            })
            .collect()
    }
}

/// Sources solved together. Wider blocks read each factor fewer times per source; 8 keeps
/// 20 sources in 3 blocks for 2 cores and a block's right-hand sides in a few MB.
const BLOCK: usize = 8;

/// Heat-method geodesic distances from each source vertex to every vertex, one row per source:
/// the operators factored once, sources in parallel blocks. A vertex that no face uses, or in
/// another component than the source, is `inf`. Approximate (first order in the edge length:
/// ~0.5–1 % of the mean distance on scanned meshes); `geodesic_fmm` is more accurate.
pub fn geodesic_heat(vertices: &[[f64; 3]], faces: &[[u32; 3]], sources: &[usize]) -> Result<Vec<Vec<f64>>> {
    check_input(vertices, faces, sources)?;
    if sources.is_empty() {
        return Ok(Vec::new());
    }
    HeatSolver::build(vertices, faces)?.distances_from(sources)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::mesh::test_meshes::grid;

    fn dist(p: [f64; 3], q: [f64; 3]) -> f64 {
        distance(&p, &q)
    }

    /// On the flat grid, from source `s`: the mean |error| / mean distance over all vertices,
    /// and the worst relative error over the vertices at least `margin` from the grid's edge
    /// and `near` from the source.
    fn flat_errors(n: usize, h: f64, s: usize, margin: f64, near: f64) -> (f64, f64) {
        let (v, f) = grid(n, h);
        let d = HeatSolver::new(&v, &f).unwrap().distances(s).unwrap();
        let side = (n - 1) as f64 * h;
        let (mut worst, mut err, mut total) = (0.0f64, 0.0, 0.0);
        for (p, t) in v.iter().zip(&d) {
            let e = dist(*p, v[s]);
            err += (t - e).abs();
            total += e;
            let inside = p[0].min(p[1]).min(side - p[0]).min(side - p[1]) >= margin;
            if inside && e >= near {
                worst = worst.max((t - e).abs() / e);
            }
        }
        (err / total, worst)
    }

    #[test]
    fn distances_on_a_flat_grid_are_nearly_euclidean() {
        // The heat method is an approximation of first order in h (CWW 2013): at t = h²
        // the distance is smoothed over a few edges around the source, and on this grid, whose
        // diagonals alternate, the distance along the grid's axes comes out ~2.5 % short at
        // h = side / 40 (diagonal directions +0.3 %): potpourri3d gives the same numbers to
        // 4·10⁻⁴. Hence: mean relative error < 2 %, worst < 3.5 % from 8 h away from the source
        // and the boundary (measured 1.47 % and 2.83 %), and both smaller at half the h.
        let (n, h) = (41, 0.25);
        let (mean, worst) = flat_errors(n, h, 20 * n + 20, 2.0, 2.0);
        assert!(mean < 0.02 && worst < 0.035, "mean {mean}, worst {worst}");
        let (mean2, worst2) = flat_errors(2 * n - 1, h / 2.0, 40 * (2 * n - 1) + 40, 2.0, 2.0);
        assert!(mean2 < mean && worst2 < worst, "no convergence: {mean2}, {worst2} vs {mean}, {worst}");
        // The source gets exactly 0 and no distance is negative or NaN.
        let (v, f) = grid(n, h);
        let d = geodesic_heat(&v, &f, &[0, 20 * n + 20]).unwrap();
        assert_eq!(d[0][0], 0.0);
        assert!(d.iter().flatten().all(|x| x.is_finite() && *x >= 0.0));
        // A corner source: distances grow along the edges nearly as Euclidean.
        let far = d[0][n - 1];
        assert!((far - 10.0).abs() < 0.3, "{far}");
    }

    #[test]
    fn a_cylinder_is_measured_as_its_unrolling() {
        // A curved surface with two boundary loops: geodesics on the open cylinder are straight
        // lines of its unrolling (the shorter way round). Measured 1.09 % (potpourri3d: the
        // same), the bound leaves room for rounding differences only.
        let (r, rings, around, dz) = (2.0, 31, 64, 0.2);
        let mut v = Vec::new();
        for j in 0..rings {
            for i in 0..around {
                let th = i as f64 * std::f64::consts::TAU / around as f64;
                v.push([r * th.cos(), r * th.sin(), j as f64 * dz]);
            }
        }
        let mut f = Vec::new();
        for j in 0..rings - 1 {
            for i in 0..around {
                let a = (j * around + i) as u32;
                let b = (j * around + (i + 1) % around) as u32;
                f.extend([[a, b, b + around as u32], [a, b + around as u32, a + around as u32]]);
            }
        }
        let s = 15 * around;
        let d = geodesic_heat(&v, &f, &[s]).unwrap();
        let (mut err, mut total) = (0.0, 0.0);
        for (k, t) in d[0].iter().enumerate() {
            let (di, dj) = ((k % around) as f64, (k / around) as f64 - 15.0);
            let arc = di.min(around as f64 - di) * std::f64::consts::TAU / around as f64 * r;
            let e = arc.hypot(dj * dz);
            err += (t - e).abs();
            total += e;
        }
        assert!(err / total < 0.0125, "mean relative error {}", err / total);
    }

    #[test]
    fn other_components_and_unused_vertices_are_inf() {
        let (mut v, mut f) = grid(5, 1.0);
        let (w, g) = grid(3, 1.0);
        let off = v.len() as u32;
        v.extend(w.iter().map(|p| [p[0] + 10.0, p[1], p[2]]));
        f.extend(g.iter().map(|t| t.map(|i| i + off)));
        v.push([9.0, 9.0, 9.0]); // used by no face
        let last = v.len() - 1;
        let d = geodesic_heat(&v, &f, &[0, off as usize + 4, last]).unwrap();
        assert!(d[0][..25].iter().all(|x| x.is_finite()) && d[0][25..].iter().all(|x| x.is_infinite()));
        assert!(d[1][..25].iter().all(|x| x.is_infinite()) && d[1][last].is_infinite());
        assert!(d[1][25..34].iter().all(|x| x.is_finite()) && d[1][29] == 0.0);
        assert!((d[1][25] - 2f64.sqrt()).abs() < 0.2, "{}", d[1][25]);
        assert!(d[2].iter().enumerate().all(|(i, x)| if i == last { *x == 0.0 } else { x.is_infinite() }));
        // One source alone, or in a block with others: the same up to rounding.
        let alone = HeatSolver::new(&v, &f).unwrap().distances(0).unwrap();
        assert!(alone.iter().zip(&d[0]).all(|(a, b)| a == b || (a - b).abs() < 1e-12 * b), "{alone:?}");
    }

    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        let (v, f) = grid(30, 0.1);
        let sources: Vec<usize> = (0..900).step_by(37).collect();
        let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("a thread pool");
        let one = pool(1).install(|| geodesic_heat(&v, &f, &sources)).unwrap();
        let two = pool(2).install(|| geodesic_heat(&v, &f, &sources)).unwrap();
        let bits = |d: &Vec<Vec<f64>>| d.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one), bits(&two));
    }

    #[test]
    fn heat_is_a_geodesic_method() {
        use crate::mesh::{geodesic_distances, GeodesicMethod};
        let (v, f) = grid(5, 1.0);
        let method = GeodesicMethod::parse("heat").unwrap();
        assert_eq!(geodesic_distances(&v, &f, &[3, 7], method).unwrap(), geodesic_heat(&v, &f, &[3, 7]).unwrap());
        let e = GeodesicMethod::parse("hot").unwrap_err().to_string();
        assert!(e.starts_with("method: ") && e.contains("'heat'") && e.contains("'fmm'"), "{e}");
    }

    #[test]
    fn bad_input_is_refused_by_name() {
        let (mut v, f) = grid(3, 1.0);
        let e = |r: Result<Vec<Vec<f64>>>| r.unwrap_err().to_string();
        assert!(e(geodesic_heat(&v, &f, &[9])).starts_with("sources: "));
        assert!(e(geodesic_heat(&v, &[[0, 1, 12]], &[0])).starts_with("faces: "));
        assert!(HeatSolver::new(&v, &[[0, 1, 12]]).err().unwrap().to_string().starts_with("faces: "));
        let solver = HeatSolver::new(&v, &f).unwrap();
        assert!(solver.distances(9).unwrap_err().to_string().starts_with("source: "));
        assert!(solver.distances_from(&[0, 9]).unwrap_err().to_string().starts_with("sources: "));
        v[4][2] = f64::NAN;
        assert!(e(geodesic_heat(&v, &f, &[0])).starts_with("vertices: "));
        v[4][2] = 1e308;
        v[0][2] = -1e308;
        assert!(e(geodesic_heat(&v, &f, &[0])).starts_with("vertices: "));
    }

    #[test]
    fn awkward_meshes_give_finite_distances_without_panic() {
        let finite_from = |v: &[[f64; 3]], f: &[[u32; 3]], s: usize| {
            let d = geodesic_heat(v, f, &[s]).unwrap();
            assert_eq!(d[0][s], 0.0);
            assert!(d[0].iter().all(|x| x.is_finite() && *x >= 0.0), "{v:?} {f:?}: {:?}", d[0]);
            d.into_iter().next().unwrap()
        };
        // A single triangle.
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        // (One triangle has one gradient: the distance comes out as the projection on the
        // direction away from the source, 1/√2 here, not 1.)
        let d = finite_from(&tri, &[[0, 1, 2]], 0);
        assert!(d[1] > 0.5 && (d[1] - d[2]).abs() < 1e-12, "{d:?}");
        // Zero-area triangles: collinear corners, coincident corners, a repeated index.
        let (mut v, mut f) = grid(4, 1.0);
        v.extend([[0.5, 4.0, 0.0], [1.0, 4.0, 0.0], [1.5, 4.0, 0.0], [3.0, 3.0, 0.0]]);
        f.extend([[12, 13, 16], [16, 17, 18], [13, 16, 17], [15, 19, 14], [14, 14, 15], [3, 3, 3]]);
        finite_from(&v, &f, 5);
        // A non-manifold edge: three fins on one edge, and a fourth face reversed.
        let v =
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, -1.0, 0.0], [0.5, 0.0, 1.0], [0.5, 0.0, -1.0]];
        let f = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [0, 5, 1]];
        let d = finite_from(&v, &f, 2);
        assert!(d[3] > d[0] && d[3] < 2.5, "{d:?}");
        // All corners at one point: every distance within the component is 0.
        let d = finite_from(&[[1.0; 3]; 3], &[[0, 1, 2]], 1);
        assert_eq!(d, vec![0.0; 3]);
        // No faces at all, and no vertices.
        assert_eq!(geodesic_heat(&tri, &[], &[1]).unwrap(), vec![vec![f64::INFINITY, 0.0, f64::INFINITY]]);
        assert!(geodesic_heat(&[], &[], &[]).unwrap().is_empty());
    }

    #[test]
    fn intrinsic_flips_make_every_weight_nonnegative_and_keep_the_area() {
        // A grid sheared hard: every other diagonal is badly non-Delaunay.
        let (mut v, f) = grid(12, 1.0);
        for p in &mut v {
            p[0] += 2.7 * p[1];
            p[2] = 0.3 * (p[0] * 0.4).sin();
        }
        let len = |it: &Intrinsic| it.len.chunks_exact(3).map(|l| area(l[0], l[1], l[2])).sum::<f64>();
        let lengths: Vec<f64> =
            (0..3 * f.len()).map(|h| dist(v[f[h / 3][h % 3] as usize], v[f[h / 3][(h + 1) % 3] as usize])).collect();
        let mut twin = vec![NONE; lengths.len()];
        for p in 0..twin.len() {
            for q in 0..twin.len() {
                let (a, b) = (f[p / 3][p % 3], f[p / 3][(p + 1) % 3]);
                if f[q / 3][q % 3] == b && f[q / 3][(q + 1) % 3] == a {
                    twin[p] = q as u32;
                }
            }
        }
        let mut it = Intrinsic { tri: f.clone(), len: lengths, twin };
        let before = len(&it);
        let negative = |it: &Intrinsic| {
            (0..it.len.len())
                .filter(|&h| it.twin[h] != NONE && it.cot_opposite(h) + it.cot_opposite(it.twin[h] as usize) < -1e-9)
                .count()
        };
        assert!(negative(&it) > 20);
        it.flip_to_delaunay();
        assert_eq!(negative(&it), 0);
        assert!((len(&it) - before).abs() < 1e-9 * before);
        for h in 0..it.len.len() {
            let t = it.twin[h];
            if t != NONE {
                assert_eq!(it.twin[t as usize] as usize, h);
                assert_eq!(it.len[t as usize], it.len[h]);
            }
        }
    }
}
