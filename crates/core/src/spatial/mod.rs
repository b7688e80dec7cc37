//! Neighborhood queries over point clouds, in one place for clustering, filters, normals and
//! registration: `PointIndex` (kiddo) for queries from arbitrary points, `CloudNeighbors` for
//! the neighborhoods of every point of a cloud at once; and Euclidean clustering (SPEC C1).
//! The formulas: docs/clouds.md (neighbors), docs/contours.md (clustering).
mod cluster;
mod index;
mod neighbors;

pub use cluster::euclidean_clusters;
pub use index::PointIndex;
pub use neighbors::{CloudNeighbors, Neighbor};

use crate::error::{check_finite_points, check_positive, Error, Result};
use rayon::prelude::*;

/// Whether a neighbor count includes the point itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Counting {
    /// The point is its own nearest neighbor (Open3D's filters and normals, `knn_graph`).
    WithSelf,
    /// Neighbors are the other points (feature degree, clustering, consistent orientation).
    Others,
}

/// The one rule for neighbor counts `k`, the same in every function: at least `min`, and no
/// more than the cloud of `n` points can give. Asking for more is an error, not a silent clamp:
/// a neighborhood smaller than asked changes normals, outlier statistics and clusters.
/// An empty cloud gives an empty result and is not checked.
pub fn check_k(name: &str, k: usize, min: usize, n: usize, counting: Counting) -> Result<()> {
    if k < min.max(1) {
        let why = if min > 1 { format!(" (a plane needs {min} points)") } else { String::new() };
        return Err(Error::invalid(name, format!("must be at least {}{why}, got {k}", min.max(1))));
    }
    let available = match counting {
        Counting::WithSelf => n,
        Counting::Others => n.saturating_sub(1),
    };
    if n > 0 && k > available {
        let what = match counting {
            Counting::WithSelf => format!("the cloud has {n} points (a point counts as its own neighbor)"),
            Counting::Others => format!("the cloud has {n} points, so each has {available} others"),
        };
        return Err(Error::invalid(name, format!("{k} neighbors asked, but {what}")));
    }
    Ok(())
}

/// The nearest point of `points` for every query: (index, distance in mm), in parallel.
pub fn nearest_neighbors(points: &[[f64; 3]], queries: &[[f64; 3]]) -> Result<(Vec<usize>, Vec<f64>)> {
    if points.is_empty() && !queries.is_empty() {
        return Err(Error::shape("points", "(N, 3) with at least one point to search", "(0, 3)"));
    }
    check_finite_points("queries", queries)?;
    if queries.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let index = PointIndex::new(points)?;
    Ok(queries.par_iter().map(|q| index.nearest(q)).unzip())
}

/// The k-nearest graph of a cloud: `(N, k)` row-major indices and distances (mm), nearest
/// first, ties by index; with `radius` only neighbors strictly closer than it, rows padded with
/// `None` and ∞.
pub fn knn_graph(points: &[[f64; 3]], k: usize, radius: Option<f64>) -> Result<(Vec<Option<usize>>, Vec<f64>)> {
    check_finite_points("points", points)?;
    check_k("k", k, 1, points.len(), Counting::WithSelf)?;
    if let Some(r) = radius {
        check_positive("radius", r, "mm")?;
    }
    let (index, dist2) = CloudNeighbors::new(points)?.knn_graph(k, radius);
    let index = index.par_iter().map(|&j| (j != u32::MAX).then_some(j as usize)).collect();
    Ok((index, dist2.par_iter().map(|d| d.sqrt()).collect()))
}
