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
//! A blank point's foot is found on the osculating paraboloid of its nearest model point,
//! h(t) = −½ tᵀ S t in that point's tangent frame, S the shape operator fitted to the normals of
//! its nearest model neighbours (dn = S·dp: exact for circles and cylinders). Where those
//! neighbours lie on one line (a model sampled in sections), the curvature across the line is
//! not seen and is taken as 0; that costs κ·d²/2 at a distance d from the line (about 2 µm for
//! a twisted blade's span curvature and sections 4 mm apart). The model's own sampling sets the
//! error where the curvature jumps: a jump Δκ between two model points d apart leaves up to
//! Δκ·(d/2)²/2 (BENCHMARKS.md: a model sampled every 0.15–0.5 mm is within 6 µm at edges of 1.5
//! blank spacings; every 1 mm both ways, 11–19 µm). So the model's normals must be the part's
//! (CAD), and its points at least as dense as the blank's.
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
/// Newton steps to a foot on the paraboloid (quadratic convergence from the tangent-plane foot:
/// three or four reach rounding).
const FOOT_STEPS: usize = 8;
/// A foot whose model normal is more than 120° from the point's is on the other side of an edge.
const FACING: f64 = -0.5;
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
        let mut shape = ModelShape { points, normals, frames, shape: Vec::new(), index };
        shape.shape = (0..model.len()).into_par_iter().map(|i| shape.shape_operator(i)).collect();
        Ok(shape)
    }

    /// S with dn = S·dp over the nearest neighbours (tangent parts in point i's frame), least
    /// squares; on a line of neighbours only its two observable terms.
    fn shape_operator(&self, i: usize) -> [f64; 3] {
        let (e1, e2) = self.frames[i];
        let (p, n) = (self.points[i], self.normals[i]);
        let near = self.index.knn(&p.into(), SHAPE_NEIGHBORS + 1);
        let offsets: Vec<([f64; 2], [f64; 2])> = near
            .iter()
            .filter(|&&(j, d2)| j != i && d2 > 0.0)
            .map(|&(j, _)| {
                let (dp, dn) = (self.points[j] - p, self.normals[j] - n);
                ([dp.dot(&e1), dp.dot(&e2)], [dn.dot(&e1), dn.dot(&e2)])
            })
            .collect();
        if offsets.is_empty() {
            return [0.0; 3];
        }
        // The principal axes (a, b) of the offsets' spread.
        let (cxx, cxy, cyy) = offsets.iter().fold((0.0, 0.0, 0.0), |(xx, xy, yy), (d, _)| {
            (xx + d[0] * d[0], xy + d[0] * d[1], yy + d[1] * d[1])
        });
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
        let [saa, sab, sbb] = s;
        // Back to (e1, e2): S = R·S_ab·Rᵀ, R's columns the axes a = (ca, sa), b = (−sa, ca).
        [
            saa * ca * ca - 2.0 * sab * ca * sa + sbb * sa * sa,
            (saa - sbb) * ca * sa + sab * (ca * ca - sa * sa),
            saa * sa * sa + 2.0 * sab * ca * sa + sbb * ca * ca,
        ]
    }

    /// A blank point's foot on the model, its stock (signed, along the model's outward normal
    /// there) and the model's unit normal at the foot. None where the paraboloid gives no foot.
    fn foot(&self, b: &V3) -> Option<(V3, f64, V3)> {
        let (i, _) = self.index.nearest(&(*b).into());
        let (e1, e2) = self.frames[i];
        let (p, n) = (self.points[i], self.normals[i]);
        let w = b - p;
        let (x, y, z) = (w.dot(&e1), w.dot(&e2), w.dot(&n));
        let [sxx, sxy, syy] = self.shape[i];
        let surface = |tx: f64, ty: f64| {
            let h = -0.5 * (sxx * tx * tx + 2.0 * sxy * tx * ty + syy * ty * ty);
            (h, -(sxx * tx + sxy * ty), -(sxy * tx + syy * ty))
        };
        // Newton on ½|(x, y, z) − (t, h(t))|², from the tangent plane's foot.
        let (mut tx, mut ty) = (x, y);
        for _ in 0..FOOT_STEPS {
            let (h, hx, hy) = surface(tx, ty);
            let (rx, ry, rz) = (tx - x, ty - y, h - z);
            let (gx, gy) = (rx + rz * hx, ry + rz * hy);
            let (mut jxx, mut jxy, mut jyy) = (1.0 + hx * hx - rz * sxx, hx * hy - rz * sxy, 1.0 + hy * hy - rz * syy);
            if !(jxx > 0.0 && jxx * jyy - jxy * jxy > 0.0) {
                // Beyond a centre of curvature: the Gauss–Newton step, which always descends.
                (jxx, jxy, jyy) = (1.0 + hx * hx, hx * hy, 1.0 + hy * hy);
            }
            let det = jxx * jyy - jxy * jxy;
            let (dx, dy) = ((jyy * gx - jxy * gy) / det, (jxx * gy - jxy * gx) / det);
            tx -= dx;
            ty -= dy;
            if dx.abs().max(dy.abs()) <= 1e-12 * (1.0 + tx.abs().max(ty.abs())) {
                break;
            }
        }
        let (h, hx, hy) = surface(tx, ty);
        let local = V3::new(-hx, -hy, 1.0).normalize();
        let stock = (x - tx) * local.x + (y - ty) * local.y + (z - h) * local.z;
        let foot = p + tx * e1 + ty * e2 + h * n;
        let normal = local.x * e1 + local.y * e2 + local.z * n;
        (stock.is_finite() && foot.iter().all(|c| c.is_finite())).then_some((foot, stock, normal))
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
    pub(super) fn new(model: &ModelShape, blank: &[[f64; 3]], spacing: f64) -> Result<StockField> {
        let found: Vec<(V3, f64, V3)> = blank.par_iter().filter_map(|b| model.foot(&V3::from(*b))).collect();
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
        if !(sw > 0.0) || mean[0].hypot(mean[1]) / sw > COVER * (spread / sw).sqrt() {
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
