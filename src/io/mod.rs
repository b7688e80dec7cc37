//! Point cloud and scan files. So far: the PLY writer (SPEC F formats; readers follow).
mod ply;

pub use ply::{write_ply, PlyScalar};
