//! The bending surface of the error decomposition (docs/contours.md C6): a polynomial of the
//! groove centres' height deviation over x, y, the clamped skin's bending that the contour error
//! is split from.
use crate::error::{check_finite, Error, Result};
use nalgebra::{DMatrix, DVector};

/// Points each coefficient needs: the degree is lowered until the fit has this many per term.
const POINTS_PER_TERM: usize = 3;

/// B(x, y) = Σ_{i+j ≤ degree} c_ij · uⁱ·vʲ with u = (x − x̄)/s, v = (y − ȳ)/s and
/// s = max(range x, range y)/2, so the terms stay of order one over the part.
#[derive(Debug, Clone, PartialEq)]
pub struct BendingSurface {
    pub degree: usize,
    /// (i, j) of each term, in the order of `coefficients`: i = 0..=degree, j = 0..=degree − i.
    pub exponents: Vec<[u32; 2]>,
    pub coefficients: Vec<f64>,
    pub center: [f64; 2],
    pub scale: f64,
    /// RMS of dz − B over the fitted points, mm.
    pub rms_residual: f64,
}

fn exponents(degree: usize) -> Vec<[u32; 2]> {
    (0..=degree as u32).flat_map(|i| (0..=degree as u32 - i).map(move |j| [i, j])).collect()
}

impl BendingSurface {
    /// The least-squares polynomial of total degree `max_degree` (lowered until there are at least
    /// three points per coefficient) through the height deviations `dz` at `x`, `y` (mm).
    pub fn fit(x: &[f64], y: &[f64], dz: &[f64], max_degree: usize) -> Result<Self> {
        for (name, v) in [("x", x), ("y", y), ("dz", dz)] {
            check_finite(name, v, 1)?;
        }
        if x.len() != dz.len() || y.len() != dz.len() {
            return Err(Error::shape("dz", format!("({},) as x and y", x.len()), format!("({},)", dz.len())));
        }
        if dz.is_empty() {
            return Err(Error::invalid("dz", "no height deviation to fit a bending surface to"));
        }
        let mut degree = max_degree;
        while degree > 0 && dz.len() < POINTS_PER_TERM * exponents(degree).len() {
            degree -= 1;
        }
        let n = dz.len() as f64;
        let center = [x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n];
        let range = |v: &[f64]| {
            v.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)) - v.iter().fold(f64::INFINITY, |a, &b| a.min(b))
        };
        let scale = (range(x).max(range(y)).max(1e-9)) / 2.0;
        let terms = exponents(degree);
        let mut surface = BendingSurface {
            degree,
            coefficients: vec![0.0; terms.len()],
            exponents: terms,
            center,
            scale,
            rms_residual: 0.0,
        };
        let a = DMatrix::from_fn(dz.len(), surface.exponents.len(), |r, c| surface.term(x[r], y[r], c));
        // SVD, as a rank-deficient layout (centres on one line) still gets the least-norm fit.
        let c = a
            .svd(true, true)
            .solve(&DVector::from_column_slice(dz), 1e-12)
            .map_err(|e| Error::invalid("dz", format!("the bending surface could not be fitted ({e})")))?;
        surface.coefficients = c.iter().copied().collect();
        let sq: f64 = (0..dz.len()).map(|r| (dz[r] - surface.at(x[r], y[r])).powi(2)).sum();
        surface.rms_residual = (sq / n).sqrt();
        Ok(surface)
    }

    fn term(&self, x: f64, y: f64, k: usize) -> f64 {
        let (u, v) = ((x - self.center[0]) / self.scale, (y - self.center[1]) / self.scale);
        let [i, j] = self.exponents[k];
        u.powi(i as i32) * v.powi(j as i32)
    }

    /// B(x, y), mm.
    pub fn at(&self, x: f64, y: f64) -> f64 {
        self.coefficients.iter().enumerate().map(|(k, c)| c * self.term(x, y, k)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_polynomial_of_the_fitted_degree_is_recovered_exactly() {
        // dz = 0.1 + 0.002 x − 0.001 y + 1e-5 x y − 2e-6 x² on a scattered set of points.
        let (x, y): (Vec<f64>, Vec<f64>) = (0..60)
            .map(|k| (200.0 * (k as f64 * 0.618034).fract() - 100.0, 150.0 * (k as f64 * 0.754878).fract()))
            .unzip();
        let truth = |x: f64, y: f64| 0.1 + 0.002 * x - 0.001 * y + 1e-5 * x * y - 2e-6 * x * x;
        let dz: Vec<f64> = x.iter().zip(&y).map(|(&x, &y)| truth(x, y)).collect();
        let b = BendingSurface::fit(&x, &y, &dz, 4).unwrap();
        assert_eq!((b.degree, b.exponents.len()), (4, 15));
        assert!(b.rms_residual < 1e-12, "{}", b.rms_residual);
        assert!((b.at(13.0, 77.0) - truth(13.0, 77.0)).abs() < 1e-12);
        // Twenty points hold 3 per term of a degree-2 surface (6 terms) but not of degree 3 (10).
        let few = BendingSurface::fit(&x[..20], &y[..20], &dz[..20], 4).unwrap();
        assert_eq!(few.degree, 2);
        assert!(BendingSurface::fit(&x, &y, &dz[..5], 4).unwrap_err().to_string().contains("dz"));
        assert!(BendingSurface::fit(&[], &[], &[], 4).unwrap_err().to_string().contains("dz"));
    }
}
