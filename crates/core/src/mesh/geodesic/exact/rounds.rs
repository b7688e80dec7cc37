//! The propagation from one source in two parts that take their queued work in rounds and hand
//! each other what they found between rounds (module notes of `exact`).
use super::*;

/// How the propagation from one source runs: in one part (`Wavefront::me` = `WHOLE`), as each source
/// of a call with several (they run in parallel); or in two parts on two threads, or in turn on
/// one, as the one source of a call.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Split {
    Whole,
    Paired,
    InTurn,
}

/// `Wavefront::me` of a propagation in one part: every face is its own.
pub(super) const WHOLE: u8 = 2;

/// The propagation from inner vertex `source`: in one part (`Split::Whole`), or in two (the
/// faces of each `Layout::owner`) that take the queued work in rounds, each round the distances
/// up to a bound, and exchange their news between rounds; on two threads when `Paired`, else in
/// turn on this one. The parts and the bounds depend on neither, so
/// the distances do not either. The result in `works[0].d`; false when the work budget ran out.
pub(super) fn propagate_in_parts(layout: &Layout, works: &mut [Buffers; 2], source: usize, split: Split) -> bool {
    let [w0, w1] = works;
    if split == Split::Whole {
        w0.reset(layout);
        let mut whole = Wavefront::new(layout, w0, WHOLE);
        whole.start(source);
        let ok = whole.round(f64::INFINITY);
        whole.finish();
        return ok;
    }
    // Both parts' buffers at once: the first time, the first touches of their memory (some
    // 10 MB a part on the bunny) overlap.
    rayon::join(|| w0.reset(layout), || w1.reset(layout));
    let (mut a, mut b) = (Wavefront::new(layout, w0, 0), Wavefront::new(layout, w1, 1));
    a.start(source);
    b.start(source);
    let mut rounds = Rounds::new(layout);
    // On two threads or in turn on this one: the rounds, and so the distances, are the same.
    let ok = match split {
        Split::Paired => in_two_threads(&mut a, &mut b, &mut rounds),
        _ => in_turn(&mut a, &mut b, &mut rounds),
    };
    for (x, y) in a.w.d.iter_mut().zip(&b.w.d) {
        *x = x.min(*y);
    }
    a.finish();
    b.finish();
    ok
}

/// The rounds left, taken in turn on this thread: each part's early half, then each part's late
/// half, round after round (the order of `Rounds`, so the bits of two threads).
pub(super) fn in_turn(a: &mut Wavefront, b: &mut Wavefront, rounds: &mut Rounds) -> bool {
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

/// Spins before a part waiting for the other's report parks its thread (`Rounds::wait`).
const SPINS: u32 = 256;

/// Sides a round takes (both parts) that the band aims at: a round's synchronisation small
/// against its work, and the order within a band close to the distances' (out of order,
/// windows are made that a nearer one would have cut: on the bunny 0.74 M sides taken with
/// rounds of 256–1024 sides, as with 16–64, and 0.88 M with 2048–8192).
pub(super) const ROUND_SIDES: usize = 512;

/// The reports a part keeps: the other reads round k's news in its own round k + 1 and the rest
/// in its round k + 2, while this part may already write its report of round k + 2 (three would
/// do; four make the index a mask).
pub(super) const REPORTS: usize = 4;

/// The rounds of a propagation in two parts. Part p's round k takes what p's queue holds up to
/// the round's bound in two halves: early, what p had queued; then, once the other part has
/// ended its round k − 1, late: its news of that round taken, what that brings. So a part whose
/// round was light goes on with the next round's early half instead of waiting for the other
/// to end its round (a part waiting for the other at every round, news first, idles whenever
/// the rounds' work is uneven). Both
/// parts set round k's bound from both parts' reports of round k − 2 (the last either knows of
/// the other when it starts round k), each with its own copy of the band, so the rounds are
/// the same on two threads and on one. Rounds are numbered from 2; the reports of rounds 0 and
/// 1 are the start (the source queued in both parts).
pub(super) struct Rounds {
    pub(super) reports: [[Report; REPORTS]; 2],
    /// Per part, the last round whose report is written.
    pub(super) completed: [std::sync::atomic::AtomicU64; 2],
    /// The next round to take, and the band as set for the one before.
    pub(super) next: u64,
    pub(super) band: Horizon,
}

/// What a part tells of its round: its news (in a mutex, as the other part's thread reads it;
/// never contended, the rounds keep writing and reading apart) and how it stands after it.
pub(super) struct Report {
    pub(super) news: std::sync::Mutex<Handover>,
    /// Sides taken in the round; `usize::MAX` for the start.
    pub(super) done: std::sync::atomic::AtomicUsize,
    /// The least distance queued after the round, inf when nothing is.
    pub(super) least: std::sync::atomic::AtomicU64,
    /// Nothing queued after the round and no news sent in it: the part has nothing to do but
    /// what news may bring.
    pub(super) idle: std::sync::atomic::AtomicBool,
}

impl Report {
    pub(super) fn start() -> Self {
        Report { news: Default::default(), done: usize::MAX.into(), least: 0f64.to_bits().into(), idle: false.into() }
    }
}

/// A part's messages of a round and the pieces of its joins.
#[derive(Default)]
pub(super) struct Handover {
    pub(super) messages: Vec<Message>,
    pub(super) pieces: Vec<(f64, f64)>,
}

/// A part's news, as the round it came from left it (a panic there, a bug, is raised on its own).
pub(super) fn lock(news: &std::sync::Mutex<Handover>) -> std::sync::MutexGuard<'_, Handover> {
    news.lock().unwrap_or_else(|e| e.into_inner())
}

/// The bounds of the rounds: each a band beyond the last (or beyond the least distance queued,
/// when that is further), the band adapted to the work of the rounds.
#[derive(Clone, Copy)]
pub(super) struct Horizon {
    /// The bands of the last two rounds, the last first.
    pub(super) widths: [f64; 2],
    pub(super) bound: f64,
}

impl Horizon {
    /// A round's bound from both parts' reports of two rounds before (`done` sides between them,
    /// the `least` distance queued in either); None when both were idle then: nothing is queued
    /// and no news is on its way, so the rounds are over. The band is that round's, scaled to
    /// the work it took (within a factor of two), not the last round's: the last one's work is
    /// not known yet, and stepping its band by what an older round took would overshoot.
    pub(super) fn next(&mut self, done: Option<usize>, least: f64, idle: bool) -> Option<f64> {
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
    pub(super) fn new(layout: &Layout) -> Self {
        Rounds {
            reports: std::array::from_fn(|_| std::array::from_fn(|_| Report::start())),
            completed: [1.into(), 1.into()],
            next: 2,
            band: Horizon { widths: [layout.mean_edge; 2], bound: 0.0 },
        }
    }

    /// Waits until part `p` has reported round `k` (or a part failed). A round takes tens of
    /// microseconds, so the wait spins a few hundred times first (a wake-up through the OS
    /// costs about as much as a round); then it parks until the other part, which unparks this
    /// thread after each report, has written it. No clock: what the parts compute, and in what
    /// order, does not depend on how long a wait takes.
    pub(super) fn wait(&self, p: usize, k: u64, failed: &std::sync::atomic::AtomicBool) {
        use std::sync::atomic::Ordering::{Acquire, Relaxed};
        let ready = || self.completed[p].load(Acquire) >= k || failed.load(Relaxed);
        for _ in 0..SPINS {
            if ready() {
                return;
            }
            std::hint::spin_loop();
        }
        while !ready() {
            std::thread::park();
        }
    }

    pub(super) fn report(&self, part: usize, round: u64) -> &Report {
        &self.reports[part][(round % REPORTS as u64) as usize]
    }

    /// The early half of a part's round k on `run`: the bound set from the reports of round
    /// k − 2 (on `band`, the part's copy), and what the part has queued up to it taken. None when
    /// the rounds are over, else the bound and whether the work budget held.
    pub(super) fn early(&self, run: &mut Wavefront, k: u64, band: &mut Horizon) -> Option<(f64, bool)> {
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
    pub(super) fn late(&self, run: &mut Wavefront, p: usize, k: u64, bound: f64) -> bool {
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
pub(super) type Panic = Box<dyn std::any::Any + Send>;

/// Runs a half of a round on two threads, `half` giving what it found and whether the work
/// budget held: Err when the budget ran out or it panicked (with the payload), the other part
/// told by `failed`.
pub(super) fn held<T>(
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

/// A thread's part of the rounds on two threads: its rounds from `rounds.next` on, before each
/// round's late half waiting until the other part has reported the round before
/// (`Rounds::wait`). Leaves when the rounds are over or either part fails. Returns whether the
/// work budget held, its band, and the payload of a panic (a bug) in its rounds.
pub(super) fn take_rounds(
    rounds: &Rounds,
    run: &mut Wavefront,
    p: usize,
    failed: &std::sync::atomic::AtomicBool,
    other: &std::thread::Thread,
) -> (bool, Horizon, Option<Panic>) {
    use std::sync::atomic::Ordering::Relaxed;
    let mut band = rounds.band;
    let mut k = rounds.next;
    // However this part leaves, the other may be waiting for its report: wake it.
    let leave = |ok: bool, band: Horizon, panic: Option<Panic>| {
        other.unpark();
        (ok, band, panic)
    };
    loop {
        if failed.load(Relaxed) {
            return leave(false, band, None);
        }
        let early =
            held(failed, || rounds.early(run, k, &mut band).map_or((None, true), |(bound, ok)| (Some(bound), ok)));
        let bound = match early {
            Ok(Some(bound)) => bound,
            Ok(None) => return leave(true, band, None),
            Err(panic) => return leave(false, band, panic),
        };
        rounds.wait(1 - p, k - 1, failed);
        if failed.load(Relaxed) {
            return leave(false, band, None);
        }
        if let Err(panic) = held(failed, || ((), rounds.late(run, p, k, bound))) {
            return leave(false, band, panic);
        }
        other.unpark();
        k += 1;
    }
}

/// The rounds with part `b` on a thread of its own (see `Rounds`): true when they are done,
/// false when the work budget ran out. The rounds are those `in_turn` takes, so the distances
/// are the same on one thread and on two.
pub(super) fn in_two_threads(a: &mut Wavefront, b: &mut Wavefront, rounds: &mut Rounds) -> bool {
    use std::panic::resume_unwind;
    use std::sync::atomic::AtomicBool;
    let failed = AtomicBool::new(false);
    let shared = &*rounds;
    let caller = std::thread::current();
    let ((ok, band, a_panic), b_panic) = std::thread::scope(|scope| {
        let second = scope.spawn(|| take_rounds(shared, b, 1, &failed, &caller));
        let first = take_rounds(shared, a, 0, &failed, second.thread());
        let (b_ok, _, b_panic) = second.join().unwrap_or((false, first.1, None));
        ((first.0 && b_ok, first.1, first.2), b_panic)
    });
    if let Some(payload) = a_panic.or(b_panic) {
        resume_unwind(payload);
    }
    rounds.band = band;
    ok
}
