//! The rounding of a V's tip, pooled over the frames of one call (docs/grooves.md, step 9).
//!
//! A V's tip rounded over a reading or two changes χ² by less than the noise does, so one
//! frame cannot say whether its bottom is sharp or rounded, and the depth moves by the whole
//! rounding with the choice (the sharp V extrapolates its tip 10–25 µm below a rounded
//! bottom). The frames of one scan share a process (one tool, one beam): what the rounding is
//! across them is what each frame's readings cannot say alone. So each V frame keeps its χ²
//! profile over the tip radius ([`RoundingCurve`]); the call estimates a prior on the radius
//! from all of them (a share at the sharp tip, the rest uniform up to a largest radius: the
//! two numbers of most marginal likelihood, an empirical Bayes estimate), and each frame's
//! depth and radius are then the medians of their posteriors under it, their standard errors
//! the posteriors' spread with the noise's at a fixed radius.
//!
//! Why not a crate: the estimate is a two-parameter grid search over a few thousand profiles,
//! and the posterior a weighted median of forty values.

/// Points a profile holds: the sharp V, the round V's profile points, the round V's own fit.
pub(super) const CURVE_POINTS: usize = 10;

/// The fine grid the profiles are read on: this many steps per reading pitch.
const STEPS_PER_PITCH: f64 = 8.0;

/// Fewest profiles a pooled prior is estimated from; below, each frame keeps its own rule
/// (the Akaike average of the sharp and the round V).
pub const MIN_POOLED: usize = 30;

/// Most frames the prior's estimate reads (every k-th frame of the call, k = ⌈F / this⌉):
/// two numbers are fixed long before, the estimate's work then does not grow with the call,
/// and a call over chunks (`machscan.dask`) can pool the same frames first.
pub const POOLED_FRAMES: usize = 4096;

/// The k of [`POOLED_FRAMES`] for a call of `frames` frames.
pub fn pooled_stride(frames: usize) -> usize {
    frames.div_ceil(POOLED_FRAMES).max(1)
}

/// One frame's χ² profile over its V's tip radius: the depth and the cost (½Σλ²) at each of
/// up to `CURVE_POINTS` radii (mm, increasing), the noise variance the costs are read
/// with, and the depth's standard error at a fixed radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundingCurve {
    pub(super) radius: [f64; CURVE_POINTS],
    pub(super) cost: [f64; CURVE_POINTS],
    pub(super) depth: [f64; CURVE_POINTS],
    pub(super) len: usize,
    pub(super) sigma2: f64,
    pub(super) pitch: f64,
    pub(super) se_depth: f64,
}

/// A prior on the tip radius: `share` at the sharp tip, the rest uniform over 0..`r_max` mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundingPrior {
    pub share: f64,
    pub r_max: f64,
}

/// A frame's depth and bottom radius under a prior, with their standard errors, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundingPosterior {
    pub depth: f64,
    pub se_depth: f64,
    pub radius: f64,
    pub se_radius: f64,
}

impl RoundingCurve {
    /// A curve from its points (radius, cost, depth), in any order; None with fewer than two.
    pub(super) fn new(points: &[(f64, f64, f64)], sigma2: f64, pitch: f64, se_depth: f64) -> Option<Self> {
        let mut p: Vec<(f64, f64, f64)> =
            points.iter().copied().filter(|(r, c, d)| r.is_finite() && c.is_finite() && d.is_finite()).collect();
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p.dedup_by(|a, b| a.0 - b.0 < 1e-9);
        if p.len() < 2 || p[0].0 > 1e-9 || !(sigma2 > 0.0 && pitch > 0.0) {
            return None;
        }
        let mut c = Self {
            radius: [0.0; CURVE_POINTS],
            cost: [0.0; CURVE_POINTS],
            depth: [0.0; CURVE_POINTS],
            len: p.len().min(CURVE_POINTS),
            sigma2,
            pitch,
            se_depth,
        };
        for (k, (r, cost, d)) in p.into_iter().take(CURVE_POINTS).enumerate() {
            (c.radius[k], c.cost[k], c.depth[k]) = (r, cost, d);
        }
        Some(c)
    }

    /// The grid step, mm.
    fn step(&self) -> f64 {
        self.pitch / STEPS_PER_PITCH
    }

    /// The cost and depth at radius `r` (linear between points; None beyond the last).
    fn at(&self, r: f64) -> Option<(f64, f64)> {
        let n = self.len;
        if r > self.radius[n - 1] + 1e-12 {
            return None;
        }
        let k = (1..n).find(|&k| self.radius[k] >= r).unwrap_or(n - 1);
        let (r0, r1) = (self.radius[k - 1], self.radius[k]);
        let t = if r1 > r0 { ((r - r0) / (r1 - r0)).clamp(0.0, 1.0) } else { 0.0 };
        let lerp = |a: &[f64; CURVE_POINTS]| a[k - 1] + t * (a[k] - a[k - 1]);
        Some((lerp(&self.cost), lerp(&self.depth)))
    }

    /// The likelihood (relative to the profile's best) and depth on the grid `g·step`,
    /// g = 0..`points`; zero likelihood beyond the profile.
    fn on_grid(&self, step: f64, points: usize) -> (Vec<f64>, Vec<f64>) {
        let least = self.cost[..self.len].iter().copied().fold(f64::INFINITY, f64::min);
        let (mut like, mut depth) = (vec![0.0; points], vec![f64::NAN; points]);
        for g in 0..points {
            if let Some((c, d)) = self.at(g as f64 * step) {
                like[g] = (-(c - least) / self.sigma2).exp();
                depth[g] = d;
            }
        }
        (like, depth)
    }

    /// The depth and radius under `prior`: their posterior medians, and as standard errors
    /// the posterior's spread with the depth's at a fixed radius.
    pub fn posterior(&self, prior: &RoundingPrior) -> Option<RoundingPosterior> {
        let step = self.step();
        let points = (prior.r_max / step).floor() as usize + 1;
        let (like, depth) = self.on_grid(step, points);
        let uniform = (1.0 - prior.share) / points as f64;
        let w: Vec<f64> =
            like.iter().enumerate().map(|(g, l)| l * (uniform + if g == 0 { prior.share } else { 0.0 })).collect();
        let total: f64 = w.iter().sum();
        if !(total > 0.0) {
            return None;
        }
        let radius: Vec<f64> = (0..points).map(|g| g as f64 * step).collect();
        let (d, var_d) = weighted_median_and_variance(&depth, &w, total);
        let (r, var_r) = weighted_median_and_variance(&radius, &w, total);
        Some(RoundingPosterior {
            depth: d,
            se_depth: (self.se_depth * self.se_depth + var_d).sqrt(),
            radius: r,
            se_radius: var_r.sqrt(),
        })
    }
}

/// The median of `values` weighted by `w` (sum `total`; zero weights skipped) and their
/// weighted variance.
fn weighted_median_and_variance(values: &[f64], w: &[f64], total: f64) -> (f64, f64) {
    let mut order: Vec<usize> = (0..values.len()).filter(|&g| w[g] > 0.0).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut acc = 0.0;
    let mut median = values[order[order.len() - 1]];
    for &g in &order {
        acc += w[g];
        if acc >= 0.5 * total {
            median = values[g];
            break;
        }
    }
    let mean = order.iter().map(|&g| w[g] * values[g]).sum::<f64>() / total;
    let var = order.iter().map(|&g| w[g] * (values[g] - mean).powi(2)).sum::<f64>() / total;
    (median, var)
}

impl RoundingPrior {
    /// The prior of most marginal likelihood over `curves`: for each largest radius on the
    /// profiles' grid, the sharp tip's share of most likelihood (`best_share`). None with
    /// fewer than [`MIN_POOLED`] curves.
    pub fn pooled(curves: &[RoundingCurve]) -> Option<Self> {
        if curves.len() < MIN_POOLED {
            return None;
        }
        // One grid for all: the finest step, out to the farthest profile.
        let step = curves.iter().map(|c| c.step()).fold(f64::INFINITY, f64::min);
        let reach = curves.iter().map(|c| c.radius[c.len - 1]).fold(0.0, f64::max);
        let points = (reach / step + 1e-9).floor() as usize + 1;
        if points < 2 {
            return None;
        }
        // Each profile's likelihood at the sharp tip and its running sums over the grid: the
        // marginal of (share, up to g) is share·L₀ + (1 − share)·S_g/(g + 1).
        let mut sharp = Vec::with_capacity(curves.len());
        let mut sums = Vec::with_capacity(curves.len() * points);
        for c in curves {
            let (like, _) = c.on_grid(step, points);
            sharp.push(like[0]);
            let mut s = 0.0;
            for l in like {
                s += l;
                sums.push(s);
            }
        }
        let mut best = (f64::NEG_INFINITY, Self { share: 1.0, r_max: 0.0 });
        let (mut a, mut b) = (vec![0.0; curves.len()], vec![0.0; curves.len()]);
        for g in 1..points {
            for (i, &l0) in sharp.iter().enumerate() {
                (a[i], b[i]) = (l0, sums[i * points + g] / (g + 1) as f64);
            }
            let share = best_share(&a, &b);
            let ll: f64 =
                a.iter().zip(&b).map(|(a, b)| (share * a + (1.0 - share) * b).max(f64::MIN_POSITIVE).ln()).sum();
            if ll > best.0 {
                best = (ll, Self { share, r_max: g as f64 * step });
            }
        }
        Some(best.1)
    }
}

/// The share s in [0, 1] that maximises Σ ln(s·aᵢ + (1 − s)·bᵢ) (concave in s: Newton's
/// method from the middle, kept in the interval; the ends where the slope there points out).
fn best_share(a: &[f64], b: &[f64]) -> f64 {
    let slope = |s: f64| -> (f64, f64) {
        a.iter().zip(b).fold((0.0, 0.0), |(d1, d2), (&a, &b)| {
            let m = (s * a + (1.0 - s) * b).max(f64::MIN_POSITIVE);
            let t = (a - b) / m;
            (d1 + t, d2 - t * t)
        })
    };
    if slope(0.0).0 <= 0.0 {
        return 0.0;
    }
    if slope(1.0).0 >= 0.0 {
        return 1.0;
    }
    let (mut lo, mut hi, mut s) = (0.0, 1.0, 0.5);
    for _ in 0..50 {
        let (d1, d2) = slope(s);
        if d1 > 0.0 {
            lo = s;
        } else {
            hi = s;
        }
        let next = if d2 < 0.0 { s - d1 / d2 } else { 0.5 * (lo + hi) };
        // Newton's step where it stays inside the bracket, else bisection.
        let next = if next > lo && next < hi { next } else { 0.5 * (lo + hi) };
        if (next - s).abs() < 1e-6 {
            return next;
        }
        s = next;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile whose χ² is (r − r0)²/s² about a radius r0 (mm), the depth falling by 0.6·r.
    fn curve(r0: f64, s: f64) -> RoundingCurve {
        let pitch = 0.025;
        let points: Vec<(f64, f64, f64)> = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0]
            .iter()
            .map(|f| {
                let r = f * pitch;
                (r, 0.5 * ((r - r0) / s).powi(2) * 1e-4, 0.3 - 0.6 * r)
            })
            .collect();
        RoundingCurve::new(&points, 1e-4, pitch, 0.002).unwrap()
    }

    #[test]
    fn a_given_prior_at_the_sharp_tip_keeps_the_sharp_depth() {
        let c = curve(0.03, 0.01);
        let p = c.posterior(&RoundingPrior { share: 1.0, r_max: 0.05 }).unwrap();
        assert!((p.depth - 0.3).abs() < 1e-12 && (p.se_depth - 0.002).abs() < 1e-12, "{p:?}");
        // No share at the sharp tip: the posterior sits at the profile's least, 0.03 mm.
        let p = c.posterior(&RoundingPrior { share: 0.0, r_max: 0.1 }).unwrap();
        assert!((p.radius - 0.03).abs() < 0.004 && (p.depth - (0.3 - 0.018)).abs() < 0.003, "{p:?}");
        assert!(p.se_depth > 0.002);
    }

    #[test]
    fn the_pooled_prior_follows_what_the_profiles_say() {
        // Sharp tips only: the share goes to them (or the radius to nothing).
        let sharp: Vec<RoundingCurve> = (0..200).map(|_| curve(0.0, 0.005)).collect();
        let p = RoundingPrior::pooled(&sharp).unwrap();
        assert!(p.share > 0.9 || p.r_max <= 0.0032, "{p:?}");
        // Tips rounded evenly up to 0.05 mm: no share at the sharp tip, the largest radius near
        // 0.05 mm.
        let rounded: Vec<RoundingCurve> = (0..200).map(|k| curve(0.05 * (k as f64 + 0.5) / 200.0, 0.004)).collect();
        let p = RoundingPrior::pooled(&rounded).unwrap();
        assert!(p.share < 0.1 && (p.r_max - 0.05).abs() < 0.008, "{p:?}");
        // Too few to pool.
        assert!(RoundingPrior::pooled(&rounded[..MIN_POOLED - 1]).is_none());
    }
}
