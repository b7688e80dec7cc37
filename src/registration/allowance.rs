//! Machining allowance (SPEC R7; paper 004 §1.2, eq 2–10): how much stock the blank leaves over
//! the model, measured from each model point along its outward normal to the blank's local
//! plane (the least-squares plane of the k nearest blank points). Positive where the blank
//! envelops the model, negative where it does not (the part would come out short there).
use crate::error::{check_finite_points, Error, Result};
use crate::spatial::PointIndex;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;

/// The plane's normal is this far from the model normal (|cos| below, 60°): the plane is not
/// the blank's surface over the point but a neighbouring feature — an edge, or a scan line
/// whose points all lie in one section — so the line along the normal meets it far off, and
/// the allowance there is NaN (reported, not guessed). Stock varies far more gently.
const GRAZING: f64 = 0.5;

/// Blank points of each local plane by default: enough for a stable plane through sensor
/// noise, few enough to stay local at the blank's sampling.
pub const PLANE_POINTS: usize = 8;

/// The signed allowance of each model point along its unit outward normal, mm: `t` with
/// `p + t·v` on the plane of the `k` nearest blank points (eq 10 as SPEC R7 corrects it:
/// `t = n·(q0 − p) / (n·v)`). NaN where that plane is inclined more than 60° to the
/// model surface (|n·v| < 0.5).
pub fn allowance(model: &[[f64; 3]], normals: &[[f64; 3]], blank: &[[f64; 3]], k: usize) -> Result<Vec<f64>> {
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
            let (q0, n) = blank_plane(&index, blank, &p, k);
            along_normal(&p, &v, &q0, &n)
        })
        .collect())
}

/// `k` for a plane of `k` blank points: at least 3, at most all of them.
pub(super) fn check_k(k: usize, blank: usize) -> Result<()> {
    if k < 3 {
        return Err(Error::invalid("k", format!("a plane needs at least 3 blank points, got k = {k}")));
    }
    if k > blank {
        return Err(Error::invalid("k", format!("{k} neighbors asked, but the blank has {blank} points")));
    }
    Ok(())
}

/// The least-squares plane of the `k` blank points nearest to `p`: its centroid and unit normal
/// (eq 3–5; the sign of the normal is arbitrary).
pub(super) fn blank_plane(
    index: &PointIndex,
    blank: &[[f64; 3]],
    p: &Vector3<f64>,
    k: usize,
) -> (Vector3<f64>, Vector3<f64>) {
    let near = index.knn(&[p[0], p[1], p[2]], k);
    let q0 = near.iter().fold(Vector3::zeros(), |a, &(i, _)| a + Vector3::from(blank[i])) / k as f64;
    let cov = near.iter().fold(Matrix3::zeros(), |a, &(i, _)| {
        let d = Vector3::from(blank[i]) - q0;
        a + d * d.transpose()
    });
    let eig = SymmetricEigen::new(cov);
    let smallest = (0..3).min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b])).unwrap_or(0);
    (q0, eig.eigenvectors.column(smallest).into_owned())
}

/// `t` with `p + t·v` on the plane through `q0` with normal `n`; NaN where it grazes.
pub(super) fn along_normal(p: &Vector3<f64>, v: &Vector3<f64>, q0: &Vector3<f64>, n: &Vector3<f64>) -> f64 {
    let nv = n.dot(v);
    if nv.abs() < GRAZING {
        f64::NAN
    } else {
        n.dot(&(q0 - p)) / nv
    }
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
        let (model, normals) = sphere(3000, 20.0);
        // The blank sampled at about 0.2 mm: 4π R² / 0.04 points.
        for (radius, expected) in [(20.5, 0.5), (19.8, -0.2)] {
            let n = (4.0 * std::f64::consts::PI * radius * radius / 0.04) as usize;
            let (blank, _) = sphere(n, radius);
            let a = allowance(&model, &normals, &blank, 8).unwrap();
            let worst = a.iter().map(|t| (t - expected).abs()).fold(0.0, f64::max);
            assert!(worst < 0.003, "R {radius}: worst error {worst}");
        }
    }

    #[test]
    fn bad_input_is_refused_by_name() {
        let (model, normals) = sphere(10, 1.0);
        let err = |n: &[[f64; 3]], k| allowance(&model, n, &model, k).unwrap_err().to_string();
        assert!(err(&normals, 2).contains("k"));
        assert!(err(&normals, 11).contains("k"));
        assert!(err(&normals[..5], 8).contains("model_normals"));
        let mut zero = normals.clone();
        zero[3] = [0.0; 3];
        assert!(err(&zero, 8).contains("model_normals"));
    }
}
