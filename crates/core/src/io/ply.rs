//! PLY files (Stanford polygon format): reader for ASCII and binary little/big-endian files
//! with any scalar vertex properties and faces; writer of float or double vertices with
//! optional normals, named scalars and triangles.
//!
//! The reader never trusts the header: counts are checked against the bytes present before
//! anything is allocated, and every failure names the file and what is wrong.
use super::{CloudFile, CloudRef, Dtype};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::io::{BufWriter, Write};
use std::path::Path;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// Decodes one value; `b` holds at least `size()` bytes.
    #[inline]
    fn decode(self, b: &[u8], big_endian: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if big_endian { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => get!(i16, 2),
            Scalar::U16 => get!(u16, 2),
            Scalar::I32 => get!(i32, 4),
            Scalar::U32 => get!(u32, 4),
            Scalar::F32 => get!(f32, 4),
            Scalar::F64 => get!(f64, 8),
        }
    }
}

#[derive(Debug, Clone)]
enum Property {
    Scalar { name: String, kind: Scalar },
    List { name: String, count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Binary { big_endian: bool },
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    body_start: usize,
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let bad = |why: String| Error::format(path, why);
    if !bytes.starts_with(b"ply") {
        return Err(bad("not a PLY file (it does not start with \"ply\")".into()));
    }
    let end = find(bytes, b"end_header")
        .ok_or_else(|| bad("no end_header line: the header is truncated or this is not a PLY file".into()))?;
    let mut body_start = end + b"end_header".len();
    // The header ends with the line break after end_header (\n or \r\n).
    if bytes.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if bytes.get(body_start) == Some(&b'\n') {
        body_start += 1;
    }
    let text = std::str::from_utf8(&bytes[..end]).map_err(|_| bad("the header is not text".into()))?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (k, line) in text.lines().enumerate().skip(1) {
        let words: Vec<&str> = line.split_whitespace().collect();
        let at = |why: String| bad(format!("header line {}: {why}", k + 1));
        match words.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                format = Some(match words.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::Binary { big_endian: false },
                    Some("binary_big_endian") => Format::Binary { big_endian: true },
                    other => return Err(at(format!("unknown format {other:?}"))),
                })
            }
            Some("element") => {
                let (Some(name), Some(count)) = (words.get(1), words.get(2)) else {
                    return Err(at("an element needs a name and a count".into()));
                };
                let count =
                    count.parse::<usize>().map_err(|_| at(format!("element count {count:?} is not a number")))?;
                elements.push(Element { name: name.to_string(), count, properties: Vec::new() });
            }
            Some("property") => {
                let el = elements.last_mut().ok_or_else(|| at("a property before any element".into()))?;
                let prop = if words.get(1) == Some(&"list") {
                    let (Some(c), Some(i), Some(n)) = (words.get(2), words.get(3), words.get(4)) else {
                        return Err(at("a list property needs a count type, an item type and a name".into()));
                    };
                    let count = Scalar::parse(c).ok_or_else(|| at(format!("unknown property type {c:?}")))?;
                    let item = Scalar::parse(i).ok_or_else(|| at(format!("unknown property type {i:?}")))?;
                    if matches!(count, Scalar::F32 | Scalar::F64) {
                        return Err(at(format!("a list count must be an integer type, got {c:?}")));
                    }
                    Property::List { name: n.to_string(), count, item }
                } else {
                    let (Some(t), Some(n)) = (words.get(1), words.get(2)) else {
                        return Err(at("a property needs a type and a name".into()));
                    };
                    let kind = Scalar::parse(t).ok_or_else(|| at(format!("unknown property type {t:?}")))?;
                    Property::Scalar { name: n.to_string(), kind }
                };
                el.properties.push(prop);
            }
            Some(other) => return Err(at(format!("unknown header keyword {other:?}"))),
        }
    }
    let format = format.ok_or_else(|| bad("the header has no format line".into()))?;
    Ok(Header { format, elements, body_start })
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A PLY file's bytes (`path` names them in messages): vertices (x, y, z required), normals,
/// other scalar vertex properties and faces (`vertex_indices` or `vertex_index`).
pub fn parse_ply(path: &Path, bytes: &[u8]) -> Result<CloudFile> {
    let header = parse_header(path, bytes)?;
    let body = &bytes[header.body_start..];
    match header.format {
        Format::Binary { big_endian } => read_binary(path, &header.elements, body, big_endian),
        Format::Ascii => read_ascii(path, &header.elements, body),
    }
}

/// Column layout of the vertex element: which property is x, y, z, nx, ny, nz.
struct VertexColumns {
    names: Vec<String>,
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
}

fn vertex_columns(path: &Path, el: &Element) -> Result<VertexColumns> {
    let mut names = Vec::new();
    for p in &el.properties {
        match p {
            Property::Scalar { name, .. } => names.push(name.clone()),
            Property::List { name, .. } => {
                return Err(Error::format(
                    path,
                    format!("vertex property {name:?} is a list; machscan reads scalar vertex properties only"),
                ))
            }
        }
    }
    let col = |n: &str| names.iter().position(|x| x == n);
    let xyz = match (col("x"), col("y"), col("z")) {
        (Some(x), Some(y), Some(z)) => [x, y, z],
        _ => return Err(Error::format(path, "the vertex element has no x, y and z properties")),
    };
    let normal = match (col("nx"), col("ny"), col("nz")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    Ok(VertexColumns { names, xyz, normal })
}

fn assemble(cols: &VertexColumns, n: usize, table: Vec<Vec<f64>>, triangles: Vec<[u32; 3]>) -> CloudFile {
    let mut points = vec![0.0; 3 * n];
    for (k, &c) in cols.xyz.iter().enumerate() {
        for i in 0..n {
            points[3 * i + k] = table[c][i];
        }
    }
    let normals = cols.normal.map(|nc| {
        let mut v = vec![0.0; 3 * n];
        for (k, &c) in nc.iter().enumerate() {
            for i in 0..n {
                v[3 * i + k] = table[c][i];
            }
        }
        v
    });
    let used: Vec<usize> = cols.xyz.iter().chain(cols.normal.iter().flatten()).copied().collect();
    let scalars = table
        .into_iter()
        .enumerate()
        .filter(|(c, _)| !used.contains(c))
        .map(|(c, v)| (cols.names[c].clone(), v))
        .collect();
    CloudFile { points, normals, scalars, triangles, dropped: 0 }
}

fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    for k in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[k], poly[k + 1]]);
    }
}

fn check_face_indices(path: &Path, triangles: &[[u32; 3]], n: usize) -> Result<()> {
    if let Some(t) = triangles.iter().find(|t| t.iter().any(|&v| v as usize >= n)) {
        return Err(Error::format(
            path,
            format!("a face refers to vertex {} but there are only {n} vertices", t.iter().max().unwrap_or(&0)),
        ));
    }
    Ok(())
}

fn read_binary(path: &Path, elements: &[Element], body: &[u8], be: bool) -> Result<CloudFile> {
    let mut pos = 0usize;
    let mut vertex: Option<(VertexColumns, usize, Vec<Vec<f64>>)> = None;
    let mut triangles = Vec::new();
    for el in elements {
        let fixed: Option<usize> = el
            .properties
            .iter()
            .map(|p| match p {
                Property::Scalar { kind, .. } => Some(kind.size()),
                Property::List { .. } => None,
            })
            .sum();
        if el.name == "vertex" {
            let cols = vertex_columns(path, el)?;
            let stride = fixed.unwrap_or(0);
            let need = el.count.checked_mul(stride).ok_or_else(|| Error::format(path, "the vertex count overflows"))?;
            if body.len() - pos < need {
                return Err(Error::format(
                    path,
                    format!(
                        "truncated: the header declares {} vertices ({need} bytes) but only {} bytes follow",
                        el.count,
                        body.len() - pos
                    ),
                ));
            }
            let data = &body[pos..pos + need];
            let kinds: Vec<(Scalar, usize)> = {
                let mut off = 0;
                el.properties
                    .iter()
                    .map(|p| {
                        let Property::Scalar { kind, .. } = p else { unreachable!() };
                        let r = (*kind, off);
                        off += kind.size();
                        r
                    })
                    .collect()
            };
            // Column by column, rows in parallel: memory bandwidth, not parsing, bounds this.
            let table: Vec<Vec<f64>> = kinds
                .iter()
                .map(|&(kind, off)| {
                    let mut col = vec![0.0; el.count];
                    if stride > 0 {
                        col.par_iter_mut()
                            .zip(data.par_chunks_exact(stride))
                            .for_each(|(v, row)| *v = kind.decode(&row[off..], be));
                    }
                    col
                })
                .collect();
            pos += need;
            vertex = Some((cols, el.count, table));
            continue;
        }
        let is_face = el.name == "face";
        for row in 0..el.count {
            let mut poly: Vec<u32> = Vec::new();
            for p in &el.properties {
                match p {
                    Property::Scalar { kind, .. } => {
                        if body.len() - pos < kind.size() {
                            return Err(Error::format(
                                path,
                                format!("truncated in element {:?}, row {row} of {}", el.name, el.count),
                            ));
                        }
                        pos += kind.size();
                    }
                    Property::List { name, count, item } => {
                        if body.len() - pos < count.size() {
                            return Err(Error::format(
                                path,
                                format!("truncated in element {:?}, row {row} of {}", el.name, el.count),
                            ));
                        }
                        let c = count.decode(&body[pos..], be);
                        pos += count.size();
                        if !(c >= 0.0) {
                            return Err(Error::format(
                                path,
                                format!("element {:?}, row {row}: negative list length {c}", el.name),
                            ));
                        }
                        let c = c as usize;
                        let need = c * item.size();
                        if body.len() - pos < need {
                            return Err(Error::format(
                                path,
                                format!("truncated in element {:?}, row {row} of {}", el.name, el.count),
                            ));
                        }
                        if is_face && (name == "vertex_indices" || name == "vertex_index") {
                            poly = (0..c)
                                .map(|k| item.decode(&body[pos + k * item.size()..], be))
                                .map(|v| if v >= 0.0 { v as u32 } else { u32::MAX })
                                .collect();
                        }
                        pos += need;
                    }
                }
            }
            fan(&poly, &mut triangles);
        }
    }
    let (cols, n, table) = vertex.ok_or_else(|| Error::format(path, "no vertex element"))?;
    check_face_indices(path, &triangles, n)?;
    Ok(assemble(&cols, n, table, triangles))
}

fn read_ascii(path: &Path, elements: &[Element], body: &[u8]) -> Result<CloudFile> {
    let text = std::str::from_utf8(body).map_err(|_| Error::format(path, "the ASCII body is not text"))?;
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let mut vertex_rows: Option<(VertexColumns, usize, usize, Vec<f64>)> = None;
    let mut triangles = Vec::new();
    for el in elements {
        if el.name == "vertex" {
            let cols = vertex_columns(path, el)?;
            let w = cols.names.len();
            let rows: Vec<(usize, &str)> = lines.by_ref().take(el.count).collect();
            if rows.len() < el.count {
                return Err(Error::format(
                    path,
                    format!(
                        "truncated: the header declares {} vertices but only {} vertex lines follow",
                        el.count,
                        rows.len()
                    ),
                ));
            }
            // Each line parsed straight into its row of a flat table, lines in parallel.
            let mut flat = vec![0.0f64; el.count * w];
            let bad: Option<String> = flat
                .par_chunks_mut(w.max(1))
                .zip(rows.par_iter())
                .filter_map(|(row, (k, line))| {
                    let mut it = line.split_ascii_whitespace();
                    for (c, v) in row.iter_mut().enumerate() {
                        match it.next() {
                            Some(t) => match t.parse::<f64>() {
                                Ok(x) => *v = x,
                                Err(_) => return Some(format!("body line {}: {t:?} is not a number", k + 1)),
                            },
                            None => {
                                return Some(format!("body line {}: {c} values, the vertex has {w} properties", k + 1))
                            }
                        }
                    }
                    None
                })
                .min();
            if let Some(e) = bad {
                return Err(Error::format(path, e));
            }
            vertex_rows = Some((cols, el.count, w, flat));
            continue;
        }
        for row in 0..el.count {
            let Some((k, line)) = lines.next() else {
                return Err(Error::format(
                    path,
                    format!("truncated in element {:?}: {row} of {} lines", el.name, el.count),
                ));
            };
            if el.name != "face" {
                continue;
            }
            let v: Vec<f64> = line
                .split_whitespace()
                .map(|t| {
                    t.parse::<f64>()
                        .map_err(|_| Error::format(path, format!("body line {}: {t:?} is not a number", k + 1)))
                })
                .collect::<Result<_>>()?;
            // The first list property holds the vertex indices (count, then items).
            if let Some(&c) = v.first() {
                let c = c as usize;
                if v.len() < 1 + c {
                    return Err(Error::format(
                        path,
                        format!("body line {}: the face lists {c} vertices but has {}", k + 1, v.len() - 1),
                    ));
                }
                let poly: Vec<u32> = v[1..1 + c].iter().map(|&x| if x >= 0.0 { x as u32 } else { u32::MAX }).collect();
                fan(&poly, &mut triangles);
            }
        }
    }
    let (cols, n, w, flat) = vertex_rows.ok_or_else(|| Error::format(path, "no vertex element"))?;
    check_face_indices(path, &triangles, n)?;
    Ok(assemble_rows(&cols, n, w, &flat, triangles))
}

/// [`assemble`] from a row-major `(n, w)` table: one pass per output, no transposition.
fn assemble_rows(cols: &VertexColumns, n: usize, w: usize, flat: &[f64], triangles: Vec<[u32; 3]>) -> CloudFile {
    let pick = |c: [usize; 3]| -> Vec<f64> {
        let mut out = vec![0.0; 3 * n];
        out.par_chunks_mut(3).zip(flat.par_chunks(w.max(1))).for_each(|(o, r)| {
            o[0] = r[c[0]];
            o[1] = r[c[1]];
            o[2] = r[c[2]];
        });
        out
    };
    let points = pick(cols.xyz);
    let normals = cols.normal.map(pick);
    let used: Vec<usize> = cols.xyz.iter().chain(cols.normal.iter().flatten()).copied().collect();
    let scalars = (0..w)
        .filter(|c| !used.contains(c))
        .map(|c| (cols.names[c].clone(), flat.iter().skip(c).step_by(w).copied().collect()))
        .collect();
    CloudFile { points, normals, scalars, triangles, dropped: 0 }
}

/// Writes `data` (checked by `write_file`): vertices with normals and scalars as `dtype`, and a
/// `face` element of triangles when there are any (`list uchar int vertex_indices`, what Open3D,
/// PCL and trimesh read).
pub(super) fn write_ply(path: &Path, data: &CloudRef<'_>, binary: bool, dtype: Dtype) -> Result<()> {
    let n = data.points.len() / 3;
    let ty = match dtype {
        Dtype::F32 => "float",
        Dtype::F64 => "double",
    };
    let mut header = format!(
        "ply\nformat {} 1.0\ncomment written by machscan {}\nelement vertex {n}\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\n",
        if binary { "binary_little_endian" } else { "ascii" },
        env!("CARGO_PKG_VERSION")
    );
    if data.normals.is_some() {
        header.push_str(&format!("property {ty} nx\nproperty {ty} ny\nproperty {ty} nz\n"));
    }
    for (name, _) in data.scalars {
        header.push_str(&format!("property {ty} {name}\n"));
    }
    let triangles = data.triangles.unwrap_or(&[]);
    if data.triangles.is_some() {
        header.push_str(&format!("element face {}\nproperty list uchar int vertex_indices\n", triangles.len()));
    }
    header.push_str("end_header\n");
    let io = |e: std::io::Error| Error::io(path, "write", &e);
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    w.write_all(header.as_bytes()).map_err(io)?;
    let mut row = Vec::with_capacity(6 + data.scalars.len());
    let mut bytes = Vec::with_capacity(8 * row.capacity());
    for i in 0..n {
        row.clear();
        row.extend_from_slice(&data.points[3 * i..3 * i + 3]);
        if let Some(nr) = data.normals {
            row.extend_from_slice(&nr[3 * i..3 * i + 3]);
        }
        row.extend(data.scalars.iter().map(|(_, v)| v[i]));
        if binary {
            bytes.clear();
            for &v in &row {
                dtype.put_le(&mut bytes, v);
            }
            w.write_all(&bytes).map_err(io)?;
        } else {
            let line: Vec<String> = row.iter().map(|&v| dtype.text(v)).collect();
            writeln!(w, "{}", line.join(" ")).map_err(io)?;
        }
    }
    for t in triangles {
        if binary {
            w.write_all(&[3u8]).map_err(io)?;
            for v in t {
                w.write_all(&(*v as i32).to_le_bytes()).map_err(io)?;
            }
        } else {
            writeln!(w, "3 {} {} {}", t[0], t[1], t[2]).map_err(io)?;
        }
    }
    w.flush().map_err(io)
}
