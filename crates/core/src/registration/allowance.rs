//! Machining allowance (SPEC R7; paper 004 §1.2, eq 2–10): how much stock the blank leaves over
//! the model, measured from each model point along its outward normal to the blank's surface
//! around the line. Positive where the blank envelops the model, negative where it does not
//! (the part would come out short there), NaN where the blank does not cover the point.
//!
//! The paper's local surface is the least-squares plane of the k nearest blank points (eq 3–5),
//! kept as `BlankSurface::Plane`. A plane sits below a curved blank by the mean sag of its
//! points, κ·d²/2, and round a blade's edge (a radius of one or two point spacings) the k
//! nearest points turn by 90° or more: no plane or height field over it follows them (0.1–0.3 mm
//! wrong at a 0.8 mm edge sampled every 0.5 mm).
//!
//! The default, `BlankSurface::Stock`, measures each blank point's distance from the model and
//! fits that stock field about the model point ([`super::stock`]): it follows the blank where
//! model and blank turn together, a fillet meeting a flank included, but needs the model's own
//! normals and a model sampled about as densely as the blank.
//!
//! `BlankSurface::Quadric` fits the blank points alone: an implicit quadric about a centre on the
//! line, the centre moved to where the line meets it, four times:
//!
//!   f(x, y, z) = z + c0 + c1·x + c2·y + c3·x² + c4·xy + c5·y² + c6·z² + c7·xz + c8·yz = 0
//!
//! in the frame (e1, e2, v) of the model normal v, lengths in units of h = 1.5 s (s the blank's
//! point spacing), blank points weighted exp(−d²/h²) about the centre. Unlike a height field this
//! holds circles and cylinders of any orientation exactly (x² + z² − 2rz = 0), so it follows an
//! edge that turns by more than 90° across the neighbourhood. Normalising by the z coefficient
//! keeps the fit linear (weighted least squares of the algebraic residual, 9 × 9). Where the fit
//! turns fast (an edge), the last two fits also try weights long along the edge and narrow across
//! it, kept where they fit far better (a curvature that jumps where a fillet meets a flank). The
//! allowance is NaN where the blank does not cover the point: the line meets no quadric, the
//! centre has no blank point within 1.5 s (a hole), the neighbours lie on one side of the line
//! (beyond the blank's end), the surface grazes the line (more than 60° from the model's normal
//! plane), or the centre has not settled. Measured against exact offsets of twisted elliptic and
//! circular-arc blades (BENCHMARKS.md): within 3 µm on smooth edges of radius ≥ 1.5 s at 0.2–1 mm
//! spacing; where a fillet meets a flank tangentially (the curvature jumps) 3–6 µm at s ≤ 0.5
//! mm, 10–18 µm at 0.75–1 mm (the stock field: within 5.9 µm there).
use super::stock::ModelShape;
use crate::error::{check_finite_points, check_positive, Error, Result};
use crate::spatial::PointIndex;
use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen, Vector3};
use rayon::prelude::*;

type V3 = Vector3<f64>;
type M9 = SMatrix<f64, 9, 9>;
type V9 = SVector<f64, 9>;

/// The blank's surface is this far from the model normal (|cos| below, 60°): it is not the
/// blank over the point but a neighbouring feature, so the line along the normal meets it far
/// off, and the allowance there is NaN (reported, not guessed). Stock varies far more gently.
pub(super) const GRAZING: f64 = 0.5;

/// Blank points of each plane by default (the paper's local surface): enough for a stable fit
/// through sensor noise, few enough to stay local at the blank's sampling.
pub const PLANE_POINTS: usize = 8;

/// The quadric's kernel width h, in blank spacings: wide enough that the Gaussian weights hold
/// well over the nine points its nine terms need through noise, narrow enough to follow an edge
/// of 1.5 s radius.
pub(super) const WIDTH: f64 = 1.5;
/// Neighbours of a quadric fit, and of an edge's long, narrow fit.
const FIT_POINTS: usize = 48;
const EDGE_POINTS: usize = 200;
/// Weights beyond this many h are cut (exp(−6.25) ≈ 0.002).
pub(super) const CUT: f64 = 2.5;
/// The edge fit's widths across and along the edge, in blank spacings.
const ACROSS: f64 = 0.4;
const ALONG: f64 = 4.5;
/// Fits per point, and how many isotropic ones come before the edge test.
const ITERATIONS: usize = 4;
const ISOTROPIC: usize = 2;
/// A fit turning by more than this (rad) over the kernel's width 2h is an edge.
const EDGE_TURN: f64 = 0.1;
/// The edge fit is kept only where its weighted residual is below this share of the isotropic
/// fit's on the same points: a curvature jump fits far better; noise alone (which both see)
/// does not choose it.
const EDGE_GAIN: f64 = 0.35;
/// ... and only where the isotropic fit leaves a mean squared algebraic residual above this (in
/// h², an RMS of 1e-3 h: under a µm at the usual spacings): a fit that already holds every point
/// has nothing to gain, and the narrow weights, which see the points across an edge on one line,
/// would only lose the curvature across it (17 µm on a cylinder of 2.5 spacings' radius).
const EDGE_FLOOR: f64 = 1e-6;
/// Ridge on the z terms of the quadric, relative to the normal matrix's trace: damps them where
/// the points are flat (z ≈ 0 makes them collinear with the constant); the other terms get
/// 1e-9, only to stay solvable.
const RIDGE: f64 = 1e-4;
/// The last step of the centre, in blank spacings, above which it has not settled.
const SETTLED: f64 = 0.05;
/// The centre has no blank point within this many spacings: a hole.
pub(super) const GAP: f64 = 1.5;
/// The weighted mean of the neighbours' offsets across the line is above this share of their
/// weighted RMS offset: they lie on one side, the line passes beyond the blank's end.
pub(super) const COVER: f64 = 0.5;
/// Blank points sampled for the spacing estimate.
const SPACING_SAMPLES: usize = 20_000;

/// The blank's local surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlankSurface {
    /// The least-squares plane of the k nearest blank points (paper 004 eq 3–5).
    Plane,
    /// The re-centred implicit quadric (module docs).
    Quadric,
    /// The blank points' stock over the model, fitted about the point ([`super::stock`]).
    Stock,
}

impl BlankSurface {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "plane" => Ok(BlankSurface::Plane),
            "quadric" => Ok(BlankSurface::Quadric),
            "stock" => Ok(BlankSurface::Stock),
            _ => Err(Error::invalid("surface", format!("expected 'stock', 'quadric' or 'plane', got {name:?}"))),
        }
    }
}

/// How the blank's surface is taken: the local surface, the plane's neighbour count (default
/// [`PLANE_POINTS`]) and the blank's point spacing (default: estimated from the blank).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlankOptions {
    pub surface: BlankSurface,
    pub k: Option<usize>,
    pub spacing: Option<f64>,
}

impl Default for BlankOptions {
    fn default() -> Self {
        BlankOptions { surface: BlankSurface::Stock, k: None, spacing: None }
    }
}

/// The measured blank, indexed, with what its local surfaces need.
pub(super) struct Blank<'a> {
    points: &'a [[f64; 3]],
    index: PointIndex,
    surface: BlankSurface,
    k: usize,
    spacing: f64,
}

impl<'a> Blank<'a> {
    pub(super) fn new(points: &'a [[f64; 3]], options: &BlankOptions) -> Result<Self> {
        check_finite_points("blank_points", points)?;
        let k = match (options.surface, options.k) {
            (BlankSurface::Plane, k) => k.unwrap_or(PLANE_POINTS),
            (BlankSurface::Quadric | BlankSurface::Stock, Some(_)) => return Err(Error::invalid(
                "k",
                "applies to surface='plane'; the stock field's and the quadric's neighbourhoods follow the blank's \
                 spacing (give spacing=)",
            )),
            (BlankSurface::Quadric | BlankSurface::Stock, None) => 0,
        };
        if let Some(s) = options.spacing {
            check_positive("spacing", s, "mm")?;
        }
        if options.surface == BlankSurface::Plane {
            if k < 3 {
                return Err(Error::invalid("k", format!("a plane needs at least 3 blank points, got k = {k}")));
            }
            if k > points.len() {
                return Err(Error::invalid(
                    "k",
                    format!("{k} neighbors asked, but the blank has {} points", points.len()),
                ));
            }
        } else if points.len() < FIT_POINTS {
            return Err(Error::invalid(
                "blank_points",
                format!("{} points are too few for a local surface ({FIT_POINTS} at least)", points.len()),
            ));
        }
        let index = PointIndex::new(points)?;
        let spacing = match options.spacing {
            Some(s) => s,
            None if options.surface != BlankSurface::Plane => {
                let s = point_spacing(points, &index);
                if !(s.is_finite() && s > 0.0) {
                    return Err(Error::invalid(
                        "blank_points",
                        "all points coincide: no spacing to fit a surface over",
                    ));
                }
                s
            }
            None => f64::NAN,
        };
        Ok(Blank { points, index, surface: options.surface, k, spacing })
    }

    /// Where the line `p + t·v` (v unit) meets the blank's local surface: `t` and the unit normal
    /// of that surface there (its sign arbitrary). None where the blank does not cover the point.
    /// The stock field is met through [`super::stock::StockField`], which needs the model too.
    pub(super) fn meet(&self, p: &V3, v: &V3) -> Option<(f64, V3)> {
        match self.surface {
            BlankSurface::Plane => self.meet_plane(p, v),
            BlankSurface::Quadric | BlankSurface::Stock => self.meet_quadric(p, v),
        }
    }

    pub(super) fn surface(&self) -> BlankSurface {
        self.surface
    }

    pub(super) fn spacing(&self) -> f64 {
        self.spacing
    }

    pub(super) fn points(&self) -> &'a [[f64; 3]] {
        self.points
    }

    fn point(&self, i: usize) -> V3 {
        V3::from(self.points[i])
    }

    /// Paper 004 eq 10 as SPEC R7 corrects it: `t = n·(q0 − p) / (n·v)`.
    fn meet_plane(&self, p: &V3, v: &V3) -> Option<(f64, V3)> {
        let near: Vec<V3> = self.index.knn(&[p[0], p[1], p[2]], self.k).iter().map(|&(i, _)| self.point(i)).collect();
        let q0 = near.iter().sum::<V3>() / near.len() as f64;
        let cov = near.iter().fold(Matrix3::zeros(), |a, q| a + (q - q0) * (q - q0).transpose());
        let eig = SymmetricEigen::new(cov);
        let smallest = (0..3).min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]))?;
        let n = eig.eigenvectors.column(smallest).into_owned();
        let nv = n.dot(v);
        (nv.abs() >= GRAZING).then(|| (n.dot(&(q0 - p)) / nv, n))
    }

    /// The re-centred implicit quadric (module docs).
    fn meet_quadric(&self, p: &V3, v: &V3) -> Option<(f64, V3)> {
        let s = self.spacing;
        let h = WIDTH * s;
        let frame = Frame::new(*v, h);
        let (mut t, mut step) = (0.0, f64::INFINITY);
        let mut fit: Option<Fit> = None;
        // The edge test and the choice between the two edge fits are made once (at the first
        // fit after the isotropic ones) and kept, so the last fits do not flip between schemes.
        let (mut edge, mut narrow) = (None::<V3>, false);
        for iteration in 0..ITERATIONS {
            let c = p + t * v;
            if iteration == ISOTROPIC {
                edge = fit.as_ref().filter(|f| f.curvature * 2.0 * h > EDGE_TURN).map(|f| f.along);
            }
            let next = match edge {
                None => {
                    let near = self.index.knn(&c.into(), FIT_POINTS);
                    let mut q: Vec<V3> = near.iter().map(|&(i, _)| self.point(i) - c).collect();
                    // The model point lies off the blank by the allowance: the neighbours' heights
                    // along v are all about −t, which makes the z terms collinear with the
                    // constant. The first centre moves along v to their weighted mean height.
                    let mut shift = 0.0;
                    if iteration == 0 {
                        let nearest = near.first()?.1;
                        let (mut sw, mut sz) = (0.0, 0.0);
                        for (qi, &(_, d2)) in q.iter().zip(&near) {
                            let w = (-(d2 - nearest) / (h * h)).exp();
                            sw += w;
                            sz += w * qi.dot(v);
                        }
                        shift = sz / sw;
                        q.iter_mut().for_each(|qi| *qi -= shift * v);
                    }
                    let weights: Vec<f64> = q
                        .iter()
                        .map(|qi| {
                            let d2 = qi.norm_squared();
                            if d2 <= (CUT * h).powi(2) {
                                (-d2 / (h * h)).exp()
                            } else {
                                0.0
                            }
                        })
                        .collect();
                    let mut f = frame.fit(&q, &weights)?;
                    f.step += shift;
                    f
                }
                Some(along) => {
                    let near = self.index.knn(&c.into(), EDGE_POINTS);
                    let q: Vec<V3> = near.iter().map(|&(i, _)| self.point(i) - c).collect();
                    let (across, long) = (ACROSS * s, ALONG * s);
                    let long_narrow: Vec<f64> = q
                        .iter()
                        .map(|qi| {
                            let a = qi.dot(&along);
                            (-(qi.norm_squared() - a * a) / (across * across) - a * a / (long * long)).exp()
                        })
                        .collect();
                    let round: Vec<f64> = q.iter().map(|qi| (-qi.norm_squared() / (h * h)).exp()).collect();
                    let (a, i) = (frame.fit(&q, &long_narrow), frame.fit(&q, &round));
                    if iteration == ISOTROPIC {
                        narrow = match (&a, &i) {
                            (Some(a), Some(i)) => i.residual > EDGE_FLOOR && a.residual < EDGE_GAIN * i.residual,
                            (Some(_), None) => true,
                            _ => false,
                        };
                    }
                    if narrow {
                        a?
                    } else {
                        i?
                    }
                }
            };
            t += next.step;
            step = next.step;
            fit = Some(next);
        }
        let fit = fit?;
        // Acceptance at the final centre.
        let c = p + t * v;
        let near = self.index.knn(&c.into(), FIT_POINTS);
        let nearest = near.first()?.1.sqrt();
        let (mut sw, mut mean, mut spread) = (0.0, nalgebra::Vector2::zeros(), 0.0);
        for &(i, d2) in &near {
            let q = self.point(i) - c;
            let w = (-d2 / (h * h)).exp();
            let xy = nalgebra::Vector2::new(q.dot(&frame.e1), q.dot(&frame.e2));
            sw += w;
            mean += w * xy;
            spread += w * xy.norm_squared();
        }
        let covered = sw > 0.0 && (mean / sw).norm() <= COVER * (spread / sw).sqrt();
        let settled = step.abs() <= SETTLED * s;
        let facing = fit.normal.dot(v).abs() >= GRAZING;
        (covered && settled && facing && nearest <= GAP * s && t.is_finite()).then_some((t, fit.normal))
    }
}

/// The frame (e1, e2, v) of a model normal and the quadric's length unit h.
struct Frame {
    e1: V3,
    e2: V3,
    v: V3,
    h: f64,
}

/// One quadric fit about a centre: the step along v to where the line meets it, mm; the unit
/// normal there; its largest principal curvature, 1/mm, and the direction of the smallest (along
/// an edge); the weighted mean squared algebraic residual.
struct Fit {
    step: f64,
    normal: V3,
    curvature: f64,
    along: V3,
    residual: f64,
}

/// Two unit tangents completing the unit normal `v` to a right-handed frame (e1, e2, v).
pub(super) fn tangent_frame(v: &V3) -> (V3, V3) {
    let a = if v.x.abs() < 0.9 { V3::x() } else { V3::y() };
    let e1 = v.cross(&a).normalize();
    (e1, v.cross(&e1))
}

impl Frame {
    fn new(v: V3, h: f64) -> Frame {
        let (e1, e2) = tangent_frame(&v);
        Frame { e1, e2, v, h }
    }

    fn terms(&self, q: &V3) -> (V9, f64) {
        let (x, y, z) = (q.dot(&self.e1) / self.h, q.dot(&self.e2) / self.h, q.dot(&self.v) / self.h);
        (V9::from([1.0, x, y, x * x, x * y, y * y, z * z, x * z, y * z]), z)
    }

    /// The weighted least-squares quadric through the points `q` (relative to the centre) and
    /// where the line x = y = 0 meets it; None where the points do not fix one or the line
    /// misses it.
    fn fit(&self, q: &[V3], weights: &[f64]) -> Option<Fit> {
        let (mut a, mut b, mut total) = (M9::zeros(), V9::zeros(), 0.0);
        for (qi, &w) in q.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            let (phi, z) = self.terms(qi);
            a += w * phi * phi.transpose();
            b -= w * z * phi;
            total += w;
        }
        if total <= 0.0 {
            return None;
        }
        let trace = a.trace();
        for j in 1..9 {
            a[(j, j)] += if j >= 6 { RIDGE } else { 1e-9 } * trace;
        }
        let chol = a.cholesky()?;
        // A pivot ratio below 1e-12 is a system no better determined than 1e12 condition.
        let l = chol.l();
        let (lo, hi) = (0..9).fold((f64::INFINITY, 0.0f64), |(lo, hi), i| (lo.min(l[(i, i)]), hi.max(l[(i, i)])));
        if !(lo > 0.0 && (lo / hi).powi(2) > 1e-12) {
            return None;
        }
        let c = chol.solve(&b);
        if !c.iter().all(|x| x.is_finite()) {
            return None;
        }
        // On the line: z + c0 + c6·z² = 0, the root that continues the tangent plane's −c0.
        let disc = 1.0 - 4.0 * c[6] * c[0];
        if disc < 0.0 {
            return None;
        }
        let dz = -2.0 * c[0] / (1.0 + disc.sqrt());
        let g = V3::new(c[1] + c[7] * dz, c[2] + c[8] * dz, 1.0 + 2.0 * c[6] * dz);
        let gn = g.norm();
        if !(gn > 0.0 && gn.is_finite()) {
            return None;
        }
        let n = g / gn;
        // Principal curvatures: the Hessian projected on the tangent plane, over |∇f|.
        let hess = Matrix3::new(2.0 * c[3], c[4], c[7], c[4], 2.0 * c[5], c[8], c[7], c[8], 2.0 * c[6]);
        let proj = Matrix3::identity() - n * n.transpose();
        let shape = SymmetricEigen::new(proj * hess * proj / gn);
        let tangent: Vec<usize> = (0..3).filter(|&k| shape.eigenvectors.column(k).dot(&n).abs() <= 0.5).collect();
        let (curvature, along) = match tangent[..] {
            [a, b] => {
                let (ka, kb) = (shape.eigenvalues[a].abs(), shape.eigenvalues[b].abs());
                let (big, small) = if ka >= kb { (ka, b) } else { (kb, a) };
                (big, shape.eigenvectors.column(small).into_owned())
            }
            _ => (0.0, V3::x()),
        };
        let to_world = |l: V3| l.x * self.e1 + l.y * self.e2 + l.z * self.v;
        let mut residual = 0.0;
        for (qi, &w) in q.iter().zip(weights) {
            let (phi, z) = self.terms(qi);
            residual += w * (z + phi.dot(&c)).powi(2);
        }
        Some(Fit {
            step: dz * self.h,
            normal: to_world(n),
            curvature: curvature / self.h,
            along: to_world(along).normalize(),
            residual: residual / total,
        })
    }
}

/// The blank's point spacing s: the median over up to 20,000 of its points of r₈·√(π/9), r₈ the
/// distance to the 8th other point (nine points in a disc of radius r₈ at a density of 1/s²). It
/// holds within 1 % through 30 % jitter, where the nearest-neighbour distance reads 0.77 s. A
/// scan of lines much farther apart than their points reads the spacing along the lines: give
/// `spacing` (about √(line gap × point spacing)).
pub fn point_spacing(points: &[[f64; 3]], index: &PointIndex) -> f64 {
    let step = points.len().div_ceil(SPACING_SAMPLES).max(1);
    let mut r: Vec<f64> =
        points.par_iter().step_by(step).filter_map(|p| index.knn(p, 9).get(8).map(|&(_, d2)| d2.sqrt())).collect();
    if r.is_empty() {
        return f64::NAN;
    }
    let mid = r.len() / 2;
    r.select_nth_unstable_by(mid, f64::total_cmp);
    r[mid] * (std::f64::consts::PI / 9.0).sqrt()
}

/// The signed allowance of each model point along its unit outward normal, mm: `t` with
/// `p + t·v` on the blank's local surface (module docs); NaN where the blank does not cover the
/// point.
pub fn allowance(
    model: &[[f64; 3]],
    normals: &[[f64; 3]],
    blank: &[[f64; 3]],
    options: &BlankOptions,
) -> Result<Vec<f64>> {
    check_finite_points("model_points", model)?;
    super::check_normals("model_normals", normals, model.len())?;
    let blank = Blank::new(blank, options)?;
    if options.surface == BlankSurface::Stock && !model.is_empty() {
        let shape = ModelShape::new(model, normals)?;
        let field = shape.field(blank.points(), blank.spacing())?;
        return Ok(model
            .par_iter()
            .zip(normals)
            .enumerate()
            .map(|(i, (p, v))| {
                let (p, v) = (V3::from(*p), V3::from(*v).normalize());
                // Where the model is sampled more coarsely than the blank, the blank's quadric.
                // And where the stock field has no measure (too few feet about p), the quadric's.
                let met = match &field {
                    Some(field) if !shape.coarser_than(i, blank.spacing()) => {
                        field.meet(&p, &v).or_else(|| blank.meet(&p, &v))
                    }
                    _ => blank.meet(&p, &v),
                };
                met.map_or(f64::NAN, |(t, _)| t)
            })
            .collect());
    }
    Ok(model
        .par_iter()
        .zip(normals)
        .map(|(p, v)| {
            let (p, v) = (V3::from(*p), V3::from(*v).normalize());
            blank.meet(&p, &v).map_or(f64::NAN, |(t, _)| t)
        })
        .collect())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// `n` points on a sphere of radius `r` (Fibonacci lattice) and their outward normals.
    pub(crate) fn sphere(n: usize, r: f64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let (s, a) = ((1.0 - z * z).sqrt(), golden * i as f64);
                let u = [s * a.cos(), s * a.sin(), z];
                (u.map(|c| r * c), u)
            })
            .unzip()
    }

    fn plane(k: usize) -> BlankOptions {
        BlankOptions { surface: BlankSurface::Plane, k: Some(k), spacing: None }
    }

    #[test]
    fn allowance_between_concentric_spheres_is_the_radius_difference() {
        // The blank sampled at about 0.2 mm: 4π R² / 0.04 points. The plane sits below a curved
        // blank by the mean sag of its points (~1.2 µm at R 20); the quadric follows it.
        for (r, options, tolerance) in
            [(20.0, plane(8), 0.003), (20.0, BlankOptions::default(), 0.0005), (5.0, BlankOptions::default(), 0.0005)]
        {
            let (model, normals) = sphere(2000, r);
            for delta in [0.5, -0.2] {
                let radius = r + delta;
                let n = (4.0 * std::f64::consts::PI * radius * radius / 0.04) as usize;
                let (blank, _) = sphere(n, radius);
                let a = allowance(&model, &normals, &blank, &options).unwrap();
                let worst = a.iter().map(|t| (t - delta).abs()).fold(0.0, f64::max);
                assert!(worst < tolerance, "{options:?} r {r} δ {delta}: worst error {worst}");
            }
        }
    }

    /// A cylinder of radius 1.5 spacings: the blank's points turn by 90° over two spacings, and
    /// the quadric still meets it within a few µm; the plane does not.
    #[test]
    fn a_thin_edge_is_followed() {
        let (s, radius, offset) = (0.5, 0.75, 0.3);
        let ring = |r: f64, phase: f64, step: f64| -> Vec<[f64; 3]> {
            let n = (2.0 * std::f64::consts::PI * r / step).round() as usize;
            (0..n)
                .flat_map(|i| {
                    let a = (i as f64 + phase) * 2.0 * std::f64::consts::PI / n as f64;
                    (0..40).map(move |j| [r * a.cos(), r * a.sin(), (j as f64 + phase) * step - 10.0])
                })
                .collect()
        };
        let blank = ring(radius + offset, 0.37, s);
        let model: Vec<[f64; 3]> = ring(radius, 0.0, 0.2).into_iter().filter(|p| p[2].abs() < 4.0).collect();
        let normals: Vec<[f64; 3]> = model.iter().map(|p| V3::new(p[0], p[1], 0.0).normalize().into()).collect();
        let a = allowance(&model, &normals, &blank, &BlankOptions::default()).unwrap();
        let worst = a.iter().map(|t| (t - offset).abs()).fold(0.0, f64::max);
        assert!(worst < 0.005, "quadric: worst error {worst}");
        let flat = allowance(&model, &normals, &blank, &plane(8)).unwrap();
        let worst_plane = flat.iter().filter(|t| t.is_finite()).map(|t| (t - offset).abs()).fold(0.0, f64::max);
        assert!(worst_plane > 0.05, "the plane cannot follow it: {worst_plane}");
    }

    #[test]
    fn beyond_the_blank_and_over_a_hole_there_is_no_allowance() {
        // A flat blank over [−10, 10]², 0.5 mm apart, with a 3 mm hole at the origin; model
        // points on a line across it and past its end.
        let blank: Vec<[f64; 3]> = (0..41 * 41)
            .map(|i| [(i % 41) as f64 * 0.5 - 10.0, (i / 41) as f64 * 0.5 - 10.0, 0.2])
            .filter(|p| p[0].hypot(p[1]) > 1.5)
            .collect();
        let model: Vec<[f64; 3]> = (0..60).map(|i| [i as f64 * 0.25 - 2.0, 0.05, 0.0]).collect();
        let a = allowance(&model, &vec![[0.0, 0.0, 1.0]; 60], &blank, &BlankOptions::default()).unwrap();
        for (p, t) in model.iter().zip(&a) {
            let inside = p[0] < 9.5 && p[0].hypot(p[1]) > 2.3;
            if inside {
                assert!((t - 0.2).abs() < 1e-9, "{p:?}: {t}");
            }
            if p[0] > 10.5 || p[0].hypot(p[1]) < 0.7 {
                assert!(t.is_nan(), "{p:?}: {t} where the blank has no surface");
            }
        }
    }

    #[test]
    fn a_scan_of_lines_needs_its_spacing_and_a_grazing_surface_is_nan() {
        // A blank of scan lines 2 mm apart, 0.1 mm along each: the plane takes the next line's
        // points with k = 30; the quadric works at the spacing √(0.1 · 2) given.
        let blank: Vec<[f64; 3]> =
            (0..4000).map(|i| [(i % 200) as f64 * 0.1 - 10.0, (i / 200) as f64 * 2.0 - 20.0, 0.3]).collect();
        let model = [[0.0, 1.0, 0.0], [0.3, -3.0, 0.0]];
        let lines = BlankOptions { spacing: Some((0.1f64 * 2.0).sqrt() * 2.0), ..BlankOptions::default() };
        for options in [plane(30), lines] {
            let a = allowance(&model, &[[0.0, 0.0, 1.0]; 2], &blank, &options).unwrap();
            assert!(a.iter().all(|t| (t - 0.3).abs() < 1e-9), "{options:?}: {a:?}");
            let grazing = allowance(&model, &[[1.0, 0.0, 0.2]; 2], &blank, &options).unwrap();
            assert!(grazing.iter().all(|t| t.is_nan()), "{options:?}: {grazing:?}");
        }
    }

    #[test]
    fn bad_input_is_refused_by_name() {
        let (model, normals) = sphere(10, 1.0);
        let err = |n: &[[f64; 3]], o: BlankOptions| allowance(&model, n, &model, &o).unwrap_err().to_string();
        assert!(err(&normals, plane(2)).contains("k"));
        assert!(err(&normals, plane(11)).contains("k"));
        assert!(err(&normals, BlankOptions { k: Some(8), ..BlankOptions::default() }).contains("k"));
        assert!(err(&normals, BlankOptions { spacing: Some(-1.0), ..BlankOptions::default() }).contains("spacing"));
        assert!(err(&normals, BlankOptions::default()).contains("blank_points"));
        assert!(err(&normals[..5], plane(8)).contains("model_normals"));
        let mut zero = normals.clone();
        zero[3] = [0.0; 3];
        assert!(err(&zero, plane(8)).contains("model_normals"));
        assert!(BlankSurface::parse("cubic").unwrap_err().to_string().contains("surface"));
    }
}
