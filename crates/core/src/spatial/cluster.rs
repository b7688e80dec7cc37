//! Euclidean clustering (SPEC C1, paper 000 §2.2): points closer than a threshold belong to the
//! same contour. Unlike k-means it needs no cluster count.
//!
//! Clusters are the connected components of the neighbor graph: i—j when j is closer than
//! `radius` to i (strictly, as Open3D's radius search: the same partition as DBSCAN with
//! min_points = 1, i.e. Open3D's `cluster_dbscan(eps, 1)`), or when j is one of the `k` nearest of i within `radius` or i one
//! of j's (the paper's k-nearest form, made symmetric so the result does not depend on which
//! point a cluster grows from). Neighbors are queried in parallel blocks and merged by
//! union–find: memory stays O(N), with no neighbor lists kept for the whole cloud. Clusters are
//! labelled 0, 1, … in the order of their lowest point index, as Open3D labels them.
//!
//! The radius form does not query a kd-tree per point: with grid cells of edge r/√3 every two
//! points of a cell are within r, so a cell is connected inside for free and only pairs of
//! nearby cells need a test, which stops at the first pair of points within r. On groove-center
//! clouds (dense along thin contours) this is several times faster than per-point queries.
use super::PointIndex;
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::collections::HashMap;

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
    crate::error::check_positive("radius", radius, "mm")?;
    let n = points.len();
    if let Some(k) = k {
        super::check_k("k", k, 1, n, super::Counting::Others)?;
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    if n >= u32::MAX as usize {
        return Err(Error::invalid("points", format!("{n} points exceed the 2^32 − 1 labels can hold")));
    }
    crate::error::check_finite_points("points", points)?;
    let mut parent: Vec<u32> = (0..n as u32).collect();
    match k {
        None => union_within_radius_grid(points, radius, &mut parent),
        Some(k) => union_knn(points, radius, k, &mut parent)?,
    }
    Ok(canonical_labels(&mut parent))
}

fn union(parent: &mut [u32], i: u32, j: u32) {
    let (a, b) = (find(parent, i), find(parent, j));
    if a != b {
        // The smaller index becomes the root, so roots are cluster minima.
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        parent[hi as usize] = lo;
    }
}

/// Labels numbered in the order of each cluster's lowest point index.
fn canonical_labels(parent: &mut [u32]) -> Vec<usize> {
    let n = parent.len();
    let mut label = vec![usize::MAX; n];
    let mut labels = Vec::with_capacity(n);
    let mut next = 0;
    for i in 0..n {
        let r = find(parent, i as u32) as usize;
        if label[r] == usize::MAX {
            label[r] = next;
            next += 1;
        }
        labels.push(label[r]);
    }
    labels
}

type Cell = [i64; 3];

/// Radius form on a grid of cells of edge r/√3 (see the module note).
fn union_within_radius_grid(points: &[[f64; 3]], radius: f64, parent: &mut [u32]) {
    let n = points.len();
    // A hair under r/√3, so that two points of one cell are strictly closer than r.
    let edge = radius / 3f64.sqrt() * (1.0 - 1e-12);
    let r2 = radius * radius;
    let cell_of = |p: &[f64; 3]| -> Cell {
        [(p[0] / edge).floor() as i64, (p[1] / edge).floor() as i64, (p[2] / edge).floor() as i64]
    };
    // Points sorted by cell (stable: within a cell, by index).
    let mut order: Vec<u32> = (0..n as u32).collect();
    let cells: Vec<Cell> = points.par_iter().map(cell_of).collect();
    order.par_sort_by_key(|&i| (cells[i as usize], i));
    let mut starts = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        if k == 0 || cells[i as usize] != cells[order[k - 1] as usize] {
            starts.push(k);
        }
    }
    starts.push(n);
    let n_cells = starts.len() - 1;
    let lookup: HashMap<Cell, usize> = (0..n_cells).map(|c| (cells[order[starts[c]] as usize], c)).collect();
    // Inside a cell every point is within r of every other.
    for c in 0..n_cells {
        let first = order[starts[c]];
        for &i in &order[starts[c] + 1..starts[c + 1]] {
            union(parent, first, i);
        }
    }
    // Forward half of the 5×5×5 neighborhood (cells up to 2 edges away can hold points within
    // r = √3 edges); each unordered pair of cells is tested once.
    let offsets: Vec<Cell> = (-2..=2i64)
        .flat_map(|a| (-2..=2i64).flat_map(move |b| (-2..=2i64).map(move |c| [a, b, c])))
        .filter(|d| *d > [0, 0, 0])
        .collect();
    let linked: Vec<Vec<(u32, u32)>> = (0..n_cells)
        .into_par_iter()
        .map(|c| {
            let here = cells[order[starts[c]] as usize];
            let members = &order[starts[c]..starts[c + 1]];
            let mut out = Vec::new();
            for d in &offsets {
                let Some(&o) = lookup.get(&[here[0] + d[0], here[1] + d[1], here[2] + d[2]]) else { continue };
                let others = &order[starts[o]..starts[o + 1]];
                'pair: for &i in members {
                    let p = points[i as usize];
                    for &j in others {
                        let q = points[j as usize];
                        if (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2) < r2 {
                            out.push((i, j));
                            break 'pair;
                        }
                    }
                }
            }
            out
        })
        .collect();
    for pairs in linked {
        for (i, j) in pairs {
            union(parent, i, j);
        }
    }
}

/// The paper's k-nearest form, via kd-tree queries in parallel blocks.
fn union_knn(points: &[[f64; 3]], radius: f64, k: usize, parent: &mut [u32]) -> Result<()> {
    let n = points.len();
    let index = PointIndex::new(points)?;
    let r2 = radius * radius;
    let mut start = 0;
    while start < n {
        let end = (start + BLOCK).min(n);
        let edges: Vec<Vec<u32>> = (start..end)
            .into_par_iter()
            .map(|i| {
                // k + 1: the point itself is its own nearest neighbor. kiddo's radius is
                // inclusive, ours strict: points at exactly `radius` come last and are dropped.
                index
                    .knn_within(&points[i], k + 1, radius)
                    .into_iter()
                    .filter(|&(j, d2)| j != i && d2 < r2)
                    .map(|(j, _)| j as u32)
                    .collect()
            })
            .collect();
        for (i, js) in (start..end).zip(edges) {
            for j in js {
                union(parent, i as u32, j);
            }
        }
        start = end;
    }
    Ok(())
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
    fn radius_is_strict_in_both_forms() {
        // Neighbors exactly `radius` apart are not joined; a hair closer they are.
        let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(euclidean_clusters(&pts, 1.0, None).unwrap(), vec![0, 1, 2]);
        assert_eq!(euclidean_clusters(&pts, 1.0, Some(2)).unwrap(), vec![0, 1, 2]);
        assert_eq!(euclidean_clusters(&pts, 1.0 + 1e-12, None).unwrap(), vec![0, 0, 0]);
        assert_eq!(euclidean_clusters(&pts, 1.0 + 1e-12, Some(2)).unwrap(), vec![0, 0, 0]);
    }

    #[test]
    fn rejects_bad_radius_and_k() {
        assert!(euclidean_clusters(&[[0.0; 3]], 0.0, None).is_err());
        assert!(euclidean_clusters(&[[0.0; 3]], 1.0, Some(0)).is_err());
        assert!(euclidean_clusters(&[[f64::NAN, 0.0, 0.0]], 1.0, None).is_err());
    }
}
