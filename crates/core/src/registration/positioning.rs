//! Positioning errors (SPEC R5; paper 003 eq 11–14): how far each measured point lies from the
//! model, per axis. Against a model given as points alone the reference is the closest model
//! point; with normals it is the closest point of the model surface, the tangent plane at the
//! closest model point (the sampling of the model then does not count as error).
use crate::error::{check_finite_points, Error, Result};
use crate::geom::transform_point;
use crate::spatial::PointIndex;
use nalgebra::{Matrix4, Matrix6, SymmetricEigen, Vector3, Vector6};
use rayon::prelude::*;

/// `e = p − q` for each measured point p (`e_x, e_y, e_z`; `e_total = |e|` is the caller's):
/// q the closest model point, or with `normals` the foot of p on the tangent plane there, so
/// that `e = ((p − q)·n) n`.
pub fn positioning_errors(
    measured: &[[f64; 3]],
    model: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
) -> Result<Vec<[f64; 3]>> {
    check_finite_points("measured", measured)?;
    check_finite_points("model_points", model)?;
    if model.is_empty() {
        return Err(Error::invalid("model_points", "must hold at least one point"));
    }
    if let Some(n) = normals {
        super::check_normals("model_normals", n, model.len())?;
    }
    let index = PointIndex::new(model)?;
    Ok(measured
        .par_iter()
        .map(|p| {
            let (j, _) = index.nearest_squared(p);
            let d = Vector3::from(*p) - Vector3::from(model[j]);
            match normals {
                Some(n) => {
                    let n = Vector3::from(n[j]).normalize();
                    (d.dot(&n) * n).into()
                }
                None => d.into(),
            }
        })
        .collect())
}

/// Gauss–Newton iterations of [`probe_fit`]; it converges quadratically, in 3–5 from a
/// millimetre off.
const PROBE_FIT_ITERATIONS: usize = 50;

/// A probe fit has converged when its last update moves no probe point by more than this, mm.
const PROBE_FIT_STEP: f64 = 1e-12;

/// Directions of the pose that the probe points fix less than this share of the best-fixed
/// one (eigenvalues of the scaled normal equations) count as not fixed at all.
const UNFIXED: f64 = 1e-10;

/// The pose found by [`probe_fit`].
#[derive(Debug, Clone)]
pub struct ProbeFit {
    /// Model → machine: where the part sits.
    pub transformation: Matrix4<f64>,
    /// Signed distance of each probed surface point from the tangent plane of its model point,
    /// along the model normal (outward positive), at `transformation`, mm.
    pub residuals: Vec<f64>,
    pub iterations: usize,
}

/// The pose of a part from touch-probe points (paper 003 §4): probe point i was commanded at
/// model point `model[i]` along its normal, so it lies on the tangent plane there; the pose
/// minimises the squared distances from those planes. A ball probe reports its centre, which
/// lies on the surface offset outward by `probe_radius`: the planes are offset by the radius,
/// which compensates the ball exactly whatever the approach direction was (SPEC R6's
/// `surface = centre − r·n` with the normal of the fitted pose).
///
/// Fixed correspondences rather than nearest neighbours: the probe knows which point it was
/// sent to, and the tangent plane of that point is exact to second order in how far the probe
/// landed from it (κ s² / 2), which the next round at the corrected pose makes negligible.
/// `init` is the pose the probe points were commanded at (model → machine).
pub fn probe_fit(
    measured: &[[f64; 3]],
    model: &[[f64; 3]],
    normals: &[[f64; 3]],
    probe_radius: f64,
    init: &Matrix4<f64>,
) -> Result<ProbeFit> {
    check_finite_points("measured", measured)?;
    check_finite_points("model_points", model)?;
    super::check_normals("model_normals", normals, model.len())?;
    if measured.len() != model.len() {
        return Err(Error::shape(
            "measured",
            format!("({}, 3): one point per model point", model.len()),
            format!("({}, 3)", measured.len()),
        ));
    }
    if !(probe_radius.is_finite() && probe_radius >= 0.0) {
        return Err(Error::invalid("probe_radius", format!("must be ≥ 0 mm, got {probe_radius}")));
    }
    if measured.len() < 6 {
        return Err(Error::invalid(
            "measured",
            format!("a pose has 6 degrees of freedom: at least 6 probe points are needed, got {}", measured.len()),
        ));
    }
    let inverse = init.try_inverse().ok_or_else(|| Error::invalid("init", "is not invertible"))?;
    let normals: Vec<Vector3<f64>> = normals.iter().map(|n| Vector3::from(*n).normalize()).collect();
    // The machine → model transform is refined; the probe points are moved into the model frame.
    let mut to_model = inverse;
    // Rotations are scaled by the probe pattern's radius of gyration, so that the rank test
    // compares millimetres with millimetres.
    let (centre, scale) = super::spread(model);
    let residual = |t: &Matrix4<f64>, i: usize| {
        let s = Vector3::from(transform_point(t, measured[i]));
        (s - Vector3::from(model[i])).dot(&normals[i]) - probe_radius
    };
    let mut iterations = 0;
    while iterations < PROBE_FIT_ITERATIONS {
        iterations += 1;
        // Linearised about the pattern's centre: r + (ω × (s − c))·n + τ·n.
        let (jtj, jtr) = (0..measured.len()).fold((Matrix6::<f64>::zeros(), Vector6::<f64>::zeros()), |(a, b), i| {
            let s = Vector3::from(transform_point(&to_model, measured[i]));
            let c = (s - centre).cross(&normals[i]) / scale;
            let j = Vector6::new(c[0], c[1], c[2], normals[i][0], normals[i][1], normals[i][2]);
            (a + j * j.transpose(), b + residual(&to_model, i) * j)
        });
        let eig = SymmetricEigen::new(jtj);
        let largest = eig.eigenvalues.max();
        if eig.eigenvalues.iter().any(|&l| l <= UNFIXED * largest) {
            return Err(Error::invalid(
                "model_points",
                "the probe points do not fix the pose: their normals leave a direction of motion free \
                 (e.g. all on one plane or on one cylinder); choose points with more varied normals",
            ));
        }
        let x =
            -(eig.eigenvectors * eig.eigenvalues.map(|l| 1.0 / l).component_mul(&(eig.eigenvectors.transpose() * jtr)));
        let step = super::twist(&(Vector3::new(x[0], x[1], x[2]) / scale), &Vector3::new(x[3], x[4], x[5]), &centre);
        to_model = step * to_model;
        // The largest displacement of the pattern under the update bounds every probe point's.
        if x.norm() * 2.0 < PROBE_FIT_STEP {
            break;
        }
    }
    let residuals = (0..measured.len()).map(|i| residual(&to_model, i)).collect();
    let transformation = to_model.try_inverse().ok_or_else(|| Error::invalid("measured", "gave a singular pose"))?;
    Ok(ProbeFit { transformation, residuals, iterations })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geom::mount_rotation;

    /// A doubly curved patch z = x²/200 − y²/300 + xy/500 and its upward normals.
    fn patch(n: usize) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        (0..n * n)
            .map(|i| {
                let (x, y) = (-40.0 + 80.0 * (i % n) as f64 / n as f64, -40.0 + 80.0 * (i / n) as f64 / n as f64);
                let z = x * x / 200.0 - y * y / 300.0 + x * y / 500.0;
                let g = Vector3::new(-(x / 100.0 + y / 500.0), -(-y / 150.0 + x / 500.0), 1.0).normalize();
                ([x, y, z], [g[0], g[1], g[2]])
            })
            .unzip()
    }

    #[test]
    fn probe_fit_recovers_the_pose_from_points_on_the_tangent_planes() {
        let (model, normals) = patch(20);
        let mut truth = Matrix4::identity();
        truth.fixed_view_mut::<3, 3>(0, 0).copy_from(&mount_rotation(0.004, -0.006, 0.008));
        truth.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::new(0.3, -0.2, 0.4));
        // Ball centres of a 2 mm probe touching exactly the model points of the true part, each
        // also slid along its tangent plane (which the fit must not see).
        let r = 2.0;
        let measured: Vec<[f64; 3]> = model
            .iter()
            .zip(&normals)
            .map(|(q, n)| {
                let (q, n) = (Vector3::from(*q), Vector3::from(*n));
                let slide = n.cross(&Vector3::new(0.3, 0.7, 0.1)).normalize() * 1e-4;
                transform_point(&truth, (q + slide + r * n).into())
            })
            .collect();
        let fit = probe_fit(&measured, &model, &normals, r, &Matrix4::identity()).unwrap();
        assert!((fit.transformation - truth).abs().max() < 1e-9, "{}", fit.transformation - truth);
        assert!(fit.residuals.iter().all(|e| e.abs() < 1e-9));
        assert!(fit.iterations < 10);
    }

    #[test]
    fn a_probe_pattern_that_leaves_a_motion_free_is_refused() {
        let model: Vec<[f64; 3]> = (0..50).map(|i| [(i % 7) as f64, (i / 7) as f64, 0.0]).collect();
        let normals = vec![[0.0, 0.0, 1.0]; model.len()];
        let err = probe_fit(&model, &model, &normals, 0.0, &Matrix4::identity()).unwrap_err().to_string();
        assert!(err.contains("model_points") && err.contains("do not fix the pose"), "{err}");
        let err = probe_fit(&model[..3], &model[..3], &normals[..3], 0.0, &Matrix4::identity()).unwrap_err();
        assert!(err.to_string().contains("at least 6"));
        assert!(probe_fit(&model, &model, &normals, -1.0, &Matrix4::identity()).is_err());
    }

    #[test]
    fn errors_against_points_and_against_the_surface() {
        // A plane z = 0 sampled every 1 mm; measured points 10 µm above it, anywhere in x, y.
        let model: Vec<[f64; 3]> = (0..400).map(|i| [(i % 20) as f64, (i / 20) as f64, 0.0]).collect();
        let normals = vec![[0.0, 0.0, 2.0]; model.len()];
        let measured = [[3.3, 7.6, 0.01], [10.45, 2.2, 0.01]];
        let surface = positioning_errors(&measured, &model, Some(&normals)).unwrap();
        assert!(surface.iter().all(|e| e[0] == 0.0 && e[1] == 0.0 && (e[2] - 0.01).abs() < 1e-15));
        let points = positioning_errors(&measured, &model, None).unwrap();
        assert!((points[0][0] - 0.3).abs() < 1e-12 && (points[0][1] + 0.4).abs() < 1e-12);
        assert!(positioning_errors(&measured, &model, Some(&normals[..3]))
            .unwrap_err()
            .to_string()
            .contains("model_normals"));
    }
}
