//! Scallop height and step-over of neighbouring tool rows (SPEC P3; paper 004 §3, whose eq 16–18
//! are garbled): exact circle geometry in the plane across the rows.
//!
//! The surface is a circle of radius |ρ| about O (ρ > 0 convex, ρ < 0 concave, ∞ flat), the
//! contact wheel a circle of radius R touching it. Two neighbouring rows an arc L apart put the
//! tool centres at distance D from O (D = ρ + R convex, |ρ| − R concave) and an angle φ = L/|ρ|
//! apart; the cusp between them is where the two tool circles meet, at r_c from O, and the
//! scallop height is how far it stands off the surface, h = r_c − ρ (convex) or |ρ| − r_c
//! (concave). The triangle O, tool centre, cusp (sides D, R, r_c; angle φ/2 at O) gives both
//! directions in closed form:
//!
//! - h from L: r_c = D cos(φ/2) ∓ √(R² − D² sin²(φ/2)) (− convex, + concave);
//! - L from h: 1 − cos(φ/2) = 2 sin²(φ/4) = h (2R − h) / (2 D r_c), since |D − r_c| = R − h.
//!
//! Written so that no digits cancel on nearly flat surfaces (|ρ| = 1e6 mm): the differences of
//! nearly equal cosines and square roots are rewritten as products of sines.
use crate::error::{Error, Result};

fn check_radius(tool_radius: f64) -> Result<()> {
    if tool_radius.is_finite() && tool_radius > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid("tool_radius", format!("must be a positive finite number of mm, got {tool_radius}")))
    }
}

/// D, the distance of the tool centres from the surface's centre of curvature; fails where a
/// concave surface is too tight for the tool.
fn centre_distance(tool_radius: f64, curvature_radius: f64) -> Result<f64> {
    if curvature_radius.is_nan() || curvature_radius == 0.0 {
        return Err(Error::invalid(
            "curvature_radius",
            format!("must be > 0 (convex), < 0 (concave) or ±inf (flat), mm; got {curvature_radius}"),
        ));
    }
    let d = if curvature_radius > 0.0 { curvature_radius + tool_radius } else { -curvature_radius - tool_radius };
    if d <= 0.0 {
        return Err(Error::invalid(
            "curvature_radius",
            format!(
                "a concave radius of {} mm is no larger than the tool radius {tool_radius} mm: the tool cannot fit",
                -curvature_radius
            ),
        ));
    }
    Ok(d)
}

/// The scallop height (mm) between rows an arc `step` apart on the surface.
pub fn scallop_height(tool_radius: f64, curvature_radius: f64, step: f64) -> Result<f64> {
    check_radius(tool_radius)?;
    if !(step.is_finite() && step >= 0.0) {
        return Err(Error::invalid("step", format!("must be a finite number ≥ 0 mm, got {step}")));
    }
    let r = tool_radius;
    if curvature_radius.is_infinite() {
        let half = step / 2.0;
        if half > r {
            return Err(Error::invalid(
                "step",
                format!("{step} mm is wider than the tool ({} mm): the rows leave a strip unground", 2.0 * r),
            ));
        }
        // R − √(R² − (L/2)²), without the cancellation.
        return Ok(half * half / (r + (r * r - half * half).sqrt()));
    }
    let d = centre_distance(r, curvature_radius)?;
    let rho = curvature_radius.abs();
    let phi = step / rho;
    let (s2, c2) = (phi / 2.0).sin_cos();
    let reach = d * s2;
    if phi >= std::f64::consts::PI || reach > r {
        return Err(Error::invalid(
            "step",
            format!("{step} mm is too wide for a {r} mm tool on a {curvature_radius} mm radius: the rows leave a strip unground"),
        ));
    }
    let root = (r * r - reach * reach).sqrt();
    let q = (phi / 4.0).sin();
    // R cos(φ/2) − √(R² − D² sin²(φ/2)) = (D² − R²) sin²(φ/2) / (R cos(φ/2) + √(…)).
    let lift = (d * d - r * r) * s2 * s2 / (r * c2 + root);
    Ok(if curvature_radius > 0.0 {
        // h = D cos(φ/2) − √(…) − ρ, with D cos(φ/2) − ρ = R cos(φ/2) − 2ρ sin²(φ/4).
        lift - 2.0 * rho * q * q
    } else {
        // h = |ρ| − D cos(φ/2) − √(…), with |ρ| − D cos(φ/2) = R cos(φ/2) + 2|ρ| sin²(φ/4).
        2.0 * rho * q * q + lift
    })
}

/// The widest step (arc length on the surface, mm) whose scallop height is `scallop_height`.
pub fn step_over(tool_radius: f64, curvature_radius: f64, scallop_height: f64) -> Result<f64> {
    check_radius(tool_radius)?;
    let (r, h) = (tool_radius, scallop_height);
    if !(h.is_finite() && h >= 0.0 && h < r) {
        return Err(Error::invalid("scallop_height", format!("must be ≥ 0 and below the tool radius {r} mm, got {h}")));
    }
    if curvature_radius.is_infinite() {
        return Ok(2.0 * (h * (2.0 * r - h)).sqrt());
    }
    let d = centre_distance(r, curvature_radius)?;
    let rho = curvature_radius.abs();
    let cusp = if curvature_radius > 0.0 { rho + h } else { rho - h };
    let q = (h * (2.0 * r - h) / (4.0 * d * cusp)).sqrt();
    if q > 1.0 {
        return Err(Error::invalid(
            "scallop_height",
            format!("{h} mm cannot be reached on a {curvature_radius} mm radius with a {r} mm tool"),
        ));
    }
    Ok(rho * 4.0 * q.asin())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_directions_invert_each_other_and_flat_is_the_limit_of_both_curvatures() {
        for rho in [f64::INFINITY, 5.0, 30.0, 1e3, 1e6, -30.0, -1e3, -1e6, -12.5] {
            for h in [0.0, 1e-6, 0.001, 0.01, 0.5] {
                let l = step_over(10.0, rho, h).unwrap();
                let back = scallop_height(10.0, rho, l).unwrap();
                assert!((back - h).abs() < 1e-12, "ρ {rho}, h {h}: L {l}, back {back}");
            }
        }
        // |ρ| = 1e6 is flat to within the curvature's own effect (~L²/8ρ ≈ 1e-8 mm here).
        let flat = step_over(10.0, f64::INFINITY, 0.01).unwrap();
        for rho in [1e6, -1e6] {
            assert!((step_over(10.0, rho, 0.01).unwrap() - flat).abs() < 1e-5);
        }
        // Convex surfaces need closer rows than flat ones, concave ones allow wider.
        assert!(step_over(10.0, 50.0, 0.01).unwrap() < flat && step_over(10.0, -50.0, 0.01).unwrap() > flat);
    }

    #[test]
    fn impossible_geometry_is_refused_by_name() {
        let e = |r: Result<f64>| r.unwrap_err().to_string();
        assert!(e(step_over(10.0, -10.0, 0.01)).contains("curvature_radius"));
        assert!(e(step_over(10.0, -5.0, 0.01)).contains("cannot fit"));
        assert!(e(step_over(10.0, 0.0, 0.01)).contains("curvature_radius"));
        assert!(e(step_over(0.0, 1.0, 0.01)).contains("tool_radius"));
        assert!(e(step_over(10.0, 1.0, 10.0)).contains("scallop_height"));
        assert!(e(scallop_height(10.0, f64::INFINITY, 25.0)).contains("step"));
        assert!(e(scallop_height(10.0, 5.0, -1.0)).contains("step"));
        assert!(e(scallop_height(10.0, 5.0, 16.0)).contains("step"));
    }
}
