//! The kd-tree facade for queries from arbitrary points (contour matching, clustering, duplicate
//! removal, registration). kiddo's immutable tree gives the best query speed for clouds built
//! once and queried many times. Neighborhoods of a cloud's own points, asked for every point at
//! once, go through `CloudNeighbors`, which answers them in bulk.
use crate::error::{Error, Result};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZeroUsize;

pub struct PointIndex {
    tree: ImmutableKdTree<f64, 3>,
    len: usize,
}

impl PointIndex {
    /// Builds the index over `points` (finite, at most u32::MAX − 1 of them); items are indices.
    pub fn new(points: &[[f64; 3]]) -> Result<Self> {
        if points.len() >= u32::MAX as usize {
            return Err(Error::invalid(
                "points",
                format!("{} points exceed the 2^32 − 1 an index can hold", points.len()),
            ));
        }
        crate::error::check_finite_points("points", points)?;
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

    /// Nearest point: (index, squared distance).
    pub fn nearest_squared(&self, q: &[f64; 3]) -> (usize, f64) {
        let r = self.tree.query(q).nearest_one::<SquaredEuclidean<f64>>().execute();
        (r.item as usize, r.distance)
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

    /// The `k` nearest points within `radius` (inclusive), nearest first: (index, squared
    /// distance).
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
