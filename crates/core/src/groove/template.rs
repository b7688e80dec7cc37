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

    /// The gradient with respect to `[x0, z0, d, w, α]` at x.
    pub fn gradient(&self, x: f64) -> [f64; 5] {
        let u = x - self.x0;
        let q = 0.25 * self.width;
        let (a, b) = tanh_pair(self.alpha * (u - q), self.alpha * (u + q));
        gradient(a, b, 0.5 * self.depth, self.alpha, u, q)
    }
}

/// The template's gradient with respect to `[x0, z0, d, w, α]` (paper 000 eq 15, extended by
/// α), from `a = tanh(α(u − q))`, `b = tanh(α(u + q))`, `u = x − x0`, `q = w/4`, half the depth:
/// the one home of the Jacobian, used reading by reading in the fit's vectorised loop.
#[inline(always)]
pub(crate) fn gradient(a: f64, b: f64, half_depth: f64, alpha: f64, u: f64, q: f64) -> [f64; 5] {
    let (sa, sb) = (1.0 - a * a, 1.0 - b * b);
    [
        half_depth * alpha * (sb - sa),
        1.0,
        0.5 * (a - b),
        -0.25 * half_depth * alpha * (sa + sb),
        half_depth * (sa * (u - q) - sb * (u + q)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let g = t.gradient(x);
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
        assert!((t.value(0.0) + 1.0).abs() < 1e-9);
    }
}
