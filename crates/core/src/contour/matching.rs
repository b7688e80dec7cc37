//! Matching actual contours to theoretical ones (SPEC C2): nearest centroid (paper 000 eq 20),
//! and a one-to-one assignment minimising the summed centroid distances (Hungarian method),
//! with contours left unmatched when their centroids are farther apart than a limit.
use crate::error::{check_finite_points, Error, Result};

/// Mean of the points.
pub fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for p in points {
        for k in 0..3 {
            m[k] += p[k];
        }
    }
    m.map(|v| v / points.len().max(1) as f64)
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// For each actual centroid, the index of the nearest theoretical centroid (eq 20).
pub fn nearest_centroid(actual: &[[f64; 3]], theoretical: &[[f64; 3]]) -> Vec<Option<usize>> {
    actual
        .iter()
        .map(|a| theoretical.iter().enumerate().min_by(|x, y| dist(a, x.1).total_cmp(&dist(a, y.1))).map(|(i, _)| i))
        .collect()
}

/// [`assign_one_to_one`] with its arguments checked: finite centroids, `max_distance` ≥ 0 mm
/// (`None`: no limit).
pub fn match_contours(
    actual: &[[f64; 3]],
    theoretical: &[[f64; 3]],
    max_distance: Option<f64>,
) -> Result<Vec<Option<usize>>> {
    check_finite_points("actual_centroids", actual)?;
    check_finite_points("theoretical_centroids", theoretical)?;
    let max_distance = max_distance.unwrap_or(f64::INFINITY);
    if !(max_distance >= 0.0) {
        return Err(Error::invalid("max_distance", format!("must be >= 0 mm, got {max_distance}")));
    }
    Ok(assign_one_to_one(actual, theoretical, max_distance))
}

/// One-to-one assignment of actual to theoretical centroids minimising the summed distance;
/// pairs farther apart than `max_distance` are left unmatched (None).
///
/// Written here rather than taken from a crate: the Hungarian method for the small matrices
/// of a part (tens of contours) is fifty lines, and none of the well-kept crates we use has it.
pub fn assign_one_to_one(actual: &[[f64; 3]], theoretical: &[[f64; 3]], max_distance: f64) -> Vec<Option<usize>> {
    let (n, m) = (actual.len(), theoretical.len());
    if n == 0 {
        return Vec::new();
    }
    if m == 0 {
        return vec![None; n];
    }
    // Square cost matrix; dummy rows/columns cost a "too far" penalty so that real pairs beyond
    // max_distance lose to staying unmatched.
    let size = n.max(m);
    let big = if max_distance.is_finite() { max_distance } else { 1e300 };
    let cost = |i: usize, j: usize| -> f64 {
        if i < n && j < m {
            let d = dist(&actual[i], &theoretical[j]);
            if d <= max_distance {
                d
            } else {
                2.0 * big + d
            }
        } else {
            big
        }
    };
    // Jonker–Volgenant style shortest augmenting path (1-based potentials).
    let inf = f64::INFINITY;
    let mut u = vec![0.0; size + 1];
    let mut v = vec![0.0; size + 1];
    let mut p = vec![0usize; size + 1]; // p[j] = row assigned to column j
    let mut way = vec![0usize; size + 1];
    for i in 1..=size {
        p[0] = i;
        let mut j0 = 0;
        let mut minv = vec![inf; size + 1];
        let mut used = vec![false; size + 1];
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let mut delta = inf;
            let mut j1 = 0;
            for j in 1..=size {
                if !used[j] {
                    let cur = cost(i0 - 1, j - 1) - u[i0] - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=size {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    let mut out = vec![None; n];
    for j in 1..=size {
        let i = p[j];
        if i >= 1 && i <= n && j <= m && dist(&actual[i - 1], &theoretical[j - 1]) <= max_distance {
            out[i - 1] = Some(j - 1);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_to_one_beats_greedy_and_leaves_strays() {
        let theo = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]];
        // Both actual centroids are nearest to theoretical 0; one-to-one must split them.
        let act = [[4.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [500.0, 0.0, 0.0]];
        assert_eq!(nearest_centroid(&act, &theo), vec![Some(0), Some(0), Some(1)]);
        assert_eq!(assign_one_to_one(&act, &theo, 20.0), vec![Some(1), Some(0), None]);
    }

    #[test]
    fn permutation_is_recovered() {
        let theo: Vec<[f64; 3]> = (0..12).map(|i| [(i * 37 % 11) as f64 * 30.0, (i / 4) as f64 * 40.0, 0.0]).collect();
        let perm = [5, 2, 9, 0, 11, 7, 3, 1, 10, 4, 8, 6];
        let act: Vec<[f64; 3]> = perm
            .iter()
            .map(|&j| {
                let t: [f64; 3] = theo[j];
                [t[0] + 0.3, t[1] - 0.2, 0.1]
            })
            .collect();
        let got = assign_one_to_one(&act, &theo, 5.0);
        assert_eq!(got, perm.iter().map(|&j| Some(j)).collect::<Vec<_>>());
    }
}
