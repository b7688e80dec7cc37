//! Pose timing (SPEC K7): the CNC samples its axes on its own clock; axis positions at the
//! profiler's frame times are interpolated linearly, rotary axes unwrapped first so a C axis
//! passing ±π does not swing through zero.
use crate::error::{Error, Result};
use std::f64::consts::PI;

/// `sample_times (S,)` strictly increasing, `samples (S, n_axes)` row-major, `frame_times (F,)`
/// inside `[sample_times[0], sample_times[S−1]]`; `rotary` lists the columns in radians.
/// Returns `(F, n_axes)` row-major.
pub fn interpolate_poses(
    sample_times: &[f64],
    samples: &[f64],
    frame_times: &[f64],
    rotary: &[usize],
) -> Result<Vec<f64>> {
    let s = sample_times.len();
    if s < 2 {
        return Err(Error::shape("sample_times", "(S,) with S >= 2 samples", format!("({s},)")));
    }
    if !samples.len().is_multiple_of(s) || samples.is_empty() {
        return Err(Error::shape(
            "samples",
            format!("({s}, n_axes): one row per sample time"),
            format!("{} values", samples.len()),
        ));
    }
    let w = samples.len() / s;
    crate::error::check_finite("sample_times", sample_times, 1)?;
    crate::error::check_finite("samples", samples, w)?;
    crate::error::check_finite("frame_times", frame_times, 1)?;
    if let Some(k) = sample_times.windows(2).position(|p| !(p[1] > p[0])) {
        return Err(Error::invalid(
            "sample_times",
            format!(
                "must be strictly increasing, but sample {} ({}) is not after sample {} ({})",
                k + 1,
                sample_times[k + 1],
                k,
                sample_times[k]
            ),
        ));
    }
    if let Some(&c) = rotary.iter().find(|&&c| c >= w) {
        return Err(Error::invalid("rotary", format!("column {c} does not exist: samples have {w} columns")));
    }
    let (t0, t1) = (sample_times[0], sample_times[s - 1]);
    if let Some(k) = frame_times.iter().position(|&t| t < t0 || t > t1) {
        return Err(Error::invalid(
            "frame_times",
            format!(
                "frame {k} at t = {} lies outside the CNC samples [{t0}, {t1}]; poses are not extrapolated",
                frame_times[k]
            ),
        ));
    }
    // Unwrap rotary columns: remove jumps larger than π between consecutive samples.
    let mut unwrapped = samples.to_vec();
    for &c in rotary {
        let mut offset = 0.0;
        for k in 1..s {
            let jump = samples[k * w + c] - samples[(k - 1) * w + c];
            offset -= 2.0 * PI * ((jump + PI) / (2.0 * PI)).floor();
            unwrapped[k * w + c] = samples[k * w + c] + offset;
        }
    }
    let mut out = vec![0.0; frame_times.len() * w];
    for (f, &t) in frame_times.iter().enumerate() {
        // Segment k with sample_times[k] <= t <= sample_times[k+1].
        let k = sample_times.partition_point(|&x| x <= t).clamp(1, s - 1) - 1;
        let u = (t - sample_times[k]) / (sample_times[k + 1] - sample_times[k]);
        for c in 0..w {
            let (a, b) = (unwrapped[k * w + c], unwrapped[(k + 1) * w + c]);
            out[f * w + c] = a + u * (b - a);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_axes_interpolate_exactly() {
        let ts = [0.0, 1.0, 2.0];
        let samples = [0.0, 10.0, 2.0, 10.0, 4.0, 13.0];
        let out = interpolate_poses(&ts, &samples, &[0.0, 0.5, 1.75, 2.0], &[]).unwrap();
        assert_eq!(out, vec![0.0, 10.0, 1.0, 10.0, 3.5, 12.25, 4.0, 13.0]);
    }

    #[test]
    fn rotary_axis_crossing_pi_is_unwrapped() {
        let ts = [0.0, 1.0];
        let samples = [3.1, -3.1];
        let out = interpolate_poses(&ts, &samples, &[0.5], &[0]).unwrap();
        assert!((out[0] - PI).abs() < 1e-12, "{}", out[0]);
        let lin = interpolate_poses(&ts, &samples, &[0.5], &[]).unwrap();
        assert!(lin[0].abs() < 1e-12);
    }

    #[test]
    fn refuses_extrapolation_and_bad_times() {
        assert!(interpolate_poses(&[0.0, 1.0], &[0.0, 1.0], &[1.5], &[]).is_err());
        assert!(interpolate_poses(&[0.0, 0.0], &[0.0, 1.0], &[0.0], &[]).is_err());
        assert!(interpolate_poses(&[0.0, 1.0], &[0.0, f64::NAN], &[0.5], &[]).is_err());
    }
}
