//! Elementary right-handed rotations and the sensor-mount Euler form.
//!
//! SPEC K2/K3: the printed matrices of paper 000 eq (4) and eq (8) are not orthonormal
//! (sign errors). Here every rotation is built as a product of elementary rotations, which
//! is orthonormal by construction; tests check it and check the closed forms of SPEC.
use nalgebra::Matrix3;

/// A coordinate axis about which an elementary rotation turns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub fn parse(name: &str) -> Option<Axis> {
        match name.to_ascii_lowercase().as_str() {
            "x" => Some(Axis::X),
            "y" => Some(Axis::Y),
            "z" => Some(Axis::Z),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }

    pub fn rotation(self, angle: f64) -> Matrix3<f64> {
        match self {
            Axis::X => rot_x(angle),
            Axis::Y => rot_y(angle),
            Axis::Z => rot_z(angle),
        }
    }
}

pub fn rot_x(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

pub fn rot_y(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

pub fn rot_z(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Sensor mount rotation of SPEC K3: `R = Rz(phi) · Ry(theta) · Rx(psi)`
/// (theta nutation, psi precession, phi spin).
pub fn mount_rotation(theta: f64, psi: f64, phi: f64) -> Matrix3<f64> {
    rot_z(phi) * rot_y(theta) * rot_x(psi)
}

/// Partial derivatives of [`mount_rotation`] with respect to (theta, psi, phi).
pub fn mount_rotation_partials(theta: f64, psi: f64, phi: f64) -> [Matrix3<f64>; 3] {
    // d/da of an elementary rotation R(a) is R(a + pi/2) with the fixed axis row/column zeroed.
    let d = |axis: Axis, a: f64| {
        let mut m = axis.rotation(a + std::f64::consts::FRAC_PI_2);
        let k = match axis {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        };
        for i in 0..3 {
            m[(k, i)] = 0.0;
            m[(i, k)] = 0.0;
        }
        m
    };
    let (rz, ry, rx) = (rot_z(phi), rot_y(theta), rot_x(psi));
    [rz * d(Axis::Y, theta) * rx, rz * ry * d(Axis::X, psi), d(Axis::Z, phi) * ry * rx]
}

/// Inverse of [`mount_rotation`]: (theta, psi, phi) with theta in [-pi/2, pi/2].
/// At gimbal lock (|theta| = pi/2) psi is set to 0 and phi carries the whole turn.
pub fn mount_rotation_angles(r: &Matrix3<f64>) -> (f64, f64, f64) {
    let s = (-r[(2, 0)]).clamp(-1.0, 1.0);
    let theta = s.asin();
    if (1.0 - s.abs()) > 1e-12 {
        let psi = r[(2, 1)].atan2(r[(2, 2)]);
        let phi = r[(1, 0)].atan2(r[(0, 0)]);
        (theta, psi, phi)
    } else {
        // R = Rz(phi) Ry(±pi/2) Rx(psi) only depends on phi ∓ psi.
        let phi = (-r[(0, 1)]).atan2(r[(1, 1)]);
        (theta, 0.0, phi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    fn assert_orthonormal(r: &Matrix3<f64>) {
        let e = r.transpose() * r - Matrix3::identity();
        assert!(e.abs().max() < 1e-14, "RᵀR − I = {e}");
        assert!((r.determinant() - 1.0).abs() < 1e-14);
    }

    #[rstest]
    #[case(0.0, 0.0, 0.0)]
    #[case(0.3, -1.2, 2.5)]
    #[case(1.5, 0.1, -3.0)]
    #[case(-0.7, 3.1, 0.01)]
    fn mount_rotation_is_orthonormal_and_matches_spec(#[case] theta: f64, #[case] psi: f64, #[case] phi: f64) {
        let r = mount_rotation(theta, psi, phi);
        assert_orthonormal(&r);
        // The corrected closed form of SPEC K3 (paper 000 eq 8 without its sign error).
        let (st, ct, ss, cs, sf, cf) = (theta.sin(), theta.cos(), psi.sin(), psi.cos(), phi.sin(), phi.cos());
        let spec = Matrix3::new(
            ct * cf,
            ss * st * cf - cs * sf,
            cs * st * cf + ss * sf,
            ct * sf,
            ss * st * sf + cs * cf,
            cs * st * sf - ss * cf,
            -st,
            ss * ct,
            cs * ct,
        );
        assert!((r - spec).abs().max() < 1e-15);
        let (t2, p2, f2) = mount_rotation_angles(&r);
        assert!((mount_rotation(t2, p2, f2) - r).abs().max() < 1e-12);
    }

    #[test]
    fn printed_eq8_is_not_a_rotation() {
        // Paper 000 eq (8) as printed: entry (2,3) reads cψ sθ sφ + sψ cφ. It is not orthonormal.
        let (theta, psi, phi) = (0.4_f64, 0.7_f64, -0.9_f64);
        let (st, ct, ss, cs, sf, cf) = (theta.sin(), theta.cos(), psi.sin(), psi.cos(), phi.sin(), phi.cos());
        let printed = Matrix3::new(
            ct * cf,
            ss * st * cf - cs * sf,
            cs * st * cf + ss * sf,
            ct * sf,
            ss * st * sf + cs * cf,
            cs * st * sf + ss * cf,
            -st,
            ss * ct,
            cs * ct,
        );
        let e = printed.transpose() * printed - Matrix3::identity();
        assert!(e.abs().max() > 0.1);
    }

    #[rstest]
    #[case(Axis::X)]
    #[case(Axis::Y)]
    #[case(Axis::Z)]
    fn elementary_rotations_are_orthonormal(#[case] axis: Axis) {
        for k in 0..50 {
            let a = -7.0 + 0.29 * k as f64;
            assert_orthonormal(&axis.rotation(a));
        }
    }

    #[test]
    fn head_rotation_matches_spec_k2() {
        let (a, c) = (0.37_f64, -1.1_f64);
        let r = rot_z(c) * rot_x(a);
        let (sa, ca, sc, cc) = (a.sin(), a.cos(), c.sin(), c.cos());
        let spec = Matrix3::new(cc, -sc * ca, sc * sa, sc, cc * ca, -cc * sa, 0.0, sa, ca);
        assert!((r - spec).abs().max() < 1e-15);
        assert_orthonormal(&r);
    }

    #[test]
    fn partials_match_finite_differences() {
        let (t, p, f) = (0.2, -0.4, 1.3);
        let parts = mount_rotation_partials(t, p, f);
        let h = 1e-6;
        let fd = [
            (mount_rotation(t + h, p, f) - mount_rotation(t - h, p, f)) / (2.0 * h),
            (mount_rotation(t, p + h, f) - mount_rotation(t, p - h, f)) / (2.0 * h),
            (mount_rotation(t, p, f + h) - mount_rotation(t, p, f - h)) / (2.0 * h),
        ];
        for k in 0..3 {
            assert!((parts[k] - fd[k]).abs().max() < 1e-8);
        }
    }
}
