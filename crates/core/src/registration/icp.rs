//! Iterative closest point (SPEC R2; paper 003 §3.2, paper 004 eq 1) with Open3D's
//! definitions and stop rule, so that a user can switch between the two without surprises:
//!
//! - a correspondence is a source point's nearest target point closer than `max_distance`;
//! - fitness = correspondences / source points, rmse = RMS distance over the correspondences,
//!   both evaluated at the transform returned (never one iteration stale);
//! - each iteration estimates an update from the correspondences, applies it, and finds the
//!   correspondences again; it stops after `max_iterations`, or when fitness and rmse changed by
//!   less than `relative_fitness` and `relative_rmse` (absolute changes, as Open3D compares
//!   them; both 0 runs exactly `max_iterations`), or — paper 003 eq 10 — when the mean squared
//!   distance falls below `mse_threshold`.
//!
//! Unlike the peers: no correspondence in reach is reported as fitness 0 and not converged (no
//! NaN); a start that is already perfect converges in one iteration; results do not depend on
//! the thread count (correspondences are searched in parallel, every sum runs in source order).
use crate::cloud::{estimate_normals, Neighborhood};
use crate::error::{check_finite_points, Error, Result};
use crate::geom::{morton_order, rot_x, rot_y, rot_z, transform_point};
use crate::spatial::PointIndex;
use nalgebra::{Matrix3, Matrix4, Matrix6, Vector3, Vector6};
use rayon::prelude::*;

/// Changes of the rmse below this share of `max_distance` are rounding.
pub(super) const ROUNDING: f64 = 1e-9;

/// Neighbours of the target normals point-to-plane estimates when none are given (Open3D's
/// usual `KDTreeSearchParamKNN`): enough for a stable plane through scanner noise.
pub const NORMAL_NEIGHBORS: usize = 20;

/// What each iteration minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IcpMethod {
    /// Σ |R s + t − q|²: Kabsch/Umeyama in closed form, with the reflection guard.
    PointToPoint,
    /// Σ ((R s + t − q)·n_q)², linearised in the small rotation (Chen & Medioni 1992): slides
    /// along flat regions, converges in fewer iterations on smooth parts; needs target normals.
    PointToPlane,
}

impl IcpMethod {
    pub const NAMES: [&'static str; 2] = ["point_to_point", "point_to_plane"];

    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "point_to_point" => Ok(IcpMethod::PointToPoint),
            "point_to_plane" => Ok(IcpMethod::PointToPlane),
            other => Err(Error::invalid(
                "method",
                format!("expected \"point_to_point\" or \"point_to_plane\", got {other:?}"),
            )),
        }
    }

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// The robust loss of the residuals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RobustKernel {
    /// Weight 1 up to k, k/|r| beyond: bounded influence, every point still counts.
    Huber,
    /// Weight (1 − (r/k)²)² up to k, 0 beyond: gross outliers have no influence.
    Tukey,
}

impl RobustKernel {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "huber" => Ok(RobustKernel::Huber),
            "tukey" => Ok(RobustKernel::Tukey),
            other => Err(Error::invalid("robust", format!("expected \"huber\", \"tukey\" or None, got {other:?}"))),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            RobustKernel::Huber => "huber",
            RobustKernel::Tukey => "tukey",
        }
    }

    /// The threshold in units of the residuals' σ that gives 95 % efficiency on Gaussian noise.
    fn tuning(self) -> f64 {
        match self {
            RobustKernel::Huber => 1.345,
            RobustKernel::Tukey => 4.685,
        }
    }

    fn weight(self, r: f64, k: f64) -> f64 {
        let a = r.abs();
        match self {
            RobustKernel::Huber => {
                if a <= k {
                    1.0
                } else {
                    k / a
                }
            }
            RobustKernel::Tukey => {
                if a < k {
                    let u = 1.0 - (a / k) * (a / k);
                    u * u
                } else {
                    0.0
                }
            }
        }
    }
}

/// Robust weights: the kernel and its threshold `scale` (mm). `None` takes it from the
/// residuals of each iteration: `tuning · 1.4826 · median |r|` (the MAD about zero: at the fit
/// the residuals are centred on zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Robust {
    pub kernel: RobustKernel,
    pub scale: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IcpOptions {
    /// Largest distance of a correspondence, mm.
    pub max_distance: f64,
    pub method: IcpMethod,
    pub max_iterations: usize,
    /// Stop when fitness changed by less than this in an iteration (and rmse too).
    pub relative_fitness: f64,
    /// Stop when rmse changed by less than this in an iteration (and fitness too), mm.
    pub relative_rmse: f64,
    /// Paper 003 eq 10: stop when the mean squared correspondence distance is below this, mm².
    pub mse_threshold: Option<f64>,
    pub robust: Option<Robust>,
    /// Share of the correspondences, the farthest, left out of each estimate (0 ≤ trim < 1).
    pub trim: f64,
}

impl IcpOptions {
    /// Open3D's defaults for the given correspondence distance: point to point, 30 iterations,
    /// both thresholds 1e-6, no robust weights, no trimming.
    pub fn new(max_distance: f64) -> Self {
        IcpOptions {
            max_distance,
            method: IcpMethod::PointToPoint,
            max_iterations: 30,
            relative_fitness: 1e-6,
            relative_rmse: 1e-6,
            mse_threshold: None,
            robust: None,
            trim: 0.0,
        }
    }

    fn validate(&self) -> Result<()> {
        if !(self.max_distance.is_finite() && self.max_distance > 0.0) {
            return Err(Error::invalid(
                "max_distance",
                format!("must be a positive distance, got {}", self.max_distance),
            ));
        }
        for (name, v) in [("relative_fitness", self.relative_fitness), ("relative_rmse", self.relative_rmse)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(name, format!("must be >= 0, got {v}")));
            }
        }
        if let Some(t) = self.mse_threshold {
            if !(t.is_finite() && t >= 0.0) {
                return Err(Error::invalid("mse_threshold", format!("must be >= 0 mm², got {t}")));
            }
        }
        if !(self.trim >= 0.0 && self.trim < 1.0) {
            return Err(Error::invalid("trim", format!("must be a share in [0, 1), got {}", self.trim)));
        }
        if let Some(Robust { scale: Some(k), .. }) = self.robust {
            if !(k.is_finite() && k > 0.0) {
                return Err(Error::invalid("robust_scale", format!("must be a positive distance, got {k}")));
            }
        }
        Ok(())
    }
}

/// Fitness and rmse after one iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IcpStep {
    pub fitness: f64,
    pub rmse: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct IcpResult {
    /// The transform applied to the source (including `init`).
    pub transformation: Matrix4<f64>,
    /// Correspondences / source points, at `transformation`.
    pub fitness: f64,
    /// RMS correspondence distance at `transformation`, mm (0 with no correspondence).
    pub rmse: f64,
    pub correspondences: usize,
    pub iterations: usize,
    /// A stop test held (the changes of fitness and rmse, or the mean squared distance); false
    /// when the iterations ran out first or no correspondence was in reach.
    pub converged: bool,
    /// Fitness and rmse after each iteration.
    pub history: Vec<IcpStep>,
}

/// A source point (index) and its target point (index), `d2` apart.
#[derive(Debug, Clone, Copy)]
struct Pair {
    source: u32,
    target: u32,
    d2: f64,
}

fn correspondences(index: &PointIndex, moved: &[[f64; 3]], max_d2: f64) -> Vec<Pair> {
    moved
        .par_iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let (j, d2) = index.nearest_squared(p);
            (d2 < max_d2).then_some(Pair { source: i as u32, target: j as u32, d2 })
        })
        .collect()
}

/// Σ f(pair, weight) over the pairs of positive weight, in fixed chunks summed in order:
/// parallel, and the same result whatever the thread count.
fn chunked_sum<T, F>(pairs: &[Pair], w: &[f64], zero: T, f: F) -> T
where
    T: Copy + Send + Sync + std::ops::Add<Output = T>,
    F: Fn(&Pair, f64) -> T + Sync,
{
    const CHUNK: usize = 4096;
    let parts: Vec<T> = pairs
        .par_chunks(CHUNK)
        .zip(w.par_chunks(CHUNK))
        .map(|(p, w)| p.iter().zip(w).filter(|(_, &wi)| wi > 0.0).fold(zero, |acc, (pi, &wi)| acc + f(pi, wi)))
        .collect();
    parts.into_iter().fold(zero, |a, b| a + b)
}

/// (fitness, rmse) of the correspondences of `n` source points.
fn metrics(pairs: &[Pair], n: usize) -> (f64, f64) {
    if pairs.is_empty() {
        return (0.0, 0.0);
    }
    let sum: f64 = pairs.iter().map(|p| p.d2).sum();
    (pairs.len() as f64 / n as f64, (sum / pairs.len() as f64).sqrt())
}

/// Iterative closest point from `source` onto `target`, starting at `init`. Point-to-plane
/// without `target_normals` estimates them over the [`NORMAL_NEIGHBORS`] nearest target points
/// (unoriented: the residual's sign does not matter); a target of that many points or fewer is
/// refused, naming `target_normals`.
pub fn icp(
    source: &[[f64; 3]],
    target: &[[f64; 3]],
    target_normals: Option<&[[f64; 3]]>,
    init: &Matrix4<f64>,
    o: &IcpOptions,
) -> Result<IcpResult> {
    o.validate()?;
    check_finite_points("source", source)?;
    check_finite_points("target", target)?;
    if source.is_empty() {
        return Err(Error::invalid("source", "must hold at least one point"));
    }
    if target.is_empty() {
        return Err(Error::invalid("target", "must hold at least one point"));
    }
    check_init(init)?;
    let estimated;
    let normals = match (o.method, target_normals) {
        (_, Some(n)) if n.len() != target.len() => {
            return Err(Error::shape(
                "target_normals",
                format!("({}, 3): one per target point", target.len()),
                format!("({}, 3)", n.len()),
            ))
        }
        (_, Some(n)) => {
            check_finite_points("target_normals", n)?;
            Some(n)
        }
        (IcpMethod::PointToPlane, None) => {
            // A target too small for the estimate is refused rather than estimated over fewer
            // neighbours: planes through a handful of points would steer the fit silently.
            if target.len() <= NORMAL_NEIGHBORS {
                return Err(Error::invalid(
                    "target_normals",
                    format!(
                        "point_to_plane estimates them over {NORMAL_NEIGHBORS} neighbours, but the target has {} \
                         points: give the target normals",
                        target.len()
                    ),
                ));
            }
            estimated = estimate_normals(target, Neighborhood::Knn(NORMAL_NEIGHBORS))?.0;
            Some(&estimated[..])
        }
        (IcpMethod::PointToPoint, None) => None,
    };
    let index = PointIndex::new(target)?;
    let max_d2 = o.max_distance * o.max_distance;
    let mut transformation = *init;
    // The source in Morton (Z-curve) order: consecutive queries then walk the same branches of
    // the tree and stay in cache whatever order the cloud came in; pairs refer to positions in
    // this order, and every sum runs in it.
    let order = morton_order(source);
    let mut moved: Vec<[f64; 3]> = order.par_iter().map(|&i| transform_point(init, source[i as usize])).collect();
    let mut pairs = correspondences(&index, &moved, max_d2);
    let (mut fitness, mut rmse) = metrics(&pairs, source.len());
    let below_mse = |rmse: f64, pairs: &[Pair]| !pairs.is_empty() && o.mse_threshold.is_some_and(|t| rmse * rmse < t);
    let mut converged = below_mse(rmse, &pairs);
    let mut history = Vec::new();
    let mut iterations = 0;
    while iterations < o.max_iterations && !converged && !pairs.is_empty() {
        let weights = weights(&moved, target, normals, &pairs, o);
        let update = match (o.method, normals) {
            (IcpMethod::PointToPlane, Some(n)) => point_to_plane(&moved, target, n, &pairs, &weights),
            _ => point_to_point(&moved, target, &pairs, &weights),
        };
        // No update (fewer than three usable pairs, or a degenerate system): nothing more to do.
        let Some(update) = update else { break };
        transformation = update * transformation;
        moved.par_iter_mut().for_each(|p| *p = transform_point(&update, *p));
        pairs = correspondences(&index, &moved, max_d2);
        let (f, r) = metrics(&pairs, source.len());
        iterations += 1;
        history.push(IcpStep { fitness: f, rmse: r });
        let (df, dr) = ((f - fitness).abs(), (r - rmse).abs());
        (fitness, rmse) = (f, r);
        if pairs.is_empty() {
            break;
        }
        if df < o.relative_fitness && dr < o.relative_rmse || below_mse(rmse, &pairs) {
            converged = true;
        } else if iterations == o.max_iterations {
            // Run out, or run exactly as asked with both thresholds 0: converged when the last
            // iteration changed nothing beyond them or beyond rounding (the rmse of a perfect
            // fit wanders at 1e-15 of the part's size).
            converged = df <= o.relative_fitness && dr <= o.relative_rmse.max(ROUNDING * o.max_distance);
        }
    }
    Ok(IcpResult { transformation, fitness, rmse, correspondences: pairs.len(), iterations, converged, history })
}

/// The weight of each pair in the next estimate: 0 for the trimmed share, the robust kernel's
/// weight of its residual, 1 otherwise.
fn weights(
    moved: &[[f64; 3]],
    target: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
    pairs: &[Pair],
    o: &IcpOptions,
) -> Vec<f64> {
    let mut w = vec![1.0; pairs.len()];
    if o.trim > 0.0 {
        let keep = ((1.0 - o.trim) * pairs.len() as f64).ceil() as usize;
        if keep < pairs.len() {
            let mut d2: Vec<f64> = pairs.iter().map(|p| p.d2).collect();
            let cut = *d2.select_nth_unstable_by(keep.max(1) - 1, f64::total_cmp).1;
            // Pairs beyond the cut are dropped; ties at the cut are all kept (order-free).
            for (wi, p) in w.iter_mut().zip(pairs) {
                if p.d2 > cut {
                    *wi = 0.0;
                }
            }
        }
    }
    let Some(robust) = o.robust else { return w };
    let residual = |p: &Pair| match (o.method, normals) {
        (IcpMethod::PointToPlane, Some(n)) => {
            let (s, q, nq) = (
                Vector3::from(moved[p.source as usize]),
                Vector3::from(target[p.target as usize]),
                Vector3::from(n[p.target as usize]),
            );
            (s - q).dot(&nq)
        }
        _ => p.d2.sqrt(),
    };
    let r: Vec<f64> = pairs.iter().map(residual).collect();
    let k = match robust.scale {
        Some(k) => k,
        None => {
            let mut a: Vec<f64> = r.iter().zip(&w).filter(|(_, &wi)| wi > 0.0).map(|(ri, _)| ri.abs()).collect();
            let mid = a.len() / 2;
            let med = *a.select_nth_unstable_by(mid, f64::total_cmp).1;
            // All residuals zero (a perfect fit): any positive threshold gives weight 1.
            (robust.kernel.tuning() * 1.4826 * med).max(f64::MIN_POSITIVE)
        }
    };
    for (wi, ri) in w.iter_mut().zip(&r) {
        if *wi > 0.0 {
            *wi = robust.kernel.weight(*ri, k);
        }
    }
    w
}

/// The weighted least-squares rigid update taking the moved source points onto their targets
/// (Umeyama 1991 without scale; the reflection guard flips the axis of the smallest singular
/// value). None with fewer than three weighted pairs or collinear ones.
fn point_to_point(moved: &[[f64; 3]], target: &[[f64; 3]], pairs: &[Pair], w: &[f64]) -> Option<Matrix4<f64>> {
    let used = w.iter().filter(|&&wi| wi > 0.0).count();
    let Sums((sw, ms, mt)) = chunked_sum(pairs, w, Sums((0.0, Vector3::zeros(), Vector3::zeros())), |p, wi| {
        Sums((wi, wi * Vector3::from(moved[p.source as usize]), wi * Vector3::from(target[p.target as usize])))
    });
    if used < 3 || !(sw > 0.0) {
        return None;
    }
    let (ms, mt) = (ms / sw, mt / sw);
    let h = chunked_sum(pairs, w, Matrix3::zeros(), |p, wi| {
        wi * (Vector3::from(moved[p.source as usize]) - ms)
            * (Vector3::from(target[p.target as usize]) - mt).transpose()
    });
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let sv = svd.singular_values;
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| sv[b].total_cmp(&sv[a]));
    if !(sv[order[1]] > 1e-12 * sv[order[0]]) {
        return None;
    }
    let v = v_t.transpose();
    let mut d = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        d[(order[2], order[2])] = -1.0;
    }
    let rotation = v * d * u.transpose();
    Some(rigid(rotation, mt - rotation * ms))
}

/// The point-to-plane update: the 6 × 6 normal equations of `r = (s − q)·n` linearised in
/// the rotation angles (α, β, γ) about x, y, z, solved by Cholesky; the update turns by
/// `Rz(γ) Ry(β) Rx(α)` (Open3D's convention) and moves by the solved translation.
fn point_to_plane(
    moved: &[[f64; 3]],
    target: &[[f64; 3]],
    normals: &[[f64; 3]],
    pairs: &[Pair],
    w: &[f64],
) -> Option<Matrix4<f64>> {
    let used = w.iter().filter(|&&wi| wi > 0.0).count();
    if used < 6 {
        return None;
    }
    let Sums((jtj, jtr)) = chunked_sum(pairs, w, Sums((Matrix6::<f64>::zeros(), Vector6::<f64>::zeros())), |p, wi| {
        let (s, q, n) = (
            Vector3::from(moved[p.source as usize]),
            Vector3::from(target[p.target as usize]),
            Vector3::from(normals[p.target as usize]),
        );
        let c = s.cross(&n);
        let j = Vector6::new(c[0], c[1], c[2], n[0], n[1], n[2]);
        let r = (s - q).dot(&n);
        Sums((wi * j * j.transpose(), wi * r * j))
    });
    let x = jtj.cholesky()?.solve(&-jtr);
    if x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let rotation = rot_z(x[2]) * rot_y(x[1]) * rot_x(x[0]);
    Some(rigid(rotation, Vector3::new(x[3], x[4], x[5])))
}

/// A tuple of sums, added element-wise (for [`chunked_sum`]).
#[derive(Clone, Copy)]
struct Sums<T>(T);

impl<A: std::ops::Add<Output = A>, B: std::ops::Add<Output = B>> std::ops::Add for Sums<(A, B)> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Sums((self.0 .0 + o.0 .0, self.0 .1 + o.0 .1))
    }
}

impl<A, B, C> std::ops::Add for Sums<(A, B, C)>
where
    A: std::ops::Add<Output = A>,
    B: std::ops::Add<Output = B>,
    C: std::ops::Add<Output = C>,
{
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Sums((self.0 .0 + o.0 .0, self.0 .1 + o.0 .1, self.0 .2 + o.0 .2))
    }
}

/// A start transform: finite, with last row (0, 0, 0, 1); refused naming `init` otherwise.
pub(super) fn check_init(init: &Matrix4<f64>) -> Result<()> {
    let last_row = [init[(3, 0)], init[(3, 1)], init[(3, 2)], init[(3, 3)]];
    if init.iter().any(|v| !v.is_finite()) || last_row != [0.0, 0.0, 0.0, 1.0] {
        return Err(Error::invalid("init", "must be a finite 4×4 rigid transform with last row (0, 0, 0, 1)"));
    }
    Ok(())
}

pub(super) fn rigid(rotation: Matrix3<f64>, translation: Vector3<f64>) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    t.fixed_view_mut::<3, 3>(0, 0).copy_from(&rotation);
    t.fixed_view_mut::<3, 1>(0, 3).copy_from(&translation);
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mount_rotation;
    use crate::testing::lcg;

    /// A smooth, asymmetric bump surface z = f(x, y) sampled on a jittered grid, with normals.
    fn surface(n: usize, seed: &mut u64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let f = |x: f64, y: f64| {
            3.0 * (-(x - 4.0).powi(2) / 30.0 - (y + 2.0).powi(2) / 50.0).exp() + 0.02 * x * y + 0.05 * x
        };
        let (mut p, mut nrm) = (Vec::new(), Vec::new());
        for i in 0..n {
            for j in 0..n {
                let x = -20.0 + 40.0 * (i as f64 + 0.3 * lcg(seed)) / n as f64;
                let y = -15.0 + 30.0 * (j as f64 + 0.3 * lcg(seed)) / n as f64;
                let h = 1e-6;
                let (fx, fy) = ((f(x + h, y) - f(x - h, y)) / (2.0 * h), (f(x, y + h) - f(x, y - h)) / (2.0 * h));
                let nv = Vector3::new(-fx, -fy, 1.0).normalize();
                p.push([x, y, f(x, y)]);
                nrm.push(nv.into());
            }
        }
        (p, nrm)
    }

    fn pose(a: f64, b: f64, c: f64, t: [f64; 3]) -> Matrix4<f64> {
        rigid(mount_rotation(a, b, c), Vector3::from(t))
    }

    fn pose_error(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
        (a - b).abs().max()
    }

    #[test]
    fn both_methods_recover_a_known_transform_on_noiseless_data() {
        let mut seed = 3;
        let (target, normals) = surface(60, &mut seed);
        // Point to point snaps to the sampling when the offset nears the point spacing (0.5–0.7
        // mm here): its test starts closer.
        let cases = [
            (IcpMethod::PointToPlane, 1e-9, pose(0.02, -0.015, 0.03, [0.4, -0.3, 0.2])),
            (IcpMethod::PointToPoint, 1e-6, pose(0.004, -0.003, 0.005, [0.1, -0.08, 0.05])),
        ];
        for (method, tol, truth) in cases {
            // The source is the target moved by the inverse of the truth: ICP must find the truth.
            let inv = truth.try_inverse().unwrap();
            let source: Vec<[f64; 3]> = target.iter().map(|&p| transform_point(&inv, p)).collect();
            let o = IcpOptions {
                method,
                max_iterations: 200,
                relative_fitness: 0.0,
                relative_rmse: 0.0,
                ..IcpOptions::new(2.0)
            };
            let r = icp(&source, &target, Some(&normals), &Matrix4::identity(), &o).unwrap();
            assert!(
                pose_error(&r.transformation, &truth) < tol,
                "{method:?}: {}",
                pose_error(&r.transformation, &truth)
            );
            assert_eq!(r.fitness, 1.0);
            assert!(r.rmse < tol && r.converged, "{method:?} rmse {} converged {}", r.rmse, r.converged);
            assert_eq!(r.history.len(), r.iterations);
        }
    }

    #[test]
    fn a_perfect_start_converges_at_once_and_no_pair_in_reach_is_not_a_nan() {
        let mut seed = 5;
        let (target, normals) = surface(30, &mut seed);
        let r = icp(&target, &target, Some(&normals), &Matrix4::identity(), &IcpOptions::new(1.0)).unwrap();
        assert!(r.converged && r.iterations == 1 && r.fitness == 1.0 && r.rmse < 1e-12, "{r:?}");
        // Exactly the iterations asked with both thresholds 0; still converged (nothing moved).
        let o = IcpOptions { relative_fitness: 0.0, relative_rmse: 0.0, max_iterations: 4, ..IcpOptions::new(1.0) };
        let r = icp(&target, &target, None, &Matrix4::identity(), &o).unwrap();
        assert!(r.converged && r.iterations == 4, "{r:?}");
        let far = pose(0.0, 0.0, 0.0, [1000.0, 0.0, 0.0]);
        let r = icp(&target, &target, None, &far, &IcpOptions::new(1.0)).unwrap();
        assert!(!r.converged && r.fitness == 0.0 && r.rmse == 0.0 && r.iterations == 0);
        assert_eq!(r.transformation, far);
    }

    #[test]
    fn fitness_and_rmse_are_those_of_the_returned_transform() {
        let mut seed = 7;
        let (target, _) = surface(40, &mut seed);
        let source: Vec<[f64; 3]> =
            target.iter().map(|&p| transform_point(&pose(0.01, 0.02, -0.01, [0.3, 0.1, 0.05]), p)).collect();
        let o = IcpOptions { max_iterations: 3, ..IcpOptions::new(0.5) };
        let r = icp(&source, &target, None, &Matrix4::identity(), &o).unwrap();
        let index = PointIndex::new(&target).unwrap();
        let moved: Vec<[f64; 3]> = source.iter().map(|&p| transform_point(&r.transformation, p)).collect();
        let (f, e) = metrics(&correspondences(&index, &moved, 0.25), source.len());
        assert!((f - r.fitness).abs() < 1e-12 && (e - r.rmse).abs() < 1e-9, "{f} {e} vs {} {}", r.fitness, r.rmse);
        assert_eq!(r.history.last().map(|h| (h.fitness, h.rmse)), Some((r.fitness, r.rmse)));
    }

    #[test]
    fn tukey_weights_recover_the_pose_through_gross_outliers() {
        let mut seed = 11;
        let (target, normals) = surface(60, &mut seed);
        let truth = pose(0.01, -0.01, 0.02, [0.2, -0.1, 0.1]);
        let inv = truth.try_inverse().unwrap();
        // 20 % of the source points lifted 0.5–2 mm off the surface along its normal.
        let source: Vec<[f64; 3]> = target
            .iter()
            .zip(&normals)
            .map(|(&p, &n)| {
                let lift = if lcg(&mut seed) < 0.2 { 0.5 + 1.5 * lcg(&mut seed) } else { 0.0 };
                let q = Vector3::from(p) + lift * Vector3::from(n);
                transform_point(&inv, q.into())
            })
            .collect();
        let base = IcpOptions { method: IcpMethod::PointToPlane, max_iterations: 100, ..IcpOptions::new(3.0) };
        let plain = icp(&source, &target, Some(&normals), &Matrix4::identity(), &base).unwrap();
        let tukey = IcpOptions { robust: Some(Robust { kernel: RobustKernel::Tukey, scale: None }), ..base };
        let robust = icp(&source, &target, Some(&normals), &Matrix4::identity(), &tukey).unwrap();
        let (ep, er) = (pose_error(&plain.transformation, &truth), pose_error(&robust.transformation, &truth));
        assert!(er < 0.005 && ep > 0.05, "plain {ep}, tukey {er}");
    }

    #[test]
    fn point_to_plane_estimates_the_normals_it_is_not_given() {
        let mut seed = 3;
        let (target, normals) = surface(60, &mut seed);
        let truth = pose(0.02, -0.015, 0.03, [0.4, -0.3, 0.2]);
        let inv = truth.try_inverse().unwrap();
        let source: Vec<[f64; 3]> = target.iter().map(|&p| transform_point(&inv, p)).collect();
        let o = IcpOptions { method: IcpMethod::PointToPlane, max_iterations: 200, ..IcpOptions::new(2.0) };
        let given = icp(&source, &target, Some(&normals), &Matrix4::identity(), &o).unwrap();
        let estimated = estimate_normals(&target, Neighborhood::Knn(NORMAL_NEIGHBORS)).unwrap().0;
        let same = icp(&source, &target, Some(&estimated), &Matrix4::identity(), &o).unwrap();
        let none = icp(&source, &target, None, &Matrix4::identity(), &o).unwrap();
        // Without normals the call is the call with the estimated ones, and still finds the pose.
        assert_eq!(none.transformation, same.transformation);
        assert!(pose_error(&none.transformation, &truth) < 1e-6, "{}", pose_error(&none.transformation, &truth));
        assert!(pose_error(&given.transformation, &truth) < 1e-9);
        let few = &target[..NORMAL_NEIGHBORS];
        let err = icp(few, few, None, &Matrix4::identity(), &o).unwrap_err().to_string();
        assert!(err.contains("target_normals") && err.contains("20"), "{err}");
    }

    #[test]
    fn bad_options_are_refused_by_name() {
        let p = vec![[0.0, 0.0, 0.0]; 4];
        let err =
            |o: IcpOptions, n: Option<&[[f64; 3]]>| icp(&p, &p, n, &Matrix4::identity(), &o).unwrap_err().to_string();
        assert!(err(IcpOptions::new(0.0), None).contains("max_distance"));
        assert!(err(IcpOptions { trim: 1.0, ..IcpOptions::new(1.0) }, None).contains("trim"));
        assert!(err(IcpOptions { method: IcpMethod::PointToPlane, ..IcpOptions::new(1.0) }, None)
            .contains("target_normals"));
        assert!(err(IcpOptions::new(1.0), Some(&p[..2])).contains("target_normals"));
    }
}
