//! machscan._core, the Python face of `machscan-core`: the only crate that uses pyo3 and numpy.
//! One file per core module; `convert` holds the seam every binding goes through (extract, enter
//! the core with the GIL released, return arrays) and `error` the one mapping of core errors to
//! exceptions. Compositions (a kernel estimating what it needs first) live in the core, not here.
mod cloud;
mod contour;
mod convert;
mod error;
mod groove;
mod io;
mod kinematics;
mod matching;
mod mesh;
mod registration;
mod spatial;
mod toolpath;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(convert::set_thread_limit, m)?)?;
    kinematics::register(m)?;
    io::register(m)?;
    groove::register(m)?;
    spatial::register(m)?;
    contour::register(m)?;
    cloud::register(m)?;
    registration::register(m)?;
    mesh::register(m)?;
    matching::register(m)?;
    toolpath::register(m)?;
    Ok(())
}
