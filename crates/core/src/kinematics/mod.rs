//! From profiler frames and machine axis positions to workpiece points (SPEC K1–K7).
//! The formulas: docs/kinematics.md.
mod calibration;
mod chain;
mod profiler;
mod scan;
mod sphere;
mod timing;

pub use calibration::{calibrate_mount, calibrate_mount_ac_head, MountCalibration};
pub use chain::{ac_table_rotate, AngleSource, KinematicChain, Step, StepArg};
pub use profiler::{profile_to_points, ProfilePoints, Profiler, ValidReadings, VENDOR_SENTINEL};
pub use scan::{frames_to_points, ScanPoints};
pub use sphere::{calibrate_mount_sphere, SphereCalibration, SPHERE_PARAMETERS};
pub use timing::interpolate_poses;
