//! Bead-chain ordering of a section's points into one continuous polyline (SPEC P2; paper 004
//! §2.1).
//!
//! The paper steps from a point to its nearest unvisited neighbour (`Chain::Nearest`). On a real
//! section that is not enough: a slab of a scan is a band of scattered points, not a thin curve,
//! and the nearest unvisited point is as often behind as ahead; every point the chain skips is
//! picked up later by a long jump back, and across a blade's thin trailing edge the chain hops to
//! the other side. The default (`Chain::Tree`) orders the points along the curve instead:
//!
//! 1. the minimum spanning tree of the points (Kruskal over their k nearest neighbours, the
//!    pieces then joined by their closest pairs): its edges follow the band, and the two sides of
//!    a thin edge meet only round the tip, since the points along each side are closer to one
//!    another than to the other side;
//! 2. the tree's longest path (its diameter) runs the length of the curve; every other point hangs
//!    off it on a short branch across the band;
//! 3. each point's place along the curve is the arc length of its branch's foot on the diameter,
//!    plus its offset along the curve's tangent there; sorting by it gives the order.
//!
//! A closed section (the diameter's two ends close together, where the tree broke the loop)
//! closes up: the order starts at the point nearest `start` and runs in `direction`.
use crate::error::{check_finite_points, Error, Result};
use crate::spatial::PointIndex;
use nalgebra::{Matrix3, Vector3};

/// Neighbours per point of the graph the spanning tree is taken from.
const NEIGHBORS: usize = 16;
/// Path vertices on each side of a diameter vertex over which its tangent is taken.
const TANGENT_SPAN: usize = 4;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Chain {
    /// Along the spanning tree's diameter (module docs).
    Tree,
    /// The paper's rule: always the nearest unvisited point.
    Nearest,
}

impl Chain {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "tree" => Ok(Chain::Tree),
            "nearest" => Ok(Chain::Nearest),
            _ => Err(Error::invalid("method", format!("expected 'tree' or 'nearest', got {name:?}"))),
        }
    }
}

#[derive(Debug, Clone)]
pub struct BeadChain {
    /// Every point once, in path order.
    pub order: Vec<usize>,
    /// Whether the path closes up (the last point next to the first).
    pub closed: bool,
}

struct UnionFind(Vec<usize>);

impl UnionFind {
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }

    fn union(&mut self, a: usize, b: usize) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.0[ra.max(rb)] = ra.min(rb);
        true
    }
}

fn dist(p: &[[f64; 3]], i: usize, j: usize) -> f64 {
    (Vector3::from(p[i]) - Vector3::from(p[j])).norm()
}

/// The minimum spanning tree as adjacency lists (edges of the k-nearest graph, the pieces joined
/// by their closest pairs).
fn spanning_tree(points: &[[f64; 3]], index: &PointIndex) -> Vec<Vec<(usize, f64)>> {
    let n = points.len();
    let k = NEIGHBORS.min(n - 1) + 1;
    let mut edges: Vec<(f64, usize, usize)> = Vec::with_capacity(n * k);
    for (i, p) in points.iter().enumerate() {
        for (j, d2) in index.knn(p, k) {
            if j != i {
                edges.push((d2.sqrt(), i.min(j), i.max(j)));
            }
        }
    }
    edges.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    edges.dedup_by(|a, b| a.1 == b.1 && a.2 == b.2);
    let mut uf = UnionFind((0..n).collect());
    let mut tree = vec![Vec::new(); n];
    let mut joined = 0;
    for &(d, i, j) in &edges {
        if uf.union(i, j) {
            tree[i].push((j, d));
            tree[j].push((i, d));
            joined += 1;
        }
    }
    // Pieces farther apart than the k-nearest graph reaches: join each to its closest point in
    // another piece, the closest pair first.
    while joined < n - 1 {
        let root0 = uf.find(0);
        let (mut best, mut pair) = (f64::INFINITY, (0, 0));
        for (i, p) in points.iter().enumerate() {
            if uf.find(i) == root0 {
                continue;
            }
            let mut m = k;
            loop {
                let near = index.knn(p, m);
                if let Some(&(j, d2)) = near.iter().find(|&&(j, _)| uf.find(j) == root0) {
                    if d2.sqrt() < best {
                        (best, pair) = (d2.sqrt(), (i, j));
                    }
                    break;
                }
                if m >= n {
                    break;
                }
                m = (2 * m).min(n);
            }
        }
        uf.union(pair.0, pair.1);
        tree[pair.0].push((pair.1, best));
        tree[pair.1].push((pair.0, best));
        joined += 1;
    }
    tree
}

/// Distances along the tree from `from`, and each vertex's parent.
fn reach(tree: &[Vec<(usize, f64)>], from: usize) -> (Vec<f64>, Vec<usize>) {
    let mut d = vec![f64::INFINITY; tree.len()];
    let mut parent = vec![usize::MAX; tree.len()];
    d[from] = 0.0;
    let mut stack = vec![from];
    while let Some(v) = stack.pop() {
        for &(w, l) in &tree[v] {
            if d[w].is_infinite() {
                d[w] = d[v] + l;
                parent[w] = v;
                stack.push(w);
            }
        }
    }
    (d, parent)
}

fn farthest(d: &[f64]) -> usize {
    (0..d.len()).fold(0, |b, i| if d[i] > d[b] { i } else { b })
}

/// The section's plane normal (least-variance axis) and main axis (largest variance).
fn plane(points: &[[f64; 3]]) -> (Vector3<f64>, Vector3<f64>) {
    let c = points.iter().map(|&p| Vector3::from(p)).sum::<Vector3<f64>>() / points.len() as f64;
    let cov =
        points.iter().fold(Matrix3::zeros(), |m, &p| m + (Vector3::from(p) - c) * (Vector3::from(p) - c).transpose());
    let e = cov.symmetric_eigen();
    let mut normal = e.eigenvectors.column(e.eigenvalues.imin()).into_owned();
    // Seen from +z (else +y, +x): counter-clockwise is the default turn of a closed section.
    let k = (0..3).rev().find(|&k| normal[k].abs() > 1e-9).unwrap_or(2);
    if normal[k] < 0.0 {
        normal = -normal;
    }
    (normal, e.eigenvectors.column(e.eigenvalues.imax()).into_owned())
}

fn tree_order(points: &[[f64; 3]], index: &PointIndex) -> (Vec<usize>, bool) {
    let n = points.len();
    let tree = spanning_tree(points, index);
    let (d0, _) = reach(&tree, 0);
    let a = farthest(&d0);
    let (da, parent) = reach(&tree, a);
    let b = farthest(&da);
    let mut path = vec![b];
    while *path.last().unwrap_or(&a) != a {
        path.push(parent[*path.last().unwrap_or(&a)]);
    }
    path.reverse();
    // Each vertex's foot on the diameter: spread from the path along the branches.
    let mut foot = vec![usize::MAX; n];
    let mut stack = Vec::new();
    for (k, &v) in path.iter().enumerate() {
        foot[v] = k;
        stack.push(v);
    }
    while let Some(v) = stack.pop() {
        for &(w, _) in &tree[v] {
            if foot[w] == usize::MAX {
                foot[w] = foot[v];
                stack.push(w);
            }
        }
    }
    let along: Vec<f64> = path.iter().map(|&v| da[v]).collect();
    let tangent = |k: usize| {
        let (lo, hi) = (k.saturating_sub(TANGENT_SPAN), (k + TANGENT_SPAN).min(path.len() - 1));
        let t = Vector3::from(points[path[hi]]) - Vector3::from(points[path[lo]]);
        let norm = t.norm();
        if norm > 0.0 {
            t / norm
        } else {
            Vector3::zeros()
        }
    };
    let tangents: Vec<Vector3<f64>> = (0..path.len()).map(tangent).collect();
    let place: Vec<f64> = (0..n)
        .map(|v| {
            let k = foot[v];
            along[k] + (Vector3::from(points[v]) - Vector3::from(points[path[k]])).dot(&tangents[k])
        })
        .collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| place[i].total_cmp(&place[j]).then(i.cmp(&j)));
    // The tree broke a closed loop between the diameter's ends, at a gap no wider than its widest
    // edge (plus the band's width either side): they lie that close, where an open section's ends
    // lie its length apart. The loop is ten gaps long at least — not ten reaches: points spread
    // at random 0.35 mm apart have a widest edge of 1.2 mm, and a 29 mm stadium section was
    // taken for open.
    let mut edges: Vec<f64> = tree.iter().flat_map(|e| e.iter().map(|&(_, l)| l)).collect();
    let q = (edges.len() * 95 / 100).min(edges.len().saturating_sub(1));
    let typical = if edges.is_empty() { 0.0 } else { *edges.select_nth_unstable_by(q, f64::total_cmp).1 };
    let widest = edges.iter().fold(0.0, |m: f64, &l| m.max(l));
    let reach = 2.0 * widest.max(3.0 * typical);
    let gap = dist(points, a, b);
    let closed = n >= 8 && gap <= reach && along[path.len() - 1] > 10.0 * gap;
    (order, closed)
}

fn nearest_order(points: &[[f64; 3]], index: &PointIndex, first: usize) -> Vec<usize> {
    let n = points.len();
    let mut visited = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut at = first;
    visited[at] = true;
    order.push(at);
    let mut k = 8.min(n);
    while order.len() < n {
        let next = loop {
            if let Some(&(j, _)) = index.knn(&points[at], k).iter().find(|&&(j, _)| !visited[j]) {
                break j;
            }
            // Everything near is taken: widen the search (the paper's window of registered points).
            k = (2 * k).min(n);
        };
        k = 8.min(n);
        visited[next] = true;
        order.push(next);
        at = next;
    }
    order
}

/// Orders a section's points into one polyline (module docs). `start`: the path begins at the
/// end (open section) or the point (closed) nearest it; `direction`: the way a closed section is
/// run, or which end an open one starts from when no `start` is given.
pub fn bead_chain(
    points: &[[f64; 3]],
    start: Option<[f64; 3]>,
    direction: Option<[f64; 3]>,
    method: Chain,
) -> Result<BeadChain> {
    check_finite_points("points", points)?;
    if let Some(s) = start {
        check_finite_points("start", &[s])?;
    }
    if let Some(d) = direction {
        if !(d.iter().all(|x| x.is_finite()) && Vector3::from(d).norm() > 0.0) {
            return Err(Error::invalid("direction", format!("must be a finite non-zero vector, got {d:?}")));
        }
    }
    let n = points.len();
    if n <= 1 {
        return Ok(BeadChain { order: (0..n).collect(), closed: false });
    }
    let index = PointIndex::new(points)?;
    let (normal, axis) = plane(points);
    let nearest_to = |q: [f64; 3]| index.nearest(&q).0;
    let lowest =
        (0..n).fold(
            0,
            |b, i| if Vector3::from(points[i]).dot(&axis) < Vector3::from(points[b]).dot(&axis) { i } else { b },
        );
    match method {
        Chain::Nearest => {
            let first = start.map_or(lowest, nearest_to);
            Ok(BeadChain { order: nearest_order(points, &index, first), closed: false })
        }
        Chain::Tree => {
            let (mut order, closed) = tree_order(points, &index);
            let p = |i: usize| Vector3::from(points[i]);
            if closed {
                let first = start.map_or(lowest, nearest_to);
                let at = order.iter().position(|&i| i == first).unwrap_or(0);
                order.rotate_left(at);
                // Counter-clockwise about the normal by default (the signed area of the polygon).
                let turn = (0..n).map(|k| p(order[k]).cross(&p(order[(k + 1) % n])).dot(&normal)).sum::<f64>();
                let heading = p(order[(1..n).find(|&k| (p(order[k]) - p(first)).norm() > 0.0).unwrap_or(1)]) - p(first);
                let forward = match direction {
                    Some(d) => heading.dot(&Vector3::from(d)) >= 0.0,
                    None => turn >= 0.0,
                };
                if !forward {
                    order[1..].reverse();
                }
            } else {
                let (head, tail) = (p(order[0]), p(order[n - 1]));
                let reverse = match (start, direction) {
                    (Some(s), _) => (tail - Vector3::from(s)).norm() < (head - Vector3::from(s)).norm(),
                    (None, Some(d)) => (tail - head).dot(&Vector3::from(d)) < 0.0,
                    (None, None) => tail.dot(&axis) < head.dot(&axis),
                };
                if reverse {
                    order.reverse();
                }
            }
            Ok(BeadChain { order, closed })
        }
    }
}
