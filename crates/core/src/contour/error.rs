//! Contour error (SPEC C3–C5, paper 000 eq 21–23).
//!
//! E = mean(P) − mean(Q) (21); Q' = Q + E. Each theoretical point P_i is paired with its
//! nearest Q'_j (M_P), each Q'_k with its nearest P_l (M_Q). When no Q'_k has P_i as its nearest
//! point, P_i keeps Q'_j (case 1); otherwise of the Q'_k that do, the farthest from P_i is taken
//! and P_i keeps whichever of Q'_j and that Q'_k is farther (22) (cases 2 and 3). So an actual
//! point straying from a corner counts with its true deviation. e_i = δ1|E| + δ2|P_i − Q'| (23).
use crate::error::{Error, Result};
use crate::spatial::PointIndex;
use rayon::prelude::*;

/// Which rule of eq (22) chose the match of a theoretical point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum MatchCase {
    /// No actual point has P_i as its nearest: the nearest actual point.
    Nearest = 1,
    /// Some do, and the nearest actual point is the farther: kept.
    NearestFarther = 2,
    /// Some do, and the farthest of them is farther than the nearest actual point: taken.
    ReverseFarther = 3,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ContourError {
    /// E = mean(P) − mean(Q), mm.
    pub offset: [f64; 3],
    /// e_i per theoretical point, mm.
    pub errors: Vec<f64>,
    /// |P_i − Q'_match| per theoretical point (the part after offset compensation), mm.
    pub deviations: Vec<f64>,
    /// Index into the actual points of each theoretical point's match.
    pub matched: Vec<usize>,
    pub cases: Vec<MatchCase>,
    pub mean: f64,
    pub std: f64,
    pub max: f64,
}

fn check(name: &str, pts: &[[f64; 3]]) -> Result<()> {
    if pts.is_empty() {
        return Err(Error::shape(name, "(n, 3) with n >= 1 points", "(0, 3)"));
    }
    crate::error::check_finite_points(name, pts)?;
    Ok(())
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// `theoretical` P (a points) and `actual` Q (b points) of one contour; weights δ1, δ2.
pub fn contour_error(theoretical: &[[f64; 3]], actual: &[[f64; 3]], delta1: f64, delta2: f64) -> Result<ContourError> {
    check("theoretical", theoretical)?;
    check("actual", actual)?;
    for (name, v) in [("delta1", delta1), ("delta2", delta2)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::invalid(name, format!("must be a weight >= 0, got {v}")));
        }
    }
    let mean = |p: &[[f64; 3]]| {
        let mut m = [0.0; 3];
        for q in p {
            for k in 0..3 {
                m[k] += q[k];
            }
        }
        m.map(|v| v / p.len() as f64)
    };
    let (mp, mq) = (mean(theoretical), mean(actual));
    let e = [mp[0] - mq[0], mp[1] - mq[1], mp[2] - mq[2]];
    let e_norm = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    let shifted: Vec<[f64; 3]> = actual.iter().map(|q| [q[0] + e[0], q[1] + e[1], q[2] + e[2]]).collect();
    let p_index = PointIndex::new(theoretical)?;
    let q_index = PointIndex::new(&shifted)?;
    // M_P: nearest Q' of every P_i; M_Q: nearest P of every Q'_k.
    let m_p: Vec<(usize, f64)> = theoretical.par_iter().map(|p| q_index.nearest(p)).collect();
    let m_q: Vec<(usize, f64)> = shifted.par_iter().map(|q| p_index.nearest(q)).collect();
    // For each P_i, the farthest Q'_k whose nearest theoretical point is P_i.
    let mut reverse: Vec<Option<(usize, f64)>> = vec![None; theoretical.len()];
    for (k, &(l, d)) in m_q.iter().enumerate() {
        match reverse[l] {
            Some((_, best)) if best >= d => {}
            _ => reverse[l] = Some((k, d)),
        }
    }
    let n = theoretical.len();
    let (mut errors, mut deviations, mut matched, mut cases) =
        (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..n {
        let (j, dj) = m_p[i];
        let (m, d, case) = match reverse[i] {
            None => (j, dj, MatchCase::Nearest),
            Some((k, dk)) if dk > dj => (k, dk, MatchCase::ReverseFarther),
            Some(_) => (j, dj, MatchCase::NearestFarther),
        };
        debug_assert!((dist(&theoretical[i], &shifted[m]) - d).abs() < 1e-9);
        errors.push(delta1 * e_norm + delta2 * d);
        deviations.push(d);
        matched.push(m);
        cases.push(case);
    }
    let mean_e = errors.iter().sum::<f64>() / n as f64;
    let std = (errors.iter().map(|v| (v - mean_e).powi(2)).sum::<f64>() / n as f64).sqrt();
    let max = errors.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Ok(ContourError { offset: e, errors, deviations, matched, cases, mean: mean_e, std, max })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64, c: [f64; 2]) -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                [c[0] + r * t.cos(), c[1] + r * t.sin(), 0.0]
            })
            .collect()
    }

    #[test]
    fn pure_offset_gives_offset_only() {
        let p = circle(360, 20.0, [0.0, 0.0]);
        let q: Vec<[f64; 3]> = p.iter().map(|v| [v[0] + 0.05, v[1] - 0.02, v[2] + 0.1]).collect();
        let r = contour_error(&p, &q, 1.0, 1.0).unwrap();
        assert!((r.offset[0] + 0.05).abs() < 1e-12 && (r.offset[2] + 0.1).abs() < 1e-12);
        let e = (0.05f64.powi(2) + 0.02f64.powi(2) + 0.1f64.powi(2)).sqrt();
        assert!(r.errors.iter().all(|v| (v - e).abs() < 1e-9));
        assert!(r.cases.iter().all(|c| *c != MatchCase::ReverseFarther));
    }

    #[test]
    fn a_point_straying_from_a_corner_counts() {
        // Theoretical square corner sampled densely; one actual point strays 1 mm out at the
        // corner: it must appear in the error of the corner point, not be skipped over.
        let mut p = Vec::new();
        for i in 0..=100 {
            p.push([i as f64 * 0.1, 0.0, 0.0]);
            p.push([0.0, i as f64 * 0.1, 0.0]);
        }
        let mut q = p.clone();
        q.push([-0.7, -0.7, 0.0]);
        let r = contour_error(&p, &q, 0.0, 1.0).unwrap();
        let corner = p.iter().position(|v| *v == [0.0, 0.0, 0.0]).unwrap();
        assert_eq!(r.cases[corner], MatchCase::ReverseFarther);
        assert!(r.max > 0.95, "{}", r.max);
    }
}
