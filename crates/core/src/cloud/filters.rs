//! Point cloud filters. Where Open3D has the same filter its definition is matched exactly,
//! so results compare index for index (Open3D 0.20, `PointCloud.cpp`):
//!
//! - voxel grid: origin = min bound − voxel/2, voxel = ⌊(p − origin)/voxel⌋, centroid = sum in
//!   point order / count (`voxel_down_sample`);
//! - statistical outlier removal: k nearest including the point itself, mean of the distances
//!   (summed nearest first); over the points with a non-zero mean, the sum of the means and of
//!   their squared deviations, both divided as Open3D does by N and N − 1 for all N points;
//!   kept when 0 < mean_i < mean + ratio·std (`remove_statistical_outlier`);
//! - radius outlier removal: points strictly within the radius, the point itself included,
//!   kept when more than `min_neighbors` (`remove_radius_outlier(nb_points, radius)`);
//! - uniform down-sampling: every k-th point from the first (`uniform_down_sample`).
//!
//! Voxel keys are 64-bit and relative to the minimum bound, so clouds in machine coordinates
//! several metres from the origin keep full precision.
use crate::error::{Error, Result};
use crate::spatial::{check_k, CloudNeighbors, Counting, PointIndex};
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

fn check_points(points: &[[f64; 3]]) -> Result<()> {
    crate::error::check_finite_points("points", points)?;
    Ok(())
}

/// Indices of the points inside the axis-aligned box `[min, max]` (bounds included).
pub fn crop_box(points: &[[f64; 3]], min: [f64; 3], max: [f64; 3]) -> Result<Vec<usize>> {
    if (0..3).any(|k| !(min[k] <= max[k])) {
        return Err(Error::invalid(
            "min_bound",
            format!("must be <= max_bound in every axis, got {min:?} and {max:?}"),
        ));
    }
    Ok((0..points.len())
        .into_par_iter()
        .filter(|&i| (0..3).all(|k| points[i][k] >= min[k] && points[i][k] <= max[k]))
        .collect())
}

/// A voxel grid: one centroid per occupied voxel, voxels in the order of their first point.
pub struct VoxelGrid {
    pub centroids: Vec<[f64; 3]>,
    /// Voxel of every input point (index into `centroids`).
    pub voxel_of_point: Vec<u32>,
}

/// Splitmix-style hasher for voxel keys: std's SipHash is several times slower here and
/// protects against nothing a point cloud can do.
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        let mut z = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 << 8) | b as u64 ^ (self.0 >> 56);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 ^= v.wrapping_add(self.0 << 6);
    }
}

/// Voxel indices per axis a key holds: three 21-bit indices packed into 64 bits.
const KEY_BITS: u32 = 21;

/// The grid of a voxel downsample: its origin (the minimum bound less half a voxel, as Open3D
/// places it) and voxel edge. A chunked run (machscan.dask) builds it from the whole cloud's
/// bounds and keys each chunk's points with it, so its voxels are the in-memory call's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoxelFrame {
    pub origin: [f64; 3],
    pub voxel: f64,
}

impl VoxelFrame {
    /// The grid over the bounds `lo`, `hi`; refused, naming `voxel_size`, when it would need
    /// more voxels per axis than a key holds.
    pub fn new(lo: [f64; 3], hi: [f64; 3], voxel: f64) -> Result<Self> {
        crate::error::check_positive("voxel_size", voxel, "mm")?;
        let origin = lo.map(|l| l - 0.5 * voxel);
        let extent = (0..3).map(|k| ((hi[k] - origin[k]) / voxel).floor() + 1.0).fold(1.0, f64::max);
        if !(extent < (1u64 << KEY_BITS) as f64) {
            return Err(Error::invalid(
                "voxel_size",
                format!(
                    "{voxel} mm over a cloud {:.6} mm across makes more than 2^21 voxels per axis",
                    (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max)
                ),
            ));
        }
        Ok(VoxelFrame { origin, voxel })
    }

    /// The voxel (i, j, k) of a point within the bounds: ⌊(p − origin) / voxel⌋, Open3D's
    /// arithmetic.
    pub fn index(&self, p: &[f64; 3]) -> [u64; 3] {
        [0, 1, 2].map(|a| ((p[a] - self.origin[a]) / self.voxel).floor() as u64)
    }

    /// The voxel's key: its three indices packed, i in the high bits.
    pub fn key(&self, p: &[f64; 3]) -> u64 {
        let [i, j, k] = self.index(p);
        (i << (2 * KEY_BITS)) | (j << KEY_BITS) | k
    }
}

pub fn voxel_downsample(points: &[[f64; 3]], voxel: f64) -> Result<VoxelGrid> {
    crate::error::check_positive("voxel_size", voxel, "mm")?;
    check_points(points)?;
    if points.is_empty() {
        return Ok(VoxelGrid { centroids: Vec::new(), voxel_of_point: Vec::new() });
    }
    if points.len() >= u32::MAX as usize {
        return Err(Error::invalid("points", "more than 2^32 − 1 points"));
    }
    let (lo, hi) = crate::geom::bounds(points);
    let grid = VoxelFrame::new(lo, hi, voxel)?;
    let keys: Vec<u64> = points.par_iter().map(|p| grid.key(p)).collect();
    let mut map: HashMap<u64, u32, BuildHasherDefault<KeyHasher>> = HashMap::default();
    let mut voxel_of_point = Vec::with_capacity(points.len());
    let mut sums: Vec<([f64; 3], u32)> = Vec::new();
    for (p, key) in points.iter().zip(&keys) {
        let id = *map.entry(*key).or_insert_with(|| {
            sums.push(([0.0; 3], 0));
            (sums.len() - 1) as u32
        });
        let s = &mut sums[id as usize];
        // Summed in point order, as Open3D accumulates: bit-identical centroids.
        s.0[0] += p[0];
        s.0[1] += p[1];
        s.0[2] += p[2];
        s.1 += 1;
        voxel_of_point.push(id);
    }
    let centroids = sums.into_iter().map(|(s, n)| [s[0] / n as f64, s[1] / n as f64, s[2] / n as f64]).collect();
    Ok(VoxelGrid { centroids, voxel_of_point })
}

/// Kept indices, ascending.
pub fn remove_statistical_outliers(points: &[[f64; 3]], k: usize, std_ratio: f64) -> Result<Vec<usize>> {
    check_points(points)?;
    check_k("k", k, 1, points.len(), Counting::WithSelf)?;
    if !(std_ratio.is_finite() && std_ratio >= 0.0) {
        return Err(Error::invalid("std_ratio", format!("must be >= 0, got {std_ratio}")));
    }
    let n = points.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    // Summed nearest first, as Open3D: bit-identical means.
    let avg: Vec<f64> = CloudNeighbors::new(points)?
        .map_knn(k, None, |_, nn| nn.iter().map(|n| n.dist2.sqrt()).sum::<f64>() / nn.len() as f64);
    // Sequential in point order, as Open3D sums.
    let valid = n as f64;
    let mut total = 0.0;
    for &a in &avg {
        if a > 0.0 {
            total += a;
        }
    }
    let mean = total / valid;
    let mut sq = 0.0;
    for &a in &avg {
        if a > 0.0 {
            sq += (a - mean) * (a - mean);
        }
    }
    let std = (sq / (valid - 1.0)).sqrt();
    let threshold = mean + std_ratio * std;
    Ok((0..n).filter(|&i| avg[i] > 0.0 && avg[i] < threshold).collect())
}

/// Kept indices, ascending: points with more than `min_neighbors` points strictly closer than
/// `radius` (the point itself counted).
pub fn remove_radius_outliers(points: &[[f64; 3]], radius: f64, min_neighbors: usize) -> Result<Vec<usize>> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(Error::invalid("radius", format!("must be a positive distance in mm, got {radius}")));
    }
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let counts = CloudNeighbors::new(points)?.count_within(radius);
    Ok((0..points.len()).filter(|&i| counts[i] > min_neighbors).collect())
}

/// Duplicate-point removal (paper 004): in point order, each point not yet removed removes every
/// other point within `tolerance`; a removed point never removes others, so no chain of
/// deletions opens a hole. Returns the kept indices, ascending.
pub fn remove_duplicates(points: &[[f64; 3]], tolerance: f64) -> Result<Vec<usize>> {
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Error::invalid("tolerance", format!("must be a positive distance in mm, got {tolerance}")));
    }
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let index = PointIndex::new(points)?;
    let mut removed = vec![false; points.len()];
    for i in 0..points.len() {
        if removed[i] {
            continue;
        }
        index.for_each_within(&points[i], tolerance, |j| {
            if j != i {
                removed[j] = true;
            }
        });
    }
    Ok((0..points.len()).filter(|&i| !removed[i]).collect())
}

/// `count` points drawn without replacement, reproducibly from `seed`; ascending indices.
pub fn random_downsample(n: usize, count: usize, seed: u64) -> Vec<usize> {
    let count = count.min(n);
    // Partial Fisher–Yates with splitmix64: no RNG crate for one shuffle.
    let mut idx: Vec<usize> = (0..n).collect();
    let mut s = seed;
    let mut next = || {
        s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    for i in 0..count {
        let j = i + (next() % (n - i) as u64) as usize;
        idx.swap(i, j);
    }
    idx.truncate(count);
    idx.sort_unstable();
    idx
}

/// Every `every`-th point from the first: 0, k, 2k, …
pub fn uniform_downsample(n: usize, every: usize) -> Result<Vec<usize>> {
    if every == 0 {
        return Err(Error::invalid("every_k", "must be at least 1"));
    }
    Ok((0..n).step_by(every).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_grid_far_from_the_origin_keeps_precision() {
        // 3 m from the origin, 10 µm voxels.
        let pts: Vec<[f64; 3]> = (0..100).map(|i| [3000.0 + i as f64 * 0.004, -2500.0, 1200.0]).collect();
        let g = voxel_downsample(&pts, 0.01).unwrap();
        assert_eq!(g.centroids.len(), 41);
        let first = g.centroids[0];
        assert!((first[0] - 3000.002).abs() < 1e-9, "{first:?}");
    }

    #[test]
    fn duplicates_do_not_chain() {
        // A chain of points 0.8 apart with tolerance 1: removing by chains would keep one.
        let pts: Vec<[f64; 3]> = (0..10).map(|i| [i as f64 * 0.8, 0.0, 0.0]).collect();
        assert_eq!(remove_duplicates(&pts, 1.0).unwrap(), vec![0, 2, 4, 6, 8]);
    }

    #[test]
    fn random_is_reproducible_and_without_replacement() {
        let a = random_downsample(1000, 100, 7);
        assert_eq!(a, random_downsample(1000, 100, 7));
        assert_ne!(a, random_downsample(1000, 100, 8));
        let mut d = a.clone();
        d.dedup();
        assert_eq!(d.len(), 100);
    }
}
