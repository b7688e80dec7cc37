//! Where the blank sits, from where a plant starts (SPEC R3, R2, R8; paper 004 §1): the chain of
//! coarse alignment, ICP and the balanced envelope fit. The envelope fit is local: it finds the
//! nearest optimum of the allowance's evenness, and from a blank clamped millimetres and degrees
//! off it stalls where the allowance changes faster than its linear model (points running off
//! the blank's ends). So the blank is first brought near by its points alone:
//!
//! 1. start: the pose given (identity: the blank as measured, in the model's frame);
//! 2. coarse: the principal frames put on top of each other (`coarse_align`);
//! 3. ICP (point to point, blank → model) from both the start and the coarse pose, the
//!    correspondence distance shrinking from 5 % of the model's size by thirds (three passes):
//!    the one that pairs more blank points, then the closer, is kept — the coarse pose is no
//!    better than the start when the blank's extent differs from the model's;
//! 4. the envelope fit from there.
//!
//! Each stage's pose and the allowance there are reported.
use super::allowance::{allowance, BlankOptions};
use super::envelope::{envelope_fit, EnvelopeFit};
use super::{coarse_align, icp, IcpOptions};
use crate::error::{check_finite_points, Error, Result};
use crate::geom::transform_point;
use nalgebra::Matrix4;

/// The first ICP correspondence distance as a share of the model's bounding-box diagonal: a
/// blank 5 mm / 5° off on a 150 mm blade (190 mm diagonal) is within it.
const FIRST_REACH: f64 = 0.05;
/// ICP passes, each with a third of the last distance.
const PASSES: usize = 3;
/// Iterations per ICP pass.
const ICP_ITERATIONS: usize = 60;

/// One stage of the chain: the blank's pose (blank → model frame) after it, how the blank's
/// points sit on the model there (ICP's figures at that pose: the share of blank points with a
/// model point within the last correspondence distance, and their RMS distance, mm), and the
/// allowance of every model point at that pose (NaN where the blank does not cover it).
#[derive(Debug, Clone)]
pub struct AlignmentStage {
    pub name: &'static str,
    pub transformation: Matrix4<f64>,
    pub fitness: f64,
    pub rmse: f64,
    pub allowance: Vec<f64>,
}

/// The chain's result: its stages and the envelope fit that ends it.
#[derive(Debug, Clone)]
pub struct BlankAlignment {
    pub stages: Vec<AlignmentStage>,
    pub fit: EnvelopeFit,
}

/// The blank pose (blank → model frame) of the balanced envelope fit, found from `init` through
/// coarse alignment and ICP (module docs).
pub fn align_blank(
    model: &[[f64; 3]],
    normals: &[[f64; 3]],
    blank: &[[f64; 3]],
    min_allowance: f64,
    options: &BlankOptions,
    init: &Matrix4<f64>,
) -> Result<BlankAlignment> {
    check_finite_points("model_points", model)?;
    check_finite_points("blank_points", blank)?;
    if model.len() < 4 || blank.len() < 4 {
        return Err(Error::invalid(
            if model.len() < 4 { "model_points" } else { "blank_points" },
            "needs at least 4 points to be aligned",
        ));
    }
    let (lo, hi) = model.iter().fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(lo, hi), p| {
        (std::array::from_fn(|k| lo[k].min(p[k])), std::array::from_fn(|k| hi[k].max(p[k])))
    });
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    if !(diagonal > 0.0) {
        return Err(Error::invalid("model_points", "all points coincide"));
    }
    // How the blank's points sit on the model at a pose: ICP's figures without a step.
    let last_reach = FIRST_REACH * diagonal / 3f64.powi(PASSES as i32 - 1);
    let stage = |name: &'static str, pose: &Matrix4<f64>| -> Result<AlignmentStage> {
        let o = IcpOptions { max_iterations: 0, ..IcpOptions::new(last_reach) };
        let r = icp(blank, model, None, pose, &o)?;
        let moved: Vec<[f64; 3]> = blank.iter().map(|&p| transform_point(pose, p)).collect();
        let allowance = allowance(model, normals, &moved, options)?;
        Ok(AlignmentStage { name, transformation: *pose, fitness: r.fitness, rmse: r.rmse, allowance })
    };
    let mut stages = vec![stage("start", init)?];
    let coarse = coarse_align(blank, model)?;
    stages.push(stage("coarse", &coarse)?);
    let mut best: Option<(&'static str, super::IcpResult)> = None;
    for (name, start) in [("icp from the start", *init), ("icp from the coarse pose", coarse)] {
        let mut pose = start;
        let mut reach = FIRST_REACH * diagonal;
        let mut last = None;
        for _ in 0..PASSES {
            let o = IcpOptions { max_iterations: ICP_ITERATIONS, ..IcpOptions::new(reach) };
            let r = icp(blank, model, None, &pose, &o)?;
            pose = r.transformation;
            last = Some(r);
            reach /= 3.0;
        }
        let Some(r) = last else { continue };
        let better = match &best {
            None => true,
            Some((_, b)) => r.fitness > b.fitness + 1e-9 || (r.fitness >= b.fitness - 1e-9 && r.rmse < b.rmse),
        };
        if better {
            best = Some((name, r));
        }
    }
    let (name, icp_result) = best.ok_or_else(|| Error::invalid("blank_points", "ICP ran no pass"))?;
    stages.push(stage(name, &icp_result.transformation)?);
    let fit = envelope_fit(model, normals, blank, min_allowance, options, &icp_result.transformation)?;
    let mut last = stage("envelope", &fit.transformation)?;
    last.allowance = fit.allowance.clone();
    stages.push(last);
    Ok(BlankAlignment { stages, fit })
}
