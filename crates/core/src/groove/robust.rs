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
/// noisy end reading alone is not a groove bottom).
pub(super) fn mean5(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    (0..n)
        .map(|i| {
            let near = &v[i.saturating_sub(2)..(i + 3).min(n)];
            near.iter().sum::<f64>() / near.len() as f64
        })
        .collect()
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
    let extrapolated = |i: usize, a: usize, b: usize| z[i] - (z[a] + (z[a] - z[b]) * (x[i] - x[a]) / (x[a] - x[b]));
    (0..n)
        .map(|i| {
            let el = (i >= 2).then(|| extrapolated(i, i - 1, i - 2));
            let er = (i + 2 < n).then(|| extrapolated(i, i + 1, i + 2));
            let (l, r) = match (el, er) {
                (Some(l), Some(r)) => (l, r),
                (Some(l), None) => (l, l),
                (None, Some(r)) => (r, r),
                (None, None) => return true,
            };
            !(l.abs() > threshold && r.abs() > threshold && l.signum() == r.signum())
        })
        .collect()
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
    Some((k, mz - k * mx))
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
