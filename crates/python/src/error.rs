//! The one mapping from core errors to Python exceptions (`to_py`; `.py()` on a core result).
//! A function, not `From<Error> for PyErr`: the orphan rule forbids that impl outside both crates.
//!
//! - `Shape`, `Invalid` → `ValueError` naming the argument;
//! - `Io` → the `OSError` subclass for its kind (`FileNotFoundError`, `PermissionError`,
//!   `IsADirectoryError`, ...), built as Python builds its own: `(errno, strerror, filename)`,
//!   so `.errno` and `.filename` are set;
//! - `Format` → `machscan.io.FileFormatError`, a `ValueError` subclass naming the file;
//! - `Interrupted` → `KeyboardInterrupt` (a long kernel stopped by Ctrl-C).
use machscan_core::Error;
use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIsADirectoryError, PyKeyboardInterrupt, PyNotADirectoryError, PyOSError,
    PyPermissionError, PyValueError,
};
use pyo3::prelude::*;
use std::io::ErrorKind;

pyo3::create_exception!(
    machscan.io,
    FileFormatError,
    PyValueError,
    "A file's content does not follow its format (truncated data, a header that promises more than \
there is, a number that is not one, ...). A ``ValueError``; ``filename`` names the file."
);

/// A core result as a Python one: `kernel(...).py()?`.
pub trait IntoPy<T> {
    fn py(self) -> PyResult<T>;
}

impl<T> IntoPy<T> for machscan_core::Result<T> {
    fn py(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}

/// The Python exception for a core error.
pub fn to_py(e: Error) -> PyErr {
    {
        match e {
            Error::Shape { .. } | Error::Invalid { .. } => PyValueError::new_err(e.to_string()),
            Error::Interrupted => PyKeyboardInterrupt::new_err("interrupted"),
            Error::Io { ref path, kind, errno, ref message, .. } => {
                let args = (errno.unwrap_or(0), message.clone(), path.clone());
                match kind {
                    ErrorKind::NotFound => PyFileNotFoundError::new_err(args),
                    ErrorKind::PermissionDenied => PyPermissionError::new_err(args),
                    ErrorKind::IsADirectory => PyIsADirectoryError::new_err(args),
                    ErrorKind::NotADirectory => PyNotADirectoryError::new_err(args),
                    ErrorKind::AlreadyExists => PyFileExistsError::new_err(args),
                    _ => PyOSError::new_err(args),
                }
            }
            Error::Format { ref path, .. } => {
                let path = path.clone();
                let err = FileFormatError::new_err(e.to_string());
                Python::attach(|py| {
                    // A missing attribute only loses the convenience, not the message.
                    let _ = err.value(py).setattr("filename", path);
                });
                err
            }
        }
    }
}
