//! Profiler model (SPEC K1): reading `i` of a frame is the SCS point `((i − i0)·δ, 0, d_i)`.
//!
//! The laser line runs along SCS x and the reading `d_i` is a height along SCS z, which points
//! out of the material towards the sensor (an engraved groove is a dip). Readings the sensor
//! could not take (vendor sentinel, NaN, outside the measuring range) are dropped, never turned
//! into points.
use crate::error::{Error, Result};

/// The "no reading" code profilers of the SR7140 / LJ family write (mm). It is the default
/// sentinel everywhere: a real height of −99999 mm cannot occur, so dropping it is safe even for
/// profilers that write NaN instead.
pub const VENDOR_SENTINEL: f64 = -99999.0;

/// Which readings count (SPEC K1): a finite number inside the measuring range that is not the
/// profiler's "no reading" code. The one rule of every function that takes frames (points,
/// groove fits, masks), so that a reading dropped by one is dropped by all.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidReadings {
    /// Readings outside `[lo, hi]` are invalid.
    pub lo: f64,
    pub hi: f64,
    /// A reading equal to this is invalid (the profiler's "no reading" code); NaN never is valid.
    pub sentinel: Option<f64>,
}

impl Default for ValidReadings {
    /// Any finite reading but the vendor sentinel.
    fn default() -> Self {
        ValidReadings { lo: f64::NEG_INFINITY, hi: f64::INFINITY, sentinel: Some(VENDOR_SENTINEL) }
    }
}

impl ValidReadings {
    /// Checks the range (`lo ≤ hi`, no NaN; None: unbounded); a NaN sentinel means "the profiler
    /// writes NaN", which is invalid anyway.
    pub fn new(valid_range: Option<(f64, f64)>, sentinel: Option<f64>) -> Result<Self> {
        let (lo, hi) = valid_range.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return Err(Error::invalid("valid_range", format!("must be (lo, hi) with lo <= hi, got ({lo}, {hi})")));
        }
        Ok(ValidReadings { lo, hi, sentinel: sentinel.filter(|s| !s.is_nan()) })
    }

    /// A reading is valid when it is a number inside the measuring range and not the sentinel.
    #[inline]
    pub fn is_valid(&self, d: f64) -> bool {
        // NaN fails both comparisons.
        d >= self.lo && d <= self.hi && d.is_finite() && Some(d) != self.sentinel
    }

    /// The readings with every invalid one turned into NaN (what the groove fits take).
    pub fn masked(&self, readings: &[f64]) -> Vec<f64> {
        readings.iter().map(|&d| if self.is_valid(d) { d } else { f64::NAN }).collect()
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profiler {
    /// Reading spacing δ along the laser line, mm.
    pub pitch: f64,
    /// Index i0 of the reading at SCS x = 0 (paper 000: N/2).
    pub center: f64,
    /// Which readings are valid.
    pub valid: ValidReadings,
}

impl Profiler {
    /// Checks the parameters; `center = None` means `n_readings / 2`.
    pub fn new(
        pitch: f64,
        n_readings: usize,
        center: Option<f64>,
        valid_range: Option<(f64, f64)>,
        sentinel: Option<f64>,
    ) -> Result<Self> {
        if n_readings == 0 {
            return Err(Error::shape("frames", "(F, N) with N >= 1 readings per frame", "N = 0"));
        }
        if !(pitch.is_finite() && pitch > 0.0) {
            return Err(Error::invalid("pitch", format!("must be a positive number of mm, got {pitch}")));
        }
        let center = center.unwrap_or(n_readings as f64 / 2.0);
        if !center.is_finite() {
            return Err(Error::invalid("center", format!("must be finite, got {center}")));
        }
        Ok(Profiler { pitch, center, valid: ValidReadings::new(valid_range, sentinel)? })
    }

    /// A reading is valid when it is a number inside the measuring range and not the sentinel.
    #[inline]
    pub fn is_valid(&self, d: f64) -> bool {
        self.valid.is_valid(d)
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
pub fn profile_to_points(frames: &[f64], n_readings: usize, profiler: &Profiler) -> Result<ProfilePoints> {
    crate::kinematics::scan::check_frames(frames, n_readings)?;
    Ok(crate::kinematics::scan::map_valid_readings(frames, n_readings, profiler, |_, p| p))
}
