//! Paper 000's tanh template pipeline (SPEC G steps 1–7): window → valid readings → spike
//! filter → line fit → bottom point → surface refit without the groove → levelling → LM
//! template fit → back to the frame's own coordinates.
use super::options::{window_range, FitModel, GrooveFit, GrooveOptions, GrooveStatus};
use super::robust::{fit_line, retain_pairs};
use super::template::{gradient, tanh_pair, TanhTemplate};
use crate::optim::{levenberg_marquardt, LeastSquares, LmOptions, LmStop};
use nalgebra::{SMatrix, SVector};

/// Levelled points and the template problem on them; `P` = 4 (α fixed) or 5 (α fitted).
///
/// Evaluation is split into element-wise passes over the frame (tanh terms, residuals, template
/// gradient columns) that the compiler vectorises, and dot products with four explicit partial
/// sums for JᵀJ and Jᵀf. The summation order is fixed, so results do not depend on threads.
pub(super) struct TemplateProblem<'a> {
    pub(super) x: &'a [f64],
    pub(super) z: &'a [f64],
    pub(super) alpha: f64,
    pub(super) scratch: std::cell::RefCell<Scratch>,
}

/// Per-frame work arrays: the two tanh terms, the residuals, the template gradient columns.
pub(super) struct Scratch {
    pub(super) a: Vec<f64>,
    pub(super) b: Vec<f64>,
    pub(super) f: Vec<f64>,
    pub(super) grad: [Vec<f64>; 5],
}

/// Σ a·b with four partial sums (vectorises; fixed order).
#[inline(always)]
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
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
pub(super) fn sum(a: &[f64]) -> f64 {
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
    pub(super) fn new(x: &'a [f64], z: &'a [f64], alpha: f64) -> Self {
        let n = x.len();
        let v = || vec![0.0; n];
        let scratch = Scratch { a: v(), b: v(), f: v(), grad: [v(), v(), v(), v(), v()] };
        TemplateProblem { x, z, alpha, scratch: std::cell::RefCell::new(scratch) }
    }

    #[inline(always)]
    pub(super) fn template(&self, p: &[f64]) -> TanhTemplate {
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
    pub(super) fn residuals(&self, t: &TanhTemplate, s: &mut Scratch) -> f64 {
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
    pub(super) fn normal_equations_of<const P: usize>(&self, p: &[f64]) -> (SMatrix<f64, P, P>, SVector<f64, P>, f64) {
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
pub(super) fn solve<Prob: LeastSquares<4> + LeastSquares<5>>(
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
pub(super) fn median3(x: f64, y: f64, z: f64) -> f64 {
    x.min(y).max(x.max(y).min(z))
}

/// Median of five with min/max only (no sort): of the two pairs (a, b) and (c, d) the overall
/// smallest and largest cannot be the median, which leaves a median of three.
#[inline(always)]
pub(super) fn median5(a: f64, b: f64, c: f64, d: f64, e: f64) -> f64 {
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

/// The paper's pipeline: SPEC G steps 1–7 with the tanh template.
#[inline(always)]
pub(super) fn fit_tanh(x: &[f64], z: &[f64], o: &GrooveOptions) -> GrooveFit {
    fit_tanh_detailed(x, z, o).0
}

/// [`fit_tanh`] with the levelled frame and the fitted template parameters (levelled, relative
/// to the frame's origin) for drawing.
#[inline(always)]
pub(super) fn fit_tanh_detailed(
    x: &[f64],
    z: &[f64],
    o: &GrooveOptions,
) -> (GrooveFit, Option<(LevelledFrame, Vec<f64>)>) {
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
        // The template measures the one groove of its window.
        groove: 0,
        rounding: None,
        ..GrooveFit::UNMEASURED
    };
    (fit, Some((frame, p)))
}
