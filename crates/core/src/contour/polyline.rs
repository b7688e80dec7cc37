//! CAD polylines discretised at a given spacing (theoretical contour points, SPEC C1).
use crate::error::{Error, Result};

/// Points along the polyline `vertices (n, 3)` at equal arc-length steps of about `spacing` mm
/// (the length divided into ⌈length / spacing⌉ equal parts, so no step exceeds `spacing`);
/// `closed` adds the segment back to the start (and the start is not repeated at the end).
///
/// Equal steps over the whole polyline, not per segment: splitting each segment on its own
/// gives segments slightly longer than a multiple of the spacing one point more, so the point
/// density, and with it the centroid of a contour (the offset E of paper 000 eq 21), would
/// depend on how the CAD system cut the curve. Vertices are kept only where a step lands on
/// them; a corner is cut by at most half a step.
pub fn resample_polyline(vertices: &[[f64; 3]], spacing: f64, closed: bool) -> Result<Vec<[f64; 3]>> {
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(Error::invalid("spacing", format!("must be a positive distance in mm, got {spacing}")));
    }
    let min = if closed { 3 } else { 2 };
    if vertices.len() < min {
        return Err(Error::shape(
            "vertices",
            format!("(n, 3) with n >= {min} for a {} polyline", if closed { "closed" } else { "open" }),
            format!("({}, 3)", vertices.len()),
        ));
    }
    crate::error::check_finite_points("vertices", vertices)?;
    let n = vertices.len();
    let segments = if closed { n } else { n - 1 };
    let seg = |s: usize| (vertices[s], vertices[(s + 1) % n]);
    let length =
        |a: [f64; 3], b: [f64; 3]| ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
    let total: f64 = (0..segments)
        .map(|s| {
            let (a, b) = seg(s);
            length(a, b)
        })
        .sum();
    if total <= 0.0 {
        return Err(Error::invalid("vertices", "the polyline has zero length"));
    }
    let parts = (total / spacing).ceil().max(1.0) as usize;
    let step = total / parts as f64;
    let count = if closed { parts } else { parts + 1 };
    let mut out = Vec::with_capacity(count);
    // Walk the segments once, emitting the points at s = k·step.
    let (mut s_idx, mut s_start) = (0usize, 0.0f64);
    for k in 0..count {
        let target = if k + 1 == count && !closed { total } else { k as f64 * step };
        loop {
            let (a, b) = seg(s_idx);
            let len = length(a, b);
            if target <= s_start + len || s_idx + 1 == segments {
                let t = if len > 0.0 { ((target - s_start) / len).clamp(0.0, 1.0) } else { 0.0 };
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])]);
                break;
            }
            s_start += len;
            s_idx += 1;
        }
    }
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
        assert_eq!(open.len(), 11);
        assert_eq!(*open.last().unwrap(), [0.0, 10.0, 0.0]);
        // Equal steps across vertices: 0.7 of length per step over segments of 10.
        let pts = resample_polyline(&sq, 0.7, true).unwrap();
        let steps: Vec<f64> = (0..pts.len())
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
            })
            .collect();
        assert_eq!(pts.len(), 58);
        // Straight steps are exact; steps across a corner are chords, shorter.
        assert!(steps.iter().all(|&d| d <= 40.0 / 58.0 + 1e-12));
    }
}
