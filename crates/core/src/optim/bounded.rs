//! Levenberg–Marquardt with box constraints, for the groove section models: Marquardt's
//! scaling (the parameters mix millimetres, cotangents and fractions), Nielsen's damping
//! update, a projection after every step and an active set (a parameter on its bound whose
//! step points outward is held, and the step re-solved without it: without that, a fit crawls
//! along a bound for tens of iterations).
//!
//! Stop tests, any of: an accepted step lowers the cost by less than `cost_tolerance`
//! relative; it lowers it by less than 1e-3 relative and the problem says the outputs no
//! longer move (`outputs_settled`); no parameter moves more than `step_tolerance`; the
//! gradient's largest entry is at most `gradient_tolerance`; the damping exceeds 1e12 (no
//! descent left).
use super::LeastSquares;
use nalgebra::{SMatrix, SVector};

/// A least-squares problem over a box.
pub trait BoundedLeastSquares<const P: usize>: LeastSquares<P> {
    /// Moves `x` into the admissible set.
    fn project(&self, x: &mut SVector<f64, P>);
    /// `(lower, upper)` bounds at `x`, for the active set.
    fn bounds(&self, x: &SVector<f64, P>) -> (SVector<f64, P>, SVector<f64, P>);
    /// Whether the step from `a` to `b` moved none of the quantities the fit is for.
    fn outputs_settled(&self, _a: &SVector<f64, P>, _b: &SVector<f64, P>) -> bool {
        false
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundedLmOptions {
    pub max_iterations: usize,
    /// Relative cost decrease of an accepted step below which the fit has converged.
    pub cost_tolerance: f64,
    /// Largest parameter move below which the fit has converged.
    pub step_tolerance: f64,
    /// `‖∇ cost‖∞` below which the fit has converged (0: off).
    pub gradient_tolerance: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct BoundedLmResult<const P: usize> {
    pub x: SVector<f64, P>,
    /// `½ Σ f²` at `x`.
    pub cost: f64,
    pub iterations: usize,
    pub converged: bool,
    /// JᵀJ at `x`, for the covariance.
    pub jtj: SMatrix<f64, P, P>,
}

/// Solves `(A + μ diag) h = −g` with the `active` parameters held at 0.
fn step<const P: usize>(
    a: &SMatrix<f64, P, P>,
    scale: &SVector<f64, P>,
    mu: f64,
    g: &SVector<f64, P>,
    active: &[bool; P],
) -> Option<SVector<f64, P>> {
    let mut m = *a;
    let mut rhs = -g;
    for i in 0..P {
        m[(i, i)] += mu * scale[i];
        if active[i] {
            for j in 0..P {
                m[(i, j)] = 0.0;
                m[(j, i)] = 0.0;
            }
            m[(i, i)] = 1.0;
            rhs[i] = 0.0;
        }
    }
    m.cholesky().map(|c| c.solve(&rhs))
}

#[inline(always)]
pub fn bounded_levenberg_marquardt<const P: usize, Prob: BoundedLeastSquares<P>>(
    problem: &Prob,
    x0: SVector<f64, P>,
    options: &BoundedLmOptions,
) -> BoundedLmResult<P> {
    let mut x = x0;
    problem.project(&mut x);
    let (mut a, mut g, mut cost) = problem.normal_equations(&x);
    if !cost.is_finite() {
        return BoundedLmResult { x, cost, iterations: 0, converged: false, jtj: a };
    }
    let (mut mu, mut nu) = (1e-3, 2.0);
    let mut converged = false;
    let mut iterations = 0;
    while iterations < options.max_iterations {
        iterations += 1;
        if g.amax() <= options.gradient_tolerance {
            converged = true;
            break;
        }
        let max_diag = (0..P).map(|i| a[(i, i)]).fold(1e-30, f64::max);
        let scale = SVector::<f64, P>::from_fn(|i, _| a[(i, i)].max(1e-12 * max_diag));
        let Some(mut h) = step(&a, &scale, mu, &g, &[false; P]) else {
            mu *= nu;
            nu *= 2.0;
            continue;
        };
        let (lo, hi) = problem.bounds(&x);
        let mut active = [false; P];
        for i in 0..P {
            active[i] = (x[i] <= lo[i] + 1e-12 && h[i] < 0.0) || (x[i] >= hi[i] - 1e-12 && h[i] > 0.0);
        }
        if active.iter().any(|&b| b) {
            match step(&a, &scale, mu, &g, &active) {
                Some(s) => h = s,
                None => {
                    mu *= nu;
                    nu *= 2.0;
                    continue;
                }
            }
        }
        let mut x_new = x + h;
        problem.project(&mut x_new);
        let hq = x_new - x;
        if hq.amax() <= options.step_tolerance {
            converged = true;
            break;
        }
        let trial = problem.normal_equations(&x_new);
        let cost_new = trial.2;
        // The gain ratio of the projected step.
        let predicted = -g.dot(&hq) - 0.5 * hq.dot(&(a * hq));
        let rho = if cost_new.is_finite() && predicted > 0.0 { (cost - cost_new) / predicted } else { -1.0 };
        if rho > 0.0 {
            let drop = cost - cost_new;
            let mut settled = drop <= options.cost_tolerance * cost + 1e-16;
            if !settled && drop <= 1e-3 * cost {
                settled = problem.outputs_settled(&x, &x_new);
            }
            x = x_new;
            (a, g, cost) = trial;
            mu *= f64::max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0).powi(3));
            nu = 2.0;
            if settled {
                converged = true;
                break;
            }
        } else {
            mu *= nu;
            nu *= 2.0;
            if mu > 1e12 {
                converged = true;
                break;
            }
        }
    }
    BoundedLmResult { x, cost, iterations, converged, jtj: a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    /// Distance to the point (2, 3) with x held in [−1, 1]: the answer is (1, 3) on the bound.
    struct Boxed;
    impl LeastSquares<2> for Boxed {
        fn len(&self) -> usize {
            2
        }
        fn normal_equations(&self, p: &Vector2<f64>) -> (Matrix2<f64>, Vector2<f64>, f64) {
            let f = Vector2::new(p[0] - 2.0, p[1] - 3.0);
            (Matrix2::identity(), f, 0.5 * f.norm_squared())
        }
    }
    impl BoundedLeastSquares<2> for Boxed {
        fn project(&self, x: &mut Vector2<f64>) {
            x[0] = x[0].clamp(-1.0, 1.0);
        }
        fn bounds(&self, _: &Vector2<f64>) -> (Vector2<f64>, Vector2<f64>) {
            (Vector2::new(-1.0, f64::NEG_INFINITY), Vector2::new(1.0, f64::INFINITY))
        }
    }

    #[test]
    fn ends_on_the_bound_with_the_free_parameter_solved() {
        let o = BoundedLmOptions {
            max_iterations: 50,
            cost_tolerance: 1e-12,
            step_tolerance: 1e-12,
            gradient_tolerance: 0.0,
        };
        let r = bounded_levenberg_marquardt(&Boxed, Vector2::new(0.0, 0.0), &o);
        assert!(r.converged);
        assert!((r.x - Vector2::new(1.0, 3.0)).amax() < 1e-9, "{}", r.x);
    }
}
