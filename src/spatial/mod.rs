//! Neighbourhood queries over point clouds, in one place for clustering, filters, normals and
//! registration: `PointIndex` (kiddo) for queries from arbitrary points, `CloudNeighbours` for
//! the neighbourhoods of every point of a cloud at once; and Euclidean clustering (SPEC C1).
mod cluster;
mod index;
mod neighbours;

pub use cluster::euclidean_clusters;
pub use index::PointIndex;
pub use neighbours::{CloudNeighbours, Neighbour};
