//! Point cloud preparation (SPEC F, papers 002 §2 and 004 §1.1): filters, normals and
//! curvature, octree simplification keeping features and the boundary.
//! The formulas: docs/clouds.md.
mod filters;
mod normals;
mod octree;

pub use filters::{
    crop_box, random_downsample, remove_duplicates, remove_radius_outliers, remove_statistical_outliers,
    uniform_downsample, voxel_downsample, VoxelFrame, VoxelGrid,
};
pub use normals::{
    estimate_normals, estimate_oriented_normals, orient_along, orient_consistent, orient_towards, principal_curvatures,
    Neighborhood, Orientation, PrincipalCurvature,
};
pub use octree::{boundary_points, feature_degree, octree_simplify, NeighborSpace, OctreeOptions};
