//! The robust statistics and line fits both methods share: medians, MADs and a percentile on
//! integer keys, the spike filters, least-squares and least-trimmed-squares lines.

// Order statistics (medians, MADs, a percentile: about ten selections per frame, a tenth of
// its time) run on integer keys with the order of `f64::total_cmp` (sign-magnitude bits made
// two's complement): the same values are selected, about twice as fast as with a float
// comparator.
#[inline(always)]
pub(super) fn key(v: f64) -> i64 {
    let b = v.to_bits() as i64;
    b ^ ((((b >> 63) as u64) >> 1) as i64)
}

/// The value of a [`key`] (the map is its own inverse).
#[inline(always)]
pub(super) fn value(k: i64) -> f64 {
    f64::from_bits(key(f64::from_bits(k as u64)) as u64)
}

/// The median of the values whose keys these are (the mean of the two middle ones for an even
/// count; the keys are reordered).
pub(super) fn median_of_keys(keys: &mut [i64]) -> f64 {
    let n = keys.len();
    let (lo, m, _) = keys.select_nth_unstable(n / 2);
    if n % 2 == 1 {
        value(*m)
    } else {
        0.5 * (value(lo.iter().copied().max().unwrap_or(*m)) + value(*m))
    }
}

/// 1.4826 · median |r − median r|, with `scratch` as work space.
pub(super) fn mad_sigma(values: impl Iterator<Item = f64>, scratch: &mut Vec<i64>) -> f64 {
    scratch.clear();
    scratch.extend(values.map(key));
    if scratch.is_empty() {
        return 0.0;
    }
    let m = median_of_keys(scratch);
    for k in scratch.iter_mut() {
        *k = key((value(*k) - m).abs());
    }
    1.4826 * median_of_keys(scratch)
}

/// The pairs `(a[i], b[i])` where `keep(i)`, as two vectors (sized once: `unzip` of a filter
/// grows them by reallocation).
pub(super) fn select_pairs(a: &[f64], b: &[f64], keep: impl Fn(usize) -> bool) -> (Vec<f64>, Vec<f64>) {
    let (mut ka, mut kb) = (Vec::with_capacity(a.len()), Vec::with_capacity(a.len()));
    for i in 0..a.len() {
        if keep(i) {
            ka.push(a[i]);
            kb.push(b[i]);
        }
    }
    (ka, kb)
}

/// NumPy's default (linear) percentile, with `scratch` as work space.
pub(super) fn percentile(values: &[f64], q: f64, scratch: &mut Vec<i64>) -> f64 {
    scratch.clear();
    scratch.extend(values.iter().map(|&v| key(v)));
    let pos = q / 100.0 * (values.len() - 1) as f64;
    let (i, t) = (pos.floor() as usize, pos.fract());
    let (_, a, above) = scratch.select_nth_unstable(i);
    let a = value(*a);
    match above.iter().copied().min() {
        Some(b) if t != 0.0 => a + t * (value(b) - a),
        _ => a,
    }
}

/// The running median of 3, with Tukey's end-point rule at the two ends (the median of the end
/// reading, its smoothed neighbor and the line through the next two smoothed values carried to
/// the end): one noisy end reading is not taken for a groove bottom.
pub(super) fn median3(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    let mut out = v.to_vec();
    let med = |a: f64, b: f64, c: f64| a.min(b).max(a.max(b).min(c));
    for i in 1..n.saturating_sub(1) {
        out[i] = med(v[i - 1], v[i], v[i + 1]);
    }
    if n >= 4 {
        out[0] = med(v[0], out[1], 3.0 * out[1] - 2.0 * out[2]);
        out[n - 1] = med(v[n - 1], out[n - 2], 3.0 * out[n - 2] - 2.0 * out[n - 3]);
    }
    out
}

/// The 5-reading moving mean; near the ends, the mean of the readings within ±2 there are (one
/// noisy end reading alone is not a groove bottom). The inner readings summed in one plain
/// pass (the same sums, left to right, as the ends': the compiler vectorises it).
pub(super) fn mean5(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    let at_end = |i: usize| {
        let near = &v[i.saturating_sub(2)..(i + 3).min(n)];
        near.iter().sum::<f64>() / near.len() as f64
    };
    if n < 5 {
        return (0..n).map(at_end).collect();
    }
    let mut out = Vec::with_capacity(n);
    out.extend([at_end(0), at_end(1)]);
    out.extend(v.windows(5).map(|w| ((((0.0 + w[0]) + w[1]) + w[2]) + w[3] + w[4]) / 5.0));
    out.extend([at_end(n - 2), at_end(n - 1)]);
    out
}

/// Readings kept by the spike test: a reading is a spike when the linear extrapolations from
/// its two left and from its two right neighbors both miss it by more than `threshold`, on
/// the same side. A V tip, a corner or a steep wall is predicted by at least one side; an
/// isolated spike by neither. At the ends the one available side decides.
pub(super) fn spike_free(x: &[f64], z: &[f64], threshold: f64) -> Vec<bool> {
    let n = x.len();
    if n < 5 {
        return vec![true; n];
    }
    // The slope of each reading step, once: both extrapolations of reading i use the step
    // beyond its neighbour (one division per reading, not two; the test was a twentieth of
    // a frame of 400 readings).
    let slope: Vec<f64> = x.windows(2).zip(z.windows(2)).map(|(x, z)| (z[1] - z[0]) / (x[1] - x[0])).collect();
    let from_left = |i: usize| z[i] - (z[i - 1] + slope[i - 2] * (x[i] - x[i - 1]));
    let from_right = |i: usize| z[i] - (z[i + 1] + slope[i + 1] * (x[i] - x[i + 1]));
    let kept = |l: f64, r: f64| !(l.abs() > threshold && r.abs() > threshold && l.signum() == r.signum());
    let mut keep = Vec::with_capacity(n);
    keep.extend([0, 1].map(|i| kept(from_right(i), from_right(i))));
    keep.extend((2..n - 2).map(|i| kept(from_left(i), from_right(i))));
    keep.extend([n - 2, n - 1].map(|i| kept(from_left(i), from_left(i))));
    keep
}

/// A line through the surface of a grooved frame: least-trimmed-squares concentration steps
/// (refit on the half of the readings nearest the line) from the line through the upper
/// quartiles of the two halves of the frame (a groove is a dip, so upper quantiles lie on the
/// surface; the least-squares line when the halves do not allow it). One step: the steps
/// converge in two or three from this start, and more steps or a second start (least squares)
/// changed no result in the accuracy tests while costing a third of the frame's time.
pub(super) const C_STEPS: usize = 1;
pub(super) fn robust_line(x: &[f64], z: &[f64], scratch: &mut Vec<i64>) -> Option<(f64, f64)> {
    let n = x.len();
    let h = (n / 2).max(2);
    let m = n / 2;
    let mut start = None;
    if m >= 2 {
        // Readings come in order along the line: the median x of a half is its middle one.
        let sorted = x.windows(2).all(|w| w[0] <= w[1]);
        let half_median = |h: &[f64]| {
            if sorted {
                let k = h.len() / 2;
                if h.len() % 2 == 1 {
                    h[k]
                } else {
                    0.5 * (h[k - 1] + h[k])
                }
            } else {
                percentile(h, 50.0, &mut Vec::new())
            }
        };
        let (xa, xb) = (half_median(&x[..m]), half_median(&x[m..]));
        let (za, zb) = (percentile(&z[..m], 75.0, scratch), percentile(&z[m..], 75.0, scratch));
        if xb > xa {
            let k = (zb - za) / (xb - xa);
            start = Some((k, za - k * xa));
        }
    }
    let (mut k, mut b) = start.or_else(|| fit_line(x.iter().copied().zip(z.iter().copied())))?;
    // The h-th smallest |residual| by selection, then the readings within it: no sort.
    let mut res = Vec::with_capacity(n);
    for _ in 0..C_STEPS {
        res.clear();
        res.extend(x.iter().zip(z).map(|(&x, &z)| (z - (k * x + b)).abs()));
        scratch.clear();
        scratch.extend(res.iter().map(|&r| key(r)));
        let t = value(*scratch.select_nth_unstable(h - 1).1);
        let nearest = (0..n).filter(|&i| res[i] <= t).map(|i| (x[i], z[i]));
        let Some(line) = fit_line(nearest) else { break };
        (k, b) = line;
    }
    Some((k, b))
}

/// Least-squares line `z = k x + b` (None when x is constant).
#[inline(always)]
pub(super) fn fit_line(x: impl Iterator<Item = (f64, f64)> + Clone) -> Option<(f64, f64)> {
    fit_line_spread(x).map(|(k, b, _)| (k, b))
}

/// [`fit_line`] with the spread of the abscissae it was fitted to: their count, mean and
/// `Σ(x − x̄)²` (the variance of the line's height needs them; they are the fit's own sums).
#[inline(always)]
pub(super) fn fit_line_spread(x: impl Iterator<Item = (f64, f64)> + Clone) -> Option<(f64, f64, [f64; 3])> {
    let (mut n, mut sx, mut sz) = (0.0, 0.0, 0.0);
    for (xi, zi) in x.clone() {
        n += 1.0;
        sx += xi;
        sz += zi;
    }
    if n < 2.0 {
        return None;
    }
    let (mx, mz) = (sx / n, sz / n);
    let (mut sxx, mut sxz) = (0.0, 0.0);
    for (xi, zi) in x {
        sxx += (xi - mx) * (xi - mx);
        sxz += (xi - mx) * (zi - mz);
    }
    if sxx <= 0.0 {
        return None;
    }
    let k = sxz / sxx;
    Some((k, mz - k * mx, [n, mx, sxx]))
}

/// Keeps the pairs `(a[i], b[i])` where `keep[i]`, in place.
pub(super) fn retain_pairs(a: &mut Vec<f64>, b: &mut Vec<f64>, keep: &[bool]) {
    let mut j = 0;
    for i in 0..a.len() {
        if keep[i] {
            a[j] = a[i];
            b[j] = b[i];
            j += 1;
        }
    }
    a.truncate(j);
    b.truncate(j);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{gauss, lcg};

    /// Frames with spikes and uneven spacing, of 0–12 and 200 readings.
    fn frames() -> Vec<(Vec<f64>, Vec<f64>)> {
        let mut seed = 5u64;
        let mut out = Vec::new();
        for n in (0..13).chain([200]) {
            for _ in 0..40 {
                let mut x = 0.0;
                let xs: Vec<f64> = (0..n)
                    .map(|_| {
                        x += 0.01 + 0.03 * lcg(&mut seed);
                        x
                    })
                    .collect();
                let zs = xs
                    .iter()
                    .map(|&x| {
                        let spike = if lcg(&mut seed) < 0.1 { 0.2 * gauss(&mut seed) } else { 0.0 };
                        (x * 7.0).sin() * 0.1 + 0.01 * gauss(&mut seed) + spike
                    })
                    .collect();
                out.push((xs, zs));
            }
        }
        out
    }

    #[test]
    fn mean5_is_the_mean_of_the_readings_within_two() {
        for (_, z) in frames() {
            let n = z.len();
            for (i, m) in mean5(&z).into_iter().enumerate() {
                let near = &z[i.saturating_sub(2)..(i + 3).min(n)];
                let mean = near.iter().sum::<f64>() / near.len() as f64;
                assert!((m - mean).abs() <= 1e-15 * mean.abs().max(1.0), "{i} of {n}: {m} {mean}");
            }
        }
    }

    #[test]
    fn spike_free_follows_its_definition() {
        // Each side's line through the two neighbours on that side, carried to the reading.
        let missed = |x: &[f64], z: &[f64], i: usize, a: usize, b: usize| {
            z[i] - (z[a] + (z[a] - z[b]) * (x[i] - x[a]) / (x[a] - x[b]))
        };
        let (mut spikes, mut near_threshold) = (0, 0);
        for (x, z) in frames() {
            let n = x.len();
            let keep = spike_free(&x, &z, 0.05);
            // Under five readings no reading has two sides to judge it by.
            if n < 5 {
                assert!(keep.iter().all(|&k| k));
                continue;
            }
            for (i, &kept) in keep.iter().enumerate() {
                let l = (i >= 2).then(|| missed(&x, &z, i, i - 1, i - 2));
                let r = (i + 2 < n).then(|| missed(&x, &z, i, i + 1, i + 2));
                let (l, r) = match (l, r) {
                    (Some(l), Some(r)) => (l, r),
                    (Some(s), None) | (None, Some(s)) => (s, s),
                    (None, None) => unreachable!("five readings or more"),
                };
                // Rounding may decide a reading whose miss is the threshold to the last bits.
                if (l.abs() - 0.05).abs() < 1e-12 || (r.abs() - 0.05).abs() < 1e-12 {
                    near_threshold += 1;
                    continue;
                }
                let spike = l.abs() > 0.05 && r.abs() > 0.05 && l.signum() == r.signum();
                assert_eq!(kept, !spike, "reading {i} of {n}: misses {l} {r}");
                spikes += usize::from(spike);
            }
        }
        assert!(spikes > 100 && near_threshold < 5, "{spikes} {near_threshold}");
    }
}
