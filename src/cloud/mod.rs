//! Point cloud preparation (SPEC F, papers 002 §2 and 004 §1.1): filters so far; normals,
//! curvature and octree simplification follow.
mod filters;

pub use filters::{
    crop_box, radius_outlier_removal, random_downsample, remove_duplicates, statistical_outlier_removal,
    uniform_downsample, voxel_downsample, VoxelGrid,
};
