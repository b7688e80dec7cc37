//! A coarser copy of a scanned height-field surface for geodesic work (isometric matching).
//!
//! Why: exact geodesics cost far more than linearly in the vertices (every window crosses
//! every face it reaches, and on a scanned surface noise makes about half the vertices saddles
//! that emit windows of their own), while the distances isometric matching needs run between
//! points tens of millimetres apart on a skin whose radii are hundreds of millimetres. A mesh of
//! a few thousand vertices measures them as well as the scan's tens of thousands: the chord of
//! a triangle of side h on a radius R shortens a path by a relative (h/R)²/24 (6 mm on R 1000
//! mm: 1.5e-6), and scan noise σ lengthens it by about (σ/h)² (5 µm at 6 mm: 7e-7).
//!
//! The thinning keeps the outline, since locating points sit near the part's edge and a point
//! outside the coarse mesh could not be placed on it: the mesh's boundary loops are walked and
//! a boundary vertex kept where the loop has run `spacing` since the last one kept or where the
//! chord from it would pass farther than `spacing / 20` from a vertex between. Inside, one
//! point per `spacing` × `spacing` cell of the xy plane: the one nearest the cell's centre,
//! unless a kept outline point is within `spacing / 2`.
use std::collections::HashMap;

/// The indices (ascending) of the points kept: the outline of the mesh `faces` of `points`
/// and about one point per `spacing` × `spacing` cell of the xy plane (module notes).
pub fn thin_xy(points: &[[f64; 3]], faces: &[[u32; 3]], spacing: f64) -> Vec<usize> {
    let mut keep = vec![false; points.len()];
    let outline = outline_kept(points, faces, spacing);
    for &v in &outline {
        keep[v] = true;
    }
    let cell = |p: &[f64; 3]| ((p[0] / spacing).floor() as i64, (p[1] / spacing).floor() as i64);
    let mut near_outline: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for &v in &outline {
        near_outline.entry(cell(&points[v])).or_default().push(v);
    }
    let mut used = vec![false; points.len()];
    faces.iter().flatten().for_each(|&v| used[v as usize] = true);
    let mut best: HashMap<(i64, i64), (f64, usize)> = HashMap::new();
    for (i, p) in points.iter().enumerate() {
        if !used[i] {
            continue;
        }
        let c = cell(p);
        let centre = [(c.0 as f64 + 0.5) * spacing, (c.1 as f64 + 0.5) * spacing];
        let d = (p[0] - centre[0]).hypot(p[1] - centre[1]);
        let slot = best.entry(c).or_insert((f64::INFINITY, i));
        if d < slot.0 {
            *slot = (d, i);
        }
    }
    for (&(cx, cy), &(_, i)) in &best {
        let p = points[i];
        let crowded = (cx - 1..=cx + 1).flat_map(|x| (cy - 1..=cy + 1).map(move |y| (x, y))).any(|c| {
            near_outline
                .get(&c)
                .is_some_and(|vs| vs.iter().any(|&v| (points[v][0] - p[0]).hypot(points[v][1] - p[1]) < 0.5 * spacing))
        });
        if !crowded {
            keep[i] = true;
        }
    }
    (0..points.len()).filter(|&i| keep[i]).collect()
}

/// The area of the mesh's xy projection.
pub fn xy_area(points: &[[f64; 3]], faces: &[[u32; 3]]) -> f64 {
    faces
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
        })
        .sum()
}

/// The boundary vertices kept along each boundary loop of the mesh (module notes).
fn outline_kept(points: &[[f64; 3]], faces: &[[u32; 3]], spacing: f64) -> Vec<usize> {
    // Boundary edges: used by one face only, directed as in that face.
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if count[&(a.min(b), a.max(b))] == 1 {
                next.entry(a).or_default().push(b);
            }
        }
    }
    let xy_gap = |a: usize, b: usize| (points[a][0] - points[b][0]).hypot(points[a][1] - points[b][1]);
    // Distance in xy from p to the segment a–b.
    let off_chord = |p: usize, a: usize, b: usize| {
        let (ax, ay) = (points[a][0], points[a][1]);
        let (dx, dy) = (points[b][0] - ax, points[b][1] - ay);
        let (px, py) = (points[p][0] - ax, points[p][1] - ay);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 { ((px * dx + py * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
        (px - t * dx).hypot(py - t * dy)
    };
    let tolerance = spacing / 20.0;
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable(); // the same loops, walked the same way, on every run
    let mut kept = Vec::new();
    for start in starts {
        // Walk one loop (or, at a vertex where loops touch, one of them) while edges are left.
        let mut lp = vec![start as usize];
        let mut at = start;
        while let Some(b) = next.get_mut(&at).and_then(Vec::pop) {
            if b == start {
                break;
            }
            lp.push(b as usize);
            at = b;
        }
        if lp.len() < 2 {
            continue;
        }
        // Greedy: from the last kept vertex, reach as far along the loop as the chord allows.
        let mut last = 0;
        kept.push(lp[0]);
        let mut run = 0.0;
        for i in 1..lp.len() {
            run += xy_gap(lp[i - 1], lp[i]);
            let fits = run <= spacing && (last + 1..i).all(|j| off_chord(lp[j], lp[last], lp[i]) <= tolerance);
            if !fits && i - 1 > last {
                last = i - 1;
                kept.push(lp[last]);
                run = xy_gap(lp[last], lp[i]);
            }
        }
        kept.push(lp[lp.len() - 1]);
    }
    kept.sort_unstable();
    kept.dedup();
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::delaunay_xy;
    use crate::mesh::test_meshes::grid_nm;

    #[test]
    fn a_grid_keeps_its_corners_and_about_one_point_per_cell() {
        // 0.5 mm grid over 60 × 40 mm, thinned to 5 mm.
        let (v, f) = grid_nm(121, 81, 0.5);
        let kept = thin_xy(&v, &f, 5.0);
        for corner in [[0.0, 0.0], [60.0, 0.0], [0.0, 40.0], [60.0, 40.0]] {
            assert!(kept.iter().any(|&i| v[i][0] == corner[0] && v[i][1] == corner[1]), "{corner:?}");
        }
        // 13 × 9 cells (the far edges start cells of their own) and the outline every 5 mm or less.
        assert!(kept.len() <= 13 * 9 + 4 * 13, "{}", kept.len());
        assert!(kept.len() >= 12 * 8, "{}", kept.len());
        // The coarse mesh covers the same outline: its xy area is the full one.
        let coarse: Vec<[f64; 3]> = kept.iter().map(|&i| v[i]).collect();
        let faces = delaunay_xy(&coarse, None).unwrap();
        let area = xy_area(&coarse, &faces);
        assert!((area - 2400.0).abs() < 1e-9, "{area}");
    }

    #[test]
    fn a_concave_outline_keeps_its_notch() {
        // An L: a 40 × 40 mm square without its upper right 20 × 20 mm quarter, 0.5 mm apart.
        let mut v = Vec::new();
        for j in 0..=80 {
            for i in 0..=80 {
                let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
                if !(x > 20.0 && y > 20.0) {
                    v.push([x, y, 0.0]);
                }
            }
        }
        let (coarse, faces, _) =
            crate::mesh::surface_mesh("points", &v, None, Some(0.75), crate::mesh::Spacing::Fixed(4.0)).unwrap();
        assert!(coarse.len() < v.len() / 10);
        // Its outline's ends are kept, and no triangle reaches into the notch beyond the full
        // mesh's own corner cut (a half-diagonal, 0.36 mm).
        for end in [[40.0, 20.0], [20.0, 40.0], [0.0, 0.0]] {
            assert!(coarse.iter().any(|p| p[0] == end[0] && p[1] == end[1]), "{end:?}");
        }
        let area = xy_area(&coarse, &faces);
        assert!((area - 1200.0).abs() < 0.5, "{area}");
    }
}
