//! The kd-tree facade. kiddo's immutable tree gives the best query speed for clouds that are
//! built once and queried many times, which is every use in machscan.
use crate::error::{Error, Result};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;

pub struct PointIndex {
    tree: ImmutableKdTree<f64, 3>,
    len: usize,
}

impl PointIndex {
    /// Builds the index over `points` (finite, at most u32::MAX − 1 of them); items are indices.
    pub fn new(points: &[[f64; 3]]) -> Result<Self> {
        if points.len() >= u32::MAX as usize {
            return Err(Error::invalid("points", format!("{} points exceed the 2^32 − 1 an index can hold", points.len())));
        }
        if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(Error::invalid("points", format!("must be finite, found {:?} at row {i}", points[i])));
        }
        let tree = ImmutableKdTree::new_from_slice(points)
            .map_err(|e| Error::invalid("points", format!("cannot build the kd-tree: {e:?}")))?;
        Ok(PointIndex { tree, len: points.len() })
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Nearest point: (index, distance).
    pub fn nearest(&self, q: &[f64; 3]) -> (usize, f64) {
        let r = self.tree.query(q).nearest_one::<SquaredEuclidean<f64>>().execute();
        (r.item as usize, r.distance.sqrt())
    }

    /// The `k` nearest points, nearest first: (index, squared distance).
    pub fn knn(&self, q: &[f64; 3], k: usize) -> Vec<(usize, f64)> {
        let Some(k) = NonZeroUsize::new(k) else { return Vec::new() };
        self.tree
            .query(q)
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute()
            .into_iter()
            .map(|r| (r.item as usize, r.distance))
            .collect()
    }

    /// Calls `visit(index)` for every point within `radius` (inclusive), in no order.
    pub fn for_each_within(&self, q: &[f64; 3], radius: f64, mut visit: impl FnMut(usize)) {
        for r in self.tree.query(q).within::<SquaredEuclidean<f64>>(radius * radius).unsorted().execute() {
            visit(r.item as usize);
        }
    }

    /// An order of the points along a Morton (Z-order) curve. Queries issued in this order hit
    /// the same tree leaves one after another instead of jumping across the cloud: scanned and
    /// merged clouds often come in no spatial order, and the cache misses then dominate.
    pub fn locality_order(points: &[[f64; 3]]) -> Vec<usize> {
        let (lo, hi) = crate::geom::bounds(points);
        let scale: Vec<f64> = (0..3).map(|k| if hi[k] > lo[k] { 1023.999 / (hi[k] - lo[k]) } else { 0.0 }).collect();
        // Spread 10 bits so that three interleave into 30.
        let spread = |v: u32| -> u64 {
            let mut x = v as u64 & 0x3ff;
            x = (x | (x << 16)) & 0x0300_00ff;
            x = (x | (x << 8)) & 0x0300_f00f;
            x = (x | (x << 4)) & 0x030c_30c3;
            (x | (x << 2)) & 0x0924_9249
        };
        let mut keyed: Vec<(u64, usize)> = points
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let c = [0, 1, 2].map(|k| ((p[k] - lo[k]) * scale[k]) as u32);
                (spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2), i)
            })
            .collect();
        keyed.par_sort_unstable();
        keyed.into_iter().map(|(_, i)| i).collect()
    }

    /// `f(i)` for every point, computed in locality order and in parallel, returned in point
    /// order (so the result does not depend on the order of evaluation).
    pub fn map_in_locality_order<T: Send + Default + Clone>(points: &[[f64; 3]], f: impl Fn(usize) -> T + Sync) -> Vec<T> {
        let order = PointIndex::locality_order(points);
        let computed: Vec<T> = order.par_iter().map(|&i| f(i)).collect();
        let mut out = vec![T::default(); points.len()];
        for (v, &i) in computed.into_iter().zip(&order) {
            out[i] = v;
        }
        out
    }

    /// The `k` nearest points of every query, nearest first, in query order.
    ///
    /// Queries run in locality order, in parallel chunks; each search is bounded by 1.5 × the
    /// k-th distance of the query before it (a near neighbour along the curve), which prunes
    /// the tree far better than an unbounded search. When the bounded search finds k points they
    /// are exactly the k nearest; otherwise the query is repeated unbounded.
    pub fn knn_many(&self, queries: &[[f64; 3]], k: usize) -> Vec<Vec<(usize, f64)>> {
        let k = k.min(self.len);
        if k == 0 {
            return vec![Vec::new(); queries.len()];
        }
        let order = PointIndex::locality_order(queries);
        let chunks: Vec<Vec<(usize, Vec<(usize, f64)>)>> = order
            .par_chunks(2048)
            .map(|chunk| {
                let mut bound = f64::INFINITY;
                chunk
                    .iter()
                    .map(|&qi| {
                        let q = &queries[qi];
                        let mut res = if bound.is_finite() { self.knn_within(q, k, bound * 1.5) } else { Vec::new() };
                        if res.len() < k {
                            res = self.knn(q, k);
                        }
                        bound = res.last().map_or(f64::INFINITY, |r| r.1.sqrt());
                        if bound == 0.0 {
                            bound = f64::INFINITY;
                        }
                        (qi, res)
                    })
                    .collect()
            })
            .collect();
        let mut out = vec![Vec::new(); queries.len()];
        for chunk in chunks {
            for (qi, res) in chunk {
                out[qi] = res;
            }
        }
        out
    }

    /// The `k` nearest points within `radius`, nearest first: (index, squared distance).
    pub fn knn_within(&self, q: &[f64; 3], k: usize, radius: f64) -> Vec<(usize, f64)> {
        let Some(kk) = NonZeroUsize::new(k) else { return Vec::new() };
        self.tree
            .query(q)
            .nearest_n::<SquaredEuclidean<f64>>(kk)
            .within(radius * radius)
            .execute()
            .into_iter()
            .map(|r| (r.item as usize, r.distance))
            .collect()
    }
}
