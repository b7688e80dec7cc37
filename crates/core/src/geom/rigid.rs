//! Rigid transforms as 4×4 homogeneous matrices, and the Kabsch (Procrustes) fit.
use nalgebra::{Matrix3, Matrix4, Vector3};

/// `T · (p, 1)` for a homogeneous rigid (or mirror) transform.
#[inline]
pub fn transform_point(t: &Matrix4<f64>, p: [f64; 3]) -> [f64; 3] {
    [
        t[(0, 0)] * p[0] + t[(0, 1)] * p[1] + t[(0, 2)] * p[2] + t[(0, 3)],
        t[(1, 0)] * p[0] + t[(1, 1)] * p[1] + t[(1, 2)] * p[2] + t[(1, 3)],
        t[(2, 0)] * p[0] + t[(2, 1)] * p[1] + t[(2, 2)] * p[2] + t[(2, 3)],
    ]
}

/// `T · (v, 0)`: directions and normals are turned, not moved.
#[inline]
pub fn transform_vector(t: &Matrix4<f64>, v: [f64; 3]) -> [f64; 3] {
    [
        t[(0, 0)] * v[0] + t[(0, 1)] * v[1] + t[(0, 2)] * v[2],
        t[(1, 0)] * v[0] + t[(1, 1)] * v[1] + t[(1, 2)] * v[2],
        t[(2, 0)] * v[0] + t[(2, 1)] * v[1] + t[(2, 2)] * v[2],
    ]
}

/// One transform applied to many rows, in parallel: points (`vectors = false`) or directions.
pub fn transform_rows(t: &Matrix4<f64>, rows: &[[f64; 3]], vectors: bool) -> Vec<[f64; 3]> {
    use rayon::prelude::*;
    rows.par_iter().map(|&p| if vectors { transform_vector(t, p) } else { transform_point(t, p) }).collect()
}

/// Result of [`kabsch`]: `dst ≈ rotation · src + translation`.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidFit {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
    /// Root mean square of the residual distances.
    pub rms: f64,
}

/// Least-squares rigid transform taking `src` onto `dst` (Kabsch 1976, with the reflection
/// guard). Works for coplanar points (e.g. profiler points, all with y = 0) as long as they
/// are not collinear; returns `None` when the points are collinear or fewer than 3.
pub fn kabsch(src: &[[f64; 3]], dst: &[[f64; 3]]) -> Option<RigidFit> {
    let n = src.len();
    if n < 3 || dst.len() != n {
        return None;
    }
    let mean = |pts: &[[f64; 3]]| {
        let mut m = Vector3::zeros();
        for p in pts {
            m += Vector3::from(*p);
        }
        m / n as f64
    };
    let (ms, md) = (mean(src), mean(dst));
    let mut h = Matrix3::zeros();
    for (s, d) in src.iter().zip(dst) {
        h += (Vector3::from(*s) - ms) * (Vector3::from(*d) - md).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut sv = svd.singular_values;
    // Rank < 2 means the points are collinear: the turn about their line is undetermined.
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| sv[b].total_cmp(&sv[a]));
    if sv[order[1]] <= 1e-12 * sv[order[0]].max(f64::MIN_POSITIVE) {
        return None;
    }
    let v = v_t.transpose();
    let mut d = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        // Reflection guard: flip the axis of the smallest singular value.
        d[(order[2], order[2])] = -1.0;
        sv[order[2]] = -sv[order[2]];
    }
    let rotation = v * d * u.transpose();
    let translation = md - rotation * ms;
    let mut ss = 0.0;
    for (s, dpt) in src.iter().zip(dst) {
        ss += (rotation * Vector3::from(*s) + translation - Vector3::from(*dpt)).norm_squared();
    }
    Some(RigidFit { rotation, translation, rms: (ss / n as f64).sqrt() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{mount_rotation, rot_z};

    #[test]
    fn kabsch_recovers_transform_from_coplanar_points() {
        // Profiler-like points: all in the SCS plane y = 0.
        let src: Vec<[f64; 3]> = (0..40).map(|i| [(i as f64 - 20.0) * 0.5, 0.0, ((i * 7) % 11) as f64 * 0.1]).collect();
        let r = mount_rotation(0.3, -0.2, 1.1);
        let t = Vector3::new(10.0, -4.0, 2.5);
        let dst: Vec<[f64; 3]> = src.iter().map(|p| (r * Vector3::from(*p) + t).into()).collect();
        let fit = kabsch(&src, &dst).unwrap();
        assert!((fit.rotation - r).abs().max() < 1e-12);
        assert!((fit.translation - t).abs().max() < 1e-12);
        assert!(fit.rms < 1e-12);
    }

    #[test]
    fn kabsch_rejects_collinear_points() {
        let src: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 0.0, 0.0]).collect();
        let dst: Vec<[f64; 3]> = src.iter().map(|p| (rot_z(0.5) * Vector3::from(*p)).into()).collect();
        assert!(kabsch(&src, &dst).is_none());
    }
}
