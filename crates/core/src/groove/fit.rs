//! The batch groove fit: each frame measured by the method its options ask for (the section
//! models of `measure.rs` by default, the paper's tanh template of `tanh.rs`), the frames in
//! parallel, and the view of one frame for figures.
use super::measure::{measure_grooves, MeasureSettings};
use super::misfit::{BottomResidual, MisfitPrior, StretchDifference};
use super::options::{
    window_range, FitModel, GrooveFit, GrooveOptions, GrooveSelect, GrooveStatus, MisfitRule, RoundingRule,
    TemplateKind,
};
use super::rounding::{pooled_stride, RoundingCurve, RoundingPrior};
use super::section::SectionModel;
use super::tanh::{fit_tanh, fit_tanh_detailed};
use super::template::TanhTemplate;
use crate::error::{Error, Result};
use rayon::prelude::*;

/// Fit one frame: `x` reading abscissae, `z` readings (NaN = invalid), same length.
///
/// On x86-64 CPUs with AVX2 and FMA the same code runs compiled for them (chosen at run time,
/// the same choice for every frame on a machine, so results never depend on the thread count):
/// the tanh and dot-product passes then run four readings at a time.
///
/// The groove `o.select` asks for; with `GrooveSelect::All` the leftmost ([`fit_frame_grooves`]
/// gives them all).
pub fn fit_frame(x: &[f64], z: &[f64], o: &GrooveOptions) -> GrooveFit {
    fit_frame_grooves(x, z, o).swap_remove(0)
}

/// The grooves of one frame `o.select` asks for: one, or with `GrooveSelect::All` one per
/// groove, left to right (one failed fit saying why when there is none).
pub fn fit_frame_grooves(x: &[f64], z: &[f64], o: &GrooveOptions) -> Vec<GrooveFit> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU has the features the function is compiled for (checked above).
            return unsafe { fit_frame_avx2_fma(x, z, o) };
        }
    }
    fit_frame_portable(x, z, o)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn fit_frame_avx2_fma(x: &[f64], z: &[f64], o: &GrooveOptions) -> Vec<GrooveFit> {
    fit_frame_portable(x, z, o)
}

// Why `#[inline(always)]` here and down the per-frame path (`fit_tanh`, `level_frame`,
// `measure_frame`, the model fits, the dot products): `#[target_feature]` compiles only the
// body of `fit_frame_avx2_fma` for AVX2 and FMA. A function it calls that is not inlined into
// it stays compiled for the baseline x86-64 (SSE2), and the AVX2 path would be no faster; the
// tanh and dot-product passes only run four readings at a time when they are inlined into the
// AVX2 function.
#[inline(always)]
fn fit_frame_portable(x: &[f64], z: &[f64], o: &GrooveOptions) -> Vec<GrooveFit> {
    if o.template == TemplateKind::Tanh {
        let fit = fit_tanh(x, z, o);
        let measured = matches!(fit.status, GrooveStatus::Converged | GrooveStatus::MaxIterations);
        if measured && !o.limits.admit(fit.width, fit.depth) {
            return vec![GrooveFit::failed(GrooveStatus::NoGroove, fit.n_used as usize)];
        }
        return vec![fit];
    }
    let (lo, hi) = window_range(x.len().min(z.len()), o);
    measure_grooves(&x[lo..hi], &z[lo..hi], &section_settings(o)).0
}

/// The section models' settings from the options: the models `template` asks for (all four
/// for `Auto`).
fn section_settings(o: &GrooveOptions) -> MeasureSettings<'_> {
    const ALL: [SectionModel; 5] = SectionModel::ALL;
    let models: &[SectionModel] = match &o.template {
        TemplateKind::Section(m) => std::slice::from_ref(m),
        _ => &ALL,
    };
    MeasureSettings {
        models,
        spike_threshold: o.spike_threshold,
        min_depth: o.min_depth,
        min_valid: o.min_valid,
        criteria: o.criteria.section(),
        select: o.select,
        limits: o.limits,
    }
}

/// One frame as the fit sees it, for figures: the readings levelled
/// (`x' = cos θ·x + sin θ·z`, `z' = −sin θ·x + cos θ·z`), the fitted shape in the same
/// coordinates, and the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameView {
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    /// The fitted section or template, densely sampled (empty when nothing was fitted).
    pub shape_x: Vec<f64>,
    pub shape_z: Vec<f64>,
    pub tilt: f64,
    pub fit: GrooveFit,
}

/// Points along a shape: `samples` values of `f(t)` for t over `[lo, hi]`.
fn sample(lo: f64, hi: f64, samples: usize, f: impl Fn(f64) -> (f64, f64)) -> (Vec<f64>, Vec<f64>) {
    (0..samples).map(|i| f(lo + (hi - lo) * i as f64 / (samples - 1) as f64)).unzip()
}

/// [`FrameView`] of one frame (`x`, `z` of one frame, as for [`fit_frame`]).
pub fn view_frame(x: &[f64], z: &[f64], o: &GrooveOptions) -> Result<FrameView> {
    o.validate()?;
    if x.len() != z.len() {
        return Err(Error::shape("z", format!("({},): one value per x", x.len()), format!("({},)", z.len())));
    }
    let masked = o.valid.masked(z);
    let z = &masked[..];
    const SAMPLES: usize = 400;
    let empty = |fit: GrooveFit| FrameView {
        x: Vec::new(),
        z: Vec::new(),
        shape_x: Vec::new(),
        shape_z: Vec::new(),
        tilt: f64::NAN,
        fit,
    };
    if o.template == TemplateKind::Tanh {
        let (fit, detail) = fit_tanh_detailed(x, z, o);
        let Some((frame, p)) = detail else { return Ok(empty(fit)) };
        let (ox, oz) = frame.origin;
        let (lo, hi) = frame.x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        let t = TanhTemplate { x0: p[0], z0: p[1], depth: p[2], width: p[3], alpha: p[4] };
        let (shape_x, shape_z) = if fit.model == FitModel::None {
            (Vec::new(), Vec::new())
        } else {
            sample(lo, hi, SAMPLES, |u| (u + ox, t.value(u) + oz))
        };
        return Ok(FrameView {
            x: frame.x.iter().map(|v| v + ox).collect(),
            z: frame.z.iter().map(|v| v + oz).collect(),
            shape_x,
            shape_z,
            tilt: frame.tilt,
            fit,
        });
    }
    let (lo, hi) = window_range(x.len(), o);
    let (mut fit, detail) = super::measure::measure_frame_detailed(&x[lo..hi], &z[lo..hi], &section_settings(o));
    // One frame pools nothing: a given prior is used, else the frame's own rule.
    if let RoundingRule::Given(prior) = o.rounding {
        fit.settle_rounding(&prior);
    }
    if let MisfitRule::Given(prior) = o.misfit {
        fit.settle_misfit(&prior);
    }
    let Some(d) = detail else { return Ok(empty(fit)) };
    // Levelled as `v = −s·x + c·z − b·c`: the absolute levelled height adds b·c back.
    let lift = d.b * d.cos;
    let (shape_x, shape_z) = match d.shape {
        None => (Vec::new(), Vec::new()),
        Some((pieces, gamma)) => {
            let (ulo, uhi) = d.u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
            sample(ulo, uhi, SAMPLES, |u| {
                let v = pieces.value(u);
                (u + gamma * v, v + lift)
            })
        }
    };
    Ok(FrameView { z: d.v.iter().map(|v| v + lift).collect(), x: d.u, shape_x, shape_z, tilt: d.tilt, fit })
}

/// The fits of a batch of frames: a row per frame, or with `GrooveSelect::All` a row per
/// groove (and one for a frame without any), `frame` saying whose.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GrooveRows {
    pub frame: Vec<u32>,
    pub fits: Vec<GrooveFit>,
    /// The prior the V's tip rounding was settled with (None: each frame's own rule).
    pub rounding_prior: Option<RoundingPrior>,
    /// The misfit variances the depths' errors were settled with (None: `MisfitRule::None`).
    pub misfit: Option<MisfitPrior>,
}

/// All frames of `z (F, N)` row-major sharing the abscissae `x (N,)`, in parallel. Each frame
/// is fitted on its own, so the result is identical whatever the thread count; then, with
/// `RoundingRule::Pooled`, the V's depths are settled under the prior their profiles pool to
/// (from every k-th frame, [`pooled_stride`]), or under a given one; and with
/// `MisfitRule::Pooled` the depths' errors take the misfit their bottoms pool to (the same
/// frames), or a given one.
pub fn fit_frames(x: &[f64], z: &[f64], options: &GrooveOptions) -> Result<GrooveRows> {
    options.validate()?;
    let n = x.len();
    if n == 0 {
        return Err(Error::shape("x", "(N,) with N >= 1", "(0,)"));
    }
    if let Some(t) = options.window {
        if t > n {
            return Err(Error::invalid("window", format!("{t} readings, but the frames have only {n}")));
        }
    }
    if let Some(c) = options.window_center {
        if c >= n {
            return Err(Error::invalid(
                "window_center",
                format!("reading {c} does not exist: the frames have {n} readings"),
            ));
        }
    }
    if !z.len().is_multiple_of(n) {
        return Err(Error::shape("z", format!("(F, {n}): one column per x"), format!("{} values", z.len())));
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid("x", format!("must be finite, found {} at index {i}", x[i])));
    }
    let mut rows = GrooveRows::default();
    if options.select != GrooveSelect::All {
        rows.fits = z.par_chunks(n).map(|row| fit_frame(x, &options.valid.masked(row), options)).collect();
        rows.frame = (0..rows.fits.len() as u32).collect();
    } else {
        let per_frame: Vec<Vec<GrooveFit>> =
            z.par_chunks(n).map(|row| fit_frame_grooves(x, &options.valid.masked(row), options)).collect();
        for (f, fits) in per_frame.into_iter().enumerate() {
            rows.frame.extend(std::iter::repeat_n(f as u32, fits.len()));
            rows.fits.extend(fits);
        }
    }
    let stride = pooled_stride(z.len() / n) as u32;
    rows.rounding_prior = match options.rounding {
        RoundingRule::Pooled => {
            let curves: Vec<RoundingCurve> = pooled_fits(&rows, stride).filter_map(|g| g.rounding).collect();
            RoundingPrior::pooled(&curves)
        }
        RoundingRule::Frame => None,
        RoundingRule::Given(prior) => Some(prior),
    };
    if let Some(prior) = rows.rounding_prior {
        rows.fits.par_iter_mut().for_each(|f| f.settle_rounding(&prior));
    }
    // The misfit after the rounding: a depth the rounding settles has no bottom residual.
    rows.misfit = match options.misfit {
        MisfitRule::Pooled => {
            let (mut residuals, mut stretch): (Vec<BottomResidual>, Vec<StretchDifference>) = (vec![], vec![]);
            for g in pooled_fits(&rows, stride) {
                residuals.extend(g.misfit);
                stretch.extend(g.stretch);
            }
            Some(MisfitPrior::pooled(&residuals, &stretch))
        }
        MisfitRule::None => None,
        MisfitRule::Given(prior) => Some(prior),
    };
    if let Some(prior) = rows.misfit {
        rows.fits.par_iter_mut().for_each(|f| f.settle_misfit(&prior));
    }
    Ok(rows)
}

/// What a call pools over its frames is read from every `stride`-th frame: its rows (with
/// `GrooveSelect::All`, each of its grooves).
fn pooled_fits(rows: &GrooveRows, stride: u32) -> impl Iterator<Item = &GrooveFit> {
    rows.frame.iter().zip(&rows.fits).filter(move |(f, _)| **f % stride == 0).map(|(_, g)| g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::groove::options::GrooveStatus;
    use crate::groove::tanh::median5;
    use crate::testing::{gauss, lcg};

    /// The paper's template pipeline.
    fn tanh() -> GrooveOptions {
        GrooveOptions { template: TemplateKind::Tanh, ..GrooveOptions::default() }
    }

    #[test]
    fn median5_network_equals_sorting() {
        let mut seed = 11u64;
        for _ in 0..20000 {
            let mut v = [0.0; 5];
            for x in v.iter_mut() {
                *x = (lcg(&mut seed) * 7.0).floor();
            }
            let m = median5(v[0], v[1], v[2], v[3], v[4]);
            v.sort_by(f64::total_cmp);
            assert_eq!(m, v[2], "{v:?}");
        }
    }

    fn frame(truth: &TanhTemplate, tilt: f64, noise: f64, seed: &mut u64) -> (Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..200).map(|i| (i as f64 - 100.0) * 0.025).collect();
        let z = x.iter().map(|&x| truth.value(x) + tilt * x + noise * gauss(seed)).collect();
        (x, z)
    }

    #[test]
    fn recovers_exact_template() {
        let truth = TanhTemplate { x0: 0.137, z0: 0.05, depth: 0.31, width: 0.48, alpha: 20.0 };
        let mut seed = 1;
        let (x, z) = frame(&truth, 0.0, 0.0, &mut seed);
        let f = fit_frame(&x, &z, &tanh());
        assert_eq!(f.status, GrooveStatus::Converged);
        assert!((f.x0 - truth.x0).abs() < 1e-9, "{f:?}");
        assert!((f.depth - truth.depth).abs() < 1e-9);
        assert!((f.width - truth.width).abs() < 1e-9);
        assert!((f.z0 - truth.z0).abs() < 1e-9);
    }

    #[test]
    fn fits_alpha_when_asked() {
        let truth = TanhTemplate { x0: -0.2, z0: 0.0, depth: 0.3, width: 0.5, alpha: 12.0 };
        let mut seed = 2;
        let (x, z) = frame(&truth, 0.0, 0.0, &mut seed);
        let o = GrooveOptions { fit_alpha: true, ..tanh() };
        let f = fit_frame(&x, &z, &o);
        assert_eq!(f.status, GrooveStatus::Converged);
        assert!((f.alpha - 12.0).abs() < 1e-4, "{f:?}");
    }

    #[test]
    fn flat_frame_has_no_groove_and_short_frame_too_few() {
        let mut seed = 3;
        let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.025).collect();
        let z: Vec<f64> = x.iter().map(|_| 0.008 * gauss(&mut seed)).collect();
        let nan = vec![f64::NAN; 200];
        for o in [GrooveOptions::default(), tanh()] {
            assert_eq!(fit_frame(&x, &z, &o).status, GrooveStatus::NoGroove);
            assert_eq!(fit_frame(&x, &nan, &o).status, GrooveStatus::TooFewValid);
        }
    }

    #[test]
    fn two_grooves_flag_the_template_and_the_section_models_measure_the_deepest() {
        let a = TanhTemplate { x0: -1.2, z0: 0.0, depth: 0.3, width: 0.48, alpha: 20.0 };
        let b = TanhTemplate { x0: 1.3, z0: 0.0, depth: 0.28, width: 0.48, alpha: 20.0 };
        let x: Vec<f64> = (0..200).map(|i| (i as f64 - 100.0) * 0.025).collect();
        let z: Vec<f64> = x.iter().map(|&x| a.value(x) + b.value(x)).collect();
        assert_eq!(fit_frame(&x, &z, &tanh()).status, GrooveStatus::TwoGrooves);
        let f = fit_frame(&x, &z, &GrooveOptions::default());
        assert_eq!((f.status, f.groove), (GrooveStatus::Converged, 0), "{f:?}");
        assert!((f.x0 - a.x0).abs() < 0.01, "{f:?}");
        // A selection the template cannot make is refused, naming the option.
        let o = GrooveOptions { select: GrooveSelect::All, ..tanh() };
        assert!(fit_frames(&x, &z, &o).unwrap_err().to_string().contains("select"));
    }

    #[test]
    fn tilted_noisy_frames_in_parallel_equal_sequential() {
        let mut seed = 9;
        let mut z = Vec::new();
        let mut x = Vec::new();
        for k in 0..200 {
            let t = TanhTemplate { x0: 0.1 * lcg(&mut seed) - 0.05, z0: 0.0, depth: 0.31, width: 0.48, alpha: 20.0 };
            let (fx, fz) = frame(&t, 0.05 * (k as f64 / 200.0 - 0.5), 0.008, &mut seed);
            x = fx;
            z.extend(fz);
        }
        let o = tanh();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| fit_frames(&x, &z, &o).unwrap().fits)
        };
        let (a, b) = (run(1), run(2));
        for (p, q) in a.iter().zip(&b) {
            assert_eq!(p.status, q.status);
            assert_eq!(p.x0.to_bits(), q.x0.to_bits());
            assert_eq!(p.depth.to_bits(), q.depth.to_bits());
        }
        let ok = a.iter().filter(|f| f.status == GrooveStatus::Converged).count();
        assert_eq!(ok, 200);
        let mean_d = a.iter().map(|f| f.depth).sum::<f64>() / 200.0;
        assert!((mean_d - 0.31).abs() < 0.005, "{mean_d}");
    }
}
