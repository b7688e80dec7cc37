//! Neighborhood queries over point clouds, in one place for clustering, filters, normals and
//! registration: `PointIndex` (kiddo) for queries from arbitrary points, `CloudNeighbors` for
//! the neighborhoods of every point of a cloud at once; and Euclidean clustering (SPEC C1).
mod cluster;
mod index;
mod neighbors;

pub use cluster::euclidean_clusters;
pub use index::PointIndex;
pub use neighbors::{CloudNeighbors, Neighbor};
