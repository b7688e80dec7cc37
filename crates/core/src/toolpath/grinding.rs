//! Belt-grinding paths from an allowance cloud (SPEC P1–P5; paper 004 §2–3).
//!
//! The cloud is the blade's surface sampled with, at each point, its outward normal (toward the
//! tool) and the allowance — the stock standing above the model there. The path is a set of rows,
//! each the intersection of the surface with one plane of a parallel family (`section_normal`),
//! joined into one polyline:
//!
//! 1. **Row spacing.** Neighbouring rows an arc L apart leave a cusp whose height depends on the
//!    tool radius R and the surface's radius ρ across the rows (`scallop.rs`). ρ is taken at
//!    sample points of the cloud from the turn of the given normals across the rows over
//!    `fit_radius` (`Cloud::across`) — the scale of a step, so scan noise does not turn into
//!    curvature — and each sample gives the widest plane
//!    spacing that keeps its cusp at the scallop height: `step_over(R, ρ, h)` times the sine of
//!    the angle between the surface and the planes. From a row at offset d, the next lies at
//!    d + Δ, Δ the smallest such spacing over the samples between d and d + Δ (a fixed point: the
//!    band only narrows as Δ does). The first and last rows lie half a step inside the cloud's
//!    ends (at most half a slab), so the stock beyond them is left at the scallop height too;
//!    where the rows would overshoot the last, every gap shrinks in proportion.
//! 2. **Row points.** The cloud points within ±thickness/2 of the plane (a slab at least 1.5
//!    times as thick as the gap between the cloud's lines across the planes, so it always holds
//!    one: a model sampled in sections) are projected onto it, ordered by the bead chain (`bead_chain.rs`) and resampled every `spacing` along the chain.
//!    Each sample is then put on the surface without leaving the plane: a height field of the
//!    nearest cloud points (cubic where they span four scan lines, else quadric, widened until they
//!    span three), solved along the in-plane direction of its normal; round an edge, where the
//!    nearest points' normals turn by more than 30°, the support function of the edge's cuts
//!    (`edge.rs`), which follows an edge of a few point spacings' radius between scan lines.
//!    This is where a path point's position, normal and allowance come from; its curvature across
//!    the rows comes from the wide fit of step 1. A fit's normal must agree with the given normals
//!    nearest it (a wrong one sinks the wheel R·δ²/2 into a flank), the fit must lie on a smooth
//!    surface through one of its nearest points (`Cloud::near_surface`), and where the cloud does not
//!    reach past the plane (a ragged end) no fit is taken: it would extrapolate.
//! 3. **Straight moves.** Points are added where the tool centre would stray more than the
//!    tolerance from the arc between two path points. Where the halving closes in on a point at
//!    which the fits on either side disagree (their nearest points change there), the wheel rolls
//!    over it — its normal turns from one fit's to the other's at one place — if they disagree by
//!    at most twice the scallop height; by more, or where no fit holds inside the cloud, the cloud
//!    is too sparse for the surface there and the call fails naming `points`, the place and the
//!    spacing needed (an edge needs its radius × 0.6 rad, `RESOLVED_TURN`). A path is never made
//!    of fits that disagree: they are where a coarse cloud misses an edge.
//! 4. **Joining.** Open rows alternate direction (a boustrophedon); closed rows all run the same
//!    way, each starting at the point nearest the end of the row before. A row is first cut where
//!    the data stops — the section runs off the cloud (round a thin edge at the cloud's end), the
//!    planes graze the surface, or no stock was measured — and the wheel could not move straight
//!    across the gap without cutting into the part: its pieces are consecutive rows with the same
//!    plane offset.
//! 5. **Feed** (eq 11–15): the removal model r = C·Vb^e₁·Vw^e₂·F^e₃ solved for the feed Vw that
//!    removes each point's allowance, clamped to the machine's limits, and held along the path
//!    while it stays within the feed step of the feed in force (a post-processor then gets one
//!    FEDRAT per real change, not one per point). The feed is in the model's unit (mm/s for the
//!    paper's calibration).
//!
//! `simulate_removal` checks a path: a spherical tool of radius R at every path point, sunk by
//! the depth the feed removes there, is swept over the blank (model + allowance), and the stock
//! left over the model is reported at every cloud point — the full depth of a cut, however deep.
use super::bead_chain::{bead_chain, Chain};
use super::edge::EdgePatch;
use super::scallop::step_over;
use crate::error::{check_finite, check_finite_points, check_positive, Error, Result};
use crate::spatial::PointIndex;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, DimDiff, DimSub, Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6, U1};
use rayon::prelude::*;
use std::collections::HashSet;

type V3 = Vector3<f64>;

/// Nearest cloud points a path point's position, normal and allowance are fitted to (of twice as
/// many candidates, those on the same side of a thin edge).
const LOCAL_POINTS: usize = 24;
/// Nearest cloud points of an edge patch (`edge.rs`): a few scan lines' worth of an edge's tip
/// (taken from the first query of a local fit, `2 × LOCAL_POINTS` points).
const EDGE_POINTS: usize = 40;
/// Cubic fields fitted over a local patch: the height, the allowance and the three components of
/// the normal.
const CHANNELS: usize = 5;
/// Neighbours whose given normal turns more than 60° from the nearest point's lie on the other
/// side of a thin edge (a blade's trailing edge) and are left out of a fit.
const SAME_SIDE: f64 = 0.5;
/// A local fit takes only neighbours whose normals turn less than 30° from the nearest point's:
/// round an edge a few point spacings in radius a height field over a wider turn is no cubic.
const LOCAL_TURN: f64 = 0.866;
/// Fewest points of a wide (curvature) fit; fewer within `fit_radius` falls back to the nearest.
const WIDE_MIN_POINTS: usize = 12;
/// Cloud samples per `fit_radius` along each axis used for the wide fits (and the samples that
/// set the row spacing): enough to fit a quadric, few enough that 1 M points stay cheap.
const WIDE_SAMPLES_PER_RADIUS: f64 = 5.0;
/// Stretches whose surface meets the section planes at less than asin(0.2) ≈ 11.5° (an edge's tip
/// seen along the section normal) do not set the row spacing: there a plane spacing says little
/// about the arc between rows.
const MIN_CROSSING: f64 = 0.2;
/// Height of the ridges the removal simulation leaves between its tool positions along a row, mm:
/// the sweep is sampled finely enough that it is continuous to this.
const SWEEP_TOLERANCE: f64 = 1e-4;
/// Times the removal simulation lengthens the stretch of a point's normal line it looks for tools
/// along (down to the cut's end each time) while a cut runs on below it: a cut carried down by
/// a chain of tools is followed that many links deep, at least.
const SIMULATION_REACHES: usize = 50;
/// Smallest eigenvalue of the Jacobi-scaled normal matrix of a local cubic fit below which the
/// local fields fall back to quadrics: over three scan lines it is 1.5e-6 (y³ is nearly a
/// combination of 1, y, y²) and the cubic's height 45 µm off; over four, 0.04.
const CUBIC_CONDITION: f64 = 1e-3;
/// Smallest eigenvalue of the Jacobi-scaled normal matrix of a quadric over a local patch's points
/// below which the patch takes twice as many points (up to 16 times `LOCAL_POINTS`): a scan's
/// points lie on lines, and a patch of two lines (a line scan, or dense points along the lines
/// round an edge) leaves the curvature across them undetermined — 7e-5 there, 0.14 over four
/// lines, on the synthetic blade.
const QUADRIC_CONDITION: f64 = 1e-3;
/// Default tolerance of the tool centre's straight moves between path points, as a fraction of
/// the scallop height.
const DEFAULT_TOLERANCE: f64 = 0.25;
/// A row is cut between two path points whose straight move strays more than this many times
/// the tolerance from the arc round them (`Row::pieces`): refinement keeps every other move
/// within the tolerance.
const CUT_STRAY: f64 = 2.0;
/// Cosine of the largest angle (15°) between a local fit's normal and its nearest points' normals.
const FIT_AGREEMENT: f64 = 0.966;
/// Cosine of the largest angle (30°) between an edge patch's normal and the nearest given normal
/// (or the arc between two of them): round an edge sampled every point spacing or so, the given
/// normals turn by up to a radian between points, and a fit between them is that far from both.
const EDGE_AGREEMENT: f64 = 0.866;
/// Sine of the largest angle (15°) between an edge patch's normal and the arc between two of the
/// given normals nearest it.
const ARC_AGREEMENT: f64 = 0.259;
/// A row is refused where the fits on either side of a point disagree by more than this many
/// scallop heights of tool-centre stray (`row_points`): the tool rolling over the point would
/// leave or cut that much more than the rows' cusp.
const DISAGREEMENT: f64 = 2.0;
/// Largest turn of the normals between neighbouring points (0.6 rad, 34°) at which every edge
/// measured was resolved for a 5–20 µm scallop height: the edge radius times this is the point
/// spacing an edge needs (BENCHMARKS.md, `benchmarks/grinding_parts.py`).
const RESOLVED_TURN: f64 = 0.6;
/// Smallest eigenvalue of the Jacobi-scaled normal matrix of the fit of the normals' turn across
/// the rows (`Cloud::across`) below which the neighbours do not span the direction across them.
const ACROSS_CONDITION: f64 = 1e-3;
/// The default slab is at least this many gaps between the cloud's lines across the planes thick
/// (`line_gap`): it then always holds one line, at most two.
const SLAB_PER_GAP: f64 = 1.5;
/// Newton iterations putting a point on the local quadric within its plane.
const PLACE_ITERATIONS: usize = 6;
/// Default feed step: a new feed is programmed where the feed that removes the allowance departs
/// from the one in force by more than this share of it. At the paper's feed exponent (−0.7) a
/// 3 % feed step changes the removal by at most 2.1 %, 8 µm on 0.4 mm of stock, and a blade
/// path of 10⁵ points needs a few thousand FEDRATs instead of one per point.
pub const DEFAULT_FEED_STEP: f64 = 0.03;

/// The removal model of belt grinding (SPEC P4, paper 004 eq 11): depth removed
/// r = C · Vb^e₁ · Vw^e₂ · F^e₃ for belt speed Vb, feed Vw and contact force F, in the units the
/// model was calibrated in — the paper's: r in mm, Vb in m/s, Vw in mm/s, F in N. The feeds it
/// gives and the feed limits are in that feed unit (mm/s for the paper's calibration); CL files
/// carry them per minute (`GrindingPaths` users convert, `machscan` writes FEDRAT/MMPM).
#[derive(Debug, Clone, Copy)]
pub struct RemovalModel {
    pub c: f64,
    pub exponents: [f64; 3],
    pub belt_speed: f64,
    pub force: f64,
    pub feed_limits: [f64; 2],
}

impl RemovalModel {
    pub fn new(c: f64, exponents: [f64; 3], belt_speed: f64, force: f64, feed_limits: [f64; 2]) -> Result<Self> {
        check_positive("removal_model.C", c, "")?;
        check_positive("removal_model.belt_speed", belt_speed, "")?;
        check_positive("removal_model.force", force, "")?;
        check_finite("removal_model.exponents", &exponents, 3)?;
        if exponents[1] == 0.0 {
            return Err(Error::invalid(
                "removal_model.exponents",
                "the feed exponent (the second) is 0: the feed does not change the removal",
            ));
        }
        let [lo, hi] = feed_limits;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
            return Err(Error::invalid(
                "removal_model.feed_limits",
                format!("expected (low, high) with 0 < low ≤ high, finite; got ({lo}, {hi})"),
            ));
        }
        Ok(RemovalModel { c, exponents, belt_speed, force, feed_limits })
    }

    /// Depth removed at feed `feed`.
    pub fn removal(&self, feed: f64) -> f64 {
        let [e1, e2, e3] = self.exponents;
        self.c * self.belt_speed.powf(e1) * feed.powf(e2) * self.force.powf(e3)
    }

    /// The feed removing `depth`, clamped to the limits; a depth ≤ 0 gets the limit that removes
    /// least.
    pub fn feed(&self, depth: f64) -> f64 {
        let [lo, hi] = self.feed_limits;
        let [e1, e2, e3] = self.exponents;
        let least = if e2 < 0.0 { hi } else { lo };
        if depth.is_nan() || depth <= 0.0 {
            return least;
        }
        let unclamped = (depth / (self.c * self.belt_speed.powf(e1) * self.force.powf(e3))).powf(1.0 / e2);
        if unclamped.is_nan() {
            least
        } else {
            unclamped.clamp(lo, hi)
        }
    }
}

#[derive(Debug, Clone)]
pub struct GrindingOptions {
    pub tool_radius: f64,
    pub scallop_height: f64,
    pub section_normal: [f64; 3],
    /// Slab thickness of a section, mm; default twice the cloud's point spacing, or 1.5 times the
    /// gap between its lines across the planes where that is more (`line_gap`).
    pub thickness: Option<f64>,
    /// Path point spacing along a row, mm; default the cloud's point spacing.
    pub spacing: Option<f64>,
    /// Largest deviation of the tool centre between two path points from the straight line
    /// joining them, mm; default a quarter of the scallop height.
    pub tolerance: Option<f64>,
    /// Radius of the curvature fits, mm; default the step-over on a flat surface, at least four
    /// point spacings.
    pub fit_radius: Option<f64>,
    pub removal: Option<RemovalModel>,
    /// A new feed is programmed where the wanted feed departs from the one in force by more than
    /// this share of it (0: at every change); default [`DEFAULT_FEED_STEP`].
    pub feed_step: Option<f64>,
}

#[derive(Debug, Clone, Default)]
pub struct GrindingPaths {
    pub points: Vec<[f64; 3]>,
    pub normals: Vec<[f64; 3]>,
    pub row: Vec<usize>,
    /// Normal curvature across the rows, 1/mm (> 0 convex).
    pub curvature: Vec<f64>,
    pub allowance: Vec<f64>,
    /// The feed programmed at each point, in the removal model's feed unit (mm/s for the
    /// paper's): the feed that removes the allowance, clamped to the limits and held while it
    /// stays within the feed step of the one in force. NaN without a removal model.
    pub feed: Vec<f64>,
    /// False where the surface is concave tighter than the tool.
    pub tool_fits: Vec<bool>,
    /// Per row: plane offset along the unit section normal (the pieces of a cut row share it), and
    /// whether it closes up.
    pub row_offsets: Vec<f64>,
    pub row_closed: Vec<bool>,
    /// Cloud points left out because their allowance is NaN: no stock was measured there (the
    /// blank does not cover the point).
    pub without_stock: usize,
}

/// A local fit: cubic fields of the height and of values (allowance, normal) over (x, y) in the
/// frame (origin, u, v, w). Cubic because at an edge of the cloud the patch is one-sided and a
/// quadric's error there grows with the third derivatives: 2.6 µm of height on a 20 mm radius
/// sampled every mm, against 0.3 µm.
struct Patch {
    origin: V3,
    u: V3,
    v: V3,
    w: V3,
    /// Cubic coefficients over (x, y) / `scale`, in the order of `cubic_terms`, one column per
    /// channel (the height first).
    value: SMatrix<f64, 10, CHANNELS>,
    scale: f64,
}

/// How well a least-squares normal matrix determines its terms: the smallest eigenvalue of the
/// matrix scaled to a unit diagonal (1 for independent terms, 0 when one is a combination of the
/// others — a scan's points on too few lines).
fn determinacy<const K: usize>(m: &SMatrix<f64, K, K>) -> f64
where
    Const<K>: DimSub<U1>,
    DefaultAllocator: Allocator<DimDiff<Const<K>, U1>>,
{
    let scaled: [f64; K] = std::array::from_fn(|k| 1.0 / m[(k, k)].max(f64::MIN_POSITIVE).sqrt());
    let mut unit = *m;
    for i in 0..K {
        for j in 0..K {
            unit[(i, j)] *= scaled[i] * scaled[j];
        }
    }
    unit.symmetric_eigenvalues().min()
}

/// Two unit vectors completing `w` (unit) to a right-handed frame (u, v, w).
fn tangent_frame(w: V3) -> (V3, V3) {
    let u = if w.x.abs() < 0.9 { V3::x() } else { V3::y() }.cross(&w).normalize();
    (u, w.cross(&u))
}

fn cubic_terms(x: f64, y: f64) -> SVector<f64, 10> {
    SVector::<f64, 10>::from([1.0, x, y, x * x, x * y, y * y, x * x * x, x * x * y, x * y * y, y * y * y])
}

impl Patch {
    /// Weighted least-squares fit to `points` and their `values` (e.g. allowance) in the frame
    /// whose w is `normal`, each point weighted by exp(−(d/σ)²) for its distance d from the
    /// origin. None when the points do not span the fields.
    fn fit(origin: V3, normal: V3, points: &[V3], values: &[[f64; CHANNELS]], sigma: f64) -> Option<Patch> {
        let w = normal.normalize();
        let (u, v) = tangent_frame(w);
        // Lengths scaled by the patch size inside the fits, for conditioning.
        let scale = points.iter().map(|p| (p - origin).norm()).fold(0.0, f64::max).max(1e-12);
        let (mut cta, mut ctv) = (SMatrix::<f64, 10, 10>::zeros(), SMatrix::<f64, 10, CHANNELS>::zeros());
        for (p, vals) in points.iter().zip(values) {
            let d = (p - origin) / scale;
            let weight = (-(p - origin).norm_squared() / (sigma * sigma)).exp();
            let c = cubic_terms(d.dot(&u), d.dot(&v));
            let mut row = *vals;
            row[0] = (p - origin).dot(&w);
            cta += weight * c * c.transpose();
            ctv += weight * c * SMatrix::<f64, 1, CHANNELS>::from_row_slice(&row);
        }
        // The cubic terms need the patch to span four lines of points across every direction; a
        // scan's points lie on lines, and across fewer a cubic is not determined (y³ is a
        // multiple of y on three lines). Then the fields are quadrics.
        if determinacy(&cta) < CUBIC_CONDITION {
            for k in 6..10 {
                cta.row_mut(k).fill(0.0);
                cta.column_mut(k).fill(0.0);
                cta[(k, k)] = 1.0;
                ctv.row_mut(k).fill(0.0);
            }
        }
        let value = cta.cholesky()?.solve(&ctv);
        value.iter().all(|c| c.is_finite()).then_some(Patch { origin, u, v, w, value, scale })
    }

    /// Height and slopes of the height field at (x, y).
    fn height_slopes(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let (a, b) = (x / self.scale, y / self.scale);
        let h = self.value.column(0);
        let dx = [0.0, 1.0, 0.0, 2.0 * a, b, 0.0, 3.0 * a * a, 2.0 * a * b, b * b, 0.0];
        let dy = [0.0, 0.0, 1.0, 0.0, a, 2.0 * b, 0.0, a * a, 2.0 * a * b, 3.0 * b * b];
        let slope = |d: [f64; 10]| (0..10).map(|k| h[k] * d[k]).sum::<f64>() / self.scale;
        (h.dot(&cubic_terms(a, b)), slope(dx), slope(dy))
    }

    /// The fields at (x, y): height, then the values' channels.
    fn value_at(&self, x: f64, y: f64) -> [f64; CHANNELS] {
        let t = cubic_terms(x / self.scale, y / self.scale);
        std::array::from_fn(|j| self.value.column(j).dot(&t))
    }

    fn coords(&self, p: V3) -> (f64, f64) {
        let d = p - self.origin;
        (d.dot(&self.u), d.dot(&self.v))
    }

    /// The surface point within the plane {p : p·n = offset} nearest `q` (a point of the
    /// plane), found along the in-plane direction of w.
    fn place_in_plane(&self, q: V3, n: V3) -> Option<V3> {
        let m = self.w - self.w.dot(&n) * n;
        if m.norm() < 1e-6 {
            return None;
        }
        let m = m.normalize();
        let mut t = 0.0;
        for _ in 0..PLACE_ITERATIONS {
            let p = q + t * m;
            let (x, y) = self.coords(p);
            let (height, hx, hy) = self.height_slopes(x, y);
            let g = (p - self.origin).dot(&self.w) - height;
            let dg = m.dot(&self.w) - hx * m.dot(&self.u) - hy * m.dot(&self.v);
            if dg.abs() < 1e-12 {
                return None;
            }
            let step = g / dg;
            t -= step;
            if step.abs() < 1e-12 {
                break;
            }
        }
        // A point that wandered off the patch is no point of the surface.
        let p = q + t * m;
        (p.iter().all(|c| c.is_finite()) && t.abs() <= self.scale).then_some(p)
    }
}

/// The cloud, with its two indices: the full one (positions, allowance) and a thinned one for the
/// wide curvature fits.
struct Cloud<'a> {
    points: &'a [[f64; 3]],
    normals: Vec<V3>,
    allowance: &'a [f64],
    index: PointIndex,
    wide: Vec<usize>,
    wide_index: PointIndex,
    fit_radius: f64,
    /// How far off the surface a chain point may stand in for a failed fit: the scallop height.
    fallback_reach: f64,
    /// The cloud's point spacing (median distance to the nearest point).
    spacing: f64,
    /// How far from a row's point the cloud is looked at for whether it reaches past the row's
    /// plane: the slab thickness.
    reach: f64,
}

impl Cloud<'_> {
    fn p(&self, i: usize) -> V3 {
        V3::from(self.points[i])
    }

    /// The mean of the given normals of `near`, for a fit frame.
    fn mean_normal(&self, near: &[usize]) -> V3 {
        let s: V3 = near.iter().map(|&i| self.normals[i]).sum();
        if s.norm() > 0.0 {
            s.normalize()
        } else {
            self.normals[near[0]]
        }
    }

    /// `near` (nearest first) without the points on the other side of a thin edge from the first.
    fn same_side(&self, near: Vec<usize>) -> Vec<usize> {
        self.within_turn(near, SAME_SIDE)
    }

    /// `near` (nearest first) without the points whose normal's cosine to the first's is below
    /// `cosine`.
    fn within_turn(&self, near: Vec<usize>, cosine: f64) -> Vec<usize> {
        let Some(&first) = near.first() else { return near };
        let reference = self.normals[first];
        near.into_iter().filter(|&i| self.normals[i].dot(&reference) > cosine).collect()
    }

    /// How well `near` determine a quadric height field over the plane of their mean normal
    /// (`determinacy`: 0 when all points lie on one or two lines).
    fn quadric_condition(&self, near: &[usize]) -> f64 {
        let (u, v) = tangent_frame(self.mean_normal(near));
        let c: V3 = near.iter().map(|&i| self.p(i)).sum::<V3>() / near.len() as f64;
        let scale = near.iter().map(|&i| (self.p(i) - c).norm()).fold(0.0, f64::max).max(1e-12);
        let mut m = Matrix6::zeros();
        for &i in near {
            let d = (self.p(i) - c) / scale;
            let (x, y) = (d.dot(&u), d.dot(&v));
            let row = Vector6::new(1.0, x, y, x * x, x * y, y * y);
            m += row * row.transpose();
        }
        determinacy(&m)
    }

    /// The local fit at q: (point on the surface in the plane (n, q), normal, allowance).
    fn local(&self, q: V3, n: V3) -> Option<(V3, V3, f64)> {
        // One neighbour query serves the edge test and the first height-field patch.
        let mut found = self.index.knn(&q.into(), 2 * LOCAL_POINTS);
        // Where the cloud does not reach past the plane (a ragged end of the cloud, where a row
        // runs beyond its last scan line), every fit extrapolates: at the blade's tip an edge
        // patch there tilted its normals 14–70° along the edge, and the wheel sank 0.3–11 mm into
        // the flank below. No point: the row is cut there.
        if self.one_sided(q, n) {
            return None;
        }
        if let Some(fit) = self.edge(q, n, &found[..EDGE_POINTS.min(found.len())]) {
            // An edge patch fitted to a wrong axis (at the cloud's end, where its points span one
            // or two scan lines) can put a point on the surface with a normal turned 70° from every
            // given one: a wheel there sinks 8 mm into the part. Its normal must lie within the
            // turn of the given normals nearest it.
            let near = self.index.knn(&fit.0.into(), 4);
            if self.normal_agrees(&near, fit.1, EDGE_AGREEMENT) && self.near_surface(&near, fit.0, fit.1) {
                return Some(fit);
            }
        }
        let mut k = LOCAL_POINTS;
        let near = loop {
            if k > LOCAL_POINTS {
                found = self.index.knn(&q.into(), 2 * k);
            }
            let mut near = self.within_turn(found.iter().map(|&(i, _)| i).collect(), LOCAL_TURN);
            near.truncate(k);
            let more = k < 16 * LOCAL_POINTS && found.len() >= 2 * k;
            // Round a tight edge few of the nearest points lie within the turn (fewer still at the
            // cloud's end): the patch widens along the edge until enough do.
            if near.len() < LOCAL_POINTS / 2 {
                if more {
                    k *= 2;
                    continue;
                }
                return None;
            }
            if !more || self.quadric_condition(&near) >= QUADRIC_CONDITION {
                break near;
            }
            k *= 2;
        };
        // Weighted toward the middle of the patch: where the patch is one-sided (an edge of the
        // cloud) the fit extrapolates, and its error grows with the patch's size.
        let sigma = (self.p(near[near.len() / 3]) - q).norm().max(1e-9);
        let pts: Vec<V3> = near.iter().map(|&i| self.p(i)).collect();
        // Where a neighbour has no stock measured the stock here is not known either: the fit
        // gives the geometry, and the allowance is NaN (the row is cut there).
        let unknown = near.iter().any(|&i| self.allowance[i].is_nan());
        let vals: Vec<[f64; CHANNELS]> = near
            .iter()
            .map(|&i| {
                let m = self.normals[i];
                [0.0, if unknown { 0.0 } else { self.allowance[i] }, m.x, m.y, m.z]
            })
            .collect();
        let fitted = || {
            let patch = Patch::fit(q, self.mean_normal(&near), &pts, &vals, sigma)?;
            let on = patch.place_in_plane(q, n)?;
            let (x, y) = patch.coords(on);
            let [_, allowance, nx, ny, nz] = patch.value_at(x, y);
            // The normal interpolated from the given ones: a model's normals are exact, and a
            // scan's were estimated over more points than this patch holds.
            let normal = V3::new(nx, ny, nz);
            (normal.norm() > 0.0).then(|| (on, normal.normalize(), if unknown { f64::NAN } else { allowance }))
        };
        // Where the surface turns within the patch (a trailing edge a few point spacings round)
        // a fit says nothing reliable: it must agree with the nearest points' own normals (with
        // their mean, or — round a tip, where they fan out and their mean is none of them — lie
        // among them, `normal_agrees`), or q itself stands in — a point of the section's chain —
        // with its nearest points' normal and allowance, if it lies within the scallop height of
        // the nearest point's tangent plane (a slab point projected onto a plane the surface
        // grazes lies off the surface: no point).
        let holds = |fit: &(V3, V3, f64)| {
            let near = self.index.knn(&fit.0.into(), 4);
            (fit.1.dot(&self.nearby(fit.0).0) >= FIT_AGREEMENT || self.normal_agrees(&near, fit.1, FIT_AGREEMENT))
                && self.near_surface(&near, fit.0, fit.1)
        };
        match fitted() {
            Some(fit) if holds(&fit) => Some(fit),
            _ => {
                let (nearest, _) = self.index.nearest(&q.into());
                if (q - self.p(nearest)).dot(&self.normals[nearest]).abs() > self.fallback_reach {
                    return None;
                }
                let (normal, allowance) = self.nearby(q);
                Some((q, normal, allowance))
            }
        }
    }

    /// The fit at q of an edge patch over `found` (q's nearest points, nearest first, with squared
    /// distances), where their normals turn by more than a height field follows (`LOCAL_TURN`);
    /// None elsewhere or where the patch does not fit.
    fn edge(&self, q: V3, n: V3, found: &[(usize, f64)]) -> Option<(V3, V3, f64)> {
        let reference = self.normals[found.first()?.0];
        if found.iter().all(|&(i, _)| self.normals[i].dot(&reference) >= LOCAL_TURN) {
            return None;
        }
        let sigma = 1.5 * found[found.len() / 3].1.sqrt();
        let points: Vec<V3> = found.iter().map(|&(i, _)| self.p(i)).collect();
        let normals: Vec<V3> = found.iter().map(|&(i, _)| self.normals[i]).collect();
        let unknown = found.iter().any(|&(i, _)| self.allowance[i].is_nan());
        let allowance: Vec<f64> = found.iter().map(|&(i, _)| if unknown { 0.0 } else { self.allowance[i] }).collect();
        let (on, normal, value) =
            EdgePatch::fit(q, reference, &points, &normals, &allowance, sigma)?.place_in_plane(q, n)?;
        Some((on, normal, if unknown { f64::NAN } else { value }))
    }

    /// Whether a fitted point p of normal m lies on a smooth surface through its nearest given
    /// points (`near`, its 4 nearest with squared distances): for one of them, q of normal n, the chord p − q is square to n + m within
    /// `DISAGREEMENT` scallop heights — exact for any circular arc from q to p, so a fit that
    /// follows an edge between scan lines passes, one off the surface does not. An edge patch
    /// taken where a flat meets a fillet (a stadium's join, every 0.35 mm at random) put the
    /// wheel's contact 0.46 mm above the flat with a normal turned 29°, and the row was refused as
    /// too sparse; one at a random cloud's end put it 80 µm into a biconvex blade's fillet.
    fn near_surface(&self, near: &[(usize, f64)], p: V3, m: V3) -> bool {
        let limit = DISAGREEMENT * self.fallback_reach;
        near.iter().any(|&(i, _)| {
            let bisector = self.normals[i] + m;
            let length = bisector.norm();
            length > 0.0 && ((p - self.p(i)).dot(&bisector) / length).abs() <= limit
        })
    }

    /// Whether `normal` at a point lies among the given normals of its 4 nearest points (`near`,
    /// with squared distances): within acos(`one`) of one, or within 15° of the arc between two
    /// of them (round an edge the normals turn by up to a radian between points, and a fit between
    /// them lies that far from both).
    fn normal_agrees(&self, near: &[(usize, f64)], normal: V3, one: f64) -> bool {
        let near: Vec<V3> = near.iter().map(|&(i, _)| self.normals[i]).collect();
        near.iter().enumerate().any(|(k, &a)| {
            a.dot(&normal) >= one
                || near[k + 1..].iter().any(|&b| {
                    let Some(axis) = a.cross(&b).try_normalize(1e-9) else { return false };
                    let across = normal.dot(&axis);
                    let Some(along) = (normal - across * axis).try_normalize(1e-9) else { return false };
                    across.abs() <= ARC_AGREEMENT && a.angle(&along) + along.angle(&b) <= a.angle(&b) + 1e-9
                })
        })
    }

    /// Whether the row's plane (normal `n`) at `q` runs off the cloud — its nearest points all lie
    /// on one side of the plane — or grazes the surface, or runs along an edge: a point without a
    /// fit there is a gap in what the rows can grind, where the row is cut, not a cloud too sparse
    /// for the surface.
    fn open(&self, q: V3, n: V3) -> bool {
        let found = self.index.knn(&q.into(), LOCAL_POINTS);
        let Some(&(nearest, _)) = found.first() else { return true };
        self.one_sided(q, n) || self.normals[nearest].cross(&n).norm() < MIN_CROSSING || self.along_edge(n, &found)
    }

    /// Whether the plane of normal n runs along an edge among `found` (their normals turn by more
    /// than `LOCAL_TURN`): it holds the edge's axis — the direction the normals are all nearly
    /// perpendicular to — within asin(`MIN_CROSSING`). A section there follows the edge instead of
    /// crossing it (planes along a blade's span): no fit places a point on it.
    fn along_edge(&self, n: V3, found: &[(usize, f64)]) -> bool {
        let reference = self.normals[found[0].0];
        if found.iter().all(|&(i, _)| self.normals[i].dot(&reference) >= LOCAL_TURN) {
            return false;
        }
        let scatter: nalgebra::Matrix3<f64> =
            found.iter().map(|&(i, _)| self.normals[i] * self.normals[i].transpose()).sum();
        let eigen = scatter.symmetric_eigen();
        let axis = eigen.eigenvectors.column(eigen.eigenvalues.imin()).into_owned();
        n.dot(&axis).abs() < MIN_CROSSING
    }

    /// Whether the cloud ends before the plane through q of normal n: its points within a slab's
    /// thickness of q (the reach of the rows' slabs, wide enough for line scans whose lines lie
    /// far apart) all lie on one side of the plane, or within a quarter of a point spacing of it.
    fn one_sided(&self, q: V3, n: V3) -> bool {
        let side = 0.25 * self.spacing;
        let (mut above, mut below) = (false, false);
        self.index.for_each_within(&q.into(), self.reach, |i| {
            let off = (self.p(i) - q).dot(&n);
            above |= off > side;
            below |= off < -side;
        });
        !(above && below)
    }

    /// The error for a row the cloud does not determine at `u.at`: where, by how much, and about
    /// the point spacing that would. The fits fail where an edge turns too far between points;
    /// measured on elliptic, circular-arc and Bézier edges (BENCHMARKS.md), they held wherever the
    /// normals turned by up to `RESOLVED_TURN` between neighbouring points, so the spacing given
    /// is that turn over the fastest one measured here (per mm), and less than the cloud's.
    fn too_sparse(&self, u: Unresolved, h: f64, limit: f64) -> Error {
        // The fastest turn between neighbouring points (at most 1.5 spacings apart) round the
        // place: where the fits fail is often beside the tightest stretch, not on it.
        let s = self.spacing;
        let found = self.index.knn(&u.at.into(), LOCAL_POINTS);
        let (mut turn, mut rate) = (0.0f64, 0.0f64);
        for (k, &(i, _)) in found.iter().enumerate() {
            for &(j, _) in &found[k + 1..] {
                let apart = (self.p(i) - self.p(j)).norm();
                if apart > 0.0 && apart <= 1.5 * s {
                    let angle = self.normals[i].angle(&self.normals[j]);
                    turn = turn.max(angle);
                    rate = rate.max(angle / apart);
                }
            }
        }
        let needed = if rate > 0.0 { (RESOLVED_TURN / rate).min(0.9 * s) } else { 0.5 * s };
        let what = if u.disagreement.is_finite() {
            format!(
                "the surface fits on either side of a point disagree by {:.3} mm of tool position (more than \
                 {DISAGREEMENT} × the scallop height {h} mm = {limit:.3} mm)",
                u.disagreement
            )
        } else {
            "no surface fit holds though the cloud surrounds the row there".to_string()
        };
        Error::invalid(
            "points",
            format!(
                "the cloud is too sparse for the surface near ({:.3}, {:.3}, {:.3}) mm: {what}. Its points lie \
                 {s:.3} mm apart and their normals turn by up to {:.0}° between neighbours there (an edge of about \
                 {:.2} mm radius); points every {needed:.2} mm or closer are needed there (normals turning at most \
                 {:.0}° from point to point)",
                u.at.x,
                u.at.y,
                u.at.z,
                turn.to_degrees(),
                if rate > 0.0 { 1.0 / rate } else { f64::INFINITY },
                RESOLVED_TURN.to_degrees()
            ),
        )
    }

    /// The given normals and allowances of the 4 nearest points on one side, weighted by inverse
    /// distance.
    fn nearby(&self, q: V3) -> (V3, f64) {
        let found = self.index.knn(&q.into(), 8);
        let near = self.same_side(found.iter().map(|&(i, _)| i).collect());
        let (mut normal, mut allowance, mut total) = (V3::zeros(), 0.0, 0.0);
        for &i in near.iter().take(4) {
            let w = 1.0 / ((self.p(i) - q).norm() + 1e-9);
            normal += w * self.normals[i];
            allowance += w * self.allowance[i];
            total += w;
        }
        (normal.try_normalize(0.0).unwrap_or(self.normals[near[0]]), allowance / total)
    }

    /// Curvature across the rows (planes of normal n) at q from the wide fit, and the sine of
    /// the angle between the surface and the planes there.
    ///
    /// The curvature is the rate at which the given normals turn along the direction `t` across
    /// the rows: the slope, along t, of the plane fitted to n_i·t over the neighbourhood (on a
    /// circle n·t is exactly linear in the distance along t). Not from a quadric of the positions:
    /// where the surface's curvature jumps (a flat meeting a fillet) such a fit across the jump
    /// put up to ±0.03 /mm into the direction along the join, where the surface is straight; a
    /// curvature of −0.096 /mm, near the tool's own, let the concave step-over grow to 4.2 mm on a
    /// prism and the pass left 0.23 mm between two rows. The normals of a prism have no component
    /// along it, so this fit gives exactly 0 there.
    fn across(&self, q: V3, n: V3) -> Option<(f64, f64)> {
        let mut near: Vec<usize> = Vec::new();
        self.wide_index.for_each_within(&q.into(), self.fit_radius, |k| near.push(self.wide[k]));
        if near.len() < WIDE_MIN_POINTS {
            near = self.wide_index.knn(&q.into(), WIDE_MIN_POINTS).into_iter().map(|(k, _)| self.wide[k]).collect();
        } else {
            let nearest = self.wide[self.wide_index.nearest(&q.into()).0];
            near.sort_by_key(|&i| i != nearest);
        }
        let near = self.same_side(near);
        if near.len() < 6 {
            return None;
        }
        let (origin, normal) = (self.p(near[0]), self.normals[near[0]]);
        let along_row = n.cross(&normal);
        if along_row.norm() < 1e-9 {
            return Some((0.0, 0.0));
        }
        let along_row = along_row.normalize();
        let across = normal.cross(&along_row);
        let (mut ata, mut atb) = (Matrix3::zeros(), V3::zeros());
        for &i in &near {
            let d = self.p(i) - origin;
            let row = V3::new(1.0, d.dot(&across), d.dot(&along_row));
            ata += row * row.transpose();
            atb += row * self.normals[i].dot(&across);
        }
        // Neighbours all on one line along the row (sections further apart than the fit radius)
        // say nothing about the turn across it.
        if determinacy(&ata) < ACROSS_CONDITION {
            return None;
        }
        let k = ata.cholesky()?.solve(&atb)[1];
        k.is_finite().then_some((k, across.dot(&n).abs()))
    }
}

/// The plane spacing that keeps the cusp at `h` where the curvature across the rows is `k` and
/// the surface meets the planes at sine `crossing`; the flat step where the tool does not fit a
/// concave stretch.
fn plane_step(r: f64, h: f64, k: f64, crossing: f64, flat: f64) -> f64 {
    let rho = if k == 0.0 { f64::INFINITY } else { 1.0 / k };
    let arc = if rho < 0.0 && -rho <= r { flat } else { step_over(r, rho, h).unwrap_or(flat) };
    arc * crossing
}

/// The median of `measure` over up to 2000 of the `count` points, spread through the cloud; 0
/// where it measures none.
fn sampled_median(count: usize, measure: impl Fn(usize) -> Option<f64>) -> f64 {
    let mut found: Vec<f64> = (0..count).step_by((count / 2000).max(1)).filter_map(measure).collect();
    if found.is_empty() {
        return 0.0;
    }
    let mid = found.len() / 2;
    *found.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Median distance from a point to its nearest neighbour.
fn point_spacing(points: &[[f64; 3]], index: &PointIndex) -> f64 {
    sampled_median(points.len(), |i| index.knn(&points[i], 2).get(1).map(|&(_, d2)| d2.sqrt()).filter(|&d| d > 0.0))
}

/// Median gap along `n` between a point's line of points and the next: the smallest offset
/// along `n` above a quarter `spacing` among a point's 32 nearest. A model sampled in sections,
/// or a line scan, has its lines further apart than its points along them; a slab thinner than
/// that gap holds no line where it falls between two, and its row has no points there (a model
/// every 0.15 mm along sections 0.5 mm apart gave no path at all). On an even cloud it is below
/// the spacing.
fn line_gap(points: &[[f64; 3]], index: &PointIndex, n: V3, spacing: f64) -> f64 {
    sampled_median(points.len(), |i| {
        let p = V3::from(points[i]);
        index
            .knn(&points[i], 32)
            .iter()
            .map(|&(j, _)| (V3::from(points[j]) - p).dot(&n).abs())
            .filter(|&d| d > 0.25 * spacing)
            .reduce(f64::min)
    })
}

/// One point per occupied voxel of size `voxel`: the first one met.
fn thin(points: &[[f64; 3]], voxel: f64) -> Vec<usize> {
    let mut seen: HashSet<[i64; 3]> = HashSet::new();
    (0..points.len()).filter(|&i| seen.insert(points[i].map(|c| (c / voxel).floor() as i64))).collect()
}

/// A polyline by arc length (closed: back to the start).
struct Polyline {
    points: Vec<V3>,
    arc: Vec<f64>,
}

impl Polyline {
    fn new(line: &[V3], closed: bool) -> Polyline {
        let mut points: Vec<V3> = line.to_vec();
        if closed {
            points.push(line[0]);
        }
        let mut arc = vec![0.0];
        for k in 1..points.len() {
            arc.push(arc[k - 1] + (points[k] - points[k - 1]).norm());
        }
        Polyline { points, arc }
    }

    fn length(&self) -> f64 {
        *self.arc.last().unwrap_or(&0.0)
    }

    fn at(&self, s: f64) -> V3 {
        let seg = self.arc.partition_point(|&a| a < s).clamp(1, self.arc.len().max(2) - 1);
        if self.points.len() < 2 {
            return self.points[0];
        }
        let (a, b) = (self.arc[seg - 1], self.arc[seg]);
        let f = if b > a { ((s - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
        self.points[seg - 1].lerp(&self.points[seg], f)
    }
}

/// Where the cloud does not determine a row: a chain point where no fit holds though the cloud
/// surrounds it (`disagreement` infinite), or a point where the fits on either side disagree
/// (`disagreement`: how far the tool centre would stray between them, mm).
#[derive(Debug, Clone, Copy)]
struct Unresolved {
    at: V3,
    disagreement: f64,
}

/// A row's path points: every `spacing` of arc length along the chain's polyline, then halved
/// where the tool centre (`tool_radius` out along the normal) strays more than `tolerance` from
/// the straight line between two neighbours — round a thin edge the normal turns half a turn in a
/// millimetre, and a machine interpolating the centre between sparse points would cut through it.
///
/// Where a point has no fit (`eval` None) and `open` says the row runs off the cloud there (or
/// grazes the surface), the link is left as it is, for `Row::pieces` to cut. Where the halving
/// closes in on a point at which the fits on either side disagree (the patches of nearest points
/// change there), the tool rolls over it: points at one place whose normals turn from one fit's
/// to the other's, so that no straight move strays more than `tolerance` — a cut there would split
/// the row wherever the cloud is a little coarse for an edge. A disagreement above `limit`, or a
/// point without a fit inside the cloud, is no path: `Unresolved`.
#[allow(clippy::too_many_arguments)]
fn row_points(
    line: &Polyline,
    closed: bool,
    spacing: f64,
    tolerance: f64,
    limit: f64,
    tool_radius: f64,
    eval: impl Fn(V3) -> Option<(V3, V3, f64)>,
    open: impl Fn(V3) -> bool,
) -> std::result::Result<Vec<(V3, V3, f64)>, Unresolved> {
    let total = line.length();
    let count = (total / spacing).round().max(1.0) as usize;
    let last = if closed { count } else { count + 1 };
    let unresolved = |q: V3| Unresolved { at: q, disagreement: f64::INFINITY };
    let mut at: Vec<(f64, (V3, V3, f64))> = Vec::with_capacity(last + 1);
    for j in 0..last {
        let s = total * j as f64 / count as f64;
        let q = line.at(s);
        match eval(q) {
            Some(e) => at.push((s, e)),
            None if open(q) => {}
            None => return Err(unresolved(q)),
        }
    }
    if closed {
        if let Some(&(_, first)) = at.first() {
            at.push((total, first));
        }
    }
    let stray = |a: &(V3, V3, f64), b: &(V3, V3, f64)| centre_stray(a.0, a.1, b.0, b.1, tool_radius);
    let min_gap = 1e-4 * spacing;
    let mut out: Vec<(V3, V3, f64)> = Vec::with_capacity(at.len());
    for pair in at.windows(2) {
        let (mut stack, mut from) = (vec![pair[1]], pair[0]);
        out.push(from.1);
        while let Some(to) = stack.last().copied() {
            let e = stray(&from.1, &to.1);
            if e > tolerance {
                let mid_s = 0.5 * (from.0 + to.0);
                if to.0 - from.0 > min_gap {
                    let q = line.at(mid_s);
                    match eval(q) {
                        Some(m) => {
                            stack.push((mid_s, m));
                            continue;
                        }
                        // Off the cloud: the link stays, and is cut if it strays too far.
                        None if open(q) => {}
                        None => return Err(unresolved(q)),
                    }
                } else if e > limit {
                    // Where the row runs off the cloud (a ragged end) the fits on either side are
                    // extrapolations: a gap in the data, cut like one.
                    if !open(from.1 .0) {
                        return Err(Unresolved { at: from.1 .0, disagreement: e });
                    }
                } else {
                    out.extend(roll(from.1, to.1, e, tolerance));
                }
            }
            stack.pop();
            if stack.is_empty() {
                break;
            }
            out.push(to.1);
            from = to;
        }
    }
    if !closed {
        if let Some(&(_, e)) = at.last() {
            out.push(e);
        }
    }
    // Neighbouring samples can land on one point (where the fits give way to the chain, or on a
    // thin edge): points closer than a thousandth of the spacing with the same normal are one.
    out.dedup_by(|b, a| (b.0 - a.0).norm() < 1e-3 * spacing && b.1.dot(&a.1) > 1.0 - 1e-12);
    Ok(out)
}

/// The points strictly between `a` and `b` (a few µm apart at most) over which the tool rolls from
/// one's normal to the other's, each straight move straying at most `tolerance` (the stray goes
/// with the square of the turn: `stray` over m² for m moves).
fn roll(a: (V3, V3, f64), b: (V3, V3, f64), stray: f64, tolerance: f64) -> Vec<(V3, V3, f64)> {
    let m = (stray / tolerance).sqrt().ceil().clamp(1.0, 1e4) as usize;
    (1..m)
        .map(|k| {
            let t = k as f64 / m as f64;
            let normal = a.1.lerp(&b.1, t).try_normalize(0.0).unwrap_or(a.1);
            (a.0.lerp(&b.0, t), normal, a.2 + t * (b.2 - a.2))
        })
        .collect()
}

/// How far the tool centre strays from the straight line between two path points (contact
/// points `a`, `b` with normals `na`, `nb`): on an arc of radius ρ whose normals turn by θ the
/// centre strays (R + ρ)(1 − cos θ/2) ≈ (R + ρ)θ²/8 from the chord, with ρθ the contact points'
/// distance — from the end points alone, so the fits' noise does not drive the halving.
fn centre_stray(a: V3, na: V3, b: V3, nb: V3, tool_radius: f64) -> f64 {
    let theta = na.angle(&nb);
    (tool_radius * theta + (b - a).norm()) * theta / 8.0
}

/// One row: (point, normal, curvature across the rows, allowance) per path point, and whether
/// it closes up.
struct Row {
    points: Vec<(V3, V3, f64, f64)>,
    closed: bool,
}

impl Row {
    /// The row in pieces the wheel can follow: cut between two path points where its centre,
    /// moving straight, would stray more than `limit` from the arc round them — where the points
    /// could not be refined (a section that runs off the cloud round a thin edge, a corner): a
    /// straight move there would cut through the edge. A closed row cut once becomes one open
    /// piece starting after the cut.
    fn pieces(self, tool_radius: f64, limit: f64) -> Vec<Row> {
        let n = self.points.len();
        let links = if self.closed { n } else { n.saturating_sub(1) };
        // A path point whose stock is unknown (NaN allowance) is no path point: the links on both
        // sides of it are cut, and the piece it alone makes is dropped below.
        let cut: Vec<usize> = (0..links)
            .filter(|&k| {
                let (a, b) = (&self.points[k], &self.points[(k + 1) % n]);
                a.3.is_nan() || b.3.is_nan() || centre_stray(a.0, a.1, b.0, b.1, tool_radius) > limit
            })
            .collect();
        if cut.is_empty() {
            // Only a row of one point can have nothing to cut; without stock it is no row.
            return if self.points.iter().any(|p| p.3.is_nan()) { Vec::new() } else { vec![self] };
        }
        let mut points = self.points;
        let mut ends: Vec<usize> = cut.iter().map(|&k| k + 1).collect();
        if self.closed {
            // Start after the first cut; the last piece then ends at it.
            let first = ends[0] % n;
            points.rotate_left(first);
            ends = ends.iter().map(|&e| (e + n - first) % n).filter(|&e| e > 0).collect();
            ends.push(n);
        } else {
            ends.push(n);
        }
        let mut out = Vec::with_capacity(ends.len());
        let mut start = 0;
        for end in ends {
            if end > start && !points[start].3.is_nan() {
                out.push(Row { points: points[start..end].to_vec(), closed: false });
            }
            start = end;
        }
        out
    }
}

fn check_inputs(cloud: Stock, o: &GrindingOptions) -> Result<V3> {
    cloud.check("", true)?;
    if cloud.allowance.iter().all(|a| a.is_nan()) {
        return Err(Error::invalid("allowance", "is NaN at every point: no stock was measured anywhere"));
    }
    let points = cloud.points;
    if points.len() < LOCAL_POINTS {
        return Err(Error::invalid(
            "points",
            format!("{} points are too few for the surface fits (at least {LOCAL_POINTS})", points.len()),
        ));
    }
    check_positive("tool_radius", o.tool_radius, "mm")?;
    let h = o.scallop_height;
    if !(h.is_finite() && h > 0.0 && h < o.tool_radius) {
        return Err(Error::invalid(
            "scallop_height",
            format!("must be > 0 and below the tool radius {} mm, got {h}", o.tool_radius),
        ));
    }
    let n = V3::from(o.section_normal);
    if !(n.iter().all(|c| c.is_finite()) && n.norm() > 0.0) {
        return Err(Error::invalid(
            "section_normal",
            format!("must be a finite non-zero vector, got {:?}", o.section_normal),
        ));
    }
    for (name, value) in
        [("thickness", o.thickness), ("spacing", o.spacing), ("tolerance", o.tolerance), ("fit_radius", o.fit_radius)]
    {
        if let Some(v) = value {
            check_positive(name, v, "mm")?;
        }
    }
    if let Some(step) = o.feed_step {
        if !(step.is_finite() && (0.0..1.0).contains(&step)) {
            return Err(Error::invalid(
                "feed_step",
                format!("must be a share of the feed, 0 ≤ step < 1 (0.03 is 3 %), got {step}"),
            ));
        }
    }
    Ok(n.normalize())
}

/// Grinding paths over an allowance cloud (module docs). A point whose allowance is NaN has no
/// stock measured (the blank does not cover it): its surface still guides the rows, but no path
/// point is put where the stock is unknown — a row is cut there — and the points are counted in
/// `without_stock`: the rule every consumer of an allowance field applies.
pub fn grinding_paths(
    points: &[[f64; 3]],
    normals: &[[f64; 3]],
    allowance: &[f64],
    options: &GrindingOptions,
) -> Result<GrindingPaths> {
    let n = check_inputs(Stock { points, normals, allowance }, options)?;
    let (r, h) = (options.tool_radius, options.scallop_height);
    let index = PointIndex::new(points)?;
    let spacing_cloud = point_spacing(points, &index);
    if spacing_cloud <= 0.0 {
        return Err(Error::invalid("points", "all points coincide"));
    }
    let flat = step_over(r, f64::INFINITY, h)?;
    // A slab wider than the gap between the cloud's lines holds one of them wherever it falls.
    let thickness = options
        .thickness
        .unwrap_or_else(|| (2.0 * spacing_cloud).max(SLAB_PER_GAP * line_gap(points, &index, n, spacing_cloud)));
    let spacing = options.spacing.unwrap_or(spacing_cloud);
    let tolerance = options.tolerance.unwrap_or(DEFAULT_TOLERANCE * h);
    let fit_radius = options.fit_radius.unwrap_or(flat.max(4.0 * spacing_cloud));
    let voxel = fit_radius / WIDE_SAMPLES_PER_RADIUS;
    let wide = if voxel > spacing_cloud { thin(points, voxel) } else { (0..points.len()).collect() };
    let wide_points: Vec<[f64; 3]> = wide.iter().map(|&i| points[i]).collect();
    let wide_index = PointIndex::new(&wide_points)?;
    let normals: Vec<V3> = normals.iter().map(|&v| V3::from(v).normalize()).collect();
    let cloud = Cloud {
        points,
        normals,
        allowance,
        index,
        wide,
        wide_index,
        fit_radius,
        fallback_reach: h,
        spacing: spacing_cloud,
        reach: thickness,
    };

    // 1. Row offsets from the samples' plane steps.
    let mut samples: Vec<(f64, f64)> = cloud
        .wide
        .par_iter()
        .filter_map(|&i| {
            let p = cloud.p(i);
            let (k, crossing) = cloud.across(p, n)?;
            (crossing >= MIN_CROSSING).then(|| (p.dot(&n), plane_step(r, h, k, crossing, flat)))
        })
        .collect();
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let offsets: Vec<f64> = points.iter().map(|&p| V3::from(p).dot(&n)).collect();
    let (lo, hi) = offsets.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &d| (a.min(d), b.max(d)));
    // The end rows lie half a step inside the cloud's ends (at most half a slab), so the stock
    // beyond them is left at the scallop height too: half a slab of a 1.5 mm cloud left 0.1 mm
    // over its last 1.5 mm.
    let end_step = |a: f64, b: f64| {
        let (i, j) = (samples.partition_point(|s| s.0 < a), samples.partition_point(|s| s.0 <= b));
        samples[i..j].iter().map(|s| s.1).fold(flat, f64::min)
    };
    let first = lo + (0.5 * thickness).min(0.5 * end_step(lo, lo + flat));
    let last = hi - (0.5 * thickness).min(0.5 * end_step(hi - flat, hi));
    let rows = row_offsets(&samples, first, last, flat, thickness);

    // 2. Row points.
    let limit = DISAGREEMENT * h;
    let mut by_offset: Vec<usize> = (0..points.len()).collect();
    by_offset.sort_by(|&a, &b| offsets[a].total_cmp(&offsets[b]));
    let sorted: Vec<f64> = by_offset.iter().map(|&i| offsets[i]).collect();
    let built: Vec<std::result::Result<Vec<Row>, Unresolved>> = rows
        .par_iter()
        .map(|&d| -> Result<_> {
            crate::interrupt::check()?;
            let a = sorted.partition_point(|&x| x < d - 0.5 * thickness);
            let b = sorted.partition_point(|&x| x <= d + 0.5 * thickness);
            if b - a < 2 {
                return Ok(Ok(Vec::new()));
            }
            let slab: Vec<[f64; 3]> =
                by_offset[a..b].iter().map(|&i| (cloud.p(i) - (offsets[i] - d) * n).into()).collect();
            let chain = bead_chain(&slab, None, None, Chain::Tree)?;
            let line: Vec<V3> = chain.order.iter().map(|&k| V3::from(slab[k])).collect();
            let line = Polyline::new(&line, chain.closed);
            let found = row_points(
                &line,
                chain.closed,
                spacing,
                tolerance,
                limit,
                r,
                |q| cloud.local(q, n),
                |q| cloud.open(q, n),
            );
            let points = match found {
                Ok(points) => points,
                Err(u) => return Ok(Err(u)),
            };
            let points = points
                .into_iter()
                .map(|(on, normal, value)| (on, normal, cloud.across(on, n).map_or(0.0, |(k, _)| k), value))
                .collect();
            let row = Row { points, closed: chain.closed };
            Ok(Ok(if row.points.is_empty() { Vec::new() } else { row.pieces(r, CUT_STRAY * tolerance) }))
        })
        .collect::<Result<_>>()?;
    // The worst place decides the spacing the cloud needs: a point without a fit, else the largest
    // disagreement.
    if let Some(worst) =
        built.iter().filter_map(|b| b.as_ref().err()).max_by(|a, b| a.disagreement.total_cmp(&b.disagreement))
    {
        return Err(cloud.too_sparse(*worst, h, limit));
    }
    let built: Vec<Vec<Row>> = built.into_iter().map(|b| b.unwrap_or_default()).collect();

    // 3. Joining.
    let mut out =
        GrindingPaths { without_stock: allowance.iter().filter(|a| a.is_nan()).count(), ..Default::default() };
    let mut open_rows = 0usize;
    let feed_step = options.feed_step.unwrap_or(DEFAULT_FEED_STEP);
    let mut held = f64::NAN;
    for (row, d) in built.into_iter().zip(rows).flat_map(|(pieces, d)| pieces.into_iter().map(move |row| (row, d))) {
        let mut points = row.points;
        if row.closed {
            if let Some(end) = out.points.last().map(|&p| V3::from(p)) {
                let start = (0..points.len())
                    .min_by(|&a, &b| (points[a].0 - end).norm().total_cmp(&(points[b].0 - end).norm()))
                    .unwrap_or(0);
                points.rotate_left(start);
            }
        } else {
            if open_rows % 2 == 1 {
                points.reverse();
            }
            open_rows += 1;
        }
        let k = out.row_offsets.len();
        for (p, normal, kappa, allowance) in points {
            out.points.push(p.into());
            out.normals.push(normal.into());
            out.row.push(k);
            out.curvature.push(kappa);
            out.tool_fits.push(!(kappa < 0.0 && -1.0 / kappa <= r));
            out.allowance.push(allowance);
            if let Some(model) = options.removal {
                let wanted = model.feed(allowance);
                if held.is_nan() || (wanted - held).abs() > feed_step * held {
                    held = wanted;
                }
            }
            out.feed.push(held);
        }
        out.row_offsets.push(d);
        out.row_closed.push(row.closed);
    }
    Ok(out)
}

/// Row offsets from `first` to `last`: each step the smallest plane step of the samples (sorted
/// by offset) between the row and the next (module docs, step 1).
fn row_offsets(samples: &[(f64, f64)], first: f64, last: f64, flat: f64, thickness: f64) -> Vec<f64> {
    if last <= first {
        return vec![0.5 * (first + last)];
    }
    let band_min = |a: f64, b: f64| -> Option<f64> {
        let i = samples.partition_point(|s| s.0 < a);
        let j = samples.partition_point(|s| s.0 <= b);
        samples[i..j].iter().map(|s| s.1).reduce(f64::min)
    };
    let mut rows = vec![first];
    let mut d = first;
    loop {
        let mut step = band_min(d - 0.5 * thickness, d + 0.5 * thickness).unwrap_or(flat);
        loop {
            match band_min(d, d + step) {
                Some(m) if m < step => step = m,
                _ => break,
            }
        }
        // A step shorter than a thousandth of the flat one would stall on a degenerate sample.
        let step = step.max(1e-3 * flat);
        if d + step >= last {
            // The rows would overshoot the last: every gap shrinks in proportion so that the last
            // row lands on it, rather than one short gap at the end.
            let end = d + step;
            let scale = (last - first) / (end - first);
            rows.push(end);
            return rows.into_iter().map(|x| first + (x - first) * scale).collect();
        }
        d += step;
        rows.push(d);
    }
}

/// Points of a surface with their outward normals and the stock standing above the model there.
#[derive(Clone, Copy)]
pub struct Stock<'a> {
    pub points: &'a [[f64; 3]],
    pub normals: &'a [[f64; 3]],
    pub allowance: &'a [f64],
}

impl Stock<'_> {
    /// Finite points and non-zero normals, one allowance per point: finite, or NaN where
    /// `without_stock` allows a point with no stock measured.
    fn check(&self, prefix: &str, without_stock: bool) -> Result<()> {
        check_finite_points(&format!("{prefix}points"), self.points)?;
        check_finite_points(&format!("{prefix}normals"), self.normals)?;
        if without_stock {
            if let Some(i) = self.allowance.iter().position(|a| a.is_infinite()) {
                return Err(Error::invalid(
                    &format!("{prefix}allowance"),
                    format!(
                        "must be finite, or NaN where no stock was measured; found {} at row {i}",
                        self.allowance[i]
                    ),
                ));
            }
        } else {
            check_finite(&format!("{prefix}allowance"), self.allowance, 1)?;
        }
        if self.normals.len() != self.points.len() || self.allowance.len() != self.points.len() {
            return Err(Error::invalid(
                &format!("{prefix}normals"),
                format!(
                    "{prefix}points, normals and allowance must have one row per point; got {}, {} and {}",
                    self.points.len(),
                    self.normals.len(),
                    self.allowance.len()
                ),
            ));
        }
        if let Some(i) = self.normals.iter().position(|n| V3::from(*n).norm() == 0.0) {
            return Err(Error::invalid(&format!("{prefix}normals"), format!("row {i} is a zero vector")));
        }
        Ok(())
    }
}

/// The stock left over the model at every blank point after a spherical tool of radius
/// `tool_radius` at each path point, sunk by `depths` below the blank (model + allowance) there,
/// has swept the path (module docs), and the nearest path point of each blank point. Negative
/// stock: cut below the model; NaN where the blank's allowance is NaN (no stock measured there). The tool centre moves in straight lines between the points of a
/// row (`rows`: the row of each path point), as a machine interpolates between GOTOs.
pub fn simulate_removal(
    blank: Stock,
    path: Stock,
    rows: &[usize],
    depths: &[f64],
    tool_radius: f64,
) -> Result<(Vec<f64>, Vec<usize>)> {
    blank.check("", true)?;
    path.check("path_", false)?;
    check_finite("depths", depths, 1)?;
    check_positive("tool_radius", tool_radius, "mm")?;
    let m = path.points.len();
    if depths.len() != m {
        return Err(Error::invalid("depths", format!("expected one per path point ({m}), got {}", depths.len())));
    }
    if m == 0 {
        return Err(Error::invalid("path_points", "the path is empty"));
    }
    if rows.len() != m {
        return Err(Error::invalid("rows", format!("expected one per path point ({m}), got {}", rows.len())));
    }
    let (points, normals, allowance) = (blank.points, blank.normals, blank.allowance);
    let (path_points, path_normals, path_allowance) = (path.points, path.normals, path.allowance);
    let r = tool_radius;
    // Tool centres: the contact point sunk to allowance − depth above the model, one radius out.
    let at: Vec<V3> = (0..m)
        .map(|j| {
            let nj = V3::from(path_normals[j]).normalize();
            V3::from(path_points[j]) + (path_allowance[j] - depths[j] + r) * nj
        })
        .collect();
    // The sweep between two points of a row as tool positions close enough that the ridges
    // between them stay below SWEEP_TOLERANCE (δ²/8R).
    let delta = (8.0 * r * SWEEP_TOLERANCE).sqrt();
    let mut centres: Vec<[f64; 3]> = Vec::with_capacity(m);
    for j in 0..m {
        centres.push(at[j].into());
        if j + 1 < m && rows[j + 1] == rows[j] {
            let pieces = ((at[j + 1] - at[j]).norm() / delta).ceil().min(1e6) as usize;
            for k in 1..pieces {
                centres.push(at[j].lerp(&at[j + 1], k as f64 / pieces as f64).into());
            }
        }
    }
    let contacts = PointIndex::new(path_points)?;
    // A tool position matters to q only if it holds a point of q's normal line between the
    // lowest any tool sinks to and the top of q's stock: its centre lies within R of that segment.
    let bottom = (0..m).map(|j| path_allowance[j] - depths[j]).fold(0.0f64, f64::min);
    let index = PointIndex::new(&centres)?;
    Ok((0..points.len())
        .into_par_iter()
        .map(|i| {
            if allowance[i].is_nan() {
                return (f64::NAN, contacts.nearest(&points[i]).0);
            }
            let q = V3::from(points[i]);
            let nq = V3::from(normals[i]).normalize();
            // The chords of q's normal line inside each tool position; the stock's top comes
            // down to a chord's lower end only if the chord reaches the top as it stands then
            // (a chord wholly below it is the line passing through the part to a tool on the
            // other side), so they are taken from the highest upper end down. The tools are
            // looked up along the stretch of the line from the top down to the lowest any tool
            // sinks to, and a tenth of a radius more (a cut a few µm below the model, common
            // where a feed removes a little more than asked, then needs no second look); where
            // the cut goes below that (a tool inside the part: a path point off the surface, or a
            // wrong normal), the stretch is lengthened until the cut ends in it, so the depth
            // reported is the cut's, not the end of the stretch looked at.
            let high = allowance[i];
            let mut low = bottom.min(high) - 0.1 * r;
            let mut left = high;
            for _ in 0..SIMULATION_REACHES {
                let mut chords: Vec<(f64, f64)> = Vec::new();
                let middle = q + nq * (0.5 * (low + high));
                index.for_each_within(&middle.into(), r + 0.5 * (high - low), |j| {
                    let w = V3::from(centres[j]) - q;
                    let b = w.dot(&nq);
                    let across2 = w.norm_squared() - b * b;
                    if across2 < r * r {
                        let half = (r * r - across2).sqrt();
                        chords.push((b - half, b + half));
                    }
                });
                chords.sort_by(|a, b| b.1.total_cmp(&a.1));
                left = high;
                for (under, over) in chords {
                    if over < left {
                        break;
                    }
                    left = left.min(under);
                }
                if left >= low {
                    break;
                }
                // A tool that carries the cut on below `left` holds a point of the line there:
                // its centre lies within R of the stretch down to `left`.
                low = left;
            }
            (left, contacts.nearest(&points[i]).0)
        })
        .unzip())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// z = a·sin(2πy/λ) over [0, 40] × [0, 60], rows along x (section normal y).
    fn wavy(spacing: f64, a: f64, lambda: f64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<f64>) {
        let (mut p, mut nn, mut al) = (Vec::new(), Vec::new(), Vec::new());
        let k = 2.0 * std::f64::consts::PI / lambda;
        for i in 0..=(40.0 / spacing) as usize {
            for j in 0..=(60.0 / spacing) as usize {
                let (x, y) = (i as f64 * spacing, j as f64 * spacing);
                let slope = a * k * (k * y).cos();
                p.push([x, y, a * (k * y).sin()]);
                nn.push(V3::new(0.0, -slope, 1.0).normalize().into());
                al.push(0.2 + 0.001 * x + 0.002 * y);
            }
        }
        (p, nn, al)
    }

    #[test]
    fn rows_lie_on_their_planes_on_the_surface_and_carry_the_allowance() {
        let (p, nn, al) = wavy(0.5, 2.0, 40.0);
        let o = GrindingOptions {
            tool_radius: 8.0,
            scallop_height: 0.01,
            section_normal: [0.0, 1.0, 0.0],
            thickness: None,
            spacing: Some(1.0),
            tolerance: None,
            fit_radius: None,
            removal: None,
            feed_step: None,
        };
        let g = grinding_paths(&p, &nn, &al, &o).unwrap();
        let k = 2.0 * std::f64::consts::PI / 40.0;
        assert!(g.row_offsets.len() > 40);
        for (i, q) in g.points.iter().enumerate() {
            assert!((q[1] - g.row_offsets[g.row[i]]).abs() < 1e-9);
            assert!((q[2] - 2.0 * (k * q[1]).sin()).abs() < 2e-4, "{q:?}");
            assert!((g.allowance[i] - (0.2 + 0.001 * q[0] + 0.002 * q[1])).abs() < 1e-6);
            let curvature = 2.0 * k * k * (k * q[1]).sin() / (1.0 + (2.0 * k * (k * q[1]).cos()).powi(2)).powf(1.5);
            assert!((g.curvature[i] - curvature).abs() < 0.1 * k * k * 2.0, "{} {}", g.curvature[i], curvature);
        }
        // Alternating open rows.
        let first: Vec<f64> = (0..2).map(|r| g.points[g.row.iter().position(|&x| x == r).unwrap()][0]).collect();
        assert!(first[0] < 1.0 && first[1] > 39.0, "{first:?}");
    }

    #[test]
    fn rows_are_cut_where_the_wheel_cannot_move_straight() {
        // Points every 0.1 mm along x with normal +y, then across a thin edge to normal −y.
        let point = |x: f64, up: bool| {
            (V3::new(x, if up { 0.5 } else { -0.5 }, 0.0), V3::new(0.0, if up { 1.0 } else { -1.0 }, 0.0), 0.0, 0.3)
        };
        let mut points: Vec<_> = (0..10).map(|k| point(0.1 * k as f64, true)).collect();
        points.extend((0..10).rev().map(|k| point(0.1 * k as f64, false)));
        let open = Row { points: points.clone(), closed: false }.pieces(10.0, 0.005);
        assert_eq!(open.iter().map(|p| p.points.len()).collect::<Vec<_>>(), vec![10, 10]);
        assert!(open.iter().all(|p| !p.closed));
        // Closed: the two turns (at the far end and back at the start) cut it into the two sides.
        let closed = Row { points: points.clone(), closed: true }.pieces(10.0, 0.005);
        assert_eq!(closed.len(), 2);
        assert_eq!(closed[0].points[0].0, points[10].0);
        assert_eq!(closed[1].points[0].0, points[0].0);
        // One side alone, closed: nothing to cut but the closing move... which turns nothing.
        let side = Row { points: points[..10].to_vec(), closed: true }.pieces(10.0, 0.005);
        assert_eq!(side.len(), 1);
        assert!(side[0].closed);
    }

    /// A straight row along x whose fits give the normal +z up to x = 0.5 and one tilted by
    /// `jump` about x beyond: the halving closes in on x = 0.5.
    fn row_with_a_jump(jump: f64, open: bool, gap: bool) -> std::result::Result<Vec<(V3, V3, f64)>, Unresolved> {
        let line = Polyline::new(&[V3::new(0.0, 0.0, 0.0), V3::new(1.0, 0.0, 0.0)], false);
        let eval = |q: V3| {
            if gap && q.x > 0.4 && q.x < 0.6 {
                return None;
            }
            let normal = if q.x < 0.5 { V3::z() } else { V3::new(0.0, -jump.sin(), jump.cos()) };
            Some((q, normal, 0.3))
        };
        row_points(&line, false, 0.25, 0.0025, 0.02, 10.0, eval, |_| open)
    }

    #[test]
    fn the_wheel_rolls_over_fits_that_disagree_a_little_and_a_row_is_refused_where_they_disagree_more() {
        // 3° between the two fits: a straight move would stray 6.9 µm (R θ²/8), within twice the scallop height
        // (20 µm), so the wheel turns over the point in moves of at most the tolerance, and the row is whole.
        let points = row_with_a_jump(3f64.to_radians(), false, false).unwrap();
        assert!(points.windows(2).all(|w| centre_stray(w[0].0, w[0].1, w[1].0, w[1].1, 10.0) <= 0.0025 + 1e-12));
        let row = Row { points: points.iter().map(|&(p, m, a)| (p, m, 0.0, a)).collect(), closed: false };
        assert_eq!(row.pieces(10.0, 0.005).len(), 1);
        // 8°: 49 µm. Before, the row was cut there (342 pieces for 157 rows on a 1.5 mm blade cloud); now the
        // cloud is too sparse for the surface at the point, and how far the fits disagree is told.
        let refused = row_with_a_jump(8f64.to_radians(), false, false).unwrap_err();
        assert!((refused.at.x - 0.5).abs() < 1e-3);
        assert!((refused.disagreement - 10.0 * 8f64.to_radians().powi(2) / 8.0).abs() < 1e-3);
        // Where the row runs off the cloud the same disagreement is a gap in the data: the link is left for
        // `Row::pieces` to cut.
        let points = row_with_a_jump(8f64.to_radians(), true, false).unwrap();
        let row = Row { points: points.iter().map(|&(p, m, a)| (p, m, 0.0, a)).collect(), closed: false };
        assert_eq!(row.pieces(10.0, 0.005).len(), 2);
        // No fit at all in the middle: cut where the cloud ends, refused where it surrounds the row.
        assert_eq!(row_with_a_jump(8f64.to_radians(), true, true).map(|p| p.len()).ok(), Some(4));
        assert!(row_with_a_jump(8f64.to_radians(), false, true).unwrap_err().disagreement.is_infinite());
    }

    #[test]
    fn the_simulation_reports_a_cut_at_its_full_depth() {
        // One blank point on the plane z = 0 with 0.3 mm of stock, and a row of wheels (R 10 mm) whose centres
        // step down its normal line from z = 9 to z = -31: each cuts from the top down into the next, so the
        // stock left is -41 mm. The stretch of the line looked at first ends at the lowest sinking (z = 0); before,
        // the cut was followed only as far as wheels within reach of that stretch (-20 mm).
        let blank = Stock { points: &[[0.0, 0.0, 0.0]], normals: &[[0.0, 0.0, 1.0]], allowance: &[0.3] };
        let path: Vec<[f64; 3]> = (0..11).map(|k| [0.0, 0.0, -1.0 - 4.0 * k as f64]).collect();
        let normals = vec![[0.0, 0.0, 1.0]; 11];
        let allowance = vec![0.3; 11];
        let path = Stock { points: &path, normals: &normals, allowance: &allowance };
        let (left, _) = simulate_removal(blank, path, &[0; 11], &[0.3; 11], 10.0).unwrap();
        assert!((left[0] + 41.0).abs() < 1e-9, "{}", left[0]);
    }

    #[test]
    fn the_feed_removes_the_allowance_within_the_limits() {
        let m = RemovalModel::new(0.02, [0.8, -0.6, 0.9], 20.0, 30.0, [1.0, 40.0]).unwrap();
        for depth in [0.05, 0.1, 0.3] {
            let f = m.feed(depth);
            if f > 1.0 && f < 40.0 {
                assert!((m.removal(f) - depth).abs() < 1e-12 * depth.max(1.0));
            }
        }
        assert_eq!(m.feed(-0.1), 40.0);
        assert_eq!(m.feed(1e9), 1.0);
        assert!(RemovalModel::new(0.02, [0.8, 0.0, 0.9], 20.0, 30.0, [1.0, 40.0]).is_err());
        assert!(RemovalModel::new(0.02, [0.8, -0.6, 0.9], 20.0, 30.0, [4.0, 1.0]).is_err());
    }
}
