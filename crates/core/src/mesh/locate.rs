//! Point location in the xy projection of a triangle mesh (SPEC S5: "locate its triangle in the
//! theoretical xy triangulation"; S4: put a matching point back on the actual surface at its x, y).
//!
//! The meshes here are height fields triangulated in xy (`delaunay_xy`), so a point's x, y name
//! one triangle and one surface point above it. A uniform grid of buckets over the xy bounds,
//! each holding the triangles whose boxes overlap it, finds the candidates; written here because
//! spade's own locate only serves a triangulation spade still holds, and these meshes come back
//! from the user or from `insert_points`.
use nalgebra::Vector3;

/// Barycentric coordinates may fall this far below 0 (relative) and still count as inside:
/// a point on a shared edge belongs to one of its triangles whatever the rounding.
const EDGE_SLACK: f64 = 1e-12;

/// The xy-projected mesh and its buckets.
pub struct XyLocator<'a> {
    vertices: &'a [[f64; 3]],
    faces: &'a [[u32; 3]],
    lo: [f64; 2],
    cell: f64,
    columns: usize,
    rows: usize,
    /// The triangles of bucket b are `list[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    list: Vec<u32>,
}

/// Where a point lands in xy: its triangle and its barycentric weights there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XyLanding {
    pub triangle: usize,
    pub barycentric: [f64; 3],
}

impl XyLanding {
    /// The point of the mesh above (or below) the located x, y: the same weights of the
    /// triangle's corners.
    pub fn point(&self, vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> [f64; 3] {
        let f = faces[self.triangle];
        let mut p = [0.0; 3];
        for (k, &v) in f.iter().enumerate() {
            for (pi, vi) in p.iter_mut().zip(vertices[v as usize]) {
                *pi += self.barycentric[k] * vi;
            }
        }
        p
    }
}

/// The barycentric weights of (x, y) in the xy projection of triangle `f`; `None` for a
/// triangle that is a line or a point in xy.
fn weights(vertices: &[[f64; 3]], f: [u32; 3], x: f64, y: f64) -> Option<[f64; 3]> {
    let [a, b, c] = f.map(|v| vertices[v as usize]);
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    let scale = ((b[0] - a[0]).abs() + (c[0] - a[0]).abs() + (b[1] - a[1]).abs() + (c[1] - a[1]).abs()).powi(2);
    if det.abs() <= 1e-14 * scale || !det.is_finite() {
        return None;
    }
    let v = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det;
    let w = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det;
    Some([1.0 - v - w, v, w])
}

impl<'a> XyLocator<'a> {
    /// Buckets of about two triangles' size. The mesh is taken as checked (finite vertices,
    /// faces in range).
    pub fn new(vertices: &'a [[f64; 3]], faces: &'a [[u32; 3]]) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for f in faces {
            for &v in f {
                let p = vertices[v as usize];
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        if faces.is_empty() {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        let (w, h) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
        let cell = ((w * h / faces.len().max(1) as f64) * 2.0).sqrt().max(w.max(h) / 4096.0).max(f64::MIN_POSITIVE);
        let columns = ((w / cell) as usize + 1).min(4096);
        let rows = ((h / cell) as usize + 1).min(4096);
        let span = |t: usize| {
            let f = faces[t];
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for &v in &f {
                let p = vertices[v as usize];
                for k in 0..2 {
                    a[k] = a[k].min(p[k]);
                    b[k] = b[k].max(p[k]);
                }
            }
            let i = |x: f64, k: usize, n: usize| (((x - lo[k]) / cell) as usize).min(n - 1);
            (i(a[0], 0, columns), i(b[0], 0, columns), i(a[1], 1, rows), i(b[1], 1, rows))
        };
        let mut start = vec![0u32; columns * rows + 1];
        for t in 0..faces.len() {
            let (i0, i1, j0, j1) = span(t);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    start[j * columns + i + 1] += 1;
                }
            }
        }
        for b in 0..columns * rows {
            start[b + 1] += start[b];
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; start[columns * rows] as usize];
        for t in 0..faces.len() {
            let (i0, i1, j0, j1) = span(t);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let b = j * columns + i;
                    list[fill[b] as usize] = t as u32;
                    fill[b] += 1;
                }
            }
        }
        XyLocator { vertices, faces, lo, cell, columns, rows, start, list }
    }

    /// The triangle whose xy projection holds (x, y), the lowest index on shared edges; `None`
    /// outside the mesh's xy outline.
    pub fn locate(&self, x: f64, y: f64) -> Option<XyLanding> {
        let i = (x - self.lo[0]) / self.cell;
        let j = (y - self.lo[1]) / self.cell;
        if !(i >= 0.0 && j >= 0.0) || i as usize >= self.columns || j as usize >= self.rows {
            // Points on the outline's far edges fall just past the last bucket.
            let (ic, jc) = (i.clamp(0.0, (self.columns - 1) as f64), j.clamp(0.0, (self.rows - 1) as f64));
            if (i - ic).abs() > 1e-9 || (j - jc).abs() > 1e-9 {
                return None;
            }
            return self.search(ic as usize, jc as usize, x, y);
        }
        self.search(i as usize, j as usize, x, y)
    }

    fn search(&self, i: usize, j: usize, x: f64, y: f64) -> Option<XyLanding> {
        let b = j * self.columns + i;
        let mut best: Option<XyLanding> = None;
        for &t in &self.list[self.start[b] as usize..self.start[b + 1] as usize] {
            let Some(w) = weights(self.vertices, self.faces[t as usize], x, y) else { continue };
            let worst = w[0].min(w[1]).min(w[2]);
            if worst >= -EDGE_SLACK && best.is_none_or(|b| (t as usize) < b.triangle) {
                best = Some(XyLanding { triangle: t as usize, barycentric: w.map(|c| c.max(0.0)) });
            }
        }
        best.map(|mut l| {
            let s: f64 = l.barycentric.iter().sum();
            l.barycentric = l.barycentric.map(|c| c / s);
            l
        })
    }

    /// The triangle nearest to (x, y) in xy, and the affine weights of (x, y) in it (some
    /// negative when outside): how a point outside the outline is extrapolated, by the plane of
    /// the nearest triangle. Searches every triangle; meant for the few points outside.
    pub fn nearest(&self, x: f64, y: f64) -> Option<XyLanding> {
        let q = Vector3::new(x, y, 0.0);
        let mut best: Option<(f64, XyLanding)> = None;
        for (t, &f) in self.faces.iter().enumerate() {
            let Some(w) = weights(self.vertices, f, x, y) else { continue };
            let [a, b, c] = f.map(|v| {
                let p = self.vertices[v as usize];
                Vector3::new(p[0], p[1], 0.0)
            });
            let (foot, _) = super::closest::closest_on_triangle(&q, &a, &b, &c);
            let d = (foot - q).norm_squared();
            if best.as_ref().is_none_or(|(bd, _)| d < *bd) {
                best = Some((d, XyLanding { triangle: t, barycentric: w }));
            }
        }
        best.map(|(_, l)| l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let v = (0..n * n).map(|i| [(i % n) as f64, (i / n) as f64, ((i % n) as f64 * 0.3).sin()]).collect();
        let mut f = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                f.extend([[a, a + 1, a + n as u32 + 1], [a, a + n as u32 + 1, a + n as u32]]);
            }
        }
        (v, f)
    }

    #[test]
    fn every_point_of_the_outline_is_found_in_the_triangle_that_holds_it() {
        let (v, f) = grid(12);
        let loc = XyLocator::new(&v, &f);
        for k in 0..2000 {
            let (x, y) = ((k as f64 * 0.6180339887).fract() * 11.0, (k as f64 * 0.7548776662).fract() * 11.0);
            let l = loc.locate(x, y).expect("inside");
            let w = weights(&v, f[l.triangle], x, y).unwrap();
            assert!(w.iter().all(|&c| c > -1e-12), "{w:?}");
            let p = l.point(&v, &f);
            assert!((p[0] - x).abs() < 1e-12 && (p[1] - y).abs() < 1e-12);
        }
        // Corners and far edges of the outline belong to it; beyond it, nothing.
        assert!(loc.locate(11.0, 11.0).is_some() && loc.locate(0.0, 0.0).is_some() && loc.locate(11.0, 5.5).is_some());
        assert!(loc.locate(11.01, 5.0).is_none() && loc.locate(-0.01, 5.0).is_none());
        let out = loc.nearest(12.0, 5.2).unwrap();
        assert!(out.barycentric.iter().any(|&c| c < 0.0));
        let p = out.point(&v, &f);
        assert!((p[0] - 12.0).abs() < 1e-12 && (p[1] - 5.2).abs() < 1e-12);
    }
}
