//! Surface meshes of scanned and theoretical surfaces (SPEC S1–S3; paper 002 §3): the Delaunay
//! triangulation of a height-field surface in its xy projection.
pub mod delaunay;

pub use delaunay::delaunay_xy;
