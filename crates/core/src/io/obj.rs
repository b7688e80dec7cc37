//! Wavefront OBJ files: `v` vertices, `vn` normals and `f` faces (any of `v`, `v/vt`, `v//vn`,
//! `v/vt/vn`; negative indices count back from the last vertex); polygons are fanned into
//! triangles. Texture coordinates, groups and materials are skipped. Normals are returned per
//! vertex when the file has one `vn` per `v`, the layout Open3D, trimesh and machscan write.
use super::{CloudFile, CloudRef, Dtype};
use crate::error::{Error, Result};
use std::io::{BufWriter, Write};
use std::path::Path;

/// An OBJ file's bytes (`path` names them in messages).
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<CloudFile> {
    let text = std::str::from_utf8(bytes).map_err(|_| Error::format(path, "not a text file"))?;
    let mut points: Vec<f64> = Vec::new();
    let mut normals: Vec<f64> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut poly: Vec<u32> = Vec::new();
    let numbers = |k: usize, words: std::str::SplitWhitespace<'_>, what: &str| -> Result<[f64; 3]> {
        let v: Vec<f64> = words
            .take(3)
            .map(|t| t.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| Error::format(path, format!("line {}: {what} needs three numbers", k + 1)))?;
        match v.as_slice() {
            [x, y, z] => Ok([*x, *y, *z]),
            _ => Err(Error::format(path, format!("line {}: {what} needs three numbers, got {}", k + 1, v.len()))),
        }
    };
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => points.extend_from_slice(&numbers(k, words, "a vertex (v)")?),
            Some("vn") => normals.extend_from_slice(&numbers(k, words, "a normal (vn)")?),
            Some("f") => {
                poly.clear();
                let n = (points.len() / 3) as i64;
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let i: i64 = first
                        .parse()
                        .map_err(|_| Error::format(path, format!("line {}: {w:?} is not a vertex reference", k + 1)))?;
                    // 1-based; negative counts back from the last vertex defined so far.
                    let idx = if i < 0 { n + i } else { i - 1 };
                    if !(0..n).contains(&idx) {
                        return Err(Error::format(
                            path,
                            format!("line {}: the face refers to vertex {i}, but {n} vertices are defined", k + 1),
                        ));
                    }
                    poly.push(idx as u32);
                }
                if poly.len() < 3 {
                    return Err(Error::format(path, format!("line {}: a face needs at least 3 vertices", k + 1)));
                }
                for j in 1..poly.len() - 1 {
                    triangles.push([poly[0], poly[j], poly[j + 1]]);
                }
            }
            _ => {}
        }
    }
    let normals = (!normals.is_empty() && normals.len() == points.len()).then_some(normals);
    Ok(CloudFile { points, normals, scalars: Vec::new(), triangles, dropped: 0 })
}

/// Writes `data` (checked by `write_file`): `v` lines, `vn` lines when there are normals, and
/// `f` lines (1-based, `v//vn` with normals).
pub(super) fn write_obj(path: &Path, data: &CloudRef<'_>, dtype: Dtype) -> Result<()> {
    let io = |e: std::io::Error| Error::io(path, "write", &e);
    let mut w = BufWriter::with_capacity(1 << 20, std::fs::File::create(path).map_err(io)?);
    writeln!(w, "# written by machscan {}", env!("CARGO_PKG_VERSION")).map_err(io)?;
    for p in data.points.chunks_exact(3) {
        writeln!(w, "v {} {} {}", dtype.text(p[0]), dtype.text(p[1]), dtype.text(p[2])).map_err(io)?;
    }
    if let Some(nr) = data.normals {
        for n in nr.chunks_exact(3) {
            writeln!(w, "vn {} {} {}", dtype.text(n[0]), dtype.text(n[1]), dtype.text(n[2])).map_err(io)?;
        }
    }
    for t in data.triangles.unwrap_or(&[]) {
        let [a, b, c] = t.map(|v| v as u64 + 1);
        if data.normals.is_some() {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}").map_err(io)?;
        } else {
            writeln!(w, "f {a} {b} {c}").map_err(io)?;
        }
    }
    w.flush().map_err(io)
}
