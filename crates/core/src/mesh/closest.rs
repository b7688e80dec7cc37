//! Closest points on a triangle mesh (SPEC S2): for each query, the nearest point of the
//! surface, its triangle and barycentric coordinates — how a tool point is carried onto the
//! scanned surface, and how far a measured point is from a model.
//!
//! A bounding-volume hierarchy over the triangles, built once per call and searched in
//! parallel. Written here: the crates that offer one (parry, bvh) bring a geometry stack or an
//! f32-only API, and the search is short. Exact ties (a point equally close to two triangles,
//! on their shared edge) go to the lower triangle index, so results do not depend on threads.
use crate::error::{check_finite_points, Error, Result};
use crate::geom::morton_order;
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

/// A child of a node: its box (float32, rounded outward, so it still holds every triangle
/// below it) and either a range of leaf slots (`count` > 0) or the index of its node.
#[derive(Clone, Copy)]
struct Child {
    lo: [f32; 3],
    hi: [f32; 3],
    first: u32,
    count: u32,
}

impl Child {
    /// Squared distance from `q` to the box (0 inside), in float64 from the rounded-out box:
    /// never more than the distance to any triangle inside.
    #[inline]
    fn distance2(&self, q: &[f64; 3]) -> f64 {
        let d = |k: usize| (self.lo[k] as f64 - q[k]).max(0.0).max(q[k] - self.hi[k] as f64);
        let (x, y, z) = (d(0), d(1), d(2));
        x * x + y * y + z * z
    }
}

/// A child left for later in a search: where it leads and its box distance (so the wait is
/// dropped without a fetch when the best has come closer).
#[derive(Clone, Copy)]
struct Waiting {
    first: u32,
    count: u32,
    d2: f64,
}

/// A node of the binary tree the build makes: both children.
#[derive(Clone, Copy)]
struct Node {
    child: [Child; 2],
}

/// A node of the tree searched: up to four children, their float32 boxes coordinate by
/// coordinate, so the four box distances are computed side by side (the compiler vectorises
/// them) and the tree is half as deep as the binary one it is collapsed from.
#[derive(Clone, Copy)]
#[repr(align(64))]
struct Wide {
    lo: [[f32; 4]; 3],
    hi: [[f32; 4]; 3],
    /// Leaf: the first slot; inner: the wide node's index.
    first: [u32; 4],
    /// Leaf: its triangles (> 0); inner: 0; no child: 0 with an empty box.
    count: [u32; 4],
}

impl Wide {
    /// Squared distances from `q` to the four boxes (infinite for a missing child).
    #[inline]
    fn distances2(&self, q: &[f64; 3]) -> [f64; 4] {
        let mut d2 = [0.0f64; 4];
        for ((lo, hi), &qk) in self.lo.iter().zip(&self.hi).zip(q) {
            for ((d2, &lo), &hi) in d2.iter_mut().zip(lo).zip(hi) {
                let d = (lo as f64 - qk).max(0.0).max(qk - hi as f64);
                *d2 += d * d;
            }
        }
        d2
    }
}

/// Room for the children a search usually leaves waiting (three per level of a tree of at most
/// 16 wide levels over 2^31 triangles); the stack grows beyond it if it must.
const STACK: usize = 48;

/// The mesh and its hierarchy. The triangles' corners are copied in leaf order, so that a leaf
/// is read from one run of memory rather than through the face and vertex tables. Boxes are
/// float32 (half the memory a search walks through); corners and distances stay float64.
pub struct TriangleBvh<'a> {
    vertices: &'a [[f64; 3]],
    faces: &'a [[u32; 3]],
    /// The triangle index of each leaf slot.
    order: Vec<u32>,
    /// The three corners of each leaf slot's triangle.
    corners: Vec<[Vector3<f64>; 3]>,
    /// The root: the box of the whole mesh and where it leads (a leaf, or wide node 0).
    root: Child,
    nodes: Vec<Wide>,
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
        if faces.len() > (u32::MAX / 2) as usize {
            return Err(Error::invalid("faces", format!("{} triangles is beyond 2^31", faces.len())));
        }
        let corner = |t: u32, k: usize| Vector3::from(vertices[faces[t as usize][k] as usize]);
        let centroid: Vec<Vector3<f64>> = (0..faces.len() as u32)
            .into_par_iter()
            .map(|t| (corner(t, 0) + corner(t, 1) + corner(t, 2)) / 3.0)
            .collect();
        let mut order: Vec<u32> = (0..faces.len() as u32).collect();
        let (root, binary) = build(&mut order, 0, &centroid, &corner);
        let mut nodes = Vec::with_capacity(binary.len() / 2 + 1);
        if root.count == 0 {
            widen(&binary, 0, &mut nodes);
        }
        let corners = order.par_iter().map(|&t| [corner(t, 0), corner(t, 1), corner(t, 2)]).collect();
        Ok(TriangleBvh { vertices, faces, order, corners, root, nodes })
    }

    /// The mesh's vertices.
    pub fn vertices(&self) -> &'a [[f64; 3]] {
        self.vertices
    }

    /// The mesh's triangles.
    pub fn faces(&self) -> &'a [[u32; 3]] {
        self.faces
    }

    /// The closest point of the mesh to `q`.
    pub fn closest(&self, q: &[f64; 3]) -> Closest {
        self.closest_from(q, None)
    }

    /// The closest point of the mesh to `q`, the search bounded from the start by the distance
    /// to triangle `hint` (a neighbouring query's answer). The answer does not depend on the
    /// hint: the least distance, ties to the lowest triangle index, is found either way, since
    /// only boxes strictly farther than the best so far are skipped.
    pub fn closest_from(&self, q: &[f64; 3], hint: Option<usize>) -> Closest {
        self.closest_with(q, hint, &mut Vec::with_capacity(STACK))
    }

    /// `closest_from` with the caller's stack of waiting children (reused across a run of
    /// queries: filling a fresh one for every query cost more than the search).
    fn closest_with(&self, q: &[f64; 3], hint: Option<usize>, stack: &mut Vec<Waiting>) -> Closest {
        let qv = Vector3::from(*q);
        let mut best =
            Closest { point: [f64::NAN; 3], distance: f64::INFINITY, triangle: usize::MAX, barycentric: [0.0; 3] };
        let mut best_d2 = f64::INFINITY;
        if let Some(t) = hint {
            let [a, b, c] = self.faces[t].map(|v| Vector3::from(self.vertices[v as usize]));
            let (p, w) = closest_on_triangle(&qv, &a, &b, &c);
            best_d2 = (p - qv).norm_squared();
            best = Closest { point: p.into(), distance: 0.0, triangle: t, barycentric: w };
        }
        // Children waiting, with their box distance (so a wait is dropped without a fetch).
        stack.clear();
        let mut next = Some(Waiting { first: self.root.first, count: self.root.count, d2: self.root.distance2(q) });
        while let Some(Waiting { first, count, d2 }) = next.take().or_else(|| stack.pop()) {
            if d2 > best_d2 {
                continue;
            }
            if count > 0 {
                let (first, count) = (first as usize, count as usize);
                for (slot, [a, b, c]) in self.corners[first..first + count].iter().enumerate() {
                    let t = self.order[first + slot] as usize;
                    let (p, w) = closest_on_triangle(&qv, a, b, c);
                    let d2 = (p - qv).norm_squared();
                    if d2 < best_d2 || (d2 == best_d2 && t < best.triangle) {
                        best_d2 = d2;
                        best = Closest { point: p.into(), distance: 0.0, triangle: t, barycentric: w };
                    }
                }
                continue;
            }
            // Into the nearest child; the others wait, nearer ones on top, if they can still hold
            // a closer triangle.
            let node = &self.nodes[first as usize];
            let d = node.distances2(q);
            let mut by = [0usize, 1, 2, 3];
            by.sort_unstable_by(|&i, &j| d[i].total_cmp(&d[j]).then(i.cmp(&j)));
            // A missing child's box is empty: its distance is infinite, and it is never taken.
            for &i in by[1..].iter().rev() {
                if d[i] <= best_d2 && d[i] < f64::INFINITY {
                    stack.push(Waiting { first: node.first[i], count: node.count[i], d2: d[i] });
                }
            }
            let i = by[0];
            next = Some(Waiting { first: node.first[i], count: node.count[i], d2: d[i] });
        }
        best.distance = best_d2.sqrt();
        best
    }

    /// The closest point to each query, in parallel. The queries are visited in Morton order of
    /// their position, in runs of fixed length, each query's search bounded by its predecessor's
    /// triangle: neighbouring queries mostly share a closest triangle, and the bound prunes most
    /// of the tree from the first step. `then` turns each query's answer into the result kept.
    /// Results are those of `closest` for each query, whatever the thread count.
    pub fn closest_many_with<T, F>(&self, queries: &[[f64; 3]], then: F) -> Vec<T>
    where
        T: Send + Sync + Clone,
        F: Fn(&[f64; 3], Closest) -> T + Sync,
    {
        const RUN: usize = 256;
        let order = morton_order(queries);
        let found: Vec<T> = order
            .par_chunks(RUN)
            .flat_map_iter(|run| {
                let mut hint = None;
                let mut stack = Vec::with_capacity(STACK);
                let then = &then;
                run.iter().map(move |&i| {
                    let q = &queries[i as usize];
                    let c = self.closest_with(q, hint, &mut stack);
                    hint = Some(c.triangle);
                    then(q, c)
                })
            })
            .collect();
        // Back to the queries' order: query order[j] was answered j-th.
        let mut at = vec![0u32; queries.len()];
        for (j, &i) in order.iter().enumerate() {
            at[i as usize] = j as u32;
        }
        at.par_iter().map(|&j| found[j as usize].clone()).collect()
    }

    /// The closest point to each query (see `closest_many_with`).
    pub fn closest_many(&self, queries: &[[f64; 3]]) -> Vec<Closest> {
        self.closest_many_with(queries, |_, c| c)
    }
}

/// The hierarchy over the leaf slots `order` (the first of them is slot `first`): a leaf child
/// when they are few, else a node over its two halves split at the median centroid along the
/// longest axis of their box, and the nodes below it in depth-first order (the node first). Large
/// halves are built in parallel; the tree and its layout are the same on any thread count.
fn build(
    order: &mut [u32],
    first: usize,
    centroid: &[Vector3<f64>],
    corner: &(dyn Fn(u32, usize) -> Vector3<f64> + Sync),
) -> (Child, Vec<Node>) {
    /// Halves smaller than this are built on the calling thread.
    const PARALLEL: usize = 4096;
    let count = order.len();
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for &t in order.iter() {
        for k in 0..3 {
            let c = corner(t, k);
            lo = lo.inf(&c);
            hi = hi.sup(&c);
        }
    }
    // Rounded outward to float32: the box still holds every corner.
    let down = |v: f64| {
        let x = v as f32;
        if x as f64 > v {
            x.next_down()
        } else {
            x
        }
    };
    let up = |v: f64| {
        let x = v as f32;
        if (x as f64) < v {
            x.next_up()
        } else {
            x
        }
    };
    let (blo, bhi) = ([down(lo.x), down(lo.y), down(lo.z)], [up(hi.x), up(hi.y), up(hi.z)]);
    if count <= LEAF {
        return (Child { lo: blo, hi: bhi, first: first as u32, count: count as u32 }, Vec::new());
    }
    let axis = (hi - lo).imax();
    let mid = count / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        centroid[a as usize][axis].total_cmp(&centroid[b as usize][axis]).then(a.cmp(&b))
    });
    let (left_slots, right_slots) = order.split_at_mut(mid);
    let ((left, left_nodes), (right, right_nodes)) = if count >= PARALLEL {
        rayon::join(|| build(left_slots, first, centroid, corner), || build(right_slots, first + mid, centroid, corner))
    } else {
        (build(left_slots, first, centroid, corner), build(right_slots, first + mid, centroid, corner))
    };
    // This node, then the left half's nodes, then the right half's: their inner children move
    // by where their half now starts.
    let moved = |c: Child, by: usize| if c.count == 0 { Child { first: c.first + by as u32, ..c } } else { c };
    let (lbase, rbase) = (1, 1 + left_nodes.len());
    let mut nodes = Vec::with_capacity(1 + left_nodes.len() + right_nodes.len());
    nodes.push(Node { child: [moved(left, lbase), moved(right, rbase)] });
    nodes.extend(left_nodes.into_iter().map(|n| Node { child: n.child.map(|c| moved(c, lbase)) }));
    nodes.extend(right_nodes.into_iter().map(|n| Node { child: n.child.map(|c| moved(c, rbase)) }));
    (Child { lo: blo, hi: bhi, first: 0, count: 0 }, nodes)
}

/// The wide node for binary node `n` (pushed to `wide`, its index returned): the binary node's
/// children, an inner one among them replaced by its own two while there is room for four (the
/// first inner one each time, so the shape is fixed by the binary tree alone), then the wide
/// nodes below, depth first.
fn widen(binary: &[Node], n: usize, wide: &mut Vec<Wide>) -> u32 {
    let mut kids: Vec<Child> = binary[n].child.to_vec();
    while kids.len() < 4 {
        let Some(k) = kids.iter().position(|c| c.count == 0) else { break };
        let inner = kids.remove(k);
        let [a, b] = binary[inner.first as usize].child;
        kids.insert(k, b);
        kids.insert(k, a);
    }
    let at = wide.len();
    wide.push(Wide { lo: [[f32::INFINITY; 4]; 3], hi: [[f32::NEG_INFINITY; 4]; 3], first: [0; 4], count: [0; 4] });
    for (i, c) in kids.iter().enumerate() {
        let first = if c.count == 0 { widen(binary, c.first as usize, wide) } else { c.first };
        let node = &mut wide[at];
        for k in 0..3 {
            node.lo[k][i] = c.lo[k];
            node.hi[k][i] = c.hi[k];
        }
        node.first[i] = first;
        node.count[i] = c.count;
    }
    at as u32
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
    if queries.len() > u32::MAX as usize {
        return Err(Error::invalid("queries", format!("{} queries is beyond 2^32", queries.len())));
    }
    let bvh = TriangleBvh::new(vertices, faces)?;
    Ok(bvh.closest_many(queries))
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
    fn every_tree_shape_finds_what_brute_force_finds() {
        // 1 to 40 triangles: a lone leaf, wide nodes with two, three and four children.
        let mut seed = 11u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for m in 1..=40usize {
            let vertices: Vec<[f64; 3]> = (0..3 * m).map(|_| [next() * 10.0, next() * 10.0, next() * 2.0]).collect();
            let faces: Vec<[u32; 3]> = (0..m as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
            let queries: Vec<[f64; 3]> =
                (0..50).map(|_| [next() * 14.0 - 2.0, next() * 14.0 - 2.0, next() * 6.0 - 3.0]).collect();
            for (q, c) in queries.iter().zip(closest_points(&vertices, &faces, &queries).unwrap()) {
                assert!((c.distance - brute(&vertices, &faces, q)).abs() < 1e-12, "{m} triangles");
            }
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
