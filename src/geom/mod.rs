//! Small shared geometry: elementary rotations, the Euler forms the papers use, rigid
//! transforms and the Kabsch fit.
mod rigid;
mod rotation;

pub use rigid::{kabsch, transform_point, transform_vector, RigidFit};
pub use rotation::{
    mount_rotation, mount_rotation_angles, mount_rotation_partials, rot_x, rot_y, rot_z,
    Axis,
};
