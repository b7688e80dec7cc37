//! Frames + poses → workpiece points in one parallel pass (SPEC K7).
//!
//! Two passes over the frames: count the valid readings of each frame, then fill each frame's
//! own slice of the output. Every output value is computed by exactly one thread in a fixed
//! place, so the result is bit-identical whatever the thread count.
use super::chain::KinematicChain;
use super::profiler::{ProfilePoints, Profiler};
use crate::error::{Error, Result};
use nalgebra::Matrix4;
use rayon::prelude::*;

/// Points of a scan in the WCS (same layout as [`ProfilePoints`]).
pub type ScanPoints = ProfilePoints;

/// Frames `(F, N)` row-major and poses `(F, n_axes)` → WCS points of every valid reading.
pub fn frames_to_points(
    chain: &KinematicChain,
    frames: &[f64],
    n_readings: usize,
    poses: &[f64],
    profiler: &Profiler,
) -> Result<ScanPoints> {
    let f = check_frames(frames, n_readings)?;
    chain.check_poses("axes", poses, Some(f))?;
    let w = chain.n_axes();
    let transforms: Vec<Matrix4<f64>> =
        (0..f).into_par_iter().map(|k| chain.transform(&poses[k * w..(k + 1) * w])).collect();
    Ok(map_valid_readings(frames, n_readings, profiler, |k, p| {
        let t = &transforms[k];
        crate::geom::transform_point(t, p)
    }))
}

/// Checks a row-major `(F, N)` frame array; returns F.
pub(crate) fn check_frames(frames: &[f64], n_readings: usize) -> Result<usize> {
    if n_readings == 0 || !frames.len().is_multiple_of(n_readings) {
        return Err(Error::shape(
            "frames",
            "(F, N) with N >= 1 readings per frame",
            format!("{} values in rows of {n_readings}", frames.len()),
        ));
    }
    Ok(frames.len() / n_readings)
}

/// The shared two-pass kernel: `map(frame, scs_point)` gives the output point of each valid
/// reading.
pub(crate) fn map_valid_readings<M>(frames: &[f64], n: usize, profiler: &Profiler, map: M) -> ProfilePoints
where
    M: Fn(usize, [f64; 3]) -> [f64; 3] + Sync,
{
    if n == 0 {
        return ProfilePoints::default();
    }
    let counts: Vec<usize> =
        frames.par_chunks(n).map(|row| row.iter().filter(|d| profiler.is_valid(**d)).count()).collect();
    let total: usize = counts.iter().sum();
    let mut points = vec![0.0f64; 3 * total];
    let mut frame_index = vec![0i64; total];
    // Hand each frame its own disjoint output slices.
    let mut slots = Vec::with_capacity(counts.len());
    {
        let (mut p_rest, mut i_rest) = (&mut points[..], &mut frame_index[..]);
        for &c in &counts {
            let (p, pr) = p_rest.split_at_mut(3 * c);
            let (i, ir) = i_rest.split_at_mut(c);
            slots.push((p, i));
            p_rest = pr;
            i_rest = ir;
        }
    }
    slots.into_par_iter().zip(frames.par_chunks(n)).enumerate().for_each(|(k, ((p_out, i_out), row))| {
        let mut j = 0;
        for (i, &d) in row.iter().enumerate() {
            if profiler.is_valid(d) {
                let q = map(k, [profiler.x(i), 0.0, d]);
                p_out[3 * j..3 * j + 3].copy_from_slice(&q);
                i_out[j] = k as i64;
                j += 1;
            }
        }
    });
    ProfilePoints { points, frame_index, dropped: frames.len() - total }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(f: usize, n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut frames = Vec::with_capacity(f * n);
        for k in 0..f {
            for i in 0..n {
                let v = ((k * 31 + i * 17) % 97) as f64 * 0.01 - 0.3;
                // Every 13th reading a sentinel, every 29th a NaN.
                frames.push(if (k + i) % 13 == 0 {
                    -99999.0
                } else if (k * i) % 29 == 5 {
                    f64::NAN
                } else {
                    v
                });
            }
        }
        let poses: Vec<f64> = (0..f)
            .flat_map(|k| {
                let t = k as f64;
                [t * 0.1, 5.0 - t * 0.05, 30.0, 0.001 * t, -0.002 * t, 0.01 * t]
            })
            .collect();
        (frames, poses)
    }

    #[test]
    fn parallel_equals_sequential_bit_for_bit() {
        let (frames, poses) = scan(300, 257);
        let chain = KinematicChain::ac_head([10.0, 0.0, 120.0], [0.01, 0.02, -0.03, 40.0, 1.0, -90.0]).unwrap();
        let prof = Profiler::new(0.025, 257, None, Some((-5.0, 5.0)), None).unwrap();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| frames_to_points(&chain, &frames, 257, &poses, &prof).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a.points.len(), b.points.len());
        assert!(a.points.iter().zip(&b.points).all(|(x, y)| x.to_bits() == y.to_bits()));
        assert_eq!(a.frame_index, b.frame_index);
    }

    #[test]
    fn drops_invalid_readings_and_keeps_order() {
        let (frames, poses) = scan(20, 50);
        let chain = KinematicChain::ac_head([0.0; 3], [0.0; 6]).unwrap();
        let prof = Profiler::new(0.5, 50, Some(10.0), Some((-5.0, 5.0)), None).unwrap();
        let out = frames_to_points(&chain, &frames, 50, &poses, &prof).unwrap();
        let valid = frames.iter().filter(|d| d.is_finite() && d.abs() <= 5.0).count();
        assert_eq!(out.frame_index.len(), valid);
        assert_eq!(out.dropped, frames.len() - valid);
        assert!(out.frame_index.windows(2).all(|w| w[0] <= w[1]));
        // Reading 0 of frame 1 (valid): x = (0 − 10)·0.5 before the pose.
        let local = super::super::profile_to_points(&frames, 50, &prof).unwrap();
        assert_eq!(local.frame_index, out.frame_index);
        assert!(local.points.chunks(3).all(|p| p[1] == 0.0));
    }

    #[test]
    fn mismatched_poses_are_an_error() {
        let (frames, poses) = scan(10, 8);
        let chain = KinematicChain::ac_head([0.0; 3], [0.0; 6]).unwrap();
        let prof = Profiler::new(0.5, 8, None, None, None).unwrap();
        let e = frames_to_points(&chain, &frames, 8, &poses[..54], &prof).unwrap_err();
        assert!(e.to_string().starts_with("axes:"), "{e}");
    }

    #[test]
    fn the_sentinel_is_dropped_nan_sentinel_means_none() {
        let frames = [-99999.0, 1.0, f64::NAN, -99999.0, 2.0, 3.0];
        let prof = Profiler::new(0.5, 3, None, None, Some(crate::kinematics::VENDOR_SENTINEL)).unwrap();
        let out = super::super::profile_to_points(&frames, 3, &prof).unwrap();
        assert_eq!(out.frame_index, vec![0, 1, 1]);
        assert_eq!(out.dropped, 3);
        let none = Profiler::new(0.5, 3, None, None, Some(f64::NAN)).unwrap();
        assert_eq!(none.valid.sentinel, None);
        let kept = super::super::profile_to_points(&frames, 3, &Profiler::new(0.5, 3, None, None, None).unwrap());
        assert_eq!(kept.unwrap().frame_index.len(), 5, "without a sentinel −99999 is a reading");
        assert!(Profiler::new(0.5, 0, None, None, None).is_err());
    }
}
