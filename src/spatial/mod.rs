//! Neighbourhood queries over point clouds: one kd-tree facade (kiddo) that clustering,
//! filters, normals and registration all use, and Euclidean clustering (SPEC C1).
mod cluster;
mod index;

pub use cluster::euclidean_clusters;
pub use index::PointIndex;
