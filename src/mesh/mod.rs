//! Surface meshes of scanned and theoretical surfaces (SPEC S1–S3; paper 002 §3): the Delaunay
//! triangulation of a height-field surface in its xy projection, closest points on a mesh, and
//! points inserted as vertices.
pub mod closest;
pub mod delaunay;
pub mod geodesic;
pub mod insert;

pub use closest::{closest_points, Closest, TriangleBvh};
pub use delaunay::delaunay_xy;
pub use geodesic::geodesic_fmm;
pub use insert::{insert_points, Inserted, Landing};
