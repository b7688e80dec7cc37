//! Envelope-constrained alignment (SPEC R8; paper 004, "datum alignment and contour
//! inclusion"): where to hold the blank so that it envelops the part with at least a minimum
//! stock everywhere, and beyond that with stock as even as possible — the balanced best fit of
//! adaptive-machining systems. Where that is not feasible, the pose that comes closest: the
//! smallest stock as large as it can be.
//!
//! Written here rather than with a solver crate because the problem is small in its unknowns
//! (six) and large in its constraints (one per model point), and the allowance is exact only
//! through the allowance kernel. So: a sequence of linearised problems (the allowance is linear
//! in a small motion of the blank), each a quadratic programme in 7 unknowns solved by a
//! log-barrier interior point method; each step is checked against the exact allowance and
//! shrunk by a trust region when it does not keep what the linearisation promised (SQP with an
//! exact L∞ penalty).
use super::allowance::{Blank, BlankOptions, BlankSurface};
use super::stock::ModelShape;
use super::twist;
use crate::error::{check_finite_points, Error, Result};
use crate::geom::{transform_point, transform_vector};
use nalgebra::{Matrix4, SMatrix, SVector, Vector3};
use rayon::prelude::*;

type Vector7 = SVector<f64, 7>;
type Matrix7 = SMatrix<f64, 7, 7>;

/// Stock below the minimum by less than this still counts as holding it, mm (rounding).
pub const FEASIBILITY: f64 = 1e-9;

/// Price of a millimetre of stock missing below the minimum, in mm² of allowance variance: far
/// above any multiplier of the constraint (about twice the allowance spread), so the penalty is
/// exact — the fit never trades missing stock for evenness.
const PENALTY: f64 = 1e3;

/// How far (mm) the blank may move relative to a model point from where it last covered it
/// while the point's allowance is extrapolated from there: a few spacings of a blank's points,
/// over which the allowance is close to linear in the motion; beyond it the blank would be
/// moved off the point, not past its edge by a hair.
const UNCOVERED_REACH: f64 = 2.0;

/// Outer (linearise, solve, check) iterations at most.
const MAX_ITERATIONS: usize = 200;

/// First trust region: the largest move of the blank per step, mm (rotations times the model's
/// radius of gyration), and the largest it may grow to.
const FIRST_REGION: f64 = 1.0;
const LARGEST_REGION: f64 = 16.0;

/// The fit has converged when a step moves the blank by less than this, mm: below what the
/// allowance resolves, as its local surfaces jump by tens of nm where their neighbourhoods
/// change, so that smaller steps only chase those jumps.
const STEP: f64 = 1e-6;

/// The pose found by [`envelope_fit`].
#[derive(Debug, Clone)]
pub struct EnvelopeFit {
    /// Applied to the blank: blank → model frame.
    pub transformation: Matrix4<f64>,
    /// Allowance of each model point at `transformation`, mm (NaN where the blank does not cover
    /// the point).
    pub allowance: Vec<f64>,
    /// Every allowance is ≥ `min_allowance` (within [`FEASIBILITY`]), counting a point the blank
    /// no longer covers by the allowance its last measurement extrapolates to.
    pub feasible: bool,
    pub iterations: usize,
    /// The last step was below [`STEP`]: the pose is a local optimum.
    pub converged: bool,
}

/// The allowance at a pose of the blank, and its derivative in a small motion of the blank.
struct Evaluation {
    allowance: Vec<f64>,
    /// `(index, a, ∂a/∂ξ)` of the points with an allowance; ξ = (ω·scale, τ).
    rows: Vec<(usize, f64, SVector<f64, 6>)>,
    variance: f64,
    smallest: f64,
}

impl Evaluation {
    /// The evaluation of `rows` (and the allowance of every point, NaN where uncovered).
    fn of(allowance: Vec<f64>, rows: Vec<(usize, f64, SVector<f64, 6>)>) -> Evaluation {
        let m = rows.len().max(1) as f64;
        let mean = rows.iter().map(|r| r.1).sum::<f64>() / m;
        let variance = rows.iter().map(|r| (r.1 - mean).powi(2)).sum::<f64>() / m;
        let smallest = rows.iter().map(|r| r.1).fold(f64::INFINITY, f64::min);
        Evaluation { allowance, rows, variance, smallest }
    }

    /// The L∞ merit: the variance, plus the penalty on the deepest shortfall.
    fn merit(&self, min_allowance: f64) -> f64 {
        self.variance + PENALTY * (min_allowance - self.smallest).max(0.0)
    }
}

/// What the fit works with: the model, the blank and its index, and the frame of the motions.
struct Problem<'a> {
    model: &'a [[f64; 3]],
    normals: Vec<Vector3<f64>>,
    blank: Blank<'a>,
    /// The model's shapes, for the stock field (`BlankSurface::Stock`).
    shape: Option<ModelShape>,
    centre: Vector3<f64>,
    scale: f64,
}

impl Problem<'_> {
    /// The blank is at `pose` (blank → model frame). The model point is taken into the blank's
    /// frame, where the index is; the blank's local surface found there is taken back, and
    /// moving it by a small motion (ω about the centre, τ) moves the point where the normal
    /// meets it by `ω × (x − c) + τ`, which changes the allowance by that along the surface
    /// normal there over `n·v`.
    fn evaluate(&self, pose: &Matrix4<f64>) -> Result<Evaluation> {
        let inverse = pose.try_inverse().ok_or_else(|| Error::invalid("init", "is not invertible"))?;
        // The blank's surface where each model normal meets it, in the model's frame: the stock
        // field of the blank moved to the model (where the model is sampled as finely as the
        // blank), or the blank's own local surface met by the model taken into the blank's frame.
        let in_blank = |p: &[f64; 3], v: &Vector3<f64>| {
            let pb = Vector3::from(transform_point(&inverse, *p));
            let vb = Vector3::from(transform_vector(&inverse, [v[0], v[1], v[2]]));
            let (a, n) = self.blank.meet(&pb, &vb.normalize())?;
            Some((a, Vector3::from(transform_vector(pose, [n[0], n[1], n[2]]))))
        };
        let met: Vec<Option<(f64, Vector3<f64>)>> = match &self.shape {
            Some(shape) => {
                let moved: Vec<[f64; 3]> = self.blank.points().iter().map(|&b| transform_point(pose, b)).collect();
                let spacing = self.blank.spacing();
                let field = shape.field(&moved, spacing)?;
                self.model
                    .par_iter()
                    .zip(&self.normals)
                    .enumerate()
                    .map(|(i, (p, v))| match &field {
                        Some(field) if !shape.coarser_than(i, spacing) => {
                            field.meet(&Vector3::from(*p), v).or_else(|| in_blank(p, v))
                        }
                        _ => in_blank(p, v),
                    })
                    .collect()
            }
            None => self.model.par_iter().zip(&self.normals).map(|(p, v)| in_blank(p, v)).collect(),
        };
        let local: Vec<(f64, Option<SVector<f64, 6>>)> = self
            .model
            .iter()
            .zip(&self.normals)
            .zip(met)
            .map(|((p, v), met)| {
                let Some((a, n)) = met else {
                    return (f64::NAN, None);
                };
                let nv = n.dot(v);
                let x = Vector3::from(*p) + a * v;
                let r = (x - self.centre).cross(&n) / (nv * self.scale);
                let t = n / nv;
                (a, Some(SVector::<f64, 6>::new(r[0], r[1], r[2], t[0], t[1], t[2])))
            })
            .collect();
        let rows: Vec<(usize, f64, SVector<f64, 6>)> =
            local.iter().enumerate().filter_map(|(i, &(a, j))| j.map(|j| (i, a, j))).collect();
        if rows.is_empty() {
            return Err(Error::invalid(
                "blank_points",
                "no model normal meets the blank's surface: is the blank in the model's frame?",
            ));
        }
        Ok(Evaluation::of(local.into_iter().map(|l| l.0).collect(), rows))
    }

    /// The small motion ξ = (ω·scale, τ) that takes the blank from pose `from` to pose `to`.
    fn motion(&self, from: &Matrix4<f64>, to: &Matrix4<f64>) -> SVector<f64, 6> {
        let relative = to * from.try_inverse().unwrap_or_else(Matrix4::identity);
        let r = nalgebra::Rotation3::from_matrix(&relative.fixed_view::<3, 3>(0, 0).into_owned());
        let omega = r.scaled_axis() * self.scale;
        let tau = Vector3::from(transform_point(&relative, self.centre.into())) - self.centre;
        SVector::<f64, 6>::new(omega[0], omega[1], omega[2], tau[0], tau[1], tau[2])
    }
}

/// Where each model point was last measured: its allowance, derivative and the blank's pose.
type Measured = Vec<Option<(f64, SVector<f64, 6>, Matrix4<f64>)>>;

/// `ev` with every point measured before but uncovered at `pose` counted by the allowance its
/// last measurement extrapolates to: a fit cannot escape the constraint by uncovering a point
/// (moving the blank off it, or turning its surface away), and a point at the blank's end,
/// covered or not by a hair, neither freezes the fit nor drops out of it. The extrapolation is
/// linear, so it holds only near where the point was measured: a pose that moves an uncovered
/// point more than [`UNCOVERED_REACH`] from there is out of bounds (the second value).
fn with_measured(problem: &Problem, ev: Evaluation, pose: &Matrix4<f64>, measured: &Measured) -> (Evaluation, bool) {
    let mut rows = ev.rows;
    let mut beyond = false;
    for (i, m) in measured.iter().enumerate() {
        if let (true, Some((a, j, at))) = (ev.allowance[i].is_nan(), m) {
            rows.push((i, a + j.dot(&problem.motion(at, pose)), *j));
            let p = problem.model[i];
            let relative = at * pose.try_inverse().unwrap_or_else(Matrix4::identity);
            let shift = Vector3::from(transform_point(&relative, p)) - Vector3::from(p);
            beyond |= shift.norm() > UNCOVERED_REACH;
        }
    }
    (Evaluation::of(ev.allowance, rows), beyond)
}

/// Records where the points measured at `pose` stand.
fn remember(measured: &mut Measured, ev: &Evaluation, pose: &Matrix4<f64>) {
    for &(i, a, j) in &ev.rows {
        if ev.allowance[i].is_finite() {
            measured[i] = Some((a, j, *pose));
        }
    }
}

/// The blank pose (blank → model frame) that holds every allowance ≥ `min_allowance` when that
/// is feasible and, among those poses, makes the allowance as even as possible (least
/// variance); when it is not feasible, the pose of the largest smallest allowance. Starts at
/// `init` (e.g. an ICP of the blank to the model) and finds the nearest such optimum.
pub fn envelope_fit(
    model: &[[f64; 3]],
    normals: &[[f64; 3]],
    blank: &[[f64; 3]],
    min_allowance: f64,
    options: &BlankOptions,
    init: &Matrix4<f64>,
) -> Result<EnvelopeFit> {
    check_finite_points("model_points", model)?;
    super::check_normals("model_normals", normals, model.len())?;
    let blank = Blank::new(blank, options)?;
    if !min_allowance.is_finite() {
        return Err(Error::invalid("min_allowance", format!("must be finite, got {min_allowance}")));
    }
    if model.is_empty() {
        return Err(Error::invalid("model_points", "must hold at least one point"));
    }
    let (centre, scale) = super::spread(model);
    let shape = (blank.surface() == BlankSurface::Stock).then(|| ModelShape::new(model, normals)).transpose()?;
    let problem = Problem {
        model,
        normals: normals.iter().map(|v| Vector3::from(*v).normalize()).collect(),
        blank,
        shape,
        centre,
        scale,
    };
    let mut pose = *init;
    let mut here = problem.evaluate(&pose)?;
    let mut measured: Measured = vec![None; model.len()];
    remember(&mut measured, &here, &pose);
    let mut region = FIRST_REGION;
    let (mut iterations, mut converged) = (0, false);
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let (xi, predicted) = step(&here, min_allowance, region);
        let size = xi.amax();
        if size < STEP || predicted <= 1e-16 * here.merit(min_allowance).abs().max(1e-12) {
            converged = true;
            break;
        }
        let trial_pose =
            twist(&(Vector3::new(xi[0], xi[1], xi[2]) / scale), &Vector3::new(xi[3], xi[4], xi[5]), &centre) * pose;
        let (trial, beyond) = with_measured(&problem, problem.evaluate(&trial_pose)?, &trial_pose, &measured);
        let actual = if beyond { f64::NEG_INFINITY } else { here.merit(min_allowance) - trial.merit(min_allowance) };
        let ratio = actual / predicted;
        if ratio > 1e-4 {
            remember(&mut measured, &trial, &trial_pose);
            (pose, here) = (trial_pose, trial);
        }
        if ratio < 0.25 {
            region = size / 4.0;
        } else if ratio > 0.75 && size > 0.9 * region {
            region = (2.0 * region).min(LARGEST_REGION);
        }
        if region < STEP {
            converged = true;
            break;
        }
    }
    Ok(EnvelopeFit {
        transformation: pose,
        feasible: here.smallest >= min_allowance - FEASIBILITY,
        allowance: here.allowance,
        iterations,
        converged,
    })
}

/// The linearised problem: minimise the variance of `a + J ξ` plus the penalty on `s`, the
/// shortfall below the minimum (`a_i + J_i ξ + s ≥ min`, `s ≥ 0`), with the move bounded by the
/// trust region (`|ξ_j| ≤ region`). Returns ξ and the merit reduction the linearisation
/// predicts for it.
fn step(here: &Evaluation, min_allowance: f64, region: f64) -> (SVector<f64, 6>, f64) {
    let m = here.rows.len() as f64;
    let mean_a = here.rows.iter().map(|r| r.1).sum::<f64>() / m;
    let mean_j = here.rows.iter().fold(SVector::<f64, 6>::zeros(), |s, r| s + r.2) / m;
    // Variance of a + Jξ = ½ ξᵀ H ξ + gᵀ ξ + const.
    let (h, g) = here.rows.iter().fold((SMatrix::<f64, 6, 6>::zeros(), SVector::<f64, 6>::zeros()), |(h, g), r| {
        let (da, dj) = (r.1 - mean_a, r.2 - mean_j);
        (h + dj * dj.transpose() * (2.0 / m), g + dj * (2.0 * da / m))
    });
    let mut q = Matrix7::zeros();
    q.fixed_view_mut::<6, 6>(0, 0).copy_from(&h);
    let mut c = Vector7::zeros();
    c.fixed_rows_mut::<6>(0).copy_from(&g);
    c[6] = PENALTY;
    // Constraints b + A·y ≥ 0. A point whose stock stays above the minimum anywhere in the
    // trust region can never bind: left out, it changes the barrier's path, not its end.
    let mut rows: Vec<(f64, Vector7)> = here
        .rows
        .iter()
        .filter(|r| r.1 - min_allowance <= r.2.lp_norm(1) * region)
        .map(|r| {
            let mut a = Vector7::zeros();
            a.fixed_rows_mut::<6>(0).copy_from(&r.2);
            a[6] = 1.0;
            (r.1 - min_allowance, a)
        })
        .collect();
    for j in 0..7 {
        let mut a = Vector7::zeros();
        a[j] = 1.0;
        if j < 6 {
            rows.push((region, a));
            rows.push((region, -a));
        } else {
            rows.push((0.0, a));
        }
    }
    let shortfall = (min_allowance - here.smallest).max(0.0);
    let mut y0 = Vector7::zeros();
    y0[6] = shortfall + region;
    let y = barrier(&q, &c, &rows, y0, here.merit(min_allowance));
    let xi = y.fixed_rows::<6>(0).into_owned();
    // The predicted merit: variance of the linear model, plus the penalty on its shortfall.
    let lin_smallest = here.rows.iter().map(|r| r.1 + r.2.dot(&xi)).fold(f64::INFINITY, f64::min);
    let lin_merit =
        here.variance + (0.5 * xi.dot(&(h * xi)) + g.dot(&xi)) + PENALTY * (min_allowance - lin_smallest).max(0.0);
    (xi, here.merit(min_allowance) - lin_merit)
}

/// Minimise `½ yᵀ Q y + cᵀ y` subject to `b_i + A_i·y > 0`, from a strictly feasible `y`, by
/// following the central path of `τ f − Σ log(b_i + A_i·y)` with Newton steps, from a duality
/// gap (constraints / τ) of `size` (the merit now) down to `GAP` of it.
fn barrier(q: &Matrix7, c: &Vector7, rows: &[(f64, Vector7)], mut y: Vector7, size: f64) -> Vector7 {
    /// The final duality gap as a share of the merit, and the growth of τ per centring.
    const GAP: f64 = 1e-10;
    const GROWTH: f64 = 20.0;
    let constraints = rows.len() as f64;
    let phi = |y: &Vector7, tau: f64| {
        let mut barrier = 0.0;
        for (b, a) in rows {
            let s = b + a.dot(y);
            if s <= 0.0 {
                return f64::INFINITY;
            }
            barrier -= s.ln();
        }
        tau * (0.5 * y.dot(&(q * y)) + c.dot(y)) + barrier
    };
    let size = size.max(1e-12);
    let mut tau = constraints / size;
    while constraints / tau > GAP * size {
        tau *= GROWTH;
        for _ in 0..50 {
            let mut grad = tau * (q * y + c);
            let mut hess = tau * q;
            for (b, a) in rows {
                let s = b + a.dot(&y);
                grad -= a / s;
                hess += a * a.transpose() / (s * s);
            }
            let Some(chol) = hess.cholesky() else { break };
            let dy = chol.solve(&-grad);
            let decrement = -grad.dot(&dy);
            // Centred: the Newton decrement bounds how far φ is above its minimum.
            if !decrement.is_finite() || decrement < 1e-9 {
                break;
            }
            // The largest step that keeps every slack positive, then backtracking (Armijo).
            let mut alpha: f64 = 1.0;
            for (b, a) in rows {
                let da = a.dot(&dy);
                if da < 0.0 {
                    alpha = alpha.min(-0.99 * (b + a.dot(&y)) / da);
                }
            }
            let f0 = phi(&y, tau);
            while alpha > 1e-12 && phi(&(y + alpha * dy), tau) > f0 - 0.25 * alpha * decrement {
                alpha *= 0.5;
            }
            if alpha <= 1e-12 {
                break;
            }
            y += alpha * dy;
        }
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mount_rotation;
    use crate::registration::allowance::tests::sphere;

    fn moved(t: &Matrix4<f64>, points: &[[f64; 3]]) -> Vec<[f64; 3]> {
        points.iter().map(|p| transform_point(t, *p)).collect()
    }

    /// Where the blank's centre ends up and the allowance of the blank put back concentric.
    fn centred(blank: &[[f64; 3]], model: &[[f64; 3]], normals: &[[f64; 3]]) -> Vec<f64> {
        crate::registration::allowance(model, normals, blank, &BlankOptions::default()).unwrap()
    }

    #[test]
    fn a_displaced_concentric_blank_is_centred_to_even_stock() {
        // A blank sphere 0.5 mm larger, shifted 0.3 mm and turned: the balanced fit puts it back
        // concentric (a turn of a sphere changes nothing): the blank's centre returns to the
        // model's, and the stock is what the concentric blank leaves.
        let (model, normals) = sphere(1000, 20.0);
        let (blank, _) = sphere(20000, 20.5);
        let mut displaced = Matrix4::identity();
        displaced.fixed_view_mut::<3, 3>(0, 0).copy_from(&mount_rotation(0.01, 0.02, -0.01));
        displaced.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::new(0.3, -0.1, 0.2));
        let fit = envelope_fit(
            &model,
            &normals,
            &moved(&displaced, &blank),
            0.0,
            &BlankOptions::default(),
            &Matrix4::identity(),
        )
        .unwrap();
        assert!(fit.feasible && fit.converged, "{fit:?}");
        let centre = Vector3::from(transform_point(&(fit.transformation * displaced), [0.0; 3]));
        assert!(centre.norm() < 1e-3, "centre {centre}");
        let expected = centred(&blank, &model, &normals);
        let spread = |a: &[f64]| {
            a.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v)) - a.iter().fold(f64::INFINITY, |m, v| m.min(*v))
        };
        assert!(spread(&fit.allowance) <= spread(&expected) + 1e-3, "{} {}", spread(&fit.allowance), spread(&expected));
    }

    #[test]
    fn an_infeasible_minimum_gives_the_largest_smallest_stock() {
        // Concentric spheres with 0.5 mm of stock cannot hold 0.6 mm: the best is the
        // concentric pose's smallest stock.
        let (model, normals) = sphere(1000, 20.0);
        let (blank, _) = sphere(20000, 20.5);
        let mut shifted = Matrix4::identity();
        shifted[(0, 3)] = 0.2;
        let fit = envelope_fit(
            &model,
            &normals,
            &moved(&shifted, &blank),
            0.6,
            &BlankOptions::default(),
            &Matrix4::identity(),
        )
        .unwrap();
        assert!(!fit.feasible);
        let smallest = |a: &[f64]| a.iter().copied().fold(f64::INFINITY, f64::min);
        let best = smallest(&centred(&blank, &model, &normals));
        assert!(smallest(&fit.allowance) > best - 1e-4, "{} {best}", smallest(&fit.allowance));
    }

    /// A blank that ends where the part ends (a scan cut at the same height): sliding it along
    /// the axis uncovers the end rows by a hair, and the fit must not freeze on them.
    #[test]
    fn a_blank_ending_where_the_part_ends_is_still_centred() {
        let ring = |r: f64, step: f64, phase: f64, lo: f64, hi: f64| -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
            let n = (2.0 * std::f64::consts::PI * r / step).round() as usize;
            let rows = ((hi - lo) / step).round() as usize + 1;
            (0..n)
                .flat_map(|i| (0..rows).map(move |j| (i, j)))
                .map(|(i, j)| {
                    let a = (i as f64 + phase) * 2.0 * std::f64::consts::PI / n as f64;
                    let z = (lo + j as f64 * step).min(hi);
                    ([r * a.cos(), r * a.sin(), z], [a.cos(), a.sin(), 0.0])
                })
                .unzip()
        };
        let (model, normals) = ring(5.0, 0.6, 0.0, 0.0, 8.0);
        let (blank, _) = ring(5.3, 0.3, 0.37, 0.0, 8.0);
        let mut clamped = Matrix4::identity();
        clamped.fixed_view_mut::<3, 3>(0, 0).copy_from(&mount_rotation(0.01, -0.01, 0.0));
        clamped.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::new(0.15, -0.1, 0.2));
        let blank = moved(&clamped, &blank);
        let fit = envelope_fit(&model, &normals, &blank, 0.1, &BlankOptions::default(), &Matrix4::identity()).unwrap();
        let a: Vec<f64> = fit.allowance.iter().copied().filter(|a| a.is_finite()).collect();
        let mean = a.iter().sum::<f64>() / a.len() as f64;
        let std = (a.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
        assert!(fit.feasible && std < 0.002 && (mean - 0.3).abs() < 0.002, "std {std}, mean {mean}: {fit:?}");
        assert!(a.len() * 10 > fit.allowance.len() * 9, "{} of {} covered", a.len(), fit.allowance.len());
    }

    #[test]
    fn bad_input_is_refused_by_name() {
        let (model, normals) = sphere(50, 1.0);
        let e = |m: f64, k| {
            let options = BlankOptions { surface: super::super::BlankSurface::Plane, k: Some(k), spacing: None };
            envelope_fit(&model, &normals, &model, m, &options, &Matrix4::identity()).unwrap_err()
        };
        assert!(e(f64::NAN, 8).to_string().contains("min_allowance"));
        assert!(e(0.0, 2).to_string().contains("k"));
    }
}
