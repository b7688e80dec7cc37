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
