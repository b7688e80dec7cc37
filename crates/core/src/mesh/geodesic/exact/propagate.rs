//! One part of the propagation from one source: its buffers, queue and the crossing of faces
//! by batches of windows (module notes of `exact`).
use super::*;

/// Sides taken between two looks at the interrupt flag.
const INTERRUPT_SIDES: usize = 4096;

/// A half-edge as the propagation knows it when windows join it: the pieces of the windows
/// waiting there, in order along the edge and disjoint (rule 3). 32 bytes, two to a cache line;
/// rule 2's best path, used only when the side's turn comes, is kept apart (`Buffers::best`).
pub(super) struct Side {
    pub(super) env: Vec<Window>,
    /// The key (as queued) of the side's one live queue entry, `u64::MAX` for none: a side is
    /// queued once, at its earliest window, not once per window.
    pub(super) queued: u64,
}

/// The buffers of a propagation, kept from one source to the next.
#[derive(Default)]
pub(super) struct Buffers {
    pub(super) d: Vec<f64>,
    /// Per half-edge, rule 2's best path from it to its face's apex: length, where it crosses.
    pub(super) best: Vec<(f64, f64)>,
    /// Per half-edge, the windows waiting there.
    pub(super) side: Vec<Side>,
    pub(super) queue: Option<RadixQueue>,
    pub(super) ids: u64,
    pub(super) out: Vec<Window>,
    /// Emptied piece lists, last emptied first: a side takes one when its first window comes,
    /// and gives it back once its windows have crossed. So only the sides on the front hold
    /// storage, and the storage they get was in use a moment ago (still in cache); a list of
    /// its own per side would cost an allocation and the first touches of its memory.
    pub(super) spare: Vec<Vec<Window>>,
    pub(super) pieces: Vec<(f64, f64)>,
    pub(super) kept: Vec<(f64, f64)>,
    pub(super) batch: Vec<Crossing>,
    /// Per vertex, the distance it last emitted at (a pseudo-source emits again only when a
    /// shorter path reaches it, which the other part's late news can bring).
    pub(super) emitted: Vec<f64>,
    /// The sides a batch crossing its face (or a pseudo-source emitting) has given windows to,
    /// each queued once when the batch is done, at the least distance of all it gave. Queued
    /// again at each window that came in lower, as a batch's windows mostly do, a source on the
    /// bunny made 0.76 M queue entries for 0.11 M turns of a side, 0.61 M of them stale, and the
    /// radix heap moved entries 4.8 M times; once per batch, 0.23 M, 0.08 M and 0.9 M.
    pub(super) touched: Vec<u32>,
    /// What this part tells the other at the end of a round, and the pieces of its joins.
    pub(super) outbox: Vec<Message>,
    pub(super) outbox_pieces: Vec<(f64, f64)>,
}

/// A message from one part of a propagation to the other, delivered between rounds.
#[derive(Clone, Copy)]
pub(super) enum Message {
    /// A vertex with faces in both parts is reached at this distance.
    Relax { v: u32, dist: f64 },
    /// A window joins side `t` (of the receiver's) with its pieces `outbox_pieces[from..to]`,
    /// left after the cut by the windows on the sender's side of the edge.
    Join { t: u32, w: Window, least: f64, slack: f64, from: u32, to: u32 },
    /// A pseudo-source lying on an edge reaches the face of half-edge `t` directly.
    EmitFromEdge { t: u32, x: f64, dv: f64 },
}

/// A window of a batch about to cross its face: its part [b0, b1] left by rule 1, its source
/// (sx, sy, σ), where the ray to the apex crosses its edge and the distance it brings the apex.
#[derive(Clone, Copy)]
pub(super) struct Crossing {
    pub(super) b0: f64,
    pub(super) b1: f64,
    pub(super) sx: f64,
    pub(super) sy: f64,
    pub(super) sigma: f64,
    pub(super) xc: f64,
    pub(super) dc: f64,
}

/// One part of the propagation from one source: the faces of `Layout::owner` `me` (all when
/// `me` is `WHOLE`), with its own copy of the vertex distances.
pub(super) struct Wavefront<'a> {
    pub(super) m: &'a Layout,
    pub(super) w: &'a mut Buffers,
    pub(super) queue: RadixQueue,
    pub(super) me: u8,
    pub(super) budget: usize,
    /// The budget when the round began.
    pub(super) started: usize,
}

impl Buffers {
    /// Ready for a propagation on `m`: every distance unknown, no window waiting.
    pub(super) fn reset(&mut self, m: &Layout) {
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

impl<'a> Wavefront<'a> {
    /// Part `me` of a propagation on `m`, with buffers `w` (`Buffers::reset`).
    pub(super) fn new(m: &'a Layout, w: &'a mut Buffers, me: u8) -> Self {
        w.ids = me as u64;
        let mut queue = w.queue.take().unwrap_or_else(RadixQueue::new);
        queue.clear();
        // A budget for each part: neither can hang.
        let budget = WORK_PER_FACE.saturating_mul(m.faces.len()).max(1_000_000);
        Wavefront { m, w, queue, me, budget, started: budget }
    }

    pub(super) fn mine(&self, h: usize) -> bool {
        self.me == WHOLE || self.m.owner[h / 3] == self.me
    }

    pub(super) fn slack(&self, d: f64) -> f64 {
        MARGIN * d.abs() + self.m.tiny
    }

    pub(super) fn relax(&mut self, v: usize, dist: f64) {
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
    pub(super) fn finish(self) {
        self.w.queue = Some(self.queue);
    }

    /// The source, inner vertex `source`, at distance 0.
    pub(super) fn start(&mut self, source: usize) {
        self.w.d[source] = 0.0;
        self.queue.push(0.0, EVENT | source as u64);
    }

    /// Takes what is queued up to `bound`; false when the work budget ran out.
    pub(super) fn round(&mut self, bound: f64) -> bool {
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
                // Out of budget, or asked to stop (looked at every few thousand sides: a load
                // of a shared flag, kept off the hot path).
                if budget == 0 || (budget.is_multiple_of(INTERRUPT_SIDES) && crate::interrupt::requested()) {
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
    pub(super) fn least(&mut self) -> f64 {
        self.queue.peek().unwrap_or(f64::INFINITY)
    }

    /// Hands this round's news for the other part to `mail` (which the other has read).
    pub(super) fn post(&mut self, mail: &mut Handover) {
        mail.messages.clear();
        mail.pieces.clear();
        std::mem::swap(&mut mail.messages, &mut self.w.outbox);
        std::mem::swap(&mut mail.pieces, &mut self.w.outbox_pieces);
    }

    /// The other part's news of the last round.
    pub(super) fn receive(&mut self, news: &Handover) {
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
    pub(super) fn queue_side(&mut self, t: usize, took: bool, least: f64) {
        if took && self.queue.due(least) < self.w.side[t].queued {
            self.w.side[t].queued = self.queue.push(least, t as u64);
        }
    }

    /// `queue_side` while a batch crosses its face: the side is queued when the batch is done
    /// (`queue_touched`), at the least of what it took.
    #[inline(always)]
    pub(super) fn touch_side(&mut self, t: usize, took: bool, least: f64) {
        let due = self.queue.due(least);
        if took && due < self.w.side[t].queued {
            self.w.side[t].queued = due;
            if !self.w.touched.contains(&(t as u32)) {
                self.w.touched.push(t as u32);
            }
        }
    }

    /// Queues the sides the batch gave windows to.
    pub(super) fn queue_touched(&mut self) {
        for &t in &self.w.touched {
            let t = t as usize;
            self.queue.push(f64::from_bits(self.w.side[t].queued), t as u64);
        }
        self.w.touched.clear();
    }

    /// A pseudo-source `v` at its final distance: its neighbours along the edges, and one window
    /// over each edge opposite it, into the faces beyond.
    pub(super) fn emit(&mut self, v: usize, dv: f64) {
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
    pub(super) fn emit_from_edge(&mut self, h: usize, x: f64, dv: f64) {
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
    pub(super) fn source_on_left(&self, left: usize, cx: f64, cy: f64, sx: f64, sy: f64) -> Option<(f64, f64)> {
        let l = self.m.half[left].len;
        (l > 0.0).then(|| (((cx - sx) * cx + (cy - sy) * cy) / l, -(cy * sx - cx * sy).abs() / l))
    }

    /// The same in the frame of the face's edge B→C (`right`).
    pub(super) fn source_on_right(
        &self,
        right: usize,
        len: f64,
        cx: f64,
        cy: f64,
        sx: f64,
        sy: f64,
    ) -> Option<(f64, f64)> {
        let l = self.m.half[right].len;
        (l > 0.0).then(|| (((sx - len) * (cx - len) + sy * cy) / l, -((cx - len) * sy - cy * (sx - len)).abs() / l))
    }

    /// Processes the windows waiting on side `h`: they cross the face. They go together, the first
    /// of them due: they share the face's data in cache, and their order among themselves does
    /// not matter.
    pub(super) fn propagate(&mut self, key: f64, h: usize) {
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
        // dropped 307 of a source's 1.5 M windows, for more work than it saved.
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
    pub(super) fn cross(&mut self, h: usize, c: &Crossing, best: (f64, f64), corners: [f64; 3]) {
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
    pub(super) fn ends(&self, h: usize) -> [f64; 2] {
        let face = self.m.faces[h / 3];
        [self.w.d[face[h % 3] as usize], self.w.d[face[(h + 1) % 3] as usize]]
    }

    /// A window leaving its face through half-edge `h` on [t0, t1] of h's frame, source (sx, sy)
    /// with the face on −y: for each face beyond, rule 3 and the queue. `ends`: the distances of
    /// h's start and end (`Wavefront::ends`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn spawn(&mut self, h: usize, t0: f64, t1: f64, sx: f64, sy: f64, sigma: f64, ends: [f64; 2]) {
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
        let seg = Window { b0: t0, b1: t1, x: sx, y: sy, sigma, id: 0 };
        let least = seg.least(t0, t1, f0, f1);
        let slack = self.slack(least + l);
        match m.half[h].mate {
            NONE => {}
            MANY => {
                for (t, same) in m.others(h) {
                    self.join(h, t, same, seg, least, slack);
                }
            }
            // The common case, without the iterator (on the hottest path, its setup shows).
            mate => self.join(h, (mate & !SAME) as usize, mate & SAME != 0, seg, least, slack),
        }
    }

    /// The window `w` leaving through `h` (in h's frame) joins side `t` of the same edge (running
    /// the `same` way as h or not): rule 3 against the windows waiting on the edge, then the
    /// queue, at the window's `least` distance.
    // Inlined at its two calls in `spawn`, the 48-byte window is not copied through the call;
    // `spawn` and `merge` stay calls (inlined too, they grew the hot loop past the cache).
    #[inline(always)]
    pub(super) fn join(&mut self, h: usize, t: usize, same: bool, w: Window, least: f64, slack: f64) {
        let m = self.m;
        let l = m.half[h].len;
        // Ids odd in one part, even in the other: pieces of one window join, of two never.
        self.w.ids += 2;
        let mut w = Window { id: self.w.ids, ..w };
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
    pub(super) fn cut_by_side(&mut self, u: usize, same: bool, w: &Window, l: f64, slack: f64) {
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
    pub(super) fn merge(&mut self, h: usize, w: &Window, b0: f64, b1: f64, l: f64, slack: f64) -> bool {
        let narrow = MIN_WIDTH * l;
        let ww = &mut *self.w;
        let w = Window { b0, b1, ..*w };
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
