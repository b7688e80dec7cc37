//! Octree simplification keeping features and the boundary (SPEC F, paper 002 §2.1–2.2).
//!
//! 1. Cube edge L = max extent, anchored at the minimum corner (eq 7); depth
//!    n = ⌈log2(L / d_min)⌉ (eq 8). A child holding all of its parent's points is carried down
//!    unchanged, so the leaves are the occupied cells of edge L / 2ⁿ: they are found by hashing
//!    cell indices, with no tree to build.
//! 2. Feature degree f_i = (1/k) Σ_j θ_ij, the mean angle (rad) between a point's normal and its
//!    k neighbours' normals, unoriented (θ = acos |n_i·n_j|) (eq 9).
//! 3. Each leaf keeps its point of largest f (set Q1) and its point nearest the cell centre (Q2).
//! 4. Boundary points Q0 in x–y (the cutting depth being z): sorted by x, groups of ε1 points
//!    keep their min-y and max-y points; sorted by y, groups of ε2 keep min-x and max-x.
//! 5. Q = Q0 ∪ Q1 ∪ Q2 as sorted unique indices.
use super::normals::{estimate_normals, Neighbourhood};
use crate::error::{Error, Result};
use crate::spatial::CloudNeighbours;
use std::collections::HashMap;

pub struct OctreeOptions {
    pub d_min: f64,
    /// Neighbours for the feature degree (and for normals when none are given).
    pub k: usize,
    /// Group sizes of the boundary rule; `None` = the points of a strip d_min wide.
    pub eps1: Option<usize>,
    pub eps2: Option<usize>,
}

/// Feature degree of every point (eq 9).
pub fn feature_degree(points: &[[f64; 3]], normals: &[[f64; 3]], k: usize) -> Result<Vec<f64>> {
    if k == 0 {
        return Err(Error::invalid("k", "must be at least 1"));
    }
    if normals.len() != points.len() {
        return Err(Error::shape("normals", format!("({}, 3): one per point", points.len()), format!("({}, 3)", normals.len())));
    }
    // k + 1: the point itself is its own nearest neighbour.
    Ok(CloudNeighbours::new(points)?.map_knn(k + 1, None, |i, nn| {
        let ni = normals[i];
        let mut sum = 0.0;
        let mut count = 0;
        for j in nn.iter().map(|n| n.index).filter(|&j| j != i).take(k) {
            let nj = normals[j];
            sum += (ni[0] * nj[0] + ni[1] * nj[1] + ni[2] * nj[2]).abs().min(1.0).acos();
            count += 1;
        }
        if count == 0 {
            0.0
        } else {
            sum / count as f64
        }
    }))
}

/// The boundary rule of step 4; `eps1`, `eps2` ≥ 1.
pub fn boundary_points(points: &[[f64; 3]], eps1: usize, eps2: usize) -> Vec<usize> {
    let mut out = Vec::new();
    for (sort_axis, other, eps) in [(0usize, 1usize, eps1), (1, 0, eps2)] {
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by(|&a, &b| points[a][sort_axis].total_cmp(&points[b][sort_axis]).then(a.cmp(&b)));
        for group in order.chunks(eps.max(1)) {
            let lo = group.iter().copied().min_by(|&a, &b| points[a][other].total_cmp(&points[b][other]).then(a.cmp(&b)));
            let hi = group.iter().copied().max_by(|&a, &b| points[a][other].total_cmp(&points[b][other]).then(b.cmp(&a)));
            out.extend(lo);
            out.extend(hi);
        }
    }
    out
}

pub fn octree_simplify(points: &[[f64; 3]], normals: Option<&[[f64; 3]]>, o: &OctreeOptions) -> Result<Vec<usize>> {
    if !(o.d_min.is_finite() && o.d_min > 0.0) {
        return Err(Error::invalid("d_min", format!("must be a positive cell edge in mm, got {}", o.d_min)));
    }
    if o.eps1 == Some(0) || o.eps2 == Some(0) {
        return Err(Error::invalid("eps1, eps2", "group sizes must be at least 1"));
    }
    let n = points.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    if let Some(nr) = normals {
        if nr.len() != n {
            return Err(Error::shape("normals", format!("({n}, 3): one per point"), format!("({}, 3)", nr.len())));
        }
    }
    if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(Error::invalid("points", format!("must be finite, found {:?} at row {i}", points[i])));
    }
    let (lo, hi) = crate::geom::bounds(points);
    let l = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(o.d_min);
    let depth = (l / o.d_min).log2().ceil().max(0.0) as u32;
    if depth > 40 {
        return Err(Error::invalid("d_min", format!("{} mm over {l} mm needs an octree {depth} levels deep (at most 40)", o.d_min)));
    }
    let cell = l / (1u64 << depth) as f64;
    let cells_per_axis = 1u64 << depth;
    let cell_of = |p: &[f64; 3]| -> [u64; 3] {
        [0, 1, 2].map(|k| (((p[k] - lo[k]) / cell).floor() as u64).min(cells_per_axis - 1))
    };
    let owned;
    let normals = match normals {
        Some(nr) => nr,
        None => {
            owned = estimate_normals(points, Neighbourhood::Knn(o.k.max(3)))?.0;
            &owned
        }
    };
    let f = feature_degree(points, normals, o.k)?;
    // Leaves: per occupied cell, the best feature point and the point nearest the centre.
    struct Leaf {
        feature: (f64, usize),
        centre: (f64, usize),
    }
    let mut leaves: HashMap<[u64; 3], Leaf> = HashMap::new();
    for (i, p) in points.iter().enumerate() {
        let c = cell_of(p);
        let centre = [0, 1, 2].map(|k| lo[k] + (c[k] as f64 + 0.5) * cell);
        let d2 = (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum::<f64>();
        let leaf = leaves.entry(c).or_insert(Leaf { feature: (f[i], i), centre: (d2, i) });
        // Strictly better only: ties keep the lowest index (points come in index order).
        if f[i] > leaf.feature.0 {
            leaf.feature = (f[i], i);
        }
        if d2 < leaf.centre.0 {
            leaf.centre = (d2, i);
        }
    }
    let mut keep: Vec<usize> = leaves.values().flat_map(|l| [l.feature.1, l.centre.1]).collect();
    let strip = |axis: usize| -> usize {
        let ext = (hi[axis] - lo[axis]).max(o.d_min);
        ((n as f64 * o.d_min / ext).round() as usize).max(2)
    };
    keep.extend(boundary_points(points, o.eps1.unwrap_or_else(|| strip(0)), o.eps2.unwrap_or_else(|| strip(1))));
    keep.sort_unstable();
    keep.dedup();
    Ok(keep)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_boundary_and_the_crease() {
        // A roof: two planes meeting at a ridge along y, sampled on a grid.
        let mut pts = Vec::new();
        for i in 0..=100 {
            for j in 0..=60 {
                let x = i as f64 * 0.5;
                pts.push([x, j as f64 * 0.5, 10.0 - (x - 25.0).abs() * 0.5]);
            }
        }
        let keep = octree_simplify(&pts, None, &OctreeOptions { d_min: 4.0, k: 8, eps1: None, eps2: None }).unwrap();
        assert!(keep.len() < pts.len() / 5, "{}", keep.len());
        assert!(keep.windows(2).all(|w| w[0] < w[1]));
        // The free boundary stays covered: along each of the four edges, kept points with no
        // gap wider than 2·d_min.
        for (axis, value, along) in [(1usize, 0.0, 0usize), (1, 30.0, 0), (0, 0.0, 1), (0, 50.0, 1)] {
            let mut s: Vec<f64> = keep.iter().filter(|&&i| pts[i][axis] == value).map(|&i| pts[i][along]).collect();
            s.sort_by(f64::total_cmp);
            let span = if along == 0 { 50.0 } else { 30.0 };
            assert!(!s.is_empty() && s[0] <= 8.0 && s[s.len() - 1] >= span - 8.0, "edge {axis}={value}: {s:?}");
            assert!(s.windows(2).all(|w| w[1] - w[0] <= 8.0), "edge {axis}={value}: {s:?}");
        }
        // Ridge points (x = 25) are kept in every leaf the ridge crosses.
        let ridge_kept = keep.iter().filter(|&&i| pts[i][0] == 25.0).count();
        assert!(ridge_kept >= 6, "{ridge_kept}");
    }
}
