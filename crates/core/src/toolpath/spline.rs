//! A smooth interpolation of values scattered over the xy plane: the polyharmonic spline
//! φ(r) = r³ with a cubic polynomial (quadratic for fewer than 20 sites),
//! `s(x) = Σ wᵢ φ(|x − xᵢ|) + q(x)`, `Σ wᵢ qⱼ(xᵢ) = 0`.
//!
//! Why this one for the mirror-milling mapping (SPEC S5 Beyond): a bent skin moves its points
//! by a smooth field that is not linear — the bend of a 300 mm plate to R = 1000 mm moves them
//! by ~x³/6R² in x and x²/2R in z — so the paper's linear interpolation between 40 mm apart
//! matching points leaves ~0.1 mm. The spline reproduces cubic fields exactly (the bend's leading
//! terms), needs no grid and no shape parameter, and for a few hundred matching points is one
//! small dense solve. With a quadratic polynomial only, the r³ spline's free boundary leaves
//! ~10 µm of the bend near the outline; the cubic takes that to ~0.1 µm.
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector, Vector2};

/// The fitted spline, for `k` value columns at once.
#[derive(Debug)]
pub struct Spline {
    centres: Vec<[f64; 2]>,
    /// Centre and scale of the sites, so that the system is conditioned in unit coordinates.
    shift: [f64; 2],
    scale: f64,
    /// Polynomial terms: 6 (quadratic) or 10 (cubic).
    terms: usize,
    /// One column per value: n weights, then the polynomial coefficients.
    coefficients: DMatrix<f64>,
}

/// Sites from which on the polynomial is cubic: 10 coefficients, with room to spare.
const CUBIC_FROM: usize = 20;

fn kernel(r: f64) -> f64 {
    r * r * r
}

/// The polynomial terms at p, and their x and y derivatives.
fn polynomial(p: [f64; 2]) -> ([f64; 10], [f64; 10], [f64; 10]) {
    let (x, y) = (p[0], p[1]);
    (
        [1.0, x, y, x * x, x * y, y * y, x * x * x, x * x * y, x * y * y, y * y * y],
        [0.0, 1.0, 0.0, 2.0 * x, y, 0.0, 3.0 * x * x, 2.0 * x * y, y * y, 0.0],
        [0.0, 0.0, 1.0, 0.0, x, 2.0 * y, 0.0, x * x, 2.0 * x * y, 3.0 * y * y],
    )
}

/// Sites closer than this fraction of their typical spacing (the median distance to the nearest
/// other site) are refused: an interpolant through both must bend between them by their values'
/// difference over their distance, which measurement noise alone makes millimetres (two points
/// 0.01 mm apart on a 15 mm grid with 10 µm between their values moved tool points by 4 mm).
const MIN_SEPARATION: f64 = 1e-3;

/// Fails naming `name` where two sites are closer than `MIN_SEPARATION` of the typical spacing.
fn check_separation(name: &str, sites: &[[f64; 2]]) -> Result<()> {
    let distance = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    // Each site's nearest other site; a few hundred sites at most, so all pairs.
    let nearest: Vec<(f64, usize)> = sites
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            sites
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(j, &q)| (distance(p, q), j))
                .fold((f64::INFINITY, usize::MAX), |m, c| if c.0 < m.0 { c } else { m })
        })
        .collect();
    let mut spacing: Vec<f64> = nearest.iter().map(|c| c.0).collect();
    spacing.sort_by(f64::total_cmp);
    let typical = spacing[spacing.len() / 2];
    match nearest.iter().enumerate().find(|(_, c)| c.0 < MIN_SEPARATION * typical) {
        Some((i, &(d, j))) => Err(Error::invalid(
            name,
            format!(
                "points {} and {} are {d:.3e} mm apart in x, y, under a thousandth of their typical spacing \
                 ({typical:.3} mm): too close to interpolate between (leave one out, or interpolation='linear')",
                i.min(j),
                i.max(j)
            ),
        )),
        None => Ok(()),
    }
}

impl Spline {
    /// Interpolates `values[i]` (k per site) at `sites[i]`. `name` names the sites in errors.
    pub fn fit(name: &str, sites: &[[f64; 2]], values: &[Vec<f64>]) -> Result<Self> {
        let n = sites.len();
        if n < 6 {
            return Err(Error::invalid(name, format!("the smooth interpolation needs at least 6 points, got {n}")));
        }
        let k = values.first().map_or(0, Vec::len);
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in sites {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let shift = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        let scale = ((hi[0] - lo[0]).max(hi[1] - lo[1]) / 2.0).max(f64::MIN_POSITIVE);
        let centres: Vec<[f64; 2]> =
            sites.iter().map(|p| [(p[0] - shift[0]) / scale, (p[1] - shift[1]) / scale]).collect();
        check_separation(name, sites)?;
        // The polynomial must be fixed by the sites (not all on one line, conic or cubic
        // curve), or the system is singular.
        let terms = if n >= CUBIC_FROM { 10 } else { 6 };
        let q = DMatrix::from_fn(n, terms, |i, c| polynomial(centres[i]).0[c]);
        let sv = q.singular_values();
        if sv.min() <= 1e-9 * sv.max() {
            return Err(Error::invalid(
                name,
                "the points do not fix a polynomial surface (they lie on one line, conic or cubic curve)",
            ));
        }
        let mut a = DMatrix::zeros(n + terms, n + terms);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = kernel((Vector2::from(centres[i]) - Vector2::from(centres[j])).norm());
            }
            for (c, &q) in polynomial(centres[i]).0[..terms].iter().enumerate() {
                a[(i, n + c)] = q;
                a[(n + c, i)] = q;
            }
        }
        let mut b = DMatrix::zeros(n + terms, k);
        for (i, v) in values.iter().enumerate() {
            for (c, &x) in v.iter().enumerate() {
                b[(i, c)] = x;
            }
        }
        let lu = a.lu();
        let coefficients = lu
            .solve(&b)
            .filter(|c| c.iter().all(|x| x.is_finite()))
            .ok_or_else(|| Error::invalid(name, "two points share the same x, y"))?;
        Ok(Spline { centres, shift, scale, terms, coefficients })
    }

    /// The interpolated values at (x, y) and their x and y derivatives.
    pub fn eval(&self, x: f64, y: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let p = [(x - self.shift[0]) / self.scale, (y - self.shift[1]) / self.scale];
        let (n, m) = (self.centres.len(), self.terms);
        let mut phi = DVector::zeros(n + m);
        let mut dx = DVector::zeros(n + m);
        let mut dy = DVector::zeros(n + m);
        for (i, c) in self.centres.iter().enumerate() {
            let (ux, uy) = (p[0] - c[0], p[1] - c[1]);
            let r = ux.hypot(uy);
            phi[i] = kernel(r);
            // d(r³)/dx = 3 r (x − cₓ).
            dx[i] = 3.0 * r * ux;
            dy[i] = 3.0 * r * uy;
        }
        let (q, qx, qy) = polynomial(p);
        for c in 0..m {
            phi[n + c] = q[c];
            dx[n + c] = qx[c];
            dy[n + c] = qy[c];
        }
        let v = self.coefficients.tr_mul(&phi);
        let gx = self.coefficients.tr_mul(&dx) / self.scale;
        let gy = self.coefficients.tr_mul(&dy) / self.scale;
        (v.iter().copied().collect(), gx.iter().copied().collect(), gy.iter().copied().collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadratic_fields_are_reproduced_and_smooth_ones_closely() {
        let sites: Vec<[f64; 2]> =
            (0..64).map(|k| [-150.0 + 300.0 * (k % 8) as f64 / 7.0, -100.0 + 200.0 * (k / 8) as f64 / 7.0]).collect();
        let f = |p: [f64; 2]| vec![3.0 + 0.2 * p[0] - p[1] + 1e-3 * p[0] * p[1], 1000.0 * (p[0] / 1000.0).sin() - p[0]];
        let values: Vec<Vec<f64>> = sites.iter().map(|&p| f(p)).collect();
        let s = Spline::fit("sites", &sites, &values).unwrap();
        let mut worst = [0.0f64; 2];
        for k in 0..500 {
            let p = [-150.0 + 300.0 * (k as f64 * 0.618).fract(), -100.0 + 200.0 * (k as f64 * 0.7549).fract()];
            let (v, gx, gy) = s.eval(p[0], p[1]);
            let t = f(p);
            worst[0] = worst[0].max((v[0] - t[0]).abs());
            worst[1] = worst[1].max((v[1] - t[1]).abs());
            // The quadratic's derivatives are exact too.
            assert!((gx[0] - (0.2 + 1e-3 * p[1])).abs() < 1e-9 && (gy[0] - (-1.0 + 1e-3 * p[0])).abs() < 1e-9);
        }
        // A quadratic exactly; the bend's displacement (up to 0.56 mm) to well under a µm.
        assert!(worst[0] < 1e-9 && worst[1] < 1e-4, "{worst:?}");
    }

    #[test]
    fn points_that_fix_no_quadratic_are_refused_by_name() {
        let line: Vec<[f64; 2]> = (0..8).map(|k| [k as f64, 2.0 * k as f64]).collect();
        let v: Vec<Vec<f64>> = line.iter().map(|_| vec![0.0]).collect();
        assert!(Spline::fit("sites", &line, &v).unwrap_err().to_string().contains("sites"));
        let mut line: Vec<[f64; 2]> = (0..30).map(|k| [k as f64, 2.0 * k as f64]).collect();
        line[3] = [0.0, 1.0];
        let v: Vec<Vec<f64>> = line.iter().map(|_| vec![0.0]).collect();
        assert!(Spline::fit("sites", &line, &v).unwrap_err().to_string().contains("sites"));
        assert!(Spline::fit("sites", &line[..5], &v[..5]).unwrap_err().to_string().contains("at least 6"));
    }

    #[test]
    fn sites_closer_than_a_thousandth_of_their_spacing_are_refused_by_name() {
        let mut sites: Vec<[f64; 2]> = (0..9).map(|k| [15.0 * (k % 3) as f64, 15.0 * (k / 3) as f64]).collect();
        sites.push([15.0 + 0.01, 15.0]);
        let v: Vec<Vec<f64>> = sites.iter().map(|_| vec![0.0]).collect();
        let e = Spline::fit("sites", &sites, &v).unwrap_err().to_string();
        assert!(e.contains("sites") && e.contains("points 4 and 9"), "{e}");
        sites[9] = [15.0 + 0.1, 15.0]; // 1/150 of the spacing: allowed
        assert!(Spline::fit("sites", &sites, &v).is_ok());
    }
}
