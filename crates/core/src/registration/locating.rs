//! Locating-region selection (SPEC R4, paper 003 §2.2): a part is located more accurately on
//! its flat regions, so the probe points are drawn from the flattest share of the surface —
//! by the U-direction line curvature of a gridded scan, or the surface variation of a cloud —
//! at random, reproducibly from a seed (the paper: 160 of 20 000 points).
use crate::cloud::{estimate_normals, Neighborhood};
use crate::error::{check_finite_points, Error, Result};
use nalgebra::{Matrix6, Vector3, Vector6};
use rayon::prelude::*;

/// Curvature along the U direction of a gridded scan `(nu, nv)` (point `(i, j)` at
/// `points[i·nv + j]`, U along i): the curvature of the circle through each point and its two
/// U neighbors (Menger: `4·area / (|a||b||c|)`, exactly 1/R on a circle of radius R); the ends
/// of each line take their neighbor's value. Needs nu ≥ 3.
pub fn line_curvature(points: &[[f64; 3]], nu: usize, nv: usize) -> Result<Vec<f64>> {
    check_finite_points("points", points)?;
    if nu < 3 || points.len() != nu * nv {
        return Err(Error::shape("points", "(nu, nv, 3) with nu >= 3 points along U", format!("({nu}, {nv}, 3)")));
    }
    let at = |i: usize, j: usize| points[i * nv + j];
    let mut out = vec![0.0; points.len()];
    for j in 0..nv {
        for i in 1..nu - 1 {
            let (p, q, r) = (at(i - 1, j), at(i, j), at(i + 1, j));
            let d = |a: [f64; 3], b: [f64; 3]| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let (a, b, c) = (d(p, q), d(q, r), d(p, r));
            let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
            let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            let den = norm(a) * norm(b) * norm(c);
            // 2·|a × b| is four times the triangle's area; coincident points have no curvature.
            out[i * nv + j] = if den > 0.0 { 2.0 * norm(cross) / den } else { 0.0 };
        }
        out[j] = out[nv + j];
        out[(nu - 1) * nv + j] = out[(nu - 2) * nv + j];
    }
    Ok(out)
}

/// SplitMix64 (Steele et al. 2014): a small, fixed generator, so that a seed draws the same
/// points on every platform and version.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (n ≥ 1; Lemire's multiply-shift with rejection: no modulo bias).
    fn below(&mut self, n: u64) -> u64 {
        loop {
            let m = (self.next() as u128) * (n as u128);
            if (m as u64) >= (n.wrapping_neg() % n) {
                return (m >> 64) as u64;
            }
        }
    }
}

/// `m` indices drawn at random (seeded) from the `keep` share of the points with the lowest
/// `curvature` (ties by index), returned ascending.
pub fn locating_points(curvature: &[f64], m: usize, keep: f64, seed: u64) -> Result<Vec<usize>> {
    let mut order = flattest(curvature, m, keep)?;
    let flat = order.len();
    // A partial Fisher–Yates shuffle: the first m are a uniform sample without replacement.
    let mut rng = SplitMix(seed);
    for i in 0..m {
        let j = i + rng.below((flat - i) as u64) as usize;
        order.swap(i, j);
    }
    order.truncate(m);
    order.sort_unstable();
    Ok(order)
}

/// The flattest `keep` share of the points, flattest first (ties by index), checked to hold `m`.
fn flattest(curvature: &[f64], m: usize, keep: f64) -> Result<Vec<usize>> {
    if let Some(i) = curvature.iter().position(|c| !c.is_finite()) {
        return Err(Error::invalid("curvature", format!("must be finite, found {} at index {i}", curvature[i])));
    }
    if !(keep > 0.0 && keep <= 1.0) {
        return Err(Error::invalid("keep", format!("must be a share in (0, 1], got {keep}")));
    }
    let n = curvature.len();
    let flat = ((keep * n as f64).ceil() as usize).min(n);
    if m > flat {
        return Err(Error::invalid(
            "m",
            format!("{m} points asked, but the flattest {:.0} % of the surface holds only {flat}", 100.0 * keep),
        ));
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_unstable_by(|&a, &b| curvature[a].total_cmp(&curvature[b]).then(a.cmp(&b)));
    order.truncate(flat);
    Ok(order)
}

/// `m` probe points from the flattest `keep` share that fix the part's pose best where it
/// matters: the pose error that probe noise leaves, measured along the normals over the whole
/// model, is smallest (an I-optimal design for the linearised fit of `probe_fit`).
///
/// A random draw (the paper's) wastes points: the weakest-fixed motion of the pose — on a
/// blade, sliding and turning along its gentle faces — then sets the error at the edges, where
/// the normals turn into that motion. Chosen greedily: each next point is the candidate that
/// lowers `trace((JᵀJ)⁻¹ W)` most (`W` the normals' second moments over the model, `J` the
/// chosen points' rows), kept at least a spacing away from the points already chosen, so that
/// the pattern stays spread over the region and one flaw of the part cannot dominate, and a
/// spacing away from the model's open edges (a design pushes points to the extremes, and a
/// probe sent to an edge of a misplaced part misses it).
pub fn probe_pattern(
    points: &[[f64; 3]],
    normals: &[[f64; 3]],
    curvature: &[f64],
    m: usize,
    keep: f64,
) -> Result<Vec<usize>> {
    check_finite_points("points", points)?;
    super::check_normals("normals", normals, points.len())?;
    if curvature.len() != points.len() {
        return Err(Error::shape("curvature", format!("({},)", points.len()), format!("({},)", curvature.len())));
    }
    if m < 6 {
        return Err(Error::invalid("m", format!("a pose needs at least 6 probe points, got {m}")));
    }
    let candidates = flattest(curvature, m, keep)?;
    let n = points.len() as f64;
    let (centre, scale) = super::spread(points);
    // The row of a point in the linearised fit: a small motion (ω·scale, τ) moves it along its
    // normal by g·(ω·scale, τ).
    let row = |i: usize| {
        let v = Vector3::from(normals[i]).normalize();
        let r = (Vector3::from(points[i]) - centre).cross(&v) / scale;
        Vector6::new(r[0], r[1], r[2], v[0], v[1], v[2])
    };
    let weight = (0..points.len()).fold(Matrix6::zeros(), |w, i| {
        let g = row(i);
        w + g * g.transpose() / n
    });
    let rows: Vec<Vector6<f64>> = candidates.iter().map(|&i| row(i)).collect();
    // The spacing: half the radius of a disc of the candidates' area over m, the area from the
    // median distance between neighbouring candidates.
    let pts: Vec<[f64; 3]> = candidates.iter().map(|&i| points[i]).collect();
    let index = crate::spatial::PointIndex::new(&pts)?;
    let mut gaps: Vec<f64> = pts.iter().map(|p| index.knn(p, 2).last().map_or(0.0, |&(_, d2)| d2.sqrt())).collect();
    gaps.sort_unstable_by(f64::total_cmp);
    let gap = gaps[gaps.len() / 2];
    let mut spacing = 0.5 * gap * (pts.len() as f64 / (std::f64::consts::PI * m as f64)).sqrt();
    let mut inside: Vec<bool> = near_open_edge(points, &pts, spacing)?.iter().map(|&e| !e).collect();
    if inside.iter().filter(|&&a| a).count() < m {
        inside = vec![true; pts.len()];
    }
    let mut alive = inside.clone();
    // A start of `A = ε I` (ε far below any point's share) makes the first picks the best single
    // points; every later pick is measured against the ones before.
    let mut inverse = Matrix6::identity() / (1e-9 * weight.trace().max(1e-300));
    let mut chosen: Vec<usize> = Vec::with_capacity(m);
    while chosen.len() < m {
        let b = inverse * weight * inverse;
        let best = (0..pts.len())
            .into_par_iter()
            .filter(|&c| alive[c])
            .map(|c| {
                let g = &rows[c];
                (c, (g.transpose() * b * g)[0] / (1.0 + (g.transpose() * inverse * g)[0]))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
        let Some((c, _)) = best else {
            // The region is full at this spacing: halve it.
            spacing *= 0.5;
            for ((a, p), &inside) in alive.iter_mut().zip(&pts).zip(&inside) {
                *a = inside && chosen.iter().all(|&k| dist2(p, &pts[k]) > spacing * spacing);
            }
            continue;
        };
        chosen.push(c);
        let g = rows[c];
        let ag = inverse * g;
        inverse -= ag * ag.transpose() / (1.0 + g.dot(&ag));
        for (a, p) in alive.iter_mut().zip(&pts) {
            *a &= dist2(p, &pts[c]) > spacing * spacing;
        }
    }
    let mut out: Vec<usize> = chosen.into_iter().map(|c| candidates[c]).collect();
    out.sort_unstable();
    Ok(out)
}

/// Neighbours of the open-edge test.
const EDGE_NEIGHBORS: usize = 12;

/// Which of `candidates` lie within `margin` of an open edge of the model `points`. A point is
/// on an open edge when its nearest neighbours lie to one side of it: their centroid is off the
/// point by more than a quarter of their mean distance (a third on a half disc; inside a
/// surface it is off by about the
/// local curvature times the squared distance, far less).
fn near_open_edge(points: &[[f64; 3]], candidates: &[[f64; 3]], margin: f64) -> Result<Vec<bool>> {
    let k = EDGE_NEIGHBORS.min(points.len());
    let index = crate::spatial::PointIndex::new(points)?;
    let edge: Vec<[f64; 3]> = points
        .par_iter()
        .filter(|p| {
            let near = index.knn(p, k);
            let c = near.iter().fold(Vector3::zeros(), |a, &(i, _)| a + Vector3::from(points[i])) / k as f64;
            let mean = near.iter().map(|&(_, d2)| d2.sqrt()).sum::<f64>() / (k - 1).max(1) as f64;
            (c - Vector3::from(**p)).norm() > mean / 4.0
        })
        .copied()
        .collect();
    if edge.is_empty() {
        return Ok(vec![false; candidates.len()]);
    }
    let edges = crate::spatial::PointIndex::new(&edge)?;
    Ok(candidates.par_iter().map(|c| edges.nearest(c).1 < margin).collect())
}

fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum()
}

/// How probe points are chosen from the flattest share.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProbePattern {
    /// At random, from a seed (the paper): [`locating_points`].
    Random,
    /// Those that fix the pose best along the model's normals: [`probe_pattern`].
    Optimal,
}

impl ProbePattern {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "random" => Ok(ProbePattern::Random),
            "optimal" => Ok(ProbePattern::Optimal),
            _ => Err(Error::invalid("pattern", format!("expected 'random' or 'optimal', got {name:?}"))),
        }
    }

    /// Chooses `m` of `points` by `curvature` (one value per point, lower is flatter).
    fn choose(
        self,
        points: &[[f64; 3]],
        normals: Option<&[[f64; 3]]>,
        curvature: &[f64],
        m: usize,
        keep: f64,
        seed: u64,
    ) -> Result<Vec<usize>> {
        match (self, normals) {
            (ProbePattern::Random, _) => locating_points(curvature, m, keep, seed),
            (ProbePattern::Optimal, Some(n)) => probe_pattern(points, n, curvature, m, keep),
            (ProbePattern::Optimal, None) => Err(Error::invalid(
                "normals",
                "pattern 'optimal' weighs the points by their normals: give the model normals",
            )),
        }
    }
}

/// Probe points on the flattest `keep` share of a cloud: the surface variation over each
/// point's `k` nearest points is its flatness; `normals` (one per point) are needed by
/// [`ProbePattern::Optimal`] only.
pub fn cloud_locating_points(
    points: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
    m: usize,
    keep: f64,
    k: usize,
    seed: u64,
    pattern: ProbePattern,
) -> Result<Vec<usize>> {
    let (_, variation, _) = estimate_normals(points, Neighborhood::Knn(k))?;
    pattern.choose(points, normals, &variation, m, keep, seed)
}

/// Probe points on the flattest `keep` share of a gridded scan `(nu, nv)` (as
/// [`line_curvature`] takes it): the U-direction line curvature is its flatness.
#[allow(clippy::too_many_arguments)]
pub fn grid_locating_points(
    points: &[[f64; 3]],
    nu: usize,
    nv: usize,
    normals: Option<&[[f64; 3]]>,
    m: usize,
    keep: f64,
    seed: u64,
    pattern: ProbePattern,
) -> Result<Vec<usize>> {
    pattern.choose(points, normals, &line_curvature(points, nu, nv)?, m, keep, seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_curvature_is_one_over_the_radius_on_a_cylinder() {
        let (nu, nv, r) = (50, 4, 12.5);
        let mut pts = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let t = 0.02 * i as f64 + 0.001 * (i * i) as f64;
                pts.push([r * t.cos(), j as f64, r * t.sin()]);
            }
        }
        let c = line_curvature(&pts, nu, nv).unwrap();
        assert!(c.iter().all(|&k| (k - 1.0 / r).abs() < 1e-12), "{:?}", &c[..4]);
    }

    #[test]
    fn points_come_from_the_flattest_share_reproducibly() {
        let curvature: Vec<f64> = (0..1000).map(|i| if i % 3 == 0 { 0.001 } else { 0.5 }).collect();
        let a = locating_points(&curvature, 160, 0.3, 7).unwrap();
        assert_eq!(a.len(), 160);
        assert!(a.iter().all(|&i| i % 3 == 0) && a.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(a, locating_points(&curvature, 160, 0.3, 7).unwrap());
        assert_ne!(a, locating_points(&curvature, 160, 0.3, 8).unwrap());
        assert!(locating_points(&curvature, 400, 0.3, 7).unwrap_err().to_string().contains("m:"));
    }
}
