//! Surface meshes of scanned and theoretical surfaces (SPEC S1–S3; paper 002 §3): the Delaunay
//! triangulation of a height-field surface in its xy projection, closest points on a mesh, and
//! points inserted as vertices.
pub mod closest;
pub mod delaunay;
pub mod geodesic;
pub mod geodesic_exact;
pub mod insert;

pub use closest::{closest_points, Closest, TriangleBvh};
pub use delaunay::delaunay_xy;
pub use geodesic::geodesic_fmm;
pub use geodesic_exact::geodesic_exact;
pub use insert::{insert_points, Inserted, Landing};

use crate::error::{Error, Result};

/// Faces whose indices all name one of the vertices.
fn check_faces(vertices: usize, faces: &[[u32; 3]]) -> Result<()> {
    match faces.iter().enumerate().find(|(_, f)| f.iter().any(|&v| v as usize >= vertices)) {
        Some((i, f)) => {
            Err(Error::invalid("faces", format!("triangle {i} = {f:?} refers to a vertex beyond the {vertices} given")))
        }
        None => Ok(()),
    }
}
