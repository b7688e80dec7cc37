//! Surface meshes of scanned and theoretical surfaces (SPEC S1–S3; paper 002 §3): the Delaunay
//! triangulation of a height-field surface in its xy projection, closest points on a mesh, and
//! points inserted as vertices.
//! The formulas: docs/mesh.md.
pub mod closest;
pub mod delaunay;
pub mod geodesic;
pub mod insert;
pub mod locate;
pub mod signed;
pub mod thin;

pub use closest::{closest_points, Closest, TriangleBvh};
pub use delaunay::{delaunay_xy, edge_length, peel_long_edges};
pub use geodesic::{geodesic_distances, geodesic_fmm, GeodesicMethod, GeodesicSolver};
pub use geodesic::{geodesic_exact, geodesic_heat, HeatSolver};
pub use insert::{insert_points, Inserted, Landing};
pub use locate::{XyLanding, XyLocator};
pub use signed::{
    face_statistics, signed_distances, unit_face_normals, FaceStatistics, PseudoNormals, SignedClosest, SignedMesh,
};
pub use thin::{thin_xy, xy_area};

use crate::error::{Error, Result};
use std::borrow::Cow;

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
    let given = faces.is_some();
    let faces = match faces {
        Some(f) => {
            check_faces(points.len(), &f).map_err(renamed)?;
            f
        }
        None => delaunay_xy(points, max_edge).map_err(renamed)?,
    };
    if faces.is_empty() {
        if let (false, Some(limit)) = (given, max_edge) {
            // Delaunay gave triangles (the points passed its checks); the trim took them all.
            let all = delaunay_xy(points, None).map_err(renamed)?;
            return Err(Error::invalid(
                "max_edge",
                format!(
                    "{limit} mm left no triangle of {name} (its Delaunay edges' median is {:.4} mm)",
                    median_edge(points, &all)
                ),
            ));
        }
        return Err(Error::invalid(name, "the surface has no triangles"));
    }
    Ok(faces)
}

/// How finely a surface given as points is meshed for geodesic work (see `thin`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spacing {
    /// Thinned to about `GEODESIC_VERTICES` vertices when the points are denser than that.
    Auto,
    /// Every point a vertex.
    Full,
    /// Thinned to about one vertex per `spacing` × `spacing` mm of the xy plane.
    Fixed(f64),
}

/// The vertices of `Spacing::Auto`: on the skin (300 × 200 mm, 1.3 mm scan) a match with
/// exact geodesics takes seconds at this size and minutes at the scan's 36 000, for the same
/// matched points to a micrometre (BENCHMARKS.md).
pub const GEODESIC_VERTICES: usize = 2000;

impl Spacing {
    /// The word form: "auto".
    pub fn parse(word: &str) -> Result<Self> {
        match word {
            "auto" => Ok(Spacing::Auto),
            _ => Err(Error::invalid("spacing", format!("expected 'auto', a spacing in mm or None, got {word:?}"))),
        }
    }
}

/// The long-edge trim of `surface_mesh` when no `max_edge` is given: triangles with an outline
/// edge beyond this many times the median edge are peeled off (`peel_long_edges`). Delaunay's
/// hull adds long, thin triangles across every inward-bowing stretch of the outline (the edge
/// of a bent part that is tilted bows by tens of µm in xy), and their straight edges are
/// shortcuts for geodesics between points near the edge: 0.15 mm on a 120 mm skin bent to
/// R 400 mm and tilted 0.01 rad, enough to stall the matching. Gaps inside the scan stay
/// bridged: trimming every long edge made geodesics go round a clamp's 12 mm shadow and the
/// match stalled at E 1.8 mm (found in review, 2026-11-23).
pub const EDGE_TRIM: f64 = 4.0;

/// The least distance (mm) from a surface at which a point that should lie on it is refused
/// (`off_surface_limit`).
pub const OFF_SURFACE_MM: f64 = 1.0;

/// How far from a surface mesh a point that should lie on it (a locating or matching point) may
/// be: two median edges of the mesh, at least `OFF_SURFACE_MM`. A point just beyond the outline
/// of a scan is on the part (the outermost points of a scan lie up to a spacing or two inside its
/// edge, more where the laser loses the edge); one farther off is a wrong point (its units, a
/// typo), whose closest point, on the surface's edge, would be used as if it were right.
/// `median_edge` is that of the surface as given (its points' spacing), not of a thinned mesh.
pub fn off_surface_limit(median_edge: f64) -> f64 {
    (2.0 * median_edge).max(OFF_SURFACE_MM)
}

/// The error for point `i` of argument `name`, `distance` from the surface (`off_surface_limit`).
pub fn off_surface(name: &str, i: usize, p: [f64; 3], distance: f64, limit: f64) -> crate::error::Error {
    crate::error::Error::invalid(
        name,
        format!(
            "point {i} ({:.3}, {:.3}, {:.3}) lies {distance:.3} mm from the surface, more than {limit:.3} mm (two median edges of \
             the surface as given, at least {OFF_SURFACE_MM} mm): it is not on the part (check its coordinates and units)",
            p[0], p[1], p[2]
        ),
    )
}

/// The median length of the triangles' edges (each inner edge counted twice; on big meshes
/// over a sample of about 20 000 triangles, evenly spread); 0 without triangles.
pub fn median_edge(points: &[[f64; 3]], faces: &[[u32; 3]]) -> f64 {
    let mut lengths: Vec<f64> = faces
        .iter()
        .step_by((faces.len() / 20_000).max(1))
        .flat_map(|t| (0..3).map(move |k| edge_length(points, t[k], t[(k + 1) % 3])))
        .collect();
    if lengths.is_empty() {
        return 0.0;
    }
    let mid = lengths.len() / 2;
    *lengths.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// A surface as a caller gives it: scan points, meshed where a kernel needs a mesh
/// ([`surface_mesh`]), or the vertices of a mesh with its triangles.
#[derive(Debug, Clone, Copy)]
pub struct ScanSurface<'a> {
    pub points: &'a [[f64; 3]],
    pub faces: Option<&'a [[u32; 3]]>,
}

impl<'a> ScanSurface<'a> {
    /// The surface as a mesh ([`surface_mesh`]); errors name the argument `name`.
    pub fn mesh(&self, name: &str, max_edge: Option<f64>, spacing: Spacing) -> Result<SurfaceMesh<'a>> {
        surface_mesh(name, self.points, self.faces.map(<[_]>::to_vec), max_edge, spacing)
    }
}

/// Vertices (the given points when none were dropped), triangles, and the median edge of the
/// surface as given (before any thinning: the points' own spacing).
pub type SurfaceMesh<'a> = (Cow<'a, [[f64; 3]]>, Vec<[u32; 3]>, f64);

/// A surface argument as a mesh for geodesic work: a mesh as given, or scan points meshed by
/// `delaunay_xy` (triangles with an edge beyond `max_edge` left out; without it, beyond
/// `EDGE_TRIM` × the median edge) and thinned as `spacing` says (`thin_xy`; the thinned points'
/// triangles kept where they lie over that mesh). Errors name the argument.
pub fn surface_mesh<'a>(
    name: &str,
    points: &'a [[f64; 3]],
    faces: Option<Vec<[u32; 3]>>,
    max_edge: Option<f64>,
    spacing: Spacing,
) -> Result<SurfaceMesh<'a>> {
    if let Spacing::Fixed(mm) = spacing {
        if !(mm.is_finite() && mm > 0.0) {
            return Err(Error::invalid("spacing", format!("must be a positive finite number of mm, got {mm}")));
        }
    }
    let given = faces.is_some();
    let full = surface_faces(name, points, faces, max_edge)?;
    // The surface as given: the points' own spacing (for `off_surface_limit`) and the peel's scale.
    let edge = median_edge(points, &full);
    if given {
        return Ok((Cow::Borrowed(points), full, edge));
    }
    let full = match max_edge {
        Some(_) => full,
        None => {
            let trim = EDGE_TRIM * edge;
            let kept = peel_long_edges(points, full, trim);
            if kept.is_empty() {
                return Err(Error::invalid(name, "no triangle is left after the long-edge trim: give max_edge"));
            }
            kept
        }
    };
    let spacing = match spacing {
        Spacing::Full => None,
        Spacing::Fixed(s) => Some(s),
        Spacing::Auto => {
            let area = xy_area(points, &full);
            let (wanted, data) = ((area / GEODESIC_VERTICES as f64).sqrt(), (area / points.len() as f64).sqrt());
            (wanted > 1.5 * data).then_some(wanted)
        }
    };
    let Some(s) = spacing else {
        return Ok((Cow::Borrowed(points), full, edge));
    };
    let kept: Vec<[f64; 3]> = thin_xy(points, &full, s).into_iter().map(|i| points[i]).collect();
    // The thinned points' triangles that lie over the full mesh: a concave outline stays concave
    // (a long-edge trim at the coarse spacing would fill notches narrower than a few spacings).
    let over = XyLocator::new(points, &full);
    let faces: Vec<[u32; 3]> = surface_faces(name, &kept, None, None)?
        .into_iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| kept[i as usize]);
            over.locate((a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0).is_some()
        })
        .collect();
    if faces.is_empty() {
        return Err(Error::invalid(name, "the thinned surface has no triangles: give a smaller spacing"));
    }
    Ok((Cow::Owned(kept), faces, edge))
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
