//! The Python face of the core: the only module that uses pyo3 and numpy. One file per core
//! module; `convert` holds the array conversion, shape checks, error mapping and the helper
//! that releases the GIL.
mod cloud;
mod contour;
mod convert;
mod groove;
mod io;
mod kinematics;
mod spatial;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    kinematics::register(m)?;
    io::register(m)?;
    groove::register(m)?;
    spatial::register(m)?;
    contour::register(m)?;
    cloud::register(m)?;
    Ok(())
}
