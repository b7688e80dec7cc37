//! Windows (module notes of `exact`): a piece of a window waiting on an edge, and the tests that
//! cut windows against the ends of their edge (rule 1) and against each other (rule 3).
use super::*;

/// A piece of a window waiting on one side of an edge, in the frame of that side's half-edge
/// (see the module notes): [b0, b1], source (x, y) with y < 0, σ. A window that later windows
/// cut keeps its `id` on every piece left.
#[derive(Clone, Copy)]
pub(super) struct Window {
    pub(super) b0: f64,
    pub(super) b1: f64,
    pub(super) x: f64,
    pub(super) y: f64,
    pub(super) sigma: f64,
    pub(super) id: u64,
}

impl Window {
    /// The distance it carries to (t, 0) of its edge.
    pub(super) fn at(&self, t: f64) -> f64 {
        self.sigma + hyp(t - self.x, self.y)
    }

    /// Its least distance on [lo, hi] (lo ≤ hi) given its values `at_lo`, `at_hi` at the ends:
    /// `at` is convex, least at x.
    pub(super) fn least(&self, lo: f64, hi: f64, at_lo: f64, at_hi: f64) -> f64 {
        if self.x <= lo {
            at_lo
        } else if self.x >= hi {
            at_hi
        } else {
            self.sigma + self.y.abs()
        }
    }

    /// The same piece in the frame of the edge's other direction.
    pub(super) fn mirrored(&self, l: f64) -> Window {
        Window { b0: l - self.b1, b1: l - self.b0, x: l - self.x, ..*self }
    }
}

/// Rule 1 at both ends of an edge of length `l` for the window (sx, sy, σ) on [b0, b1]: vertex
/// A (at x = 0) is known at `da`, B (at x = l) at `db`. Since f(x) − x does not increase, A wins
/// a prefix, cut off by solving f(x) − x = d(A): x = (sx² + sy² − k²) / (2(k + sx)), k = d(A) − σ;
/// B a suffix alike. Returns the part left, [b0, b1], with the distances f(b0), f(b1) the window
/// carries at its ends (four of the tests need them, so each is taken once), or None when the
/// ends beat all of it.
#[allow(clippy::too_many_arguments)]
pub(super) fn cut_ends(
    sx: f64,
    sy: f64,
    sigma: f64,
    l: f64,
    da: f64,
    db: f64,
    b0: f64,
    b1: f64,
    slack: f64,
) -> Option<[f64; 4]> {
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
pub(super) fn on_edge(num: f64, den: f64) -> Option<f64> {
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
#[inline(always)] // on the hottest path, once per pair of windows: no call there
pub(super) fn crossings(w: &Window, o: &Window, lo: f64, hi: f64) -> ([f64; 2], usize) {
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
pub(super) fn share(w: &Window, o: &Window, lo: f64, hi: f64, bar: f64, mut take: impl FnMut(f64, f64, bool)) {
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
pub(super) fn append(out: &mut Vec<Window>, seg: &Window, a: f64, b: f64, narrow: f64) {
    if !(b - a > narrow) {
        return;
    }
    match out.last_mut() {
        Some(last) if last.id == seg.id && last.b1 == a => last.b1 = b,
        _ => out.push(Window { b0: a, b1: b, ..*seg }),
    }
}

/// The pieces of `list` (in order, disjoint) that overlap (b0, b1). A batch's windows mostly
/// reach an edge in order, so the end of the list is tried first; a window overlaps few pieces,
/// so they are counted one by one (a binary search's chain of dependent loads cost more).
pub(super) fn overlapping(list: &[Window], b0: f64, b1: f64) -> std::ops::Range<usize> {
    let n = list.len();
    let i = if list.last().is_none_or(|s| s.b1 <= b0) { n } else { list.partition_point(|s| s.b1 <= b0) };
    let j = i + list[i..].iter().take_while(|s| s.b0 < b1).count();
    i..j
}
