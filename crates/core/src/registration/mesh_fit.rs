//! The best fit of a scan to a CAD mesh, with only the motions the set-up allows.
//!
//! Each iteration pairs every scan point with its closest point on the triangles (not on the
//! mesh's vertices: a coarse CAD tessellation has few) and minimises the squared distances to
//! the paired triangles' planes (point to plane, Chen & Medioni 1992) by a Gauss–Newton step in
//! the free motions only. The motions are the machine's letters: X, Y, Z shifts and A, B, C
//! rotations about lines parallel to X, Y, Z through a pivot; with a rotary `axis`, C turns
//! about that line instead. The pose is built from the six numbers every iteration,
//!
//!   T = Shift(x, y, z) · Pivot · Rz(c) Ry(b) Rx(a) · Pivot⁻¹ · init,
//!
//! so a held motion is exactly zero, not a small residue of composed updates (as composing
//! free rotations about X and Z would leave one about Y). Correspondences, fitness, rmse and
//! the stop rule are those of `icp` (Open3D's), with the rmse taken over the distances to the
//! triangles, not to their planes.
use super::icp::{check_init, rigid, IcpResult, IcpStep, ROUNDING};
use crate::error::{check_finite_points, Error, Result};
use crate::geom::{rot_x, rot_y, rot_z, transform_point};
use crate::mesh::{unit_face_normals, Closest, TriangleBvh};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix4, Matrix6, Vector3, Vector6};
use rayon::prelude::*;

/// Letters of the motions, in the order of `Motion`'s numbers.
pub const MOTIONS: [char; 6] = ['x', 'y', 'z', 'a', 'b', 'c'];

/// Which of the six motions are free.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dof(pub [bool; 6]);

impl Dof {
    pub const ALL: Dof = Dof([true; 6]);

    /// Reads the machine letters, e.g. "xyzabc" or "xyc" (any order, either case).
    pub fn parse(letters: &str) -> Result<Self> {
        let mut free = [false; 6];
        for ch in letters.chars() {
            let Some(k) = MOTIONS.iter().position(|&m| m == ch.to_ascii_lowercase()) else {
                return Err(Error::invalid(
                    "dof",
                    format!("{ch:?} is not a motion: use the letters x y z (shifts) and a b c (rotations about X Y Z)"),
                ));
            };
            if free[k] {
                return Err(Error::invalid("dof", format!("{ch:?} is given twice in {letters:?}")));
            }
            free[k] = true;
        }
        if !free.contains(&true) {
            return Err(Error::invalid("dof", "names no motion: give at least one of x y z a b c"));
        }
        Ok(Dof(free))
    }

    /// The letters of the free motions.
    pub fn letters(&self) -> String {
        MOTIONS.iter().zip(self.0).filter(|(_, f)| *f).map(|(m, _)| *m).collect()
    }
}

/// A rotary axis: C turns about the line through `point` along `direction`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotaryAxis {
    pub point: [f64; 3],
    pub direction: [f64; 3],
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshFitOptions {
    /// Largest distance of a correspondence, mm.
    pub max_distance: f64,
    pub max_iterations: usize,
    pub relative_fitness: f64,
    pub relative_rmse: f64,
    pub dof: Dof,
    pub axis: Option<RotaryAxis>,
}

impl MeshFitOptions {
    /// Every motion free, 30 iterations, both thresholds 1e-6 (Open3D's criteria).
    pub fn new(max_distance: f64) -> Self {
        MeshFitOptions {
            max_distance,
            max_iterations: 30,
            relative_fitness: 1e-6,
            relative_rmse: 1e-6,
            dof: Dof::ALL,
            axis: None,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct MeshFit {
    /// transformation, fitness, rmse (to the triangles), correspondences, iterations,
    /// converged and history, as `icp` defines them.
    pub icp: IcpResult,
    /// x, y, z (mm) and a, b, c (rad) of the fit, after `init`; exactly 0 where held.
    pub motion: [f64; 6],
    /// Free motions the scan does not fix (a plane leaves its own shifts and turn free, a
    /// cylinder its turn about the axis): held at 0, named by letter.
    pub undetermined: String,
}

/// Where the rotations turn: a frame whose z is the rotary axis (or the machine's Z) and whose
/// origin is the pivot.
struct Pivot {
    origin: Vector3<f64>,
    frame: Matrix3<f64>,
}

impl Pivot {
    fn new(axis: Option<RotaryAxis>) -> Result<Self> {
        let Some(ax) = axis else {
            return Ok(Pivot { origin: Vector3::zeros(), frame: Matrix3::identity() });
        };
        let d = Vector3::from(ax.direction);
        if !(ax.point.iter().chain(&ax.direction).all(|v| v.is_finite()) && d.norm() > 0.0) {
            return Err(Error::invalid("axis", "needs a finite point and a non-zero direction"));
        }
        let z = d.normalize();
        // A and B then turn about the machine's X and Y as far as the axis allows: x is X made
        // square to the axis (Y when the axis lies along X).
        let seed = if z.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let x = (seed - z * z.dot(&seed)).normalize();
        let y = z.cross(&x);
        Ok(Pivot { origin: Vector3::from(ax.point), frame: Matrix3::from_columns(&[x, y, z]) })
    }

    /// The pose of the six numbers, and its derivative along each of them applied to `p`.
    fn pose(&self, m: &[f64; 6]) -> Matrix4<f64> {
        let r = self.frame * rot_z(m[5]) * rot_y(m[4]) * rot_x(m[3]) * self.frame.transpose();
        rigid(r, Vector3::new(m[0], m[1], m[2]) + self.origin - r * self.origin)
    }

    /// ∂(pose · p)/∂m for the three rotations, at m, for a point `p` already moved by `init`.
    fn rotation_partials(&self, m: &[f64; 6], p: &Vector3<f64>) -> [Vector3<f64>; 3] {
        let (rx, ry, rz) = (rot_x(m[3]), rot_y(m[4]), rot_z(m[5]));
        let (dx, dy, dz) = (turned(Vector3::x(), rx), turned(Vector3::y(), ry), turned(Vector3::z(), rz));
        let local = self.frame.transpose() * (p - self.origin);
        [self.frame * rz * ry * dx * local, self.frame * rz * dy * rx * local, self.frame * dz * ry * rx * local]
    }
}

/// d/da of a rotation by a about the unit axis e is [e]× R(a).
fn turned(axis: Vector3<f64>, r: Matrix3<f64>) -> Matrix3<f64> {
    axis.cross_matrix() * r
}

/// The fit of `points` to the mesh `(vertices, faces)` from `init`.
pub fn fit_to_mesh(
    points: &[[f64; 3]],
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    init: &Matrix4<f64>,
    o: &MeshFitOptions,
) -> Result<MeshFit> {
    if !(o.max_distance.is_finite() && o.max_distance > 0.0) {
        return Err(Error::invalid("max_distance", format!("must be a positive distance, got {}", o.max_distance)));
    }
    for (name, v) in [("relative_fitness", o.relative_fitness), ("relative_rmse", o.relative_rmse)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::invalid(name, format!("must be >= 0, got {v}")));
        }
    }
    check_finite_points("points", points)?;
    if points.is_empty() {
        return Err(Error::invalid("points", "must hold at least one point"));
    }
    if points.len() > u32::MAX as usize {
        return Err(Error::invalid("points", format!("{} points is beyond 2^32", points.len())));
    }
    check_init(init)?;
    let pivot = Pivot::new(o.axis)?;
    let bvh = TriangleBvh::new(vertices, faces)?;
    let normal = unit_face_normals(vertices, faces);
    let started: Vec<[f64; 3]> = points.par_iter().map(|&p| transform_point(init, p)).collect();
    let free: Vec<usize> = (0..6).filter(|&k| o.dof.0[k]).collect();
    let max_d2 = o.max_distance * o.max_distance;
    let mut motion = [0.0; 6];
    let pairs_at = |motion: &[f64; 6]| {
        let pose = pivot.pose(motion);
        let moved: Vec<[f64; 3]> = started.par_iter().map(|&p| transform_point(&pose, p)).collect();
        let closest = bvh.closest_many(&moved);
        (moved, closest)
    };
    let metrics = |closest: &[Closest]| {
        let (mut n, mut sum) = (0usize, 0.0);
        for c in closest {
            if c.distance * c.distance < max_d2 {
                n += 1;
                sum += c.distance * c.distance;
            }
        }
        (n, if n > 0 { (n as f64 / points.len() as f64, (sum / n as f64).sqrt()) } else { (0.0, 0.0) })
    };
    let (mut moved, mut closest) = pairs_at(&motion);
    let (mut used, (mut fitness, mut rmse)) = metrics(&closest);
    let mut history = Vec::new();
    let mut iterations = 0;
    let mut converged = false;
    let mut undetermined = String::new();
    while iterations < o.max_iterations && used > 0 {
        // Normal equations of r = n·(p(m) − c) in the free motions, summed in point order
        // (chunks of fixed size, added in turn) so the result is the same on any thread count.
        let parts: Vec<(Matrix6<f64>, Vector6<f64>)> = (0..moved.len())
            .collect::<Vec<_>>()
            .par_chunks(4096)
            .map(|chunk| {
                let (mut jtj, mut jtr) = (Matrix6::zeros(), Vector6::zeros());
                for &i in chunk {
                    let c = &closest[i];
                    if !(c.distance * c.distance < max_d2) {
                        continue;
                    }
                    let n = normal[c.triangle];
                    let r = n.dot(&(Vector3::from(moved[i]) - Vector3::from(c.point)));
                    let rot = pivot.rotation_partials(&motion, &Vector3::from(started[i]));
                    let row = Vector6::new(n.x, n.y, n.z, n.dot(&rot[0]), n.dot(&rot[1]), n.dot(&rot[2]));
                    jtj += row * row.transpose();
                    jtr += r * row;
                }
                (jtj, jtr)
            })
            .collect();
        let (mut full, mut rhs) = (Matrix6::<f64>::zeros(), Vector6::<f64>::zeros());
        for (a, b) in parts {
            full += a;
            rhs += b;
        }
        let jtj = DMatrix::from_fn(free.len(), free.len(), |i, j| full[(free[i], free[j])]);
        let jtr = DVector::from_iterator(free.len(), free.iter().map(|&m| rhs[m]));
        let Some((step, null)) = solve_free(&jtj, &jtr) else { break };
        undetermined = null.iter().map(|&j| MOTIONS[free[j]]).collect();
        for (j, &m) in free.iter().enumerate() {
            motion[m] -= step[j];
        }
        (moved, closest) = pairs_at(&motion);
        let (n, (f, r)) = metrics(&closest);
        used = n;
        iterations += 1;
        history.push(IcpStep { fitness: f, rmse: r });
        let (df, dr) = ((f - fitness).abs(), (r - rmse).abs());
        (fitness, rmse) = (f, r);
        if used > 0 && df < o.relative_fitness && dr < o.relative_rmse {
            converged = true;
            break;
        }
        if used > 0 && iterations == o.max_iterations {
            // As `icp`: run exactly as asked, converged when the last step changed nothing
            // beyond the thresholds or beyond rounding.
            converged = df <= o.relative_fitness && dr <= o.relative_rmse.max(ROUNDING * o.max_distance);
        }
    }
    let transformation = pivot.pose(&motion) * init;
    Ok(MeshFit {
        icp: IcpResult { transformation, fitness, rmse, correspondences: used, iterations, converged, history },
        motion,
        undetermined,
    })
}

/// The Gauss–Newton step of the normal equations, by the eigen-decomposition of the system
/// scaled to unit diagonal (rotations and shifts in comparable units): directions with an
/// eigenvalue below 1e-10 of the largest are left out (the minimum-norm step), and the free
/// motions they are made of are returned as undetermined. None with no equation at all.
fn solve_free(jtj: &DMatrix<f64>, jtr: &DVector<f64>) -> Option<(DVector<f64>, Vec<usize>)> {
    let k = jtj.nrows();
    let scale = DVector::from_iterator(k, (0..k).map(|i| if jtj[(i, i)] > 0.0 { jtj[(i, i)].sqrt() } else { 1.0 }));
    let a = DMatrix::from_fn(k, k, |i, j| jtj[(i, j)] / (scale[i] * scale[j]));
    let b = DVector::from_iterator(k, (0..k).map(|i| jtr[i] / scale[i]));
    let eig = a.symmetric_eigen();
    let top = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
    if !(top > 0.0) {
        return None;
    }
    let mut x = DVector::zeros(k);
    let mut null = Vec::new();
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        let v = eig.eigenvectors.column(i);
        if l > 1e-10 * top {
            x += v * (v.dot(&b) / l);
        } else {
            null.extend((0..k).filter(|&j| v[j].abs() > 0.3));
        }
    }
    null.sort_unstable();
    null.dedup();
    Some((DVector::from_iterator(k, (0..k).map(|i| x[i] / scale[i])), null))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::lcg;

    /// A closed, lumpy, asymmetric body (a deformed sphere) as a triangle mesh, wound outward.
    fn body(n: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let radius = |th: f64, ph: f64| 20.0 + 3.0 * (2.0 * th).cos() * ph.sin() + 2.0 * (3.0 * ph).sin();
        let mut v = vec![[0.0, 0.0, radius(0.0, 0.0) * 1.3]];
        for i in 1..n {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..2 * n {
                let ph = std::f64::consts::PI * j as f64 / n as f64;
                let r = radius(th, ph);
                v.push([r * th.sin() * ph.cos() * 1.5, r * th.sin() * ph.sin(), r * th.cos() * 1.3]);
            }
        }
        v.push([0.0, 0.0, -radius(std::f64::consts::PI, 0.0) * 1.3]);
        let ring = |i: usize, j: usize| (1 + (i - 1) * 2 * n + j % (2 * n)) as u32;
        let last = (v.len() - 1) as u32;
        let mut f = Vec::new();
        for j in 0..2 * n {
            f.push([0, ring(1, j), ring(1, j + 1)]);
            f.push([last, ring(n - 1, j + 1), ring(n - 1, j)]);
        }
        for i in 1..n - 1 {
            for j in 0..2 * n {
                f.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                f.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        (v, f)
    }

    /// Points on the mesh's triangles (random barycentric weights).
    fn sample(v: &[[f64; 3]], f: &[[u32; 3]], count: usize, seed: &mut u64) -> Vec<[f64; 3]> {
        (0..count)
            .map(|_| {
                let t = f[(lcg(seed) * f.len() as f64) as usize % f.len()];
                let (mut a, mut b) = (lcg(seed), lcg(seed));
                if a + b > 1.0 {
                    (a, b) = (1.0 - a, 1.0 - b);
                }
                let [p, q, r] = t.map(|i| Vector3::from(v[i as usize]));
                (p + a * (q - p) + b * (r - p)).into()
            })
            .collect()
    }

    fn options(dof: &str) -> MeshFitOptions {
        MeshFitOptions {
            dof: Dof::parse(dof).unwrap(),
            max_iterations: 100,
            relative_fitness: 0.0,
            relative_rmse: 0.0,
            ..MeshFitOptions::new(5.0)
        }
    }

    #[test]
    fn every_motion_free_recovers_the_pose_to_1e_9() {
        let (v, f) = body(40);
        let mut seed = 5;
        let on = sample(&v, &f, 3000, &mut seed);
        let pivot = Pivot::new(None).unwrap();
        let truth = [0.4, -0.3, 0.5, 0.02, -0.015, 0.03];
        let scan: Vec<[f64; 3]> =
            on.iter().map(|&p| transform_point(&pivot.pose(&truth).try_inverse().unwrap(), p)).collect();
        let fit = fit_to_mesh(&scan, &v, &f, &Matrix4::identity(), &options("xyzabc")).unwrap();
        let err = (fit.icp.transformation - pivot.pose(&truth)).abs().max();
        assert!(err < 1e-9 && fit.icp.rmse < 1e-9, "pose error {err}, rmse {}", fit.icp.rmse);
        assert!(fit.undetermined.is_empty() && fit.icp.fitness == 1.0);
    }

    #[test]
    fn held_motions_stay_exactly_zero_and_a_rotary_axis_is_used() {
        let (v, f) = body(40);
        let mut seed = 9;
        let on = sample(&v, &f, 3000, &mut seed);
        // A rotary table whose axis is tilted and off the origin; the part sits turned on it and
        // shifted along X and Y.
        let axis = RotaryAxis { point: [3.0, -2.0, 0.0], direction: [0.1, 0.05, 1.0] };
        let pivot = Pivot::new(Some(axis)).unwrap();
        let truth = [0.3, -0.2, 0.0, 0.0, 0.0, 0.04];
        let scan: Vec<[f64; 3]> =
            on.iter().map(|&p| transform_point(&pivot.pose(&truth).try_inverse().unwrap(), p)).collect();
        let o = MeshFitOptions { axis: Some(axis), ..options("xyc") };
        let fit = fit_to_mesh(&scan, &v, &f, &Matrix4::identity(), &o).unwrap();
        assert_eq!([fit.motion[2], fit.motion[3], fit.motion[4]], [0.0; 3]);
        for k in [0, 1, 5] {
            assert!((fit.motion[k] - truth[k]).abs() < 1e-9, "{k}: {} vs {}", fit.motion[k], truth[k]);
        }
    }

    #[test]
    fn a_flat_part_names_the_motions_it_cannot_fix() {
        // A flat, tilted-free plate: its own shifts and turn are not seen by the fit.
        let n = 20u32;
        let v: Vec<[f64; 3]> = (0..n * n).map(|i| [(i % n) as f64 * 2.0, (i / n) as f64 * 2.0, 0.0]).collect();
        let mut f = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let k = j * n + i;
                f.push([k, k + 1, k + n]);
                f.push([k + 1, k + n + 1, k + n]);
            }
        }
        let mut seed = 1;
        let scan: Vec<[f64; 3]> =
            sample(&v, &f, 2000, &mut seed).iter().map(|p| [p[0] * 0.9 + 1.0, p[1] * 0.9 + 1.0, p[2] - 0.3]).collect();
        let fit = fit_to_mesh(&scan, &v, &f, &Matrix4::identity(), &options("xyzc")).unwrap();
        assert!((fit.motion[2] - 0.3).abs() < 1e-12, "{:?}", fit.motion);
        assert_eq!((fit.motion[0], fit.motion[1], fit.motion[5]), (0.0, 0.0, 0.0));
        assert_eq!(fit.undetermined, "xyc");
    }

    #[test]
    fn bad_options_are_refused_by_name() {
        let (v, f) = body(8);
        let p = [[0.0; 3]];
        for (dof, word) in [("xq", "'q'"), ("xx", "twice"), ("", "no motion")] {
            let e = Dof::parse(dof).unwrap_err().to_string();
            assert!(e.contains("dof") && e.contains(word), "{e}");
        }
        let o = MeshFitOptions { axis: Some(RotaryAxis { point: [0.0; 3], direction: [0.0; 3] }), ..options("c") };
        assert!(fit_to_mesh(&p, &v, &f, &Matrix4::identity(), &o).unwrap_err().to_string().contains("axis"));
        let o = MeshFitOptions { max_distance: 0.0, ..options("c") };
        assert!(fit_to_mesh(&p, &v, &f, &Matrix4::identity(), &o).unwrap_err().to_string().contains("max_distance"));
    }
}
