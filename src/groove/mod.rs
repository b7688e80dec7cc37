//! Groove cross-section extraction (SPEC G, paper 000 §2.1): per profiler frame, level the
//! surface around the groove and fit the tanh template by Levenberg–Marquardt.
mod fit;
mod template;

pub use fit::{
    fit_frame, fit_frames, level_frame, GrooveFit, GrooveOptions, GrooveStatus, LevelledFrame, TemplateKind,
};
pub use template::{TanhTemplate, VTemplate};
