//! Plain text point files: XYZ / CSV / PTS, one point per line, chosen columns; and the mesh
//! text format of the geodesic test meshes.
use super::{CloudFile, Dtype, TextColumns};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::path::Path;

/// Points from columns `columns` (x, y, z; 0-based) of a text file. `delimiter` None splits on
/// whitespace and commas. Leading lines that are not numbers (headers) are skipped, and so are
/// blank lines and lines starting with `#` or `//`.
pub fn read_xyz(path: &Path, bytes: &[u8], text_columns: TextColumns) -> Result<Vec<f64>> {
    let TextColumns { delimiter, columns } = text_columns;
    let text = std::str::from_utf8(bytes).map_err(|_| Error::format(path, "not a text file"))?;
    let split = |l: &str| -> Vec<String> {
        match delimiter {
            Some(d) => l.split(d).map(|t| t.trim().to_string()).collect(),
            None => {
                l.split(|c: char| c.is_whitespace() || c == ',').filter(|t| !t.is_empty()).map(String::from).collect()
            }
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
                p[j] =
                    cells[c].parse::<f64>().map_err(|_| format!("line {}: {:?} is not a number", k + 1, cells[c]))?;
            }
            Ok(p)
        })
        .collect();
    let mut out = Vec::with_capacity(3 * rows.len());
    for r in rows {
        out.extend_from_slice(&r.map_err(|e| Error::format(path, e))?);
    }
    Ok(out)
}

/// Writes one point per line, `x<sep>y<sep>z`, the shortest text that reads back to the value
/// in `dtype`.
pub(super) fn write_xyz(path: &Path, points: &[f64], delimiter: char, dtype: Dtype) -> Result<()> {
    use std::io::Write;
    let io = |e: std::io::Error| Error::io(path, "write", &e);
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(path).map_err(io)?);
    for p in points.chunks_exact(3) {
        writeln!(w, "{}{delimiter}{}{delimiter}{}", dtype.text(p[0]), dtype.text(p[1]), dtype.text(p[2]))
            .map_err(io)?;
    }
    w.flush().map_err(io)
}

/// The plain mesh text format of the geodesic test meshes (pygeodesic / Kirsanov): a line
/// `n_vertices n_faces`, then n_vertices lines `x y z` and n_faces lines of three 0-based
/// vertex indices. `None` when the text does not have that shape (it is then a point file).
pub fn parse_mesh_txt(path: &Path, bytes: &[u8]) -> Result<Option<CloudFile>> {
    let Ok(text) = std::str::from_utf8(bytes) else { return Ok(None) };
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let Some(first) = lines.next() else { return Ok(None) };
    let head: Vec<&str> = first.split_whitespace().collect();
    let (Ok(nv), Ok(nf)) = (head.first().unwrap_or(&"").parse::<usize>(), head.get(1).unwrap_or(&"").parse::<usize>())
    else {
        return Ok(None);
    };
    if head.len() != 2 {
        return Ok(None);
    }
    let rest: Vec<&str> = lines.collect();
    if nv.checked_add(nf) != Some(rest.len()) {
        return Err(Error::format(
            path,
            format!("the mesh header announces {nv} vertices and {nf} faces, but {} lines follow", rest.len()),
        ));
    }
    let mut points = Vec::with_capacity(3 * nv);
    for (k, l) in rest[..nv].iter().enumerate() {
        let v: Vec<f64> = l
            .split_whitespace()
            .map(|t| t.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| Error::format(path, format!("vertex {k}: {l:?} is not three numbers")))?;
        if v.len() != 3 {
            return Err(Error::format(path, format!("vertex {k}: {l:?} is not three numbers")));
        }
        points.extend_from_slice(&v);
    }
    let mut faces = Vec::with_capacity(nf);
    for (k, l) in rest[nv..].iter().enumerate() {
        let v: Vec<u32> = l
            .split_whitespace()
            .map(|t| t.parse::<u32>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| Error::format(path, format!("face {k}: {l:?} is not three vertex indices")))?;
        if v.len() != 3 || v.iter().any(|&i| i as usize >= nv) {
            return Err(Error::format(path, format!("face {k}: {l:?} is not three vertex indices below {nv}")));
        }
        faces.push([v[0], v[1], v[2]]);
    }
    Ok(Some(CloudFile { points, triangles: faces, ..CloudFile::default() }))
}
