//! Levenberg–Marquardt with Nielsen's damping update (paper 000 eq 14–19, Madsen–Nielsen–
//! Tingleff 2004), for small fixed-size problems: the parameter count is a const generic, the
//! normal equations live on the stack, and the problem accumulates JᵀJ and Jᵀf itself so no
//! Jacobian matrix is ever stored (a groove frame has ~200 residuals, a calibration thousands).
//! The formulas: docs/grooves.md ("The optimiser").
use nalgebra::{SMatrix, SVector};

mod bounded;
pub use bounded::{bounded_levenberg_marquardt, BoundedLeastSquares, BoundedLmOptions, BoundedLmResult};

/// A nonlinear least-squares problem `min ½ Σ f_i(x)²` with `P` parameters.
pub trait LeastSquares<const P: usize> {
    /// Number of residuals.
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// `(JᵀJ, Jᵀf, ½ Σ f_i²)` at `x`, J the Jacobian of f.
    fn normal_equations(&self, x: &SVector<f64, P>) -> (SMatrix<f64, P, P>, SVector<f64, P>, f64);
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    pub max_iterations: usize,
    /// Paper 000's own test: stop when `½ Σ f² / n < cost_tolerance`.
    pub cost_tolerance: f64,
    /// Stop when `‖Δx‖ ≤ step_tolerance · (‖x‖ + step_tolerance)`.
    pub step_tolerance: f64,
    /// Stop when `‖Jᵀf‖∞ ≤ gradient_tolerance`.
    pub gradient_tolerance: f64,
    /// Initial damping `μ0 = tau · max diag(JᵀJ)`.
    pub tau: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 100,
            cost_tolerance: 0.0,
            step_tolerance: 1e-12,
            gradient_tolerance: 1e-14,
            tau: 1e-3,
        }
    }
}

/// Which stop test fired.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LmStop {
    CostBelowTolerance,
    SmallStep,
    SmallGradient,
    MaxIterations,
    /// The cost or the normal equations became non-finite, or could not be solved.
    Failed,
}

impl LmStop {
    pub fn converged(self) -> bool {
        matches!(self, LmStop::CostBelowTolerance | LmStop::SmallStep | LmStop::SmallGradient)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct LmResult<const P: usize> {
    pub x: SVector<f64, P>,
    /// `½ Σ f²` at `x`.
    pub cost: f64,
    pub iterations: usize,
    pub stop: LmStop,
    /// JᵀJ at `x`, for the covariance `σ̂² (JᵀJ)⁻¹`.
    pub jtj: SMatrix<f64, P, P>,
}

#[inline(always)] // so that callers compiled for wider vector units get their own copy
pub fn levenberg_marquardt<const P: usize, Prob: LeastSquares<P>>(
    problem: &Prob,
    x0: SVector<f64, P>,
    options: &LmOptions,
) -> LmResult<P> {
    let n = problem.len().max(1) as f64;
    let mut x = x0;
    let (mut jtj, mut g, mut cost) = problem.normal_equations(&x);
    let finish = |x, cost, iterations, stop, jtj| LmResult { x, cost, iterations, stop, jtj };
    if !cost.is_finite() {
        return finish(x, cost, 0, LmStop::Failed, jtj);
    }
    let mut mu = options.tau * (0..P).map(|i| jtj[(i, i)]).fold(0.0, f64::max);
    if mu <= 0.0 {
        mu = options.tau;
    }
    let mut nu = 2.0;
    for iteration in 1..=options.max_iterations {
        if cost / n < options.cost_tolerance {
            return finish(x, cost, iteration - 1, LmStop::CostBelowTolerance, jtj);
        }
        if g.amax() <= options.gradient_tolerance {
            return finish(x, cost, iteration - 1, LmStop::SmallGradient, jtj);
        }
        // (JᵀJ + μ I) h = −Jᵀf  (paper 000 eq 16 with D = I).
        let mut a = jtj;
        for i in 0..P {
            a[(i, i)] += mu;
        }
        let h = match a.cholesky() {
            Some(ch) => ch.solve(&(-g)),
            None => {
                mu *= nu;
                nu *= 2.0;
                continue;
            }
        };
        if h.norm() <= options.step_tolerance * (x.norm() + options.step_tolerance) {
            return finish(x, cost, iteration - 1, LmStop::SmallStep, jtj);
        }
        let x_new = x + h;
        // Evaluate the trial with its normal equations in one pass: most steps from a good
        // start are accepted, and then they are needed anyway.
        let trial = problem.normal_equations(&x_new);
        let cost_new = trial.2;
        // Gain ratio (eq 18): actual over predicted reduction, L(0) − L(h) = ½ hᵀ(μh − g).
        let predicted = 0.5 * h.dot(&(mu * h - g));
        let rho = if cost_new.is_finite() && predicted > 0.0 { (cost - cost_new) / predicted } else { -1.0 };
        if rho > 0.0 {
            x = x_new;
            (jtj, g, cost) = trial;
            // Nielsen's update (eq 17).
            mu *= f64::max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0).powi(3));
            nu = 2.0;
        } else {
            mu *= nu;
            nu *= 2.0;
        }
        if !mu.is_finite() || !cost.is_finite() {
            return finish(x, cost, iteration, LmStop::Failed, jtj);
        }
    }
    finish(x, cost, options.max_iterations, LmStop::MaxIterations, jtj)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    /// Rosenbrock as least squares: f = (10 (y − x²), 1 − x).
    struct Rosenbrock;
    impl LeastSquares<2> for Rosenbrock {
        fn len(&self) -> usize {
            2
        }
        fn normal_equations(&self, p: &Vector2<f64>) -> (Matrix2<f64>, Vector2<f64>, f64) {
            let f = [10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]];
            let j = [[-20.0 * p[0], 10.0], [-1.0, 0.0]];
            let mut jtj = Matrix2::zeros();
            let mut g = Vector2::zeros();
            for r in 0..2 {
                for a in 0..2 {
                    g[a] += j[r][a] * f[r];
                    for b in 0..2 {
                        jtj[(a, b)] += j[r][a] * j[r][b];
                    }
                }
            }
            (jtj, g, 0.5 * (f[0] * f[0] + f[1] * f[1]))
        }
    }

    #[test]
    fn solves_rosenbrock() {
        let r = levenberg_marquardt(&Rosenbrock, Vector2::new(-1.2, 1.0), &LmOptions::default());
        assert!(r.stop.converged(), "{:?}", r.stop);
        assert!((r.x - Vector2::new(1.0, 1.0)).amax() < 1e-8, "{}", r.x);
    }
}
