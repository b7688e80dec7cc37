//! The stock field (issue #32 §3): the allowance found where the blank was measured, as each
//! blank point's distance from the model, and carried to the model points.
//!
//! Every blank point b has a foot f on the model (its closest point there) and a stock
//! a = (b − f)·n(f). A point of the line p + t·v along the model normal at p has p for its foot,
//! so the line meets the blank where the stock field a(f) is taken at f = p: the allowance at p
//! is that field, fitted about p from the blank points' stocks. Where the blank is the model
//! offset by a stock that varies gently, the field is smooth whatever the model's curvature
//! does: where a fillet meets a flank, model and blank turn at the same place and the field
//! carries neither the turn nor the curvature jump — which the blank's own local surface (the
//! quadric, fitted to blank points alone) cannot follow at 0.75–1 mm spacing (BENCHMARKS.md).
//!
//! A blank point's foot is found from its nearest model point p: in the plane of p's normal n and
//! the blank point's tangent offset t̂, the model's section is taken as the circle of its normal
//! curvature κ = t̂ᵀ S t̂ there, S the shape operator fitted to the normals of p's nearest model
//! neighbours (dn = S·dp: exact for circles and cylinders). The circle, not the osculating
//! paraboloid, because a model sampled every millimetre round an edge of 0.8 mm radius puts a
//! blank point's foot half a millimetre from p, where the paraboloid is 19 µm off the circle. Where
//! p's neighbours lie on one line (a model sampled in sections), the curvature across the line is
//! not seen: it is taken as a cylinder's where the sections cross an edge, as a helicoid's (0)
//! on a twisted flank ([`ModelShape::shape_operator`]). A foot is read only near p or where the
//! model was sampled beyond p in its direction ([`Reach::ahead`]). The model's own sampling sets the
//! error where the curvature jumps: a jump Δκ between two model points d apart leaves up to
//! Δκ·(d/2)²/2 (BENCHMARKS.md: with the model sampled every 0.15–0.5 mm, edges of 1.5 blank
//! spacings are within 6.3 µm; every 1 mm both ways, the field alone was 10–20 µm off, where the
//! blank's quadric held 1–15 µm at blank spacings of 0.5–0.75 mm). So the model's normals must be the part's (CAD), and where the
//! model is sampled more coarsely than the blank (its fourth nearest point farther than the blank's
//! spacing) the blank's own quadric measures the point instead ([`ModelShape::coarser_than`]).
//!
//! The field about p is a weighted least-squares quadratic in the feet's tangent coordinates
//! (taken along the chord's tangent direction at the chord's length, so that a field wrapping
//! round an edge is not compressed), with the quadric's Gaussian weights exp(−d²/h²), h = 1.5
//! blank spacings; feet whose model normal faces away from p's (the other side of a thin edge)
//! are left out. The blank's normal there, for the envelope fit, is v − ∇a (first order in the
//! stock's slope).
use super::allowance::{tangent_frame, COVER, CUT, GAP, GRAZING, WIDTH};
use crate::error::{Error, Result};
use crate::spatial::PointIndex;
use nalgebra::{SMatrix, SVector, Vector3};
use rayon::prelude::*;

type V3 = Vector3<f64>;

/// Model neighbours of a shape operator: the nearest few, so that it sees one side of a
/// curvature jump where it can (a foot lies within half a model spacing of its point).
const SHAPE_NEIGHBORS: usize = 4;
/// The neighbours lie on one line when the lesser spread of their offsets is below this share of
/// the greater.
const ON_A_LINE: f64 = 0.05;
/// A foot whose model normal is more than 120° from the point's is on the other side of an edge.
const FACING: f64 = -0.5;
/// A foot is read from a model point's shape only where one of its nearest model points lies at
/// least this share of the foot's offset ahead of it, in its direction.
const AHEAD: f64 = 0.5;
/// The nearest model points looked at for that (more than the shape's four: a model sampled
/// at random leaves gaps between its nearest few).
const REACH_NEIGHBORS: usize = 8;
/// ... but any foot within this share of the blank's spacing of its model point is read.
const FREE: f64 = 0.5;
/// The least total weight of the feet a field is fitted to (about three feet within h): fewer,
/// and the blank's quadric measures the point.
const MIN_WEIGHT: f64 = 3.0;
/// At most this many feet in a fit (within 2.5 h there are about 45 on a surface sampled at the
/// blank's spacing, more where the model is concave).
const FIELD_POINTS: usize = 128;

/// The model's points with their unit normals, tangent frames and shape operators, indexed.
pub(super) struct ModelShape {
    points: Vec<V3>,
    normals: Vec<V3>,
    frames: Vec<(V3, V3)>,
    /// (S_xx, S_xy, S_yy) in the point's tangent frame.
    shape: Vec<[f64; 3]>,
    /// The distance to the farthest of those neighbours: how finely the model is sampled there.
    sampling: Vec<f64>,
    /// Where the nearest model points lie about each point ([`Reach`]).
    reach: Vec<Reach>,
    index: PointIndex,
}

impl ModelShape {
    /// `normals` are checked non-zero by the caller.
    pub(super) fn new(model: &[[f64; 3]], normals: &[[f64; 3]]) -> Result<ModelShape> {
        if model.is_empty() {
            return Err(Error::invalid("model_points", "must hold at least one point"));
        }
        let index = PointIndex::new(model)?;
        let points: Vec<V3> = model.iter().map(|p| V3::from(*p)).collect();
        let normals: Vec<V3> = normals.iter().map(|n| V3::from(*n).normalize()).collect();
        let frames: Vec<(V3, V3)> = normals.iter().map(tangent_frame).collect();
        let mut shape =
            ModelShape { points, normals, frames, shape: Vec::new(), sampling: Vec::new(), reach: Vec::new(), index };
        let found: Vec<([f64; 3], f64, Reach)> =
            (0..model.len()).into_par_iter().map(|i| shape.shape_operator(i)).collect();
        shape.shape = found.iter().map(|f| f.0).collect();
        shape.sampling = found.iter().map(|f| f.1).collect();
        shape.reach = found.iter().map(|f| f.2).collect();
        Ok(shape)
    }

    /// S with dn = S·dp over the nearest neighbours (tangent parts in point i's frame), least
    /// squares; on a line of neighbours its two observable terms, the third that of a cylinder
    /// through them. And the distance to the farthest of those neighbours, and where they lie.
    fn shape_operator(&self, i: usize) -> ([f64; 3], f64, Reach) {
        let (e1, e2) = self.frames[i];
        let (p, n) = (self.points[i], self.normals[i]);
        // One query for both: the shape's neighbours are the nearest of the reach's.
        let reach_near = self.index.knn(&p.into(), REACH_NEIGHBORS + 1);
        let near = &reach_near[..reach_near.len().min(SHAPE_NEIGHBORS + 1)];
        let offsets: Vec<([f64; 2], [f64; 2])> = near
            .iter()
            .filter(|&&(j, d2)| j != i && d2 > 0.0)
            .map(|&(j, _)| {
                let (dp, dn) = (self.points[j] - p, self.normals[j] - n);
                ([dp.dot(&e1), dp.dot(&e2)], [dn.dot(&e1), dn.dot(&e2)])
            })
            .collect();
        let sampling = near.last().map_or(f64::INFINITY, |&(_, d2)| d2.sqrt());
        if offsets.is_empty() {
            return ([0.0; 3], sampling, Reach::NOWHERE);
        }
        // The principal axes (a, b) of the offsets' spread.
        let (cxx, cxy, cyy) = offsets
            .iter()
            .fold((0.0, 0.0, 0.0), |(xx, xy, yy), (d, _)| (xx + d[0] * d[0], xy + d[0] * d[1], yy + d[1] * d[1]));
        let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        let (ca, sa) = (angle.cos(), angle.sin());
        let mid = 0.5 * (cxx + cyy);
        let radius = (0.25 * (cxx - cyy).powi(2) + cxy * cxy).sqrt();
        let on_a_line = mid - radius < ON_A_LINE * (mid + radius);
        // Rows n_a = s_aa·a + s_ab·b and n_b = s_ab·a + s_bb·b.
        let (mut m, mut r) = (SMatrix::<f64, 3, 3>::zeros(), SVector::<f64, 3>::zeros());
        for (d, dn) in &offsets {
            let (a, b) = (ca * d[0] + sa * d[1], -sa * d[0] + ca * d[1]);
            let (na, nb) = (ca * dn[0] + sa * dn[1], -sa * dn[0] + ca * dn[1]);
            for (row, value) in [(SVector::<f64, 3>::new(a, b, 0.0), na), (SVector::<f64, 3>::new(0.0, a, b), nb)] {
                m += row * row.transpose();
                r += row * value;
            }
        }
        let unknowns = if on_a_line { 2 } else { 3 };
        let trace = m.trace();
        let mut s = [0.0; 3];
        let solved = if on_a_line {
            let mut m2 = m.fixed_view::<2, 2>(0, 0).into_owned();
            m2[(0, 0)] += 1e-9 * trace;
            m2[(1, 1)] += 1e-9 * trace;
            m2.cholesky().map(|c| c.solve(&r.fixed_rows::<2>(0).into_owned()).iter().copied().collect::<Vec<f64>>())
        } else {
            for k in 0..3 {
                m[(k, k)] += 1e-9 * trace;
            }
            m.cholesky().map(|c| c.solve(&r).iter().copied().collect::<Vec<f64>>())
        };
        if let Some(v) = solved.filter(|v| v.iter().all(|x| x.is_finite())) {
            s[..unknowns].copy_from_slice(&v);
        }
        if on_a_line && s[0].abs() > 1e-9 {
            // Across the line the curvature is not seen. Where the sections cross an edge (the
            // normal turns far more along them than across, |s_ab/s_aa| ≤ 0.25), the edge is a
            // cylinder (Gaussian curvature 0): s_bb = s_ab²/s_aa. Taken as 0 there, a section 5°
            // off square to a twisted blade's edge of 0.8 mm radius read its feet two
            // millimetres across 16 µm off. On a twisted flank (|s_ab/s_aa| ≥ 0.5) the surface is
            // a helicoid, whose curvature along the span is 0; linear between the two.
            let ratio = (s[1] / s[0]).abs();
            let weight = ((0.5 - ratio) / 0.25).clamp(0.0, 1.0);
            s[2] = weight * s[1] * s[1] / s[0];
        }
        let [saa, sab, sbb] = s;
        // Back to (e1, e2): S = R·S_ab·Rᵀ, R's columns the axes a = (ca, sa), b = (−sa, ca).
        let operator = [
            saa * ca * ca - 2.0 * sab * ca * sa + sbb * sa * sa,
            (saa - sbb) * ca * sa + sab * (ca * ca - sa * sa),
            saa * sa * sa + 2.0 * sab * ca * sa + sbb * ca * ca,
        ];
        let mut reach = Reach { axis: (ca, sa), offsets: [[0.0; 2]; REACH_NEIGHBORS], count: 0, on_a_line };
        for &(j, d2) in &reach_near {
            if j != i && d2 > 0.0 && reach.count < REACH_NEIGHBORS {
                let dp = self.points[j] - p;
                reach.offsets[reach.count] = [dp.dot(&e1), dp.dot(&e2)];
                reach.count += 1;
            }
        }
        (operator, sampling, reach)
    }

    /// The model is sampled more coarsely than the blank at model point `i` (its farthest
    /// shape neighbour beyond the blank's `spacing`): the stock field would read a shape the
    /// model does not resolve there, and the blank's own quadric is the better measure.
    pub(super) fn coarser_than(&self, i: usize, spacing: f64) -> bool {
        self.sampling[i] > spacing
    }

    /// The stock field of `blank` (in the model's frame, point spacing `spacing`); None where
    /// every model point is coarser than the blank (the quadric measures them all).
    pub(super) fn field(&self, blank: &[[f64; 3]], spacing: f64) -> Result<Option<StockField>> {
        if self.sampling.iter().all(|&d| d > spacing) {
            return Ok(None);
        }
        StockField::new(self, blank, spacing).map(Some)
    }

    /// A blank point's foot on the model, its stock (signed, along the model's outward normal
    /// there) and the model's unit normal at the foot; None beyond the centre of curvature.
    fn foot(&self, b: &V3, spacing: f64) -> Option<(V3, f64, V3)> {
        let (i, _) = self.index.nearest(&(*b).into());
        let (e1, e2) = self.frames[i];
        let (p, n) = (self.points[i], self.normals[i]);
        let w = b - p;
        let (x, y, z) = (w.dot(&e1), w.dot(&e2), w.dot(&n));
        let t = x.hypot(y);
        // Beyond p's neighbours its shape says nothing: a CAD mesh's flat has vertices only at
        // its ends, and the last arc vertex's curvature carried over the flat put feet up to
        // 0.3 mm off. Along a line of neighbours (a section) only the offset along it counts;
        // across the sections the curvature is the cylinder's or the helicoid's (above).
        if !self.reach[i].ahead(x, y, FREE * spacing) {
            return None;
        }
        let (dx, dy) = if t > 0.0 { (x / t, y / t) } else { (1.0, 0.0) };
        let [sxx, sxy, syy] = self.shape[i];
        // The normal section along the offset, as the circle of its normal curvature κ (centre
        // at −n/κ): the point's distance from it and the foot, at the angle φ round the centre.
        let kappa = sxx * dx * dx + 2.0 * sxy * dx * dy + syy * dy * dy;
        let a = 1.0 + kappa * z;
        if !(a > 0.0) {
            return None;
        }
        let stock = (kappa * (t * t + z * z) + 2.0 * z) / ((kappa * t).hypot(a) + 1.0);
        let phi = (kappa * t).atan2(a);
        // The arc φ/κ to the foot (t/a as κ → 0), and sin φ/φ, written so that a flat section is
        // not divided by κ = 0.
        let arc = if phi.abs() > 1e-8 { phi / kappa } else { t / a };
        let sinc = |u: f64| if u.abs() > 1e-8 { u.sin() / u } else { 1.0 };
        let (along, height) = (arc * sinc(phi), -arc * (0.5 * phi).sin() * sinc(0.5 * phi));
        let direction = dx * e1 + dy * e2;
        let foot = p + along * direction + height * n;
        let normal = phi.cos() * n + phi.sin() * direction;
        (stock.is_finite() && foot.iter().all(|c| c.is_finite())).then_some((foot, stock, normal))
    }
}

/// Where a model point's nearest model points lie, in its tangent frame: their offsets, and the
/// axis (cos, sin) of its shape neighbours' spread and whether they lie on one line.
#[derive(Debug, Clone, Copy)]
struct Reach {
    axis: (f64, f64),
    offsets: [[f64; 2]; REACH_NEIGHBORS],
    count: usize,
    on_a_line: bool,
}

impl Reach {
    const NOWHERE: Reach = Reach { axis: (1.0, 0.0), offsets: [[0.0; 2]; REACH_NEIGHBORS], count: 0, on_a_line: false };

    /// The tangent offset (x, y) is no longer than `free`, or a neighbour lies ahead of it: at
    /// least [`AHEAD`] of its length along it (along the line only, where the shape's neighbours
    /// lie on one). A foot failing both lies where the model point's shape was not measured.
    fn ahead(&self, x: f64, y: f64, free: f64) -> bool {
        let (x, y) = if self.on_a_line {
            let (ca, sa) = self.axis;
            let a = ca * x + sa * y;
            (a * ca, a * sa)
        } else {
            (x, y)
        };
        let t2 = x * x + y * y;
        // Within `free` the foot is among the model points whatever its direction: a model
        // sampled at random has gaps between its nearest few, and refusing feet there cost
        // more than it saved (BENCHMARKS.md).
        t2 <= free * free || self.offsets[..self.count].iter().any(|d| d[0] * x + d[1] * y >= AHEAD * t2)
    }
}

/// The blank's feet on the model with their stocks, indexed.
pub(super) struct StockField {
    feet: Vec<[f64; 3]>,
    stock: Vec<f64>,
    normals: Vec<V3>,
    index: PointIndex,
    spacing: f64,
}

impl StockField {
    /// `blank` in the model's frame; `spacing` its point spacing.
    fn new(model: &ModelShape, blank: &[[f64; 3]], spacing: f64) -> Result<StockField> {
        let found: Vec<(V3, f64, V3)> = blank.par_iter().filter_map(|b| model.foot(&V3::from(*b), spacing)).collect();
        let feet: Vec<[f64; 3]> = found.iter().map(|f| f.0.into()).collect();
        let index = PointIndex::new(&feet)?;
        Ok(StockField {
            stock: found.iter().map(|f| f.1).collect(),
            normals: found.iter().map(|f| f.2).collect(),
            feet,
            index,
            spacing,
        })
    }

    /// The stock field at model point `p` of unit normal `v`, and the blank's unit normal there.
    /// None where the blank does not cover p: no foot within 1.5 spacings (a hole), the feet
    /// on one side (beyond the blank's end), a blank surface more than 60° from the model's
    /// normal plane, or a field the feet do not fix.
    pub(super) fn meet(&self, p: &V3, v: &V3) -> Option<(f64, V3)> {
        let s = self.spacing;
        let h = WIDTH * s;
        let near = self.index.knn_within(&(*p).into(), FIELD_POINTS, CUT * h);
        if near.first().is_none_or(|&(_, d2)| d2.sqrt() > GAP * s) {
            return None;
        }
        let (e1, e2) = tangent_frame(v);
        type M6 = SMatrix<f64, 6, 6>;
        type V6 = SVector<f64, 6>;
        let (mut m, mut r) = (M6::zeros(), V6::zeros());
        let (mut sw, mut mean, mut spread) = (0.0, [0.0; 2], 0.0);
        for &(j, d2) in &near {
            if self.normals[j].dot(v) < FACING {
                continue;
            }
            let d = V3::from(self.feet[j]) - p;
            let (mut x, mut y) = (d.dot(&e1) / h, d.dot(&e2) / h);
            let across = x.hypot(y);
            if across > 0.0 {
                let chord = d2.sqrt() / h / across;
                (x, y) = (x * chord, y * chord);
            }
            let w = (-d2 / (h * h)).exp();
            let phi = V6::from([1.0, x, y, x * x, x * y, y * y]);
            m += w * phi * phi.transpose();
            r += w * self.stock[j] * phi;
            sw += w;
            mean = [mean[0] + w * x, mean[1] + w * y];
            spread += w * (x * x + y * y);
        }
        if !(sw >= MIN_WEIGHT) || mean[0].hypot(mean[1]) / sw > COVER * (spread / sw).sqrt() {
            return None;
        }
        // The quadratic where the feet fix it, else the plane (few feet: the field's slope only).
        let (a, gx, gy) = solve(&m, &r).or_else(|| {
            let m3 = m.fixed_view::<3, 3>(0, 0).into_owned();
            solve(&m3, &r.fixed_rows::<3>(0).into_owned())
        })?;
        let normal = (v - (gx * e1 + gy * e2) / h).normalize();
        (normal.dot(v) >= GRAZING && a.is_finite()).then_some((a, normal))
    }
}

/// The weighted least-squares coefficients' first three (value, slope in x and y), by Cholesky;
/// None where a pivot ratio below 1e-12 says the points do not fix them.
fn solve<const N: usize>(m: &SMatrix<f64, N, N>, r: &SVector<f64, N>) -> Option<(f64, f64, f64)> {
    let mut m = *m;
    let trace = m.trace();
    for k in 1..N {
        m[(k, k)] += 1e-9 * trace;
    }
    let chol = m.cholesky()?;
    let l = chol.l();
    let (lo, hi) = (0..N).fold((f64::INFINITY, 0.0f64), |(lo, hi), i| (lo.min(l[(i, i)]), hi.max(l[(i, i)])));
    if !(lo > 0.0 && (lo / hi).powi(2) > 1e-12) {
        return None;
    }
    let c = chol.solve(r);
    c.iter().all(|x| x.is_finite()).then(|| (c[0], c[1], c[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registration::allowance::tests::sphere;
    use crate::registration::{allowance, BlankOptions, BlankSurface};
    use crate::testing::lcg;
    use nalgebra::Rotation3;

    /// A stadium (flats 2·`half` long joined by half circles of radius `r`, the curvature jumping
    /// from 1/r to 0 where they meet) extruded along z and turned off the axes: the point at
    /// arc length σ round the section and height z, and its outward normal.
    struct Stadium {
        half: f64,
        r: f64,
        turn: Rotation3<f64>,
    }

    impl Stadium {
        fn perimeter(&self) -> f64 {
            4.0 * self.half + 2.0 * std::f64::consts::PI * self.r
        }

        fn at(&self, sigma: f64, z: f64, offset: f64) -> (V3, V3) {
            let (l, r, pi) = (2.0 * self.half, self.r, std::f64::consts::PI);
            let s = sigma.rem_euclid(self.perimeter());
            let (q, n) = if s < l {
                (V3::new(-self.half + s, r, z), V3::y())
            } else if s < l + pi * r {
                let a = (s - l) / r;
                let n = V3::new(a.sin(), a.cos(), 0.0);
                (V3::new(self.half, 0.0, z) + r * n, n)
            } else if s < 2.0 * l + pi * r {
                (V3::new(self.half - (s - l - pi * r), -r, z), -V3::y())
            } else {
                let a = (s - 2.0 * l - pi * r) / r;
                let n = V3::new(-a.sin(), -a.cos(), 0.0);
                (V3::new(-self.half, 0.0, z) + r * n, n)
            };
            (self.turn * (q + offset * n), self.turn * n)
        }

        /// Rows `rows` apart in z over `z`, points `step` apart round each (a random phase per
        /// row when `seed` is given).
        fn sample(
            &self,
            step: f64,
            rows: f64,
            z: (f64, f64),
            offset: &dyn Fn(f64, f64) -> f64,
            seed: Option<&mut u64>,
        ) -> Vec<(V3, V3, f64)> {
            let mut seed = seed;
            let n = (self.perimeter() / step).round() as usize;
            let mut out = Vec::new();
            let mut h = z.0;
            while h <= z.1 {
                let phase = seed.as_deref_mut().map_or(0.0, lcg);
                for i in 0..n {
                    let sigma = (i as f64 + phase) * self.perimeter() / n as f64;
                    let a = offset(sigma, h);
                    let (p, v) = self.at(sigma, h, a);
                    out.push((p, v, a));
                }
                h += rows;
            }
            out
        }
    }

    fn stadium() -> Stadium {
        Stadium { half: 5.0, r: 1.5, turn: Rotation3::from_euler_angles(0.3, -0.5, 0.8) }
    }

    /// The worst |error| of the allowance on the stadium's model (σ every 0.15 mm, rows every 2
    /// mm), the blank sampled every `spacing` mm with the stock `offset`.
    fn worst(surface: BlankSurface, spacing: f64, offset: &dyn Fn(f64, f64) -> f64) -> f64 {
        let part = stadium();
        let model = part.sample(0.15, 2.0, (2.0, 18.0), &|_, _| 0.0, None);
        let mut seed = 11u64;
        let blank: Vec<[f64; 3]> =
            part.sample(spacing, spacing, (-2.0, 22.0), offset, Some(&mut seed)).iter().map(|b| b.0.into()).collect();
        let points: Vec<[f64; 3]> = model.iter().map(|m| m.0.into()).collect();
        let normals: Vec<[f64; 3]> = model.iter().map(|m| m.1.into()).collect();
        let options = BlankOptions { surface, k: None, spacing: None };
        let a = allowance(&points, &normals, &blank, &options).unwrap();
        // The truth: a point of the model normal's line has the model point for its foot.
        let perimeter = part.perimeter();
        let n = (perimeter / 0.15).round() as usize;
        a.iter()
            .enumerate()
            .map(|(i, &t)| {
                let sigma = (i % n) as f64 * perimeter / n as f64;
                let z = 2.0 + 2.0 * (i / n) as f64;
                (t - offset(sigma, z)).abs()
            })
            .fold(0.0, |w, e| if e.is_nan() || w.is_nan() { f64::NAN } else { w.max(e) })
    }

    #[test]
    fn a_fillet_meeting_a_flank_is_followed_at_a_coarse_spacing() {
        // Edges of 1.5 blank spacings where the curvature jumps from 1/1.5 mm to 0: the stock
        // field holds them within 0.2 µm (uniform stock) and 0.8 µm (varying); the blank's own
        // quadric, which must fit the jump, is 7.7–7.8 µm off there.
        let uniform = |_: f64, _: f64| 0.3;
        let perimeter = stadium().perimeter();
        let varying =
            |sigma: f64, z: f64| 0.3 + 0.1 * (std::f64::consts::TAU * sigma / perimeter + 0.4).sin() * (z / 9.0).cos();
        for (name, offset) in [("uniform", &uniform as &dyn Fn(f64, f64) -> f64), ("varying", &varying)] {
            let stock = worst(BlankSurface::Stock, 1.0, offset);
            assert!(stock < 0.002, "{name}: stock field worst error {stock}");
            let quadric = worst(BlankSurface::Quadric, 1.0, offset);
            assert!(quadric > 0.005, "{name}: the quadric was expected to miss the joins: {quadric}");
        }
    }

    #[test]
    fn where_the_model_is_coarser_than_the_blank_the_quadric_measures() {
        // The model every 1 mm round the stadium and 1 mm apart, the blank every 0.5 mm: every
        // model point's fourth neighbour is farther than the blank's spacing, so every point is
        // the quadric's; with the blank every 1.5 mm, none is.
        let part = stadium();
        let model = part.sample(1.0, 1.0, (4.0, 16.0), &|_, _| 0.0, None);
        let points: Vec<[f64; 3]> = model.iter().map(|m| m.0.into()).collect();
        let normals: Vec<[f64; 3]> = model.iter().map(|m| m.1.into()).collect();
        let shape = ModelShape::new(&points, &normals).unwrap();
        for (spacing, coarser) in [(0.5, true), (1.5, false)] {
            let mut seed = 3u64;
            let blank: Vec<[f64; 3]> = part
                .sample(spacing, spacing, (0.0, 20.0), &|_, _| 0.3, Some(&mut seed))
                .iter()
                .map(|b| b.0.into())
                .collect();
            let options = |surface| BlankOptions { surface, k: None, spacing: Some(spacing) };
            let stock = allowance(&points, &normals, &blank, &options(BlankSurface::Stock)).unwrap();
            let quadric = allowance(&points, &normals, &blank, &options(BlankSurface::Quadric)).unwrap();
            let same = stock.iter().zip(&quadric).filter(|(a, b)| a.to_bits() == b.to_bits()).count();
            assert!((0..points.len()).all(|i| shape.coarser_than(i, spacing) == coarser));
            assert_eq!(same == points.len(), coarser, "spacing {spacing}: {same} of {} equal", points.len());
        }
    }

    #[test]
    fn the_stock_between_concentric_spheres_is_their_radii_difference() {
        // Every normal section of a sphere is the circle the foot is found on: exact to rounding
        // and the shape operators' fit.
        for (r, delta) in [(5.0, 0.3), (5.0, -0.2), (20.0, 0.5)] {
            let (model, normals) = sphere(4000, r);
            let radius = r + delta;
            let (blank, _) = sphere((4.0 * std::f64::consts::PI * radius * radius / 0.09) as usize, radius);
            let a = allowance(&model, &normals, &blank, &BlankOptions::default()).unwrap();
            let worst = a.iter().map(|t| (t - delta).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-4, "r {r} δ {delta}: worst error {worst}");
        }
    }

    #[test]
    fn shape_operators_of_a_cylinder_sampled_in_sections() {
        // Sections every 2 mm, points every 0.15 mm round them: the neighbours lie on a line,
        // the curvature along the axis is taken as 0 and the one round it is 1/r.
        let part = Stadium { half: 0.0, r: 2.0, turn: Rotation3::identity() };
        let model = part.sample(0.15, 2.0, (0.0, 10.0), &|_, _| 0.0, None);
        let points: Vec<[f64; 3]> = model.iter().map(|m| m.0.into()).collect();
        let normals: Vec<[f64; 3]> = model.iter().map(|m| m.1.into()).collect();
        let shape = ModelShape::new(&points, &normals).unwrap();
        for i in (0..points.len()).step_by(37) {
            let (e1, e2) = shape.frames[i];
            let [sxx, sxy, syy] = shape.shape[i];
            // S along the axis z and round the section.
            let along = V3::z();
            let round = V3::z().cross(&V3::from(normals[i]));
            let s = |a: &V3, b: &V3| {
                let (a1, a2, b1, b2) = (a.dot(&e1), a.dot(&e2), b.dot(&e1), b.dot(&e2));
                sxx * a1 * b1 + sxy * (a1 * b2 + a2 * b1) + syy * a2 * b2
            };
            assert!((s(&round, &round) - 0.5).abs() < 1e-3, "{i}: {}", s(&round, &round));
            assert!(s(&along, &along).abs() < 1e-9 && s(&along, &round).abs() < 1e-9);
        }
    }
}
