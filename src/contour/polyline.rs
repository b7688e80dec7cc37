//! CAD polylines discretised at a given spacing (theoretical contour points, SPEC C1).
use crate::error::{Error, Result};

/// Points along the polyline `vertices (n, 3)` every `spacing` mm of arc length, vertices
/// included where the spacing lands on them; `closed` adds the segment back to the start.
/// Each segment is split into ⌈length / spacing⌉ equal parts, so no point is farther than
/// `spacing` from the next and corners are kept.
pub fn resample_polyline(vertices: &[[f64; 3]], spacing: f64, closed: bool) -> Result<Vec<[f64; 3]>> {
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(Error::invalid("spacing", format!("must be a positive distance in mm, got {spacing}")));
    }
    let min = if closed { 3 } else { 2 };
    if vertices.len() < min {
        return Err(Error::shape("vertices", format!("(n, 3) with n >= {min} for a {} polyline", if closed { "closed" } else { "open" }), format!("({}, 3)", vertices.len())));
    }
    if let Some(i) = vertices.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(Error::invalid("vertices", format!("must be finite, found {:?} at row {i}", vertices[i])));
    }
    let mut out = Vec::new();
    let n = vertices.len();
    let segments = if closed { n } else { n - 1 };
    for s in 0..segments {
        let (a, b) = (vertices[s], vertices[(s + 1) % n]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
        let parts = (len / spacing).ceil().max(1.0) as usize;
        for k in 0..parts {
            let t = k as f64 / parts as f64;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])]);
        }
    }
    if !closed {
        out.push(vertices[n - 1]);
    }
    // Repeated vertices give zero-length segments: drop exact duplicates in a row.
    out.dedup();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_is_sampled_evenly_with_corners() {
        let sq = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 10.0, 0.0], [0.0, 10.0, 0.0]];
        let pts = resample_polyline(&sq, 1.0, true).unwrap();
        assert_eq!(pts.len(), 40);
        assert!(pts.contains(&[10.0, 10.0, 0.0]));
        let open = resample_polyline(&sq, 3.0, false).unwrap();
        assert_eq!(open.len(), 3 * 4 + 1);
        assert_eq!(*open.last().unwrap(), [0.0, 10.0, 0.0]);
    }
}
