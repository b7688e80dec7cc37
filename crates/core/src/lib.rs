//! machscan: on-machine measurement kernels for five-axis machining.
//!
//! The kernels, free of pyo3 and numpy: the compiler keeps them so (the extension is the crate
//! `machscan` in `crates/python`). Every failure is an `Error` naming the argument or file at fault.

// `!(a <= b)` is how the core rejects NaN together with out-of-range values: a NaN fails
// every comparison, so the negated form is true for it. `partial_cmp` would hide that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
pub mod cloud;
pub mod contour;
pub mod error;
pub mod geom;
pub mod groove;
pub mod interrupt;
pub mod io;
pub mod kinematics;
pub mod matching;
pub mod mesh;
pub mod optim;
pub mod registration;
pub mod spatial;
pub mod toolpath;

pub use error::{Error, Result};

#[cfg(test)]
mod testing;
#[cfg(test)]
mod thread_independence;
