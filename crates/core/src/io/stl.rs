//! STL files (stereolithography), binary and ASCII: a soup of triangles, each with its own three
//! corners. Reading merges corners with identical coordinates into shared vertices (in order of
//! first appearance), so the mesh is indexed like every other machscan mesh; writing computes
//! each facet's normal from its corners (right-hand rule), as STL readers expect.
use super::{CloudFile, CloudRef};
use crate::error::{Error, Result};
use std::collections::HashMap;
use std::io::{BufWriter, Write};
use std::path::Path;

const HEADER: usize = 80;
const RECORD: usize = 50;

/// Corners → shared vertices, merged when their coordinates are equal (−0 equals +0).
#[derive(Default)]
struct Welder {
    index: HashMap<[u64; 3], u32>,
    points: Vec<f64>,
}

impl Welder {
    fn vertex(&mut self, p: [f64; 3]) -> u32 {
        // `+ 0.0` turns −0.0 into +0.0, so the two zeros share a key.
        let key = p.map(|v| (v + 0.0).to_bits());
        let next = self.index.len() as u32;
        *self.index.entry(key).or_insert_with(|| {
            self.points.extend_from_slice(&p);
            next
        })
    }
}

/// An STL file's bytes (`path` names them in messages), binary or ASCII.
pub fn parse_stl(path: &Path, bytes: &[u8]) -> Result<CloudFile> {
    if bytes.len() >= HEADER + 4 {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        // A binary file is exactly its header, count and records; some binary files begin
        // their header with "solid" too, so the size decides.
        if count.checked_mul(RECORD).and_then(|b| b.checked_add(HEADER + 4)) == Some(bytes.len()) {
            return Ok(parse_binary(&bytes[HEADER + 4..], count));
        }
    }
    let text = std::str::from_utf8(bytes).ok().filter(|t| t.trim_start().starts_with("solid"));
    match text {
        Some(t) => parse_ascii(path, t),
        None if bytes.len() >= HEADER + 4 => {
            let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
            Err(Error::format(
                path,
                format!(
                    "not an ASCII STL (no leading \"solid\"), and as a binary STL the header announces {count} triangles ({} bytes) but the file has {} bytes",
                    (HEADER + 4) as u128 + RECORD as u128 * count as u128,
                    bytes.len()
                ),
            ))
        }
        None => Err(Error::format(path, "too short for a binary STL and not an ASCII one")),
    }
}

fn parse_binary(records: &[u8], count: usize) -> CloudFile {
    let mut welder = Welder::default();
    let mut triangles = Vec::with_capacity(count);
    for r in records.chunks_exact(RECORD) {
        let f = |k: usize| f32::from_le_bytes([r[4 * k], r[4 * k + 1], r[4 * k + 2], r[4 * k + 3]]) as f64;
        // Floats 0..3 are the facet normal; 3..12 the corners; then a 2-byte attribute.
        let mut t = [0u32; 3];
        for (c, v) in t.iter_mut().enumerate() {
            let k = 3 + 3 * c;
            *v = welder.vertex([f(k), f(k + 1), f(k + 2)]);
        }
        triangles.push(t);
    }
    CloudFile { points: welder.points, triangles, ..CloudFile::default() }
}

fn parse_ascii(path: &Path, text: &str) -> Result<CloudFile> {
    let mut welder = Welder::default();
    let mut triangles = Vec::new();
    let mut corners: Vec<u32> = Vec::with_capacity(3);
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("vertex") => {
                let v: Vec<f64> =
                    words.map(|t| t.parse::<f64>()).collect::<std::result::Result<_, _>>().map_err(|_| {
                        Error::format(path, format!("line {}: {:?} is not a vertex x y z", k + 1, line.trim()))
                    })?;
                if v.len() != 3 {
                    return Err(Error::format(
                        path,
                        format!("line {}: a vertex needs x y z, got {:?}", k + 1, line.trim()),
                    ));
                }
                corners.push(welder.vertex([v[0], v[1], v[2]]));
            }
            Some("endloop") => {
                if corners.len() != 3 {
                    return Err(Error::format(
                        path,
                        format!("line {}: a facet has {} vertices, STL facets have 3", k + 1, corners.len()),
                    ));
                }
                triangles.push([corners[0], corners[1], corners[2]]);
                corners.clear();
            }
            _ => {}
        }
    }
    if !corners.is_empty() {
        return Err(Error::format(path, "truncated: the last facet has no endloop"));
    }
    Ok(CloudFile { points: welder.points, triangles, ..CloudFile::default() })
}

fn facet_normal(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    // A degenerate facet gets the zero normal, which readers take as "compute it yourself".
    if len > 0.0 && len.is_finite() {
        n.map(|x| x / len)
    } else {
        [0.0; 3]
    }
}

/// Writes the triangles of `data` (checked by `write_file`) as float32.
pub(super) fn write_stl(path: &Path, data: &CloudRef<'_>, binary: bool) -> Result<()> {
    let triangles = data.triangles.unwrap_or(&[]);
    let Ok(count) = u32::try_from(triangles.len()) else {
        return Err(Error::invalid(
            "triangles",
            format!("{} triangles exceed the 2^32 − 1 STL holds", triangles.len()),
        ));
    };
    let p = |i: u32| -> [f64; 3] {
        let i = i as usize;
        [data.points[3 * i], data.points[3 * i + 1], data.points[3 * i + 2]]
    };
    let io = |e: std::io::Error| Error::io(path, "write", &e);
    let mut w = BufWriter::with_capacity(1 << 20, std::fs::File::create(path).map_err(io)?);
    if binary {
        let mut header = [b' '; HEADER];
        let title = format!("binary STL written by machscan {}", env!("CARGO_PKG_VERSION"));
        header[..title.len()].copy_from_slice(title.as_bytes());
        w.write_all(&header).map_err(io)?;
        w.write_all(&count.to_le_bytes()).map_err(io)?;
        let mut rec = Vec::with_capacity(RECORD);
        for t in triangles {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            rec.clear();
            for v in facet_normal(a, b, c).iter().chain(&a).chain(&b).chain(&c) {
                rec.extend_from_slice(&(*v as f32).to_le_bytes());
            }
            rec.extend_from_slice(&[0, 0]);
            w.write_all(&rec).map_err(io)?;
        }
    } else {
        let f = |v: f64| format!("{:e}", v as f32);
        writeln!(w, "solid machscan").map_err(io)?;
        for t in triangles {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            let n = facet_normal(a, b, c);
            writeln!(w, "  facet normal {} {} {}\n    outer loop", f(n[0]), f(n[1]), f(n[2])).map_err(io)?;
            for q in [a, b, c] {
                writeln!(w, "      vertex {} {} {}", f(q[0]), f(q[1]), f(q[2])).map_err(io)?;
            }
            writeln!(w, "    endloop\n  endfacet").map_err(io)?;
        }
        writeln!(w, "endsolid machscan").map_err(io)?;
    }
    w.flush().map_err(io)
}
