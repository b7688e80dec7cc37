//! The groove fit's options (one `Default` for every default), the per-frame result and its
//! status codes.
use super::measure::SECTION_CRITERIA;
use super::section::SectionModel;
use crate::error::{Error, Result};
use crate::kinematics::ValidReadings;
use crate::optim::LmOptions;

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
    /// A second dip at least half as deep as the first lies in the window (the tanh template;
    /// the section models find every groove and measure the one `select` asks for).
    TwoGrooves = 4,
    /// The groove touches the window edge: no surface on one side.
    Clipped = 5,
    /// The fit failed numerically, or ran away to a width outside ¼–4× the nominal width.
    Failed = 6,
}

/// How a frame's groove is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TemplateKind {
    /// The default: the section models (trapezoid, V, round-bottomed V, U, elliptic U) fitted,
    /// the best by AIC chosen per frame; width and depth are the section's geometry.
    Auto,
    /// One section model only.
    Section(SectionModel),
    /// Paper 000 eq (11): a difference of two tanh steps (α = 20 mm⁻¹ in the paper); width and
    /// depth are the template's w and d. Fits rounded, U-like sections; on a straight-sided V
    /// it is ~18 % off in width and depth.
    Tanh,
}

impl TemplateKind {
    pub const NAMES: [&'static str; 7] = ["auto", "trapezoid", "v", "round", "u", "ellipse", "tanh"];

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
            FitModel::Section(SectionModel::Ellipse) => 6,
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

/// Which of a frame's grooves are measured. Grooves are dips deeper than `min_depth` and the
/// surface noise, found by walking from each bottom out to the surface (or to the corner it
/// shares with a neighbour); those measured outside the validity limits do not count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GrooveSelect {
    /// The deepest (the default).
    Deepest,
    /// The n-th from the left (0 = the leftmost), counting grooves within the limits.
    Left(usize),
    /// The n-th from the right.
    Right(usize),
    /// The one whose bottom is nearest this x (in the frame's own coordinates, mm).
    Nearest(f64),
    /// Every groove: a row per groove, left to right.
    All,
}

impl GrooveSelect {
    pub const NAMES: [&'static str; 5] = ["deepest", "left", "right", "nearest", "all"];

    /// The selection named `name`, with the `index` of "left"/"right" and the `near` x of
    /// "nearest" (each refused where it has no meaning, so a mistyped call is not silently
    /// another selection).
    pub fn parse(name: &str, index: usize, near: Option<f64>) -> Result<Self> {
        let select = match name {
            "deepest" => GrooveSelect::Deepest,
            "left" => GrooveSelect::Left(index),
            "right" => GrooveSelect::Right(index),
            "all" => GrooveSelect::All,
            "nearest" => match near {
                Some(x) if x.is_finite() => GrooveSelect::Nearest(x),
                Some(x) => return Err(Error::invalid("near", format!("must be a finite x, mm, got {x}"))),
                None => return Err(Error::invalid("near", "select=\"nearest\" needs the x to be near, mm")),
            },
            other => {
                return Err(Error::invalid(
                    "select",
                    format!("expected one of {}, got {other:?}", Self::NAMES.map(|n| format!("{n:?}")).join(", ")),
                ))
            }
        };
        if index != 0 && !matches!(select, GrooveSelect::Left(_) | GrooveSelect::Right(_)) {
            return Err(Error::invalid(
                "index",
                format!("counts grooves for select=\"left\" or \"right\", not {name:?}"),
            ));
        }
        if near.is_some() && !matches!(select, GrooveSelect::Nearest(_)) {
            return Err(Error::invalid("near", format!("is for select=\"nearest\", not {name:?}")));
        }
        Ok(select)
    }

    pub fn name(self) -> &'static str {
        match self {
            GrooveSelect::Deepest => "deepest",
            GrooveSelect::Left(_) => "left",
            GrooveSelect::Right(_) => "right",
            GrooveSelect::Nearest(_) => "nearest",
            GrooveSelect::All => "all",
        }
    }
}

/// Validity limits: a groove measured outside them is not a groove of the part (a scratch, a
/// neighbouring feature); `None` = no limit. `min_depth` is the options' own.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GrooveLimits {
    pub min_width: Option<f64>,
    pub max_width: Option<f64>,
    pub max_depth: Option<f64>,
}

impl GrooveLimits {
    fn check(&self, min_depth: f64) -> Result<()> {
        for (name, v) in [("min_width", self.min_width), ("max_width", self.max_width), ("max_depth", self.max_depth)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::invalid(name, format!("must be a positive width or depth, mm, got {v}")));
                }
            }
        }
        if let (Some(lo), Some(hi)) = (self.min_width, self.max_width) {
            if lo > hi {
                return Err(Error::invalid("max_width", format!("{hi} mm is below min_width {lo} mm")));
            }
        }
        if let Some(hi) = self.max_depth {
            if hi < min_depth {
                return Err(Error::invalid("max_depth", format!("{hi} mm is below min_depth {min_depth} mm")));
            }
        }
        Ok(())
    }

    /// Whether a measured width and depth lie within the limits.
    pub fn admit(&self, width: f64, depth: f64) -> bool {
        self.min_width.is_none_or(|lo| width >= lo)
            && self.max_width.is_none_or(|hi| width <= hi)
            && self.max_depth.is_none_or(|hi| depth <= hi)
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
    /// Which grooves of a frame are measured.
    pub select: GrooveSelect,
    /// What counts as a groove beyond `min_depth`.
    pub limits: GrooveLimits,
    /// How a V's tip rounding is settled ([`RoundingRule`]).
    pub rounding: RoundingRule,
    /// How the misfit of the chosen section at the bottom enters the depth's error
    /// ([`MisfitRule`]).
    pub misfit: MisfitRule,
}

/// How the misfit one frame cannot tell from its noise enters the standard errors: a section's
/// at its groove's bottom (the depth's), a U's against the ellipse (its measures')
/// (docs/grooves.md, step 11; [`super::misfit`]).
// The given prior is some 250 bytes, the other rules none: boxed, the options would no longer
// be `Copy`, and they are copied once per call, not per frame.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum MisfitRule {
    /// Its variance pooled over the call's frames per model chosen (from every k-th frame, as
    /// the rounding prior); a model chosen in fewer than [`super::misfit::MIN_POOLED`] of them
    /// is left as it is.
    #[default]
    Pooled,
    /// None: the errors of the models alone.
    None,
    /// These variances (a pooled call's, to measure its parts or one frame alike).
    Given(super::MisfitPrior),
}

impl MisfitRule {
    /// "pooled" or "none" (given variances have no name).
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "pooled" => Ok(Self::Pooled),
            "none" => Ok(Self::None),
            other => Err(Error::invalid(
                "misfit",
                format!("expected \"pooled\", \"none\" or variances by model name (mm²), got {other:?}"),
            )),
        }
    }

    /// The name [`MisfitRule::parse`] reads; "given" for given variances.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Pooled => "pooled",
            Self::None => "none",
            Self::Given(_) => "given",
        }
    }
}

/// How a V's tip rounding, which one frame's readings cannot tell from a sharp tip, is
/// settled (docs/grooves.md, step 9).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum RoundingRule {
    /// A prior pooled over the call's V's ([`super::RoundingPrior::pooled`], from every k-th
    /// frame, at most [`super::rounding::POOLED_FRAMES`]); each frame's own rule where fewer
    /// than [`super::rounding::MIN_POOLED`] V's are among them.
    #[default]
    Pooled,
    /// Each frame on its own: the Akaike average of the sharp and the round V.
    Frame,
    /// This prior (a process the plant knows, or one a pooled call reported).
    Given(super::RoundingPrior),
}

impl RoundingRule {
    /// "pooled" or "frame" (a given prior has no name).
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "pooled" => Ok(Self::Pooled),
            "frame" => Ok(Self::Frame),
            other => Err(Error::invalid(
                "rounding",
                format!("expected \"pooled\", \"frame\" or (share, r_max) with r_max in mm, got {other:?}"),
            )),
        }
    }

    /// The name [`RoundingRule::parse`] reads; "given" for a given prior.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Pooled => "pooled",
            Self::Frame => "frame",
            Self::Given(_) => "given",
        }
    }
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
            select: GrooveSelect::Deepest,
            limits: GrooveLimits::default(),
            rounding: RoundingRule::Pooled,
            misfit: MisfitRule::Pooled,
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
        if self.template == TemplateKind::Tanh && self.select != GrooveSelect::Deepest {
            return Err(Error::invalid(
                "select",
                format!(
                    "{:?} needs the section models: the tanh template measures one groove per frame",
                    self.select.name()
                ),
            ));
        }
        self.limits.check(self.min_depth)?;
        if let RoundingRule::Given(p) = self.rounding {
            if !(0.0..=1.0).contains(&p.share) {
                return Err(Error::invalid("rounding", format!("share must be within 0..1, got {}", p.share)));
            }
            if !(p.r_max.is_finite() && p.r_max >= 0.0) {
                return Err(Error::invalid("rounding", format!("r_max must be a radius >= 0 mm, got {}", p.r_max)));
            }
        }
        if let MisfitRule::Given(m) = self.misfit {
            for (model, v) in SectionModel::ALL.iter().zip(m.variance) {
                if let Some(v) = v.filter(|v| !(v.is_finite() && *v >= 0.0)) {
                    return Err(Error::invalid(
                        "misfit",
                        format!("the variance of {:?} must be >= 0 mm², got {v}", model.name()),
                    ));
                }
            }
            for (name, s) in super::misfit::STRETCH_MEASURES.iter().zip(m.stretch) {
                let Some(s) = s else { continue };
                if !(s.variance.is_finite() && s.variance >= 0.0) {
                    return Err(Error::invalid(
                        "misfit",
                        format!("the variance of \"u:{name}\" must be >= 0, got {}", s.variance),
                    ));
                }
                if !s.bias.is_finite() {
                    return Err(Error::invalid("misfit", format!("\"u:{name}:bias\" must be finite, got {}", s.bias)));
                }
            }
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
    /// The section models' further measures (NaN for the tanh template): the angle between
    /// each flank and the surface line, degrees (90 = a vertical wall); the cross-section
    /// area between the surface line and the section, mm²; the radius of a round bottom, mm
    /// (U and round V; 0 for a sharp V; NaN for a flat floor); the surface step across the
    /// groove, right surface minus left along the surface line's normal, mm (NaN when a side
    /// has fewer than three surface readings, as beside a shared corner).
    pub flank_angle_left: f64,
    pub flank_angle_right: f64,
    pub area: f64,
    pub bottom_radius: f64,
    pub step: f64,
    /// Their standard errors, and those of the center x0 and z0 (same units).
    pub se_x0: f64,
    pub se_z0: f64,
    pub se_flank_angle_left: f64,
    pub se_flank_angle_right: f64,
    pub se_area: f64,
    pub se_bottom_radius: f64,
    pub se_step: f64,
    /// Surface slope angle θ used for levelling, rad.
    pub tilt: f64,
    pub iterations: u32,
    /// Readings used in the fit.
    pub n_used: u32,
    pub status: GrooveStatus,
    /// What was fitted.
    pub model: FitModel,
    /// The groove's place among the frame's grooves, from the left (0 = leftmost); −1 when
    /// no groove was found.
    pub groove: i32,
    /// A V's χ² profile over its tip radius (V's and round V's of the default call), for the
    /// prior the call pools over its frames.
    pub rounding: Option<super::rounding::RoundingCurve>,
    /// The chosen section's residual at the bottom (section models, where no rounding curve
    /// settles the depth), for the misfit the call pools over its frames.
    pub misfit: Option<super::misfit::BottomResidual>,
    /// The ellipse's measures against the U's (where one was chosen and both fitted), for the
    /// stretch misfit the call pools.
    pub stretch: Option<super::misfit::StretchDifference>,
}

impl GrooveFit {
    /// Every measure NaN and no model: what a fit starts from and a failure keeps.
    pub(super) const UNMEASURED: GrooveFit = GrooveFit {
        x0: f64::NAN,
        z0: f64::NAN,
        depth: f64::NAN,
        width: f64::NAN,
        alpha: f64::NAN,
        rms: f64::NAN,
        se_depth: f64::NAN,
        se_width: f64::NAN,
        flank_angle_left: f64::NAN,
        flank_angle_right: f64::NAN,
        area: f64::NAN,
        bottom_radius: f64::NAN,
        step: f64::NAN,
        se_x0: f64::NAN,
        se_z0: f64::NAN,
        se_flank_angle_left: f64::NAN,
        se_flank_angle_right: f64::NAN,
        se_area: f64::NAN,
        se_bottom_radius: f64::NAN,
        se_step: f64::NAN,
        tilt: f64::NAN,
        iterations: 0,
        n_used: 0,
        status: GrooveStatus::Failed,
        model: FitModel::None,
        groove: -1,
        rounding: None,
        misfit: None,
        stretch: None,
    };

    /// The depth of a V with a rounding profile as its posterior under `prior` says (its
    /// median; the standard error with the posterior's spread), unchanged without one.
    pub fn settle_rounding(&mut self, prior: &super::RoundingPrior) {
        if let Some(p) = self.rounding.and_then(|c| c.posterior(prior)) {
            (self.depth, self.se_depth) = (p.depth, p.se_depth);
        }
    }

    /// The standard errors with the misfit `prior`: the depth's with what it gives the bottom
    /// residual, a U's measures' with what it gives their differences from the ellipse's
    /// (unchanged without them).
    pub fn settle_misfit(&mut self, prior: &super::MisfitPrior) {
        let widen = |se: &mut f64, variance: f64| *se = (*se * *se + variance).sqrt();
        if let Some(b) = self.misfit {
            widen(&mut self.se_depth, b.depth_variance(prior));
        }
        if let Some(s) = self.stretch {
            use super::section::*;
            let v = s.variances(prior);
            widen(&mut self.se_width, v[WIDTH]);
            widen(&mut self.se_depth, v[DEPTH]);
            // The center's variance is along the surface line: x0's nearly all of it.
            widen(&mut self.se_x0, v[CENTER]);
            // An angle is no more uncertain than uniform over what a flank may take (as the
            // fit's own errors are held).
            let uniform = uniform_angle_variance().sqrt();
            for (se, v) in
                [(&mut self.se_flank_angle_left, v[ANGLE_LEFT]), (&mut self.se_flank_angle_right, v[ANGLE_RIGHT])]
            {
                if *se < uniform {
                    widen(se, v);
                    *se = se.min(uniform);
                }
            }
            widen(&mut self.se_area, v[AREA]);
            widen(&mut self.se_bottom_radius, v[RADIUS]);
        }
    }

    pub(super) fn failed(status: GrooveStatus, n_used: usize) -> Self {
        GrooveFit { n_used: n_used as u32, status, ..GrooveFit::UNMEASURED }
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
