//! Coarse alignment (SPEC R3, paper 004): the principal frames of both clouds (centroid and the
//! axes of the covariance) put on top of each other. An axis is known only up to its sign, so
//! the four proper (det +1) sign choices are tried and the one whose moved source lies closest
//! to the target is kept: enough for ICP to converge from any start orientation on a part
//! without symmetry.
use crate::error::{check_finite_points, Error, Result};
use crate::geom::transform_point;
use crate::spatial::PointIndex;
use nalgebra::{Matrix3, Matrix4, SymmetricEigen, Vector3};
use rayon::prelude::*;

/// Source points scored per candidate: a fixed, evenly strided subset (the score ranks four
/// candidates that differ by half-turns; a few thousand points rank them as all would).
const SCORED: usize = 4000;

/// Centroid and principal axes (columns, by decreasing variance) of a cloud.
fn principal_frame(points: &[[f64; 3]]) -> (Vector3<f64>, Matrix3<f64>) {
    let n = points.len() as f64;
    let c = points.iter().fold(Vector3::zeros(), |a, p| a + Vector3::from(*p)) / n;
    let cov = points.iter().fold(Matrix3::zeros(), |a, p| {
        let d = Vector3::from(*p) - c;
        a + d * d.transpose()
    }) / n;
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let axes = Matrix3::from_columns(&order.map(|k| eig.eigenvectors.column(k).into_owned()));
    (c, axes)
}

/// The rigid transform (applied to the source) that puts the source's principal frame on the
/// target's, with the sign choice whose moved source lies closest to the target (RMS nearest
/// distance over an evenly strided subset of the source).
pub fn coarse_align(source: &[[f64; 3]], target: &[[f64; 3]]) -> Result<Matrix4<f64>> {
    check_finite_points("source", source)?;
    check_finite_points("target", target)?;
    for (name, p) in [("source", source), ("target", target)] {
        if p.len() < 4 {
            return Err(Error::invalid(
                name,
                format!("needs at least 4 points for its principal axes, got {}", p.len()),
            ));
        }
    }
    let (cs, es) = principal_frame(source);
    let (ct, et) = principal_frame(target);
    let index = PointIndex::new(target)?;
    let step = source.len().div_ceil(SCORED);
    let scored: Vec<[f64; 3]> = source.iter().step_by(step).copied().collect();
    let mut best: Option<(f64, Matrix4<f64>)> = None;
    for signs in [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]] {
        let s = Matrix3::from_diagonal(&Vector3::from(signs));
        let mut r = et * s * es.transpose();
        // An eigenvector basis may be left-handed: keep the rotation proper.
        if r.determinant() < 0.0 {
            r = et * s * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0)) * es.transpose();
        }
        let mut t = Matrix4::identity();
        t.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        t.fixed_view_mut::<3, 1>(0, 3).copy_from(&(ct - r * cs));
        let ss: f64 = scored
            .par_iter()
            .map(|&p| index.nearest_squared(&transform_point(&t, p)).1)
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        if best.as_ref().is_none_or(|(b, _)| ss < *b) {
            best = Some((ss, t));
        }
    }
    Ok(best.map(|(_, t)| t).unwrap_or_else(Matrix4::identity))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mount_rotation;
    use crate::registration::{icp, IcpOptions};

    /// An asymmetric part: a box-like blob with a bump and a tab, sampled on its surface.
    fn part() -> Vec<[f64; 3]> {
        let mut seed = 17u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64) / ((1u64 << 53) as f64)
        };
        (0..6000)
            .map(|_| {
                let (u, v) = (rnd() * std::f64::consts::TAU, rnd() * std::f64::consts::PI);
                let r = 1.0 + 0.3 * (-(u - 1.0).powi(2) * 4.0).exp() + 0.15 * (2.0 * v).sin() * u.cos().max(0.0);
                [
                    60.0 * r * v.sin() * u.cos(),
                    35.0 * r * v.sin() * u.sin(),
                    20.0 * r * v.cos() + 3.0 * (u.sin() > 0.5) as i32 as f64,
                ]
            })
            .collect()
    }

    #[test]
    fn icp_converges_from_any_start_orientation_after_coarse_alignment() {
        let target = part();
        for (k, angles) in [(0.0, 0.0, 2.5), (3.0, 0.5, -1.0), (-2.0, 1.2, 0.7), (1.5, -2.8, 3.0)].iter().enumerate() {
            let misplace = {
                let mut m = Matrix4::identity();
                m.fixed_view_mut::<3, 3>(0, 0).copy_from(&mount_rotation(angles.0, angles.1, angles.2));
                m.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::new(40.0, -25.0, 10.0 * k as f64));
                m
            };
            let source: Vec<[f64; 3]> = target.iter().map(|&p| transform_point(&misplace, p)).collect();
            let init = coarse_align(&source, &target).unwrap();
            let r = icp(&source, &target, None, &init, &IcpOptions { max_iterations: 100, ..IcpOptions::new(10.0) })
                .unwrap();
            let truth = misplace.try_inverse().unwrap();
            assert!(
                (r.transformation - truth).abs().max() < 1e-6,
                "start {k}: {}",
                (r.transformation - truth).abs().max()
            );
        }
    }
}
