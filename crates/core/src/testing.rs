//! What the tests share: a small fixed generator, so tests need no extra crate and draw the same
//! numbers on every platform.

/// A linear congruential generator (Knuth's MMIX constants): the next state, and a uniform
/// number in [0, 1) from its top 53 bits.
pub(crate) fn lcg(seed: &mut u64) -> f64 {
    step(seed);
    ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
}

fn step(seed: &mut u64) {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
}

/// A standard normal number (Box–Muller on two `lcg` draws).
pub(crate) fn gauss(seed: &mut u64) -> f64 {
    let (u, v) = (lcg(seed).max(1e-300), lcg(seed));
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// The generator's next state, its top 31 bits as an integer (for bytes and indices).
pub(crate) fn lcg_bits(seed: &mut u64) -> u64 {
    step(seed);
    *seed >> 33
}
