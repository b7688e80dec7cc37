//! The misfit of the chosen section at a groove's bottom, pooled over the frames of one call
//! (docs/grooves.md, step 11).
//!
//! The standard errors are those of the models fitted. A section none of them holds (a bowl
//! with curved flanks, a beam's profile) is measured as the nearest model's, and that model's
//! bias is not in them: on parabolic bowls ±2·se had held the depth in 59 % of frames. To first
//! order the depth's bias is the systematic residual at the bottom (the true section is the
//! fit plus it, and the depth is read at the bottom's minimum), which one frame estimates
//! about as noisily as the bias itself. The frames of one scan share a tool, so across them
//! the misfit is a variance the call can estimate: each frame keeps the residual a quadratic
//! gives at its bottom and that residual's noise variance ([`BottomResidual`]); per model
//! chosen, the call estimates the variance τ² of the true residuals (a random-effects
//! variance, median-based so that a few failed frames do not set it), and each frame's depth
//! variance takes its residual's posterior second moment under N(0, τ²). Where the models
//! hold the section τ² is 0 and nothing changes.
//!
//! The same pooling covers the one choice made on more evidence than Akaike's: the circle (U)
//! kept over the ellipse unless the ellipse fits clearly better. A U chosen on a section a
//! little wider than deep is the readings shrunk to a circle; its errors, conditional on
//! k = 1, had held a half-ellipse's flank angles and radius in 90 % of frames. Where both were
//! fitted each frame keeps, per measure, the ellipse's value less the U's and that difference's
//! variance were the U right (the ellipse's variance less the U's: the U is the efficient one
//! of a nested pair, Hausman 1978) ([`StretchDifference`]); the call pools, per measure, the
//! true differences' mean (a bias: a ball cutter crossed obliquely is always wider than deep,
//! and each frame's difference, within its noise, had pooled to no variance) and their
//! variance about it, and a U chosen takes their posterior second moment.
//!
//! Why not a crate: a median-matching bisection over a few thousand pairs, and a 3 × 3 solve.

use super::robust;
use super::section::{SectionModel, MEASURES};

/// Fewest frames of one model the misfit variance is estimated from; below, that model's
/// frames keep their errors as they are.
pub const MIN_POOLED: usize = 30;

/// The readings the bottom's residual is read from: within this many reading pitches of the
/// bottom (a quadratic over nine readings: wide enough to be steady, narrow enough to follow
/// a bottom's curvature that the model lacks).
const REACH_PITCHES: f64 = 4.0;

/// Fewest readings for the quadratic (three parameters).
const MIN_READINGS: usize = 5;

/// The median of χ² with one degree of freedom.
const CHI2_1_MEDIAN: f64 = 0.454_936_423_119_572_7;

/// One fit's residual at its bottom (readings minus the section, along the beam, from a
/// quadratic through the residuals near it), its noise variance (mm²), and the model fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BottomResidual {
    pub model: SectionModel,
    pub residual: f64,
    pub variance: f64,
}

/// The variance of the true bottom residuals, per section model (mm², by
/// [`SectionModel::index`]; None: not estimated, the model's frames unchanged), and the true
/// differences between the ellipse's measures and the U's, per measure (by the indices of
/// [`super::section::Measures`]; None: not estimated, the U's unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MisfitPrior {
    pub variance: [Option<f64>; 5],
    pub stretch: [Option<StretchMisfit>; MEASURES],
}

/// The true ellipse-less-U differences of one measure over a call: their mean (in the
/// measure's unit; 0 where the pooled median is within two of its standard errors of 0) and
/// their variance about it (the unit squared: mm², degrees², mm⁴ for the area).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StretchMisfit {
    pub bias: f64,
    pub variance: f64,
}

/// The names of the measures the stretch misfit is pooled for (by the indices of
/// [`super::section::Measures`]), as the result's fields; given or reported as "u:<name>".
pub const STRETCH_MEASURES: [&str; MEASURES] =
    ["width", "depth", "x0", "flank_angle_left", "flank_angle_right", "area", "bottom_radius"];

/// One frame's ellipse against its U, both fitted: per measure the ellipse's value less the
/// U's, that difference's variance were the U right (NaN where a model lacks the measure), and
/// whether the U was chosen (only then do its errors take the pooled variance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StretchDifference {
    pub difference: [f64; MEASURES],
    pub variance: [f64; MEASURES],
    pub circle_chosen: bool,
}

impl StretchDifference {
    /// The variances the misfit adds to the U's measures under `prior`: per measure the true
    /// difference's posterior second moment under N(μ, τ²), (μ + B·(d − μ))² + B·v with
    /// B = τ²/(τ² + v); 0 where not estimated, or where the ellipse was chosen.
    pub fn variances(&self, prior: &MisfitPrior) -> [f64; MEASURES] {
        std::array::from_fn(|k| match prior.stretch[k] {
            Some(s) if self.circle_chosen && self.difference[k].is_finite() && self.variance[k] > 0.0 => {
                let b = s.variance / (s.variance + self.variance[k]);
                (s.bias + b * (self.difference[k] - s.bias)).powi(2) + b * self.variance[k]
            }
            _ => 0.0,
        })
    }
}

impl BottomResidual {
    /// The residual at `bottom` of a quadratic fitted to the `residuals` of the readings at
    /// `u` within [`REACH_PITCHES`] of it, with its variance under noise `sigma`; None with
    /// fewer than [`MIN_READINGS`] there.
    pub(super) fn at(
        model: SectionModel,
        u: &[f64],
        residual: impl Fn(usize) -> f64,
        bottom: f64,
        pitch: f64,
        sigma: f64,
    ) -> Option<Self> {
        let reach = REACH_PITCHES * pitch;
        let (mut a, mut b, mut m) = (nalgebra::Matrix3::<f64>::zeros(), nalgebra::Vector3::<f64>::zeros(), 0);
        for (i, &ui) in u.iter().enumerate() {
            let du = ui - bottom;
            if du.abs() <= reach {
                // Scaled by the reach, so that the normal equations stay well conditioned.
                let t = du / reach;
                let row = nalgebra::Vector3::new(1.0, t, t * t);
                a += row * row.transpose();
                b += row * residual(i);
                m += 1;
            }
        }
        if m < MIN_READINGS {
            return None;
        }
        let inv = a.try_inverse()?;
        let coef = inv * b;
        let variance = sigma * sigma * inv[(0, 0)];
        (coef[0].is_finite() && variance.is_finite() && variance > 0.0).then_some(BottomResidual {
            model,
            residual: coef[0],
            variance,
        })
    }

    /// The depth variance the misfit adds under `prior`: the posterior second moment of the
    /// true residual, B²·r² + B·v with B = τ²/(τ² + v) (0 where τ² is 0 or not estimated).
    pub fn depth_variance(&self, prior: &MisfitPrior) -> f64 {
        match prior.variance[self.model.index()] {
            Some(tau2) if tau2 > 0.0 => {
                let b = tau2 / (tau2 + self.variance);
                b * b * self.residual * self.residual + b * self.variance
            }
            _ => 0.0,
        }
    }
}

impl MisfitPrior {
    /// The misfit variance of each model over these residuals: per model with at least
    /// [`MIN_POOLED`] of them, the τ² ≥ 0 at which the median of r²/(v + τ²) is χ²₁'s median
    /// (0 where it is below that already: the residuals are the noise's); and per measure over
    /// the ellipse-less-U differences from at least [`MIN_POOLED`] frames, their mean (the
    /// median, where it is two of its standard errors from 0) and τ² about it alike.
    pub fn pooled(residuals: &[BottomResidual], stretch: &[StretchDifference]) -> Self {
        let mut prior = MisfitPrior::default();
        for k in 0..MEASURES {
            let pairs: Vec<(f64, f64)> = stretch
                .iter()
                .filter(|s| s.difference[k].is_finite() && s.variance[k].is_finite() && s.variance[k] > 0.0)
                .map(|s| (s.difference[k], s.variance[k]))
                .collect();
            if pairs.len() >= MIN_POOLED {
                let bias = pooled_bias(pairs.iter().map(|p| p.0).collect());
                let centred: Vec<(f64, f64)> = pairs.iter().map(|&(d, v)| ((d - bias).powi(2), v)).collect();
                prior.stretch[k] = Some(StretchMisfit { bias, variance: misfit_variance(&centred) });
            }
        }
        for model in SectionModel::ALL {
            let pairs: Vec<(f64, f64)> =
                residuals.iter().filter(|r| r.model == model).map(|r| (r.residual * r.residual, r.variance)).collect();
            if pairs.len() >= MIN_POOLED {
                prior.variance[model.index()] = Some(misfit_variance(&pairs));
            }
        }
        prior
    }
}

/// The median of `d`, where it is at least two of its standard errors from 0, else 0. Its
/// standard error: the normal's √(π/2)·σ/√n, σ from the median absolute deviation (1.4826·MAD),
/// so that a few failed frames set neither.
fn pooled_bias(d: Vec<f64>) -> f64 {
    let mut keys: Vec<i64> = d.iter().map(|&x| robust::key(x)).collect();
    let m = robust::median_of_keys(&mut keys);
    let se =
        (std::f64::consts::PI / 2.0).sqrt() * robust::mad_sigma(d.iter().copied(), &mut keys) / (d.len() as f64).sqrt();
    if m.abs() >= 2.0 * se {
        m
    } else {
        0.0
    }
}

/// The τ² of [`MisfitPrior::pooled`] for pairs (r², v): bisection, since the median of
/// r²/(v + τ²) falls as τ² grows.
fn misfit_variance(pairs: &[(f64, f64)]) -> f64 {
    let mut keys: Vec<i64> = Vec::with_capacity(pairs.len());
    let mut median_at = |tau2: f64| {
        keys.clear();
        keys.extend(pairs.iter().map(|&(r2, v)| robust::key(r2 / (v + tau2))));
        robust::median_of_keys(&mut keys)
    };
    if median_at(0.0) <= CHI2_1_MEDIAN {
        return 0.0;
    }
    // At τ² = max r² / median every ratio is below the median sought.
    let (mut lo, mut hi) = (0.0, pairs.iter().map(|p| p.0).fold(0.0, f64::max) / CHI2_1_MEDIAN);
    // Forty halvings: τ² to a 10⁻¹² of its bracket, far finer than its own spread.
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if median_at(mid) > CHI2_1_MEDIAN {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{gauss, lcg};

    fn residuals(n: usize, sd: f64, tau: f64, seed: &mut u64) -> Vec<BottomResidual> {
        (0..n)
            .map(|_| {
                let v = sd * sd * (0.5 + lcg(seed));
                BottomResidual {
                    model: SectionModel::U,
                    residual: tau * gauss(seed) + v.sqrt() * gauss(seed),
                    variance: v,
                }
            })
            .collect()
    }

    #[test]
    fn noise_alone_pools_to_no_misfit() {
        let mut seed = 5;
        let prior = MisfitPrior::pooled(&residuals(4000, 0.002, 0.0, &mut seed), &[]);
        let tau2 = prior.variance[SectionModel::U.index()].unwrap();
        // The sample median scatters by about 4 % at 4000: τ² within a tenth of v, mostly 0.
        assert!(tau2 < 0.1 * 0.002f64.powi(2), "{tau2}");
        assert_eq!(prior.variance[SectionModel::V.index()], None);
    }

    #[test]
    fn a_systematic_misfit_pools_to_its_variance() {
        let mut seed = 6;
        let tau = 0.004;
        let prior = MisfitPrior::pooled(&residuals(4000, 0.002, tau, &mut seed), &[]);
        let tau2 = prior.variance[SectionModel::U.index()].unwrap();
        assert!((tau2.sqrt() / tau - 1.0).abs() < 0.1, "{} against {tau}", tau2.sqrt());
        // A frame's added variance: its residual's posterior second moment.
        let r = BottomResidual { model: SectionModel::U, residual: 0.006, variance: 0.002f64.powi(2) };
        let b = tau2 / (tau2 + r.variance);
        assert!((r.depth_variance(&prior) - (b * b * 0.006f64.powi(2) + b * r.variance)).abs() < 1e-18);
        // Fewer frames than MIN_POOLED: not estimated.
        let few = MisfitPrior::pooled(&residuals(MIN_POOLED - 1, 0.002, tau, &mut seed), &[]);
        assert_eq!(few.variance[SectionModel::U.index()], None);
        assert_eq!(r.depth_variance(&few), 0.0);
    }

    #[test]
    fn the_stretch_misfit_pools_per_measure_and_widens_only_a_chosen_circle() {
        // Width differences with a true spread of 10 µm beyond a noise of 3 µm; angle
        // differences of the noise alone; the bottom radius missing (NaN) on every frame.
        let (tau, sd) = (0.010, 0.003);
        let mut seed = 8;
        let frames: Vec<StretchDifference> = (0..2000)
            .map(|i| {
                let mut difference = [f64::NAN; MEASURES];
                let mut variance = [f64::NAN; MEASURES];
                (difference[0], variance[0]) = (tau * gauss(&mut seed) + sd * gauss(&mut seed), sd * sd);
                (difference[3], variance[3]) = (0.5 * gauss(&mut seed), 0.25);
                StretchDifference { difference, variance, circle_chosen: i % 2 == 0 }
            })
            .collect();
        let prior = MisfitPrior::pooled(&[], &frames);
        let (width, angle) = (prior.stretch[0].unwrap(), prior.stretch[3].unwrap());
        assert!((width.variance.sqrt() / tau - 1.0).abs() < 0.1 && width.bias == 0.0, "{width:?}");
        assert!(angle.variance < 0.1 * 0.25 && angle.bias == 0.0, "{angle:?}");
        assert_eq!(prior.stretch[6], None);
        assert_eq!(prior.variance, [None; 5]);
        let (circle, ellipse) = (frames[0].variances(&prior), frames[1].variances(&prior));
        let b = width.variance / (width.variance + sd * sd);
        let expected = b * b * frames[0].difference[0].powi(2) + b * sd * sd;
        assert!((circle[0] - expected).abs() < 1e-18, "{circle:?}");
        assert_eq!(circle[6], 0.0);
        assert_eq!(ellipse, [0.0; MEASURES]);
        // A bias every frame shares, each difference within its noise: its mean is pooled (a
        // stretch always the same way: an oblique crossing), not a variance, and a U takes it.
        let shifted: Vec<StretchDifference> = frames
            .iter()
            .map(|f| {
                let mut f = *f;
                f.difference[3] += 0.3;
                f
            })
            .collect();
        let angle = MisfitPrior::pooled(&[], &shifted).stretch[3].unwrap();
        assert!((angle.bias - 0.3).abs() < 0.05 && angle.variance < 0.1 * 0.25, "{angle:?}");
        let prior = MisfitPrior { stretch: [Some(angle); MEASURES], ..MisfitPrior::default() };
        assert!(shifted[0].variances(&prior)[3] > 0.8 * 0.3f64.powi(2));
    }

    #[test]
    fn the_bottom_residual_is_the_quadratic_through_the_residuals() {
        // Residuals 1 + 2t + 3t² (t in mm) at a 25 µm pitch: the quadratic's value at the
        // bottom is 1, exactly, and its variance that of the intercept.
        let u: Vec<f64> = (0..40).map(|i| (i as f64 - 20.0) * 0.025).collect();
        let r = BottomResidual::at(SectionModel::Round, &u, |i| 1.0 + 2.0 * u[i] + 3.0 * u[i] * u[i], 0.0, 0.025, 0.01)
            .unwrap();
        assert!((r.residual - 1.0).abs() < 1e-12, "{r:?}");
        // Nine readings within four pitches; a quadratic's intercept variance exceeds σ²/9.
        assert!(r.variance > 1e-4 / 9.0 && r.variance < 1e-4, "{r:?}");
        assert!(BottomResidual::at(SectionModel::Round, &u[..3], |_| 0.0, 0.0, 0.025, 0.01).is_none());
    }
}
