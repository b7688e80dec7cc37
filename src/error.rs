//! The one error type of the core. Every variant carries the name of the argument (or file)
//! at fault, so the Python layer can raise a message a plant engineer understands.
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// An array argument has the wrong shape.
    #[error("{name}: expected {expected}, got {actual}")]
    Shape { name: String, expected: String, actual: String },
    /// An argument has an unusable value (NaN, out of range, inconsistent with another).
    #[error("{name}: {reason}")]
    Invalid { name: String, reason: String },
    /// A file could not be read or written, or its content is not what it claims.
    #[error("{path}: {reason}")]
    File { path: String, reason: String },
}

impl Error {
    pub fn shape(name: &str, expected: impl Into<String>, actual: impl Into<String>) -> Self {
        Error::Shape { name: name.to_string(), expected: expected.into(), actual: actual.into() }
    }

    pub fn invalid(name: &str, reason: impl Into<String>) -> Self {
        Error::Invalid { name: name.to_string(), reason: reason.into() }
    }
}

impl Error {
    pub fn file(path: &std::path::Path, reason: impl Into<String>) -> Self {
        Error::File { path: path.display().to_string(), reason: reason.into() }
    }
}

pub type Result<T> = std::result::Result<T, Error>;

/// Fails with `Error::Invalid` naming `name` and the first row holding a non-finite value.
/// `values` is row-major with `width` columns.
pub fn check_finite(name: &str, values: &[f64], width: usize) -> Result<()> {
    if let Some(pos) = values.iter().position(|v| !v.is_finite()) {
        let (row, col) = match pos.checked_div(width) {
            Some(row) => (row, pos % width),
            None => (pos, 0),
        };
        return Err(Error::invalid(
            name,
            format!("must be finite, found {} at row {}, column {}", values[pos], row, col),
        ));
    }
    Ok(())
}
