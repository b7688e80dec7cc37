//! Toolpath compensation for mirror milling (SPEC S5; paper 002 §4): the toolpath programmed on
//! the theoretical surface, carried onto the scanned actual surface by the mapping the matched
//! points define.
//!
//! Each tool point t is split into its foot f on the theoretical surface and its offset h along
//! the theoretical normal nₜ (a pocket floor lies h below the skin; a contact point has h = 0).
//! The foot is mapped onto the actual surface — point a, normal nₐ — and the tool point becomes
//! `a + h·nₐ`; a given tool axis turns with the normal (the rotation taking nₜ to nₐ), otherwise
//! the axis is nₐ. Normals point to +z (the side the surfaces are height fields over).
//!
//! The mapping (`Interpolation`):
//! - `Cubic` (default): polyharmonic splines (`spline.rs`) through the matching pairs give the
//!   actual point of any theoretical x, y, and the theoretical surface between the matching
//!   points (its foot and normal); quadratic fields are reproduced exactly.
//! - `Linear` (the paper, eq 17): the theoretical matching points triangulated in xy, the same
//!   connectivity for the actual ones, the same barycentric combination of the actual corners.
//!
//! The actual surface (`Normals`): `Smooth` (default) puts the mapped point on a quadric fitted
//! to the scan points around it, and takes its normal: a 5 µm noisy scan at 1.3 mm tilts
//! triangle normals by ~0.2°; `Triangle` (the paper) takes the closest point of the scan mesh
//! and its triangle's normal.
//!
//! Tool points whose foot lies outside the xy hull of the theoretical matching points are
//! extrapolated (by the spline, or by the plane of the nearest triangle) and flagged in
//! `inside`.
//! The formulas: docs/matching.md (compensation), docs/grinding.md (grinding paths).
pub mod bead_chain;
mod edge;
pub mod grinding;
pub mod scallop;
pub mod spline;

use crate::error::{check_finite_points, check_positive, Error, Result};
use crate::mesh::{
    delaunay_xy, median_edge, off_surface, off_surface_limit, ScanSurface, Spacing, TriangleBvh, XyLocator,
};
use crate::spatial::PointIndex;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use rayon::prelude::*;
use spline::Spline;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    Cubic,
    Linear,
}

impl Interpolation {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "cubic" => Ok(Interpolation::Cubic),
            "linear" => Ok(Interpolation::Linear),
            _ => Err(Error::invalid("interpolation", format!("expected 'cubic' or 'linear', got {name:?}"))),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Normals {
    Smooth,
    Triangle,
}

impl Normals {
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "smooth" => Ok(Normals::Smooth),
            "triangle" => Ok(Normals::Triangle),
            _ => Err(Error::invalid("normals", format!("expected 'smooth' or 'triangle', got {name:?}"))),
        }
    }
}

#[derive(Debug, Clone, Copy)]
pub struct CompensateOptions {
    pub interpolation: Interpolation,
    pub normals: Normals,
    /// Radius (mm) of the scan patch the smooth surface is fitted to; `None`: 5 median edge
    /// lengths of the scan mesh.
    pub radius: Option<f64>,
    /// Triangles of the scan's mesh with an edge beyond this (mm) are left out; `None`: those
    /// beyond `EDGE_TRIM` × the median edge, peeled from the outline (as the match meshes it).
    pub max_edge: Option<f64>,
}

/// Fewest scan points a local quadric is fitted to: 6 coefficients, with room for noise.
const QUADRIC_POINTS: usize = 12;
/// How far from 1 a given tool axis's length may be: CL files print axes to 4–6 decimals
/// (0.70711, 0.70711 has length 1 + 4.6e-6); each is normalised, so only a length this far off
/// says the columns are not an axis.
const AXIS_TOLERANCE: f64 = 1e-3;
/// How many times the foot of an offset tool point is refined (the normal at the foot moves it).
const FOOT_ITERATIONS: usize = 4;

#[derive(Debug, Clone)]
pub struct Compensated {
    pub points: Vec<[f64; 3]>,
    pub axes: Vec<[f64; 3]>,
    pub inside: Vec<bool>,
    /// Whether the mapped point's x, y lies over the scan mesh (the surfaces are height fields
    /// over xy). Where it does not (beyond the scan's outline, over a hole the mesh leaves open)
    /// the scan does not cover it, and the point was put on the scan's edge nearest to it, which
    /// is not where the part is.
    pub on_scan: Vec<bool>,
    /// Each tool point's offset h (mm) along the theoretical normal.
    pub offsets: Vec<f64>,
}

/// One tool point compensated (a row of `Compensated`).
struct Placed {
    point: [f64; 3],
    axis: [f64; 3],
    inside: bool,
    on_scan: bool,
    offset: f64,
}

/// The theoretical side of the mapping: the surface between the matching points, and where
/// each theoretical x, y goes.
enum Mapping {
    /// z of the theoretical surface, then x, y, z of the actual point, over theoretical x, y.
    Cubic {
        theoretical: Spline,
        actual: Spline,
    },
    Linear {
        faces: Vec<[u32; 3]>,
    },
}

/// +z-facing unit normal of a height field with slopes (zx, zy).
fn height_normal(zx: f64, zy: f64) -> Vector3<f64> {
    Vector3::new(-zx, -zy, 1.0).normalize()
}

fn upward(n: Vector3<f64>) -> Vector3<f64> {
    if n.z < 0.0 {
        -n
    } else {
        n
    }
}

/// The actual surface as the scan gives it.
struct ActualSurface<'a> {
    vertices: &'a [[f64; 3]],
    faces: &'a [[u32; 3]],
    bvh: TriangleBvh<'a>,
    index: PointIndex,
    radius: f64,
}

impl ActualSurface<'_> {
    /// The surface point near `q` and its normal.
    fn project(&self, q: Vector3<f64>, normals: Normals) -> (Vector3<f64>, Vector3<f64>) {
        let c = self.bvh.closest(&q.into());
        let f = self.faces[c.triangle].map(|v| Vector3::from(self.vertices[v as usize]));
        let triangle_normal = upward((f[1] - f[0]).cross(&(f[2] - f[0])).normalize());
        let on_mesh = Vector3::from(c.point);
        if normals == Normals::Triangle {
            return (on_mesh, triangle_normal);
        }
        self.quadric(on_mesh, triangle_normal).unwrap_or((on_mesh, triangle_normal))
    }

    /// A quadric height field over the plane of the scan points within `radius` of `q` (over a
    /// gap, within a wider radius that surrounds `q`), `q` put on it along the plane's normal.
    fn quadric(&self, q: Vector3<f64>, guess: Vector3<f64>) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let mut near: Vec<usize> = Vec::new();
        self.index.for_each_within(&q.into(), self.radius, |i| near.push(i));
        if near.len() < QUADRIC_POINTS {
            // q is over a gap in the scan (a clamp's shadow): widen until the points are enough
            // and lie around q, not on one side of it — a fit to one side extrapolates its slope
            // across the gap (2.4° over a 16 mm gap with the 12 nearest points).
            let mut r = self.radius;
            while r < 16.0 * self.radius {
                r *= 1.5;
                near.clear();
                self.index.for_each_within(&q.into(), r, |i| near.push(i));
                if near.len() >= QUADRIC_POINTS {
                    let c =
                        near.iter().map(|&i| Vector3::from(self.vertices[i])).sum::<Vector3<f64>>() / near.len() as f64;
                    if (c - q).norm() < 0.5 * r {
                        break;
                    }
                }
            }
            if near.len() < QUADRIC_POINTS {
                near = self.index.knn(&q.into(), QUADRIC_POINTS).into_iter().map(|(i, _)| i).collect();
            }
        }
        let pts: Vec<Vector3<f64>> = near.iter().map(|&i| Vector3::from(self.vertices[i])).collect();
        let centroid = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
        let cov = pts.iter().fold(Matrix3::zeros(), |m, p| m + (p - centroid) * (p - centroid).transpose());
        let eig = cov.symmetric_eigen();
        let k = eig.eigenvalues.imin();
        let mut w = eig.eigenvectors.column(k).into_owned();
        if w.dot(&guess) < 0.0 {
            w = -w;
        }
        let u = Unit::new_normalize(if w.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() }.cross(&w));
        let v = w.cross(&u);
        let (mut ata, mut atb) = (nalgebra::Matrix6::<f64>::zeros(), nalgebra::Vector6::<f64>::zeros());
        for p in &pts {
            let d = p - q;
            let (x, y, h) = (d.dot(&u), d.dot(&v), d.dot(&w));
            let row = nalgebra::Vector6::new(1.0, x, y, x * x, x * y, y * y);
            ata += row * row.transpose();
            atb += row * h;
        }
        let c = ata.cholesky()?.solve(&atb);
        // At (0, 0) of the frame centred on q: height c0, slopes c1, c2.
        let n = (w - c[1] * u.into_inner() - c[2] * v).normalize();
        let point = q + c[0] * w;
        (point.iter().all(|x| x.is_finite()) && n.iter().all(|x| x.is_finite())).then_some((point, upward(n)))
    }
}

/// Compensates the tool points (module docs). `tool_axes` is one unit axis per tool point, or
/// `None`; `actual` the scan, as points (meshed as the match meshes them, not thinned, so that
/// `on_scan` tells where the scan has no points) or as a mesh. Errors name `actual_surface`.
pub fn compensate_toolpath(
    tool_points: &[[f64; 3]],
    tool_axes: Option<&[[f64; 3]]>,
    theoretical_matching: &[[f64; 3]],
    actual_matching: &[[f64; 3]],
    actual: ScanSurface<'_>,
    options: CompensateOptions,
) -> Result<Compensated> {
    let (actual_vertices, actual_faces, _) = actual.mesh("actual_surface", options.max_edge, Spacing::Full)?;
    let (actual_vertices, actual_faces) = (&actual_vertices[..], &actual_faces[..]);
    check_finite_points("tool_points", tool_points)?;
    if let Some(a) = tool_axes {
        for (i, x) in a.iter().enumerate() {
            // A row of three NaN: the point has no axis of its own (a `GOTO/x,y,z` among
            // five-axis ones); the actual normal is its axis.
            if x.iter().all(|c| c.is_nan()) {
                continue;
            }
            if let Some(k) = x.iter().position(|c| !c.is_finite()) {
                return Err(Error::invalid(
                    "tool_points",
                    format!("must be finite, found {} at row {i}, column {} (a point without a tool axis has NaN in all three of columns 3–5)", x[k], 3 + k),
                ));
            }
            let norm = Vector3::from(*x).norm();
            if (norm - 1.0).abs() > AXIS_TOLERANCE {
                return Err(Error::invalid(
                    "tool_points",
                    format!("the tool axis of point {i} (columns 3–5) is not a unit vector: its length is {norm}, more than {AXIS_TOLERANCE} from 1"),
                ));
            }
        }
    }
    check_finite_points("theoretical_matching", theoretical_matching)?;
    check_finite_points("actual_matching", actual_matching)?;
    let n = theoretical_matching.len();
    if actual_matching.len() != n {
        return Err(Error::invalid(
            "actual_matching",
            format!("expected {n} points, one per theoretical matching point, got {}", actual_matching.len()),
        ));
    }
    if let Some(r) = options.radius {
        check_positive("radius", r, "mm")?;
    }
    // One connectivity for both sets (SPEC S5 Note): the theoretical one.
    let faces = delaunay_xy(theoretical_matching, None).map_err(|e| match e {
        Error::Invalid { reason, .. } => Error::invalid("theoretical_matching", reason),
        other => other,
    })?;
    let hull = XyLocator::new(theoretical_matching, &faces);
    let xy: Vec<[f64; 2]> = theoretical_matching.iter().map(|p| [p[0], p[1]]).collect();
    let mapping = match options.interpolation {
        Interpolation::Cubic => Mapping::Cubic {
            theoretical: Spline::fit(
                "theoretical_matching",
                &xy,
                &theoretical_matching.iter().map(|p| vec![p[2]]).collect::<Vec<_>>(),
            )?,
            actual: Spline::fit(
                "theoretical_matching",
                &xy,
                &actual_matching.iter().map(|p| p.to_vec()).collect::<Vec<_>>(),
            )?,
        },
        Interpolation::Linear => Mapping::Linear { faces: faces.clone() },
    };
    let bvh = TriangleBvh::new(actual_vertices, actual_faces).map_err(|e| match e {
        Error::Invalid { name, reason } => Error::invalid(&format!("actual_surface ({name})"), reason),
        other => other,
    })?;
    let edge = median_edge(actual_vertices, actual_faces);
    let radius = options.radius.unwrap_or(5.0 * edge);
    // The actual matching points lie on the scan (`isometric_match` puts them there); one off it
    // is a wrong point, and the mapping would carry the toolpath to it.
    let limit = off_surface_limit(edge);
    for (i, p) in actual_matching.iter().enumerate() {
        let d = bvh.closest(p).distance;
        if !(d <= limit) {
            return Err(off_surface("actual_matching", i, *p, d, limit));
        }
    }
    let scan_outline = XyLocator::new(actual_vertices, actual_faces);
    let actual = ActualSurface {
        vertices: actual_vertices,
        faces: actual_faces,
        bvh,
        index: PointIndex::new(actual_vertices)?,
        radius,
    };

    // The theoretical surface at x, y: point and normal, and the actual point it maps to.
    let theoretical_at = |x: f64, y: f64| -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        match &mapping {
            Mapping::Cubic { theoretical, actual } => {
                let (z, zx, zy) = theoretical.eval(x, y);
                let (a, _, _) = actual.eval(x, y);
                (Vector3::new(x, y, z[0]), height_normal(zx[0], zy[0]), Vector3::new(a[0], a[1], a[2]))
            }
            Mapping::Linear { faces } => {
                // Delaunay triangles are never flat in xy, so `nearest` finds one.
                let Some(l) = hull.locate(x, y).or_else(|| hull.nearest(x, y)) else {
                    let nan = Vector3::repeat(f64::NAN);
                    return (nan, nan, nan);
                };
                let f = faces[l.triangle];
                let corner = |pts: &[[f64; 3]], k: usize| Vector3::from(pts[f[k] as usize]);
                let w = l.barycentric;
                let t = (0..3).map(|k| w[k] * corner(theoretical_matching, k)).sum::<Vector3<f64>>();
                let a = (0..3).map(|k| w[k] * corner(actual_matching, k)).sum::<Vector3<f64>>();
                let [p, q, r] = [0, 1, 2].map(|k| corner(theoretical_matching, k));
                (t, upward((q - p).cross(&(r - p)).normalize()), a)
            }
        }
    };
    let results: Vec<Placed> = tool_points
        .par_iter()
        .enumerate()
        .map(|(i, t)| {
            let t = Vector3::from(*t);
            // The foot: the theoretical point whose normal line passes through t.
            let mut xy = (t.x, t.y);
            let (mut foot, mut nt, mut mapped) = theoretical_at(xy.0, xy.1);
            for _ in 0..FOOT_ITERATIONS {
                let h = (t - foot).dot(&nt);
                let next = (t.x - h * nt.x, t.y - h * nt.y);
                if (next.0 - xy.0).hypot(next.1 - xy.1) < 1e-9 {
                    break;
                }
                xy = next;
                (foot, nt, mapped) = theoretical_at(xy.0, xy.1);
            }
            let h = (t - foot).dot(&nt);
            // Far outside the hull the extrapolated mapping (cubic) overflows: no answer, said so.
            if !(mapped.iter().chain(nt.iter()).all(|c| c.is_finite()) && h.is_finite()) {
                return Err(Error::invalid(
                    "tool_points",
                    format!("point {i} lies too far from the matching points to be mapped (the mapping overflows)"),
                ));
            }
            let inside = hull.locate(xy.0, xy.1).is_some();
            let (a, na) = actual.project(mapped, options.normals);
            let on_scan = scan_outline.locate(mapped.x, mapped.y).is_some();
            let axis = match tool_axes.map(|axes| axes[i]) {
                Some(given) if !given[0].is_nan() => {
                    Rotation3::rotation_between(&nt, &na).unwrap_or_else(Rotation3::identity) * Vector3::from(given)
                }
                _ => na,
            };
            Ok(Placed { point: (a + h * na).into(), axis: axis.normalize().into(), inside, on_scan, offset: h })
        })
        .collect::<Result<_>>()?;
    Ok(Compensated {
        points: results.iter().map(|r| r.point).collect(),
        axes: results.iter().map(|r| r.axis).collect(),
        inside: results.iter().map(|r| r.inside).collect(),
        on_scan: results.iter().map(|r| r.on_scan).collect(),
        offsets: results.iter().map(|r| r.offset).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: f64 = 1000.0;

    /// The flat plate point (u, v, 0) bent onto the cylinder of radius R about the y axis
    /// (an isometry), and that point's upward normal.
    fn bend(p: [f64; 3]) -> (Vector3<f64>, Vector3<f64>) {
        let a = p[0] / R;
        let n = Vector3::new(-a.sin(), 0.0, a.cos());
        (Vector3::new(R * a.sin(), p[1], R * (1.0 - a.cos())) + p[2] * n, n)
    }

    /// The bent plate sampled at `spacing` in u, v, with `noise` (mm, standard deviation of a
    /// sum of uniforms) along z.
    fn scan(spacing: f64, noise: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (nx, ny) = ((300.0 / spacing) as usize + 1, (200.0 / spacing) as usize + 1);
        let v: Vec<[f64; 3]> = (0..nx * ny)
            .map(|k| {
                let (u, w) = (
                    -150.0 + (k % nx) as f64 * 300.0 / (nx - 1) as f64,
                    -100.0 + (k / nx) as f64 * 200.0 / (ny - 1) as f64,
                );
                let mut p: [f64; 3] = bend([u, w, 0.0]).0.into();
                p[2] += noise * 2.0 * ((0..3).map(|_| uniform()).sum::<f64>() - 1.5);
                p
            })
            .collect();
        let f = delaunay_xy(&v, None).unwrap();
        (v, f)
    }

    #[test]
    fn a_bent_noisy_scan_is_compensated_to_microns_and_the_smooth_normals_keep_the_axes_within_a_tenth_of_a_degree() {
        let (sv, sf) = scan(1.3, 0.005);
        let t_match: Vec<[f64; 3]> = (0..64)
            .map(|k| [-140.0 + 280.0 * (k % 8) as f64 / 7.0, -90.0 + 180.0 * (k / 8) as f64 / 7.0, 0.0])
            .collect();
        let a_match: Vec<[f64; 3]> = t_match.iter().map(|&p| bend(p).0.into()).collect();
        // Tool points on the skin and 2 mm into it, inside the matching hull; one outside.
        let mut tools: Vec<[f64; 3]> = (0..400)
            .map(|k| {
                [
                    -135.0 + 270.0 * (k as f64 * 0.618034).fract(),
                    -85.0 + 170.0 * (k as f64 * 0.754878).fract(),
                    if k % 2 == 0 { 0.0 } else { -2.0 },
                ]
            })
            .collect();
        tools.push([148.0, 0.0, 0.0]);
        let run = |interpolation, normals| {
            let o = CompensateOptions { interpolation, normals, radius: None, max_edge: None };
            let scan = ScanSurface { points: &sv, faces: Some(&sf) };
            compensate_toolpath(&tools, None, &t_match, &a_match, scan, o).unwrap()
        };
        let errors = |c: &Compensated| {
            let (mut dist, mut angle) = (0.0f64, 0.0f64);
            for (i, t) in tools.iter().enumerate().take(400) {
                let (p, n) = bend(*t);
                dist = dist.max((Vector3::from(c.points[i]) - p).norm());
                angle = angle.max(Vector3::from(c.axes[i]).angle(&n).to_degrees());
                assert!(c.inside[i]);
            }
            assert!(!c.inside[400]);
            (dist, angle)
        };
        let (d, a) = errors(&run(Interpolation::Cubic, Normals::Smooth));
        assert!(d < 0.02 && a < 0.05, "smooth: {d} mm, {a}°");
        // The paper's triangle normals tilt with the scan's noise.
        let (d, a) = errors(&run(Interpolation::Linear, Normals::Triangle));
        assert!(d < 0.05 && a > 0.1, "paper: {d} mm, {a}°");
    }
}
