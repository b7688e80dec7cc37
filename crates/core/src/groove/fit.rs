//! The batch groove fit: options, the per-frame result, and the paper's tanh template pipeline
//! (window → valid readings → spike filter → line fit → bottom point → surface refit without
//! the groove → levelling → LM template fit → back to the frame's own coordinates, SPEC G steps
//! 1–7). The default method, the section models, is `measure.rs`; `fit_frame` picks by
//! `GrooveOptions::template`.
use super::measure::{measure_frame, MeasureSettings, SECTION_CRITERIA};
use super::section::SectionModel;
use super::template::{gradient, tanh_pair, TanhTemplate};
use crate::error::{Error, Result};
use crate::kinematics::ValidReadings;
use crate::optim::{levenberg_marquardt, LeastSquares, LmOptions, LmStop};
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

/// What became of a frame. Codes are stable: they are what Python sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum GrooveStatus {
    /// The fit converged (small step, small gradient, or the paper's cost test).
    Converged = 0,
    /// The iteration limit was hit; the parameters are the best found.
    MaxIterations = 1,
    /// No dip deeper than `min_depth` (and 5× the surface noise) in the window, or the fit left
    /// the window or came out with a non-positive depth or width.
    NoGroove = 2,
    /// Fewer valid readings than `min_valid` in the window, or too few surface readings left.
    TooFewValid = 3,
    /// A second dip at least half as deep as the first lies in the window.
    TwoGrooves = 4,
    /// The groove touches the window edge: no surface on one side.
    Clipped = 5,
    /// The fit failed numerically, or ran away to a width outside ¼–4× the nominal width.
    Failed = 6,
}

/// How a frame's groove is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TemplateKind {
    /// The default: the four section models (trapezoid, V, round-bottomed V, U) fitted, the
    /// best by AIC chosen per frame; width and depth are the section's geometry.
    Auto,
    /// One section model only.
    Section(SectionModel),
    /// Paper 000 eq (11): a difference of two tanh steps (α = 20 mm⁻¹ in the paper); width and
    /// depth are the template's w and d. Fits rounded, U-like sections; on a straight-sided V
    /// it is ~18 % off in width and depth.
    Tanh,
}

impl TemplateKind {
    pub const NAMES: [&'static str; 6] = ["auto", "trapezoid", "v", "round", "u", "tanh"];

    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "auto" => TemplateKind::Auto,
            "tanh" => TemplateKind::Tanh,
            other => match SectionModel::ALL.iter().find(|m| m.name() == other) {
                Some(m) => TemplateKind::Section(*m),
                None => {
                    return Err(Error::invalid(
                        "template",
                        format!("expected one of {}, got {other:?}", Self::NAMES.map(|n| format!("{n:?}")).join(", ")),
                    ))
                }
            },
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            TemplateKind::Auto => "auto",
            TemplateKind::Tanh => "tanh",
            TemplateKind::Section(m) => m.name(),
        }
    }
}

/// What was fitted to a frame. Codes are stable: they are what Python sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FitModel {
    /// Nothing (the frame was not measured).
    None,
    Tanh,
    Section(SectionModel),
}

impl FitModel {
    pub fn code(self) -> u8 {
        match self {
            FitModel::None => 0,
            FitModel::Tanh => 1,
            FitModel::Section(SectionModel::Trapezoid) => 2,
            FitModel::Section(SectionModel::V) => 3,
            FitModel::Section(SectionModel::Round) => 4,
            FitModel::Section(SectionModel::U) => 5,
        }
    }
}

/// When the Levenberg–Marquardt fit of a frame stops; `None` takes the method's own default
/// (the paper's template: 100 iterations, step 1e-8 relative, gradient 1e-13, cost test off;
/// the section models: `measure::SECTION_CRITERIA`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FitCriteria {
    /// Iterations per fit (the section models: per model, half of it for the trapezoid that
    /// screens the frame first; a chosen model that has not converged gets three times as many
    /// more).
    pub max_iterations: Option<usize>,
    /// The template: paper 000's `½ Σ f² / t < ε`; the section models: the relative cost
    /// decrease of an accepted step below which the fit has converged.
    pub cost_tolerance: Option<f64>,
    /// The template: step relative to the parameters; the section models: the largest
    /// parameter move.
    pub step_tolerance: Option<f64>,
    /// `‖Jᵀf‖∞` below which the fit has converged.
    pub gradient_tolerance: Option<f64>,
}

/// The paper's template fit's defaults.
pub const TANH_CRITERIA: LmOptions =
    LmOptions { max_iterations: 100, cost_tolerance: 0.0, step_tolerance: 1e-8, gradient_tolerance: 1e-13, tau: 1e-6 };

impl FitCriteria {
    fn check(&self) -> Result<()> {
        for (name, v) in [
            ("step_tolerance", self.step_tolerance),
            ("gradient_tolerance", self.gradient_tolerance),
            ("cost_tolerance", self.cost_tolerance),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(Error::invalid(name, format!("must be >= 0, got {v}")));
                }
            }
        }
        Ok(())
    }

    pub fn tanh(&self) -> LmOptions {
        let d = TANH_CRITERIA;
        LmOptions {
            max_iterations: self.max_iterations.unwrap_or(d.max_iterations),
            cost_tolerance: self.cost_tolerance.unwrap_or(d.cost_tolerance),
            step_tolerance: self.step_tolerance.unwrap_or(d.step_tolerance),
            gradient_tolerance: self.gradient_tolerance.unwrap_or(d.gradient_tolerance),
            tau: d.tau,
        }
    }

    pub fn section(&self) -> crate::optim::BoundedLmOptions {
        let d = SECTION_CRITERIA;
        crate::optim::BoundedLmOptions {
            max_iterations: self.max_iterations.unwrap_or(d.max_iterations),
            cost_tolerance: self.cost_tolerance.unwrap_or(d.cost_tolerance),
            step_tolerance: self.step_tolerance.unwrap_or(d.step_tolerance),
            gradient_tolerance: self.gradient_tolerance.unwrap_or(d.gradient_tolerance),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrooveOptions {
    /// How the groove is measured.
    pub template: TemplateKind,
    /// The tanh template's shape coefficient α, mm⁻¹ (paper 000: 20, chosen by eye).
    pub alpha: f64,
    /// Fit α as a fifth parameter of the tanh template, starting from `alpha`.
    pub fit_alpha: bool,
    /// Nominal groove width l, mm, of the tanh template pipeline: the readings within l of the
    /// bottom are left out of its surface refit. The section models find the groove's extent
    /// from the data and do not use it.
    pub nominal_width: f64,
    /// Number t of readings kept around `window_center`; `None` keeps them all.
    pub window: Option<usize>,
    /// Reading index the window is centered on; `None` = N/2.
    pub window_center: Option<usize>,
    /// Drop a reading deviating more than this from the median of its 5-reading neighborhood
    /// (mm); `None` disables the spike filter.
    pub spike_threshold: Option<f64>,
    /// Shallowest dip that counts as a groove, mm.
    pub min_depth: f64,
    /// Fewest valid readings in the window.
    pub min_valid: usize,
    /// When each fit stops.
    pub criteria: FitCriteria,
    /// Which readings are valid: the others (NaN, the vendor's no-reading code, outside the
    /// measuring range) are left out, by the rule every function that takes frames applies.
    pub valid: ValidReadings,
}

impl Default for GrooveOptions {
    fn default() -> Self {
        GrooveOptions {
            template: TemplateKind::Auto,
            alpha: 20.0,
            fit_alpha: false,
            nominal_width: 0.5,
            window: None,
            window_center: None,
            spike_threshold: Some(0.1),
            min_depth: 0.03,
            min_valid: 12,
            criteria: FitCriteria::default(),
            valid: ValidReadings::default(),
        }
    }
}

impl GrooveOptions {
    pub fn validate(&self) -> Result<()> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(name, format!("must be a positive number, got {v}")))
            }
        };
        positive("alpha", self.alpha)?;
        positive("nominal_width", self.nominal_width)?;
        if !(self.min_depth.is_finite() && self.min_depth >= 0.0) {
            return Err(Error::invalid("min_depth", format!("must be >= 0 mm, got {}", self.min_depth)));
        }
        if let Some(s) = self.spike_threshold {
            positive("spike_threshold", s)?;
        }
        if self.window == Some(0) {
            return Err(Error::invalid("window", "must hold at least one reading"));
        }
        self.criteria.check()
    }
}

/// The result for one frame. Positions are in the frame's own coordinates (the x, z given);
/// for a frame that could not be fitted they are NaN and `status` says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrooveFit {
    /// Groove center x0 and surface height z0 there, mm.
    pub x0: f64,
    pub z0: f64,
    /// Depth and width, mm: the section's deepest point below the surface line and the
    /// distance between its flanks at the surface line; the tanh template's d and w.
    pub depth: f64,
    pub width: f64,
    /// The tanh template's α used or fitted, mm⁻¹ (NaN for the section models).
    pub alpha: f64,
    /// Residual RMS of the fit, mm.
    pub rms: f64,
    /// Standard errors of depth and width from `σ̂² (JᵀJ)⁻¹`, mm.
    pub se_depth: f64,
    pub se_width: f64,
    /// Surface slope angle θ used for levelling, rad.
    pub tilt: f64,
    pub iterations: u32,
    /// Readings used in the fit.
    pub n_used: u32,
    pub status: GrooveStatus,
    /// What was fitted.
    pub model: FitModel,
}

impl GrooveFit {
    pub(super) fn failed(status: GrooveStatus, n_used: usize) -> Self {
        GrooveFit {
            x0: f64::NAN,
            z0: f64::NAN,
            depth: f64::NAN,
            width: f64::NAN,
            alpha: f64::NAN,
            rms: f64::NAN,
            se_depth: f64::NAN,
            se_width: f64::NAN,
            tilt: f64::NAN,
            iterations: 0,
            n_used: n_used as u32,
            status,
            model: FitModel::None,
        }
    }
}

/// Least-squares line `z = k x + b` (None when x is constant).
#[inline(always)]
pub(super) fn fit_line(x: impl Iterator<Item = (f64, f64)> + Clone) -> Option<(f64, f64)> {
    let (mut n, mut sx, mut sz) = (0.0, 0.0, 0.0);
    for (xi, zi) in x.clone() {
        n += 1.0;
        sx += xi;
        sz += zi;
    }
    if n < 2.0 {
        return None;
    }
    let (mx, mz) = (sx / n, sz / n);
    let (mut sxx, mut sxz) = (0.0, 0.0);
    for (xi, zi) in x {
        sxx += (xi - mx) * (xi - mx);
        sxz += (xi - mx) * (zi - mz);
    }
    if sxx <= 0.0 {
        return None;
    }
    let k = sxz / sxx;
    Some((k, mz - k * mx))
}

/// Keeps the pairs `(a[i], b[i])` where `keep[i]`, in place.
pub(super) fn retain_pairs(a: &mut Vec<f64>, b: &mut Vec<f64>, keep: &[bool]) {
    let mut j = 0;
    for i in 0..a.len() {
        if keep[i] {
            a[j] = a[i];
            b[j] = b[i];
            j += 1;
        }
    }
    a.truncate(j);
    b.truncate(j);
}

/// Levelled points and the template problem on them; `P` = 4 (α fixed) or 5 (α fitted).
///
/// Evaluation is split into element-wise passes over the frame (tanh terms, residuals, template
/// gradient columns) that the compiler vectorises, and dot products with four explicit partial
/// sums for JᵀJ and Jᵀf. The summation order is fixed, so results do not depend on threads.
struct TemplateProblem<'a> {
    x: &'a [f64],
    z: &'a [f64],
    alpha: f64,
    scratch: std::cell::RefCell<Scratch>,
}

/// Per-frame work arrays: the two tanh terms, the residuals, the template gradient columns.
struct Scratch {
    a: Vec<f64>,
    b: Vec<f64>,
    f: Vec<f64>,
    grad: [Vec<f64>; 5],
}

/// Σ a·b with four partial sums (vectorises; fixed order).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// Σ a with four partial sums.
#[inline(always)]
fn sum(a: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let ca = a.chunks_exact(4);
    let ra = ca.remainder();
    for x in ca {
        for l in 0..4 {
            acc[l] += x[l];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + ra.iter().sum::<f64>()
}

impl<'a> TemplateProblem<'a> {
    fn new(x: &'a [f64], z: &'a [f64], alpha: f64) -> Self {
        let n = x.len();
        let v = || vec![0.0; n];
        let scratch = Scratch { a: v(), b: v(), f: v(), grad: [v(), v(), v(), v(), v()] };
        TemplateProblem { x, z, alpha, scratch: std::cell::RefCell::new(scratch) }
    }

    #[inline(always)]
    fn template(&self, p: &[f64]) -> TanhTemplate {
        TanhTemplate {
            x0: p[0],
            z0: p[1],
            depth: p[2],
            width: p[3],
            alpha: if p.len() > 4 { p[4] } else { self.alpha },
        }
    }

    /// Fills `a`, `b` with `tanh(α(x − x0 ∓ w/4))` and `f` with the residuals; returns ½Σf².
    #[inline(always)]
    fn residuals(&self, t: &TanhTemplate, s: &mut Scratch) -> f64 {
        let (q, hd, al, x0, z0) = (0.25 * t.width, 0.5 * t.depth, t.alpha, t.x0, t.z0);
        for (x, (a, b)) in self.x.iter().zip(s.a.iter_mut().zip(s.b.iter_mut())) {
            (*a, *b) = tanh_pair(al * (x - x0 - q), al * (x - x0 + q));
        }
        for ((f, z), (a, b)) in s.f.iter_mut().zip(self.z).zip(s.a.iter().zip(&s.b)) {
            *f = z - z0 - hd * (a - b);
        }
        0.5 * dot(&s.f, &s.f)
    }

    #[inline(always)]
    fn normal_equations_of<const P: usize>(&self, p: &[f64]) -> (SMatrix<f64, P, P>, SVector<f64, P>, f64) {
        let t = self.template(p);
        let mut guard = self.scratch.borrow_mut();
        let s = &mut *guard;
        let cost = self.residuals(&t, s);
        let (hd, q, al) = (0.5 * t.depth, 0.25 * t.width, t.alpha);
        // ∂T/∂p of eq (15), and ∂T/∂α; the z0 column is all ones and is not stored.
        let [g0, _, g2, g3, g4] = &mut s.grad;
        let ab = s.a.iter().zip(&s.b);
        for ((((a, b), x), g0), ((g2, g3), g4)) in
            ab.zip(self.x).zip(g0.iter_mut()).zip(g2.iter_mut().zip(g3.iter_mut()).zip(g4.iter_mut()))
        {
            let g = gradient(*a, *b, hd, al, x - t.x0, q);
            (*g0, *g2, *g3, *g4) = (g[0], g[2], g[3], g[4]);
        }
        let n = self.x.len() as f64;
        let col = |k: usize| -> Option<&[f64]> {
            if k == 1 {
                None
            } else {
                Some(&s.grad[k][..])
            }
        };
        let mut jtj = SMatrix::<f64, P, P>::zeros();
        let mut g = SVector::<f64, P>::zeros();
        for r in 0..P {
            // ∂f/∂p = −∂T/∂p: JᵀJ is sign-free, Jᵀf flips.
            g[r] = -match col(r) {
                Some(c) => dot(c, &s.f),
                None => sum(&s.f),
            };
            for c in r..P {
                let v = match (col(r), col(c)) {
                    (Some(x), Some(y)) => dot(x, y),
                    (Some(x), None) | (None, Some(x)) => sum(x),
                    (None, None) => n,
                };
                jtj[(r, c)] = v;
                jtj[(c, r)] = v;
            }
        }
        (jtj, g, cost)
    }
}

/// Runs LM with 4 or 5 parameters: `(params [x0, z0, d, w, shape], cost, iterations, stop,
/// var(d), var(w))` with the variances from (JᵀJ)⁻¹ (to be scaled by σ̂²).
#[inline(always)]
fn solve<Prob: LeastSquares<4> + LeastSquares<5>>(
    problem: &Prob,
    start: [f64; 5],
    fit_shape: bool,
    lm: &LmOptions,
) -> (Vec<f64>, f64, usize, LmStop, f64, f64) {
    if fit_shape {
        let r = levenberg_marquardt::<5, _>(problem, SVector::from(start), lm);
        let (cd, cw) = r.jtj.try_inverse().map_or((f64::INFINITY, f64::INFINITY), |m| (m[(2, 2)], m[(3, 3)]));
        (r.x.as_slice().to_vec(), r.cost, r.iterations, r.stop, cd, cw)
    } else {
        let r = levenberg_marquardt::<4, _>(problem, SVector::from([start[0], start[1], start[2], start[3]]), lm);
        let (cd, cw) = r.jtj.try_inverse().map_or((f64::INFINITY, f64::INFINITY), |m| (m[(2, 2)], m[(3, 3)]));
        let mut v = r.x.as_slice().to_vec();
        v.push(start[4]);
        (v, r.cost, r.iterations, r.stop, cd, cw)
    }
}

impl LeastSquares<4> for TemplateProblem<'_> {
    #[inline(always)]
    fn len(&self) -> usize {
        self.x.len()
    }
    #[inline(always)]
    fn normal_equations(&self, p: &SVector<f64, 4>) -> (SMatrix<f64, 4, 4>, SVector<f64, 4>, f64) {
        self.normal_equations_of::<4>(p.as_slice())
    }
}

impl LeastSquares<5> for TemplateProblem<'_> {
    fn len(&self) -> usize {
        self.x.len()
    }
    #[inline(always)]
    fn normal_equations(&self, p: &SVector<f64, 5>) -> (SMatrix<f64, 5, 5>, SVector<f64, 5>, f64) {
        self.normal_equations_of::<5>(p.as_slice())
    }
}

/// Median of three, branch-free.
#[inline(always)]
fn median3(x: f64, y: f64, z: f64) -> f64 {
    x.min(y).max(x.max(y).min(z))
}

/// Median of five with min/max only (no sort): of the two pairs (a, b) and (c, d) the overall
/// smallest and largest cannot be the median, which leaves a median of three.
#[inline(always)]
fn median5(a: f64, b: f64, c: f64, d: f64, e: f64) -> f64 {
    median3(e, a.min(b).max(c.min(d)), a.max(b).min(c.max(d)))
}

/// A frame made ready for the template fit (SPEC G steps 1–4 and the initial guess).
#[derive(Debug, Clone, PartialEq)]
pub struct LevelledFrame {
    /// Levelled readings, relative to `origin`, mm.
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    /// Levelled coordinates of the local origin (the bottom x and the surface mean z).
    pub origin: (f64, f64),
    /// Surface slope angle θ = atan k2, rad: `x' = cos θ·x + sin θ·z`, `z' = −sin θ·x + cos θ·z`.
    pub tilt: f64,
    /// Initial guess `[x0, z0, d, w, α]` in the local levelled coordinates.
    pub start: [f64; 5],
}

/// Steps 1–4 of SPEC G: window, valid readings, spikes, line fit, bottom, surface refit,
/// levelling, initial guess. `Err` carries the status of a frame that cannot be fitted and the
/// number of readings it had.
#[inline(always)]
pub fn level_frame(
    x: &[f64],
    z: &[f64],
    o: &GrooveOptions,
) -> std::result::Result<LevelledFrame, (GrooveStatus, usize)> {
    let n = x.len().min(z.len());
    // 1. Window of t readings around the center, valid readings only.
    let (lo, hi) = window_range(n, o);
    let mut px = Vec::with_capacity(hi - lo);
    let mut pz = Vec::with_capacity(hi - lo);
    for i in lo..hi {
        if z[i].is_finite() && x[i].is_finite() {
            px.push(x[i]);
            pz.push(z[i]);
        }
    }
    if px.len() < o.min_valid.max(6) {
        return Err((GrooveStatus::TooFewValid, px.len()));
    }
    // Spike filter: a reading far from the median of its neighbors is an outlier.
    if let Some(th) = o.spike_threshold {
        // Median of the five readings around i (the window slides inward at the ends).
        let n_p = px.len();
        let keep: Vec<bool> = (0..n_p)
            .map(|i| {
                let a = i.saturating_sub(2).min(n_p - 5);
                let w = &pz[a..a + 5];
                (pz[i] - median5(w[0], w[1], w[2], w[3], w[4])).abs() <= th
            })
            .collect();
        retain_pairs(&mut px, &mut pz, &keep);
        if px.len() < o.min_valid.max(6) {
            return Err((GrooveStatus::TooFewValid, px.len()));
        }
    }
    // 2. Line through all points; the bottom is the point deepest below it (a groove is a dip).
    let Some((k1, b1)) = fit_line(px.iter().copied().zip(pz.iter().copied())) else {
        return Err((GrooveStatus::TooFewValid, px.len()));
    };
    // The depth below the line is averaged over 5 readings first: a groove is ~20 readings
    // wide, a spike the spike filter let through is one or two, and must not win.
    let below_line: Vec<f64> = (0..px.len()).map(|i| k1 * px[i] + b1 - pz[i]).collect();
    let (mut ib, mut below) = (0, f64::NEG_INFINITY);
    for i in 0..px.len() {
        let a = i.saturating_sub(2).min(px.len() - 5);
        let d = below_line[a..a + 5].iter().sum::<f64>() / 5.0;
        if d > below {
            below = d;
            ib = i;
        }
    }
    // The bottom reading itself: the deepest of the five.
    let a = ib.saturating_sub(2).min(px.len() - 5);
    ib = (a..a + 5).max_by(|&i, &j| below_line[i].total_cmp(&below_line[j])).unwrap_or(ib);
    if below < o.min_depth {
        return Err((GrooveStatus::NoGroove, px.len()));
    }
    let xd = px[ib];
    // 3. Surface refit without the l readings' width on each side of the bottom.
    let l = o.nominal_width;
    let surface = || px.iter().copied().zip(pz.iter().copied()).filter(move |(x, _)| (x - xd).abs() > l);
    let (n_left, n_right) = surface().fold((0, 0), |(a, b), (x, _)| if x < xd { (a + 1, b) } else { (a, b + 1) });
    if n_left + n_right < 4 {
        return Err((GrooveStatus::TooFewValid, px.len()));
    }
    if n_left < 2 || n_right < 2 {
        return Err((GrooveStatus::Clipped, px.len()));
    }
    let Some((k2, b2)) = fit_line(surface()) else {
        return Err((GrooveStatus::TooFewValid, px.len()));
    };
    // Surface noise (robust: 1.4826 · median |r|, so a second groove does not inflate it) and
    // the deepest second dip, both measured on the surface points.
    let mut abs_r: Vec<f64> = surface().map(|(x, z)| (k2 * x + b2 - z).abs()).collect();
    let deepest_other = surface().map(|(x, z)| k2 * x + b2 - z).fold(0.0f64, f64::max);
    let mid = abs_r.len() / 2;
    let sigma = 1.4826 * *abs_r.select_nth_unstable_by(mid, f64::total_cmp).1;
    let depth0 = k2 * xd + b2 - pz[ib];
    if depth0 < o.min_depth.max(5.0 * sigma) {
        return Err((GrooveStatus::NoGroove, px.len()));
    }
    if deepest_other > 0.5 * depth0 && deepest_other > o.min_depth.max(5.0 * sigma) {
        return Err((GrooveStatus::TwoGrooves, px.len()));
    }
    // 4. Level: rotate by −θ so the surface runs along x' (eq 13).
    let theta = k2.atan();
    let (s, c) = theta.sin_cos();
    let lx: Vec<f64> = px.iter().zip(&pz).map(|(&x, &z)| c * x + s * z).collect();
    let lz: Vec<f64> = px.iter().zip(&pz).map(|(&x, &z)| -s * x + c * z).collect();
    // 5. Initial guess: x0 at the bottom, z0 the levelled surface mean, d the bottom depth, w = l.
    let (mut zsum, mut zn) = (0.0, 0.0);
    for i in 0..lx.len() {
        if (px[i] - xd).abs() > l {
            zsum += lz[i];
            zn += 1.0;
        }
    }
    // Fit in coordinates centered on the start (bottom x, surface z), so the relative step test
    // measures the groove, not how far the frame sits from the sensor origin.
    let (ox, oz) = (lx[ib], zsum / zn);
    let lx: Vec<f64> = lx.iter().map(|v| v - ox).collect();
    let lz: Vec<f64> = lz.iter().map(|v| v - oz).collect();
    // Width start: twice the distance between the half-depth crossings on either side of the
    // bottom (a V, and the template, are w/2 wide at half depth); the nominal width when the
    // crossings are not found within it.
    let half = 0.5 * lz[ib];
    let crossing = |step: isize| -> Option<f64> {
        let mut i = ib as isize;
        while i + step >= 0 && ((i + step) as usize) < lx.len() {
            let j = (i + step) as usize;
            if lz[j] >= half {
                let (a, b) = (i as usize, j);
                let t = (half - lz[a]) / (lz[b] - lz[a]);
                return Some(lx[a] + t * (lx[b] - lx[a]));
            }
            if (lx[j] - lx[ib]).abs() > l {
                return None;
            }
            i += step;
        }
        None
    };
    let w0 = match (crossing(-1), crossing(1)) {
        (Some(a), Some(b)) if b > a => (2.0 * (b - a)).clamp(0.5 * l, 2.0 * l),
        _ => l,
    };
    let start = [0.0, 0.0, -lz[ib], w0, o.alpha];
    Ok(LevelledFrame { x: lx, z: lz, origin: (ox, oz), tilt: theta, start })
}

/// Fit one frame: `x` reading abscissae, `z` readings (NaN = invalid), same length.
///
/// On x86-64 CPUs with AVX2 and FMA the same code runs compiled for them (chosen at run time,
/// the same choice for every frame on a machine, so results never depend on the thread count):
/// the tanh and dot-product passes then run four readings at a time.
pub fn fit_frame(x: &[f64], z: &[f64], o: &GrooveOptions) -> GrooveFit {
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
unsafe fn fit_frame_avx2_fma(x: &[f64], z: &[f64], o: &GrooveOptions) -> GrooveFit {
    fit_frame_portable(x, z, o)
}

#[inline(always)]
fn fit_frame_portable(x: &[f64], z: &[f64], o: &GrooveOptions) -> GrooveFit {
    if o.template == TemplateKind::Tanh {
        return fit_tanh(x, z, o);
    }
    let (lo, hi) = window_range(x.len().min(z.len()), o);
    measure_frame(&x[lo..hi], &z[lo..hi], &section_settings(o))
}

/// The section models' settings from the options: the models `template` asks for (all four
/// for `Auto`).
fn section_settings(o: &GrooveOptions) -> MeasureSettings<'_> {
    const ALL: [SectionModel; 4] = SectionModel::ALL;
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
    }
}

/// The readings `[lo, hi)` of the window of `o.window` readings around `o.window_center`.
pub(super) fn window_range(n: usize, o: &GrooveOptions) -> (usize, usize) {
    match o.window {
        None => (0, n),
        Some(t) => {
            let c = o.window_center.unwrap_or(n / 2).min(n);
            let lo = c.saturating_sub(t / 2);
            (lo, (lo + t).min(n))
        }
    }
}

/// The paper's pipeline: SPEC G steps 1–7 with the tanh template.
#[inline(always)]
fn fit_tanh(x: &[f64], z: &[f64], o: &GrooveOptions) -> GrooveFit {
    fit_tanh_detailed(x, z, o).0
}

/// [`fit_tanh`] with the levelled frame and the fitted template parameters (levelled, relative
/// to the frame's origin) for drawing.
#[inline(always)]
fn fit_tanh_detailed(x: &[f64], z: &[f64], o: &GrooveOptions) -> (GrooveFit, Option<(LevelledFrame, Vec<f64>)>) {
    let frame = match level_frame(x, z, o) {
        Ok(f) => f,
        Err((status, n)) => return (GrooveFit::failed(status, n), None),
    };
    let (lx, lz, (ox, oz), start) = (&frame.x, &frame.z, frame.origin, frame.start);
    let (s, c) = frame.tilt.sin_cos();
    let theta = frame.tilt;
    let lm = o.criteria.tanh();
    let (p, cost, iterations, stop, cov_d, cov_w) =
        solve(&TemplateProblem::new(lx, lz, o.alpha), start, o.fit_alpha, &lm);
    let m = lx.len();
    let n_par = if o.fit_alpha { 5 } else { 4 };
    let xmin = lx.iter().copied().fold(f64::INFINITY, f64::min);
    let xmax = lx.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let status = match stop {
        LmStop::Failed => GrooveStatus::Failed,
        _ if !(p[2] > 0.0 && p[3] > 0.0 && p[4] > 0.0) || p[0] < xmin || p[0] > xmax => GrooveStatus::NoGroove,
        // A width far from the nominal one is a fit that locked onto something else (a spike,
        // a dropout edge) and ran away.
        _ if p[3] < 0.25 * o.nominal_width || p[3] > 4.0 * o.nominal_width => GrooveStatus::Failed,
        _ if p.iter().any(|v| !v.is_finite()) => GrooveStatus::Failed,
        LmStop::MaxIterations => GrooveStatus::MaxIterations,
        _ => GrooveStatus::Converged,
    };
    if matches!(status, GrooveStatus::Failed | GrooveStatus::NoGroove) {
        return (GrooveFit::failed(status, m), Some((frame, p)));
    }
    let sigma2 = 2.0 * cost / (m.saturating_sub(n_par).max(1)) as f64;
    // 7. Back to the frame's coordinates (inverse of eq 13).
    let (x0, z0) = (p[0] + ox, p[1] + oz);
    let fit = GrooveFit {
        x0: c * x0 - s * z0,
        z0: s * x0 + c * z0,
        depth: p[2],
        width: p[3],
        alpha: p[4],
        rms: (2.0 * cost / m as f64).sqrt(),
        se_depth: (sigma2 * cov_d).sqrt(),
        se_width: (sigma2 * cov_w).sqrt(),
        tilt: theta,
        iterations: iterations as u32,
        n_used: m as u32,
        status,
        model: FitModel::Tanh,
    };
    (fit, Some((frame, p)))
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
    let (fit, detail) = super::measure::measure_frame_detailed(&x[lo..hi], &z[lo..hi], &section_settings(o));
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

/// All frames of `z (F, N)` row-major sharing the abscissae `x (N,)`, in parallel. Each frame
/// is fitted on its own, so the result is identical whatever the thread count.
pub fn fit_frames(x: &[f64], z: &[f64], options: &GrooveOptions) -> Result<Vec<GrooveFit>> {
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
    Ok(z.par_chunks(n).map(|row| fit_frame(x, &options.valid.masked(row), options)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

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

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
    }

    fn gauss(seed: &mut u64) -> f64 {
        let (u, v) = (lcg(seed).max(1e-300), lcg(seed));
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
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
    fn two_grooves_are_flagged() {
        let a = TanhTemplate { x0: -1.2, z0: 0.0, depth: 0.3, width: 0.48, alpha: 20.0 };
        let b = TanhTemplate { x0: 1.3, z0: 0.0, depth: 0.28, width: 0.48, alpha: 20.0 };
        let x: Vec<f64> = (0..200).map(|i| (i as f64 - 100.0) * 0.025).collect();
        let z: Vec<f64> = x.iter().map(|&x| a.value(x) + b.value(x)).collect();
        for o in [GrooveOptions::default(), tanh()] {
            let f = fit_frame(&x, &z, &o);
            assert_eq!(f.status, GrooveStatus::TwoGrooves, "{f:?}");
        }
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
                .install(|| fit_frames(&x, &z, &o).unwrap())
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
