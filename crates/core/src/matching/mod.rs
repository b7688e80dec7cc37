//! Isometric matching (SPEC S4; paper 002 §3.3): where did each theoretical matching point go on
//! the bent, scanned skin?
//!
//! A thin skin clamped on the machine bends without stretching, so geodesic distances along it
//! are kept. The matching points p'ᵢ on the actual surface are moved (in x, y; z follows the
//! surface) until their geodesic distances to the two actual locating points r'₁, r'₂ and to one
//! another equal the theoretical ones: the vectors V₁ (theoretical) and V₂ (actual) of
//! `2n + n(n−1)/2` distances (eq 10–11), Levenberg–Marquardt on `V₂ − V₁` (eq 16) with the
//! paper's damping schedule, objective T = ‖V₂ − V₁‖ (14) and largest error E (15).
//!
//! The Jacobian of a distance d(a, p'ⱼ) with respect to p'ⱼ's x, y is either the paper's (eq
//! 12–13: a quadratic in x, y fitted to the distances from a to all matching points, then
//! differentiated) or the gradient of a's distance field at p'ⱼ (SPEC S4 Beyond), fitted over
//! the two rings of mesh vertices around p'ⱼ. The Jacobian only steers the steps: both end at
//! the same matched points; the gradient takes fewer steps.
//! The formulas: docs/matching.md.
use crate::error::{check_finite_points, Error, Result};
use crate::mesh::{
    closest_points, geodesic_distances, insert_points, off_surface, off_surface_limit, GeodesicMethod, ScanSurface,
    Spacing, XyLocator,
};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix6, Vector2, Vector6};

/// A points that lands this close (mm) to a mesh vertex or edge is put on it, not beside it.
const INSERT_TOLERANCE: f64 = 1e-6;
/// The paper's damping: starts at 0.001, ÷5 after a better step, ×5 after a worse one.
const DAMPING_START: f64 = 1e-3;
const DAMPING_FACTOR: f64 = 5.0;
/// Damping beyond which no step improves T any more: the noise floor of the scan.
const DAMPING_LIMIT: f64 = 1e8;
/// The other signs of the noise floor: `FLAT_STEPS` accepted steps in a row, each lowering T by
/// less than `FLAT` of itself, or a rejected step of which the linear model expected less than
/// 2 `FLAT` of T² (about `FLAT` of T). Measured on the bent skin with 10 µm noise: E stays at
/// 1.14–1.16 µm, above the default tolerance, while T falls by 0.3, 0.14, 0.04, 0.01 % a step
/// and then by nothing; without this stop the match went on to its iteration limit (50, ~55 s)
/// for the same points. Away from the floor the paper's Jacobian lowers T by a third a step.
const FLAT: f64 = 1e-3;
const FLAT_STEPS: usize = 2;

/// How the Jacobian of the distances is formed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Jacobian {
    /// Eq 12–13: a quadratic surface of distances over the matching points' x, y.
    Quadratic,
    /// The gradient of the distance field at each matching point (SPEC S4 Beyond).
    Gradient,
}

impl Jacobian {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "quadratic" => Ok(Jacobian::Quadratic),
            "gradient" => Ok(Jacobian::Gradient),
            _ => Err(Error::invalid("jacobian", format!("expected 'quadratic' or 'gradient', got {name:?}"))),
        }
    }
}

/// Why the iterations stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// E ≤ tolerance.
    Tolerance,
    /// The last accepted step moved no point by more than a hundredth of the tolerance.
    Step,
    /// T stopped falling: no step improved it, even with the damping at its limit or where the
    /// linear model expected next to nothing, or the last `FLAT_STEPS` accepted steps each
    /// lowered it by less than `FLAT` of itself (the noise floor: E stays above the tolerance
    /// there, the points move but T no more).
    Stalled,
    MaxIterations,
}

impl Stop {
    pub fn name(self) -> &'static str {
        match self {
            Stop::Tolerance => "tolerance",
            Stop::Step => "step",
            Stop::Stalled => "stalled",
            Stop::MaxIterations => "max_iterations",
        }
    }

    /// Whether the matched points are as good as the data allows.
    pub fn converged(self) -> bool {
        self != Stop::MaxIterations
    }
}

/// A triangle mesh, borrowed, and the median edge of the surface as the user gave it (before
/// thinning: the scan's own spacing), which sets how far off it a point may be given
/// (`off_surface_limit`).
#[derive(Clone, Copy)]
pub struct Surface<'a> {
    pub vertices: &'a [[f64; 3]],
    pub faces: &'a [[u32; 3]],
    pub given_edge: f64,
}

#[derive(Debug, Clone, Copy)]
pub struct MatchOptions {
    pub jacobian: Jacobian,
    pub method: GeodesicMethod,
    pub max_iterations: usize,
    /// E (mm) at which the match is done.
    pub tolerance: f64,
}

#[derive(Debug, Clone)]
pub struct IsometricMatch {
    /// The matched actual points, on the actual surface.
    pub points: Vec<[f64; 3]>,
    /// The actual locating points, on the actual surface.
    pub locating: [[f64; 3]; 2],
    /// T and E of the starting points, then after each iteration.
    pub objective: Vec<f64>,
    pub max_error: Vec<f64>,
    pub iterations: usize,
    pub stop: Stop,
    /// The final V₂ − V₁ (mm), in the order of eq 11: d(r₁, pⱼ), d(r₂, pⱼ), then d(pᵢ, pⱼ) for i < j.
    pub residuals: Vec<f64>,
}

/// The distances of eq 11 between the locating points and the matching points, from the
/// distance rows of the mesh (`rows[s]` from the vertex `vertex[sources[s]]`). `vertex` holds
/// r₁, r₂, p₁ … pₙ. Where both directions were computed, their mean (fast marching is not
/// symmetric; exact methods are).
struct Distances {
    /// `d[a][j]`: from point a (0, 1 locating; 2 + i matching i) to matching point j.
    d: Vec<Vec<f64>>,
}

impl Distances {
    fn new(rows: &[Vec<f64>], sources: &[usize], vertex: &[u32], n: usize) -> Self {
        let mut row_of = vec![None; n + 2];
        for (s, &a) in sources.iter().enumerate() {
            row_of[a] = Some(s);
        }
        let one = |a: usize, b: usize| -> f64 {
            match (row_of[a], row_of[b]) {
                (Some(ra), Some(rb)) => 0.5 * (rows[ra][vertex[b] as usize] + rows[rb][vertex[a] as usize]),
                (Some(ra), None) => rows[ra][vertex[b] as usize],
                (None, Some(rb)) => rows[rb][vertex[a] as usize],
                (None, None) => f64::NAN,
            }
        };
        Distances {
            d: (0..n + 2).map(|a| (0..n).map(|j| if a == j + 2 { 0.0 } else { one(a, j + 2) }).collect()).collect(),
        }
    }

    /// V of eq 11.
    fn vector(&self) -> Vec<f64> {
        let n = self.d[0].len();
        let mut v = Vec::with_capacity(2 * n + n * (n - 1) / 2);
        v.extend_from_slice(&self.d[0]);
        v.extend_from_slice(&self.d[1]);
        for i in 0..n {
            v.extend_from_slice(&self.d[2 + i][i + 1..]);
        }
        v
    }
}

/// The points put on the surface at their x, y (the surface is a height field over xy);
/// `None` for one outside the surface's outline.
fn on_surface(surface: Surface<'_>, locator: &XyLocator<'_>, xy: &[[f64; 2]]) -> Option<Vec<[f64; 3]>> {
    xy.iter().map(|p| locator.locate(p[0], p[1]).map(|l| l.point(surface.vertices, surface.faces))).collect()
}

/// Inserts `points` (r₁, r₂, p₁ … pₙ) into the mesh and computes the distances from the
/// vertices `sources` (indices into `points`).
fn distances(
    surface: Surface<'_>,
    points: &[[f64; 3]],
    sources: &[usize],
    method: GeodesicMethod,
) -> Result<(Distances, Option<Field>)> {
    let n = points.len() - 2;
    let ins = insert_points(surface.vertices, surface.faces, points, INSERT_TOLERANCE)?;
    let src: Vec<usize> = sources.iter().map(|&a| ins.indices[a] as usize).collect();
    let rows = geodesic_distances(&ins.vertices, &ins.faces, &src, method)?;
    let d = Distances::new(&rows, sources, &ins.indices, n);
    let field = (sources.len() == n + 2).then_some(Field {
        rows,
        vertices: ins.vertices,
        faces: ins.faces,
        vertex: ins.indices,
    });
    Ok((d, field))
}

/// One evaluation of the actual side: V₂ − V₁, the distances, the fields (gradient Jacobian
/// only) and the matching points on the surface.
type Evaluation = (Vec<f64>, Distances, Option<Field>, Vec<[f64; 3]>);

/// The distance fields of every point on the mesh they were computed on, for the gradient
/// Jacobian.
struct Field {
    rows: Vec<Vec<f64>>,
    vertices: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    vertex: Vec<u32>,
}

impl Field {
    /// ∂d/∂(x, y) of the distance from point `a` at matching point `j`: a plane fitted to the
    /// distances of the vertices within two rings of pⱼ's vertex, through pⱼ's own.
    fn gradients(&self, n: usize) -> Vec<Vec<Vector2<f64>>> {
        // The two rings around each matching point's vertex.
        let mut ring: Vec<Vec<u32>> = vec![Vec::new(); self.vertices.len()];
        let targets: Vec<u32> = self.vertex[2..].to_vec();
        let mut is_target = vec![false; self.vertices.len()];
        for &t in &targets {
            is_target[t as usize] = true;
        }
        let mut first: Vec<Vec<u32>> = vec![Vec::new(); self.vertices.len()];
        for f in &self.faces {
            for &v in f {
                if is_target[v as usize] {
                    first[v as usize].extend(f.iter().filter(|&&u| u != v));
                }
            }
        }
        let mut wanted = vec![false; self.vertices.len()];
        for &t in &targets {
            for &u in &first[t as usize] {
                wanted[u as usize] = true;
            }
        }
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); self.vertices.len()];
        for f in &self.faces {
            for &v in f {
                if wanted[v as usize] {
                    around[v as usize].extend(f.iter().filter(|&&u| u != v));
                }
            }
        }
        for &t in &targets {
            let mut r: Vec<u32> = first[t as usize].clone();
            for &u in &first[t as usize] {
                r.extend(&around[u as usize]);
            }
            r.sort_unstable();
            r.dedup();
            r.retain(|&u| u != t);
            ring[t as usize] = r;
        }
        (0..n + 2)
            .map(|a| {
                (0..n)
                    .map(|j| {
                        let t = self.vertex[2 + j] as usize;
                        if a == j + 2 {
                            return Vector2::zeros();
                        }
                        let row = &self.rows[a];
                        let (c, d0) = (self.vertices[t], row[t]);
                        let (mut m, mut b) = (Matrix2::zeros(), Vector2::zeros());
                        for &u in &ring[t] {
                            let du = row[u as usize];
                            if !du.is_finite() {
                                continue;
                            }
                            let p = self.vertices[u as usize];
                            let x = Vector2::new(p[0] - c[0], p[1] - c[1]);
                            m += x * x.transpose();
                            b += x * (du - d0);
                        }
                        m.try_inverse().map_or(Vector2::zeros(), |mi| mi * b)
                    })
                    .collect()
            })
            .collect()
    }
}

/// ∂d/∂(x, y) by eq 12–13: for each point a, the quadratic
/// d_a(x, y) = a + bx + cy + ex² + fxy + gy² fitted to its distances to the matching points (itself left out: the cone tip at 0 is
/// no part of a smooth surface), differentiated at each matching point.
fn quadratic_gradients(d: &Distances, xy: &[[f64; 2]]) -> Vec<Vec<Vector2<f64>>> {
    let n = xy.len();
    let q = QuadraticFrame::new(xy);
    (0..n + 2)
        .map(|a| {
            let (mut m, mut b) = (Matrix6::zeros(), Vector6::zeros());
            for (j, &p) in xy.iter().enumerate() {
                if a == j + 2 {
                    continue;
                }
                let phi = q.basis(p);
                m += phi * phi.transpose();
                b += phi * d.d[a][j];
            }
            let c = m.try_inverse().map_or(Vector6::zeros(), |mi| mi * b);
            xy.iter()
                .map(|&p| {
                    let (x, y) = q.local(p);
                    Vector2::new(c[1] + 2.0 * c[3] * x + c[4] * y, c[2] + c[4] * x + 2.0 * c[5] * y) / q.s
                })
                .collect()
        })
        .collect()
}

/// The frame of eq 12–13's quadratic: x, y centred on the points and scaled by their extent, so
/// that the normal equations are well conditioned in mm.
struct QuadraticFrame {
    cx: f64,
    cy: f64,
    s: f64,
}

impl QuadraticFrame {
    fn new(xy: &[[f64; 2]]) -> Self {
        let n = xy.len() as f64;
        let (cx, cy) = (xy.iter().map(|p| p[0]).sum::<f64>() / n, xy.iter().map(|p| p[1]).sum::<f64>() / n);
        let s = xy.iter().map(|p| (p[0] - cx).abs().max((p[1] - cy).abs())).fold(0.0, f64::max).max(1e-12);
        QuadraticFrame { cx, cy, s }
    }

    fn local(&self, p: [f64; 2]) -> (f64, f64) {
        ((p[0] - self.cx) / self.s, (p[1] - self.cy) / self.s)
    }

    fn basis(&self, p: [f64; 2]) -> Vector6<f64> {
        let (x, y) = self.local(p);
        Vector6::new(1.0, x, y, x * x, x * y, y * y)
    }
}

/// The Jacobian of V (eq 11 order) with respect to (x₁, y₁, …, xₙ, yₙ), from the gradients
/// `g[a][j]` of the distance from point a at matching point j.
fn jacobian(g: &[Vec<Vector2<f64>>], n: usize) -> DMatrix<f64> {
    let m = 2 * n + n * (n - 1) / 2;
    let mut jac = DMatrix::zeros(m, 2 * n);
    let mut row = 0;
    for ga in &g[..2] {
        for (j, gj) in ga.iter().enumerate() {
            jac[(row, 2 * j)] = gj.x;
            jac[(row, 2 * j + 1)] = gj.y;
            row += 1;
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            // d(pᵢ, pⱼ) moves with pⱼ along pᵢ's field, and with pᵢ along pⱼ's.
            jac[(row, 2 * j)] = g[2 + i][j].x;
            jac[(row, 2 * j + 1)] = g[2 + i][j].y;
            jac[(row, 2 * i)] = g[2 + j][i].x;
            jac[(row, 2 * i + 1)] = g[2 + j][i].y;
            row += 1;
        }
    }
    jac
}

/// Eq 12–13 fit a quadratic in x, y to the distances at the matching points other than the
/// source; the fit is only defined when those points do not lie on one line or conic. Checked
/// on the theoretical points (the actual ones are their near-isometric images): a degenerate fit
/// would give zero gradients and a match that stalls without saying why.
fn check_quadratic_fit(matching: &[[f64; 3]]) -> Result<()> {
    let xy: Vec<[f64; 2]> = matching.iter().map(|p| [p[0], p[1]]).collect();
    let q = QuadraticFrame::new(&xy);
    for skip in 0..xy.len() {
        // The normal matrix's Cholesky pivots, by hand: direct, where an SVD iterates (nalgebra's
        // does not stop on some exactly rank-deficient matrices). A pivot below 1e-14 of the
        // largest diagonal is a singular value ratio below ~1e-7: the points lie on a conic.
        let normal = (0..xy.len())
            .filter(|&j| j != skip)
            .map(|j| q.basis(xy[j]))
            .fold(Matrix6::zeros(), |m, r| m + r * r.transpose());
        let mut m: [[f64; 6]; 6] = std::array::from_fn(|i| std::array::from_fn(|j| normal[(i, j)]));
        let hi = (0..6).map(|i| m[i][i]).fold(0.0, f64::max);
        let mut lo = f64::INFINITY;
        for k in 0..6 {
            let pivot = m[k][k];
            lo = lo.min(pivot);
            if !(pivot > 1e-14 * hi) {
                break;
            }
            let row_k = m[k];
            for row in m.iter_mut().skip(k + 1) {
                let f = row[k] / pivot;
                for (x, y) in row.iter_mut().zip(&row_k).skip(k + 1) {
                    *x -= f * y;
                }
            }
        }
        if !(lo > 1e-14 * hi) {
            return Err(Error::invalid(
                "theoretical_matching",
                format!("the points other than point {skip} lie on one line or conic in x, y, so the quadratic Jacobian (eq 12–13) is not defined: spread them, or use jacobian='gradient'"),
            ));
        }
    }
    Ok(())
}

/// The x, y rigid motion that takes the theoretical locating points to the actual ones: where
/// the matching points start when none are given.
fn start_by_locating(t_loc: &[[f64; 3]; 2], a_loc: &[[f64; 3]; 2], t_match: &[[f64; 3]]) -> Vec<[f64; 2]> {
    let angle = |p: &[[f64; 3]; 2]| (p[1][1] - p[0][1]).atan2(p[1][0] - p[0][0]);
    let (s, c) = (angle(a_loc) - angle(t_loc)).sin_cos();
    t_match
        .iter()
        .map(|p| {
            let (x, y) = (p[0] - t_loc[0][0], p[1] - t_loc[0][1]);
            [a_loc[0][0] + c * x - s * y, a_loc[0][1] + s * x + c * y]
        })
        .collect()
}

/// Puts the given points on the surface (their closest points), refusing one farther from it
/// than `off_surface_limit`.
fn onto(surface: Surface<'_>, name: &str, points: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
    check_finite_points(name, points)?;
    let closest = closest_points(surface.vertices, surface.faces, points)?;
    let limit = off_surface_limit(surface.given_edge);
    if let Some((i, c)) = closest.iter().enumerate().find(|(_, c)| !(c.distance <= limit)) {
        return Err(off_surface(name, i, points[i], c.distance, limit));
    }
    Ok(closest.into_iter().map(|c| c.point).collect())
}

/// How scan points are meshed for the match: triangles with an edge beyond `max_edge` left out
/// (by default those beyond `EDGE_TRIM` × the median edge, peeled from the outline) and the
/// points thinned as `spacing` says ([`crate::mesh::surface_mesh`]). A surface given as a mesh is taken as is.
#[derive(Debug, Clone, Copy)]
pub struct Meshing {
    pub max_edge: Option<f64>,
    pub spacing: Spacing,
}

/// [`isometric_match`] on surfaces as a caller gives them: scan points are meshed first
/// ([`Meshing`]), a mesh is taken as given. Errors name `theoretical_points`, `actual_points`.
#[allow(clippy::too_many_arguments)]
pub fn isometric_match_points(
    theoretical: ScanSurface<'_>,
    actual: ScanSurface<'_>,
    meshing: Meshing,
    theoretical_locating: &[[f64; 3]],
    actual_locating: &[[f64; 3]],
    theoretical_matching: &[[f64; 3]],
    actual_initial: Option<&[[f64; 3]]>,
    options: MatchOptions,
) -> Result<IsometricMatch> {
    let (tv, tf, t_edge) = theoretical.mesh("theoretical_points", meshing.max_edge, meshing.spacing)?;
    let (av, af, a_edge) = actual.mesh("actual_points", meshing.max_edge, meshing.spacing)?;
    isometric_match(
        Surface { vertices: &tv, faces: &tf, given_edge: t_edge },
        Surface { vertices: &av, faces: &af, given_edge: a_edge },
        theoretical_locating,
        actual_locating,
        theoretical_matching,
        actual_initial,
        options,
    )
}

/// Matches the theoretical matching points onto the actual surface (module docs).
/// `actual_initial`: the starting actual matching points (x, y used); by default the
/// theoretical ones moved by the x, y rigid motion of the locating points.
pub fn isometric_match(
    theoretical: Surface<'_>,
    actual: Surface<'_>,
    theoretical_locating: &[[f64; 3]],
    actual_locating: &[[f64; 3]],
    theoretical_matching: &[[f64; 3]],
    actual_initial: Option<&[[f64; 3]]>,
    options: MatchOptions,
) -> Result<IsometricMatch> {
    for (name, p) in [("theoretical_locating", theoretical_locating), ("actual_locating", actual_locating)] {
        if p.len() != 2 {
            return Err(Error::invalid(name, format!("expected the 2 locating points r1, r2, got {}", p.len())));
        }
    }
    let n = theoretical_matching.len();
    let least = if options.jacobian == Jacobian::Quadratic { 7 } else { 3 };
    if n < least {
        let why = if least == 7 { " (the quadratic Jacobian fits 6 coefficients to the other points)" } else { "" };
        return Err(Error::invalid("theoretical_matching", format!("needs at least {least} points{why}, got {n}")));
    }
    if let Some(a) = actual_initial {
        check_finite_points("actual_initial", a)?;
        if a.len() != n {
            return Err(Error::invalid(
                "actual_initial",
                format!("expected {n} points, one per matching point, got {}", a.len()),
            ));
        }
    }
    for (name, p) in [("theoretical_locating", theoretical_locating), ("actual_locating", actual_locating)] {
        check_finite_points(name, p)?;
        // The start and the frame of eq 11 need the direction r1 → r2 in xy.
        let scale = p.iter().flatten().fold(1.0f64, |m, c| m.max(c.abs()));
        if (p[1][0] - p[0][0]).hypot(p[1][1] - p[0][1]) <= 1e-9 * scale {
            return Err(Error::invalid(name, "r1 and r2 coincide in x, y: the two locating points must be apart"));
        }
    }
    if options.jacobian == Jacobian::Quadratic {
        check_quadratic_fit(theoretical_matching)?;
    }
    if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
        return Err(Error::invalid(
            "tolerance",
            format!("must be a positive finite number of mm, got {}", options.tolerance),
        ));
    }
    let t_loc: [[f64; 3]; 2] = onto(theoretical, "theoretical_locating", theoretical_locating)?
        .try_into()
        .map_err(|_| Error::invalid("theoretical_locating", "expected 2 points"))?;
    let a_loc: [[f64; 3]; 2] = onto(actual, "actual_locating", actual_locating)?
        .try_into()
        .map_err(|_| Error::invalid("actual_locating", "expected 2 points"))?;
    let t_match = onto(theoretical, "theoretical_matching", theoretical_matching)?;

    // V₁, once: distances on the theoretical surface from every matching point.
    let mut t_points = t_loc.to_vec();
    t_points.extend(&t_match);
    let matching: Vec<usize> = (2..n + 2).collect();
    let (d1, _) = distances(theoretical, &t_points, &matching, options.method)?;
    let v1 = d1.vector();
    if let Some(k) = v1.iter().position(|d| !d.is_finite()) {
        return Err(Error::invalid("theoretical_points", format!("distance {k} of V1 is not finite: the theoretical surface does not join all the locating and matching points")));
    }

    let locator = XyLocator::new(actual.vertices, actual.faces);
    let mut xy: Vec<[f64; 2]> = match actual_initial {
        Some(a) => a.iter().map(|p| [p[0], p[1]]).collect(),
        None => {
            // A strongly bent part is shorter in xy than flat (the chord, not the arc), so the
            // rigid motion can carry points near its far edge past the outline (R = 250 mm, a
            // 300 mm plate: up to 148 mm). Those start just inside the nearest triangle.
            let mut xy = start_by_locating(&t_loc, &a_loc, &t_match);
            for p in &mut xy {
                if locator.locate(p[0], p[1]).is_some() {
                    continue;
                }
                if let Some(mut near) = locator.nearest(p[0], p[1]) {
                    let w = near.barycentric.map(|c| c.max(0.0));
                    let sum = w.iter().sum::<f64>();
                    near.barycentric = w.map(|c| 0.999 * c / sum + 0.001 / 3.0);
                    let q = near.point(actual.vertices, actual.faces);
                    *p = [q[0], q[1]];
                }
            }
            xy
        }
    };
    let sources: Vec<usize> =
        if options.jacobian == Jacobian::Gradient { (0..n + 2).collect() } else { matching.clone() };
    let evaluate = |xy: &[[f64; 2]]| -> Result<Option<Evaluation>> {
        let Some(p) = on_surface(actual, &locator, xy) else { return Ok(None) };
        let mut pts = a_loc.to_vec();
        pts.extend(&p);
        let (d, field) = distances(actual, &pts, &sources, options.method)?;
        let f: Vec<f64> = d.vector().iter().zip(&v1).map(|(a, b)| a - b).collect();
        Ok(Some((f, d, field, p)))
    };
    let Some((mut f, mut d, mut field, mut points)) = evaluate(&xy)? else {
        let i = xy.iter().position(|p| locator.locate(p[0], p[1]).is_none()).unwrap_or(0);
        let [x, y] = xy[i];
        return Err(match actual_initial {
            Some(_) => Error::invalid("actual_initial", format!("point {i} ({x:.3}, {y:.3}) lies outside the actual surface's xy outline")),
            None => Error::invalid(
                "theoretical_matching",
                format!("point {i}, moved by the rigid motion of the locating points to ({x:.3}, {y:.3}), lies outside the actual surface's xy outline (check it lies on the part, and actual_locating)"),
            ),
        });
    };
    let norm = |f: &[f64]| f.iter().map(|v| v * v).sum::<f64>().sqrt();
    let worst = |f: &[f64]| f.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    if f.iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid(
            "actual_points",
            "the actual surface does not join all the locating and matching points",
        ));
    }
    let (mut objective, mut max_error) = (vec![norm(&f)], vec![worst(&f)]);
    let mut u = DAMPING_START;
    let mut iterations = 0;
    // Accepted steps in a row that lowered T by less than `FLAT` of itself.
    let mut flat = 0;
    let stop = loop {
        crate::interrupt::check()?;
        if *max_error.last().unwrap_or(&0.0) <= options.tolerance {
            break Stop::Tolerance;
        }
        if iterations >= options.max_iterations {
            break Stop::MaxIterations;
        }
        let g = match (&field, options.jacobian) {
            (Some(fl), Jacobian::Gradient) => fl.gradients(n),
            _ => quadratic_gradients(&d, &xy),
        };
        let j = jacobian(&g, n);
        let jt_f = j.transpose() * DVector::from_column_slice(&f);
        let jt_j = j.transpose() * &j;
        let (mut accepted, mut floor) = (None, false);
        // Damping up until a step improves T (eq 16), each try one iteration.
        while iterations < options.max_iterations && u <= DAMPING_LIMIT {
            iterations += 1;
            let a = &jt_j + DMatrix::identity(2 * n, 2 * n) * u;
            let step = a.lu().solve(&(-&jt_f)).unwrap_or_else(|| DVector::zeros(2 * n));
            // What the linear model expects of the step: the fraction of T² it removes.
            let expected = 1.0 - (&j * &step + DVector::from_column_slice(&f)).norm_squared() / norm(&f).powi(2);
            let trial: Vec<[f64; 2]> =
                xy.iter().enumerate().map(|(i, p)| [p[0] + step[2 * i], p[1] + step[2 * i + 1]]).collect();
            let better = match evaluate(&trial)? {
                Some(e) if norm(&e.0) < *objective.last().unwrap_or(&f64::INFINITY) => Some(e),
                _ => None,
            };
            match better {
                Some(e) => {
                    u /= DAMPING_FACTOR;
                    let moved = (0..n).map(|i| step[2 * i].hypot(step[2 * i + 1])).fold(0.0, f64::max);
                    accepted = Some((e, trial, moved));
                    break;
                }
                None => {
                    u *= DAMPING_FACTOR;
                    objective.push(*objective.last().unwrap_or(&f64::NAN));
                    max_error.push(*max_error.last().unwrap_or(&f64::NAN));
                    // A step that fails where the model expected next to nothing of it: more
                    // damping only shortens it (the floor, without ~20 more tries up to the limit).
                    if !(expected >= 2.0 * FLAT) {
                        floor = true;
                        break;
                    }
                }
            }
        }
        let Some(((fe, de, fielde, pe), trial, moved)) = accepted else {
            break if u > DAMPING_LIMIT || floor { Stop::Stalled } else { Stop::MaxIterations };
        };
        (f, d, field, points, xy) = (fe, de, fielde, pe, trial);
        let before = *objective.last().unwrap_or(&f64::INFINITY);
        objective.push(norm(&f));
        max_error.push(worst(&f));
        if moved < 0.01 * options.tolerance {
            break Stop::Step;
        }
        flat = if norm(&f) > (1.0 - FLAT) * before { flat + 1 } else { 0 };
        if flat >= FLAT_STEPS {
            break Stop::Stalled;
        }
    };
    Ok(IsometricMatch { points, locating: a_loc, objective, max_error, iterations, stop, residuals: f })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::median_edge;

    /// A flat grid over [x0, x0 + w] × [y0, y0 + h] at spacing s, turned by `angle` about the
    /// origin, then shifted.
    fn plate(w: f64, h: f64, s: f64, angle: f64, shift: [f64; 2]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let (nx, ny) = ((w / s).round() as usize + 1, (h / s).round() as usize + 1);
        let (sn, cs) = angle.sin_cos();
        let v: Vec<[f64; 3]> = (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f64 * s, (k / nx) as f64 * s);
                [cs * x - sn * y + shift[0], sn * x + cs * y + shift[1], 0.0]
            })
            .collect();
        let f = crate::mesh::delaunay_xy(&v, None).unwrap();
        (v, f)
    }

    fn moved(p: [f64; 3], angle: f64, shift: [f64; 2]) -> [f64; 3] {
        let (sn, cs) = angle.sin_cos();
        [cs * p[0] - sn * p[1] + shift[0], sn * p[0] + cs * p[1] + shift[1], p[2]]
    }

    #[test]
    fn a_rigidly_moved_flat_plate_is_matched_exactly_by_either_jacobian() {
        // Exact geodesics on a flat mesh are Euclidean, so the matched points are the moved ones
        // up to the stopping tolerance.
        let (tv, tf) = plate(60.0, 40.0, 2.0, 0.0, [0.0, 0.0]);
        let (angle, shift) = (0.2, [7.0, -3.0]);
        let (av, af) = plate(60.0, 40.0, 2.0, angle, shift);
        let loc = [[3.3, 2.1, 0.0], [56.7, 37.9, 0.0]];
        let matching: Vec<[f64; 3]> =
            (0..16).map(|k| [6.1 + 15.7 * (k % 4) as f64, 5.3 + 9.9 * (k / 4) as f64, 0.0]).collect();
        let truth: Vec<[f64; 3]> = matching.iter().map(|&p| moved(p, angle, shift)).collect();
        let a_loc = loc.map(|p| moved(p, angle, shift));
        // A start 1 mm off the truth.
        let start: Vec<[f64; 3]> =
            truth.iter().enumerate().map(|(k, p)| [p[0] + (k as f64).sin(), p[1] + (k as f64).cos(), 0.0]).collect();
        for jacobian in [Jacobian::Gradient, Jacobian::Quadratic] {
            let opts = MatchOptions { jacobian, method: GeodesicMethod::Exact, max_iterations: 60, tolerance: 1e-7 };
            let r = isometric_match(
                Surface { vertices: &tv, faces: &tf, given_edge: median_edge(&tv, &tf) },
                Surface { vertices: &av, faces: &af, given_edge: median_edge(&av, &af) },
                &loc,
                &a_loc,
                &matching,
                Some(&start),
                opts,
            )
            .unwrap();
            let err = r.points.iter().zip(&truth).map(|(p, t)| (p[0] - t[0]).hypot(p[1] - t[1])).fold(0.0, f64::max);
            assert!(
                err < 1e-5,
                "{jacobian:?}: worst {err} mm after {} iterations ({:?}), T {:?}",
                r.iterations,
                r.stop,
                r.objective
            );
            assert_eq!(r.objective.len(), r.iterations + 1);
        }
    }

    #[test]
    fn bad_input_is_refused_by_name() {
        let (v, f) = plate(20.0, 20.0, 2.0, 0.0, [0.0, 0.0]);
        let s = Surface { vertices: &v, faces: &f, given_edge: median_edge(&v, &f) };
        // A 3 × 3 grid: without any one of its points the rest fix a quadratic (eq 12–13).
        let m: Vec<[f64; 3]> = (0..9).map(|k| [4.0 + 6.0 * (k % 3) as f64, 4.0 + 6.0 * (k / 3) as f64, 0.0]).collect();
        let line: Vec<[f64; 3]> = (0..8).map(|k| [2.0 + 2.0 * k as f64, 3.0 + k as f64, 0.0]).collect();
        let loc = [[1.0, 1.0, 0.0], [19.0, 19.0, 0.0]];
        let opts = MatchOptions {
            jacobian: Jacobian::Quadratic,
            method: GeodesicMethod::Fmm,
            max_iterations: 5,
            tolerance: 1e-3,
        };
        let e = |r: Result<IsometricMatch>| r.unwrap_err().to_string();
        assert!(e(isometric_match(s, s, &loc[..1], &loc, &m, None, opts)).contains("theoretical_locating"));
        assert!(e(isometric_match(s, s, &loc, &loc, &m[..5], None, opts)).contains("theoretical_matching"));
        assert!(e(isometric_match(s, s, &loc, &loc, &line, None, opts)).contains("one line or conic"));
        let same = [loc[0], loc[0]];
        assert!(
            e(isometric_match(s, s, &same, &loc, &m, None, opts)).contains("theoretical_locating: r1 and r2 coincide")
        );
        assert!(e(isometric_match(s, s, &loc, &loc, &m, Some(&m[..3]), opts)).contains("actual_initial"));
        let far: Vec<[f64; 3]> = m.iter().map(|p| [p[0] + 100.0, p[1], 0.0]).collect();
        assert!(e(isometric_match(s, s, &loc, &loc, &m, Some(&far), opts)).contains("actual_initial"));
        assert!(e(isometric_match(s, s, &loc, &loc, &m, None, MatchOptions { tolerance: 0.0, ..opts }))
            .contains("tolerance"));
    }
}
