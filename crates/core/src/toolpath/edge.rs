//! A surface patch round a sharp edge — a blade's leading or trailing edge, its radius a few point
//! spacings or less — described by the support function of its cross-sections.
//!
//! A height field cannot follow an edge whose normal turns half a turn within a patch, and the
//! points of one scan line say nothing about where the edge lies between lines. But round an edge
//! the normals all lie nearly perpendicular to one direction, the edge's axis t; cut the patch
//! across t at s = (p − o)·t and every cut is a convex curve, which its support function
//! h(φ) = p·(cos φ, sin φ) determines: the point of normal angle φ is
//! `h·(cos φ, sin φ) + h′·(−sin φ, cos φ)` (the envelope of its tangent lines). Each cloud point
//! with its normal gives one sample of h(s, φ) — its position projected on its normal, within the
//! cut — so the given normals carry the curve between points, and h varies slowly with s, so the
//! cuts of two scan lines carry the edge between them.
//!
//! h(s, φ) is fitted over {1, cos φ, sin φ, cos 2φ, sin 2φ} × {1, s} and s²: a circle, whatever
//! its centre, is {1, cos φ, sin φ}; the doubled angles take an ellipse-like tip. On the synthetic
//! blade (edge radius 0.66 mm, sampled every 0.5 mm) this puts path points on the surface to 2 µm
//! where a height field is off by up to 90 µm.
use nalgebra::{DMatrix, DVector, Matrix3, SVector, Vector3};

type V3 = Vector3<f64>;

const TERMS: usize = 11;
/// Newton iterations for the point of a cut in the section plane.
const ITERATIONS: usize = 30;
/// Step of the numerical derivatives of a point of the patch, in radians and in units of the
/// patch's size.
const STEP: f64 = 1e-6;
/// Step of the numerical second derivatives (their error goes with its square, their rounding
/// with the inverse of it squared).
const STEP2: f64 = 1e-4;
/// Largest normal angle from the patch's middle at which a point is taken, radians: the fit holds
/// over the angles its points span.
const MAX_ANGLE: f64 = 1.6;

/// Smallest sine of the angle between the section plane and the edge's axis at which the plane
/// cuts across the edge (as `grinding::MIN_CROSSING` for the row spacing).
const MIN_AXIS_CROSSING: f64 = 0.2;
/// Cosine to the middle normal below which a normal belongs to the other side of a thin edge
/// (more than 120° round).
const OTHER_SIDE: f64 = -0.5;

/// h's terms at (s, φ), s in units of the patch size.
fn terms(s: f64, phi: f64) -> SVector<f64, TERMS> {
    let (sin, cos) = phi.sin_cos();
    let (sin2, cos2) = (2.0 * phi).sin_cos();
    SVector::<f64, TERMS>::from([1.0, cos, sin, cos2, sin2, s, s * cos, s * sin, s * cos2, s * sin2, s * s])
}

/// dh/dφ's terms at (s, φ).
fn terms_phi(s: f64, phi: f64) -> SVector<f64, TERMS> {
    let (sin, cos) = phi.sin_cos();
    let (sin2, cos2) = (2.0 * phi).sin_cos();
    let d = [0.0, -sin, cos, -2.0 * sin2, 2.0 * cos2];
    SVector::<f64, TERMS>::from([d[0], d[1], d[2], d[3], d[4], 0.0, s * d[1], s * d[2], s * d[3], s * d[4], 0.0])
}

/// The allowance's terms: a quadric in (s, φ).
fn allowance_terms(s: f64, phi: f64) -> SVector<f64, 6> {
    SVector::<f64, 6>::from([1.0, s, phi, s * s, s * phi, phi * phi])
}

/// Weighted least squares by SVD: the support terms are near-dependent over a narrow range of
/// angles (cos φ and cos 2φ are both 1 − O(φ²)), where normal equations lose the digits.
fn solve<const K: usize>(rows: &[SVector<f64, K>], values: &[f64], weights: &[f64]) -> Option<SVector<f64, K>> {
    let a = DMatrix::from_fn(rows.len(), K, |i, j| weights[i].sqrt() * rows[i][j]);
    let b = DVector::from_fn(rows.len(), |i, _| weights[i].sqrt() * values[i]);
    let svd = a.svd(true, true);
    let largest = svd.singular_values.max();
    let x = svd.solve(&b, 1e-10 * largest).ok()?;
    let x = SVector::<f64, K>::from_iterator(x.iter().copied());
    x.iter().all(|c| c.is_finite()).then_some(x)
}

pub(super) struct EdgePatch {
    origin: V3,
    axis: V3,
    e1: V3,
    e2: V3,
    scale: f64,
    support: SVector<f64, TERMS>,
    allowance: SVector<f64, 6>,
    /// The normal angles and the positions along the axis (patch units) the fitted points span.
    angles: (f64, f64),
    along: (f64, f64),
}

impl EdgePatch {
    /// Fits the patch to `points` with their unit `normals` and `allowance` round `origin`, each
    /// weighted by exp(−(d/σ)²) for its distance d from the origin; angles are measured from
    /// `reference`, the normal nearest the origin. None where the normals do not turn (no edge:
    /// the cuts' angles do not span the terms) or the fit fails.
    pub(super) fn fit(
        origin: V3,
        reference: V3,
        points: &[V3],
        normals: &[V3],
        allowance: &[f64],
        sigma: f64,
    ) -> Option<EdgePatch> {
        // The axis: the direction the normals are most nearly perpendicular to — of this side's
        // normals: with the other side's (opposite) normals of a thin edge, a flank's normals
        // would leave every direction across them about as perpendicular.
        let scatter: Matrix3<f64> =
            normals.iter().filter(|m| m.dot(&reference) > OTHER_SIDE).map(|m| m * m.transpose()).sum();
        let eigen = scatter.symmetric_eigen();
        let axis = eigen.eigenvectors.column(eigen.eigenvalues.imin()).into_owned();
        let e1 = (reference - reference.dot(&axis) * axis).try_normalize(1e-6)?;
        let e2 = axis.cross(&e1);
        let scale = points.iter().map(|p| (p - origin).norm()).fold(0.0, f64::max).max(1e-12);
        let (mut rows, mut arows, mut h, mut a, mut w) = (vec![], vec![], vec![], vec![], vec![]);
        let (mut angles, mut along) = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, f64::NEG_INFINITY));
        for ((p, m), &value) in points.iter().zip(normals).zip(allowance) {
            let cut = V3::new(m.dot(&e1), m.dot(&e2), 0.0);
            let Some(cut) = cut.try_normalize(1e-6) else { continue };
            let phi = cut.y.atan2(cut.x);
            if phi.abs() > MAX_ANGLE {
                continue;
            }
            let d = p - origin;
            let s = d.dot(&axis) / scale;
            rows.push(terms(s, phi));
            arows.push(allowance_terms(s, phi));
            h.push(d.dot(&e1) * cut.x + d.dot(&e2) * cut.y);
            a.push(value);
            w.push((-d.norm_squared() / (sigma * sigma)).exp());
            angles = (angles.0.min(phi), angles.1.max(phi));
            along = (along.0.min(s), along.1.max(s));
        }
        if rows.len() < 2 * TERMS {
            return None;
        }
        let support = solve(&rows, &h, &w)?;
        let allowance = solve(&arows, &a, &w)?;
        Some(EdgePatch { origin, axis, e1, e2, scale, support, allowance, angles, along })
    }

    /// The point of the cut at s (patch units) with normal angle φ.
    fn at(&self, s: f64, phi: f64) -> V3 {
        let h = self.support.dot(&terms(s, phi));
        let dh = self.support.dot(&terms_phi(s, phi));
        let (sin, cos) = phi.sin_cos();
        self.origin + s * self.scale * self.axis + (h * cos - dh * sin) * self.e1 + (h * sin + dh * cos) * self.e2
    }

    /// The point of the patch in the plane {p : (p − q)·n = 0} nearest `q`, with its normal and
    /// allowance: Newton on (s, φ) for "in the plane" and "q lies along the normal".
    pub(super) fn place_in_plane(&self, q: V3, n: V3) -> Option<(V3, V3, f64)> {
        // A plane along the edge's axis cuts it in a line along the edge, not across it: no point
        // of the patch is determined there.
        if n.dot(&self.axis).abs() < MIN_AXIS_CROSSING {
            return None;
        }
        let (mut s, mut phi) = ((q - self.origin).dot(&self.axis) / self.scale, 0.0);
        let (mut converged, mut near) = (false, false);
        let (mut ds, mut dphi) = (V3::zeros(), V3::zeros());
        for _ in 0..ITERATIONS {
            let p = self.at(s, phi);
            ds = (self.at(s + STEP, phi) - self.at(s - STEP, phi)) / (2.0 * STEP);
            dphi = (self.at(s, phi + STEP) - self.at(s, phi - STEP)) / (2.0 * STEP);
            let f = [(p - q).dot(&n), (p - q).dot(&dphi)];
            // Gauss–Newton (p_φ·p_φ for the second condition's derivative) finds the point from
            // afar; once near it, full Newton adds (p − q)·p_φφ, as large as p_φ·p_φ where q lies
            // a good part of the edge's radius off the surface (a chain point round a tip sampled
            // every radian) — without it the iteration crawls or cycles there.
            let (mut j21, mut j22) = (ds.dot(&dphi), dphi.dot(&dphi));
            if near {
                let dphi2 = (self.at(s, phi + STEP2) - 2.0 * p + self.at(s, phi - STEP2)) / (STEP2 * STEP2);
                let dsphi = (self.at(s + STEP2, phi + STEP2)
                    - self.at(s + STEP2, phi - STEP2)
                    - self.at(s - STEP2, phi + STEP2)
                    + self.at(s - STEP2, phi - STEP2))
                    / (4.0 * STEP2 * STEP2);
                j21 += (p - q).dot(&dsphi);
                j22 += (p - q).dot(&dphi2);
            }
            let j = nalgebra::Matrix2::new(ds.dot(&n), dphi.dot(&n), j21, j22);
            let step = j.try_inverse()? * nalgebra::Vector2::new(f[0], f[1]);
            s -= step.x;
            phi -= step.y;
            if !(s.is_finite() && phi.is_finite()) {
                return None;
            }
            if step.abs().max() < 1e-10 {
                converged = true;
                break;
            }
            near = step.abs().max() < 1e-2;
        }
        // Outside the angles and the stretch of the edge the points span the patch extrapolates
        // (at the end of a scan, an edge's support function says nothing of where it goes on).
        let inside = phi >= self.angles.0 && phi <= self.angles.1 && s >= self.along.0 && s <= self.along.1;
        if !(converged && inside) {
            return None;
        }
        let p = self.at(s, phi);
        let (sin, cos) = phi.sin_cos();
        let outward = cos * self.e1 + sin * self.e2;
        let normal = dphi.cross(&ds).try_normalize(1e-12)?;
        let normal = if normal.dot(&outward) < 0.0 { -normal } else { normal };
        Some((p, normal, self.allowance.dot(&allowance_terms(s, phi))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tapered cylinder's edge, sampled on lines across its axis: the patch puts a point
    /// between two lines on the true surface.
    #[test]
    fn a_point_between_scan_lines_lies_on_the_edge() {
        let (r0, taper) = (0.66, 0.02);
        let (mut points, mut normals, mut allowance) = (vec![], vec![], vec![]);
        for line in -4..=4 {
            let z = 0.5 * line as f64;
            let r = r0 + taper * z;
            for k in -8..=8 {
                let phi = 0.37 * k as f64 + 0.1 * z;
                let m = V3::new(phi.cos(), phi.sin(), 0.0);
                points.push(r * m + V3::new(0.0, 0.0, z));
                normals.push(m);
                allowance.push(0.3 + 0.01 * z);
            }
        }
        let q = V3::new(0.7, 0.05, 0.25);
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by(|&a, &b| (points[a] - q).norm().total_cmp(&(points[b] - q).norm()));
        order.truncate(40);
        let pick = |v: &[V3]| order.iter().map(|&i| v[i]).collect::<Vec<V3>>();
        let a: Vec<f64> = order.iter().map(|&i| allowance[i]).collect();
        let sigma = 1.5 * (points[order[13]] - q).norm();
        let patch = EdgePatch::fit(q, normals[order[0]], &pick(&points), &pick(&normals), &a, sigma).unwrap();
        let (p, m, value) = patch.place_in_plane(q, V3::z()).unwrap();
        let r = r0 + taper * 0.25;
        assert!((p.z - 0.25).abs() < 1e-12);
        assert!((p.xy().norm() - r).abs() < 2e-4, "{}", p.xy().norm() - r);
        assert!(m.dot(&V3::new(p.x, p.y, -taper * r).normalize()) > 0.9999);
        assert!((value - 0.3025).abs() < 1e-4);
    }
}
