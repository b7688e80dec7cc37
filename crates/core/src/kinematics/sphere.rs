//! Sensor mount calibration with a reference sphere (SPEC K4 "beyond"): what plants do instead of
//! measuring correspondences on a CMM. A sphere of known radius R is scanned from several machine
//! poses; every valid reading, carried to the WCS with the machine pose and a trial mount, must
//! lie on the sphere. The six mount parameters m = (θ, ψ, φ, Δ) and the centre c solve
//!
//!   min Σ (|M_f (R(θ, ψ, φ) s + Δ) − c| − R)²
//!
//! over every reading s of every frame f (M_f the machine's WCS ← C2 transform at the frame's
//! pose), by Levenberg–Marquardt on the analytic Jacobian: with u the unit vector from c to the
//! point, ∂r/∂Δ = uᵀ M_R, ∂r/∂angle_k = uᵀ M_R (∂R/∂angle_k) s, ∂r/∂c = −uᵀ.
//!
//! A sphere looks the same from every direction, so poses that see it alike leave motions of
//! the mount unseen (turning the sensor about the sphere's centre when the sphere always sits at
//! the same place of the laser line and stand-off): the normal equations are checked, scaled to
//! unit diagonal, and a direction with an eigenvalue below 1e-10 of the largest is refused,
//! naming the parameters it moves.
use super::{profile_to_points, KinematicChain, Profiler};
use crate::error::{Error, Result};
use crate::geom::{mount_rotation, mount_rotation_partials};
use crate::optim::{levenberg_marquardt, LeastSquares, LmOptions};
use nalgebra::{Matrix3, Matrix4, SMatrix, SVector, Vector3};

/// The parameters in their order: the mount's, then the centre's.
pub const SPHERE_PARAMETERS: [&str; 9] = ["theta", "psi", "phi", "dx", "dy", "dz", "center_x", "center_y", "center_z"];

#[derive(Debug, Clone, PartialEq)]
pub struct SphereCalibration {
    /// (θ, ψ, φ, Δx, Δy, Δz): rad, mm.
    pub mount: [f64; 6],
    /// The sphere's centre in the WCS, mm.
    pub center: [f64; 3],
    /// Row-major 9×9 covariance `σ̂² (JᵀJ)⁻¹`, `σ̂² = Σ r² / (n − 9)`, in the order of
    /// `SPHERE_PARAMETERS`.
    pub covariance: [f64; 81],
    pub std_errors: [f64; 9],
    /// Root mean square of the distances of the points from the sphere, mm.
    pub rms: f64,
    /// Distance of each point from the sphere (+ outside), mm.
    pub residuals: Vec<f64>,
    /// The frame of each point.
    pub frame_index: Vec<i64>,
    pub iterations: usize,
    pub converged: bool,
}

struct SphereProblem<'a> {
    scs: &'a [[f64; 3]],
    machine: Vec<Matrix4<f64>>,
    frame: &'a [i64],
    radius: f64,
}

impl SphereProblem<'_> {
    /// The WCS point of reading i at parameters x.
    fn point(&self, rotation: &Matrix3<f64>, x: &SVector<f64, 9>, i: usize) -> Vector3<f64> {
        let m = &self.machine[self.frame[i] as usize];
        let local = rotation * Vector3::from(self.scs[i]) + Vector3::new(x[3], x[4], x[5]);
        m.fixed_view::<3, 3>(0, 0) * local + m.fixed_view::<3, 1>(0, 3)
    }

    fn residuals(&self, x: &SVector<f64, 9>) -> Vec<f64> {
        let rotation = mount_rotation(x[0], x[1], x[2]);
        let c = Vector3::new(x[6], x[7], x[8]);
        (0..self.scs.len()).map(|i| (self.point(&rotation, x, i) - c).norm() - self.radius).collect()
    }
}

impl LeastSquares<9> for SphereProblem<'_> {
    fn len(&self) -> usize {
        self.scs.len()
    }

    fn normal_equations(&self, x: &SVector<f64, 9>) -> (SMatrix<f64, 9, 9>, SVector<f64, 9>, f64) {
        let rotation = mount_rotation(x[0], x[1], x[2]);
        let partials = mount_rotation_partials(x[0], x[1], x[2]);
        let c = Vector3::new(x[6], x[7], x[8]);
        let mut jtj = SMatrix::<f64, 9, 9>::zeros();
        let mut g = SVector::<f64, 9>::zeros();
        let mut cost = 0.0;
        for i in 0..self.scs.len() {
            let p = self.point(&rotation, x, i);
            let offset = p - c;
            let length = offset.norm();
            let r = length - self.radius;
            cost += 0.5 * r * r;
            // At the centre the direction is undefined; such a point carries no information.
            if length == 0.0 {
                continue;
            }
            let u = offset / length;
            let m = self.machine[self.frame[i] as usize].fixed_view::<3, 3>(0, 0).into_owned();
            let um = m.transpose() * u;
            let s = Vector3::from(self.scs[i]);
            let mut row = SVector::<f64, 9>::zeros();
            for (k, dr) in partials.iter().enumerate() {
                row[k] = um.dot(&(dr * s));
            }
            row[3] = um.x;
            row[4] = um.y;
            row[5] = um.z;
            row[6] = -u.x;
            row[7] = -u.y;
            row[8] = -u.z;
            jtj += row * row.transpose();
            g += row * r;
        }
        (jtj, g, cost)
    }
}

/// The centre of the sphere of radius `radius` best through `points` (an algebraic fit of
/// |p|² = 2 c·p + k with the radius free, for a start).
fn sphere_center(points: &[Vector3<f64>]) -> Option<Vector3<f64>> {
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let mut a = SMatrix::<f64, 4, 4>::zeros();
    let mut b = SVector::<f64, 4>::zeros();
    for p in points {
        let q = p - mean;
        let row = SVector::<f64, 4>::new(2.0 * q.x, 2.0 * q.y, 2.0 * q.z, 1.0);
        a += row * row.transpose();
        b += row * q.norm_squared();
    }
    let x = a.lu().solve(&b)?;
    Some(mean + Vector3::new(x[0], x[1], x[2]))
}

/// Calibrates the mount of an AC head with C2 from a scan of a sphere of `radius`: frames
/// `(F, n_readings)` row-major, `poses` (F, 6) X, Y, Z, A, C, C2, the C2 offset, a start for the
/// mount (the nominal one) and optionally for the centre (default: the sphere fitted to the
/// points at the start mount).
#[allow(clippy::too_many_arguments)]
pub fn calibrate_mount_sphere(
    frames: &[f64],
    n_readings: usize,
    profiler: &Profiler,
    poses: &[f64],
    c2_offset: [f64; 3],
    radius: f64,
    mount0: [f64; 6],
    center0: Option<[f64; 3]>,
) -> Result<SphereCalibration> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(Error::invalid("radius", format!("must be a positive length in mm, got {radius}")));
    }
    crate::error::check_finite("mount", &mount0, 6)?;
    let head = KinematicChain::ac_head(c2_offset, [0.0; 6])?;
    let n_frames = frames.len().checked_div(n_readings).unwrap_or(0);
    head.check_poses("poses", poses, Some(n_frames))?;
    let points = profile_to_points(frames, n_readings, profiler)?;
    let scs: Vec<[f64; 3]> = points.points.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    if scs.len() < 9 {
        return Err(Error::invalid(
            "scan",
            format!("{} valid readings: the sphere fit needs at least 9 (the mount's six and the centre)", scs.len()),
        ));
    }
    let machine: Vec<Matrix4<f64>> = poses.chunks_exact(6).map(|q| head.transform(q)).collect();
    let problem = SphereProblem { scs: &scs, machine, frame: &points.frame_index, radius };
    let x_start = SVector::<f64, 9>::from_iterator(mount0.iter().copied().chain([0.0; 3]));
    let center = match center0 {
        Some(c) => {
            crate::error::check_finite("center", &c, 3)?;
            Vector3::from(c)
        }
        None => {
            let rotation = mount_rotation(mount0[0], mount0[1], mount0[2]);
            let wcs: Vec<Vector3<f64>> = (0..scs.len()).map(|i| problem.point(&rotation, &x_start, i)).collect();
            sphere_center(&wcs).ok_or_else(|| {
                Error::invalid("scan", "the points lie on a plane or a line: they do not show a sphere")
            })?
        }
    };
    let mut x0 = x_start;
    x0[6] = center.x;
    x0[7] = center.y;
    x0[8] = center.z;
    undetermined(&problem.normal_equations(&x0).0)?;
    let options = LmOptions { max_iterations: 200, ..LmOptions::default() };
    let fit = levenberg_marquardt(&problem, x0, &options);
    let x = fit.x;
    undetermined(&fit.jtj)?;
    let residuals = problem.residuals(&x);
    let n = residuals.len();
    let ss: f64 = residuals.iter().map(|r| r * r).sum();
    let sigma2 = ss / (n.saturating_sub(9).max(1) as f64);
    let cov =
        fit.jtj.try_inverse().map(|m| m * sigma2).unwrap_or_else(|| SMatrix::<f64, 9, 9>::from_element(f64::INFINITY));
    let mut covariance = [0.0; 81];
    let mut std_errors = [0.0; 9];
    for a in 0..9 {
        std_errors[a] = cov[(a, a)].max(0.0).sqrt();
        for b in 0..9 {
            covariance[a * 9 + b] = cov[(a, b)];
        }
    }
    Ok(SphereCalibration {
        mount: [x[0], x[1], x[2], x[3], x[4], x[5]],
        center: [x[6], x[7], x[8]],
        covariance,
        std_errors,
        rms: (ss / n as f64).sqrt(),
        residuals,
        frame_index: points.frame_index,
        iterations: fit.iterations,
        converged: fit.stop.converged(),
    })
}

/// Refuses poses that leave a combination of the parameters unseen (module docs), from the
/// normal equations JᵀJ, naming the parameters the weakest direction moves and what to add.
fn undetermined(jtj: &SMatrix<f64, 9, 9>) -> Result<()> {
    let scale: Vec<f64> = (0..9).map(|i| jtj[(i, i)].sqrt()).collect();
    if let Some(k) = scale.iter().position(|&s| !(s > 0.0)) {
        return Err(Error::invalid(
            "scan",
            format!(
                "the points do not depend on {} at all: scan the sphere from poses that move it",
                SPHERE_PARAMETERS[k]
            ),
        ));
    }
    let scaled = SMatrix::<f64, 9, 9>::from_fn(|i, j| jtj[(i, j)] / (scale[i] * scale[j]));
    let eig = scaled.symmetric_eigen();
    let top = eig.eigenvalues.max();
    let (weakest, value) =
        eig.eigenvalues.iter().copied().enumerate().fold(
            (0, f64::INFINITY),
            |best, (i, v)| {
                if v < best.1 {
                    (i, v)
                } else {
                    best
                }
            },
        );
    if value > 1e-10 * top {
        return Ok(());
    }
    let v = eig.eigenvectors.column(weakest);
    let names: Vec<&str> = (0..9).filter(|&k| v[k].abs() > 0.3).map(|k| SPHERE_PARAMETERS[k]).collect();
    Err(Error::invalid(
        "scan",
        format!(
            "the poses do not determine {}: they can change together without moving a point off the sphere. Add \
             poses that turn the sensor differently (A, C, C2), and scan the sphere at other places along the laser \
             line and at other stand-offs",
            names.join(", ")
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::lcg;

    const RADIUS: f64 = 12.7;
    const C2: [f64; 3] = [-120.0, 35.0, 115.0];
    const MOUNT: [f64; 6] = [0.0031, -0.0024, 0.0042, 0.62, -0.41, -140.0];
    const CENTER: [f64; 3] = [200.0, 100.0, -50.0];

    /// Frames of the sphere seen from `angles` (A, C, C2), the sphere put at `spots` (x along the
    /// line, stand-off) in turn, seven sweeps ±6 mm across the line each; `noise` mm.
    fn scan(angles: &[[f64; 3]], spots: &[[f64; 2]], noise: f64) -> (Vec<f64>, Vec<f64>, Profiler) {
        let profiler = Profiler::new(0.05, 801, None, None, None).unwrap();
        let head = KinematicChain::ac_head(C2, MOUNT).unwrap();
        let (mut frames, mut poses) = (Vec::new(), Vec::new());
        let mut seed = 5u64;
        for (k, a) in angles.iter().enumerate() {
            let spot = spots[k % spots.len()];
            for s in 0..7 {
                let sweep = -6.0 + 2.0 * s as f64;
                let t0 = head.transform(&[0.0, 0.0, 0.0, a[0], a[1], a[2]]);
                let r = t0.fixed_view::<3, 3>(0, 0).into_owned();
                let want = Vector3::from(CENTER) + r * Vector3::new(spot[0], sweep, spot[1]);
                let shift = want - t0.fixed_view::<3, 1>(0, 3);
                let pose = [shift.x, shift.y, shift.z, a[0], a[1], a[2]];
                let t = head.transform(&pose).try_inverse().unwrap();
                let cs = t.fixed_view::<3, 3>(0, 0) * Vector3::from(CENTER) + t.fixed_view::<3, 1>(0, 3);
                for i in 0..801 {
                    let x = profiler.x(i);
                    let h = RADIUS * RADIUS - (x - cs.x).powi(2) - cs.y.powi(2);
                    // Box–Muller from two uniforms: Gaussian noise.
                    let (u1, u2) = (lcg(&mut seed).max(1e-300), lcg(&mut seed));
                    let e = noise * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                    frames.push(if h > 0.0 { cs.z + h.sqrt() + e } else { f64::NAN });
                }
                poses.extend(pose);
            }
        }
        (frames, poses, profiler)
    }

    /// Head orientations (A, C, C2), rad: 0°, 30°, 30° turned 90°, 30° turned 180° with C2 45°, 45°
    /// turned 270° with C2 90°.
    const ANGLES: [[f64; 3]; 5] =
        [[0.0, 0.0, 0.0], [0.52, 0.0, 0.0], [0.52, 1.57, 0.0], [0.52, 3.1, 0.79], [0.79, 4.71, 1.57]];
    const SPOTS: [[f64; 2]; 3] = [[-8.0, 52.0], [0.0, 60.0], [8.0, 68.0]];

    #[test]
    fn five_poses_recover_the_mount_and_the_centre_through_8_um_of_noise() {
        let (frames, poses, profiler) = scan(&ANGLES, &SPOTS, 0.008);
        let start = [0.0, 0.0, 0.0, 0.0, 0.0, -139.0];
        let cal = calibrate_mount_sphere(&frames, 801, &profiler, &poses, C2, RADIUS, start, None).unwrap();
        assert!(cal.converged);
        for k in 0..3 {
            assert!((cal.mount[k] - MOUNT[k]).abs() < 5e-5, "angle {k}: {} mrad", (cal.mount[k] - MOUNT[k]) * 1e3);
            assert!(
                (cal.mount[3 + k] - MOUNT[3 + k]).abs() < 0.005,
                "shift {k}: {} µm",
                (cal.mount[3 + k] - MOUNT[3 + k]) * 1e3
            );
            assert!((cal.center[k] - CENTER[k]).abs() < 0.005, "centre {k}");
        }
        assert!((cal.rms - 0.008).abs() < 0.003, "rms {}", cal.rms);
        // The covariance covers the errors (within 4 standard errors).
        for (k, (m, s)) in cal.mount.iter().zip(&cal.std_errors).enumerate() {
            assert!((m - MOUNT[k]).abs() < 4.0 * s + 1e-9, "{k}");
        }
    }

    #[test]
    fn poses_that_see_the_sphere_alike_are_refused_by_name() {
        // The sphere always at the same place of the line and stand-off: turning the sensor about
        // its centre is unseen.
        let (frames, poses, profiler) = scan(&ANGLES, &[[0.0, 60.0]], 0.0);
        let e = calibrate_mount_sphere(&frames, 801, &profiler, &poses, C2, RADIUS, MOUNT, Some(CENTER))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("scan: the poses do not determine") && e.contains("stand-offs"), "{e}");
        let e = calibrate_mount_sphere(&frames, 801, &profiler, &poses, C2, -1.0, MOUNT, None).unwrap_err().to_string();
        assert!(e.contains("radius"), "{e}");
    }
}
