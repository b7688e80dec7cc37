//! Exact geodesic distances on a triangle mesh (SPEC S3; paper 002 §3.2): the length of the
//! shortest path along the polyhedral surface from a source vertex to every vertex.
//!
//! # The maths
//!
//! On a polyhedral surface a shortest path is straight inside every face it crosses: laid flat
//! ("unfolded") into one plane, the faces it crosses show it as a straight segment. It bends only
//! at vertices where the surface is not locally convex: saddle vertices (total angle ≥ 2π) and
//! boundary vertices [MMP87]. So with the *pseudo-sources* (the source, saddle and boundary
//! vertices) d(p) = min over pseudo-sources v of d(v) + |v p|, |v p| the length of a straight
//! segment from v to p in an unfolding in which the segment stays on the surface.
//!
//! A *window* is a bundle of such straight segments from one pseudo-source, across one sequence
//! of faces, that reach an interval [b0, b1] of an edge. In the frame of the edge (its start at
//! the origin, the edge along +x, the face the window enters on +y) it is (b0, b1, s, σ): s =
//! (sx, sy), sy < 0, is the unfolded pseudo-source and σ its distance, and the distance it
//! carries to the point x of the edge is f(x) = σ + |s − (x, 0)|. Crossing the face ABC it enters
//! (A = (0, 0), B = (L, 0), C = (cx, cy), cy ≥ 0), the rays from s through [b0, b1] left of the
//! ray s→C leave through AC and those right of it through CB; the ray s→C crosses the x axis at
//!
//! ```text
//!     xc = sx + (cx − sx)·(−sy)/(cy − sy)
//! ```
//!
//! and where xc ∈ [b0, b1] C is reached at σ + |sC| [CH90]. The ray through (b, 0) meets AC at
//! A + μ(C − A) and CB at B + ν(C − B) with
//!
//! ```text
//!     μ = sy·b / (cx·sy + cy·(b − sx)),      ν = sy·(b − L) / ((cx − L)·sy + cy·(b − sx)),
//! ```
//!
//! which stay finite on zero-area faces (cy = 0: μ = b/cx, ν = (b − L)/(cx − L)), so a path can
//! cross a sliver.
//!
//! # The algorithm
//!
//! A window-propagation method of the MMP family [MMP87, SSK05] with the pruning of the
//! Improved Chen–Han algorithm [XW09] and the triangle-oriented batching of VTP [QHY16]. One
//! radix queue holds the pseudo-sources (by distance) and the sides of edges where windows wait
//! (by the smallest distance a waiting window carries). A pseudo-source's turn comes after
//! everything nearer, so its distance is final and it emits once: to its neighbours along the
//! edges, and one window over each edge opposite it. A side's turn sends all its waiting
//! windows across its face together (they share the face's data in cache; their order among
//! themselves does not matter), each making at most two children on the face's other edges:
//! first the whole batch reaches the apex, so that every window of it splits by the batch's
//! best path there (rule 2) and every child is cut by the apex's distance (rule 1).
//!
//! Windows lose the parts that another known path beats at every point. Each rule compares
//! with a real path (a vertex distance is always the length of some path), strictly and with a
//! margin for rounding, so no part of a shortest path is ever dropped and the distances stay
//! exact:
//!
//! 1. *Edge ends* [XW09]: vertex A reaches the point x of its edge at d(A) + x. Since f(x) − x
//!    does not increase, the points where A wins form a prefix of the window, cut off by solving
//!    f(x) − x = d(A): x = (sx² + sy² − k²) / (2(k + sx)), k = d(A) − σ. B cuts a suffix alike.
//!    Applied when a window is made, with the ends' distances then; it is what stops windows
//!    that come round again far behind the front (applied again when the window crosses its
//!    face, with the latest distances, it cut almost nothing).
//! 2. *One angle, one split* [XW09, QHY16]: per face and entering edge, the best path so far from
//!    that edge to the apex C, of length D* crossing the edge at q*. A window that reaches C
//!    longer than D* is beaten by that path wherever its rays cross the segment q*C, so its rays
//!    left of q* only go on through AC and those right of q* only through CB.
//! 3. *Windows against windows* [MMP87, SSK05]: the windows waiting on one side of an edge are
//!    kept cut to a disjoint list in order along the edge, each piece where its window is best
//!    (the earlier where two tie); a new window also loses what a window waiting on another side
//!    of the edge beats. f_w − f_o vanishes where a hyperbola meets the edge, at most twice:
//!    squaring σ_w + r_w = σ_o + r_o twice leaves a quadratic, whose roots Newton steps on
//!    f_w − f_o polish. Windows that have crossed are not kept: on the bunny they would cut
//!    almost nothing more.
//!
//! Vertex distances come from the rays that reach the apex (or the shortest path through a
//! window end, also a real path) and from a pseudo-source to its neighbours along the edges.
//!
//! Several sources in one call run in parallel, one per thread. The one source of a call runs in
//! two parts (on meshes of 2048 faces and more): the faces are dealt in blocks of the Morton
//! order (below) to two parts, each with its own queue, windows and copy of the vertex
//! distances. They take their queued work in rounds, each round up to a common bound a band
//! further on, and each hands the other what it found for it: windows leaving into the other's
//! faces and new distances of vertices on both. A round has two halves: first what the part had
//! queued, then, with the other's news of the round before, what that brings; so a part whose
//! round was light goes on with the next round's first half instead of waiting (`Rounds`). On
//! two threads the parts run at once (one source on the bunny 1.6–1.8× faster than on one), on
//! one in turn, and in turn too once two threads stop paying (when another program keeps the
//! second core busy); nothing depends on the threads, so neither do the distances. Out of
//! order within a band, a part may settle a pseudo-source before a shorter path to it arrives
//! from the other: it then emits again, at the shorter distance, and what it emitted before
//! loses to that (a pseudo-source too early costs time, never accuracy). A source's row alone
//! and in a batch are the same up to rounding.
//!
//! The work: on the Stanford bunny (69 451 faces, about half its vertices saddles) the distance
//! field along the edges has some 14 pieces per edge (Kirsanov's MMP ends with 1.455 million
//! intervals), and every one has to cross its face once (this code: 1.55 million crossings per
//! source); the cost is per window: memory traffic and square roots. So the faces are
//! renumbered along a Morton curve of their centroids, a half-edge's data sits together, the
//! queue is a radix heap (distances mostly grow; what comes in behind waits in a binary heap)
//! in which a batch queues each side it gave windows to once, when it is done; a side's list of
//! pieces is taken from a pool of emptied lists when its first window comes and given back when
//! it has crossed (only the front holds storage, and it is warm in cache), every square root a
//! window's tests share is taken once, and the buffers are kept from one source to the next
//! and, up to 256 MB, from one mesh to the next (`KEPT`).
//!
//! Degenerate input: a non-manifold edge passes each window on to every other face on it. A
//! vertex on a boundary or non-manifold edge, where the faces around it are not one fan, or on a
//! face of near-zero area is a pseudo-source (a pseudo-source too many costs time, never
//! accuracy). A pseudo-source lying on the line of the edge it emits across (a zero-area face
//! closing a T-junction) emits into the face beyond as if it were its vertex. A face naming a
//! vertex twice is only a segment: distances pass along its edges, no window enters it.
//!
//! [MMP87] J. Mitchell, D. Mount, C. Papadimitriou, "The discrete geodesic problem", SIAM J.
//! Comput. 16(4), 1987. [CH90] J. Chen, Y. Han, "Shortest paths on a polyhedron", Proc. SoCG
//! 1990. [SSK05] V. Surazhsky, T. Surazhsky, D. Kirsanov, S. Gortler, H. Hoppe, "Fast exact and
//! approximate geodesics on meshes", ACM TOG 24(3), 2005. [XW09] S.-Q. Xin, G.-J. Wang,
//! "Improving Chen and Han's algorithm on the discrete geodesic problem", ACM TOG 28(4), 2009.
//! [QHY16] Y. Qin, X. Han, H. Yu, Y. Yu, J. Zhang, "Fast and exact discrete geodesic computation
//! based on triangle-oriented wavefront propagation", ACM TOG 35(4), 2016.
use super::geodesic::{check_input, unreached, Around};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Relative margin by which another path must beat a window before the window loses a part:
/// far above rounding (1e-16), far below any tolerance a user sees.
const MARGIN: f64 = 1e-12;
/// A window narrower than this fraction of its edge carries rays that its neighbours' ends
/// also carry (up to rounding); dropping it keeps rounding noise from multiplying windows.
const MIN_WIDTH: f64 = 1e-13;
/// A face whose height is below this fraction of its longest edge counts as zero-area: its
/// vertices become pseudo-sources.
const SLIVER: f64 = 1e-10;
/// A work budget per face (sides processed); real meshes use a few tens. It only guards
/// against a pathological input looping for ever: past it the call fails rather than hang.
const WORK_PER_FACE: usize = 100_000;
/// "No index".
const NONE: u32 = u32::MAX;
/// Faces per block of the Morton order; the blocks go alternately to the two parts of a
/// propagation. Smaller blocks share each round's work more evenly but make more news to
/// exchange (on the bunny, messages per side taken: 64 faces 0.39, 256 0.20, 1024 0.11; the
/// longer part of each round, summed, 0.55–0.57 of all sides taken at all three).
const FACE_BLOCK: usize = 256;
/// Faces below which one source runs in one part: with a few blocks each, two parts on two
/// threads gained nothing (icospheres, two threads against one: 320 faces 0.8×, 1280 faces
/// 1.0–1.1×; 5120 faces 1.1–1.4×, 20 480 faces 1.2–1.6×).
const PAIRED_FACES: usize = 8 * FACE_BLOCK;
/// `Half::mate` of a half-edge on an edge of more than two faces.
const MANY: u32 = u32::MAX - 1;
/// `Half::mate` flag: the mate runs the same way (faces oriented inconsistently).
const SAME: u32 = 1 << 31;

/// A half-edge `3 f + i` runs from `faces[f][i]` to `faces[f][(i + 1) % 3]`; in its frame (start
/// at the origin, along +x) the face's third vertex is at (cx, cy), cy ≥ 0. `mate` is the other
/// half-edge of its edge (with `SAME` when it runs the same way), `NONE` on a boundary, `MANY` on
/// an edge of more than two faces.
#[derive(Clone, Copy)]
struct Half {
    len: f64,
    cx: f64,
    cy: f64,
    mate: u32,
}

impl Default for Half {
    fn default() -> Self {
        Half { len: 0.0, cx: 0.0, cy: 0.0, mate: NONE }
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn hyp(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

fn distinct(f: &[u32; 3]) -> bool {
    f[0] != f[1] && f[1] != f[2] && f[0] != f[2]
}

/// 21 bits of `x` spread to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f00000000ffff;
    x = (x | x << 16) & 0x1f0000ff0000ff;
    x = (x | x << 8) & 0x100f00f00f00f00f;
    x = (x | x << 4) & 0x10c30c30c30c30c3;
    (x | x << 2) & 0x1249249249249249
}

/// The mesh as the propagation sees it, built once for all sources.
struct Layout {
    /// Vertices and faces renumbered: faces along a Morton curve of their centroids, vertices in
    /// the order the faces first use them (the unused ones last).
    points: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    /// The new number of each given vertex.
    inner: Vec<u32>,
    half: Vec<Half>,
    /// Half-edges on one undirected edge: `edge_half[edge_start[e]..edge_start[e + 1]]` for
    /// `e = edge_of[h]`; `NONE` for the half-edges of a face that names a vertex twice.
    edge_of: Vec<u32>,
    edge_start: Vec<u32>,
    edge_half: Vec<u32>,
    pseudo: Vec<bool>,
    around: Around,
    /// Absolute rounding scale of the mesh: 1e-15 of its extent.
    tiny: f64,
    /// Which of the two parts of a propagation works on each face (blocks of the Morton order,
    /// alternately), and whether a vertex has faces in both.
    owner: Vec<u8>,
    shared: Vec<bool>,
    /// The mean length of the half-edges (1 when all are degenerate): the first band of rounds.
    mean_edge: f64,
}

/// Each face's half-edges, and per vertex its corner angles summed and whether it is a
/// pseudo-source so far (on a face that names a vertex twice or is a sliver). The faces in
/// parallel, then the angles summed per vertex in face order (the same sums on any number of
/// threads; a face that names a vertex twice adds angles of 0).
fn geometry(points: &[[f64; 3]], faces: &[[u32; 3]]) -> (Vec<Half>, Vec<f64>, Vec<bool>) {
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
struct Edges {
    edge_of: Vec<u32>,
    edge_start: Vec<u32>,
    edge_half: Vec<u32>,
}

impl Edges {
    /// The half-edges sorted by their vertex pair, then by number: a counting sort by the
    /// smaller vertex, then each vertex's few sorted (a third of the layout's time went to a
    /// comparison sort of all of them).
    fn new(n: usize, faces: &[[u32; 3]]) -> Self {
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
    fn new(given_points: &[[f64; 3]], given_faces: &[[u32; 3]]) -> Self {
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
        // once, on the two threads they need: one after the other they took 14 of the layout's
        // 22 ms on the bunny.
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
    fn start(&self, h: usize) -> u32 {
        self.faces[h / 3][h % 3]
    }

    /// The other half-edges of `h`'s edge, each with whether it runs the same way as `h`.
    fn others(&self, h: usize) -> impl Iterator<Item = (usize, bool)> + '_ {
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
    fn one_fan(&self, v: usize) -> bool {
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

/// A piece of a window waiting on one side of an edge, in the frame of that side's half-edge
/// (see the module notes): [b0, b1], source (x, y) with y < 0, σ. A window that later windows
/// cut keeps its `id` on every piece left.
#[derive(Clone, Copy)]
struct Seg {
    b0: f64,
    b1: f64,
    x: f64,
    y: f64,
    sigma: f64,
    id: u64,
}

impl Seg {
    /// The distance it carries to (t, 0) of its edge.
    fn at(&self, t: f64) -> f64 {
        self.sigma + hyp(t - self.x, self.y)
    }

    /// Its least distance on [lo, hi] (lo ≤ hi) given its values `at_lo`, `at_hi` at the ends:
    /// `at` is convex, least at x.
    fn least(&self, lo: f64, hi: f64, at_lo: f64, at_hi: f64) -> f64 {
        if self.x <= lo {
            at_lo
        } else if self.x >= hi {
            at_hi
        } else {
            self.sigma + self.y.abs()
        }
    }

    /// The same piece in the frame of the edge's other direction.
    fn mirrored(&self, l: f64) -> Seg {
        Seg { b0: l - self.b1, b1: l - self.b0, x: l - self.x, ..*self }
    }
}

/// A monotone priority queue (a radix heap): the propagation only ever queues distances at
/// least the one it last took out (a window's children carry more than it, a vertex reached
/// from it too), so entries are binned by the highest bit in which their key differs from the
/// last key taken, and each is moved at most once per bit: a few cheap moves instead of a
/// binary heap's cache misses. Keys are distances ≥ 0, whose f64 bits order like the numbers.
/// Equal keys come out last in, first out, the same on every run.
struct Radix {
    last: u64,
    bins: Vec<Vec<(u64, u64)>>,
    /// Bit b set when bin b holds entries (64 bins: keys are ≥ 0, their sign bits never differ).
    full: u64,
    /// Entries queued below `last`, which a radix heap cannot order: the other part's news, which
    /// comes after this part has gone on, and a child that rounding put a hair below its parent;
    /// taken first, in order (taken at `last` instead, out of order, they once made the two parts'
    /// work run away).
    behind: std::collections::BinaryHeap<std::cmp::Reverse<(u64, u64)>>,
}

impl Radix {
    fn new() -> Self {
        Radix { last: 0, bins: (0..64).map(|_| Vec::new()).collect(), full: 0, behind: Default::default() }
    }

    fn clear(&mut self) {
        self.bins.iter_mut().for_each(Vec::clear);
        self.last = 0;
        self.full = 0;
        self.behind.clear();
    }

    /// The bin of `key` when `last` is the last key taken: one past its highest bit that differs.
    fn bin(key: u64, last: u64) -> usize {
        (64 - (key ^ last).leading_zeros()) as usize
    }

    /// The key as queued (its bits; 0 for a negative one).
    fn due(&self, key: f64) -> u64 {
        if key > 0.0 {
            key.to_bits()
        } else {
            0
        }
    }

    /// Queues `item` at `key`; returns the key as queued (`due`).
    #[inline(always)]
    fn push(&mut self, key: f64, item: u64) -> u64 {
        let key = self.due(key);
        if key < self.last {
            self.behind.push(std::cmp::Reverse((key, item)));
            return key;
        }
        let b = Self::bin(key, self.last);
        self.bins[b].push((key, item));
        self.full |= 1 << b;
        key
    }

    /// Brings the least keys to bin 0; false when the queue is empty.
    #[inline(always)]
    fn settle(&mut self) -> bool {
        if self.full & 1 != 0 {
            return true;
        }
        if self.full == 0 {
            return false;
        }
        let b = self.full.trailing_zeros() as usize;
        let mut moving = std::mem::take(&mut self.bins[b]);
        let last = moving.iter().map(|e| e.0).min().unwrap_or(self.last);
        // The keys of bin b differ from the new least below bit b: they all go to lower bins.
        // Local copies of the bins and bits keep the loop in registers (1 % fewer instructions
        // in all on the bunny).
        let (lower, mut full) = (&mut self.bins[..b], self.full & !(1 << b));
        for &e in &moving {
            let to = Self::bin(e.0, last);
            lower[to].push(e);
            full |= 1 << to;
        }
        moving.clear();
        self.bins[b] = moving;
        self.last = last;
        self.full = full;
        true
    }

    /// The least key queued.
    fn peek(&mut self) -> Option<f64> {
        if let Some(std::cmp::Reverse((key, _))) = self.behind.peek() {
            return Some(f64::from_bits(*key));
        }
        if !self.settle() {
            return None;
        }
        self.bins[0].last().map(|e| f64::from_bits(e.0))
    }

    /// Takes an entry of the least key if that is at most `bound`.
    #[inline(always)]
    fn pop_to(&mut self, bound: f64) -> Option<(f64, u64)> {
        if let Some(&std::cmp::Reverse((key, item))) = self.behind.peek() {
            if f64::from_bits(key) > bound {
                return None;
            }
            self.behind.pop();
            return Some((f64::from_bits(key), item));
        }
        if !self.settle() || self.bins[0].last().is_none_or(|e| f64::from_bits(e.0) > bound) {
            return None;
        }
        let (key, item) = self.bins[0].pop()?;
        if self.bins[0].is_empty() {
            self.full &= !1;
        }
        Some((f64::from_bits(key), item))
    }
}

/// Queue items: the windows waiting on a side (its half-edge), or a vertex to emit.
const EVENT: u64 = 1 << 63;

/// Rule 1 at both ends of an edge of length `l` for the window (sx, sy, σ) on [b0, b1]: vertex
/// A (at x = 0) is known at `da`, B (at x = l) at `db`. Since f(x) − x does not increase, A wins
/// a prefix, cut off by solving f(x) − x = d(A): x = (sx² + sy² − k²) / (2(k + sx)), k = d(A) − σ;
/// B a suffix alike. Returns the part left, [b0, b1], with the distances f(b0), f(b1) the window
/// carries at its ends (four of the tests need them, so each is taken once), or None when the
/// ends beat all of it.
#[allow(clippy::too_many_arguments)]
fn cut_ends(sx: f64, sy: f64, sigma: f64, l: f64, da: f64, db: f64, b0: f64, b1: f64, slack: f64) -> Option<[f64; 4]> {
    let f = |x: f64| sigma + hyp(x - sx, sy);
    let (mut b0, mut b1) = (b0, b1);
    let (mut f0, mut f1) = (f(b0), f(b1));
    if da.is_finite() {
        let dv = da + slack;
        if f1 - b1 > dv {
            return None;
        }
        if f0 - b0 > dv {
            let k = dv - sigma;
            let x = (sx * sx + sy * sy - k * k) / (2.0 * (k + sx));
            if x.is_finite() {
                // max/min, not clamp: rounding can leave b0 a hair above b1 (clamp would panic;
                // the caller drops such a window as too narrow).
                b0 = x.max(b0).min(b1);
                f0 = f(b0);
            }
        }
    }
    if db.is_finite() {
        let dv = db + slack;
        if f0 - (l - b0) > dv {
            return None;
        }
        if f1 - (l - b1) > dv {
            let (rx, k) = (l - sx, dv - sigma);
            let x = (rx * rx + sy * sy - k * k) / (2.0 * (k + rx));
            if x.is_finite() {
                b1 = l - x.max(l - b1).min(l - b0);
                f1 = f(b1);
            }
        }
    }
    Some([b0, b1, f0, f1])
}

/// μ or ν of the module notes, kept on the edge; None when rounding made it meaningless.
fn on_edge(num: f64, den: f64) -> Option<f64> {
    let t = num / den;
    if t.is_nan() {
        None
    } else {
        Some(t.clamp(0.0, 1.0))
    }
}

/// Where f_w = f_o on (lo, hi), sorted; a spare point does no harm (the caller only splits
/// there), a missed one would. Squaring f_w − f_o = 0 twice gives a quadratic (a double root
/// when the σ are equal, which rounding can push to a negative discriminant: it is clamped at
/// 0); each root is polished by Newton steps on f_w − f_o itself, since squaring loses
/// precision near the roots and the cut is made there.
#[inline(always)] // 2 % faster than a call from each `share`
fn crossings(w: &Seg, o: &Seg, lo: f64, hi: f64) -> ([f64; 2], usize) {
    let (a1, a2, delta) = (w.x, o.x, o.sigma - w.sigma);
    let (h1, h2) = (w.y * w.y, o.y * o.y);
    let alpha = 2.0 * (a2 - a1);
    let beta = a1 * a1 - a2 * a2 + h1 - h2 - delta * delta;
    let qa = alpha * alpha - 4.0 * delta * delta;
    let qb = 2.0 * alpha * beta + 8.0 * delta * delta * a2;
    let qc = beta * beta - 4.0 * delta * delta * (a2 * a2 + h2);
    let candidates = if qa != 0.0 {
        let q = -0.5 * (qb + qb.signum() * (qb * qb - 4.0 * qa * qc).max(0.0).sqrt());
        [q / qa, qc / q]
    } else {
        [-qc / qb, f64::NAN]
    };
    let mut found = [0.0; 2];
    let mut n = 0;
    let reach = hi - lo;
    let tight = 2e-15 * reach * w.y.abs().min(o.y.abs());
    for mut t in candidates {
        // Far outside, no polish brings it in.
        if !(t > lo - reach && t < hi + reach) {
            continue;
        }
        for _ in 0..3 {
            let (rw, ro) = (hyp(t - w.x, w.y), hyp(t - o.x, o.y));
            // (f_w − f_o) / (f_w − f_o)′ with the slopes (t − x)/r over a common denominator.
            let step = (w.sigma + rw - o.sigma - ro) * rw * ro / ((t - w.x) * ro - (t - o.x) * rw);
            if !step.is_finite() {
                break;
            }
            t -= step;
            // Newton converges quadratically: after a step s the root is off by about
            // |g''| s² / (2 |g'|), g = f_w − f_o, and a cut off by e costs the distances at most
            // |g'| e, i.e. |g''| s² / 2 ≤ s² / (2 min |y|) (|g''| ≤ 1/min |y|). Stop once that is
            // below 1e-15 of the interval: one step from the quadratic's root mostly does it.
            // (Near a double root, where it converges slowly, the two windows are equal to
            // second order there, so the place of the cut is moot.)
            if step * step <= tight {
                break;
            }
        }
        if t > lo && t < hi && !found[..n].contains(&t) {
            found[n] = t;
            n += 1;
        }
    }
    if n == 2 && found[0] > found[1] {
        found.swap(0, 1);
    }
    (found, n)
}

/// How `w` and `o` share (lo, hi): the sub-intervals, in order, each with whether `w` keeps it,
/// which it does where w − o ≤ `bar`; passed to `take` as (from, to, w keeps).
fn share(w: &Seg, o: &Seg, lo: f64, hi: f64, bar: f64, mut take: impl FnMut(f64, f64, bool)) {
    // Each window's most and least on [lo, hi] from its values at the ends (f is convex).
    let (w0, w1, o0, o1) = (w.at(lo), w.at(hi), o.at(lo), o.at(hi));
    if w0.max(w1) - o.least(lo, hi, o0, o1) <= bar {
        return take(lo, hi, true);
    }
    if w.least(lo, hi, w0, w1) - o0.max(o1) > bar {
        return take(lo, hi, false);
    }
    let (roots, n) = crossings(w, o, lo, hi);
    // Between crossings w − o keeps its sign, so the first and last sub-intervals are decided
    // by the ends' values where those are clearly away from the bar; near it (the end may be a
    // crossing itself), and for the middle one, by the value at the middle.
    let at_middle = |from: f64, to: f64| {
        let mid = 0.5 * (from + to);
        w.at(mid) - o.at(mid) <= bar
    };
    let by_end = |end: f64, from: f64, to: f64| {
        if (end - bar).abs() > 2.0 * bar.abs() {
            end <= bar
        } else {
            at_middle(from, to)
        }
    };
    let mut from = lo;
    for (k, &to) in roots[..n].iter().chain(std::iter::once(&hi)).enumerate() {
        let keeps = if k == 0 {
            by_end(w0 - o0, from, to)
        } else if k == n {
            by_end(w1 - o1, from, to)
        } else {
            at_middle(from, to)
        };
        take(from, to, keeps);
        from = to;
    }
}

/// Appends [a, b] of `seg` to `out`, joined to the last piece when that is the same window and
/// ends at `a`; pieces of at most `narrow` are dropped.
fn append(out: &mut Vec<Seg>, seg: &Seg, a: f64, b: f64, narrow: f64) {
    if !(b - a > narrow) {
        return;
    }
    match out.last_mut() {
        Some(last) if last.id == seg.id && last.b1 == a => last.b1 = b,
        _ => out.push(Seg { b0: a, b1: b, ..*seg }),
    }
}

/// A half-edge as the propagation knows it when windows join it: the pieces of the windows
/// waiting there, in order along the edge and disjoint (rule 3). 32 bytes, two to a cache line;
/// rule 2's best path, used only when the side's turn comes, is kept apart (`Work::best`).
struct Side {
    env: Vec<Seg>,
    /// The key (as queued) of the side's one live queue entry, `u64::MAX` for none: a side is
    /// queued once, at its earliest window, not once per window.
    queued: u64,
}

/// The buffers of a propagation, kept from one source to the next.
#[derive(Default)]
struct Work {
    d: Vec<f64>,
    /// Per half-edge, rule 2's best path from it to its face's apex: length, where it crosses.
    best: Vec<(f64, f64)>,
    /// Per half-edge, the windows waiting there.
    side: Vec<Side>,
    queue: Option<Radix>,
    ids: u64,
    out: Vec<Seg>,
    /// Emptied piece lists, last emptied first: a side takes one when its first window comes,
    /// and gives it back once its windows have crossed. So only the sides on the front hold
    /// storage, and the storage they get was in use a moment ago (still in cache); a list of
    /// its own per side took 14 % more time on the bunny (allocation, first touches of memory).
    spare: Vec<Vec<Seg>>,
    pieces: Vec<(f64, f64)>,
    kept: Vec<(f64, f64)>,
    batch: Vec<Crossing>,
    /// Per vertex, the distance it last emitted at (a pseudo-source emits again only when a
    /// shorter path reaches it, which the other part's late news can bring).
    emitted: Vec<f64>,
    /// The sides a batch crossing its face (or a pseudo-source emitting) has given windows to,
    /// each queued once when the batch is done, at the least distance of all it gave. Queued
    /// again at each window that came in lower, as a batch's windows mostly do, a source on the
    /// bunny made 0.76 M queue entries for 0.11 M turns of a side, 0.61 M of them stale, and the
    /// radix heap moved entries 4.8 M times; once per batch, 0.23 M, 0.08 M and 0.9 M (8–10 %
    /// less time, on one thread and on two).
    touched: Vec<u32>,
    /// What this part tells the other at the end of a round, and the pieces of its joins.
    outbox: Vec<Message>,
    outbox_pieces: Vec<(f64, f64)>,
}

/// News from one part of a propagation to the other, delivered between rounds.
#[derive(Clone, Copy)]
enum Message {
    /// A vertex with faces in both parts is reached at this distance.
    Relax { v: u32, dist: f64 },
    /// A window joins side `t` (of the receiver's) with its pieces `outbox_pieces[from..to]`,
    /// left after the cut by the windows on the sender's side of the edge.
    Join { t: u32, w: Seg, least: f64, slack: f64, from: u32, to: u32 },
    /// A pseudo-source lying on an edge reaches the face of half-edge `t` directly.
    EmitFromEdge { t: u32, x: f64, dv: f64 },
}

/// A window of a batch about to cross its face: its part [b0, b1] left by rule 1, its source
/// (sx, sy, σ), where the ray to the apex crosses its edge and the distance it brings the apex.
#[derive(Clone, Copy)]
struct Crossing {
    b0: f64,
    b1: f64,
    sx: f64,
    sy: f64,
    sigma: f64,
    xc: f64,
    dc: f64,
}

/// One part of the propagation from one source: the faces of `Layout::owner` `me` (all when
/// `me` is `WHOLE`), with its own copy of the vertex distances.
struct Run<'a> {
    m: &'a Layout,
    w: &'a mut Work,
    queue: Radix,
    me: u8,
    budget: usize,
    /// The budget when the round began.
    started: usize,
}

impl Work {
    /// The memory it holds, about: the large buffers and the piece lists (all back in `spare`
    /// once a propagation has run its course).
    fn bytes(&self) -> usize {
        use std::mem::size_of;
        let lists: usize = self.spare.iter().map(Vec::capacity).sum();
        size_of::<f64>() * (self.d.capacity() + self.emitted.capacity())
            + size_of::<(f64, f64)>() * self.best.capacity()
            + size_of::<Side>() * self.side.capacity()
            + size_of::<Seg>() * lists
    }

    /// Ready for a propagation on `m`: every distance unknown, no window waiting.
    fn reset(&mut self, m: &Layout) {
        let (nv, nh) = (m.points.len(), m.half.len());
        self.d.clear();
        self.d.resize(nv, f64::INFINITY);
        self.emitted.clear();
        self.emitted.resize(nv, f64::INFINITY);
        self.outbox.clear();
        self.outbox_pieces.clear();
        self.touched.clear();
        self.side.truncate(nh);
        self.best.clear();
        self.best.resize(nh, (f64::INFINITY, 0.0));
        for side in &mut self.side {
            if side.env.capacity() > 0 {
                let mut env = std::mem::take(&mut side.env);
                env.clear();
                self.spare.push(env);
            }
            side.queued = u64::MAX;
        }
        self.side.resize_with(nh, || Side { env: Vec::new(), queued: u64::MAX });
    }
}

impl<'a> Run<'a> {
    /// Part `me` of a propagation on `m`, with buffers `w` (`Work::reset`).
    fn new(m: &'a Layout, w: &'a mut Work, me: u8) -> Self {
        w.ids = me as u64;
        let mut queue = w.queue.take().unwrap_or_else(Radix::new);
        queue.clear();
        // A budget for each part: neither can hang.
        let budget = WORK_PER_FACE.saturating_mul(m.faces.len()).max(1_000_000);
        Run { m, w, queue, me, budget, started: budget }
    }

    fn mine(&self, h: usize) -> bool {
        self.me == WHOLE || self.m.owner[h / 3] == self.me
    }

    fn slack(&self, d: f64) -> f64 {
        MARGIN * d.abs() + self.m.tiny
    }

    fn relax(&mut self, v: usize, dist: f64) {
        if dist < self.w.d[v] {
            self.w.d[v] = dist;
            if self.m.pseudo[v] {
                self.queue.push(dist, EVENT | v as u64);
            }
            if self.me != WHOLE && self.m.shared[v] {
                self.w.outbox.push(Message::Relax { v: v as u32, dist });
            }
        }
    }

    /// Gives the queue back to the buffers, for the next source.
    fn finish(self) {
        self.w.queue = Some(self.queue);
    }

    /// The source, inner vertex `source`, at distance 0.
    fn start(&mut self, source: usize) {
        self.w.d[source] = 0.0;
        self.queue.push(0.0, EVENT | source as u64);
    }

    /// Takes what is queued up to `bound`; false when the work budget ran out.
    fn round(&mut self, bound: f64) -> bool {
        let mut budget = self.budget;
        while let Some((key, item)) = self.queue.pop_to(bound) {
            if item & EVENT != 0 {
                let v = (item & !EVENT) as usize;
                // Once per distance: a later, shorter one has its own event. Shorter by no more
                // than rounding (a path of the same length, summed in another order) is not
                // shorter: emitting again would double the vertex's windows for nothing.
                let (dv, before) = (self.w.d[v], self.w.emitted[v]);
                if before == f64::INFINITY || dv < before - self.slack(before) {
                    self.w.emitted[v] = dv;
                    self.emit(v, dv);
                    self.queue_touched();
                }
            } else {
                if budget == 0 {
                    self.budget = 0;
                    return false;
                }
                budget -= 1;
                self.propagate(key, item as usize);
                self.queue_touched();
            }
        }
        self.budget = budget;
        true
    }

    /// The least distance queued, inf when nothing is.
    fn least(&mut self) -> f64 {
        self.queue.peek().unwrap_or(f64::INFINITY)
    }

    /// Hands this round's news for the other part to `mail` (which the other has read).
    fn post(&mut self, mail: &mut News) {
        mail.messages.clear();
        mail.pieces.clear();
        std::mem::swap(&mut mail.messages, &mut self.w.outbox);
        std::mem::swap(&mut mail.pieces, &mut self.w.outbox_pieces);
    }

    /// The other part's news of the last round.
    fn receive(&mut self, news: &News) {
        let pieces = &news.pieces;
        for &message in &news.messages {
            match message {
                Message::Relax { v, dist } => {
                    let v = v as usize;
                    if dist < self.w.d[v] {
                        self.w.d[v] = dist;
                        if self.m.pseudo[v] {
                            self.queue.push(dist, EVENT | v as u64);
                        }
                    }
                }
                Message::Join { t, w, least, slack, from, to } => {
                    let t = t as usize;
                    let l = self.m.half[t].len;
                    let mut took = false;
                    for &(b0, b1) in &pieces[from as usize..to as usize] {
                        took |= self.merge(t, &w, b0, b1, l, slack);
                    }
                    self.queue_side(t, took, least);
                }
                Message::EmitFromEdge { t, x, dv } => self.emit_from_edge(t as usize, x, dv),
            }
        }
        self.queue_touched();
    }

    /// Queues side `t` at `least` now, if it took a window and is not queued lower already. The
    /// other part's news queues this way: its joins reach many sides, mostly once each, where
    /// `touch_side`'s look-up of the sides touched so far would grow with the round.
    #[inline(always)]
    fn queue_side(&mut self, t: usize, took: bool, least: f64) {
        if took && self.queue.due(least) < self.w.side[t].queued {
            self.w.side[t].queued = self.queue.push(least, t as u64);
        }
    }

    /// `queue_side` while a batch crosses its face: the side is queued when the batch is done
    /// (`queue_touched`), at the least of what it took.
    #[inline(always)]
    fn touch_side(&mut self, t: usize, took: bool, least: f64) {
        let due = self.queue.due(least);
        if took && due < self.w.side[t].queued {
            self.w.side[t].queued = due;
            if !self.w.touched.contains(&(t as u32)) {
                self.w.touched.push(t as u32);
            }
        }
    }

    /// Queues the sides the batch gave windows to.
    fn queue_touched(&mut self) {
        for &t in &self.w.touched {
            let t = t as usize;
            self.queue.push(f64::from_bits(self.w.side[t].queued), t as u64);
        }
        self.w.touched.clear();
    }

    /// A pseudo-source `v` at its final distance: its neighbours along the edges, and one window
    /// over each edge opposite it, into the faces beyond.
    fn emit(&mut self, v: usize, dv: f64) {
        let m = self.m;
        for &f in m.around.of(v) {
            let f = f as usize;
            if self.me != WHOLE && m.owner[f] != self.me {
                continue; // the other part emits there, at its own news of v
            }
            let face = m.faces[f];
            let Some(k) = face.iter().position(|&u| u as usize == v) else {
                continue;
            };
            if !distinct(&face) {
                for &u in &face {
                    let length = norm(sub(m.points[u as usize], m.points[v]));
                    self.relax(u as usize, dv + length);
                }
                continue;
            }
            // Along the face's two edges at v, whose lengths the half-edges hold (the same
            // bits as measuring them again: where every vertex is a saddle, emitting is most
            // of the work).
            for (i, &u) in face.iter().enumerate() {
                if i != k {
                    let along = if i == (k + 1) % 3 { 3 * f + k } else { 3 * f + i };
                    self.relax(u as usize, dv + m.half[along].len);
                }
            }
            let opposite = 3 * f + (k + 1) % 3;
            let Half { len, cx, cy, .. } = m.half[opposite];
            if cy > SLIVER * len {
                self.spawn(opposite, 0.0, len, cx, -cy, dv, self.ends(opposite));
            } else if cx > 0.0 && cx < len {
                // v lies on the edge: it sees the faces beyond directly.
                for (t, same) in m.others(opposite) {
                    let x = if same { cx } else { len - cx };
                    if self.mine(t) {
                        self.emit_from_edge(t, x, dv);
                    } else {
                        self.w.outbox.push(Message::EmitFromEdge { t: t as u32, x, dv });
                    }
                }
            }
        }
    }

    /// A pseudo-source at (x, 0) on half-edge `h`, reaching h's face directly.
    fn emit_from_edge(&mut self, h: usize, x: f64, dv: f64) {
        let m = self.m;
        let (f, i) = (h / 3, h % 3);
        let Half { len, cx, cy, .. } = m.half[h];
        let apex = m.faces[f][(i + 2) % 3] as usize;
        self.relax(apex, dv + hyp(cx - x, cy));
        let (left, right) = (3 * f + (i + 2) % 3, 3 * f + (i + 1) % 3);
        if let Some((sx, sy)) = self.source_on_left(left, cx, cy, x, 0.0) {
            self.spawn(left, 0.0, m.half[left].len, sx, sy, dv, self.ends(left));
        }
        if let Some((sx, sy)) = self.source_on_right(right, len, cx, cy, x, 0.0) {
            self.spawn(right, 0.0, m.half[right].len, sx, sy, dv, self.ends(right));
        }
    }

    /// The source (sx, sy) of a window on half-edge A→B, in the frame of the face's edge C→A
    /// (`left`), with the face on −y.
    fn source_on_left(&self, left: usize, cx: f64, cy: f64, sx: f64, sy: f64) -> Option<(f64, f64)> {
        let l = self.m.half[left].len;
        (l > 0.0).then(|| (((cx - sx) * cx + (cy - sy) * cy) / l, -(cy * sx - cx * sy).abs() / l))
    }

    /// The same in the frame of the face's edge B→C (`right`).
    fn source_on_right(&self, right: usize, len: f64, cx: f64, cy: f64, sx: f64, sy: f64) -> Option<(f64, f64)> {
        let l = self.m.half[right].len;
        (l > 0.0).then(|| (((sx - len) * (cx - len) + sy * cy) / l, -((cx - len) * sy - cy * (sx - len)).abs() / l))
    }

    /// Processes the windows waiting on side `h`: they cross the face. They go together, the first
    /// of them due: they share the face's data in cache, and their order among themselves does
    /// not matter.
    fn propagate(&mut self, key: f64, h: usize) {
        let m = self.m;
        let side = &self.w.side[h];
        if side.queued != key.to_bits() {
            return; // a later entry of this side stands for it
        }
        // The side is due at `key`, its least distance when queued: a merge only ever replaces
        // a piece by a shorter one, so that least has not grown since.
        self.w.side[h].queued = u64::MAX;
        let mut mine = std::mem::take(&mut self.w.side[h].env);
        let face = m.faces[h / 3];
        let (a, b) = (face[h % 3] as usize, face[(h + 1) % 3] as usize);
        let (da, db) = (self.w.d[a], self.w.d[b]);
        // First the whole batch reaches the apex: its best path is then known before any window
        // splits by rule 2 and before any child is cut by the apex's distance (rule 1).
        let Half { cx, cy, .. } = m.half[h];
        let mut batch = std::mem::take(&mut self.w.batch);
        batch.clear();
        let mut best = self.w.best[h];
        // Rule 1 is not applied again here with the ends' latest distances: on the bunny that
        // dropped 307 of a source's 1.5 M windows, and cost 3.5 % of the time.
        for s in &mine {
            let (b0, b1) = (s.b0, s.b1);
            // Straight when the apex's ray crosses the window, else through the nearer end.
            let (sx, sy, sigma) = (s.x, s.y, s.sigma);
            let xc = sx + (cx - sx) * (-sy) / (cy - sy);
            let q = if xc.is_nan() { b0 } else { xc.clamp(b0, b1) };
            let dc = if q == xc { sigma + hyp(cx - sx, cy - sy) } else { sigma + hyp(q - sx, sy) + hyp(cx - q, cy) };
            if dc < best.0 {
                best = (dc, q);
            }
            batch.push(Crossing { b0, b1, sx, sy, sigma, xc, dc });
        }
        mine.clear();
        self.w.spare.push(mine);
        let apex = face[(h + 2) % 3] as usize;
        if best.0 < self.w.best[h].0 {
            self.w.best[h] = best;
            self.relax(apex, best.0);
        }
        // The corners' distances as the children's rule 1 sees them: nothing the batch does
        // from here on changes a vertex distance.
        let corners = [da, db, self.w.d[apex]];
        for c in &batch {
            self.cross(h, c, best, corners);
        }
        self.w.batch = batch;
    }

    /// Sends the part [b0, b1] of a window on `h` (in h's frame) across h's face: splits by
    /// rule 2 against the best path `best` to the apex and makes the children on the face's
    /// other two edges. `corners`: the distances of h's start, end and apex.
    fn cross(&mut self, h: usize, c: &Crossing, best: (f64, f64), corners: [f64; 3]) {
        let m = self.m;
        let (f, i) = (h / 3, h % 3);
        let Half { len: l, cx, cy, .. } = m.half[h];
        let Crossing { b0, b1, sx, sy, sigma, xc, dc } = *c;

        // Rule 2.
        let (mut left_end, mut right_start) = (b1.min(xc), b0.max(xc));
        if dc > best.0 + self.slack(best.0) {
            left_end = left_end.min(best.1);
            right_start = right_start.max(best.1);
        }

        if left_end > b0 {
            // Through C→A, measured from C.
            let left = 3 * f + (i + 2) % 3;
            let lca = m.half[left].len;
            let mu = |x: f64| on_edge(sy * x, cx * sy + cy * (x - sx));
            let far = if left_end == xc { Some(1.0) } else { mu(left_end) };
            if let (Some(near), Some(far), Some((tx, ty))) = (mu(b0), far, self.source_on_left(left, cx, cy, sx, sy)) {
                self.spawn(left, (1.0 - far) * lca, (1.0 - near) * lca, tx, ty, sigma, [corners[2], corners[0]]);
            }
        }
        if right_start < b1 {
            // Through B→C, measured from B.
            let right = 3 * f + (i + 1) % 3;
            let lbc = m.half[right].len;
            let nu = |x: f64| on_edge(sy * (x - l), (cx - l) * sy + cy * (x - sx));
            let far = if right_start == xc { Some(1.0) } else { nu(right_start) };
            if let (Some(near), Some(far), Some((tx, ty))) =
                (nu(b1), far, self.source_on_right(right, l, cx, cy, sx, sy))
            {
                self.spawn(right, near * lbc, far * lbc, tx, ty, sigma, [corners[1], corners[2]]);
            }
        }
    }

    /// The distances of half-edge `h`'s start and end.
    fn ends(&self, h: usize) -> [f64; 2] {
        let face = self.m.faces[h / 3];
        [self.w.d[face[h % 3] as usize], self.w.d[face[(h + 1) % 3] as usize]]
    }

    /// A window leaving its face through half-edge `h` on [t0, t1] of h's frame, source (sx, sy)
    /// with the face on −y: for each face beyond, rule 3 and the queue. `ends`: the distances of
    /// h's start and end (`Run::ends`).
    #[allow(clippy::too_many_arguments)]
    fn spawn(&mut self, h: usize, t0: f64, t1: f64, sx: f64, sy: f64, sigma: f64, ends: [f64; 2]) {
        let m = self.m;
        let l = m.half[h].len;
        if !(sy < 0.0 && l > 0.0 && sx.is_finite()) {
            return; // rays along the edge never enter the face beyond
        }
        let (t0, t1) = (t0.max(0.0), t1.min(l));
        // Rule 1 already here, with the edge ends' distances as they are now: a window the ends
        // beat is never merged or queued.
        let slack = self.slack(sigma + l);
        let Some([t0, t1, f0, f1]) = cut_ends(sx, sy, sigma, l, ends[0], ends[1], t0, t1, slack) else {
            return;
        };
        if !(t1 - t0 > MIN_WIDTH * l) {
            return;
        }
        let seg = Seg { b0: t0, b1: t1, x: sx, y: sy, sigma, id: 0 };
        let least = seg.least(t0, t1, f0, f1);
        let slack = self.slack(least + l);
        match m.half[h].mate {
            NONE => {}
            MANY => {
                for (t, same) in m.others(h) {
                    self.join(h, t, same, seg, least, slack);
                }
            }
            // The common case, without the iterator (it cost 6 % of the instructions).
            mate => self.join(h, (mate & !SAME) as usize, mate & SAME != 0, seg, least, slack),
        }
    }

    /// The window `w` leaving through `h` (in h's frame) joins side `t` of the same edge (running
    /// the `same` way as h or not): rule 3 against the windows waiting on the edge, then the
    /// queue, at the window's `least` distance.
    // Inlined at its two calls in `spawn`, the 48-byte window is not copied (8 sources on one
    // thread 8 % faster; inlining `spawn` or `merge` too was slower, 4–17 %).
    #[inline(always)]
    fn join(&mut self, h: usize, t: usize, same: bool, w: Seg, least: f64, slack: f64) {
        let m = self.m;
        let l = m.half[h].len;
        // Ids odd in one part, even in the other: pieces of one window join, of two never.
        self.w.ids += 2;
        let mut w = Seg { id: self.w.ids, ..w };
        if !same {
            w = w.mirrored(l);
        }
        let fast = m.half[h].mate != MANY && self.w.side[h].env.is_empty();
        if fast && self.mine(t) {
            // On a manifold edge the one other side of t is h, the side w comes from; mostly
            // nothing waits there.
            let took = self.merge(t, &w, w.b0, w.b1, l, slack);
            return self.touch_side(t, took, least);
        }
        self.w.pieces.clear();
        self.w.pieces.push((w.b0, w.b1));
        if !fast {
            if m.half[h].mate == MANY {
                for (u, same) in m.others(t) {
                    if self.mine(u) {
                        self.cut_by_side(u, same, &w, l, slack);
                    }
                }
            } else {
                self.cut_by_side(h, same, &w, l, slack);
            }
        }
        if !self.mine(t) {
            let from = self.w.outbox_pieces.len() as u32;
            self.w.outbox_pieces.extend_from_slice(&self.w.pieces);
            let to = self.w.outbox_pieces.len() as u32;
            if to > from {
                self.w.outbox.push(Message::Join { t: t as u32, w, least, slack, from, to });
            }
            return;
        }
        let pieces = std::mem::take(&mut self.w.pieces);
        let mut took = false;
        for &(b0, b1) in &pieces {
            took |= self.merge(t, &w, b0, b1, l, slack);
        }
        self.w.pieces = pieces;
        self.touch_side(t, took, least);
    }

    /// Rule 3 across the edge (of length `l`): cuts `self.w.pieces` (of `w`, on a side of the
    /// edge) where a window waiting on its other side `u` (running the `same` way or not) beats
    /// `w` by more than `slack`.
    fn cut_by_side(&mut self, u: usize, same: bool, w: &Seg, l: f64, slack: f64) {
        let ww = &mut *self.w;
        let list = &ww.side[u].env;
        if list.is_empty() || ww.pieces.is_empty() {
            return;
        }
        let (lo, hi) = (ww.pieces[0].0, ww.pieces[ww.pieces.len() - 1].1);
        let range = if same { overlapping(list, lo, hi) } else { overlapping(list, l - hi, l - lo) };
        for o in &list[range] {
            let o = if same { *o } else { o.mirrored(l) };
            ww.kept.clear();
            for &(p0, p1) in &ww.pieces {
                let (a, b) = (p0.max(o.b0), p1.min(o.b1));
                if !(a < b) {
                    ww.kept.push((p0, p1));
                    continue;
                }
                let kept = &mut ww.kept;
                let mut keep = |u: f64, v: f64| match kept.last_mut() {
                    Some(last) if last.1 == u => last.1 = v,
                    _ => kept.push((u, v)),
                };
                if p0 < a {
                    keep(p0, a);
                }
                share(w, &o, a, b, slack, |u, v, mine| {
                    if mine {
                        keep(u, v)
                    }
                });
                if b < p1 {
                    keep(b, p1);
                }
            }
            ww.kept.retain(|&(p0, p1)| p1 - p0 > MIN_WIDTH * l);
            std::mem::swap(&mut ww.pieces, &mut ww.kept);
        }
    }

    /// Rule 3 on the window's own side: the piece [b0, b1] of `w` takes over the parts of the
    /// list waiting on side `h` where it beats what is there by more than `slack`. Returns
    /// whether it took any.
    #[allow(clippy::too_many_arguments)]
    fn merge(&mut self, h: usize, w: &Seg, b0: f64, b1: f64, l: f64, slack: f64) -> bool {
        let narrow = MIN_WIDTH * l;
        let ww = &mut *self.w;
        let w = Seg { b0, b1, ..*w };
        let list = &mut ww.side[h].env;
        if list.capacity() == 0 {
            if let Some(spare) = ww.spare.pop() {
                *list = spare;
            }
        }
        let range = overlapping(list, b0, b1);
        if range.is_empty() {
            // Over nothing yet (the common case: a batch's windows reach an edge side by side).
            if b1 - b0 > narrow {
                list.insert(range.start, w);
                return true;
            }
            return false;
        }
        let out = &mut ww.out;
        out.clear();
        // [cursor, b1] of w is still to place.
        let mut cursor = b0;
        for o in &list[range.clone()] {
            let (lo, hi) = (o.b0.max(b0), o.b1.min(b1));
            if o.b0 < lo {
                append(out, o, o.b0, lo, narrow);
            }
            if cursor < lo {
                append(out, &w, cursor, lo, narrow);
            }
            share(&w, o, lo, hi, -slack, |u, v, mine| append(out, if mine { &w } else { o }, u, v, narrow));
            cursor = cursor.max(hi);
            if hi < o.b1 {
                append(out, o, hi, o.b1, narrow);
            }
        }
        if cursor < b1 {
            append(out, &w, cursor, b1, narrow);
        }
        let took = out.iter().any(|s| s.id == w.id);
        if out.len() == range.len() {
            list[range].copy_from_slice(out);
        } else {
            list.splice(range, out.drain(..));
        }
        took
    }
}

/// The pieces of `list` (in order, disjoint) that overlap (b0, b1). A batch's windows mostly
/// reach an edge in order, so the end of the list is tried first; a window overlaps few pieces,
/// so they are counted one by one (a binary search's chain of dependent loads cost more).
fn overlapping(list: &[Seg], b0: f64, b1: f64) -> std::ops::Range<usize> {
    let n = list.len();
    let i = if list.last().is_none_or(|s| s.b1 <= b0) { n } else { list.partition_point(|s| s.b1 <= b0) };
    let j = i + list[i..].iter().take_while(|s| s.b0 < b1).count();
    i..j
}

/// Propagation buffers of meshes laid out before (their `ExactGeodesics` dropped), kept for the
/// next: a page's first touch costs 1.5–2 µs on this host, and each `geodesic_distances` call on
/// the bunny freed its 21 MB of buffers and touched some 7,700 new pages again (prepared, the
/// calls touch none). Kept, a call touches none either and takes 4–5 % less time (one source,
/// 131 → 126 ms at the least). At most `KEPT_BYTES` are kept: a large mesh does not leave all
/// its buffers behind.
static KEPT: std::sync::Mutex<Vec<Work>> = std::sync::Mutex::new(Vec::new());

/// The most memory of propagation buffers kept for later meshes (`KEPT`): the bunny's take 21 MB,
/// about 300 bytes per face.
const KEPT_BYTES: usize = 256 << 20;

/// A mesh laid out once for exact geodesics (`GeodesicSolver` with `GeodesicMethod::Exact`):
/// each call of `distances` reuses the layout and the propagation buffers of earlier calls (one
/// set per thread that has worked on it, a few tens of bytes per half-edge), and the first call
/// those that meshes before left (`KEPT`).
pub(super) struct ExactGeodesics {
    layout: Layout,
    n: usize,
    /// Buffers not in use, handed from source to source and from call to call: rayon calls a
    /// `map_init` initialiser once per job it splits off, which here is about once per source.
    idle: std::sync::Mutex<Vec<Work>>,
}

impl ExactGeodesics {
    /// Lays out a mesh whose vertices and faces have passed `check_input`.
    pub(super) fn new(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Self {
        ExactGeodesics { layout: Layout::new(vertices, faces), n: vertices.len(), idle: Default::default() }
    }

    /// One row per source (each below the vertex count), sources in parallel.
    pub(super) fn distances(&self, sources: &[usize]) -> Result<Vec<Vec<f64>>> {
        // One source: in two parts, on two threads where there are; several, or one on a mesh
        // too small to share: one part each, in parallel. The choice never depends on the
        // threads alone (two parts in turn give the bits of two parts at once).
        let split = match (sources.len(), rayon::current_num_threads()) {
            (1, _) if self.layout.faces.len() < PAIRED_FACES => Split::Whole,
            (1, 1) => Split::InTurn,
            (1, _) => Split::Paired,
            _ => Split::Whole,
        };
        sources
            .par_iter()
            .map(|&s| {
                let take = || {
                    let mine = self.idle.lock().ok().and_then(|mut idle| idle.pop());
                    mine.or_else(|| KEPT.lock().ok().and_then(|mut kept| kept.pop())).unwrap_or_default()
                };
                let mut works = [take(), take()];
                let row = distances_from(&self.layout, &mut works, self.n, s, split);
                if let Ok(mut idle) = self.idle.lock() {
                    // The first back last, so that the next source takes it first: one part
                    // uses only the first, which stays warm from source to source.
                    let [first, second] = works;
                    idle.extend([second, first]);
                }
                row
            })
            .collect()
    }
}

impl Drop for ExactGeodesics {
    /// Hands the buffers to the next mesh (`KEPT`), as far as `KEPT_BYTES` allows.
    fn drop(&mut self) {
        let mine = std::mem::take(self.idle.get_mut().unwrap_or_else(|e| e.into_inner()));
        let mut left = Vec::new();
        if let Ok(mut kept) = KEPT.lock() {
            let mut bytes: usize = kept.iter().map(Work::bytes).sum();
            for work in mine {
                let more = work.bytes();
                if bytes + more <= KEPT_BYTES {
                    bytes += more;
                    kept.push(work);
                } else {
                    left.push(work);
                }
            }
        }
        drop(left); // freed outside the lock
    }
}

/// Exact geodesic distances along the mesh surface from each source vertex to every vertex,
/// one row per source, sources in parallel. A vertex that no face uses, or that no face path
/// reaches, is `inf`. Degenerate and non-manifold meshes are accepted (see the module notes).
pub fn geodesic_exact(vertices: &[[f64; 3]], faces: &[[u32; 3]], sources: &[usize]) -> Result<Vec<Vec<f64>>> {
    check_input(vertices, faces, sources)?;
    ExactGeodesics::new(vertices, faces).distances(sources)
}

/// How the propagation from one source runs: in one part (`Run::me` = `WHOLE`), as each source
/// of a call with several (they run in parallel); or in two parts on two threads, or in turn on
/// one, as the one source of a call.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Split {
    Whole,
    Paired,
    InTurn,
}

/// `Run::me` of a propagation in one part: every face is its own.
const WHOLE: u8 = 2;

/// The propagation from inner vertex `source`: in one part (`Split::Whole`), or in two (the
/// faces of each `Layout::owner`) that take the queued work in rounds, each round the distances
/// up to a bound, and exchange their news between rounds; on two threads when `Paired` (until
/// they stop paying), else in turn on this one. The parts and the bounds depend on neither, so
/// the distances do not either. The result in `works[0].d`; false when the work budget ran out.
fn propagate_in_parts(layout: &Layout, works: &mut [Work; 2], source: usize, split: Split) -> bool {
    let [w0, w1] = works;
    if split == Split::Whole {
        w0.reset(layout);
        let mut whole = Run::new(layout, w0, WHOLE);
        whole.start(source);
        let ok = whole.round(f64::INFINITY);
        whole.finish();
        return ok;
    }
    // Both parts' buffers at once: the first time, their memory's first touches (some 10 MB a
    // part) took 8.5 ms on the bunny in turn, 5 ms at once.
    rayon::join(|| w0.reset(layout), || w1.reset(layout));
    let (mut a, mut b) = (Run::new(layout, w0, 0), Run::new(layout, w1, 1));
    a.start(source);
    b.start(source);
    let mut rounds = Rounds::new(layout);
    // On two threads until they stop paying (see `in_two_threads`), then in turn on this one:
    // the rounds are the same either way.
    let paired = if split == Split::Paired { in_two_threads(&mut a, &mut b, &mut rounds, stops_paying) } else { None };
    let ok = paired.unwrap_or_else(|| in_turn(&mut a, &mut b, &mut rounds));
    for (x, y) in a.w.d.iter_mut().zip(&b.w.d) {
        *x = x.min(*y);
    }
    a.finish();
    b.finish();
    ok
}

/// The rounds left, taken in turn on this thread: each part's early half, then each part's late
/// half, round after round (the order of `Rounds`, so the bits of two threads).
fn in_turn(a: &mut Run, b: &mut Run, rounds: &mut Rounds) -> bool {
    // Each part steps its own copy of the band, as on two threads.
    let mut bands = [rounds.band; 2];
    let ok = loop {
        let k = rounds.next;
        let Some((bound, ea)) = rounds.early(a, k, &mut bands[0]) else { break true };
        let Some((same, eb)) = rounds.early(b, k, &mut bands[1]) else { break true };
        debug_assert_eq!(bound.to_bits(), same.to_bits());
        if !(ea && eb) {
            break false;
        }
        let (la, lb) = (rounds.late(a, 0, k, bound), rounds.late(b, 1, k, bound));
        rounds.next += 1;
        if !(la && lb) {
            break false;
        }
    };
    rounds.band = bands[0];
    ok
}

/// Whether the rounds on two threads so far, `paired` ns, stopped paying against the parts'
/// own times summed, `in_turn` ns (about what taking them in turn costs): after 20 ms, so that
/// a slow start does not decide, when they saved less than a tenth. Unloaded, two threads take
/// about 0.55 of the sum on the bunny. A call after the machine was idle for a moment starts
/// slowly: both threads did a quarter of their usual work in its first 6–7 ms (the host wakes
/// the idle cores), and judged after 5 ms, a call on the bunny 50 ms after the last gave up the
/// pair in 5 of 15 tries and took one thread's time (208–223 ms against 112–134 ms).
fn stops_paying(paired: u64, in_turn: u64) -> bool {
    paired > 20_000_000 && 10 * paired > 9 * in_turn
}

/// Sides a round takes (both parts) that the band aims at: a round's synchronisation small
/// against its work, and the order within a band close to the distances' (out of order,
/// windows are made that a nearer one would have cut: on the bunny 0.74 M sides taken with
/// rounds of 256–1024 sides, as with 16–64, and 0.88 M with 2048–8192; aiming at 256–2048
/// changes the time by 1 %).
const ROUND_SIDES: usize = 512;

/// The reports a part keeps: the other reads round k's news in its own round k + 1 and the rest
/// in its round k + 2, while this part may already write its report of round k + 2 (three would
/// do; four make the index a mask).
const REPORTS: usize = 4;

/// The rounds of a propagation in two parts. Part p's round k takes what p's queue holds up to
/// the round's bound in two halves: early, what p had queued; then, once the other part has
/// ended its round k − 1, late: its news of that round taken, what that brings. So a part whose
/// round was light goes on with the next round's early half instead of waiting for the other
/// to end its round (waiting for it at every round, with the news taken first, the bunny took
/// 8–13 % longer on two threads; putting aside the early half's work that the news can touch,
/// the faces with a vertex on the other part's, 3 % longer, for 1.5 % fewer sides taken). Both
/// parts set round k's bound from both parts' reports of round k − 2 (the last either knows of
/// the other when it starts round k), each with its own copy of the band, so the rounds are
/// the same on two threads and on one. Rounds are numbered from 2; the reports of rounds 0 and
/// 1 are the start (the source queued in both parts).
struct Rounds {
    reports: [[Report; REPORTS]; 2],
    /// Per part, the last round whose report is written.
    completed: [std::sync::atomic::AtomicU64; 2],
    /// The next round to take, and the band as set for the one before.
    next: u64,
    band: Band,
}

/// What a part tells of its round: its news (in a mutex, as the other part's thread reads it;
/// never contended, the rounds keep writing and reading apart) and how it stands after it.
struct Report {
    news: std::sync::Mutex<News>,
    /// Sides taken in the round; `usize::MAX` for the start.
    done: std::sync::atomic::AtomicUsize,
    /// The least distance queued after the round, inf when nothing is.
    least: std::sync::atomic::AtomicU64,
    /// Nothing queued after the round and no news sent in it: the part has nothing to do but
    /// what news may bring.
    idle: std::sync::atomic::AtomicBool,
}

impl Report {
    fn start() -> Self {
        Report { news: Default::default(), done: usize::MAX.into(), least: 0f64.to_bits().into(), idle: false.into() }
    }
}

/// A part's messages of a round and the pieces of its joins.
#[derive(Default)]
struct News {
    messages: Vec<Message>,
    pieces: Vec<(f64, f64)>,
}

/// A part's news, as the round it came from left it (a panic there, a bug, is raised on its own).
fn lock(news: &std::sync::Mutex<News>) -> std::sync::MutexGuard<'_, News> {
    news.lock().unwrap_or_else(|e| e.into_inner())
}

/// The bounds of the rounds: each a band beyond the last (or beyond the least distance queued,
/// when that is further), the band adapted to the work of the rounds.
#[derive(Clone, Copy)]
struct Band {
    /// The bands of the last two rounds, the last first.
    widths: [f64; 2],
    bound: f64,
}

impl Band {
    /// A round's bound from both parts' reports of two rounds before (`done` sides between them,
    /// the `least` distance queued in either); None when both were idle then: nothing is queued
    /// and no news is on its way, so the rounds are over. The band is that round's, scaled to
    /// the work it took (within a factor of two), not the last round's: the last one's work is
    /// not known yet, and stepping its band by what an older round took would overshoot.
    fn next(&mut self, done: Option<usize>, least: f64, idle: bool) -> Option<f64> {
        if idle {
            return None;
        }
        let before = self.widths[1];
        let width = match done {
            Some(done) => before * (ROUND_SIDES as f64 / done.max(1) as f64).clamp(0.5, 2.0),
            None => before,
        };
        self.widths = [width, self.widths[0]];
        self.bound = if least < f64::INFINITY { self.bound.max(least) } else { self.bound } + width;
        Some(self.bound)
    }
}

impl Rounds {
    fn new(layout: &Layout) -> Self {
        Rounds {
            reports: std::array::from_fn(|_| std::array::from_fn(|_| Report::start())),
            completed: [1.into(), 1.into()],
            next: 2,
            band: Band { widths: [layout.mean_edge; 2], bound: 0.0 },
        }
    }

    fn report(&self, part: usize, round: u64) -> &Report {
        &self.reports[part][(round % REPORTS as u64) as usize]
    }

    /// The early half of a part's round k on `run`: the bound set from the reports of round
    /// k − 2 (on `band`, the part's copy), and what the part has queued up to it taken. None when
    /// the rounds are over, else the bound and whether the work budget held.
    fn early(&self, run: &mut Run, k: u64, band: &mut Band) -> Option<(f64, bool)> {
        use std::sync::atomic::Ordering::Relaxed;
        let before = [0, 1].map(|q| self.report(q, k - 2));
        let done =
            before.iter().map(|r| r.done.load(Relaxed)).try_fold(0usize, |sum, d| (d != usize::MAX).then(|| sum + d));
        let least = before.iter().map(|r| f64::from_bits(r.least.load(Relaxed))).fold(f64::INFINITY, f64::min);
        let bound = band.next(done, least, before.iter().all(|r| r.idle.load(Relaxed)))?;
        run.started = run.budget;
        Some((bound, run.round(bound)))
    }

    /// The late half: the other part's news of round k − 1 taken, then what it queued up to
    /// `bound`, and the round reported. False when the work budget ran out. The other part's
    /// report of round k − 1 must be written.
    fn late(&self, run: &mut Run, p: usize, k: u64, bound: f64) -> bool {
        use std::sync::atomic::Ordering::{Relaxed, Release};
        run.receive(&lock(&self.report(1 - p, k - 1).news));
        let ok = run.round(bound);
        let mine = self.report(p, k);
        let sent = {
            let mut news = lock(&mine.news);
            run.post(&mut news);
            !news.messages.is_empty()
        };
        let least = run.least();
        mine.done.store(run.started - run.budget, Relaxed);
        mine.least.store(least.to_bits(), Relaxed);
        mine.idle.store(least == f64::INFINITY && !sent, Relaxed);
        self.completed[p].store(k, Release);
        ok
    }
}

/// The payload of a panic in a part's rounds (a bug), raised again on the caller's thread.
type Panic = Box<dyn std::any::Any + Send>;

/// Runs a half of a round on two threads, `half` giving what it found and whether the work
/// budget held: Err when the budget ran out or it panicked (with the payload), the other part
/// told by `failed`.
fn held<T>(
    failed: &std::sync::atomic::AtomicBool,
    half: impl FnOnce() -> (T, bool),
) -> std::result::Result<T, Option<Panic>> {
    use std::panic::{catch_unwind, AssertUnwindSafe};
    let outcome = catch_unwind(AssertUnwindSafe(half));
    if !matches!(outcome, Ok((_, true))) {
        failed.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    match outcome {
        Ok((found, true)) => Ok(found),
        Ok((_, false)) => Err(None),
        Err(payload) => Err(Some(payload)),
    }
}

/// How a part left its rounds on two threads.
enum Left {
    Done,
    Failed,
    /// Stopped before this round: two threads stopped paying.
    Stopped(u64),
}

/// A thread's part of the rounds on two threads: its rounds from `rounds.next` on, before each
/// round's late half waiting until the other part has reported the round before. Leaves when
/// the rounds are over, when either part fails, or at `stop_at`. `judge`, given the time since
/// the start and this thread's own time in its rounds, says when to stop (three rounds on, so
/// that the other thread, which reads `stop_at` after waiting for this one, stops at the same
/// round). Returns how it left, its band, and the payload of a panic (a bug) in its rounds.
fn take_rounds(
    rounds: &Rounds,
    run: &mut Run,
    p: usize,
    failed: &std::sync::atomic::AtomicBool,
    stop_at: &std::sync::atomic::AtomicU64,
    mut judge: impl FnMut(u64, u64) -> bool,
) -> (Left, Band, Option<Panic>) {
    use std::sync::atomic::Ordering::{Acquire, Relaxed};
    use std::time::Instant;
    let (started, mut busy, mut band) = (Instant::now(), 0u64, rounds.band);
    let mut k = rounds.next;
    loop {
        if failed.load(Relaxed) {
            return (Left::Failed, band, None);
        }
        if k >= stop_at.load(Relaxed) {
            return (Left::Stopped(k), band, None);
        }
        let round = Instant::now();
        let early =
            held(failed, || rounds.early(run, k, &mut band).map_or((None, true), |(bound, ok)| (Some(bound), ok)));
        let bound = match early {
            Ok(Some(bound)) => bound,
            Ok(None) => return (Left::Done, band, None),
            Err(panic) => return (Left::Failed, band, panic),
        };
        busy += round.elapsed().as_nanos() as u64;
        let mut spins = 0u32;
        while rounds.completed[1 - p].load(Acquire) + 1 < k && !failed.load(Relaxed) {
            // A round lasts tens of microseconds: spin rather than sleep, but yield the core
            // after a while in case it is shared.
            spins += 1;
            if spins < 1 << 14 {
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
        if failed.load(Relaxed) {
            return (Left::Failed, band, None);
        }
        let round = Instant::now();
        if let Err(panic) = held(failed, || ((), rounds.late(run, p, k, bound))) {
            return (Left::Failed, band, panic);
        }
        busy += round.elapsed().as_nanos() as u64;
        // Decided after round k is reported: the other part waits for round k + 1's report
        // before it starts round k + 3, so both stop there.
        if stop_at.load(Relaxed) == u64::MAX && judge(started.elapsed().as_nanos() as u64, busy) {
            stop_at.store(k + 3, Relaxed);
        }
        k += 1;
    }
}

/// The rounds with part `b` on a thread of its own (see `Rounds`). Some(ok) when the rounds
/// are done. The second thread pays only while the machine gives each thread a core: once the
/// rounds stop paying, the second thread stops and None tells the caller to take the rest in
/// turn (on the bunny, with the machine's other core busy, the pair took 1.3–5× one thread's
/// time; with this, one thread's and the 20 ms before it is judged: 220–303 ms against 207–219
/// on one thread, with a busy loop on the other core). `gives_up` is `stops_paying`, or a
/// test's judge.
fn in_two_threads(a: &mut Run, b: &mut Run, rounds: &mut Rounds, gives_up: fn(u64, u64) -> bool) -> Option<bool> {
    use std::panic::resume_unwind;
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
    let (failed, stop_at, b_busy) = (AtomicBool::new(false), AtomicU64::new(u64::MAX), AtomicU64::new(0));
    let shared = &*rounds;
    // The rounds' time on two threads against the parts' own times summed (what taking them
    // in turn would cost, about), from the second thread's first round on: it may start late
    // when its core was idle (see `stops_paying`).
    let mut from = None;
    let judge = |paired: u64, a_busy: u64| {
        let b = b_busy.load(Relaxed);
        if b == 0 {
            return false;
        }
        let (paired_before, a_before, b_before) = *from.get_or_insert((paired, a_busy, b));
        gives_up(paired - paired_before, a_busy - a_before + b - b_before)
    };
    let ((left, band, a_panic), b_panic) = std::thread::scope(|scope| {
        let second = scope.spawn(|| {
            take_rounds(shared, b, 1, &failed, &stop_at, |_, busy| {
                b_busy.store(busy, Relaxed);
                false
            })
            .2
        });
        let first = take_rounds(shared, a, 0, &failed, &stop_at, judge);
        (first, second.join().ok().flatten())
    });
    if let Some(payload) = a_panic.or(b_panic) {
        resume_unwind(payload);
    }
    rounds.band = band;
    match left {
        Left::Done => Some(true),
        Left::Failed => Some(false),
        Left::Stopped(k) => {
            rounds.next = k;
            None
        }
    }
}

/// One row of `geodesic_exact`, in the given numbering.
fn distances_from(layout: &Layout, works: &mut [Work; 2], n: usize, s: usize, split: Split) -> Result<Vec<f64>> {
    let inner = layout.inner[s] as usize;
    if layout.around.of(inner).is_empty() {
        return Ok(unreached(n, s));
    }
    if !propagate_in_parts(layout, works, inner, split) {
        return Err(Error::invalid(
            "faces",
            format!("the exact propagation from vertex {s} did not settle within its work budget"),
        ));
    }
    Ok(layout.inner.iter().map(|&i| works[0].d[i as usize]).collect())
}

#[cfg(test)]
mod tests {
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

    /// Buffers a mesh leaves behind (`KEPT`) serve the next, larger or smaller, with the bits of
    /// fresh ones.
    #[test]
    fn buffers_left_by_another_mesh_give_the_bits_of_fresh_ones() {
        let bumpy = |n: usize| {
            let (mut v, f) = grid(n, n, 0.5);
            v.iter_mut().for_each(|p| p[2] = 0.2 * (1.3 * p[0]).sin() * (1.1 * p[1]).cos());
            (v, f)
        };
        let (big, small) = (bumpy(50), bumpy(30));
        let row = |(v, f): &(Vec<[f64; 3]>, Vec<[u32; 3]>), works: &mut [Work; 2], split| {
            let layout = Layout::new(v, f);
            distances_from(&layout, works, v.len(), 7, split).unwrap()
        };
        for split in [Split::Whole, Split::InTurn] {
            let fresh = [&big, &small].map(|mesh| row(mesh, &mut Default::default(), split));
            let mut used: [Work; 2] = Default::default();
            for (k, mesh) in [&small, &big, &small, &big].into_iter().enumerate() {
                let again = row(mesh, &mut used, split);
                let expected = &fresh[(k + 1) % 2];
                assert!(again.iter().zip(expected).all(|(x, y)| x.to_bits() == y.to_bits()), "mesh {k}");
            }
        }
        // And through `KEPT` (shared with the tests running beside this one): whichever buffers
        // the next mesh gets, its row is that of fresh ones.
        let used = ExactGeodesics::new(&big.0, &big.1);
        used.distances(&[7, 8]).unwrap();
        drop(used);
        let d = ExactGeodesics::new(&small.0, &small.1).distances(&[7]).unwrap();
        // One part: the small mesh is below `PAIRED_FACES`.
        assert!(small.1.len() < PAIRED_FACES);
        let fresh = row(&small, &mut Default::default(), Split::Whole);
        assert!(d[0].iter().zip(&fresh).all(|(x, y)| x.to_bits() == y.to_bits()));
    }

    #[test]
    fn two_threads_that_stop_paying_hand_the_rest_to_one_with_the_same_result() {
        use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
        // A judge that gives up on two threads after five rounds, as when the cores are busy.
        static JUDGED: AtomicUsize = AtomicUsize::new(0);
        let after_five = |_: u64, _: u64| JUDGED.fetch_add(1, Relaxed) + 1 >= 5;
        let (mut v, f) = grid(60, 60, 0.5);
        v.iter_mut().for_each(|p| p[2] = 0.2 * (1.3 * p[0]).sin() * (1.1 * p[1]).cos());
        let layout = Layout::new(&v, &f);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        for s in [1830, 7] {
            let alone = pool.install(|| geodesic_exact(&v, &f, &[s]).unwrap());
            let (mut w0, mut w1) = (Work::default(), Work::default());
            w0.reset(&layout);
            w1.reset(&layout);
            let (mut a, mut b) = (Run::new(&layout, &mut w0, 0), Run::new(&layout, &mut w1, 1));
            let inner = layout.inner[s] as usize;
            a.start(inner);
            b.start(inner);
            let mut rounds = Rounds::new(&layout);
            JUDGED.store(0, Relaxed);
            assert!(in_two_threads(&mut a, &mut b, &mut rounds, after_five).is_none());
            assert_eq!(JUDGED.load(Relaxed), 5);
            assert!(in_turn(&mut a, &mut b, &mut rounds));
            let row = layout.inner.iter().map(|&i| a.w.d[i as usize].min(b.w.d[i as usize]));
            assert!(row.zip(&alone[0]).all(|(x, y)| x.to_bits() == y.to_bits()), "source {s}");
        }
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
        let mut w = Work::default();
        w.reset(&layout);
        let mut whole = Run::new(&layout, &mut w, WHOLE);
        whole.budget = 200;
        whole.start(inner);
        assert!(!whole.round(f64::INFINITY));
        for paired in [false, true] {
            let (mut w0, mut w1) = (Work::default(), Work::default());
            w0.reset(&layout);
            w1.reset(&layout);
            let (mut a, mut b) = (Run::new(&layout, &mut w0, 0), Run::new(&layout, &mut w1, 1));
            (a.budget, b.budget) = (200, 200);
            a.start(inner);
            b.start(inner);
            let mut rounds = Rounds::new(&layout);
            let ok = if paired {
                in_two_threads(&mut a, &mut b, &mut rounds, |_, _| false)
            } else {
                Some(in_turn(&mut a, &mut b, &mut rounds))
            };
            assert_eq!(ok, Some(false), "paired: {paired}");
        }
    }

    /// Reference distances written by pygeodesic (Kirsanov's exact MMP), see `reference_dir`.
    struct Reference {
        vertices: Vec<[f64; 3]>,
        faces: Vec<[u32; 3]>,
        /// (source, pygeodesic's seconds, distances)
        runs: Vec<(usize, f64, Vec<f64>)>,
    }

    /// `$GEOREF_DIR`, else `target/georef`: text files "nv nf ns", the vertices, the faces, then
    /// per source "source s seconds" and its nv distances, made by
    /// `scripts/geodesic_reference.py` (the data are not in the repository).
    fn reference(name: &str) -> Option<Reference> {
        let dir = std::env::var("GEOREF_DIR").unwrap_or_else(|_| {
            let target =
                std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| format!("{}/target", env!("CARGO_MANIFEST_DIR")));
            format!("{target}/georef")
        });
        let text = std::fs::read_to_string(format!("{dir}/{name}.txt")).ok()?;
        let mut t = text.split_whitespace();
        let mut next = || t.next().expect("a complete reference file");
        let (nv, nf, ns): (usize, usize, usize) =
            (next().parse().unwrap(), next().parse().unwrap(), next().parse().unwrap());
        let vertices = (0..nv).map(|_| [0; 3].map(|_| next().parse().unwrap())).collect();
        let faces = (0..nf).map(|_| [0; 3].map(|_| next().parse().unwrap())).collect();
        let runs = (0..ns)
            .map(|_| {
                assert_eq!(next(), "source");
                let (s, secs) = (next().parse().unwrap(), next().parse().unwrap());
                (s, secs, (0..nv).map(|_| next().parse().unwrap()).collect())
            })
            .collect();
        Some(Reference { vertices, faces, runs })
    }

    /// Worst |ours − pygeodesic's| over every vertex of every reference source, and each
    /// source's time (one thread) next to pygeodesic's.
    fn compare(name: &str, r: &Reference) -> f64 {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let mut worst_all: f64 = 0.0;
        for (s, secs, truth) in &r.runs {
            let start = std::time::Instant::now();
            let d = pool.install(|| geodesic_exact(&r.vertices, &r.faces, &[*s]).unwrap());
            let ours = start.elapsed().as_secs_f64();
            let e = worst(&d[0], |i| truth[i]);
            if e > 1e-9 {
                let bad: Vec<_> = (0..truth.len()).filter(|&i| (d[0][i] - truth[i]).abs() > 1e-9).collect();
                eprintln!(
                    "  {} bad, e.g. {:?}",
                    bad.len(),
                    bad.iter().take(5).map(|&i| (i, d[0][i], truth[i])).collect::<Vec<_>>()
                );
            }
            eprintln!(
                "{name} source {s}: worst |diff| {e:.3e}, {ours:.4} s here, {secs:.4} s pygeodesic ({:.1}x)",
                secs / ours
            );
            worst_all = worst_all.max(e);
        }
        eprintln!("{name}: worst |diff| over {} sources {worst_all:.3e}", r.runs.len());
        worst_all
    }

    #[test]
    fn small_meshes_match_pygeodesic_when_the_reference_is_there() {
        for name in ["flat", "hedgehog"] {
            match reference(name) {
                Some(r) => assert!(compare(name, &r) < 1e-9, "{name}"),
                None => eprintln!("{name}: no reference file, skipped (see `reference`)"),
            }
        }
    }

    /// The Stanford bunny of `$BUNNY_PLY` (default data/stanford-bunny-mesh/ in the repository):
    /// 35947 vertices, holes at its base, 1113 vertices no face uses. Published check:
    /// d(14558 → 13039) = 0.22686869313968416 (pygeodesic's notebook); with
    /// `target/georef/bunny.txt` every vertex of every reference source as well.
    /// `cargo test --release --lib mesh::geodesic_exact -- --ignored --nocapture`
    /// One source on the bunny, timed: `cargo test --release --lib geodesic_exact::tests::bunny_time
    /// -- --ignored --nocapture`.
    #[test]
    #[ignore = "a timing, not a test (bench_mesh.py measures it)"]
    fn bunny_time() {
        let Ok(text) = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/data/stanford-bunny-mesh/stanford_bunny.ply"
        )) else {
            return;
        };
        let (v, f) = read_ascii_ply(&text);
        let t = std::time::Instant::now();
        let layout = Layout::new(&v, &f);
        let mut works = [Work::default(), Work::default()];
        eprintln!("layout {:?}, pseudo-sources {}", t.elapsed(), layout.pseudo.iter().filter(|&&p| p).count());
        for s in [0, 14558] {
            let mut best = f64::INFINITY;
            let mut d = Vec::new();
            for _ in 0..4 {
                let t = std::time::Instant::now();
                d = distances_from(&layout, &mut works, v.len(), s, Split::Paired).unwrap();
                best = best.min(t.elapsed().as_secs_f64());
            }
            eprintln!("source {s}: best of 4 {best:.4} s, d[13039] = {}", d[13039]);
        }
    }

    #[test]
    #[ignore = "slow in debug builds"]
    fn bunny_matches_pygeodesic() {
        let path = std::env::var("BUNNY_PLY").unwrap_or_else(|_| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/data/stanford-bunny-mesh/stanford_bunny.ply").to_string()
        });
        let Ok(text) = std::fs::read_to_string(&path) else {
            eprintln!("{path}: not readable, skipped");
            return;
        };
        let (vertices, faces) = read_ascii_ply(&text);
        assert_eq!((vertices.len(), faces.len()), (35947, 69451));
        let d = geodesic_exact(&vertices, &faces, &[14558]).unwrap();
        let published = 0.22686869313968416;
        eprintln!("bunny d(14558 -> 13039) = {:.17} (published {published})", d[0][13039]);
        assert!((d[0][13039] - published).abs() < 1e-9);
        match reference("bunny") {
            Some(r) => {
                assert!(r.vertices == vertices && r.faces == faces, "the reference is of another bunny");
                assert!(compare("bunny", &r) < 1e-9);
            }
            None => eprintln!("bunny: no reference file, only the published value checked"),
        }
    }

    /// The vertices (x y z first, single precision as the file declares) and triangles of an
    /// ASCII PLY.
    fn read_ascii_ply(text: &str) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let (header, body) = text.split_once("end_header").expect("a PLY header");
        let count = |what: &str| -> usize {
            header
                .lines()
                .find_map(|l| l.strip_prefix(&format!("element {what} ")))
                .and_then(|n| n.trim().parse().ok())
                .expect("an element count")
        };
        let (nv, nf) = (count("vertex"), count("face"));
        let mut lines = body.lines().filter(|l| !l.trim().is_empty());
        let vertices = (0..nv)
            .map(|_| {
                let mut t = lines.next().expect("a vertex line").split_whitespace();
                [0; 3].map(|_| t.next().and_then(|x| x.parse::<f32>().ok()).expect("a coordinate") as f64)
            })
            .collect();
        let faces = (0..nf)
            .map(|_| {
                let mut t = lines.next().expect("a face line").split_whitespace();
                assert_eq!(t.next(), Some("3"), "triangles only");
                [0; 3].map(|_| t.next().and_then(|x| x.parse().ok()).expect("an index"))
            })
            .collect();
        (vertices, faces)
    }
}
