//! Surface meshes of scanned and theoretical surfaces (SPEC S1–S3; paper 002 §3): the Delaunay
//! triangulation of a height-field surface in its xy projection, closest points on a mesh, and
//! points inserted as vertices.
pub mod closest;
pub mod delaunay;
pub mod geodesic;
pub mod geodesic_exact;
pub mod geodesic_heat;
pub mod insert;
pub mod locate;

pub use closest::{closest_points, Closest, TriangleBvh};
pub use delaunay::delaunay_xy;
pub use geodesic::{geodesic_distances, geodesic_fmm, GeodesicMethod};
pub use geodesic_exact::geodesic_exact;
pub use geodesic_heat::{geodesic_heat, HeatSolver};
pub use insert::{insert_points, Inserted, Landing};
pub use locate::{XyLanding, XyLocator};

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

/// The faces of a surface argument given either as scan points (meshed by `delaunay_xy`, long
/// edges beyond `max_edge` left out) or as a mesh; errors name the argument, `name`.
pub fn surface_faces(
    name: &str,
    points: &[[f64; 3]],
    faces: Option<Vec<[u32; 3]>>,
    max_edge: Option<f64>,
) -> Result<Vec<[u32; 3]>> {
    let renamed = |e: Error| match e {
        Error::Invalid { name: arg, reason } if arg == "points" || arg == "vertices" || arg == "faces" => {
            Error::invalid(name, reason)
        }
        other => other,
    };
    crate::error::check_finite_points(name, points)?;
    let faces = match faces {
        Some(f) => {
            check_faces(points.len(), &f).map_err(renamed)?;
            f
        }
        None => delaunay_xy(points, max_edge).map_err(renamed)?,
    };
    if faces.is_empty() {
        return Err(Error::invalid(name, "the surface has no triangles"));
    }
    Ok(faces)
}

/// Meshes with known geodesics, shared by the geodesic tests.
#[cfg(test)]
pub(crate) mod test_meshes {
    /// A flat n × n grid of spacing h, split along alternating diagonals.
    pub(crate) fn grid(n: usize, h: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        grid_nm(n, n, h)
    }

    /// A flat n × m grid (n along x) of spacing h, split along alternating diagonals.
    pub(crate) fn grid_nm(n: usize, m: usize, h: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let v = (0..n * m).map(|i| [(i % n) as f64 * h, (i / n) as f64 * h, 0.0]).collect();
        let mut f = Vec::new();
        for j in 0..m - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
                if (i + j) % 2 == 0 {
                    f.extend([[a, b, d], [a, d, c]]);
                } else {
                    f.extend([[a, b, c], [b, d, c]]);
                }
            }
        }
        (v, f)
    }
}
