//! Euclidean clustering (SPEC C1, paper 000 §2.2): points closer than a threshold belong to the
//! same contour. Unlike k-means it needs no cluster count.
//!
//! Clusters are the connected components of the neighbour graph: i—j when j is within `radius`
//! of i (radius form, the same partition as DBSCAN with min_points = 1, i.e. Open3D's
//! `cluster_dbscan(eps, 1)`), or when j is one of the `k` nearest of i within `radius` or i one
//! of j's (the paper's k-nearest form, made symmetric so the result does not depend on which
//! point a cluster grows from). Neighbours are queried in parallel blocks and merged by
//! union–find: memory stays O(N), with no neighbour lists kept for the whole cloud. Clusters are
//! labelled 0, 1, … in the order of their lowest point index, as Open3D labels them.
use super::PointIndex;
use crate::error::{Error, Result};
use rayon::prelude::*;

const BLOCK: usize = 8192;

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        // Path halving.
        let p = parent[i as usize];
        parent[i as usize] = parent[p as usize];
        i = parent[p as usize];
    }
    i
}

/// Labels `(N,)`: the cluster of every point, 0..n_clusters−1.
pub fn euclidean_clusters(points: &[[f64; 3]], radius: f64, k: Option<usize>) -> Result<Vec<usize>> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(Error::invalid("radius", format!("must be a positive distance in mm, got {radius}")));
    }
    if k == Some(0) {
        return Err(Error::invalid("k", "must be at least 1"));
    }
    let n = points.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let index = PointIndex::new(points)?;
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut start = 0;
    while start < n {
        let end = (start + BLOCK).min(n);
        let edges: Vec<Vec<u32>> = (start..end)
            .into_par_iter()
            .map(|i| {
                let mut out = Vec::new();
                match k {
                    None => index.for_each_within(&points[i], radius, |j| {
                        if j > i {
                            out.push(j as u32)
                        }
                    }),
                    Some(k) => {
                        // k + 1: the point itself is its own nearest neighbour.
                        for (j, _) in index.knn_within(&points[i], k + 1, radius) {
                            if j != i {
                                out.push(j as u32);
                            }
                        }
                    }
                }
                out
            })
            .collect();
        for (i, js) in (start..end).zip(edges) {
            for j in js {
                let (a, b) = (find(&mut parent, i as u32), find(&mut parent, j));
                if a != b {
                    // The smaller index becomes the root, so roots are cluster minima.
                    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                    parent[hi as usize] = lo;
                }
            }
        }
        start = end;
    }
    let mut label = vec![usize::MAX; n];
    let mut labels = Vec::with_capacity(n);
    let mut next = 0;
    for i in 0..n {
        let r = find(&mut parent, i as u32) as usize;
        if label[r] == usize::MAX {
            label[r] = next;
            next += 1;
        }
        labels.push(label[r]);
    }
    Ok(labels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separates_two_lines_and_labels_by_first_point() {
        let mut pts = Vec::new();
        for i in 0..100 {
            pts.push([10.0 + i as f64 * 0.5, 0.0, 0.0]); // cluster B listed first? no: A below
        }
        for i in 0..50 {
            pts.insert(0, [i as f64 * 0.5, 20.0, 0.0]);
        }
        let labels = euclidean_clusters(&pts, 1.0, None).unwrap();
        assert!(labels[..50].iter().all(|&l| l == 0));
        assert!(labels[50..].iter().all(|&l| l == 1));
        let labels_k = euclidean_clusters(&pts, 1.0, Some(5)).unwrap();
        assert_eq!(labels, labels_k);
        // A gap larger than the radius splits a line.
        let split = euclidean_clusters(&pts, 0.4, None).unwrap();
        assert_eq!(*split.iter().max().unwrap(), 149);
    }

    #[test]
    fn chains_across_blocks_merge() {
        // A single long chain, longer than a block, listed in a scrambled order.
        let n = 3 * BLOCK + 17;
        let mut order: Vec<usize> = (0..n).collect();
        let mut s = 12345u64;
        for i in (1..n).rev() {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            order.swap(i, (s >> 33) as usize % (i + 1));
        }
        let pts: Vec<[f64; 3]> = order.iter().map(|&i| [i as f64 * 0.1, 0.0, 0.0]).collect();
        let labels = euclidean_clusters(&pts, 0.15, None).unwrap();
        assert!(labels.iter().all(|&l| l == 0));
    }

    #[test]
    fn rejects_bad_radius_and_k() {
        assert!(euclidean_clusters(&[[0.0; 3]], 0.0, None).is_err());
        assert!(euclidean_clusters(&[[0.0; 3]], 1.0, Some(0)).is_err());
        assert!(euclidean_clusters(&[[f64::NAN, 0.0, 0.0]], 1.0, None).is_err());
    }
}
