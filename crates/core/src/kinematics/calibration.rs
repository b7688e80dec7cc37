//! Sensor mount calibration (SPEC K4, paper 000 eq 9–10).
//!
//! Given profiler points in the SCS and the same points measured independently in the WCS
//! (a CMM-measured calibration block), recover the six mount parameters (θ, ψ, φ, Δx, Δy, Δz)
//! of `C2_T_SCS`. Every SCS point has y = 0, so a linear solve of a 3×4 matrix cannot recover
//! the rotation; instead: bring each WCS point into the C2 frame with its known machine
//! transform, Kabsch for a start, then Levenberg–Marquardt on the exact Euler form, and the
//! covariance `σ̂² (JᵀJ)⁻¹` with `σ̂² = Σ r² / (3n − 6)`.
use super::KinematicChain;
use crate::error::{Error, Result};
use crate::geom::{kabsch, mount_rotation, mount_rotation_angles, mount_rotation_partials, transform_point};
use crate::optim::{levenberg_marquardt, LeastSquares, LmOptions, LmStop};
use nalgebra::{Matrix4, SMatrix, SVector, Vector3};

#[derive(Debug, Clone, PartialEq)]
pub struct MountCalibration {
    /// (θ, ψ, φ, Δx, Δy, Δz): rad, rad, rad, mm, mm, mm.
    pub params: [f64; 6],
    /// Root mean square of the 3D residual distances, mm.
    pub rms: f64,
    /// Standard errors of the parameters from the covariance.
    pub std_errors: [f64; 6],
    /// Row-major 6×6 covariance of the parameters.
    pub covariance: [f64; 36],
    /// Residual distance of each correspondence, mm.
    pub residuals: Vec<f64>,
    pub iterations: usize,
    pub converged: bool,
}

struct MountProblem<'a> {
    scs: &'a [[f64; 3]],
    local: &'a [[f64; 3]],
}

impl MountProblem<'_> {
    fn residual(&self, r: &nalgebra::Matrix3<f64>, d: &Vector3<f64>, i: usize) -> Vector3<f64> {
        r * Vector3::from(self.scs[i]) + d - Vector3::from(self.local[i])
    }
}

impl LeastSquares<6> for MountProblem<'_> {
    fn len(&self) -> usize {
        3 * self.scs.len()
    }

    fn normal_equations(&self, x: &SVector<f64, 6>) -> (SMatrix<f64, 6, 6>, SVector<f64, 6>, f64) {
        let r = mount_rotation(x[0], x[1], x[2]);
        let dr = mount_rotation_partials(x[0], x[1], x[2]);
        let d = Vector3::new(x[3], x[4], x[5]);
        let mut jtj = SMatrix::<f64, 6, 6>::zeros();
        let mut g = SVector::<f64, 6>::zeros();
        let mut cost = 0.0;
        for i in 0..self.scs.len() {
            let s = Vector3::from(self.scs[i]);
            let res = self.residual(&r, &d, i);
            cost += 0.5 * res.norm_squared();
            // J rows for the 3 components: [dR_k s | I].
            let mut j = SMatrix::<f64, 3, 6>::zeros();
            for (k, drk) in dr.iter().enumerate() {
                j.fixed_view_mut::<3, 1>(0, k).copy_from(&(drk * s));
            }
            j.fixed_view_mut::<3, 3>(0, 3).copy_from(&nalgebra::Matrix3::identity());
            jtj += j.transpose() * j;
            g += j.transpose() * res;
        }
        (jtj, g, cost)
    }
}

/// [`calibrate_mount`] for an AC head with C2: `poses (n, 6)` row-major X, Y, Z, A, C, C2 at which
/// each point was seen (`None`: WCS = mount · SCS) and the C2 offset.
pub fn calibrate_mount_ac_head(
    scs: &[[f64; 3]],
    wcs: &[[f64; 3]],
    poses: Option<&[f64]>,
    c2_offset: [f64; 3],
) -> Result<MountCalibration> {
    let machine: Option<Vec<Matrix4<f64>>> = match poses {
        None => None,
        Some(p) => {
            // The head without its mount: the mount is what is solved for.
            let head = KinematicChain::ac_head(c2_offset, [0.0; 6])?;
            head.check_poses("axes", p, Some(scs.len()))?;
            Some(p.chunks_exact(6).map(|q| head.transform(q)).collect())
        }
    };
    calibrate_mount(scs, wcs, machine.as_deref())
}

/// `scs`, `wcs`: corresponding points. `machine`: for each point the transform WCS ← C2 frame
/// (the machine pose with the C2 axis and its offset, without the mount); `None` = identity.
pub fn calibrate_mount(
    scs: &[[f64; 3]],
    wcs: &[[f64; 3]],
    machine: Option<&[Matrix4<f64>]>,
) -> Result<MountCalibration> {
    let n = scs.len();
    if wcs.len() != n {
        return Err(Error::shape(
            "wcs_points",
            format!("({n}, 3): one point per SCS point"),
            format!("({}, 3)", wcs.len()),
        ));
    }
    if n < 3 {
        return Err(Error::shape("scs_points", "(n, 3) with n >= 3 correspondences", format!("({n}, 3)")));
    }
    let flat = |p: &[[f64; 3]]| p.iter().flatten().copied().collect::<Vec<_>>();
    crate::error::check_finite("scs_points", &flat(scs), 3)?;
    crate::error::check_finite("wcs_points", &flat(wcs), 3)?;
    let local: Vec<[f64; 3]> = match machine {
        None => wcs.to_vec(),
        Some(ts) => {
            if ts.len() != n {
                return Err(Error::shape(
                    "axes",
                    format!("({n}, 6): one pose per correspondence"),
                    format!("{} poses", ts.len()),
                ));
            }
            ts.iter()
                .zip(wcs)
                .map(|(t, p)| {
                    let inv = t.try_inverse().unwrap_or_else(Matrix4::identity);
                    transform_point(&inv, *p)
                })
                .collect()
        }
    };
    let start = kabsch(scs, &local).ok_or_else(|| {
        Error::invalid("scs_points", "the points are collinear: a line of points cannot fix the turn about itself; use points spread along the laser line at two or more heights, or several poses")
    })?;
    let (t0, p0, f0) = mount_rotation_angles(&start.rotation);
    let x0 = SVector::<f64, 6>::from([t0, p0, f0, start.translation.x, start.translation.y, start.translation.z]);
    let problem = MountProblem { scs, local: &local };
    let options = LmOptions { max_iterations: 200, ..LmOptions::default() };
    let fit = levenberg_marquardt(&problem, x0, &options);
    let x = fit.x;
    let r = mount_rotation(x[0], x[1], x[2]);
    let d = Vector3::new(x[3], x[4], x[5]);
    let residuals: Vec<f64> = (0..n).map(|i| problem.residual(&r, &d, i).norm()).collect();
    let ss: f64 = residuals.iter().map(|v| v * v).sum();
    let dof = (3 * n).saturating_sub(6).max(1) as f64;
    let sigma2 = ss / dof;
    let cov =
        fit.jtj.try_inverse().map(|m| m * sigma2).unwrap_or_else(|| SMatrix::<f64, 6, 6>::from_element(f64::INFINITY));
    let mut covariance = [0.0; 36];
    let mut std_errors = [0.0; 6];
    for a in 0..6 {
        std_errors[a] = cov[(a, a)].max(0.0).sqrt();
        for b in 0..6 {
            covariance[a * 6 + b] = cov[(a, b)];
        }
    }
    Ok(MountCalibration {
        params: [x[0], x[1], x[2], x[3], x[4], x[5]],
        rms: (ss / n as f64).sqrt(),
        std_errors,
        covariance,
        residuals,
        iterations: fit.iterations,
        converged: fit.stop.converged() || (fit.stop == LmStop::MaxIterations && fit.cost == 0.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_correspondences_give_exact_mount() {
        let truth = [0.02, -0.015, 1.3, 35.0, -2.0, -110.0];
        let r = mount_rotation(truth[0], truth[1], truth[2]);
        let d = Vector3::new(truth[3], truth[4], truth[5]);
        let scs: Vec<[f64; 3]> = (0..60).map(|i| [(i as f64 - 30.0) * 1.3, 0.0, ((i * 13) % 7) as f64 - 3.0]).collect();
        let wcs: Vec<[f64; 3]> = scs.iter().map(|s| (r * Vector3::from(*s) + d).into()).collect();
        let cal = calibrate_mount(&scs, &wcs, None).unwrap();
        for (p, t) in cal.params.iter().zip(truth) {
            assert!((p - t).abs() < 1e-9, "{:?}", cal.params);
        }
        assert!(cal.rms < 1e-9);
        assert!(cal.converged);
    }

    #[test]
    fn collinear_points_are_refused() {
        let scs: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 0.0, 0.0]).collect();
        let e = calibrate_mount(&scs, &scs, None).unwrap_err();
        assert!(e.to_string().starts_with("scs_points"));
    }
}
