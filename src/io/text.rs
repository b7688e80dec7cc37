//! Plain text point files: XYZ / CSV / PTS, one point per line, chosen columns.
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::path::Path;

/// Points from columns `columns` (x, y, z; 0-based) of a text file. `delimiter` None splits on
/// whitespace and commas. Leading lines that are not numbers (headers) are skipped, and so are
/// blank lines and lines starting with `#` or `//`.
pub fn read_xyz(path: &Path, delimiter: Option<char>, columns: [usize; 3]) -> Result<Vec<f64>> {
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    let text = std::str::from_utf8(&bytes).map_err(|_| Error::file(path, "not a text file"))?;
    let split = |l: &str| -> Vec<String> {
        match delimiter {
            Some(d) => l.split(d).map(|t| t.trim().to_string()).collect(),
            None => l.split(|c: char| c.is_whitespace() || c == ',').filter(|t| !t.is_empty()).map(String::from).collect(),
        }
    };
    let need = columns.iter().max().copied().unwrap_or(0) + 1;
    let mut lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            let t = l.trim();
            !t.is_empty() && !t.starts_with('#') && !t.starts_with("//")
        })
        .collect();
    // Header lines: leading lines whose first cell is not a number.
    let skip = lines.iter().take_while(|(_, l)| split(l).first().is_none_or(|c| c.parse::<f64>().is_err())).count();
    lines.drain(..skip);
    let rows: Vec<std::result::Result<[f64; 3], String>> = lines
        .par_iter()
        .map(|(k, l)| {
            let cells = split(l);
            if cells.len() < need {
                return Err(format!("line {}: {} columns, column {} was asked for", k + 1, cells.len(), need - 1));
            }
            let mut p = [0.0; 3];
            for (j, &c) in columns.iter().enumerate() {
                p[j] = cells[c].parse::<f64>().map_err(|_| format!("line {}: {:?} is not a number", k + 1, cells[c]))?;
            }
            Ok(p)
        })
        .collect();
    let mut out = Vec::with_capacity(3 * rows.len());
    for r in rows {
        out.extend_from_slice(&r.map_err(|e| Error::file(path, e))?);
    }
    Ok(out)
}

/// Writes one point per line, `x<sep>y<sep>z`, shortest round-trip text.
pub fn write_xyz(path: &Path, points: &[f64], delimiter: char) -> Result<()> {
    use std::io::Write;
    let io = |e: std::io::Error| Error::file(path, format!("cannot write: {e}"));
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(path).map_err(io)?);
    for p in points.chunks_exact(3) {
        writeln!(w, "{}{delimiter}{}{delimiter}{}", p[0], p[1], p[2]).map_err(io)?;
    }
    w.flush().map_err(io)
}
