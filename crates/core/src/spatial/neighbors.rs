//! Neighborhoods of every point of one cloud: its k nearest points, or all points within a
//! radius. Outlier removal, normals, curvature and the feature degree ask exactly this.
//!
//! Why our own tree beside kiddo (`PointIndex`): kiddo answers one query at a time, each walking
//! the tree alone — about 3 µs for k = 20, the speed of Open3D's nanoflann. Here the queries are
//! the cloud's own points, so they are answered a leaf at a time: the leaves that can hold a
//! neighbor of any point of the leaf are gathered once into contiguous coordinate arrays, and
//! each point of the leaf scans those arrays in a loop the compiler vectorises. The gather radius
//! is guessed from the previous leaf's largest k-th distance (leaves are visited in tree order,
//! so the previous leaf is a spatial neighbor); a query whose k-th distance exceeds it is
//! answered again with a gather radius that is certain to be enough, so every answer is exact.
//! Measured in benchmarks/bench_cloud.py (`knn_graph`, SOR, ROR, normals against Open3D).
//!
//! Neighbors are sorted by (squared distance, index): results do not depend on the tree, the
//! order of evaluation or the thread count.
use crate::error::{Error, Result};
use rayon::prelude::*;

/// Points per leaf. Smaller leaves gather fewer needless candidates (about 170 per leaf for
/// k = 20 on a scanned surface) at the cost of more gathers; 16 measured best against 24 and 32.
const LEAF_SIZE: usize = 16;
/// Leaves per parallel task; within a task each leaf's gather radius starts from the last's.
const LEAVES_PER_TASK: usize = 64;
/// Squared-radius margin on the gather radius guessed from the previous leaf.
const GUESS_MARGIN2: f64 = 1.3;
/// Subtrees larger than this are split on two threads while building.
const PARALLEL_SPLIT: usize = 16_384;

/// One neighbor of a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// Index into the cloud.
    pub index: usize,
    /// Squared distance to the query point.
    pub dist2: f64,
    pub point: [f64; 3],
}

struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    kind: NodeKind,
}

enum NodeKind {
    Inner(u32, u32),
    /// Range of tree positions.
    Leaf(u32, u32),
}

/// A bucket kd-tree over one cloud, answering neighborhood queries for all of its points.
pub struct CloudNeighbors {
    /// Tree position → index into the cloud.
    order: Vec<u32>,
    /// Coordinates in tree order, one array per axis.
    xyz: [Vec<f64>; 3],
    /// `nodes[0]` is the root.
    nodes: Vec<Node>,
    /// Node ids of the leaves in tree order.
    leaves: Vec<u32>,
    /// Squared diagonal of the cloud's box.
    extent2: f64,
}

/// Points gathered around one leaf, one array per axis.
#[derive(Default)]
struct Candidates {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    index: Vec<u32>,
}

/// Per-task buffers, reused from leaf to leaf.
#[derive(Default)]
struct Scratch {
    cand: Candidates,
    d2: Vec<f64>,
    /// (squared distance bits, cloud index, candidate position) of the points passing the filter.
    sel: Vec<(u64, u32, u32)>,
    pos: Vec<u32>,
    /// (position, k-th distance) of the queries of this pass answered so far.
    answered: Vec<([f64; 3], f64)>,
    /// k neighbors per query of the leaf.
    found: Vec<Neighbor>,
    count: Vec<usize>,
    kth2: Vec<f64>,
    pending: Vec<usize>,
}

impl CloudNeighbors {
    /// Builds the tree over `points` (finite, fewer than 2^32 − 1).
    pub fn new(points: &[[f64; 3]]) -> Result<Self> {
        let n = points.len();
        if n >= u32::MAX as usize {
            return Err(Error::invalid("points", format!("{n} points exceed the 2^32 − 1 an index can hold")));
        }
        crate::error::check_finite_points("points", points)?;
        // Points travel with their indices while splitting: sequential access, no indirection.
        let mut items: Vec<([f64; 3], u32)> = points.par_iter().enumerate().map(|(i, p)| (*p, i as u32)).collect();
        let (lo, hi) = crate::geom::bounds(points);
        split(&mut items, lo, hi);
        let order: Vec<u32> = items.par_iter().map(|it| it.1).collect();
        let xyz = [0, 1, 2].map(|k| items.par_iter().map(|it| it.0[k]).collect::<Vec<f64>>());
        drop(items);
        let mut tree = CloudNeighbors {
            order,
            xyz,
            nodes: Vec::with_capacity(4 * n / LEAF_SIZE + 1),
            leaves: Vec::new(),
            extent2: 0.0,
        };
        if n > 0 {
            tree.build_nodes(0, n);
            let root = &tree.nodes[0];
            tree.extent2 = (0..3).map(|k| (root.hi[k] - root.lo[k]).powi(2)).sum();
        }
        Ok(tree)
    }

    pub fn len(&self) -> usize {
        self.order.len()
    }

    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// `f(i, neighbors)` for every point i, returned in point order. The neighbors are the
    /// `k` nearest points (the point itself included), nearest first; with `radius` only those
    /// strictly closer than it, so there may be fewer (Open3D's hybrid search; a NaN radius
    /// finds none). Squared distances overflow beyond about 1e154 mm: such points are nobody's
    /// neighbors.
    pub fn map_knn<T, F>(&self, k: usize, radius: Option<f64>, f: F) -> Vec<T>
    where
        T: Send + Default,
        F: Fn(usize, &[Neighbor]) -> T + Sync,
    {
        let (k, cap2) = (k.min(self.len()), cap_squared(radius));
        self.map_leaves(|leaf, s, guess, out| self.leaf_knn(leaf, k, cap2, s, guess, &mut |i, nb| f(i, nb), out))
    }

    /// The k-nearest graph as flat rows in point order: row i holds the neighbors of point i
    /// as in `map_knn`, (index, squared distance), padded with (u32::MAX, ∞) when `radius`
    /// leaves fewer than k. Without a vector per point: each task writes its rows in tree order
    /// into one buffer, and the rows are gathered from there into point order in parallel.
    pub fn knn_graph(&self, k: usize, radius: Option<f64>) -> (Vec<u32>, Vec<f64>) {
        let (k, cap2) = (k.min(self.len()), cap_squared(radius));
        if k == 0 {
            return (Vec::new(), Vec::new());
        }
        let tasks: Vec<Vec<(u32, f64)>> = self.run_tasks(|leaves, scratch, guess| {
            let mut rows: Vec<(u32, f64)> = Vec::with_capacity(leaves.len() * LEAF_SIZE * k);
            let mut unit = Vec::new();
            for &leaf in leaves {
                let mut write = |_: usize, nb: &[Neighbor]| {
                    rows.extend(nb.iter().map(|n| (n.index as u32, n.dist2)));
                    rows.extend(std::iter::repeat_n((u32::MAX, f64::INFINITY), k - nb.len()));
                };
                self.leaf_knn(leaf, k, cap2, scratch, guess, &mut write, &mut unit);
                unit.clear();
            }
            rows
        });
        // Tree position → (task, row in the task).
        let mut row_of = vec![(0u32, 0u32); self.len()];
        let mut t = 0;
        for (task, rows) in tasks.iter().enumerate() {
            for r in 0..rows.len() / k {
                row_of[self.order[t] as usize] = (task as u32, r as u32);
                t += 1;
            }
        }
        let mut index = vec![u32::MAX; self.len() * k];
        let mut dist2 = vec![f64::INFINITY; self.len() * k];
        index.par_chunks_mut(k).zip(dist2.par_chunks_mut(k)).zip(&row_of).for_each(|((ri, rd), &(task, r))| {
            let row = &tasks[task as usize][r as usize * k..(r as usize + 1) * k];
            for (c, &(j, d)) in row.iter().enumerate() {
                ri[c] = j;
                rd[c] = d;
            }
        });
        (index, dist2)
    }

    /// How many points lie strictly closer than `radius` to each point (itself included).
    pub fn count_within(&self, radius: f64) -> Vec<usize> {
        let r2 = radius * radius;
        self.map_leaves(|leaf, s, _guess, out| {
            let (a, b, lo, hi) = self.leaf(leaf);
            self.gather(&lo, &hi, r2, true, &mut s.cand);
            s.d2.resize(s.cand.x.len(), 0.0);
            for t in a..b {
                let q = self.position(t);
                squared_distances(&q, &s.cand, &mut s.d2);
                out.push(s.d2.iter().filter(|&&d| d < r2).count());
            }
        })
    }

    fn position(&self, t: usize) -> [f64; 3] {
        [self.xyz[0][t], self.xyz[1][t], self.xyz[2][t]]
    }

    fn leaf(&self, leaf: u32) -> (usize, usize, [f64; 3], [f64; 3]) {
        let node = &self.nodes[leaf as usize];
        match node.kind {
            NodeKind::Leaf(a, b) => (a as usize, b as usize, node.lo, node.hi),
            NodeKind::Inner(..) => unreachable!("leaves holds leaf nodes only"),
        }
    }

    /// Runs `per_task` on runs of LEAVES_PER_TASK consecutive leaves in parallel, each with its
    /// own scratch buffers and gather-radius guess; results in tree order.
    fn run_tasks<R: Send>(&self, per_task: impl Fn(&[u32], &mut Scratch, &mut f64) -> R + Sync) -> Vec<R> {
        self.leaves
            .par_chunks(LEAVES_PER_TASK)
            .map(|leaves| {
                let (mut scratch, mut guess) = (Scratch::default(), f64::NAN);
                per_task(leaves, &mut scratch, &mut guess)
            })
            .collect()
    }

    /// Runs `per_leaf` over all leaves in parallel tasks and returns its outputs in point order.
    fn map_leaves<T, G>(&self, per_leaf: G) -> Vec<T>
    where
        T: Send + Default,
        G: Fn(u32, &mut Scratch, &mut f64, &mut Vec<T>) + Sync,
    {
        let in_tree_order: Vec<Vec<T>> = self.run_tasks(|leaves, scratch, guess| {
            let mut out = Vec::with_capacity(leaves.len() * LEAF_SIZE);
            for &leaf in leaves {
                per_leaf(leaf, scratch, guess, &mut out);
            }
            out
        });
        let mut out: Vec<T> = std::iter::repeat_with(T::default).take(self.len()).collect();
        for (t, v) in in_tree_order.into_iter().flatten().enumerate() {
            out[self.order[t] as usize] = v;
        }
        out
    }

    /// The k nearest (strictly within `cap2` when finite) of every point of one leaf.
    #[allow(clippy::too_many_arguments)]
    fn leaf_knn<T>(
        &self,
        leaf: u32,
        k: usize,
        cap2: f64,
        s: &mut Scratch,
        guess: &mut f64,
        f: &mut impl FnMut(usize, &[Neighbor]) -> T,
        out: &mut Vec<T>,
    ) {
        let (a, b, lo, hi) = self.leaf(leaf);
        let m = b - a;
        if k == 0 {
            out.extend((a..b).map(|t| f(self.order[t] as usize, &[])));
            return;
        }
        let diag2 = (hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2);
        // Squared gather radius: the previous leaf's widest k-th distance, with a margin (a
        // second pass costs more than a few more candidates).
        let mut reach2 = if guess.is_finite() { *guess * GUESS_MARGIN2 } else { diag2 }.min(cap2);
        // Slack on the filter bound, far above the rounding of a squared distance.
        let scale = lo.iter().chain(hi.iter()).fold(1.0f64, |acc, v| acc.max(v.abs()));
        let slack = 1e-9 * scale;
        s.found.resize(m * k, Neighbor { index: 0, dist2: 0.0, point: [0.0; 3] });
        s.count.resize(m, 0);
        s.kth2.resize(m, 0.0);
        s.pending.clear();
        s.pending.extend(0..m);
        loop {
            self.gather(&lo, &hi, reach2, false, &mut s.cand);
            let nc = s.cand.x.len();
            s.d2.resize(nc, 0.0);
            s.pos.resize(nc, 0);
            s.answered.clear();
            for pi in 0..s.pending.len() {
                let qi = s.pending[pi];
                let q = self.position(a + qi);
                squared_distances(&q, &s.cand, &mut s.d2);
                // A filter on the candidates before the selection. Any bound gives the exact
                // answer as long as k points pass it (otherwise all are taken again). Every
                // neighbor of an answered query p lies within its k-th distance plus |q − p|
                // of q, so the nearest answered query gives a tight one; the first query of a
                // pass takes the gather radius.
                let mut bound = reach2.sqrt();
                for &(p, kth) in &s.answered {
                    let step = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt();
                    bound = bound.min(kth + step);
                }
                let bound = (bound * (1.0 + 1e-9) + slack).powi(2);
                let mut taken = select(&s.d2, &s.cand.index, bound, cap2, k, &mut s.pos, &mut s.sel);
                if taken < k && bound.is_finite() {
                    taken = select(&s.d2, &s.cand.index, f64::INFINITY, cap2, k, &mut s.pos, &mut s.sel);
                }
                for (r, &(bits, index, j)) in s.sel[..taken].iter().enumerate() {
                    let j = j as usize;
                    s.found[qi * k + r] = Neighbor {
                        index: index as usize,
                        dist2: f64::from_bits(bits),
                        point: [s.cand.x[j], s.cand.y[j], s.cand.z[j]],
                    };
                }
                s.count[qi] = taken;
                s.kth2[qi] = if taken == k { f64::from_bits(s.sel[k - 1].0) } else { f64::INFINITY };
                if taken == k {
                    s.answered.push((q, s.kth2[qi].sqrt()));
                }
            }
            // An answer is exact when its k-th point lies within the gather radius (no point
            // outside the gathered leaves is that close), or when the radius is the cap.
            if reach2 >= cap2 {
                break;
            }
            let r2 = reach2;
            let failed: Vec<usize> = s.pending.iter().copied().filter(|&qi| s.kth2[qi] > r2).collect();
            if failed.is_empty() {
                break;
            }
            // A k-th distance among the gathered points bounds the true one, and only shrinks
            // as more points are gathered, so the loop ends; a query that did not find k points
            // needs a wider gather.
            let worst = failed.iter().map(|&qi| s.kth2[qi]).fold(0.0f64, f64::max);
            let wider = if worst.is_finite() { worst } else { (4.0 * reach2).max(diag2).max(self.extent2 * 1e-6) };
            // A radius that does not grow (all of it below the smallest float) takes everything.
            reach2 = if wider > reach2 { wider } else { f64::INFINITY }.min(cap2);
            s.pending = failed;
        }
        let mut widest = 0.0f64;
        for qi in 0..m {
            let n = s.count[qi];
            if n == k {
                widest = widest.max(s.kth2[qi]);
            }
            out.push(f(self.order[a + qi] as usize, &s.found[qi * k..qi * k + n]));
        }
        *guess = widest;
    }

    /// Fills `cand` with the points of every leaf whose box lies within `sqrt(r2)` of the box
    /// (lo, hi) (strictly within when `strict`).
    fn gather(&self, lo: &[f64; 3], hi: &[f64; 3], r2: f64, strict: bool, cand: &mut Candidates) {
        cand.x.clear();
        cand.y.clear();
        cand.z.clear();
        cand.index.clear();
        let mut stack = vec![0u32];
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id as usize];
            let gap2 = box_gap2(&node.lo, &node.hi, lo, hi);
            if gap2 > r2 || (strict && gap2 >= r2) {
                continue;
            }
            match node.kind {
                NodeKind::Inner(l, r) => {
                    stack.push(r);
                    stack.push(l);
                }
                NodeKind::Leaf(a, b) => {
                    let (a, b) = (a as usize, b as usize);
                    cand.x.extend_from_slice(&self.xyz[0][a..b]);
                    cand.y.extend_from_slice(&self.xyz[1][a..b]);
                    cand.z.extend_from_slice(&self.xyz[2][a..b]);
                    cand.index.extend_from_slice(&self.order[a..b]);
                }
            }
        }
    }

    /// Appends the node over tree positions a..b and its subtree; the split positions are the
    /// ones `split` used (the middle of the range).
    fn build_nodes(&mut self, a: usize, b: usize) -> u32 {
        let id = self.nodes.len() as u32;
        self.nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], kind: NodeKind::Leaf(a as u32, b as u32) });
        let (lo, hi) = if b - a <= LEAF_SIZE {
            self.leaves.push(id);
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for k in 0..3 {
                for &v in &self.xyz[k][a..b] {
                    lo[k] = lo[k].min(v);
                    hi[k] = hi[k].max(v);
                }
            }
            (lo, hi)
        } else {
            let mid = a + (b - a) / 2;
            let l = self.build_nodes(a, mid);
            let r = self.build_nodes(mid, b);
            self.nodes[id as usize].kind = NodeKind::Inner(l, r);
            let (nl, nr) = (&self.nodes[l as usize], &self.nodes[r as usize]);
            ([0, 1, 2].map(|k| nl.lo[k].min(nr.lo[k])), [0, 1, 2].map(|k| nl.hi[k].max(nr.hi[k])))
        };
        let node = &mut self.nodes[id as usize];
        node.lo = lo;
        node.hi = hi;
        id
    }
}

/// Orders `items` into a kd-tree: the middle element splits the range along the widest axis of
/// the cell (lo, hi) — the parent's cell cut at the split, which needs no pass over the points;
/// ties by index, so the tree is the same on every run — down to leaves of LEAF_SIZE.
fn split(items: &mut [([f64; 3], u32)], lo: [f64; 3], hi: [f64; 3]) {
    if items.len() <= LEAF_SIZE {
        return;
    }
    let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])).then(b.cmp(&a))).unwrap_or(0);
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1)));
    let cut = items[mid].0[axis];
    let (mut left_hi, mut right_lo) = (hi, lo);
    left_hi[axis] = cut;
    right_lo[axis] = cut;
    let (left, right) = items.split_at_mut(mid);
    if left.len() + right.len() > PARALLEL_SPLIT {
        rayon::join(|| split(left, lo, left_hi), || split(right, right_lo, hi));
    } else {
        split(left, lo, left_hi);
        split(right, right_lo, hi);
    }
}

/// The squared cap of a neighbor search: ∞ without a radius; a NaN radius finds nothing.
fn cap_squared(radius: Option<f64>) -> f64 {
    let cap2 = radius.map_or(f64::INFINITY, |r| r * r);
    if cap2.is_nan() {
        0.0
    } else {
        cap2
    }
}

/// Squared distance between two boxes (0 when they overlap).
#[inline(always)]
fn box_gap2(alo: &[f64; 3], ahi: &[f64; 3], blo: &[f64; 3], bhi: &[f64; 3]) -> f64 {
    let mut s = 0.0;
    for k in 0..3 {
        let g = (alo[k] - bhi[k]).max(blo[k] - ahi[k]).max(0.0);
        s += g * g;
    }
    s
}

/// The up to `k` candidates nearest first with squared distance ≤ `bound` and < `cap2`, sorted
/// by (squared distance, index), written to `sel`; returns how many. `pos` is scratch as long as
/// `d2`. Entries are (distance bits, index, candidate position): the bits of a non-negative float
/// order as the float does, and integer tuples compare fast.
fn select(
    d2: &[f64],
    index: &[u32],
    bound: f64,
    cap2: f64,
    k: usize,
    pos: &mut [u32],
    sel: &mut Vec<(u64, u32, u32)>,
) -> usize {
    // Branch-free compaction of positions: most candidates fail the test, and unpredictably.
    let limit = if bound < cap2 { bound } else { cap2.next_down() };
    let mut n = 0;
    for (j, &d) in d2.iter().enumerate() {
        pos[n] = j as u32;
        n += (d <= limit) as usize;
    }
    sel.clear();
    sel.extend(pos[..n].iter().map(|&j| (d2[j as usize].to_bits(), index[j as usize], j)));
    let taken = k.min(n);
    if n > taken && taken > 0 {
        sel.select_nth_unstable(taken - 1);
    }
    sel[..taken].sort_unstable();
    taken
}

/// Squared distances from `q` to every candidate, into `out` (as long as the candidates).
fn squared_distances(q: &[f64; 3], c: &Candidates, out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has the feature the function is compiled for (checked above).
            return unsafe { squared_distances_avx2(q, c, out) };
        }
    }
    squared_distances_portable(q, c, out)
}

/// Compiled for AVX2: four distances per instruction. No FMA, so that every distance is
/// bit-identical to the portable path's.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn squared_distances_avx2(q: &[f64; 3], c: &Candidates, out: &mut [f64]) {
    squared_distances_portable(q, c, out)
}

#[inline(always)]
fn squared_distances_portable(q: &[f64; 3], c: &Candidates, out: &mut [f64]) {
    let n = out.len();
    let (x, y, z) = (&c.x[..n], &c.y[..n], &c.z[..n]);
    for i in 0..n {
        let (dx, dy, dz) = (x[i] - q[0], y[i] - q[1], z[i] - q[2]);
        out[i] = dx * dx + dy * dy + dz * dz;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Every point of the cloud by (squared distance to point i, index): sorted once per point,
    /// and every k and radius checked against prefixes of it.
    fn brute_sorted(points: &[[f64; 3]], i: usize) -> Vec<(usize, f64)> {
        let q = points[i];
        let mut all: Vec<(usize, f64)> = points
            .iter()
            .enumerate()
            .map(|(j, p)| (j, (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)))
            .collect();
        all.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        all
    }

    /// The k nearest strictly closer than √cap2, from a sorted list.
    fn nearest(sorted: &[(usize, f64)], k: usize, cap2: f64) -> &[(usize, f64)] {
        let within = sorted.partition_point(|&(_, d2)| d2 < cap2);
        &sorted[..within.min(k)]
    }

    fn cloud(n: usize, seed: u64) -> Vec<[f64; 3]> {
        // A noisy wavy sheet with a few far outliers and exact duplicates: uneven density.
        let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut pts: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                let (x, y) = (rnd() * 50.0, rnd() * 30.0);
                [x, y, (x / 7.0).sin() * 2.0 + rnd() * 0.05]
            })
            .collect();
        for i in 0..n / 50 {
            pts[i * 37 % n] = [rnd() * 50.0, rnd() * 30.0, 20.0 + rnd() * 40.0];
        }
        for i in 0..n / 40 {
            pts[(i * 53 + 11) % n] = pts[(i * 29 + 3) % n];
        }
        pts
    }

    #[test]
    fn knn_equals_brute_force() {
        let pts = cloud(3000, 1);
        let tree = CloudNeighbors::new(&pts).unwrap();
        let ks = [1, 5, 20, 33, 70];
        let got: Vec<Vec<Vec<(usize, f64)>>> = ks
            .iter()
            .map(|&k| tree.map_knn(k, None, |_, nb| nb.iter().map(|n| (n.index, n.dist2)).collect()))
            .collect();
        for i in 0..pts.len() {
            let sorted = brute_sorted(&pts, i);
            for (&k, g) in ks.iter().zip(&got) {
                assert_eq!(g[i], nearest(&sorted, k, f64::INFINITY), "k {k} point {i}");
            }
        }
        for k in ks {
            assert!(tree.map_knn(k, None, |_, nb| nb.iter().all(|n| n.point == pts[n.index])).iter().all(|&ok| ok));
        }
    }

    #[test]
    fn hybrid_equals_brute_force() {
        let pts = cloud(2000, 2);
        let tree = CloudNeighbors::new(&pts).unwrap();
        let cases = [(10, 0.3), (30, 1.0), (5, 100.0)];
        let got: Vec<Vec<Vec<(usize, f64)>>> = cases
            .iter()
            .map(|&(k, r)| tree.map_knn(k, Some(r), |_, nb| nb.iter().map(|n| (n.index, n.dist2)).collect()))
            .collect();
        for i in 0..pts.len() {
            let sorted = brute_sorted(&pts, i);
            for (&(k, r), g) in cases.iter().zip(&got) {
                assert_eq!(g[i], nearest(&sorted, k, r * r), "k {k} r {r} point {i}");
            }
        }
    }

    #[test]
    fn graph_rows_equal_map_knn() {
        let pts = cloud(3000, 5);
        let tree = CloudNeighbors::new(&pts).unwrap();
        for (k, radius) in [(7, None), (25, Some(0.4))] {
            let (index, dist2) = tree.knn_graph(k, radius);
            let lists =
                tree.map_knn(k, radius, |_, nb| nb.iter().map(|n| (n.index as u32, n.dist2)).collect::<Vec<_>>());
            for (i, list) in lists.iter().enumerate() {
                let mut row: Vec<(u32, f64)> = (0..k).map(|r| (index[i * k + r], dist2[i * k + r])).collect();
                assert!(row[list.len()..].iter().all(|&(j, d)| j == u32::MAX && d == f64::INFINITY));
                row.truncate(list.len());
                assert_eq!(&row, list, "k {k} point {i}");
            }
        }
        assert_eq!(tree.knn_graph(0, None), (Vec::new(), Vec::new()));
    }

    #[test]
    fn counts_equal_brute_force() {
        let pts = cloud(2500, 3);
        let tree = CloudNeighbors::new(&pts).unwrap();
        let radii = [0.2, 0.5, 3.0];
        let got: Vec<Vec<usize>> = radii.iter().map(|&r| tree.count_within(r)).collect();
        for i in 0..pts.len() {
            let sorted = brute_sorted(&pts, i);
            for (&r, g) in radii.iter().zip(&got) {
                assert_eq!(g[i], nearest(&sorted, usize::MAX, r * r).len(), "r {r} point {i}");
            }
        }
    }

    #[test]
    fn small_and_degenerate_clouds() {
        let empty = CloudNeighbors::new(&[]).unwrap();
        assert!(empty.map_knn(5, None, |_, nb| nb.len()).is_empty());
        assert!(empty.count_within(1.0).is_empty());
        let same = vec![[1.0, 2.0, 3.0]; 100];
        let tree = CloudNeighbors::new(&same).unwrap();
        let got = tree.map_knn(7, None, |i, nb| (i, nb.iter().map(|n| n.index).collect::<Vec<_>>()));
        assert!(got.iter().all(|(_, nb)| nb == &(0..7).collect::<Vec<_>>()));
        assert!(tree.count_within(1e-9).iter().all(|&c| c == 100));
        let two = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let tree = CloudNeighbors::new(&two).unwrap();
        assert_eq!(tree.map_knn(10, None, |_, nb| nb.len()), vec![2, 2]);
        assert!(CloudNeighbors::new(&[[0.0, f64::NAN, 0.0]]).is_err());
        // Two clusters of identical points closer than any squared distance can tell: every
        // gather radius rounds to 0, and the search must still end.
        let mut tiny = vec![[0.0; 3]; 32];
        for p in &mut tiny[16..] {
            p[0] = 1e-160;
        }
        let tree = CloudNeighbors::new(&tiny).unwrap();
        assert!(tree.map_knn(20, None, |_, nb| nb.len()).iter().all(|&n| n == 20));
        assert!(tree.map_knn(5, Some(f64::NAN), |_, nb| nb.len()).iter().all(|&n| n == 0));
    }

    #[test]
    fn same_answer_on_one_thread() {
        let pts = cloud(20_000, 4);
        let tree = CloudNeighbors::new(&pts).unwrap();
        let two = tree.map_knn(12, None, |_, nb| nb.to_vec());
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let one = pool.install(|| CloudNeighbors::new(&pts).unwrap().map_knn(12, None, |_, nb| nb.to_vec()));
        assert_eq!(one, two);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn knn_on_grids_far_from_the_origin(nx in 1usize..30, ny in 1usize..30, k in 1usize..40, offset in 0.0f64..5000.0) {
            // Grids: many exact ties, which the index order must break.
            let pts: Vec<[f64; 3]> = (0..nx * ny).map(|i| [offset + (i % nx) as f64 * 0.1, offset + (i / nx) as f64 * 0.1, offset]).collect();
            let tree = CloudNeighbors::new(&pts).unwrap();
            let got = tree.map_knn(k, None, |_, nb| nb.iter().map(|n| (n.index, n.dist2)).collect::<Vec<_>>());
            for (i, g) in got.iter().enumerate() {
                let sorted = brute_sorted(&pts, i);
                prop_assert_eq!(g.as_slice(), nearest(&sorted, k, f64::INFINITY));
            }
        }
    }
}
