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
//! two threads or more the parts run at once, on one in turn: a fixed rule (the mesh's size and
//! the pool's thread count), never the clock or the host's load. The rounds are the same either
//! way, so the distances are too, bit for bit. Out of
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
//! (and from call to call of a prepared mesh; they are freed with it).
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
mod layout;
mod propagate;
mod queue;
mod rounds;
#[cfg(test)]
mod tests;
mod window;

use super::{check_input, unreached, Around};
use crate::error::{Error, Result};
use layout::*;
use propagate::*;
use queue::*;
use rayon::prelude::*;
use rounds::*;
use std::f64::consts::PI;
use window::*;

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
/// exchange (on the bunny, messages per side taken: 64 faces 0.39, 256 0.20, 1024 0.11, while
/// the longer part of the rounds stays about 0.56 of all sides taken).
const FACE_BLOCK: usize = 256;
/// Faces below which one source runs in one part: with a few blocks each, the parts would
/// exchange about as much as they work (BENCHMARKS.md, exact geodesics).
const PAIRED_FACES: usize = 8 * FACE_BLOCK;
/// `Half::mate` of a half-edge on an edge of more than two faces.
const MANY: u32 = u32::MAX - 1;
/// `Half::mate` flag: the mate runs the same way (faces oriented inconsistently).
const SAME: u32 = 1 << 31;

/// A mesh laid out once for exact geodesics (`GeodesicSolver` with `GeodesicMethod::Exact`):
/// each call of `distances` reuses the layout and the propagation buffers of earlier calls (one
/// set per thread that has worked on it, a few tens of bytes per half-edge). They are freed with
/// it: nothing is kept for the life of the process.
pub(super) struct ExactGeodesics {
    layout: Layout,
    n: usize,
    /// Buffers not in use, handed from source to source and from call to call: rayon calls a
    /// `map_init` initialiser once per job it splits off, which here is about once per source.
    idle: std::sync::Mutex<Vec<Buffers>>,
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
                let take = || self.idle.lock().ok().and_then(|mut idle| idle.pop()).unwrap_or_default();
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

/// Exact geodesic distances along the mesh surface from each source vertex to every vertex,
/// one row per source, sources in parallel. A vertex that no face uses, or that no face path
/// reaches, is `inf`. Degenerate and non-manifold meshes are accepted (see the module notes).
pub fn geodesic_exact(vertices: &[[f64; 3]], faces: &[[u32; 3]], sources: &[usize]) -> Result<Vec<Vec<f64>>> {
    check_input(vertices, faces, sources)?;
    ExactGeodesics::new(vertices, faces).distances(sources)
}

/// One row of `geodesic_exact`, in the given numbering.
fn distances_from(layout: &Layout, works: &mut [Buffers; 2], n: usize, s: usize, split: Split) -> Result<Vec<f64>> {
    crate::interrupt::check()?;
    let inner = layout.inner[s] as usize;
    if layout.around.of(inner).is_empty() {
        return Ok(unreached(n, s));
    }
    if !propagate_in_parts(layout, works, inner, split) {
        crate::interrupt::check()?;
        return Err(Error::invalid(
            "faces",
            format!("the exact propagation from vertex {s} did not settle within its work budget"),
        ));
    }
    Ok(layout.inner.iter().map(|&i| works[0].d[i as usize]).collect())
}
