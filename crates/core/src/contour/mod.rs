//! Contours (SPEC C, paper 000 §2.2): polyline discretisation, matching actual to theoretical
//! contours, and the contour error with the bidirectional nearest-point correction.
//! The formulas: docs/contours.md.
mod bending;
mod error;
mod matching;
mod polyline;

pub use bending::BendingSurface;
pub use error::{contour_error, ContourError, MatchCase};
pub use matching::{assign_one_to_one, centroid, match_contours, nearest_centroid};
pub use polyline::resample_polyline;
