//! Profiler model (SPEC K1): reading `i` of a frame is the SCS point `((i − i0)·δ, 0, d_i)`.
//!
//! The laser line runs along SCS x and the reading `d_i` is a height along SCS z, which points
//! out of the material towards the sensor (an engraved groove is a dip). Readings the sensor
//! could not take (vendor sentinel, NaN, outside the measuring range) are dropped, never turned
//! into points.
use crate::error::{Error, Result};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profiler {
    /// Reading spacing δ along the laser line, mm.
    pub pitch: f64,
    /// Index i0 of the reading at SCS x = 0 (paper 000: N/2).
    pub center: f64,
    /// Readings outside `[lo, hi]` are invalid (the sentinel lies outside it).
    pub valid_lo: f64,
    pub valid_hi: f64,
}

impl Profiler {
    /// Checks the parameters; `center = None` means `n_readings / 2`.
    pub fn new(pitch: f64, n_readings: usize, center: Option<f64>, valid_range: Option<(f64, f64)>) -> Result<Self> {
        if !(pitch.is_finite() && pitch > 0.0) {
            return Err(Error::invalid("pitch", format!("must be a positive number of mm, got {pitch}")));
        }
        let center = center.unwrap_or(n_readings as f64 / 2.0);
        if !center.is_finite() {
            return Err(Error::invalid("center", format!("must be finite, got {center}")));
        }
        let (lo, hi) = valid_range.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return Err(Error::invalid("valid_range", format!("must be (lo, hi) with lo <= hi, got ({lo}, {hi})")));
        }
        Ok(Profiler { pitch, center, valid_lo: lo, valid_hi: hi })
    }

    /// A reading is valid when it is a number inside the measuring range.
    #[inline]
    pub fn is_valid(&self, d: f64) -> bool {
        // NaN fails both comparisons.
        d >= self.valid_lo && d <= self.valid_hi && d.is_finite()
    }

    /// SCS x of reading `i`.
    #[inline]
    pub fn x(&self, i: usize) -> f64 {
        (i as f64 - self.center) * self.pitch
    }
}

/// Points of a whole scan in one coordinate system, frame by frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProfilePoints {
    /// Row-major `(M, 3)`.
    pub points: Vec<f64>,
    /// Frame of each point, `(M,)`.
    pub frame_index: Vec<i64>,
    /// Invalid readings dropped.
    pub dropped: usize,
}

/// Frames `(F, N)` row-major → SCS points of every valid reading, in frame-then-reading order.
pub fn profile_to_points(frames: &[f64], n_readings: usize, profiler: &Profiler) -> ProfilePoints {
    crate::kinematics::scan::map_valid_readings(frames, n_readings, profiler, |_, p| p)
}
