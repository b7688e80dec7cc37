//! Delaunay triangulation of a surface seen from above (SPEC S1; paper 002 §3.1): the points'
//! xy projection is triangulated and the triangles are lifted back to 3D. Right for the skins of
//! mirror milling, which are height fields over the machine table.
//!
//! spade does the triangulation: exact predicates, so no point set makes it fail or loop.
use crate::error::{check_finite_points, Error, Result};
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

/// A point of the projection, carrying its index in the input.
struct Vertex {
    position: Point2<f64>,
    index: u32,
}

impl HasPosition for Vertex {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.position
    }
}

/// The triangles `[a, b, c]` (indices into `points`, counter-clockwise seen from +z) of the
/// Delaunay triangulation of the points' xy projection; with `max_edge`, those with an edge
/// longer than it in 3D are left out (the long thin triangles a concave outline leaves along
/// its hull).
///
/// Rules for degenerate input: points with the same x and y as an earlier point are left out
/// of every triangle (the first is kept); points all on one line in xy, or fewer than three
/// distinct ones, are an error (there is no triangle). Four or more points on one circle have
/// several Delaunay triangulations; one of them is returned.
pub fn delaunay_xy(points: &[[f64; 3]], max_edge: Option<f64>) -> Result<Vec<[u32; 3]>> {
    check_finite_points("points", points)?;
    if let Some(m) = max_edge {
        if !(m > 0.0) {
            return Err(Error::invalid("max_edge", format!("must be a length > 0 mm (inf: no trim), got {m}")));
        }
    }
    if points.len() > u32::MAX as usize {
        return Err(Error::invalid("points", format!("at most {} points, got {}", u32::MAX, points.len())));
    }
    // Exact duplicates in xy: the first of each is kept, so the rule does not depend on spade's.
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    order.sort_unstable_by(|&a, &b| {
        // + 0.0 makes −0.0 and 0.0 one value.
        let (pa, pb) = (points[a as usize], points[b as usize]);
        (pa[0] + 0.0).total_cmp(&(pb[0] + 0.0)).then((pa[1] + 0.0).total_cmp(&(pb[1] + 0.0))).then(a.cmp(&b))
    });
    let mut vertices = Vec::with_capacity(points.len());
    let mut last: Option<[f64; 2]> = None;
    for &i in &order {
        let p = points[i as usize];
        let xy = [p[0] + 0.0, p[1] + 0.0];
        if last != Some(xy) {
            vertices.push(Vertex { position: Point2::new(xy[0], xy[1]), index: i });
            last = Some(xy);
        }
    }
    let triangulation: DelaunayTriangulation<Vertex> = DelaunayTriangulation::bulk_load(vertices).map_err(|e| {
        Error::invalid(
            "points",
            format!("cannot be triangulated: {e:?} (coordinates beyond ±1e150 or below 1e-140 in magnitude)"),
        )
    })?;
    let faces: Vec<[u32; 3]> = triangulation.inner_faces().map(|f| f.vertices().map(|v| v.data().index)).collect();
    let faces = match max_edge {
        Some(m) => without_long_edges(points, faces, m),
        None => faces,
    };
    if triangulation.num_inner_faces() == 0 {
        return Err(Error::invalid(
            "points",
            format!(
                "{} distinct points in xy, all on one line or fewer than three: no triangle",
                triangulation.num_vertices()
            ),
        ));
    }
    Ok(faces)
}

/// The triangles none of whose edges is longer than `max_edge` in 3D.
pub fn without_long_edges(points: &[[f64; 3]], faces: Vec<[u32; 3]>, max_edge: f64) -> Vec<[u32; 3]> {
    faces.into_iter().filter(|t| (0..3).all(|k| edge_length(points, t[k], t[(k + 1) % 3]) <= max_edge)).collect()
}

/// The triangles left when those with an outline edge longer than `max_edge` are peeled off,
/// from the outline inwards until no outline edge is that long. Delaunay's convex hull lays long,
/// thin triangles across every inward-bowing stretch of a scan's outline, where there is no part;
/// they go. A gap inside the scan (a clamp's shadow, a dropout) stays bridged: the part is there,
/// and the chord across it is the surface to (h/R)²/24 (1 µm over 16 mm at R 400 mm), where the
/// way round a hole is millimetres longer. A gap open to the outline is peeled like the hull.
pub fn peel_long_edges(points: &[[f64; 3]], faces: Vec<[u32; 3]>, max_edge: f64) -> Vec<[u32; 3]> {
    // Each edge with the triangles on it, sorted by its vertex pair.
    let mut keyed: Vec<(u32, u32, u32)> = faces
        .iter()
        .enumerate()
        .flat_map(|(f, t)| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]), f as u32)))
        .collect();
    keyed.sort_unstable();
    let on_edge = |a: u32, b: u32| {
        let key = (a.min(b), a.max(b));
        let lo = keyed.partition_point(|e| (e.0, e.1) < key);
        &keyed[lo..lo + keyed[lo..].partition_point(|e| (e.0, e.1) == key)]
    };
    let mut alive = vec![true; faces.len()];
    let mut stack: Vec<usize> = (0..faces.len()).collect();
    while let Some(f) = stack.pop() {
        let t = faces[f];
        let outline_too_long = |k: usize| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edge_length(points, a, b) > max_edge && on_edge(a, b).iter().filter(|e| alive[e.2 as usize]).count() == 1
        };
        if alive[f] && (0..3).any(outline_too_long) {
            alive[f] = false;
            // Its neighbours may now be on the outline.
            for k in 0..3 {
                stack.extend(on_edge(t[k], t[(k + 1) % 3]).iter().map(|e| e.2 as usize).filter(|&g| alive[g]));
            }
        }
    }
    faces.into_iter().zip(alive).filter_map(|(t, a)| a.then_some(t)).collect()
}

/// The 3D length of the edge a–b.
pub fn edge_length(points: &[[f64; 3]], a: u32, b: u32) -> f64 {
    let (p, q) = (points[a as usize], points[b as usize]);
    (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_with_a_centre_gives_four_triangles_counter_clockwise() {
        let pts = [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [2.0, 2.0, 1.0], [0.0, 2.0, 1.0], [1.0, 1.0, 2.0]];
        let faces = delaunay_xy(&pts, None).unwrap();
        assert_eq!(faces.len(), 4);
        for t in &faces {
            assert!(t.contains(&4));
            let [a, b, c] = t.map(|i| pts[i as usize]);
            let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(cross > 0.0);
        }
        // 3D edges from the centre are √3 long; the outline's are 2: max_edge 1.9 drops all.
        assert_eq!(delaunay_xy(&pts, Some(1.9)).unwrap().len(), 0);
        assert_eq!(delaunay_xy(&pts, Some(2.0)).unwrap().len(), 4);
    }

    #[test]
    fn duplicates_keep_the_first_and_degenerate_input_is_refused_by_name() {
        let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 5.0], [-0.0, 0.0, 9.0]];
        let faces = delaunay_xy(&pts, None).unwrap();
        assert_eq!(faces.len(), 1);
        let mut t = faces[0];
        t.sort_unstable();
        assert_eq!(t, [0, 1, 2]);
        let line = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 1.0]];
        assert!(delaunay_xy(&line, None).unwrap_err().to_string().contains("one line"));
        assert!(delaunay_xy(&pts, Some(0.0)).unwrap_err().to_string().contains("max_edge"));
        assert!(delaunay_xy(&[[f64::NAN, 0.0, 0.0]], None).unwrap_err().to_string().contains("points"));
    }
}
