//! Groove cross-section extraction (SPEC G, paper 000 §2.1): per profiler frame, the groove's
//! width, depth and center. The default measures the groove's geometry with section models
//! (`measure`, `section`); the paper's tanh template stays available (`fit`, `template`).
//! The formulas: docs/grooves.md.
mod bowl;
mod fit;
mod measure;
mod misfit;
mod options;
mod robust;
mod rounding;
mod section;
mod tanh;
mod template;

pub use bowl::{fit_bowl, Bowl, BowlBeams, BowlFit, BowlHit, BOWL_PARAMS};
pub use fit::{fit_frame, fit_frame_grooves, fit_frames, view_frame, FrameView, GrooveRows};
pub use measure::SECTION_CRITERIA;
pub use misfit::{BottomResidual, MisfitPrior, StretchDifference, StretchMisfit, STRETCH_MEASURES};
pub use options::{
    FitCriteria, FitModel, GrooveFit, GrooveLimits, GrooveOptions, GrooveSelect, GrooveStatus, MisfitRule,
    RoundingRule, TemplateKind, TANH_CRITERIA,
};
pub use rounding::{pooled_stride, RoundingCurve, RoundingPosterior, RoundingPrior, MIN_POOLED, POOLED_FRAMES};
pub use section::{Beams, Pieces, SectionModel};
pub use tanh::{level_frame, LevelledFrame};
pub use template::TanhTemplate;
