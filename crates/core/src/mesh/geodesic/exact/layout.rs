//! The mesh as the exact propagation sees it: half-edges in their unfolding frames, undirected
//! edges, pseudo-sources, faces renumbered along a Morton curve and dealt to the two parts.
use super::*;

/// A half-edge `3 f + i` runs from `faces[f][i]` to `faces[f][(i + 1) % 3]`; in its frame (start
/// at the origin, along +x) the face's third vertex is at (cx, cy), cy ≥ 0. `mate` is the other
/// half-edge of its edge (with `SAME` when it runs the same way), `NONE` on a boundary, `MANY` on
/// an edge of more than two faces.
#[derive(Clone, Copy)]
pub(super) struct Half {
    pub(super) len: f64,
    pub(super) cx: f64,
    pub(super) cy: f64,
    pub(super) mate: u32,
}

impl Default for Half {
    fn default() -> Self {
        Half { len: 0.0, cx: 0.0, cy: 0.0, mate: NONE }
    }
}

pub(super) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub(super) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

pub(super) fn hyp(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

pub(super) fn distinct(f: &[u32; 3]) -> bool {
    f[0] != f[1] && f[1] != f[2] && f[0] != f[2]
}

/// 21 bits of `x` spread to every third bit.
pub(super) fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f00000000ffff;
    x = (x | x << 16) & 0x1f0000ff0000ff;
    x = (x | x << 8) & 0x100f00f00f00f00f;
    x = (x | x << 4) & 0x10c30c30c30c30c3;
    (x | x << 2) & 0x1249249249249249
}

/// The mesh as the propagation sees it, built once for all sources.
pub(super) struct Layout {
    /// Vertices and faces renumbered: faces along a Morton curve of their centroids, vertices in
    /// the order the faces first use them (the unused ones last).
    pub(super) points: Vec<[f64; 3]>,
    pub(super) faces: Vec<[u32; 3]>,
    /// The new number of each given vertex.
    pub(super) inner: Vec<u32>,
    pub(super) half: Vec<Half>,
    /// Half-edges on one undirected edge: `edge_half[edge_start[e]..edge_start[e + 1]]` for
    /// `e = edge_of[h]`; `NONE` for the half-edges of a face that names a vertex twice.
    pub(super) edge_of: Vec<u32>,
    pub(super) edge_start: Vec<u32>,
    pub(super) edge_half: Vec<u32>,
    pub(super) pseudo: Vec<bool>,
    pub(super) around: Around,
    /// Absolute rounding scale of the mesh: 1e-15 of its extent.
    pub(super) tiny: f64,
    /// Which of the two parts of a propagation works on each face (blocks of the Morton order,
    /// alternately), and whether a vertex has faces in both.
    pub(super) owner: Vec<u8>,
    pub(super) shared: Vec<bool>,
    /// The mean length of the half-edges (1 when all are degenerate): the first band of rounds.
    pub(super) mean_edge: f64,
}

/// Each face's half-edges, and per vertex its corner angles summed and whether it is a
/// pseudo-source so far (on a face that names a vertex twice or is a sliver). The faces in
/// parallel, then the angles summed per vertex in face order (the same sums on any number of
/// threads; a face that names a vertex twice adds angles of 0).
pub(super) fn geometry(points: &[[f64; 3]], faces: &[[u32; 3]]) -> (Vec<Half>, Vec<f64>, Vec<bool>) {
    let p = |v: u32| points[v as usize];
    let mut half = vec![Half::default(); 3 * faces.len()];
    let corners: Vec<([f64; 3], bool)> = half
        .par_chunks_mut(3)
        .zip(faces.par_iter())
        .map(|(half, face)| {
            // The corners' angles, and whether the face makes its vertices pseudo-sources.
            let mut angle = [0.0; 3];
            if !distinct(face) {
                return (angle, true);
            }
            let mut longest: f64 = 0.0;
            for i in 0..3 {
                let (a, b, c) = (p(face[i]), p(face[(i + 1) % 3]), p(face[(i + 2) % 3]));
                let (ab, ac) = (sub(b, a), sub(c, a));
                let len = norm(ab);
                longest = longest.max(len);
                let area = norm(cross(ab, ac));
                if len > 0.0 {
                    half[i] = Half { len, cx: dot(ac, ab) / len, cy: area / len, mate: NONE };
                }
                angle[i] = area.atan2(dot(ab, ac));
            }
            let height = half.iter().map(|h| h.cy).fold(f64::INFINITY, f64::min);
            (angle, !(height > SLIVER * longest))
        })
        .collect();
    let mut angle = vec![0.0; points.len()];
    let mut pseudo = vec![false; points.len()];
    for (face, (a, degenerate)) in faces.iter().zip(&corners) {
        for i in 0..3 {
            angle[face[i] as usize] += a[i];
            pseudo[face[i] as usize] |= *degenerate;
        }
    }
    (half, angle, pseudo)
}

/// The undirected edges (`Layout::edge_of`, `edge_start`, `edge_half`).
pub(super) struct Edges {
    pub(super) edge_of: Vec<u32>,
    pub(super) edge_start: Vec<u32>,
    pub(super) edge_half: Vec<u32>,
}

impl Edges {
    /// The half-edges sorted by their vertex pair, then by number: a counting sort by the
    /// smaller vertex, then each vertex's few sorted (a comparison sort of all of them was the
    /// layout's slowest step).
    pub(super) fn new(n: usize, faces: &[[u32; 3]]) -> Self {
        let mut first = vec![0u32; n + 1];
        for face in faces.iter().filter(|face| distinct(face)) {
            (0..3).for_each(|i| first[face[i].min(face[(i + 1) % 3]) as usize + 1] += 1);
        }
        for v in 0..n {
            first[v + 1] += first[v];
        }
        let mut keyed = vec![(0u32, 0u32, 0u32); first[n] as usize];
        let mut next = first.clone();
        for (f, face) in faces.iter().enumerate() {
            if distinct(face) {
                for i in 0..3 {
                    let (a, b) = (face[i], face[(i + 1) % 3]);
                    let slot = &mut next[a.min(b) as usize];
                    keyed[*slot as usize] = (a.min(b), a.max(b), (3 * f + i) as u32);
                    *slot += 1;
                }
            }
        }
        for v in 0..n {
            keyed[first[v] as usize..first[v + 1] as usize].sort_unstable();
        }
        let mut edge_of = vec![NONE; 3 * faces.len()];
        let mut edge_start = Vec::new();
        let mut edge_half = Vec::with_capacity(keyed.len());
        for (k, &(a, b, h)) in keyed.iter().enumerate() {
            if k == 0 || (keyed[k - 1].0, keyed[k - 1].1) != (a, b) {
                edge_start.push(edge_half.len() as u32);
            }
            edge_of[h as usize] = (edge_start.len() - 1) as u32;
            edge_half.push(h);
        }
        edge_start.push(edge_half.len() as u32);
        Edges { edge_of, edge_start, edge_half }
    }
}

impl Layout {
    pub(super) fn new(given_points: &[[f64; 3]], given_faces: &[[u32; 3]]) -> Self {
        let n = given_points.len();
        // Morton order of the face centroids.
        let centroid = |f: &[u32; 3]| {
            let p = f.map(|v| given_points[v as usize]);
            [0, 1, 2].map(|k| p[0][k] / 3.0 + p[1][k] / 3.0 + p[2][k] / 3.0)
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for f in given_faces {
            let c = centroid(f);
            for k in 0..3 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        let scale = [0, 1, 2].map(|k| if hi[k] > lo[k] { 2097151.0 / (hi[k] - lo[k]) } else { 0.0 });
        let mut order: Vec<(u64, u32)> = given_faces
            .par_iter()
            .enumerate()
            .map(|(i, f)| {
                let c = centroid(f);
                let q = [0, 1, 2].map(|k| ((c[k] - lo[k]) * scale[k]).clamp(0.0, 2097151.0) as u64);
                (spread(q[0]) | spread(q[1]) << 1 | spread(q[2]) << 2, i as u32)
            })
            .collect();
        order.par_sort_unstable();
        let mut inner = vec![NONE; n];
        let mut outer = Vec::with_capacity(n);
        let mut faces = Vec::with_capacity(given_faces.len());
        for &(_, i) in &order {
            faces.push(given_faces[i as usize].map(|v| {
                if inner[v as usize] == NONE {
                    inner[v as usize] = outer.len() as u32;
                    outer.push(v);
                }
                inner[v as usize]
            }));
        }
        for (v, slot) in inner.iter_mut().enumerate() {
            if *slot == NONE {
                *slot = outer.len() as u32;
                outer.push(v as u32);
            }
        }
        let points: Vec<[f64; 3]> = outer.iter().map(|&v| given_points[v as usize]).collect();

        // The faces' geometry (in parallel) and the undirected edges (a serial counting sort) at
        // once: the serial sort would otherwise leave the other threads idle.
        let ((mut half, angle, mut pseudo), (edges, around)) =
            rayon::join(|| geometry(&points, &faces), || (Edges::new(n, &faces), Around::new(n, &faces)));
        let Edges { edge_of, edge_start, edge_half } = edges;
        let start = |h: u32| faces[h as usize / 3][h as usize % 3];
        for e in 0..edge_start.len() - 1 {
            let group = &edge_half[edge_start[e] as usize..edge_start[e + 1] as usize];
            if let &[g, h] = group {
                let same = if start(g) == start(h) { SAME } else { 0 };
                half[g as usize].mate = h | same;
                half[h as usize].mate = g | same;
            } else if group.len() > 2 {
                group.iter().for_each(|&h| half[h as usize].mate = MANY);
            }
            if group.len() != 2 {
                let (a, b) = (start(group[0]), faces[group[0] as usize / 3][(group[0] as usize + 1) % 3]);
                pseudo[a as usize] = true;
                pseudo[b as usize] = true;
            }
        }

        let extent = points.iter().flat_map(|q| q.iter()).fold(0.0f64, |m, c| m.max(c.abs()));
        let owner: Vec<u8> = (0..faces.len()).map(|f| ((f / FACE_BLOCK) & 1) as u8).collect();
        let mut parts = vec![0u8; n];
        for (face, &o) in faces.iter().zip(&owner) {
            face.iter().for_each(|&v| parts[v as usize] |= 1 << o);
        }
        let shared = parts.iter().map(|&p| p == 3).collect();
        let mean_edge = half.iter().map(|h| h.len).sum::<f64>() / half.len().max(1) as f64;
        let mut layout = Layout {
            points,
            faces,
            inner,
            half,
            edge_of,
            edge_start,
            edge_half,
            pseudo,
            around,
            tiny: 1e-15 * extent,
            owner,
            shared,
            mean_edge: if mean_edge > 0.0 { mean_edge } else { 1.0 },
        };
        // one_fan(v) reads only v's own flag, so the vertices can be decided in parallel.
        let pseudo: Vec<bool> = angle
            .par_iter()
            .enumerate()
            .map(|(v, &total)| layout.pseudo[v] || total > 2.0 * PI - 1e-5 || !layout.one_fan(v))
            .collect();
        layout.pseudo = pseudo;
        layout
    }

    /// The vertex half-edge `h` starts at.
    pub(super) fn start(&self, h: usize) -> u32 {
        self.faces[h / 3][h % 3]
    }

    /// The other half-edges of `h`'s edge, each with whether it runs the same way as `h`.
    pub(super) fn others(&self, h: usize) -> impl Iterator<Item = (usize, bool)> + '_ {
        let (one, many): (Option<u32>, &[u32]) = match self.half[h].mate {
            NONE => (None, &[]),
            MANY => {
                let e = self.edge_of[h] as usize;
                (None, &self.edge_half[self.edge_start[e] as usize..self.edge_start[e + 1] as usize])
            }
            t => (Some(t), &[]),
        };
        let one = one.map(|t| ((t & !SAME) as usize, t & SAME != 0));
        let many = many.iter().map(|&t| t as usize).filter(move |&t| t != h);
        one.into_iter().chain(many.map(move |t| (t, self.start(t) == self.start(h))))
    }

    /// Whether the faces around an interior vertex `v` (every edge at it shared by two faces)
    /// form one closed fan; two fans meeting at a vertex let paths bend there.
    pub(super) fn one_fan(&self, v: usize) -> bool {
        if self.pseudo[v] {
            return true; // already a pseudo-source, nothing to decide
        }
        let around = self.around.of(v);
        let Some(&first) = around.first() else {
            return true;
        };
        // The half-edge of face f that touches v and is not `not`: (v → next) or (prev → v).
        let other_side = |f: usize, not: usize| -> Option<usize> {
            let k = self.faces[f].iter().position(|&u| u as usize == v)?;
            let (out, inn) = (3 * f + k, 3 * f + (k + 2) % 3);
            Some(if out == not { inn } else { out })
        };
        let (mut f, mut h) = (first as usize, usize::MAX);
        for step in 1..=around.len() {
            let Some(exit) = other_side(f, h) else {
                return false;
            };
            // An interior vertex's edges have two faces each (else it is a pseudo-source already).
            let mate = self.half[exit].mate;
            if mate >= MANY {
                return false;
            }
            let next = (mate & !SAME) as usize;
            f = next / 3;
            h = next;
            if f == first as usize {
                return step == around.len();
            }
        }
        false
    }
}
