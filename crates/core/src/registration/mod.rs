//! Registration (SPEC R; papers 003 and 004 §1): where a measured part really sits against its
//! model. `icp` is the kernel the positioning and allowance workflows stand on.
//! The formulas: docs/registration.md.
pub mod allowance;
pub mod blank_alignment;
pub mod coarse;
pub mod envelope;
pub mod icp;
pub mod locating;
pub mod mesh_fit;
pub mod positioning;
mod stock;

pub use allowance::{allowance, BlankOptions, BlankSurface};
pub use blank_alignment::{align_blank, AlignmentStage, BlankAlignment};
pub use coarse::coarse_align;
pub use envelope::{envelope_fit, EnvelopeFit};
pub use icp::{icp, IcpMethod, IcpOptions, IcpResult, IcpStep, Robust, RobustKernel};
pub use locating::{
    cloud_locating_points, grid_locating_points, line_curvature, locating_points, probe_pattern, ProbePattern,
};
pub use mesh_fit::{fit_to_mesh, Dof, MeshFit, MeshFitOptions, RotaryAxis};
pub use positioning::{positioning_errors, probe_fit, ProbeFit};

use crate::error::{check_finite_points, Error, Result};
use nalgebra::{Matrix4, Rotation3, Vector3};

/// Model normals: finite, one per model point, none zero (a zero normal has no direction).
fn check_normals(name: &str, normals: &[[f64; 3]], points: usize) -> Result<()> {
    check_finite_points(name, normals)?;
    if normals.len() != points {
        return Err(Error::shape(
            name,
            format!("({points}, 3): one per model point"),
            format!("({}, 3)", normals.len()),
        ));
    }
    if let Some(i) = normals.iter().position(|n| n.iter().map(|c| c * c).sum::<f64>() < 1e-24) {
        return Err(Error::invalid(name, format!("normal {i} is zero: it has no direction")));
    }
    Ok(())
}

/// The small rigid motion that turns by the rotation vector `omega` about `centre` and then
/// moves by `tau`: the update of the Gauss–Newton fits, linearised about the centre of their
/// points so that rotation and translation are nearly uncoupled.
fn twist(omega: &Vector3<f64>, tau: &Vector3<f64>, centre: &Vector3<f64>) -> Matrix4<f64> {
    let r = Rotation3::new(*omega).into_inner();
    let mut t = Matrix4::identity();
    t.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    t.fixed_view_mut::<3, 1>(0, 3).copy_from(&(centre - r * centre + tau));
    t
}

/// The centroid of points and their RMS distance from it (at least 1e-9): the centre and the
/// length scale of the Gauss–Newton fits, whose rotations are scaled by it so that rank tests
/// and trust regions compare millimetres with millimetres.
fn spread(points: &[[f64; 3]]) -> (Vector3<f64>, f64) {
    let n = points.len().max(1) as f64;
    let centre = points.iter().fold(Vector3::zeros(), |a, p| a + Vector3::from(*p)) / n;
    let rms = (points.iter().map(|p| (Vector3::from(*p) - centre).norm_squared()).sum::<f64>() / n).sqrt();
    (centre, rms.max(1e-9))
}
