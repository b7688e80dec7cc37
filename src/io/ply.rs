//! PLY writer: ASCII or binary little-endian, `double` coordinates (no precision loss at
//! machine coordinates of several metres), optional normals and named scalar properties.
use crate::error::{Error, Result};
use std::io::{BufWriter, Write};
use std::path::Path;

/// A named per-point scalar property (e.g. frame index, allowance, curvature).
pub struct PlyScalar<'a> {
    pub name: &'a str,
    pub values: &'a [f64],
}

/// `points` and `normals` row-major `(N, 3)`; every scalar has N values.
pub fn write_ply(path: &Path, points: &[f64], normals: Option<&[f64]>, scalars: &[PlyScalar<'_>], binary: bool) -> Result<()> {
    let n = points.len() / 3;
    if let Some(nr) = normals {
        if nr.len() != points.len() {
            return Err(Error::shape("normals", format!("({n}, 3): one normal per point"), format!("({}, 3)", nr.len() / 3)));
        }
    }
    for s in scalars {
        if s.values.len() != n {
            return Err(Error::shape(s.name, format!("({n},): one value per point"), format!("({},)", s.values.len())));
        }
        if s.name.is_empty() || s.name.contains(char::is_whitespace) {
            return Err(Error::invalid("scalars", format!("property name {:?} must be one word", s.name)));
        }
    }
    let io = |e: std::io::Error| Error::file(path, format!("cannot write: {e}"));
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    let mut header = format!(
        "ply\nformat {} 1.0\ncomment written by machscan {}\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\n",
        if binary { "binary_little_endian" } else { "ascii" },
        env!("CARGO_PKG_VERSION")
    );
    if normals.is_some() {
        header.push_str("property double nx\nproperty double ny\nproperty double nz\n");
    }
    for s in scalars {
        header.push_str(&format!("property double {}\n", s.name));
    }
    header.push_str("end_header\n");
    w.write_all(header.as_bytes()).map_err(io)?;
    let mut row = Vec::with_capacity(6 + scalars.len());
    for i in 0..n {
        row.clear();
        row.extend_from_slice(&points[3 * i..3 * i + 3]);
        if let Some(nr) = normals {
            row.extend_from_slice(&nr[3 * i..3 * i + 3]);
        }
        row.extend(scalars.iter().map(|s| s.values[i]));
        if binary {
            for v in &row {
                w.write_all(&v.to_le_bytes()).map_err(io)?;
            }
        } else {
            // `{}` of an f64 prints the shortest text that reads back to the same value.
            let line: Vec<String> = row.iter().map(|v| format!("{v}")).collect();
            writeln!(w, "{}", line.join(" ")).map_err(io)?;
        }
    }
    w.flush().map_err(io)?;
    Ok(())
}
