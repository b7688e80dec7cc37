//! Point cloud preparation (SPEC F, papers 002 §2 and 004 §1.1): filters, normals and
//! curvature, octree simplification keeping features and the boundary.
mod filters;
mod normals;
mod octree;

pub use filters::{
    crop_box, radius_outlier_removal, random_downsample, remove_duplicates, statistical_outlier_removal,
    uniform_downsample, voxel_downsample, VoxelGrid,
};
pub use normals::{
    estimate_normals, orient_along, orient_consistent, orient_towards, principal_curvatures, Neighborhood,
};
pub use octree::{boundary_points, feature_degree, octree_simplify, NeighborSpace, OctreeOptions};
