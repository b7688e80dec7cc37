//! Small shared geometry: elementary rotations, the Euler forms the papers use, rigid
//! transforms and the Kabsch fit.
//! The formulas: docs/kinematics.md.
mod rigid;
mod rotation;

pub use rigid::{kabsch, transform_point, transform_rows, transform_vector, RigidFit};
pub use rotation::{mount_rotation, mount_rotation_angles, mount_rotation_partials, rot_x, rot_y, rot_z, Axis};

/// Axis-aligned bounds `(min, max)` of the points (±∞ when there are none).
pub fn bounds(points: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}
