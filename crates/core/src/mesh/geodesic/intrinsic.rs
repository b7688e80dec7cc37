//! An intrinsic triangulation: a triangle mesh held as edge lengths, flipped to the intrinsic
//! Delaunay triangulation without changing the surface (Bobenko & Springborn 2007; Sharp,
//! Soliman & Crane, "Navigating intrinsic triangulations", 2019), on Sharp & Crane's tufted
//! cover where the mesh has a boundary ("A Laplacian for nonmanifold triangle meshes", 2020).
//! The heat method builds its operators on it (`heat`).

/// "No twin": the edge is never flipped.
pub(super) const NONE: u32 = u32::MAX;

/// The area of a triangle from its side lengths (Kahan's ordering of Heron's formula, accurate
/// for needles); 0 when the lengths violate the triangle inequality.
pub(super) fn area(a: f64, b: f64, c: f64) -> f64 {
    let mut s = [a, b, c];
    s.sort_unstable_by(|x, y| y.total_cmp(x));
    let [a, b, c] = s;
    let p = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
    if p > 0.0 {
        0.25 * p.sqrt()
    } else {
        0.0
    }
}

/// Strict triangle inequalities.
pub(super) fn is_triangle(a: f64, b: f64, c: f64) -> bool {
    a < b + c && b < a + c && c < a + b
}

/// A triangulation held as edge lengths: halfedge 3f + k runs from corner k to corner k + 1 of
/// face f, and its twin is the halfedge of the other face along the same edge, in the opposite
/// direction, when the edge has exactly two faces oriented alike (NONE otherwise: such an edge
/// is never flipped). A flip may leave two faces sharing two edges, or a vertex twice in one
/// face: a Δ-complex, which the operators below handle since they only accumulate by corner.
pub(super) struct Intrinsic {
    pub(super) tri: Vec<[u32; 3]>,
    pub(super) len: Vec<f64>,
    pub(super) twin: Vec<u32>,
}

impl Intrinsic {
    /// The cotangent of the angle opposite halfedge h in its face.
    pub(super) fn cot_opposite(&self, h: usize) -> f64 {
        let (f, k) = (h / 3, h % 3);
        let (a, b, c) = (self.len[3 * f + (k + 1) % 3], self.len[3 * f + (k + 2) % 3], self.len[h]);
        (a * a + b * b - c * c) / (4.0 * area(a, b, c))
    }

    /// Flips until every flippable edge is Delaunay (opposite angles summing to ≤ π). Each flip
    /// lowers the Dirichlet energy of the piecewise-linear interpolant (Rippa), so the loop
    /// ends; the cap only guards against a rounding cycle.
    pub(super) fn flip_to_delaunay(&mut self) {
        let nh = self.len.len();
        let mut stack: Vec<usize> = (0..nh).filter(|&h| self.twin[h] != NONE && h < self.twin[h] as usize).collect();
        let mut queued = vec![false; nh];
        for &h in &stack {
            queued[h] = true;
        }
        let mut budget = 20 * nh + 100;
        while let Some(h) = stack.pop() {
            queued[h] = false;
            let g = self.twin[h];
            // A tolerance so that a cocircular pair (a square's diagonal) is left alone.
            if g == NONE {
                continue;
            }
            let sum = self.cot_opposite(h) + self.cot_opposite(g as usize);
            if sum.is_nan() || sum >= -1e-12 {
                continue;
            }
            if budget == 0 {
                break;
            }
            if !self.flip(h) {
                continue;
            }
            budget -= 1;
            let (f1, f2) = (h / 3, g as usize / 3);
            for s in [3 * f1 + 1, 3 * f1 + 2, 3 * f2 + 1, 3 * f2 + 2] {
                if self.twin[s] != NONE && !queued[s] {
                    queued[s] = true;
                    stack.push(s);
                }
            }
        }
    }

    /// The tufted cover (Sharp & Crane 2020): the faces twice, a front and a back sheet, glued
    /// edge to edge as the mesh is and front to back along the boundary `boundary` (front
    /// halfedges). A boundary edge then has two opposite angles too and is flipped like any
    /// other when they sum to more than π: on an open mesh a boundary triangle with an obtuse
    /// angle opposite the boundary (a convex hull's slivers) otherwise keeps a negative cotangent
    /// weight, the heat goes negative and the distances there fall to half (measured on a random
    /// xy Delaunay mesh: 8 % mean error, 54 % worst; potpourri3d, which builds this cover, 1.2 %).
    /// Without flips both sheets are alike and each counts half: the operators are the mesh's.
    pub(super) fn tufted(self, boundary: &[usize]) -> Intrinsic {
        let f = self.tri.len();
        // The back copy of face (a, b, c) is (b, a, c): halfedge k of the front runs along the
        // same edge as halfedge [0, 2, 1][k] of the back, the other way.
        let back = |h: usize| 3 * (f + h / 3) + [0, 2, 1][h % 3];
        let (mut tri, mut len) = (self.tri, self.len);
        tri.extend_from_within(..);
        len.extend_from_within(..);
        for t in &mut tri[f..] {
            *t = [t[1], t[0], t[2]];
        }
        for l in len[3 * f..].chunks_exact_mut(3) {
            l.swap(1, 2);
        }
        let mut twin = vec![NONE; 2 * self.twin.len()];
        for (h, &t) in self.twin.iter().enumerate() {
            if t != NONE {
                twin[h] = t;
                twin[back(h)] = back(t as usize) as u32;
            }
        }
        for &h in boundary {
            twin[h] = back(h) as u32;
            twin[back(h)] = h as u32;
        }
        Intrinsic { tri, len, twin }
    }

    /// Replaces the edge of halfedge h (a → b, in face (a, b, i), its twin in (b, a, j)) by the
    /// edge i–j, measured in the plane where both triangles are laid out. Refused (false) when
    /// the two faces are one or a new triangle would be degenerate.
    pub(super) fn flip(&mut self, h: usize) -> bool {
        let g = self.twin[h] as usize;
        let (f1, k1, f2, k2) = (h / 3, h % 3, g / 3, g % 3);
        if f1 == f2 {
            return false;
        }
        let (h1, h2) = (3 * f1 + (k1 + 1) % 3, 3 * f1 + (k1 + 2) % 3);
        let (g1, g2) = (3 * f2 + (k2 + 1) % 3, 3 * f2 + (k2 + 2) % 3);
        let (a, b, i) = (self.tri[f1][k1], self.tri[f1][(k1 + 1) % 3], self.tri[f1][(k1 + 2) % 3]);
        let j = self.tri[f2][(k2 + 2) % 3];
        // h: a→b, h1: b→i, h2: i→a; g: b→a, g1: a→j, g2: j→b.
        let (lab, lbi, lia, laj, ljb) = (self.len[h], self.len[h1], self.len[h2], self.len[g1], self.len[g2]);
        if lab.is_nan() || lab <= 0.0 {
            return false;
        }
        // a at the origin, b on the x axis, i above it, j below.
        let xi = (lab * lab + lia * lia - lbi * lbi) / (2.0 * lab);
        let yi = 2.0 * area(lab, lbi, lia) / lab;
        let xj = (lab * lab + laj * laj - ljb * ljb) / (2.0 * lab);
        let yj = 2.0 * area(lab, laj, ljb) / lab;
        let d = (xi - xj).hypot(yi + yj);
        if !(is_triangle(d, lia, laj) && is_triangle(d, ljb, lbi)) {
            return false;
        }
        // New faces (j, i, a) and (i, j, b): slot 0 of each is the new edge; the four outer
        // halfedges move to the slots listed, their twins follow.
        let old = [h1, h2, g1, g2];
        let new = [3 * f2 + 2, 3 * f1 + 1, 3 * f1 + 2, 3 * f2 + 1];
        let saved = old.map(|x| (self.len[x], self.twin[x]));
        let moved = |x: u32| old.iter().position(|&o| o == x as usize).map_or(x, |q| new[q] as u32);
        for q in 0..4 {
            let (l, t) = saved[q];
            self.len[new[q]] = l;
            let t = if t == NONE { NONE } else { moved(t) };
            self.twin[new[q]] = t;
            if t != NONE {
                self.twin[t as usize] = new[q] as u32;
            }
        }
        self.len[3 * f1] = d;
        self.len[3 * f2] = d;
        self.twin[3 * f1] = (3 * f2) as u32;
        self.twin[3 * f2] = (3 * f1) as u32;
        self.tri[f1] = [j, i, a];
        self.tri[f2] = [i, j, b];
        true
    }
}
