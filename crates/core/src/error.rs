//! The one error type of the core. Every variant carries the name of the argument (or file)
//! at fault, so the Python layer can raise a message a plant engineer understands. The mapping
//! to Python exceptions is in one place: the extension crate's `error.rs`.
use std::path::Path;
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// An array argument has the wrong shape.
    #[error("{name}: expected {expected}, got {actual}")]
    Shape { name: String, expected: String, actual: String },
    /// An argument has an unusable value (NaN, out of range, inconsistent with another).
    #[error("{name}: {reason}")]
    Invalid { name: String, reason: String },
    /// The operating system refused to open, read or write a file (it is missing, not
    /// permitted, a directory, the disk is full, ...).
    #[error("{path}: cannot {action}: {message}")]
    Io {
        path: String,
        /// "read" or "write".
        action: &'static str,
        kind: std::io::ErrorKind,
        /// The OS error number, when the OS gave one.
        errno: Option<i32>,
        /// The OS's own text, without Rust's "(os error N)" suffix.
        message: String,
    },
    /// A file was read, but its content does not follow its format (truncated, a header that
    /// promises more than there is, a number that is not one, ...).
    #[error("{path}: {reason}")]
    Format { path: String, reason: String },
    /// The user asked a long kernel to stop (`interrupt::request`).
    #[error("interrupted")]
    Interrupted,
}

impl Error {
    pub fn shape(name: &str, expected: impl Into<String>, actual: impl Into<String>) -> Self {
        Error::Shape { name: name.to_string(), expected: expected.into(), actual: actual.into() }
    }

    pub fn invalid(name: &str, reason: impl Into<String>) -> Self {
        Error::Invalid { name: name.to_string(), reason: reason.into() }
    }

    /// The same error naming the argument `to` where it named `from`: for a caller whose
    /// argument has another name than the kernel's.
    pub fn renamed(self, from: &str, to: &str) -> Self {
        match self {
            Error::Shape { name, expected, actual } if name == from => {
                Error::Shape { name: to.into(), expected, actual }
            }
            Error::Invalid { name, reason } if name == from => Error::Invalid { name: to.into(), reason },
            other => other,
        }
    }

    /// The OS refused `action` ("read" or "write") on `path`.
    pub fn io(path: &Path, action: &'static str, e: &std::io::Error) -> Self {
        let text = e.to_string();
        let message = match e.raw_os_error() {
            Some(code) => text.trim_end_matches(&format!(" (os error {code})")).to_string(),
            None => text,
        };
        Error::Io { path: path.display().to_string(), action, kind: e.kind(), errno: e.raw_os_error(), message }
    }

    /// The content of `path` does not follow its format.
    pub fn format(path: &Path, reason: impl Into<String>) -> Self {
        Error::Format { path: path.display().to_string(), reason: reason.into() }
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

/// The largest coordinate a point may have: a square of it (distances, cross products) stays
/// finite, 1e150² = 1e300 < f64::MAX. Beyond it the kernels' arithmetic would overflow into
/// inf and NaN; in millimetres it is far beyond any part.
pub const MAX_COORDINATE: f64 = 1e150;

/// `check_finite` for points, which also fails where a coordinate is beyond ±`MAX_COORDINATE`.
pub fn check_finite_points(name: &str, points: &[[f64; 3]]) -> Result<()> {
    let values = points.as_flattened();
    check_finite(name, values, 3)?;
    match values.iter().position(|v| v.abs() > MAX_COORDINATE) {
        Some(pos) => Err(Error::invalid(
            name,
            format!(
                "coordinates beyond ±1e150 cannot be measured (their squares overflow), found {:e} at row {}, column {}",
                values[pos],
                pos / 3,
                pos % 3
            ),
        )),
        None => Ok(()),
    }
}

/// Fails unless `value` is a finite number > 0 (a length, a tolerance, ...). `unit` is put in
/// the message, e.g. "mm".
pub fn check_positive(name: &str, value: f64, unit: &str) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        return Ok(());
    }
    let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
    Err(Error::invalid(name, format!("must be a positive finite number{unit}, got {value}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn io_errors_keep_the_kind_and_drop_rusts_suffix() {
        let e = std::fs::read("/nonexistent/machscan/file.ply").unwrap_err();
        let err = Error::io(Path::new("/nonexistent/machscan/file.ply"), "read", &e);
        match &err {
            Error::Io { kind, errno, message, .. } => {
                assert_eq!(*kind, std::io::ErrorKind::NotFound);
                assert!(errno.is_some());
                assert!(!message.contains("os error"), "{message}");
            }
            other => panic!("{other:?}"),
        }
        assert!(err.to_string().starts_with("/nonexistent/machscan/file.ply: cannot read: "));
    }

    #[test]
    fn finite_and_positive_checks_name_the_argument() {
        assert!(check_finite("p", &[1.0, 2.0, 3.0], 3).is_ok());
        let e = check_finite("p", &[1.0, 2.0, 3.0, 4.0, f64::NAN, 6.0], 3).unwrap_err();
        assert_eq!(e.to_string(), "p: must be finite, found NaN at row 1, column 1");
        assert!(check_positive("voxel_size", 0.5, "mm").is_ok());
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(check_positive("voxel_size", bad, "mm").unwrap_err().to_string().starts_with("voxel_size: "));
        }
    }
}
