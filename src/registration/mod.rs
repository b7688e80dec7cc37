//! Registration (SPEC R; papers 003 and 004 §1): where a measured part really sits against its
//! model. `icp` is the kernel the positioning and allowance workflows stand on.
pub mod allowance;
pub mod coarse;
pub mod icp;
pub mod locating;
pub mod positioning;

pub use allowance::allowance;
pub use coarse::coarse_align;
pub use icp::{icp, IcpMethod, IcpOptions, IcpResult, IcpStep, Robust, RobustKernel};
pub use locating::{line_curvature, locating_points};
pub use positioning::positioning_errors;

use crate::error::{check_finite_points, Error, Result};

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
