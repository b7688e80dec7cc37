//! Groove cross-section extraction (SPEC G, paper 000 §2.1): per profiler frame, the groove's
//! width, depth and center. The default measures the groove's geometry with section models
//! (`measure`, `section`); the paper's tanh template stays available (`fit`, `template`).
//! The formulas: docs/grooves.md.
mod fit;
mod measure;
mod section;
mod template;

pub use fit::{
    fit_frame, fit_frames, level_frame, view_frame, FitCriteria, FitModel, FrameView, GrooveFit, GrooveOptions,
    GrooveStatus, LevelledFrame, TemplateKind, TANH_CRITERIA,
};
pub use measure::SECTION_CRITERIA;
pub use section::{Beams, Pieces, SectionModel};
pub use template::TanhTemplate;
