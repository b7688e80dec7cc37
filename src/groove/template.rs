//! The groove template of paper 000 eq (11):
//!
//! `z = z0 + ½·d·( tanh(α(x − x0 − w/4)) − tanh(α(x − x0 + w/4)) )`
//!
//! At half depth the template is w/2 wide, so for a V groove `w` is the width at the surface.
//! At the centre the dip is `d·tanh(αw/4)` deep (0.984·d for α = 20 mm⁻¹, w = 0.48 mm).

/// Parameters `[x0, z0, d, w, α]` (mm, mm, mm, mm, mm⁻¹).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TanhTemplate {
    pub x0: f64,
    pub z0: f64,
    pub depth: f64,
    pub width: f64,
    pub alpha: f64,
}

/// tanh from one exponential; `f64::tanh` is several times slower and this kernel runs
/// ~10⁸ times a second. Relative error below 1e-15 away from 0; near 0 the subtraction
/// loses bits, so small arguments take the library route.
#[inline(always)]
pub(crate) fn fast_tanh(y: f64) -> f64 {
    if y.abs() < 0.25 {
        return y.tanh();
    }
    let e = (-2.0 * y.abs()).exp();
    ((1.0 - e) / (1.0 + e)).copysign(y)
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

    /// Depth of the dip at the centre: `d·tanh(αw/4)`.
    pub fn centre_depth(&self) -> f64 {
        self.depth * (0.25 * self.alpha * self.width).tanh()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
                let f = |q: [f64; 5]| TanhTemplate { x0: q[0], z0: q[1], depth: q[2], width: q[3], alpha: q[4] }.value(x);
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
        assert!((t.centre_depth() - 1.0).abs() < 1e-9);
    }
}
