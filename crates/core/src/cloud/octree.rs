//! Octree simplification keeping features and the boundary (SPEC F, paper 002 §2.1–2.2).
//!
//! 1. Cube edge L = max extent, anchored at the minimum corner (eq 7); depth
//!    n = ⌈log2(L / d_min)⌉ (eq 8). A child holding all of its parent's points is carried down
//!    unchanged, so the leaves are the occupied cells of edge L / 2ⁿ: they are found by hashing
//!    cell indices, with no tree to build.
//! 2. Feature degree f_i = (1/k) Σ_j θ_ij, the mean angle (rad) between a point's normal and its
//!    k neighbors' normals, unoriented (θ = acos |n_i·n_j|) (eq 9).
//! 3. Each leaf keeps its point of largest f (set Q1) and its point nearest the cell center (Q2).
//! 4. Boundary points Q0 in x–y (the cutting depth being z): sorted by x, groups of ε1 points
//!    keep their min-y and max-y points; sorted by y, groups of ε2 keep min-x and max-x.
//! 5. Q = Q0 ∪ Q1 ∪ Q2 as sorted unique indices.
//!
//! Two options go beyond the paper, both off by default. Measured at equal point counts against
//! a voxel grid (tests/test_octree.py), the rule as written keeps creases well but not height
//! steps: neighborhoods a few tenths of a millimetre across never reach over a 3 mm step, so
//! the feature degree there is noise and each leaf straddling the step keeps one random point.
//! - `neighbors: Xy` takes the neighbors of the normals and of the feature degree in the x–y
//!   projection, so a step's two sides see each other (height-field scans, z the cutting depth,
//!   as the boundary rule already assumes).
//! - `refine`: a leaf whose largest feature degree exceeds `feature_threshold` is split
//!   `refine` levels deeper, and each occupied sub-cell keeps its Q1 and Q2 points: points are
//!   spent along the features instead of evenly.
use super::normals::{estimate_normals, Neighborhood};
use crate::error::{Error, Result};
use std::collections::HashMap;

/// Where the neighbors of the normals and of the feature degree are taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NeighborSpace {
    /// The k nearest in 3D (the paper).
    Xyz,
    /// The k nearest in the x–y projection (height-field scans).
    Xy,
}

impl NeighborSpace {
    /// `"xyz"` or `"xy"`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "xyz" => Ok(NeighborSpace::Xyz),
            "xy" => Ok(NeighborSpace::Xy),
            other => Err(Error::invalid("neighbors", format!("expected \"xyz\" or \"xy\", got {other:?}"))),
        }
    }

    /// The k nearest in this space.
    fn knn(self, k: usize) -> Neighborhood {
        match self {
            NeighborSpace::Xyz => Neighborhood::Knn(k),
            NeighborSpace::Xy => Neighborhood::KnnXy(k),
        }
    }
}

/// Deepest octree level: cell indices per axis are u64 counts of `2^depth` cells, and past 40
/// levels a cell is below 1e-12 of the cloud, finer than the coordinates resolve.
const MAX_DEPTH: usize = 40;

pub struct OctreeOptions {
    pub d_min: f64,
    /// Neighbors for the feature degree (and for normals when none are given).
    pub k: usize,
    /// Group sizes of the boundary rule; `None` = the points of a strip d_min wide.
    pub eps1: Option<usize>,
    pub eps2: Option<usize>,
    pub neighbors: NeighborSpace,
    /// Extra levels for leaves whose largest feature degree exceeds `feature_threshold` (0: the
    /// paper's rule).
    pub refine: usize,
    /// Radians.
    pub feature_threshold: f64,
}

impl OctreeOptions {
    /// The paper's rule with cells of edge `d_min`.
    pub fn new(d_min: f64) -> Self {
        OctreeOptions {
            d_min,
            k: 10,
            eps1: None,
            eps2: None,
            neighbors: NeighborSpace::Xyz,
            refine: 0,
            feature_threshold: 0.05,
        }
    }
}

/// Feature degree of every point (eq 9): the mean unoriented angle to the normals of its `k`
/// nearest other points, taken in `space`.
pub fn feature_degree(points: &[[f64; 3]], normals: &[[f64; 3]], k: usize, space: NeighborSpace) -> Result<Vec<f64>> {
    crate::spatial::check_k("k", k, 1, points.len(), crate::spatial::Counting::Others)?;
    if normals.len() != points.len() {
        return Err(Error::shape(
            "normals",
            format!("({}, 3): one per point", points.len()),
            format!("({}, 3)", normals.len()),
        ));
    }
    // k + 1: the point itself is its own nearest neighbor.
    space.knn(k + 1).map(points, |i, nn| {
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
    })
}

/// The boundary rule of step 4; `eps1`, `eps2` ≥ 1.
pub fn boundary_points(points: &[[f64; 3]], eps1: usize, eps2: usize) -> Vec<usize> {
    let mut out = Vec::new();
    for (sort_axis, other, eps) in [(0usize, 1usize, eps1), (1, 0, eps2)] {
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by(|&a, &b| points[a][sort_axis].total_cmp(&points[b][sort_axis]).then(a.cmp(&b)));
        for group in order.chunks(eps.max(1)) {
            let lo =
                group.iter().copied().min_by(|&a, &b| points[a][other].total_cmp(&points[b][other]).then(a.cmp(&b)));
            let hi =
                group.iter().copied().max_by(|&a, &b| points[a][other].total_cmp(&points[b][other]).then(b.cmp(&a)));
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
    if o.refine > MAX_DEPTH {
        return Err(Error::invalid("refine", format!("at most {MAX_DEPTH} extra levels, got {}", o.refine)));
    }
    let n = points.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    if let Some(nr) = normals {
        if nr.len() != n {
            return Err(Error::shape("normals", format!("({n}, 3): one per point"), format!("({}, 3)", nr.len())));
        }
        crate::error::check_finite_points("normals", nr)?;
    }
    crate::error::check_finite_points("points", points)?;
    if !(o.feature_threshold.is_finite() && o.feature_threshold >= 0.0) {
        return Err(Error::invalid(
            "feature_threshold",
            format!("must be an angle >= 0 in radians, got {}", o.feature_threshold),
        ));
    }
    let (lo, hi) = crate::geom::bounds(points);
    let l = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(o.d_min);
    let depth = (l / o.d_min).log2().ceil().max(0.0) as u32;
    let deepest = depth.checked_add(o.refine as u32).filter(|&d| d as usize <= MAX_DEPTH).ok_or_else(|| {
        Error::invalid(
            "d_min",
            format!("{} mm over {l} mm with refine = {} needs an octree deeper than 40 levels", o.d_min, o.refine),
        )
    })?;
    let owned;
    let normals = match normals {
        Some(nr) => nr,
        None => {
            owned = estimate_normals(points, o.neighbors.knn(o.k.max(3)))?.0;
            &owned
        }
    };
    let f = feature_degree(points, normals, o.k, o.neighbors)?;
    let leaves = best_per_cell(points, &f, lo, l, depth, |_| true);
    let mut keep: Vec<usize> = Vec::with_capacity(2 * leaves.len());
    if o.refine == 0 {
        keep.extend(leaves.values().flat_map(|b| [b.feature.1, b.center.1]));
    } else {
        // Feature leaves give way to their occupied sub-cells `refine` levels down.
        let coarse = cell_indexer(lo, l, depth);
        let hot = |i: usize| leaves[&coarse(&points[i])].feature.0 > o.feature_threshold;
        keep.extend(
            leaves.values().filter(|b| b.feature.0 <= o.feature_threshold).flat_map(|b| [b.feature.1, b.center.1]),
        );
        let fine = best_per_cell(points, &f, lo, l, deepest, hot);
        keep.extend(fine.values().flat_map(|b| [b.feature.1, b.center.1]));
    }
    let strip = |axis: usize| -> usize {
        let ext = (hi[axis] - lo[axis]).max(o.d_min);
        ((n as f64 * o.d_min / ext).round() as usize).max(2)
    };
    keep.extend(boundary_points(points, o.eps1.unwrap_or_else(|| strip(0)), o.eps2.unwrap_or_else(|| strip(1))));
    keep.sort_unstable();
    keep.dedup();
    Ok(keep)
}

/// The best points of one cell: (feature degree, index) of its largest feature degree and
/// (squared distance, index) of its point nearest the center.
struct CellBest {
    feature: (f64, usize),
    center: (f64, usize),
}

/// Maps a point to its cell at `depth` of the cube of edge `l` on `lo`.
fn cell_indexer(lo: [f64; 3], l: f64, depth: u32) -> impl Fn(&[f64; 3]) -> [u64; 3] {
    let cell = l / (1u64 << depth) as f64;
    let last = (1u64 << depth) - 1;
    move |p: &[f64; 3]| [0, 1, 2].map(|k| (((p[k] - lo[k]) / cell).floor() as u64).min(last))
}

/// Per occupied cell at `depth` (among the points `take` accepts): the Q1 and Q2 candidates.
/// Strictly better only, points in index order: ties keep the lowest index.
fn best_per_cell(
    points: &[[f64; 3]],
    f: &[f64],
    lo: [f64; 3],
    l: f64,
    depth: u32,
    take: impl Fn(usize) -> bool,
) -> HashMap<[u64; 3], CellBest> {
    let cell = l / (1u64 << depth) as f64;
    let cell_of = cell_indexer(lo, l, depth);
    let mut cells: HashMap<[u64; 3], CellBest> = HashMap::new();
    for (i, p) in points.iter().enumerate() {
        if !take(i) {
            continue;
        }
        let c = cell_of(p);
        let center = [0, 1, 2].map(|k| lo[k] + (c[k] as f64 + 0.5) * cell);
        let d2 = (0..3).map(|k| (p[k] - center[k]).powi(2)).sum::<f64>();
        let best = cells.entry(c).or_insert(CellBest { feature: (f[i], i), center: (d2, i) });
        if f[i] > best.feature.0 {
            best.feature = (f[i], i);
        }
        if d2 < best.center.0 {
            best.center = (d2, i);
        }
    }
    cells
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
        let keep = octree_simplify(&pts, None, &OctreeOptions { k: 8, ..OctreeOptions::new(4.0) }).unwrap();
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

    /// A plate with a 3 mm step at x = 25 (jittered grid, as a height-field scan sees it).
    fn stepped_plate() -> Vec<[f64; 3]> {
        let mut pts = Vec::new();
        for i in 0..200 {
            for j in 0..120 {
                let jitter = ((i * 7 + j * 13) % 11) as f64 * 0.005;
                let x = i as f64 * 0.25 + jitter;
                pts.push([x, j as f64 * 0.25 + jitter, if x < 25.0 { 0.0 } else { -3.0 }]);
            }
        }
        pts
    }

    #[test]
    fn xy_neighbors_see_the_step_and_refine_spends_points_on_it() {
        let pts = stepped_plate();
        let near_step = |p: &[f64; 3]| (p[0] - 25.0).abs() < 1.0;
        // In 3D, 10 neighbors never reach over 3 mm: the feature degree is 0 at the step.
        let n3 = estimate_normals(&pts, Neighborhood::Knn(10)).unwrap().0;
        let f3 = feature_degree(&pts, &n3, 10, NeighborSpace::Xyz).unwrap();
        assert!(f3.iter().all(|&f| f < 1e-6), "{:?}", f3.iter().cloned().fold(0.0, f64::max));
        // In x–y they do: the points at the step stand out, the rest stays flat.
        let nxy = estimate_normals(&pts, Neighborhood::KnnXy(10)).unwrap().0;
        let fxy = feature_degree(&pts, &nxy, 10, NeighborSpace::Xy).unwrap();
        assert!(pts.iter().zip(&fxy).all(|(p, &f)| near_step(p) || f < 1e-6));
        assert!(pts.iter().zip(&fxy).filter(|(p, _)| near_step(p)).any(|(_, &f)| f > 0.5));
        let paper =
            octree_simplify(&pts, None, &OctreeOptions { neighbors: NeighborSpace::Xy, ..OctreeOptions::new(4.0) })
                .unwrap();
        let refined = octree_simplify(
            &pts,
            None,
            &OctreeOptions { neighbors: NeighborSpace::Xy, refine: 2, ..OctreeOptions::new(4.0) },
        )
        .unwrap();
        let at_step = |keep: &[usize]| keep.iter().filter(|&&i| near_step(&pts[i])).count();
        // Cells of 3.125 mm → sub-cells of 0.78 mm along the step's 30 mm: many more points
        // there, and the same points elsewhere.
        assert!(at_step(&refined) >= 3 * at_step(&paper), "{} vs {}", at_step(&refined), at_step(&paper));
        let far = |keep: &[usize]| keep.iter().copied().filter(|&i| (pts[i][0] - 25.0).abs() > 8.0).collect::<Vec<_>>();
        assert_eq!(far(&refined), far(&paper));
        // Both sides of the step keep points right at its edge.
        for side in [-1.0, 1.0] {
            assert!(refined.iter().any(|&i| (pts[i][0] - 25.0) * side > 0.0 && (pts[i][0] - 25.0).abs() < 0.3));
        }
    }
}
