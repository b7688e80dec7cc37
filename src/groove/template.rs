//! The groove template of paper 000 eq (11):
//!
//! `z = z0 + ½·d·( tanh(α(x − x0 − w/4)) − tanh(α(x − x0 + w/4)) )`
//!
//! At half depth the template is w/2 wide, so for a V groove `w` is the width at the surface.
//! At the center the dip is `d·tanh(αw/4)` deep (0.984·d for α = 20 mm⁻¹, w = 0.48 mm).

/// Parameters `[x0, z0, d, w, α]` (mm, mm, mm, mm, mm⁻¹).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TanhTemplate {
    pub x0: f64,
    pub z0: f64,
    pub depth: f64,
    pub width: f64,
    pub alpha: f64,
}

/// `e^y` for `y <= 0`, branch-free so that loops over a frame vectorise: Cody–Waite range
/// reduction `y = k·ln2 + r`, a degree-12 Taylor polynomial for `e^r` (|r| ≤ ln2/2, relative
/// error < 2e-16) and `2^k` written straight into the exponent bits. `f64::exp` is a call into
/// libm that stops the compiler from vectorising the template loop.
#[inline(always)]
pub(crate) fn exp_nonpositive(y: f64) -> f64 {
    const LOG2E: f64 = std::f64::consts::LOG2_E;
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    const SHIFTER: f64 = 6_755_399_441_055_744.0; // 1.5·2^52: rounds to an integer in the low bits
    let y = y.max(-700.0);
    let t = y * LOG2E + SHIFTER;
    let k = t - SHIFTER;
    let r = (y - k * LN2_HI) - k * LN2_LO;
    let mut p = 1.0 / 479_001_600.0;
    for c in [
        1.0 / 39_916_800.0,
        1.0 / 3_628_800.0,
        1.0 / 362_880.0,
        1.0 / 40_320.0,
        1.0 / 5_040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ] {
        p = p * r + c;
    }
    // 2^k from the integer in t's low mantissa bits (two's complement wraps for k < 0).
    let scale = f64::from_bits((t.to_bits() << 52).wrapping_add(1023u64 << 52));
    p * scale
}

/// `tanh(y) = sign(y)·(1 − e)/(1 + e)`, `e = e^(−2|y|)`; absolute error below 3e-16.
#[inline(always)]
pub(crate) fn fast_tanh(y: f64) -> f64 {
    let e = exp_nonpositive(-2.0 * y.abs());
    ((1.0 - e) / (1.0 + e)).copysign(y)
}

/// `(tanh ya, tanh yb)` with one division instead of two (divisions are the slowest step of
/// the template loop): `1/((1 + ea)(1 + eb))` serves both quotients.
#[inline(always)]
pub(crate) fn tanh_pair(ya: f64, yb: f64) -> (f64, f64) {
    let ea = exp_nonpositive(-2.0 * ya.abs());
    let eb = exp_nonpositive(-2.0 * yb.abs());
    let inv = 1.0 / ((1.0 + ea) * (1.0 + eb));
    (((1.0 - ea) * (1.0 + eb) * inv).copysign(ya), ((1.0 - eb) * (1.0 + ea) * inv).copysign(yb))
}

impl TanhTemplate {
    #[inline(always)]
    pub fn value(&self, x: f64) -> f64 {
        let u = x - self.x0;
        let q = 0.25 * self.width;
        let a = fast_tanh(self.alpha * (u - q));
        let b = fast_tanh(self.alpha * (u + q));
        self.z0 + 0.5 * self.depth * (a - b)
    }

    /// Value and gradient with respect to `[x0, z0, d, w, α]` (paper 000 eq 15, extended by α).
    #[inline(always)]
    pub fn value_and_gradient(&self, x: f64) -> (f64, [f64; 5]) {
        let u = x - self.x0;
        let q = 0.25 * self.width;
        let a = fast_tanh(self.alpha * (u - q));
        let b = fast_tanh(self.alpha * (u + q));
        let (sa, sb) = (1.0 - a * a, 1.0 - b * b);
        let hd = 0.5 * self.depth;
        let value = self.z0 + hd * (a - b);
        let grad = [
            hd * self.alpha * (sb - sa),
            1.0,
            0.5 * (a - b),
            -0.25 * hd * self.alpha * (sa + sb),
            hd * (sa * (u - q) - sb * (u + q)),
        ];
        (value, grad)
    }

    /// Depth of the dip at the center: `d·tanh(αw/4)`.
    pub fn center_depth(&self) -> f64 {
        self.depth * (0.25 * self.alpha * self.width).tanh()
    }
}

/// A V groove with rounded corners: `z = z0 − d·h(x − x0)`,
/// `h(u) = (2/w)·(s(u + w/2) − 2 s(u) + s(u − w/2))`, `s(t) = ln(1 + e^(βt))/β`.
///
/// For β → ∞, `h` is the tent of height 1 and half-width w/2: straight flanks meeting the
/// surface at x0 ± w/2 and the tip d below it. A finite β rounds the tip and the edges over
/// about 1/β mm, as a laser-cut groove is. `d` is the depth of the flanks' meeting point
/// (the sharp V's tip); the dip at the center is `d·h(0)`, a little less.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VTemplate {
    pub x0: f64,
    pub z0: f64,
    pub depth: f64,
    pub width: f64,
    /// β, mm⁻¹.
    pub sharpness: f64,
}

/// softplus_β(t) and its derivative σ(βt), stable for any t.
#[inline(always)]
fn softplus(t: f64, beta: f64) -> (f64, f64) {
    let e = exp_nonpositive(-beta * t.abs());
    let s = t.max(0.0) + (1.0 + e).ln() / beta;
    let sig = if t >= 0.0 { 1.0 / (1.0 + e) } else { e / (1.0 + e) };
    (s, sig)
}

impl VTemplate {
    /// Value and gradient with respect to `[x0, z0, d, w, β]`.
    #[inline(always)]
    pub fn value_and_gradient(&self, x: f64) -> (f64, [f64; 5]) {
        let (u, hw, b) = (x - self.x0, 0.5 * self.width, self.sharpness);
        let (sp, gp) = softplus(u + hw, b);
        let (s0, g0) = softplus(u, b);
        let (sm, gm) = softplus(u - hw, b);
        let k = 2.0 / self.width;
        let big_s = sp - 2.0 * s0 + sm;
        let h = k * big_s;
        let dh_du = k * (gp - 2.0 * g0 + gm);
        let dh_dw = -h / self.width + (gp - gm) / self.width;
        // ∂s/∂β = (t·σ(βt) − s(t))/β
        let ds_db = |t: f64, s: f64, g: f64| (t * g - s) / b;
        let dh_db = k * (ds_db(u + hw, sp, gp) - 2.0 * ds_db(u, s0, g0) + ds_db(u - hw, sm, gm));
        let d = self.depth;
        (self.z0 - d * h, [d * dh_du, 1.0, -h, -d * dh_dw, -d * dh_db])
    }

    pub fn value(&self, x: f64) -> f64 {
        self.value_and_gradient(x).0
    }

    /// Depth of the dip at the center, `d·h(0)`.
    pub fn center_depth(&self) -> f64 {
        self.z0 - self.value(self.x0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v_template_gradient_and_limits() {
        let t = VTemplate { x0: 0.02, z0: 0.1, depth: 0.31, width: 0.48, sharpness: 60.0 };
        let h = 1e-7;
        for &x in &[-0.4, -0.25, -0.1, 0.0, 0.05, 0.2, 0.26, 0.5] {
            let (_, g) = t.value_and_gradient(x);
            let p = [t.x0, t.z0, t.depth, t.width, t.sharpness];
            for k in 0..5 {
                let (mut up, mut dn) = (p, p);
                up[k] += h;
                dn[k] -= h;
                let f =
                    |q: [f64; 5]| VTemplate { x0: q[0], z0: q[1], depth: q[2], width: q[3], sharpness: q[4] }.value(x);
                let fd = (f(up) - f(dn)) / (2.0 * h);
                assert!((fd - g[k]).abs() < 1e-5 * (1.0 + fd.abs()), "x={x} k={k}: {fd} vs {}", g[k]);
            }
        }
        // Sharp limit: a tent of depth d and surface width w.
        let sharp = VTemplate { x0: 0.0, z0: 0.0, depth: 0.3, width: 0.48, sharpness: 1e5 };
        assert!((sharp.value(0.0) + 0.3).abs() < 1e-4);
        assert!((sharp.value(0.12) + 0.15).abs() < 1e-4);
        assert!(sharp.value(0.3).abs() < 1e-9);
    }

    #[test]
    fn exp_matches_std() {
        let mut worst: f64 = 0.0;
        for k in 0..=200000 {
            let y = -(k as f64) * 3.5e-3;
            let (a, b) = (exp_nonpositive(y), y.exp());
            if b > 0.0 {
                worst = worst.max(((a - b) / b).abs());
            }
        }
        assert!(worst < 4e-16, "{worst}");
        assert_eq!(exp_nonpositive(-1e6), exp_nonpositive(-700.0));
    }

    #[test]
    fn tanh_pair_matches_std() {
        for k in -3000..=3000 {
            let (ya, yb) = (k as f64 * 7e-3, 2.0 - k as f64 * 3e-3);
            let (a, b) = tanh_pair(ya, yb);
            assert!((a - ya.tanh()).abs() < 5e-16 && (b - yb.tanh()).abs() < 5e-16, "{ya} {yb}");
        }
    }

    #[test]
    fn fast_tanh_matches_std() {
        let mut worst: f64 = 0.0;
        for k in -40000..=40000 {
            let y = k as f64 * 1e-3;
            worst = worst.max((fast_tanh(y) - y.tanh()).abs());
        }
        assert!(worst < 4e-16, "{worst}");
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let t = TanhTemplate { x0: 0.03, z0: 0.1, depth: 0.31, width: 0.48, alpha: 20.0 };
        let h = 1e-7;
        for &x in &[-0.4, -0.2, -0.1, 0.0, 0.05, 0.13, 0.3] {
            let (_, g) = t.value_and_gradient(x);
            let p = [t.x0, t.z0, t.depth, t.width, t.alpha];
            for k in 0..5 {
                let (mut up, mut dn) = (p, p);
                up[k] += h;
                dn[k] -= h;
                let f =
                    |q: [f64; 5]| TanhTemplate { x0: q[0], z0: q[1], depth: q[2], width: q[3], alpha: q[4] }.value(x);
                let fd = (f(up) - f(dn)) / (2.0 * h);
                assert!((fd - g[k]).abs() < 1e-6 * (1.0 + fd.abs()), "x={x} k={k}: {fd} vs {}", g[k]);
            }
        }
    }

    #[test]
    fn half_depth_width_is_half_the_surface_width() {
        let t = TanhTemplate { x0: 0.0, z0: 0.0, depth: 1.0, width: 0.48, alpha: 200.0 };
        // With a sharp template the half-depth crossings sit at ±w/4.
        assert!((t.value(0.12) + 0.5).abs() < 1e-3);
        assert!((t.center_depth() - 1.0).abs() < 1e-9);
    }
}
