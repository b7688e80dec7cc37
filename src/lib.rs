//! machscan: on-machine measurement kernels for five-axis machining.
//!
//! The core modules are free of pyo3; `python` is the only place that talks to Python.
pub mod cloud;
pub mod contour;
pub mod error;
pub mod geom;
pub mod groove;
pub mod io;
pub mod kinematics;
pub mod optim;
pub mod python;
pub mod spatial;

pub use error::{Error, Result};
