//! Closest points on a triangle mesh (SPEC S2): for each query, the nearest point of the
//! surface, its triangle and barycentric coordinates — how a tool point is carried onto the
//! scanned surface, and how far a measured point is from a model.
//!
//! A bounding-volume hierarchy over the triangles, built once per call and searched in
//! parallel. Written here: the crates that offer one (parry, bvh) bring a geometry stack or an
//! f32-only API, and the search is short. Exact ties (a point equally close to two triangles,
//! on their shared edge) go to the lower triangle index, so results do not depend on threads.
use crate::error::{check_finite_points, Error, Result};
use nalgebra::Vector3;
use rayon::prelude::*;

/// Triangles per leaf of the hierarchy.
const LEAF: usize = 4;

/// The closest point of the mesh to one query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    pub point: [f64; 3],
    pub distance: f64,
    pub triangle: usize,
    /// Weights of the triangle's three vertices (sum 1, each in [0, 1]).
    pub barycentric: [f64; 3],
}

/// A node of the hierarchy: its box and either two children or a range of triangles.
struct Node {
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    /// Leaf: `(start, count)` in `order`; inner: `(left child, 0)` (right = left + 1).
    first: usize,
    count: usize,
}

/// The mesh and its hierarchy.
pub struct TriangleBvh<'a> {
    vertices: &'a [[f64; 3]],
    faces: &'a [[u32; 3]],
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl<'a> TriangleBvh<'a> {
    /// Builds the hierarchy by median splits of the triangle centroids along the box's longest
    /// axis. Faces are checked: indices in range.
    pub fn new(vertices: &'a [[f64; 3]], faces: &'a [[u32; 3]]) -> Result<Self> {
        check_finite_points("vertices", vertices)?;
        super::check_faces(vertices.len(), faces)?;
        if faces.is_empty() {
            return Err(Error::invalid("faces", "must hold at least one triangle"));
        }
        let corner = |t: u32, k: usize| Vector3::from(vertices[faces[t as usize][k] as usize]);
        let centroid: Vec<Vector3<f64>> =
            (0..faces.len() as u32).map(|t| (corner(t, 0) + corner(t, 1) + corner(t, 2)) / 3.0).collect();
        let mut bvh = TriangleBvh { vertices, faces, order: (0..faces.len() as u32).collect(), nodes: Vec::new() };
        bvh.nodes.push(Node { lo: Vector3::zeros(), hi: Vector3::zeros(), first: 0, count: faces.len() });
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let (first, count) = (bvh.nodes[n].first, bvh.nodes[n].count);
            let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
            for &t in &bvh.order[first..first + count] {
                for k in 0..3 {
                    let c = corner(t, k);
                    lo = lo.inf(&c);
                    hi = hi.sup(&c);
                }
            }
            bvh.nodes[n].lo = lo;
            bvh.nodes[n].hi = hi;
            if count <= LEAF {
                continue;
            }
            let axis = (hi - lo).imax();
            let mid = count / 2;
            bvh.order[first..first + count].select_nth_unstable_by(mid, |&a, &b| {
                centroid[a as usize][axis].total_cmp(&centroid[b as usize][axis]).then(a.cmp(&b))
            });
            let left = bvh.nodes.len();
            bvh.nodes.push(Node { lo, hi, first, count: mid });
            bvh.nodes.push(Node { lo, hi, first: first + mid, count: count - mid });
            bvh.nodes[n].first = left;
            bvh.nodes[n].count = 0;
            stack.push(left);
            stack.push(left + 1);
        }
        Ok(bvh)
    }

    /// The closest point of the mesh to `q`.
    pub fn closest(&self, q: &[f64; 3]) -> Closest {
        let q = Vector3::from(*q);
        let mut best =
            Closest { point: [f64::NAN; 3], distance: f64::INFINITY, triangle: usize::MAX, barycentric: [0.0; 3] };
        let mut best_d2 = f64::INFINITY;
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if box_distance2(&node.lo, &node.hi, &q) > best_d2 {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.first..node.first + node.count] {
                    let f = self.faces[t as usize];
                    let [a, b, c] = f.map(|v| Vector3::from(self.vertices[v as usize]));
                    let (p, w) = closest_on_triangle(&q, &a, &b, &c);
                    let d2 = (p - q).norm_squared();
                    if d2 < best_d2 || (d2 == best_d2 && (t as usize) < best.triangle) {
                        best_d2 = d2;
                        best = Closest { point: p.into(), distance: 0.0, triangle: t as usize, barycentric: w };
                    }
                }
            } else {
                // The nearer child last, so that it is searched first.
                let (l, r) = (node.first, node.first + 1);
                let (dl, dr) = (
                    box_distance2(&self.nodes[l].lo, &self.nodes[l].hi, &q),
                    box_distance2(&self.nodes[r].lo, &self.nodes[r].hi, &q),
                );
                if dl <= dr {
                    stack.push(r);
                    stack.push(l);
                } else {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        best.distance = best_d2.sqrt();
        best
    }
}

/// Squared distance from `q` to the box `[lo, hi]` (0 inside).
fn box_distance2(lo: &Vector3<f64>, hi: &Vector3<f64>, q: &Vector3<f64>) -> f64 {
    (0..3).map(|k| (lo[k] - q[k]).max(0.0).max(q[k] - hi[k]).powi(2)).sum()
}

/// The closest point of triangle `abc` to `p` and its barycentric weights, by the Voronoi
/// regions of the vertices, edges and face (Ericson, Real-Time Collision Detection §5.1.5).
pub(super) fn closest_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> (Vector3<f64>, [f64; 3]) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        // A degenerate (zero-area) triangle whose regions above did not catch p: its nearest
        // corner is as good as any point of it.
        let corners = [(a, [1.0, 0.0, 0.0]), (b, [0.0, 1.0, 0.0]), (c, [0.0, 0.0, 1.0])];
        let (x, w) = corners
            .iter()
            .min_by(|x, y| (x.0 - p).norm_squared().total_cmp(&(y.0 - p).norm_squared()))
            .copied()
            .unwrap_or((a, [1.0, 0.0, 0.0]));
        return (*x, w);
    }
    let (v, w) = (vb / denom, vc / denom);
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// The closest point of the mesh `(vertices, faces)` to each query, in parallel.
pub fn closest_points(vertices: &[[f64; 3]], faces: &[[u32; 3]], queries: &[[f64; 3]]) -> Result<Vec<Closest>> {
    check_finite_points("queries", queries)?;
    let bvh = TriangleBvh::new(vertices, faces)?;
    Ok(queries.par_iter().map(|q| bvh.closest(q)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over every triangle, the reference of the hierarchy.
    fn brute(vertices: &[[f64; 3]], faces: &[[u32; 3]], q: &[f64; 3]) -> f64 {
        faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| Vector3::from(vertices[v as usize]));
                (closest_on_triangle(&Vector3::from(*q), &a, &b, &c).0 - Vector3::from(*q)).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn the_hierarchy_finds_what_brute_force_finds() {
        // A wavy 30 × 30 grid, and queries above, below and beside it.
        let n = 30;
        let vertices: Vec<[f64; 3]> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64, (i / n) as f64);
                [x, y, (x / 3.0).sin() * (y / 4.0).cos()]
            })
            .collect();
        let mut faces = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let v = (j * n + i) as u32;
                faces.push([v, v + 1, v + n as u32]);
                faces.push([v + 1, v + n as u32 + 1, v + n as u32]);
            }
        }
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let queries: Vec<[f64; 3]> =
            (0..500).map(|_| [next() * 40.0 - 5.0, next() * 40.0 - 5.0, next() * 6.0 - 3.0]).collect();
        let found = closest_points(&vertices, &faces, &queries).unwrap();
        for (q, c) in queries.iter().zip(&found) {
            assert!((c.distance - brute(&vertices, &faces, q)).abs() < 1e-12);
            let f = faces[c.triangle];
            let p: Vector3<f64> = (0..3).map(|k| c.barycentric[k] * Vector3::from(vertices[f[k] as usize])).sum();
            assert!((p - Vector3::from(c.point)).norm() < 1e-12);
            assert!((c.barycentric.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_faces_are_refused_by_name() {
        let v = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(closest_points(&v, &[[0, 1, 3]], &[[0.0; 3]]).unwrap_err().to_string().contains("faces"));
        assert!(closest_points(&v, &[], &[[0.0; 3]]).unwrap_err().to_string().contains("faces"));
        assert!(closest_points(&v, &[[0, 1, 2]], &[[f64::NAN; 3]]).unwrap_err().to_string().contains("queries"));
    }
}
