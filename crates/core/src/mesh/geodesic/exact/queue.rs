//! The propagation's priority queue.

/// A monotone priority queue (a radix heap): the propagation only ever queues distances at
/// least the one it last took out (a window's children carry more than it, a vertex reached
/// from it too), so entries are binned by the highest bit in which their key differs from the
/// last key taken, and each is moved at most once per bit: a few cheap moves instead of a
/// binary heap's cache misses. Keys are distances ≥ 0, whose f64 bits order like the numbers.
/// Equal keys come out last in, first out, the same on every run.
pub(super) struct RadixQueue {
    pub(super) last: u64,
    pub(super) bins: Vec<Vec<(u64, u64)>>,
    /// Bit b set when bin b holds entries (64 bins: keys are ≥ 0, their sign bits never differ).
    pub(super) full: u64,
    /// Entries queued below `last`, which a radix heap cannot order: the other part's news, which
    /// comes after this part has gone on, and a child that rounding put a hair below its parent;
    /// taken first, in order (taken at `last` instead, out of order, they once made the two parts'
    /// work run away).
    pub(super) behind: std::collections::BinaryHeap<std::cmp::Reverse<(u64, u64)>>,
}

impl RadixQueue {
    pub(super) fn new() -> Self {
        RadixQueue { last: 0, bins: (0..64).map(|_| Vec::new()).collect(), full: 0, behind: Default::default() }
    }

    pub(super) fn clear(&mut self) {
        self.bins.iter_mut().for_each(Vec::clear);
        self.last = 0;
        self.full = 0;
        self.behind.clear();
    }

    /// The bin of `key` when `last` is the last key taken: one past its highest bit that differs.
    pub(super) fn bin(key: u64, last: u64) -> usize {
        (64 - (key ^ last).leading_zeros()) as usize
    }

    /// The key as queued (its bits; 0 for a negative one).
    pub(super) fn due(&self, key: f64) -> u64 {
        if key > 0.0 {
            key.to_bits()
        } else {
            0
        }
    }

    /// Queues `item` at `key`; returns the key as queued (`due`).
    #[inline(always)]
    pub(super) fn push(&mut self, key: f64, item: u64) -> u64 {
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
    pub(super) fn settle(&mut self) -> bool {
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
        // Local copies of the bins and bits keep the loop in registers.
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
    pub(super) fn peek(&mut self) -> Option<f64> {
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
    pub(super) fn pop_to(&mut self, bound: f64) -> Option<(f64, u64)> {
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
pub(super) const EVENT: u64 = 1 << 63;
