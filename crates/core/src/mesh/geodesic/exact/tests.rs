use super::*;

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}

use crate::mesh::test_meshes::grid_nm as grid;

/// The largest |row − truth|; inf where one is inf and the other not.
fn worst(row: &[f64], truth: impl Fn(usize) -> f64) -> f64 {
    row.iter()
        .enumerate()
        .map(|(i, &d)| {
            let t = truth(i);
            match (d.is_finite(), t.is_finite()) {
                (true, true) => (d - t).abs(),
                (false, false) if d == t => 0.0,
                _ => f64::INFINITY,
            }
        })
        .fold(0.0, f64::max)
}

#[test]
fn distances_on_a_flat_grid_are_euclidean() {
    let (v, mut f) = grid(21, 17, 0.5);
    // Faces wound either way: the unfolding does not rely on orientation.
    f.iter_mut().step_by(3).for_each(|t| t.swap(0, 1));
    let sources = [0, 10, 178, 356];
    let d = geodesic_exact(&v, &f, &sources).unwrap();
    for (row, &s) in d.iter().zip(&sources) {
        let e = worst(row, |i| dist(v[i], v[s]));
        assert!(e < 1e-12, "source {s}: worst {e}");
    }
}

/// A planar grid folded along its grid lines onto a prism (a polygonal half-cylinder): an
/// isometry of the plane strip, so the distances are the planar ones.
#[test]
fn a_folded_strip_keeps_planar_distances() {
    let (n, m, h) = (13, 9, 0.3);
    let (flat, f) = grid(n, m, h);
    let turn = PI / (n - 1) as f64; // half a turn over the strip
    let radius = h / (2.0 * (turn / 2.0).sin());
    let v: Vec<[f64; 3]> = (0..n * m)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            let t = i as f64 * turn;
            [radius * t.cos(), radius * t.sin(), j as f64 * h]
        })
        .collect();
    let sources = [0, 6, 50, n * m - 1];
    let d = geodesic_exact(&v, &f, &sources).unwrap();
    for (row, &s) in d.iter().zip(&sources) {
        let e = worst(row, |i| dist(flat[i], flat[s]));
        assert!(e < 1e-12, "source {s}: worst {e}");
    }
}

/// The unit cube's surface, each face an n × n grid; from the corner at the origin a point
/// of a face through it is straight, a point (1, y, z) of a face away from it is
/// min(√((1 + y)² + z²), √((1 + z)² + y²)) by unfolding either neighbour, and alike for the
/// other far faces.
#[test]
fn cube_distances_from_a_corner_unfold_in_closed_form() {
    let n = 4;
    let mut v: Vec<[f64; 3]> = Vec::new();
    let mut f = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut id = |p: [f64; 3], v: &mut Vec<[f64; 3]>| -> u32 {
        let key = p.map(|c| (c * n as f64).round() as i64);
        *index.entry(key).or_insert_with(|| {
            v.push(p);
            (v.len() - 1) as u32
        })
    };
    for axis in 0..3 {
        for side in [0.0, 1.0] {
            let at = |i: usize, j: usize| {
                let mut p = [0.0; 3];
                p[axis] = side;
                p[(axis + 1) % 3] = i as f64 / n as f64;
                p[(axis + 2) % 3] = j as f64 / n as f64;
                p
            };
            for i in 0..n {
                for j in 0..n {
                    let a = id(at(i, j), &mut v);
                    let b = id(at(i + 1, j), &mut v);
                    let c = id(at(i, j + 1), &mut v);
                    let dd = id(at(i + 1, j + 1), &mut v);
                    f.extend([[a, b, dd], [a, dd, c]]);
                }
            }
        }
    }
    let origin = v.iter().position(|p| *p == [0.0; 3]).unwrap();
    let d = geodesic_exact(&v, &f, &[origin]).unwrap();
    let truth = |p: [f64; 3]| {
        match (0..3).find(|&k| p[k] == 0.0) {
            Some(_) => norm(p),
            None => {
                // On the face where coordinate k is 1; the others are y, z.
                let k = (0..3).find(|&k| p[k] == 1.0).unwrap();
                let (y, z) = (p[(k + 1) % 3], p[(k + 2) % 3]);
                hyp(1.0 + y, z).min(hyp(1.0 + z, y))
            }
        }
    };
    let e = worst(&d[0], |i| truth(v[i]));
    assert!(e < 1e-12, "worst {e}");
    let far = v.iter().position(|p| *p == [1.0; 3]).unwrap();
    assert!((d[0][far] - 5f64.sqrt()).abs() < 1e-12);
}

/// Shortest path in a rectangle around an axis-aligned rectangular hole: straight when the
/// segment misses the hole's inside, else around its corners (a visibility graph).
fn around_hole(p: [f64; 2], q: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let clear = |a: [f64; 2], b: [f64; 2]| {
        // Liang–Barsky against the open rectangle.
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let dir = [b[0] - a[0], b[1] - a[1]];
        for k in 0..2 {
            for (bound, sign) in [(lo[k], -1.0), (hi[k], 1.0)] {
                let (num, den) = (sign * (bound - a[k]), sign * dir[k]);
                if den == 0.0 {
                    if num <= 0.0 {
                        return true;
                    }
                } else if den > 0.0 {
                    t1 = t1.min(num / den);
                } else {
                    t0 = t0.max(num / den);
                }
            }
        }
        t1 - t0 <= 1e-12
    };
    let nodes = [p, q, lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    let mut best = [f64::INFINITY; 6];
    best[0] = 0.0;
    let mut done = [false; 6];
    for _ in 0..6 {
        let Some(u) = (0..6).filter(|&k| !done[k]).min_by(|&x, &y| best[x].total_cmp(&best[y])) else { break };
        done[u] = true;
        for w in 0..6 {
            if !done[w] && clear(nodes[u], nodes[w]) {
                best[w] = best[w].min(best[u] + hyp(nodes[w][0] - nodes[u][0], nodes[w][1] - nodes[u][1]));
            }
        }
    }
    best[1]
}

#[test]
fn paths_go_around_a_hole() {
    let (v, f) = grid(16, 16, 1.0);
    // The hole: the squares in [5, 10] × [6, 9].
    let (lo, hi) = ([5.0, 6.0], [10.0, 9.0]);
    let f: Vec<[u32; 3]> = f
        .into_iter()
        .filter(|t| {
            let c = t.iter().fold([0.0; 2], |c, &k| [c[0] + v[k as usize][0] / 3.0, c[1] + v[k as usize][1] / 3.0]);
            !(c[0] > lo[0] && c[0] < hi[0] && c[1] > lo[1] && c[1] < hi[1])
        })
        .collect();
    let sources = [7 * 16 + 2, 16 * 4 + 7, 255];
    let d = geodesic_exact(&v, &f, &sources).unwrap();
    for (row, &s) in d.iter().zip(&sources) {
        let inside = |i: usize| v[i][0] > lo[0] && v[i][0] < hi[0] && v[i][1] > lo[1] && v[i][1] < hi[1];
        let e = worst(row, |i| if inside(i) { f64::INFINITY } else { around_hole(p2(&v, s), p2(&v, i), lo, hi) });
        assert!(e < 1e-12, "source {s}: worst {e}");
    }
    // Straight across the hole is 10; around its corners longer.
    let (a, b) = (7 * 16 + 2, 7 * 16 + 12);
    assert!(d[0][b] > 10.0 + 0.1 && (d[0][b] - around_hole(p2(&v, a), p2(&v, b), lo, hi)).abs() < 1e-12);
}

fn p2(v: &[[f64; 3]], i: usize) -> [f64; 2] {
    [v[i][0], v[i][1]]
}

/// Lengths of shortest paths along the edges: real paths on the surface, so no shorter
/// than the geodesics.
fn along_edges(v: &[[f64; 3]], f: &[[u32; 3]], s: usize) -> Vec<f64> {
    let mut d = vec![f64::INFINITY; v.len()];
    let mut done = vec![false; v.len()];
    d[s] = 0.0;
    for _ in 0..v.len() {
        let Some(u) = (0..v.len()).filter(|&k| !done[k]).min_by(|&a, &b| d[a].total_cmp(&d[b])) else { break };
        done[u] = true;
        for t in f.iter().filter(|t| t.contains(&(u as u32))) {
            for &w in t {
                d[w as usize] = d[w as usize].min(d[u] + dist(v[u], v[w as usize]));
            }
        }
    }
    d
}

/// A bumpy grid (saddles everywhere): between the straight line and the path along the
/// edges, and the same whatever the order of the faces and of their corners.
#[test]
fn a_bumpy_surface_is_bounded_and_order_free() {
    let (mut v, f) = grid(15, 13, 0.4);
    v.iter_mut().for_each(|p| p[2] = 0.3 * (1.7 * p[0]).sin() * (1.3 * p[1]).cos());
    let sources = [0, 97, 194];
    let d = geodesic_exact(&v, &f, &sources).unwrap();
    let mut g: Vec<[u32; 3]> = f.iter().rev().map(|t| [t[1], t[2], t[0]]).collect();
    g.swap(3, 40);
    let e = geodesic_exact(&v, &g, &sources).unwrap();
    for (k, &s) in sources.iter().enumerate() {
        let edges = along_edges(&v, &f, s);
        for i in 0..v.len() {
            assert!(d[k][i] >= dist(v[i], v[s]) - 1e-12 && d[k][i] <= edges[i] + 1e-12, "source {s} vertex {i}");
            assert!((d[k][i] - e[k][i]).abs() < 1e-12, "source {s} vertex {i}: {} vs {}", d[k][i], e[k][i]);
        }
    }
}

#[test]
fn unreached_and_unused_vertices_are_inf() {
    let (mut v, mut f) = grid(4, 4, 1.0);
    let (w, g) = grid(3, 3, 1.0);
    let shift = v.len() as u32;
    v.extend(w.iter().map(|p| [p[0] + 10.0, p[1], p[2]]));
    f.extend(g.iter().map(|t| t.map(|k| k + shift)));
    v.push([5.0, 5.0, 5.0]); // used by no face
    let lone = v.len() - 1;
    let d = geodesic_exact(&v, &f, &[0, 16, lone]).unwrap();
    assert!(d[0][..16].iter().all(|x| x.is_finite()));
    assert!(d[0][16..].iter().all(|x| x.is_infinite()));
    assert!(d[1][..16].iter().all(|x| x.is_infinite()) && d[1][lone].is_infinite());
    assert!((d[1][16 + 8] - 8f64.sqrt()).abs() < 1e-12);
    assert!(d[2].iter().enumerate().all(|(i, &x)| if i == lone { x == 0.0 } else { x.is_infinite() }));
}

/// Three unit-square fins on the z axis, 120° apart: two fins unfold into one plane across
/// the shared edge, so from fin 1 at (r1, z1) to fin 2 at (r2, z2) it is √((r1 + r2)² + Δz²).
#[test]
fn a_non_manifold_edge_passes_paths_to_every_fin() {
    let n = 4;
    let mut v: Vec<[f64; 3]> = (0..=n).map(|j| [0.0, 0.0, j as f64 / n as f64]).collect();
    let mut f = Vec::new();
    let mut fin_of = vec![(0usize, 0.0, 0.0); v.len()];
    for k in 0..v.len() {
        fin_of[k] = (usize::MAX, 0.0, v[k][2]);
    }
    for fin in 0..3 {
        let a = 2.0 * PI * fin as f64 / 3.0;
        let base = v.len();
        let id = |i: usize, j: usize| if i == 0 { j as u32 } else { (base + (i - 1) * (n + 1) + j) as u32 };
        for i in 1..=n {
            for j in 0..=n {
                let r = i as f64 / n as f64;
                v.push([r * a.cos(), r * a.sin(), j as f64 / n as f64]);
                fin_of.push((fin, r, j as f64 / n as f64));
            }
        }
        for i in 0..n {
            for j in 0..n {
                f.extend([[id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]]);
            }
        }
    }
    let s = n + 1 + 2 * (n + 1) + 1; // fin 0, r = 3/4, z = 1/4
    let d = geodesic_exact(&v, &f, &[s]).unwrap();
    let (_, rs, zs) = fin_of[s];
    let e = worst(&d[0], |i| {
        let (fin, r, z) = fin_of[i];
        if fin == 0 {
            hyp(r - rs, z - zs)
        } else {
            hyp(r + rs, z - zs)
        }
    });
    assert!(e < 1e-12, "worst {e}");
}

/// A flat grid where one edge (a, d) is split at its midpoint m on one side only, the crack
/// closed by the zero-area face (a, d, m): paths cross the sliver, distances stay Euclidean.
/// With m moved 1e-9 or 1e-6 off the edge into its side's triangle, (a, d, m) is a
/// near-zero-area needle of a planar triangulation instead.
#[test]
fn paths_cross_zero_and_near_zero_area_slivers() {
    for off in [0.0, 1e-9, 1e-6] {
        let (mut v, mut f) = grid(9, 9, 1.0);
        // Square (3, 3)-(4, 4), (i + j) even: faces [a, b, d], [a, d, c] share the diagonal a-d.
        let (a, d) = (3 * 9 + 3, 4 * 9 + 4);
        let c = a + 9;
        let k = f.iter().position(|t| *t == [a as u32, d as u32, c as u32]).unwrap();
        let shift = off / 2f64.sqrt();
        v.push([3.5 - shift, 3.5 + shift, 0.0]);
        let mid = (v.len() - 1) as u32;
        f[k] = [a as u32, mid, c as u32];
        f.push([mid, d as u32, c as u32]);
        f.push([a as u32, d as u32, mid]);
        let sources = [0, 80, 4, 36, mid as usize];
        let dd = geodesic_exact(&v, &f, &sources).unwrap();
        for (row, &s) in dd.iter().zip(&sources) {
            let e = worst(row, |i| dist(v[i], v[s]));
            assert!(e < 1e-12, "offset {off}, source {s}: worst {e}");
        }
    }
}

#[test]
fn degenerate_faces_give_no_nan_and_no_panic() {
    let (mut v, mut f) = grid(6, 6, 1.0);
    v.push(v[14]); // a copy of vertex 14
    let copy = (v.len() - 1) as u32;
    f.push([14, copy, 15]); // zero-length edge
    f.push([7, 7, 8]); // a vertex named twice
    f.push([20, 21, 22]); // collinear
    f.push([copy, 30, 31]);
    f.push([3, 3, 3]);
    // As far as a coordinate may be (its square still finite); beyond, the input is refused.
    v.push([crate::error::MAX_COORDINATE, 0.0, 0.0]);
    let far = (v.len() - 1) as u32;
    f.push([0, 1, far]);
    let sources: Vec<usize> = (0..v.len()).step_by(5).collect();
    let mut beyond = v.clone();
    beyond[far as usize][0] = f64::MAX / 4.0;
    assert!(geodesic_exact(&beyond, &f, &sources).unwrap_err().to_string().contains("vertices"));
    let d = geodesic_exact(&v, &f, &sources).unwrap();
    for (row, &s) in d.iter().zip(&sources) {
        assert!(row.iter().all(|x| !x.is_nan()), "source {s}");
        assert_eq!(row[s], 0.0);
        for (i, &x) in row.iter().enumerate() {
            // No path on the surface is shorter than the straight line.
            assert!(x >= dist(v[i], v[s]) * (1.0 - 1e-12), "source {s} vertex {i}: {x}");
        }
    }
}

#[test]
fn bad_input_is_refused_by_name_and_threads_do_not_change_results() {
    let (v, f) = grid(8, 8, 1.0);
    assert!(geodesic_exact(&v, &f, &[64]).unwrap_err().to_string().contains("sources"));
    assert!(geodesic_exact(&v, &[[0, 1, 64]], &[0]).unwrap_err().to_string().contains("faces"));
    let mut bad = v.clone();
    bad[3][1] = f64::NAN;
    assert!(geodesic_exact(&bad, &f, &[0]).unwrap_err().to_string().contains("vertices"));
    let sources: Vec<usize> = (0..64).collect();
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let one = pool(1).install(|| geodesic_exact(&v, &f, &sources).unwrap());
    let three = pool(3).install(|| geodesic_exact(&v, &f, &sources).unwrap());
    assert!(one.iter().flatten().zip(three.iter().flatten()).all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// One source alone runs in two parts, on two threads or in turn on one: the same bits
/// either way, and the same distances as in a batch (one part) up to rounding; on a bumpy
/// grid (saddles everywhere) of 28 face blocks, where the parts exchange news every round.
#[test]
fn one_source_on_two_threads_is_the_same_as_on_one_and_in_a_batch() {
    let (mut v, f) = grid(60, 60, 0.5);
    v.iter_mut().for_each(|p| p[2] = 0.2 * (1.3 * p[0]).sin() * (1.1 * p[1]).cos());
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let batch = pool(2).install(|| geodesic_exact(&v, &f, &[1830, 7, 3599]).unwrap());
    for (k, s) in [1830, 7, 3599].into_iter().enumerate() {
        let paired = pool(2).install(|| geodesic_exact(&v, &f, &[s]).unwrap());
        let alone = pool(1).install(|| geodesic_exact(&v, &f, &[s]).unwrap());
        assert!(paired[0].iter().zip(&alone[0]).all(|(x, y)| x.to_bits() == y.to_bits()), "source {s}");
        let e = worst(&paired[0], |i| batch[k][i]);
        assert!(e < 1e-12, "source {s}: {e}");
        let edges = along_edges(&v, &f, s);
        assert!((0..v.len()).all(|i| batch[k][i] >= dist(v[i], v[s]) - 1e-12 && batch[k][i] <= edges[i] + 1e-12));
    }
}

/// Buffers an earlier source or mesh left serve the next, larger or smaller, with the bits of
/// fresh ones; so do a prepared mesh's buffers from call to call.
#[test]
fn buffers_used_before_give_the_bits_of_fresh_ones() {
    let bumpy = |n: usize| {
        let (mut v, f) = grid(n, n, 0.5);
        v.iter_mut().for_each(|p| p[2] = 0.2 * (1.3 * p[0]).sin() * (1.1 * p[1]).cos());
        (v, f)
    };
    let (big, small) = (bumpy(50), bumpy(30));
    let row = |(v, f): &(Vec<[f64; 3]>, Vec<[u32; 3]>), works: &mut [Buffers; 2], split| {
        let layout = Layout::new(v, f);
        distances_from(&layout, works, v.len(), 7, split).unwrap()
    };
    for split in [Split::Whole, Split::InTurn] {
        let fresh = [&big, &small].map(|mesh| row(mesh, &mut Default::default(), split));
        let mut used: [Buffers; 2] = Default::default();
        for (k, mesh) in [&small, &big, &small, &big].into_iter().enumerate() {
            let again = row(mesh, &mut used, split);
            let expected = &fresh[(k + 1) % 2];
            assert!(again.iter().zip(expected).all(|(x, y)| x.to_bits() == y.to_bits()), "mesh {k}");
        }
    }
    let prepared = ExactGeodesics::new(&big.0, &big.1);
    let first = prepared.distances(&[7, 8, 9]).unwrap();
    let again = prepared.distances(&[9, 7]).unwrap();
    let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
    assert!(same(&again[0], &first[2]) && same(&again[1], &first[0]));
}

/// A propagation whose work budget runs out says so, in one part and in two, in turn and on
/// two threads (the budget only guards against a pathological mesh looping for ever; here it
/// is cut to a few sides of the bumpy grid, which needs thousands).
#[test]
fn a_propagation_out_of_its_work_budget_fails() {
    let (mut v, f) = grid(60, 60, 0.5);
    v.iter_mut().for_each(|p| p[2] = 0.2 * (1.3 * p[0]).sin() * (1.1 * p[1]).cos());
    let layout = Layout::new(&v, &f);
    let inner = layout.inner[1830] as usize;
    let mut w = Buffers::default();
    w.reset(&layout);
    let mut whole = Wavefront::new(&layout, &mut w, WHOLE);
    whole.budget = 200;
    whole.start(inner);
    assert!(!whole.round(f64::INFINITY));
    for paired in [false, true] {
        let (mut w0, mut w1) = (Buffers::default(), Buffers::default());
        w0.reset(&layout);
        w1.reset(&layout);
        let (mut a, mut b) = (Wavefront::new(&layout, &mut w0, 0), Wavefront::new(&layout, &mut w1, 1));
        (a.budget, b.budget) = (200, 200);
        a.start(inner);
        b.start(inner);
        let mut rounds = Rounds::new(&layout);
        let ok =
            if paired { in_two_threads(&mut a, &mut b, &mut rounds) } else { in_turn(&mut a, &mut b, &mut rounds) };
        assert!(!ok, "paired: {paired}");
    }
}
