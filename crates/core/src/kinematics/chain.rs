//! Machine models as chains of elementary transforms (SPEC K7), with the presets of
//! K2+K3 (AC double-swing head with C2 and sensor mount), K5 (AB head, mirror-milling support
//! side) and K6 (AC cradle table).
//!
//! A chain `S1 · S2 · … · Sn` maps coordinates of the last link (sensor, tool, part) into the
//! first (WCS). Each step is rigid or a mirror; angles and translations come from constants or
//! from columns of the axis-position row of a pose.
use crate::error::{Error, Result};
use crate::geom::{mount_rotation, Axis};
use nalgebra::{Matrix3, Matrix4, Vector3};
use rayon::prelude::*;

/// Where a rotation angle comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AngleSource {
    Constant(f64),
    /// Column of the pose row, in radians.
    AxisColumn(usize),
}

#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// Constant translation, mm.
    Translate([f64; 3]),
    /// Translation by pose columns (None = 0), e.g. the linear axes X, Y, Z.
    TranslateAxes([Option<usize>; 3]),
    /// Rotation about a coordinate axis.
    Rotate(Axis, AngleSource),
    /// Constant rotation matrix (e.g. a sensor mount), must be orthonormal.
    Rotation(Matrix3<f64>),
    /// Mirror: diagonal of ±1 (paper 002's support side: (−1, 1, −1)).
    Mirror([f64; 3]),
}

/// One argument of a step as a caller spells it (the Python tuples `("rotate", "z", 0.5)`),
/// before [`Step::parse`] gives it a meaning: the rules and their messages live here, so a
/// binding only converts values.
#[derive(Debug, Clone, PartialEq)]
pub enum StepArg {
    None,
    Text(String),
    Number(f64),
    /// Numbers, row-major, of this shape (a vector, a 3×3 rotation).
    Array(Vec<f64>, Vec<usize>),
    /// A list that is not all numbers (axis names, None).
    List(Vec<StepArg>),
}

/// The step kinds `Step::parse` takes, as the messages list them.
const STEP_KINDS: &str = "translate, translate_axes, rotate, rotate_axis, rotation or mirror";

impl Step {
    /// Step `k` of a chain from its kind and arguments; `axis_names` resolves pose columns given
    /// by name. Errors name `steps` and the step:
    ///
    /// - `("translate", (x, y, z))` constant, mm; `("translate_axes", (cx, cy, cz))` by pose
    ///   columns (an index or an axis name; None for 0);
    /// - `("rotate", "x"|"y"|"z", angle)` constant, rad; `("rotate_axis", "x"|"y"|"z", column)`;
    /// - `("rotation", R)` a constant 3×3 rotation; `("mirror", (sx, sy, sz))` with ±1.
    pub fn parse(k: usize, kind: &str, args: &[StepArg], axis_names: &[String]) -> Result<Step> {
        let bad = |why: String| Error::invalid("steps", format!("step {k}: {why}"));
        let wanted = match kind {
            "translate" | "translate_axes" | "rotation" | "mirror" => 1,
            "rotate" | "rotate_axis" => 2,
            other => return Err(bad(format!("unknown step kind {other:?}; use {STEP_KINDS}"))),
        };
        if args.len() != wanted {
            return Err(bad(format!("{kind:?} needs {wanted} argument(s) after the kind, got {}", args.len())));
        }
        let numbers = |a: &StepArg, shape: &[usize], what: &str| -> Result<Vec<f64>> {
            match a {
                StepArg::Array(v, s) if s == shape => Ok(v.clone()),
                _ => Err(bad(format!("expected {what}"))),
            }
        };
        let vector = |a: &StepArg, what: &str| -> Result<[f64; 3]> {
            let v = numbers(a, &[3], what)?;
            Ok([v[0], v[1], v[2]])
        };
        let axis = |a: &StepArg| -> Result<Axis> {
            match a {
                StepArg::Text(s) => {
                    Axis::parse(s).ok_or_else(|| bad(format!("axis must be \"x\", \"y\" or \"z\", got {s:?}")))
                }
                _ => Err(bad("axis must be \"x\", \"y\" or \"z\"".into())),
            }
        };
        let column = |a: &StepArg| -> Result<usize> {
            match a {
                StepArg::Text(s) => axis_names
                    .iter()
                    .position(|n| n == s)
                    .ok_or_else(|| bad(format!("unknown axis name {s:?}; axes are {axis_names:?}"))),
                StepArg::Number(c) if *c >= 0.0 && c.fract() == 0.0 && *c < usize::MAX as f64 => Ok(*c as usize),
                _ => Err(bad("a pose column is an index or an axis name".into())),
            }
        };
        Ok(match kind {
            "translate" => Step::Translate(vector(&args[0], "a translation (x, y, z) in mm")?),
            "translate_axes" => {
                let items: Vec<StepArg> = match &args[0] {
                    StepArg::List(items) => items.clone(),
                    StepArg::Array(v, s) if s.len() == 1 => v.iter().map(|&c| StepArg::Number(c)).collect(),
                    _ => return Err(bad("needs three columns (None for 0)".into())),
                };
                if items.len() != 3 {
                    return Err(bad(format!("needs three columns, got {}", items.len())));
                }
                let mut c = [None; 3];
                for (slot, item) in c.iter_mut().zip(&items) {
                    *slot = match item {
                        StepArg::None => None,
                        other => Some(column(other)?),
                    };
                }
                Step::TranslateAxes(c)
            }
            "rotate" => match &args[1] {
                StepArg::Number(angle) => Step::Rotate(axis(&args[0])?, AngleSource::Constant(*angle)),
                _ => return Err(bad("angle must be a number (rad)".into())),
            },
            "rotate_axis" => Step::Rotate(axis(&args[0])?, AngleSource::AxisColumn(column(&args[1])?)),
            "rotation" => {
                Step::Rotation(Matrix3::from_row_slice(&numbers(&args[0], &[3, 3], "a 3×3 rotation matrix")?))
            }
            _ => Step::Mirror(vector(&args[0], "a mirror diagonal (±1, ±1, ±1)")?),
        })
    }
    fn max_column(&self) -> Option<usize> {
        match self {
            Step::TranslateAxes(cols) => cols.iter().flatten().copied().max(),
            Step::Rotate(_, AngleSource::AxisColumn(c)) => Some(*c),
            _ => None,
        }
    }

    fn matrix(&self, pose: &[f64]) -> Matrix4<f64> {
        let mut m = Matrix4::identity();
        match self {
            Step::Translate(t) => {
                m.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::from(*t));
            }
            Step::TranslateAxes(cols) => {
                for (k, c) in cols.iter().enumerate() {
                    if let Some(c) = c {
                        m[(k, 3)] = pose[*c];
                    }
                }
            }
            Step::Rotate(axis, source) => {
                let angle = match source {
                    AngleSource::Constant(a) => *a,
                    AngleSource::AxisColumn(c) => pose[*c],
                };
                m.fixed_view_mut::<3, 3>(0, 0).copy_from(&axis.rotation(angle));
            }
            Step::Rotation(r) => {
                m.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
            }
            Step::Mirror(d) => {
                for k in 0..3 {
                    m[(k, k)] = d[k];
                }
            }
        }
        m
    }

    fn describe(&self) -> String {
        match self {
            Step::Translate(t) => format!("translate({}, {}, {})", t[0], t[1], t[2]),
            Step::TranslateAxes(c) => {
                let s = |o: &Option<usize>| o.map_or("0".to_string(), |c| format!("axis[{c}]"));
                format!("translate({}, {}, {})", s(&c[0]), s(&c[1]), s(&c[2]))
            }
            Step::Rotate(a, AngleSource::Constant(v)) => format!("rot_{}({v})", a.name()),
            Step::Rotate(a, AngleSource::AxisColumn(c)) => format!("rot_{}(axis[{c}])", a.name()),
            Step::Rotation(_) => "rotation(R)".to_string(),
            Step::Mirror(d) => format!("mirror({}, {}, {})", d[0], d[1], d[2]),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct KinematicChain {
    steps: Vec<Step>,
    n_axes: usize,
    axis_names: Vec<String>,
}

impl KinematicChain {
    /// A chain over poses with `n_axes` columns (named for messages).
    pub fn new(steps: Vec<Step>, axis_names: Vec<String>) -> Result<Self> {
        let n_axes = axis_names.len();
        for (k, step) in steps.iter().enumerate() {
            if let Some(c) = step.max_column() {
                if c >= n_axes {
                    return Err(Error::invalid(
                        "steps",
                        format!("step {k} ({}) uses axis column {c}, but the chain has {n_axes} axes", step.describe()),
                    ));
                }
            }
            if let Step::Mirror(d) = step {
                if d.iter().any(|v| *v != 1.0 && *v != -1.0) {
                    return Err(Error::invalid(
                        "steps",
                        format!("step {k}: a mirror diagonal holds only ±1, got {d:?}"),
                    ));
                }
            }
            if let Step::Rotation(r) = step {
                let e = (r.transpose() * r - Matrix3::identity()).abs().max();
                if !(e < 1e-9) || r.determinant() < 0.0 {
                    return Err(Error::invalid(
                        "steps",
                        format!("step {k}: rotation matrix is not a proper rotation (‖RᵀR − I‖ = {e:e})"),
                    ));
                }
            }
            let finite = match step {
                Step::Translate(t) => t.iter().all(|v| v.is_finite()),
                Step::Rotate(_, AngleSource::Constant(a)) => a.is_finite(),
                _ => true,
            };
            if !finite {
                return Err(Error::invalid("steps", format!("step {k} ({}) must be finite", step.describe())));
            }
        }
        Ok(KinematicChain { steps, n_axes, axis_names })
    }

    /// SPEC K2 + K3: gantry with AC double-swing head, sixth axis C2 and the sensor mount.
    /// Pose columns X, Y, Z, A, C, C2 (mm, rad). `mount` = (θ, ψ, φ, Δx, Δy, Δz).
    ///
    /// `WCS_T_SCS = [Rz(C)·Rx(A), (X,Y,Z)] · [Rz(C2), L] · [Rz(φ)·Ry(θ)·Rx(ψ), Δ]`.
    pub fn ac_head(c2_offset: [f64; 3], mount: [f64; 6]) -> Result<Self> {
        crate::error::check_finite("c2_offset", &c2_offset, 3)?;
        crate::error::check_finite("mount", &mount, 6)?;
        KinematicChain::new(
            vec![
                Step::TranslateAxes([Some(0), Some(1), Some(2)]),
                Step::Rotate(Axis::Z, AngleSource::AxisColumn(4)),
                Step::Rotate(Axis::X, AngleSource::AxisColumn(3)),
                Step::Translate(c2_offset),
                Step::Rotate(Axis::Z, AngleSource::AxisColumn(5)),
                Step::Translate([mount[3], mount[4], mount[5]]),
                Step::Rotation(mount_rotation(mount[0], mount[1], mount[2])),
            ],
            ["X", "Y", "Z", "A", "C", "C2"].map(String::from).to_vec(),
        )
    }

    /// SPEC K5 (paper 002 eq 1–6): AB double-swing head, support side of mirror milling.
    /// Pose columns X, Y, Z, A, B. Maps tool-frame points to support-side workpiece points:
    /// `mirror(−1,1,−1) · (X,Y,Z) · (−Lba−Lat) · Ry(B) · Lba · Rx(A) · Lat`.
    pub fn ab_mirror_support(lat: [f64; 3], lba: [f64; 3]) -> Result<Self> {
        crate::error::check_finite("lat", &lat, 3)?;
        crate::error::check_finite("lba", &lba, 3)?;
        let back = [-lba[0] - lat[0], -lba[1] - lat[1], -lba[2] - lat[2]];
        KinematicChain::new(
            vec![
                Step::Mirror([-1.0, 1.0, -1.0]),
                Step::TranslateAxes([Some(0), Some(1), Some(2)]),
                Step::Translate(back),
                Step::Rotate(Axis::Y, AngleSource::AxisColumn(4)),
                Step::Translate(lba),
                Step::Rotate(Axis::X, AngleSource::AxisColumn(3)),
                Step::Translate(lat),
            ],
            ["X", "Y", "Z", "A", "B"].map(String::from).to_vec(),
        )
    }

    /// SPEC K6 (paper 003 eq 1): AC cradle table turning about `center` (t = O'_w − O_w).
    /// Pose columns A, C: `P' = Rx(A)·Rz(C)·(P − t) + t` (C turns first, then A).
    pub fn ac_table(center: [f64; 3]) -> Result<Self> {
        crate::error::check_finite("center", &center, 3)?;
        KinematicChain::new(
            vec![
                Step::Translate(center),
                Step::Rotate(Axis::X, AngleSource::AxisColumn(0)),
                Step::Rotate(Axis::Z, AngleSource::AxisColumn(1)),
                Step::Translate([-center[0], -center[1], -center[2]]),
            ],
            ["A", "C"].map(String::from).to_vec(),
        )
    }

    pub fn n_axes(&self) -> usize {
        self.n_axes
    }

    pub fn axis_names(&self) -> &[String] {
        &self.axis_names
    }

    pub fn steps(&self) -> &[Step] {
        &self.steps
    }

    pub fn describe(&self) -> String {
        self.steps.iter().map(Step::describe).collect::<Vec<_>>().join(" · ")
    }

    /// The 4×4 transform for one pose (`pose.len() == n_axes`, finite: checked by callers).
    pub fn transform(&self, pose: &[f64]) -> Matrix4<f64> {
        let mut t = Matrix4::identity();
        for step in &self.steps {
            t *= step.matrix(pose);
        }
        t
    }

    /// Checks a row-major `(F, n_axes)` pose array: shape and finiteness.
    pub fn check_poses(&self, name: &str, poses: &[f64], rows: Option<usize>) -> Result<usize> {
        let w = self.n_axes;
        let names = self.axis_names.join(", ");
        if w == 0 {
            return Ok(rows.unwrap_or(0));
        }
        if !poses.len().is_multiple_of(w) {
            return Err(Error::shape(
                name,
                format!("(F, {w}) with columns {names}"),
                format!("{} values", poses.len()),
            ));
        }
        let f = poses.len() / w;
        if let Some(r) = rows {
            if r != f {
                return Err(Error::shape(
                    name,
                    format!("({r}, {w}): one pose per row of the other input"),
                    format!("({f}, {w})"),
                ));
            }
        }
        crate::error::check_finite(name, poses, w)?;
        Ok(f)
    }

    /// Transforms for every pose, row-major `(F, 4, 4)`, parallel over poses.
    pub fn transforms(&self, poses: &[f64]) -> Result<Vec<f64>> {
        let f = self.check_poses("axes", poses, None)?;
        let w = self.n_axes.max(1);
        let mut out = vec![0.0; f * 16];
        out.par_chunks_mut(16).enumerate().for_each(|(k, o)| {
            let pose = if self.n_axes == 0 { &[][..] } else { &poses[k * w..(k + 1) * w] };
            let t = self.transform(pose);
            for r in 0..4 {
                for c in 0..4 {
                    o[r * 4 + c] = t[(r, c)];
                }
            }
        });
        Ok(out)
    }

    /// Each point with its own pose: `points (N,3)`, `poses (N, n_axes)` → `(N,3)`.
    /// With `vectors = true` the translation is ignored (directions, normals).
    pub fn apply(&self, points: &[f64], poses: &[f64], vectors: bool) -> Result<Vec<f64>> {
        let n = points.len() / 3;
        crate::error::check_finite(if vectors { "vectors" } else { "points" }, points, 3)?;
        self.check_poses("axes", poses, Some(n))?;
        let w = self.n_axes;
        let mut out = vec![0.0; n * 3];
        out.par_chunks_mut(3).enumerate().for_each(|(k, o)| {
            let t = self.transform(&poses[k * w..(k + 1) * w]);
            let p = [points[3 * k], points[3 * k + 1], points[3 * k + 2]];
            let q = if vectors { crate::geom::transform_vector(&t, p) } else { crate::geom::transform_point(&t, p) };
            o.copy_from_slice(&q);
        });
        Ok(out)
    }
}

/// Points and, when given, normals after a table turn.
pub type TurnedPoints = (Vec<[f64; 3]>, Option<Vec<[f64; 3]>>);

/// SPEC K6 (paper 003 eq 1): CAD points and normals turned by an AC cradle table at angles
/// `a`, `c` about `center`: `P' = Rx(a)·Rz(c)·(P − center) + center`, `n' = Rx(a)·Rz(c)·n`.
pub fn ac_table_rotate(
    points: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
    a: f64,
    c: f64,
    center: [f64; 3],
) -> Result<TurnedPoints> {
    if !(a.is_finite() && c.is_finite()) {
        return Err(Error::invalid("a, c", format!("table angles must be finite, got a = {a}, c = {c}")));
    }
    let t = KinematicChain::ac_table(center)?.transform(&[a, c]);
    crate::error::check_finite_points("points", points)?;
    let turned = crate::geom::transform_rows(&t, points, false);
    let normals = match normals {
        None => None,
        Some(nr) => {
            if nr.len() != points.len() {
                return Err(Error::shape(
                    "normals",
                    format!("({}, 3): one normal per point", points.len()),
                    format!("({}, 3)", nr.len()),
                ));
            }
            crate::error::check_finite_points("normals", nr)?;
            Some(crate::geom::transform_rows(&t, nr, true))
        }
    };
    Ok((turned, normals))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{rot_x, rot_y, rot_z, transform_point};
    use crate::testing::lcg;

    #[test]
    fn steps_parse_from_what_a_caller_spells_and_errors_name_the_step() {
        let names: Vec<String> = ["X", "Y", "Z", "A"].map(String::from).to_vec();
        let text = |s: &str| StepArg::Text(s.into());
        let vec3 = |v: [f64; 3]| StepArg::Array(v.to_vec(), vec![3]);
        let parse = |kind: &str, args: &[StepArg]| Step::parse(2, kind, args, &names);
        assert_eq!(parse("translate", &[vec3([1.0, 2.0, 3.0])]), Ok(Step::Translate([1.0, 2.0, 3.0])));
        let cols = StepArg::List(vec![text("X"), StepArg::None, StepArg::Number(2.0)]);
        assert_eq!(parse("translate_axes", &[cols]), Ok(Step::TranslateAxes([Some(0), None, Some(2)])));
        assert_eq!(
            parse("translate_axes", &[vec3([0.0, 1.0, 2.0])]),
            Ok(Step::TranslateAxes([Some(0), Some(1), Some(2)]))
        );
        assert_eq!(
            parse("rotate", &[text("z"), StepArg::Number(0.5)]),
            Ok(Step::Rotate(Axis::Z, AngleSource::Constant(0.5)))
        );
        assert_eq!(
            parse("rotate_axis", &[text("x"), text("A")]),
            Ok(Step::Rotate(Axis::X, AngleSource::AxisColumn(3)))
        );
        let eye = StepArg::Array(Matrix3::<f64>::identity().as_slice().to_vec(), vec![3, 3]);
        assert_eq!(parse("rotation", &[eye]), Ok(Step::Rotation(Matrix3::identity())));
        assert_eq!(parse("mirror", &[vec3([-1.0, 1.0, -1.0])]), Ok(Step::Mirror([-1.0, 1.0, -1.0])));
        for (kind, args, why) in [
            ("spin", vec![text("x")], "unknown step kind"),
            ("rotate", vec![text("x")], "needs 2 argument(s)"),
            ("rotate", vec![text("w"), StepArg::Number(1.0)], "axis must be"),
            ("rotate", vec![text("x"), text("fast")], "angle must be a number"),
            ("rotate_axis", vec![text("x"), text("B")], "unknown axis name \"B\""),
            ("rotate_axis", vec![text("x"), StepArg::Number(1.5)], "a pose column is an index"),
            ("translate", vec![StepArg::Array(vec![1.0, 2.0], vec![2])], "a translation (x, y, z)"),
            ("translate_axes", vec![StepArg::List(vec![text("X")])], "needs three columns, got 1"),
            ("rotation", vec![vec3([1.0, 0.0, 0.0])], "a 3×3 rotation"),
        ] {
            let e = parse(kind, &args).unwrap_err().to_string();
            assert!(e.starts_with("steps: step 2: ") && e.contains(why), "{kind}: {e}");
        }
    }

    /// Paper 002 eq (6), printed closed form.
    fn eq6(p: [f64; 3], ax: [f64; 5], lat: [f64; 3], lba: [f64; 3]) -> [f64; 3] {
        let [xl, yl, zl] = p;
        let [x, y, z, a, b] = ax;
        let (sa, ca, sb, cb) = (a.sin(), a.cos(), b.sin(), b.cos());
        let inner = lba[2] + sa * (yl + lat[1]) + ca * (zl + lat[2]);
        [
            -x - cb * (xl + lat[0] + lba[0]) - sb * inner + lba[0] + lat[0],
            y + ca * (yl + lat[1]) - lat[1] - sa * (zl + lat[2]),
            -z + sb * (xl + lat[0] + lba[0]) - cb * inner + lba[2] + lat[2],
        ]
    }

    #[test]
    fn ab_mirror_support_matches_paper_002_eq6() {
        let mut s = 7u64;
        let mut r = |lo: f64, hi: f64| lo + (hi - lo) * lcg(&mut s);
        for _ in 0..1000 {
            let lat = [r(-50.0, 50.0), r(-50.0, 50.0), r(50.0, 400.0)];
            let lba = [r(-50.0, 50.0), r(-50.0, 50.0), r(50.0, 300.0)];
            let chain = KinematicChain::ab_mirror_support(lat, lba).unwrap();
            let p = [r(-20.0, 20.0), r(-20.0, 20.0), r(-20.0, 20.0)];
            let ax = [r(-1000.0, 1000.0), r(-1000.0, 1000.0), r(-500.0, 500.0), r(-1.6, 1.6), r(-1.6, 1.6)];
            let got = transform_point(&chain.transform(&ax), p);
            let want = eq6(p, ax, lat, lba);
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() < 1e-9, "{got:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn ac_head_matches_spec_products() {
        let c2 = [12.0, -3.0, 150.0];
        let mount = [0.01, -0.02, 0.5, 30.0, 5.0, -80.0];
        let chain = KinematicChain::ac_head(c2, mount).unwrap();
        let pose = [100.0, -50.0, 20.0, 0.3, -0.8, 1.2];
        let t = chain.transform(&pose);
        let rt = rot_z(pose[4]) * rot_x(pose[3]);
        let rm = rot_z(mount[2]) * rot_y(mount[0]) * rot_x(mount[1]);
        let p = Vector3::new(2.5, 0.0, -0.3);
        let want = rt * (rot_z(pose[5]) * (rm * p + Vector3::new(mount[3], mount[4], mount[5])) + Vector3::from(c2))
            + Vector3::new(pose[0], pose[1], pose[2]);
        let got = transform_point(&t, [p.x, p.y, p.z]);
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-12);
        }
        let r = t.fixed_view::<3, 3>(0, 0).into_owned();
        assert!((r.transpose() * r - Matrix3::identity()).abs().max() < 1e-14);
    }

    #[test]
    fn ac_table_matches_paper_003_eq1() {
        let center = [10.0, 20.0, -30.0];
        let chain = KinematicChain::ac_table(center).unwrap();
        let (a, c) = (0.4, -2.0);
        let t = chain.transform(&[a, c]);
        let p = Vector3::new(1.0, 2.0, 3.0);
        let tv = Vector3::from(center);
        let want = rot_x(a) * rot_z(c) * (p - tv) + tv;
        let got = transform_point(&t, [1.0, 2.0, 3.0]);
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn rejects_bad_steps() {
        assert!(KinematicChain::new(vec![Step::Rotate(Axis::X, AngleSource::AxisColumn(3))], vec!["A".into()]).is_err());
        assert!(KinematicChain::new(vec![Step::Mirror([2.0, 1.0, 1.0])], vec![]).is_err());
        assert!(KinematicChain::new(vec![Step::Rotation(Matrix3::identity() * 2.0)], vec![]).is_err());
    }

    #[test]
    fn nan_pose_is_an_error() {
        let chain = KinematicChain::ac_table([0.0; 3]).unwrap();
        let e = chain.transforms(&[0.0, 0.0, f64::NAN, 1.0]).unwrap_err();
        assert!(e.to_string().contains("row 1"), "{e}");
    }
}
