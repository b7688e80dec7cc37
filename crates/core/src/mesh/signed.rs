//! Signed distances to a triangle mesh: how far each measured point lies outside (+) or inside
//! (−) the CAD model, the figure every inspection report is built on.
//!
//! The distance is that of the closest point (closest.rs); the sign is that of (q − c)·n, with
//! n the angle-weighted pseudo-normal of the feature the closest point lies on — the face, one
//! of its edges or one of its corners (Bærentzen & Aanæs 2005). Unlike a sign from counting
//! ray crossings, it needs no closed mesh: it holds wherever the closest feature is surrounded
//! by consistently wound triangles, so an open CAD patch or a mesh with holes elsewhere still
//! gives the right sign near its surface. The triangles must be wound counter-clockwise seen
//! from outside; a mesh whose neighbours disagree, or a closed one wound inside out, is refused.
use super::closest::{Closest, TriangleBvh};
use crate::error::{check_finite_points, Error, Result};
use nalgebra::Vector3;
use rayon::prelude::*;

/// A measured point's signed distance and where it lands on the mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignedClosest {
    /// Distance to the closest point, + outside, − inside, mm.
    pub distance: f64,
    pub closest: Closest,
}

/// The pseudo-normals of a mesh: of each face, each face's three edges (edge k runs from
/// corner k to corner k + 1) and each vertex. Not unit length: only the sign of a dot product
/// with them is used.
pub struct PseudoNormals {
    face: Vec<Vector3<f64>>,
    edge: Vec<[Vector3<f64>; 3]>,
    vertex: Vec<Vector3<f64>>,
}

impl PseudoNormals {
    /// The pseudo-normals of `(vertices, faces)`, after checking that the winding is consistent:
    /// an edge shared by two triangles must run opposite ways in them.
    pub fn new(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<Self> {
        let corner = |f: &[u32; 3], k: usize| Vector3::from(vertices[f[k] as usize]);
        // A zero-area triangle's normal is zero: it adds nothing to its neighbours' sums.
        let face = unit_face_normals(vertices, faces);
        // Each corner's share of its vertex's pseudo-normal: its angle times the face normal.
        let share: Vec<[Vector3<f64>; 3]> = faces
            .par_iter()
            .zip(&face)
            .map(|(f, n)| {
                std::array::from_fn(|k| {
                    let (u, v) = (corner(f, (k + 1) % 3) - corner(f, k), corner(f, (k + 2) % 3) - corner(f, k));
                    let angle = if u.norm() > 0.0 && v.norm() > 0.0 { u.angle(&v) } else { 0.0 };
                    angle * n
                })
            })
            .collect();
        let mut vertex = vec![Vector3::zeros(); vertices.len()];
        for (f, s) in faces.iter().zip(&share) {
            for k in 0..3 {
                vertex[f[k] as usize] += s[k];
            }
        }
        // The edges: every triangle side (slot 3·face + k runs from corner k to k + 1) keyed by
        // its two vertices, sorted, so the sides of one edge are neighbours, in slot order.
        let key = |slot: usize| {
            let f = faces[slot / 3];
            let (a, b) = (f[slot % 3], f[(slot % 3 + 1) % 3]);
            (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
        };
        let mut sides: Vec<(u64, u32)> = (0..faces.len() * 3).into_par_iter().map(|s| (key(s), s as u32)).collect();
        sides.par_sort_unstable();
        let mut edge = vec![[Vector3::zeros(); 3]; faces.len()];
        let (mut clashing, mut closed) = (0usize, true);
        for group in sides.chunk_by(|x, y| x.0 == y.0) {
            // How often the edge runs from its lower vertex to its higher, and back.
            let forward = group
                .iter()
                .filter(|&&(_, s)| {
                    let f = faces[s as usize / 3];
                    f[s as usize % 3] < f[(s as usize % 3 + 1) % 3]
                })
                .count();
            let backward = group.len() - forward;
            if group.len() == 2 && (forward == 2 || backward == 2) {
                clashing += 1;
            }
            closed &= forward == 1 && backward == 1;
            let sum: Vector3<f64> = group.iter().map(|&(_, s)| face[s as usize / 3]).sum();
            for &(_, s) in group {
                edge[s as usize / 3][s as usize % 3] = sum;
            }
        }
        if clashing > 0 {
            return Err(Error::invalid(
                "faces",
                format!(
                    "{clashing} edges are run the same way by both their triangles: the triangles are not wound \
                     consistently, so inside and outside are undefined (wind every triangle counter-clockwise seen \
                     from outside, e.g. trimesh.repair.fix_winding)"
                ),
            ));
        }
        if closed && enclosed_volume(vertices, faces) < 0.0 {
            return Err(Error::invalid(
                "faces",
                "the closed mesh is wound inside out (its enclosed volume is negative): reverse each triangle's \
                 vertex order",
            ));
        }
        Ok(PseudoNormals { face, edge, vertex })
    }

    /// The pseudo-normal at a closest point: of the vertex when its weights put it on a corner,
    /// of the edge when one weight is zero, of the face otherwise.
    pub fn at(&self, faces: &[[u32; 3]], c: &Closest) -> Vector3<f64> {
        let w = c.barycentric;
        let f = faces[c.triangle];
        let zeros = w.iter().filter(|&&x| x == 0.0).count();
        match zeros {
            2 => self.vertex[f[(0..3).find(|&k| w[k] != 0.0).unwrap_or(0)] as usize],
            // The edge without weight is the one from corner k + 1 to k + 2 when w[k] = 0.
            1 => self.edge[c.triangle][((0..3).find(|&k| w[k] == 0.0).unwrap_or(0) + 1) % 3],
            _ => self.face[c.triangle],
        }
    }
}

/// Each triangle's unit normal (right-handed in its vertex order); zero for a triangle of no area,
/// which has no side.
pub fn unit_face_normals(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<Vector3<f64>> {
    faces
        .par_iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| Vector3::from(vertices[v as usize]));
            let n = (b - a).cross(&(c - a));
            let len = n.norm();
            if len > 0.0 {
                n / len
            } else {
                Vector3::zeros()
            }
        })
        .collect()
}

/// The volume the triangles enclose, by the divergence theorem (positive when wound
/// counter-clockwise seen from outside).
fn enclosed_volume(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> f64 {
    faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| Vector3::from(vertices[v as usize]));
            a.dot(&b.cross(&c))
        })
        .sum::<f64>()
        / 6.0
}

/// A mesh prepared for signed distances: its hierarchy and pseudo-normals.
pub struct SignedMesh<'a> {
    bvh: TriangleBvh<'a>,
    normals: PseudoNormals,
}

impl<'a> SignedMesh<'a> {
    pub fn new(vertices: &'a [[f64; 3]], faces: &'a [[u32; 3]]) -> Result<Self> {
        let bvh = TriangleBvh::new(vertices, faces)?;
        let normals = PseudoNormals::new(vertices, faces)?;
        Ok(SignedMesh { bvh, normals })
    }

    /// The sign of `q` against its closest point `c`: +1 outside, −1 inside; a point on the
    /// surface counts as outside with distance 0.
    fn signed(&self, q: &[f64; 3], c: Closest) -> SignedClosest {
        let n = self.normals.at(self.bvh.faces(), &c);
        let side = (Vector3::from(*q) - Vector3::from(c.point)).dot(&n);
        SignedClosest { distance: if side < 0.0 { -c.distance } else { c.distance }, closest: c }
    }

    pub fn signed_distance(&self, q: &[f64; 3]) -> SignedClosest {
        self.signed(q, self.bvh.closest(q))
    }

    /// Every query's signed distance, in parallel; independent of the thread count.
    pub fn signed_distances(&self, queries: &[[f64; 3]]) -> Vec<SignedClosest> {
        self.bvh.closest_many_with(queries, |q, c| self.signed(q, c))
    }
}

/// The signed distance of each point to the mesh `(vertices, faces)`.
pub fn signed_distances(vertices: &[[f64; 3]], faces: &[[u32; 3]], points: &[[f64; 3]]) -> Result<Vec<SignedClosest>> {
    check_finite_points("points", points)?;
    if points.len() > u32::MAX as usize {
        return Err(Error::invalid("points", format!("{} points is beyond 2^32", points.len())));
    }
    Ok(SignedMesh::new(vertices, faces)?.signed_distances(points))
}

/// Statistics of the signed distances of the points landing on one face (a CAD face, or the
/// whole mesh), mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceStatistics {
    pub face: u32,
    pub count: usize,
    pub min: f64,
    pub max: f64,
    pub mean: f64,
    /// Standard deviation (n − 1 in the denominator; 0 for one point).
    pub std: f64,
    /// Share of the points outside `[lower, upper]`, 0–1.
    pub out_of_tolerance: f64,
}

/// Per-face statistics of `distances`, the points grouped by `face_of_point`, for every face
/// `0..faces` that some point lands on, in face order. Tolerance `[lower, upper]` in mm.
pub fn face_statistics(
    distances: &[f64],
    face_of_point: &[u32],
    faces: usize,
    lower: f64,
    upper: f64,
) -> Result<Vec<FaceStatistics>> {
    if face_of_point.len() != distances.len() {
        return Err(Error::shape(
            "faces",
            format!("({},): one per distance", distances.len()),
            format!("({},)", face_of_point.len()),
        ));
    }
    if !(lower.is_finite() && upper.is_finite() && lower <= upper) {
        return Err(Error::invalid("tolerance", format!("needs finite lower <= upper, got [{lower}, {upper}]")));
    }
    if let Some(d) = distances.iter().find(|d| !d.is_finite()) {
        return Err(Error::invalid("distances", format!("must be finite, found {d}")));
    }
    if let Some(f) = face_of_point.iter().find(|&&f| f as usize >= faces) {
        return Err(Error::invalid("faces", format!("face {f} is beyond the {faces} faces")));
    }
    // Two passes in point order (mean, then squared deviations): exact enough for a spread far
    // below the mean, and the same figures whatever the thread count.
    let mut count = vec![0usize; faces];
    let mut sum = vec![0.0; faces];
    let mut min = vec![f64::INFINITY; faces];
    let mut max = vec![f64::NEG_INFINITY; faces];
    let mut out = vec![0usize; faces];
    for (&d, &f) in distances.iter().zip(face_of_point) {
        let f = f as usize;
        count[f] += 1;
        sum[f] += d;
        min[f] = min[f].min(d);
        max[f] = max[f].max(d);
        out[f] += usize::from(d < lower || d > upper);
    }
    let mean: Vec<f64> = (0..faces).map(|f| if count[f] > 0 { sum[f] / count[f] as f64 } else { 0.0 }).collect();
    let mut ss = vec![0.0; faces];
    for (&d, &f) in distances.iter().zip(face_of_point) {
        ss[f as usize] += (d - mean[f as usize]).powi(2);
    }
    Ok((0..faces)
        .filter(|&f| count[f] > 0)
        .map(|f| FaceStatistics {
            face: f as u32,
            count: count[f],
            min: min[f],
            max: max[f],
            mean: mean[f],
            std: if count[f] > 1 { (ss[f] / (count[f] - 1) as f64).sqrt() } else { 0.0 },
            out_of_tolerance: out[f] as f64 / count[f] as f64,
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cube of side 2 centred on the origin, wound outward.
    fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let v: Vec<[f64; 3]> = (0..8)
            .map(|i| [(i & 1) as f64 * 2.0 - 1.0, ((i >> 1) & 1) as f64 * 2.0 - 1.0, (i >> 2) as f64 * 2.0 - 1.0])
            .collect();
        let f = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        (v, f)
    }

    /// The exact signed distance to the cube [-1, 1]³.
    fn cube_sdf(p: [f64; 3]) -> f64 {
        let q = p.map(|x| x.abs() - 1.0);
        let outside = q.map(|x| x.max(0.0));
        let o = (outside[0].powi(2) + outside[1].powi(2) + outside[2].powi(2)).sqrt();
        o + q[0].max(q[1]).max(q[2]).min(0.0)
    }

    #[test]
    fn the_cube_gives_its_exact_signed_distance_near_faces_edges_and_corners() {
        let (v, f) = cube();
        let mut seed = 3u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let points: Vec<[f64; 3]> =
            (0..4000).map(|_| [next() * 4.0 - 2.0, next() * 4.0 - 2.0, next() * 4.0 - 2.0]).collect();
        let found = signed_distances(&v, &f, &points).unwrap();
        for (p, s) in points.iter().zip(&found) {
            assert!((s.distance - cube_sdf(*p)).abs() < 1e-12, "{p:?}: {} vs {}", s.distance, cube_sdf(*p));
        }
        // Exactly off a corner and an edge, where a face normal alone would give either sign.
        for p in [[1.5, 1.5, 1.5], [1.2, 1.3, 0.0], [-1.0001, 0.0, 0.0], [0.0, 0.0, 0.999]] {
            assert!((SignedMesh::new(&v, &f).unwrap().signed_distance(&p).distance - cube_sdf(p)).abs() < 1e-12);
        }
    }

    #[test]
    fn inconsistent_or_inside_out_winding_is_refused() {
        let (v, mut f) = cube();
        f[0] = [0, 1, 2];
        let e = signed_distances(&v, &f, &[[0.0; 3]]).unwrap_err().to_string();
        assert!(e.contains("faces") && e.contains("wound consistently"), "{e}");
        let (v, f) = cube();
        let flipped: Vec<[u32; 3]> = f.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let e = signed_distances(&v, &flipped, &[[0.0; 3]]).unwrap_err().to_string();
        assert!(e.contains("inside out"), "{e}");
    }

    #[test]
    fn an_open_patch_signs_by_its_winding() {
        // The cube's top face alone (+z outward): above +, below −, beside it by the edge.
        let (v, f) = cube();
        let top = vec![f[2], f[3]];
        let d =
            signed_distances(&v, &top, &[[0.0, 0.0, 1.5], [0.0, 0.0, 0.5], [1.5, 0.0, 1.5], [1.5, 0.0, 0.5]]).unwrap();
        assert!((d[0].distance - 0.5).abs() < 1e-15 && (d[1].distance + 0.5).abs() < 1e-15);
        assert!(d[2].distance > 0.0 && d[3].distance < 0.0);
    }

    #[test]
    fn face_statistics_match_their_definitions() {
        let d = [0.1, -0.2, 0.3, 0.05, 0.5];
        let faces = [0, 0, 2, 2, 2];
        let s = face_statistics(&d, &faces, 3, -0.1, 0.2).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].face, s[0].count, s[0].min, s[0].max), (0, 2, -0.2, 0.1));
        assert!((s[0].mean + 0.05).abs() < 1e-15 && (s[0].std - (0.045f64).sqrt()).abs() < 1e-15);
        assert!((s[0].out_of_tolerance - 0.5).abs() < 1e-15 && (s[1].out_of_tolerance - 2.0 / 3.0).abs() < 1e-15);
        assert!(face_statistics(&d, &faces, 2, -0.1, 0.2).unwrap_err().to_string().contains("faces"));
        assert!(face_statistics(&d, &faces, 3, 0.2, -0.1).unwrap_err().to_string().contains("tolerance"));
    }
}
