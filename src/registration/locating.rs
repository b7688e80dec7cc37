//! Locating-region selection (SPEC R4, paper 003 §2.2): a part is located more accurately on
//! its flat regions, so the probe points are drawn from the flattest share of the surface —
//! by the U-direction line curvature of a gridded scan, or the surface variation of a cloud —
//! at random, reproducibly from a seed (the paper: 160 of 20 000 points).
use crate::error::{check_finite_points, Error, Result};

/// Curvature along the U direction of a gridded scan `(nu, nv)` (point `(i, j)` at
/// `points[i·nv + j]`, U along i): the curvature of the circle through each point and its two
/// U neighbors (Menger: `4·area / (|a||b||c|)`, exactly 1/R on a circle of radius R); the ends
/// of each line take their neighbor's value. Needs nu ≥ 3.
pub fn line_curvature(points: &[[f64; 3]], nu: usize, nv: usize) -> Result<Vec<f64>> {
    check_finite_points("points", points)?;
    if nu < 3 || points.len() != nu * nv {
        return Err(Error::shape("points", "(nu, nv, 3) with nu >= 3 points along U", format!("({nu}, {nv}, 3)")));
    }
    let at = |i: usize, j: usize| points[i * nv + j];
    let mut out = vec![0.0; points.len()];
    for j in 0..nv {
        for i in 1..nu - 1 {
            let (p, q, r) = (at(i - 1, j), at(i, j), at(i + 1, j));
            let d = |a: [f64; 3], b: [f64; 3]| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let (a, b, c) = (d(p, q), d(q, r), d(p, r));
            let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
            let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            let den = norm(a) * norm(b) * norm(c);
            // 2·|a × b| is four times the triangle's area; coincident points have no curvature.
            out[i * nv + j] = if den > 0.0 { 2.0 * norm(cross) / den } else { 0.0 };
        }
        out[j] = out[nv + j];
        out[(nu - 1) * nv + j] = out[(nu - 2) * nv + j];
    }
    Ok(out)
}

/// SplitMix64 (Steele et al. 2014): a small, fixed generator, so that a seed draws the same
/// points on every platform and version.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (n ≥ 1; Lemire's multiply-shift with rejection: no modulo bias).
    fn below(&mut self, n: u64) -> u64 {
        loop {
            let m = (self.next() as u128) * (n as u128);
            if (m as u64) >= (n.wrapping_neg() % n) {
                return (m >> 64) as u64;
            }
        }
    }
}

/// `m` indices drawn at random (seeded) from the `keep` share of the points with the lowest
/// `curvature` (ties by index), returned ascending.
pub fn locating_points(curvature: &[f64], m: usize, keep: f64, seed: u64) -> Result<Vec<usize>> {
    if let Some(i) = curvature.iter().position(|c| !c.is_finite()) {
        return Err(Error::invalid("curvature", format!("must be finite, found {} at index {i}", curvature[i])));
    }
    if !(keep > 0.0 && keep <= 1.0) {
        return Err(Error::invalid("keep", format!("must be a share in (0, 1], got {keep}")));
    }
    let n = curvature.len();
    let flat = ((keep * n as f64).ceil() as usize).min(n);
    if m > flat {
        return Err(Error::invalid(
            "m",
            format!("{m} points asked, but the flattest {:.0} % of the surface holds only {flat}", 100.0 * keep),
        ));
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_unstable_by(|&a, &b| curvature[a].total_cmp(&curvature[b]).then(a.cmp(&b)));
    order.truncate(flat);
    // A partial Fisher–Yates shuffle: the first m are a uniform sample without replacement.
    let mut rng = SplitMix(seed);
    for i in 0..m {
        let j = i + rng.below((flat - i) as u64) as usize;
        order.swap(i, j);
    }
    order.truncate(m);
    order.sort_unstable();
    Ok(order)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_curvature_is_one_over_the_radius_on_a_cylinder() {
        let (nu, nv, r) = (50, 4, 12.5);
        let mut pts = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let t = 0.02 * i as f64 + 0.001 * (i * i) as f64;
                pts.push([r * t.cos(), j as f64, r * t.sin()]);
            }
        }
        let c = line_curvature(&pts, nu, nv).unwrap();
        assert!(c.iter().all(|&k| (k - 1.0 / r).abs() < 1e-12), "{:?}", &c[..4]);
    }

    #[test]
    fn points_come_from_the_flattest_share_reproducibly() {
        let curvature: Vec<f64> = (0..1000).map(|i| if i % 3 == 0 { 0.001 } else { 0.5 }).collect();
        let a = locating_points(&curvature, 160, 0.3, 7).unwrap();
        assert_eq!(a.len(), 160);
        assert!(a.iter().all(|&i| i % 3 == 0) && a.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(a, locating_points(&curvature, 160, 0.3, 7).unwrap());
        assert_ne!(a, locating_points(&curvature, 160, 0.3, 8).unwrap());
        assert!(locating_points(&curvature, 400, 0.3, 7).unwrap_err().to_string().contains("m:"));
    }
}
