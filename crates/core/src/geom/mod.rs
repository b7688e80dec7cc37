//! Small shared geometry: elementary rotations, the Euler forms the papers use, rigid
//! transforms, the Kabsch fit, and the Morton order that keeps neighbouring queries together.
//! The formulas: docs/kinematics.md.
mod rigid;
mod rotation;

use rayon::prelude::*;
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

/// The indices of `points` sorted along the Morton curve of their bounding box (21 bits per
/// axis; ties by index, so the order is fixed).
pub fn morton_order(points: &[[f64; 3]]) -> Vec<u32> {
    let (lo, hi) = bounds(points);
    let scale: [f64; 3] = std::array::from_fn(|k| if hi[k] > lo[k] { 2_097_151.0 / (hi[k] - lo[k]) } else { 0.0 });
    // Spreads the 21 low bits of v to every third bit.
    let spread = |v: u64| {
        let mut x = v & 0x1f_ffff;
        x = (x | x << 32) & 0x001f_0000_0000_ffff;
        x = (x | x << 16) & 0x001f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let q: [u64; 3] = std::array::from_fn(|k| ((p[k] - lo[k]) * scale[k]) as u64);
            (spread(q[0]) | spread(q[1]) << 1 | spread(q[2]) << 2, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}
