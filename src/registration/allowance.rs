//! Machining allowance (SPEC R7; paper 004 §1.2, eq 2–10): how much stock the blank leaves over
//! the model, measured from each model point along its outward normal to the blank's local
//! surface around it, fitted to the k nearest blank points. Positive where the blank envelops
//! the model, negative where it does not (the part would come out short there).
//!
//! The paper's local surface is the least-squares plane (eq 3–5). A plane through k points of a
//! curved blank sits below it by their mean sag, κ·d²/2: 4–5 µm on a 5 mm radius sampled at
//! 0.2 mm, 35 µm at a blade's leading edge. The local quadric (a height field of second degree
//! over that plane) follows the curvature and leaves only third-order terms, so it is the
//! default; the plane is kept as the paper's method.
use crate::error::{check_finite_points, Error, Result};
use crate::spatial::PointIndex;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};
use rayon::prelude::*;

/// The blank's surface is this far from the model normal (|cos| below, 60°): it is not the
/// blank over the point but a neighbouring feature — an edge, or a scan line whose points all
/// lie in one section — so the line along the normal meets it far off, and the allowance there
/// is NaN (reported, not guessed). Stock varies far more gently.
const GRAZING: f64 = 0.5;

/// How far (rad) the quadric may turn across its points before the plane is used instead.
const MAX_TURN: f64 = 0.5;

/// Blank points of each local surface by default: enough for a stable fit through sensor
/// noise, few enough to stay local at the blank's sampling.
pub const PLANE_POINTS: usize = 8;

/// The local surface fitted to the k nearest blank points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlankSurface {
    /// The least-squares plane (paper 004 eq 3–5).
    Plane,
    /// A quadric height field over that plane (needs k ≥ 6; falls back to the plane where the
    /// points do not fix one, e.g. all on one scan line, or where the surface turns by more
    /// than 0.5 rad across them, e.g. round a thin edge).
    Quadric,
}

impl BlankSurface {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "plane" => Ok(BlankSurface::Plane),
            "quadric" => Ok(BlankSurface::Quadric),
            _ => Err(Error::invalid("surface", format!("expected 'quadric' or 'plane', got {name:?}"))),
        }
    }
}

/// The signed allowance of each model point along its unit outward normal, mm: `t` with
/// `p + t·v` on the local `surface` of the `k` nearest blank points (for the plane, eq 10 as
/// SPEC R7 corrects it: `t = n·(q0 − p) / (n·v)`). NaN where that surface is inclined more
/// than 60° to the model surface where the line meets it (|n·v| < 0.5).
pub fn allowance(
    model: &[[f64; 3]],
    normals: &[[f64; 3]],
    blank: &[[f64; 3]],
    k: usize,
    surface: BlankSurface,
) -> Result<Vec<f64>> {
    check_finite_points("model_points", model)?;
    check_finite_points("blank_points", blank)?;
    super::check_normals("model_normals", normals, model.len())?;
    check_k(k, blank.len())?;
    let index = PointIndex::new(blank)?;
    Ok(model
        .par_iter()
        .zip(normals)
        .map(|(p, v)| {
            let (p, v) = (Vector3::from(*p), Vector3::from(*v).normalize());
            meet(&index, blank, &p, &v, k, surface).map_or(f64::NAN, |(t, _)| t)
        })
        .collect())
}

/// `k` for a local surface of `k` blank points: at least 3, at most all of them.
pub(super) fn check_k(k: usize, blank: usize) -> Result<()> {
    if k < 3 {
        return Err(Error::invalid("k", format!("a plane needs at least 3 blank points, got k = {k}")));
    }
    if k > blank {
        return Err(Error::invalid("k", format!("{k} neighbors asked, but the blank has {blank} points")));
    }
    Ok(())
}

/// Where the line `p + t·v` meets the local `surface` of the `k` blank points nearest to `p`:
/// `t` and the unit normal of that surface there (its sign arbitrary). None where the surface
/// is inclined more than 60° to the line's normal plane, or the line misses the quadric.
pub(super) fn meet(
    index: &PointIndex,
    blank: &[[f64; 3]],
    p: &Vector3<f64>,
    v: &Vector3<f64>,
    k: usize,
    surface: BlankSurface,
) -> Option<(f64, Vector3<f64>)> {
    let near: Vec<Vector3<f64>> = index.knn(&[p[0], p[1], p[2]], k).iter().map(|&(i, _)| blank[i].into()).collect();
    let q0 = near.iter().sum::<Vector3<f64>>() / k as f64;
    let cov = near.iter().fold(Matrix3::zeros(), |a, q| a + (q - q0) * (q - q0).transpose());
    let eig = SymmetricEigen::new(cov);
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let n = eig.eigenvectors.column(order[0]).into_owned();
    let plane = || {
        let nv = n.dot(v);
        (nv.abs() >= GRAZING).then(|| (n.dot(&(q0 - p)) / nv, n))
    };
    // The quadric corrects the plane for curvature; where the plane itself is not the blank over
    // the point, neither is the quadric.
    if surface == BlankSurface::Plane || k < 6 || n.dot(v).abs() < GRAZING {
        return plane();
    }
    // The height field z = h(x, y) over the plane's frame (x, y along the two larger axes).
    let (e1, e2) = (eig.eigenvectors.column(order[2]).into_owned(), eig.eigenvectors.column(order[1]).into_owned());
    let local = |q: &Vector3<f64>| Vector3::new((q - q0).dot(&e1), (q - q0).dot(&e2), (q - q0).dot(&n));
    let row = |x: f64, y: f64| Vector6::new(1.0, x, y, x * x, x * y, y * y);
    // Scaled by the spread of the points, so that the normal equations are well conditioned.
    let scale = (eig.eigenvalues[order[2]] / k as f64).sqrt().max(1e-12);
    let (mut ata, mut atz) = (Matrix6::<f64>::zeros(), Vector6::<f64>::zeros());
    for q in &near {
        let l = local(q);
        let r = row(l[0] / scale, l[1] / scale);
        ata += r * r.transpose();
        atz += r * l[2];
    }
    // Points that do not spread over two directions (one scan line) do not fix a quadric.
    let fixed = SymmetricEigen::new(ata).eigenvalues;
    if fixed.min() <= 1e-6 * fixed.max() {
        return plane();
    }
    let c = ata.cholesky()?.solve(&atz);
    let (c0, c1, c2) = (c[0], c[1] / scale, c[2] / scale);
    let (c3, c4, c5) = (c[3] / (scale * scale), c[4] / (scale * scale), c[5] / (scale * scale));
    // A height field is a fair model only where the surface turns little over the points: where
    // it turns by more than ~0.5 rad across them (a thin edge, the points wrapping round it) the
    // quadric is not single-valued and the plane is the safer answer.
    let reach = near.iter().map(|q| (local(q).xy()).norm()).fold(0.0, f64::max);
    let bend = SymmetricEigen::new(nalgebra::Matrix2::new(2.0 * c3, c4, c4, 2.0 * c5)).eigenvalues.abs().max();
    if bend * reach > MAX_TURN {
        return plane();
    }
    // z(t) − h(x(t), y(t)) = A t² + B t + C along the line, in the local frame.
    let (pl, vl) = (local(p), Vector3::new(v.dot(&e1), v.dot(&e2), v.dot(&n)));
    let (px, py, pz, vx, vy, vz) = (pl[0], pl[1], pl[2], vl[0], vl[1], vl[2]);
    let a = -(c3 * vx * vx + c4 * vx * vy + c5 * vy * vy);
    let b = vz - c1 * vx - c2 * vy - 2.0 * c3 * px * vx - c4 * (px * vy + py * vx) - 2.0 * c5 * py * vy;
    let cc = pz - c0 - c1 * px - c2 * py - c3 * px * px - c4 * px * py - c5 * py * py;
    let disc = b * b - 4.0 * a * cc;
    if disc < 0.0 || b == 0.0 {
        return None;
    }
    // The root that continues the tangent-plane solution −C/B (stable for small A).
    let t = -2.0 * cc / (b + b.signum() * disc.sqrt());
    let (x, y) = (px + t * vx, py + t * vy);
    if x.hypot(y) > reach {
        return plane(); // met outside the points: an extrapolated quadric
    }
    let grad = Vector3::new(-(c1 + 2.0 * c3 * x + c4 * y), -(c2 + c4 * x + 2.0 * c5 * y), 1.0).normalize();
    let normal = grad[0] * e1 + grad[1] * e2 + grad[2] * n;
    (normal.dot(v).abs() >= GRAZING && t.is_finite()).then_some((t, normal))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// `n` points on a sphere of radius `r` (Fibonacci lattice) and their outward normals.
    pub(crate) fn sphere(n: usize, r: f64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let (s, a) = ((1.0 - z * z).sqrt(), golden * i as f64);
                let u = [s * a.cos(), s * a.sin(), z];
                (u.map(|c| r * c), u)
            })
            .unzip()
    }

    #[test]
    fn allowance_between_concentric_spheres_is_the_radius_difference() {
        // The blank sampled at about 0.2 mm: 4π R² / 0.04 points. The plane sits below a curved
        // blank by the mean sag of its points (~1.2 µm at R 20, ~5 µm at R 5); the quadric
        // follows the curvature.
        for (r, surface, tolerance) in [
            (20.0, BlankSurface::Plane, 0.003),
            (20.0, BlankSurface::Quadric, 0.0005),
            (5.0, BlankSurface::Quadric, 0.0005),
        ] {
            let (model, normals) = sphere(2000, r);
            for delta in [0.5, -0.2] {
                let radius = r + delta;
                let n = (4.0 * std::f64::consts::PI * radius * radius / 0.04) as usize;
                let (blank, _) = sphere(n, radius);
                let a = allowance(&model, &normals, &blank, 8, surface).unwrap();
                let worst = a.iter().map(|t| (t - delta).abs()).fold(0.0, f64::max);
                assert!(worst < tolerance, "{surface:?} r {r} δ {delta}: worst error {worst}");
            }
        }
    }

    #[test]
    fn points_on_one_line_fall_back_to_the_plane_and_a_grazing_surface_is_nan() {
        // A blank of scan lines 2 mm apart, 0.1 mm along each: the 8 nearest points of a model
        // point lie on one line, which fixes a plane only with the next line's points.
        let blank: Vec<[f64; 3]> =
            (0..4000).map(|i| [(i % 200) as f64 * 0.1 - 10.0, (i / 200) as f64 * 2.0 - 20.0, 0.3]).collect();
        let model = [[0.0, 1.0, 0.0], [0.3, -3.0, 0.0]];
        for surface in [BlankSurface::Plane, BlankSurface::Quadric] {
            let a = allowance(&model, &[[0.0, 0.0, 1.0]; 2], &blank, 30, surface).unwrap();
            assert!(a.iter().all(|t| (t - 0.3).abs() < 1e-12), "{surface:?}: {a:?}");
            let grazing = allowance(&model, &[[1.0, 0.0, 0.2]; 2], &blank, 30, surface).unwrap();
            assert!(grazing.iter().all(|t| t.is_nan()));
        }
    }

    #[test]
    fn bad_input_is_refused_by_name() {
        let (model, normals) = sphere(10, 1.0);
        let err = |n: &[[f64; 3]], k| allowance(&model, n, &model, k, BlankSurface::Quadric).unwrap_err().to_string();
        assert!(err(&normals, 2).contains("k"));
        assert!(err(&normals, 11).contains("k"));
        assert!(err(&normals[..5], 8).contains("model_normals"));
        let mut zero = normals.clone();
        zero[3] = [0.0; 3];
        assert!(err(&zero, 8).contains("model_normals"));
        assert!(BlankSurface::parse("cubic").unwrap_err().to_string().contains("surface"));
    }
}
