//! PCD files (Point Cloud Library): `ascii`, `binary` and `binary_compressed` (LZF) data, header
//! versions .5 to 0.7. Fields x, y, z are the points; normal_x/y/z the normals; every other
//! single-count field is returned by name (multi-count fields as name_0, name_1, ...).
//!
//! `binary_compressed` stores the fields column by column (all x, then all y, ...) after
//! LZF compression; `binary` stores packed records row by row.
use super::lzf::lzf_decompress;
use super::{CloudFile, CloudRef, Dtype};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::path::Path;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    I,
    U,
    F,
}

#[derive(Debug, Clone)]
struct Field {
    name: String,
    size: usize,
    kind: Kind,
    count: usize,
}

impl Field {
    fn decode(&self, b: &[u8]) -> f64 {
        macro_rules! le {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                <$t>::from_le_bytes(a) as f64
            }};
        }
        match (self.kind, self.size) {
            (Kind::I, 1) => b[0] as i8 as f64,
            (Kind::U, 1) => b[0] as f64,
            (Kind::I, 2) => le!(i16, 2),
            (Kind::U, 2) => le!(u16, 2),
            (Kind::I, 4) => le!(i32, 4),
            (Kind::U, 4) => le!(u32, 4),
            (Kind::I, 8) => le!(i64, 8),
            (Kind::U, 8) => le!(u64, 8),
            (Kind::F, 4) => le!(f32, 4),
            (Kind::F, 8) => le!(f64, 8),
            _ => f64::NAN, // excluded by the header check
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Data {
    Ascii,
    Binary,
    BinaryCompressed,
}

pub fn parse_pcd(path: &Path, bytes: &[u8]) -> Result<CloudFile> {
    let bad = |why: String| Error::format(path, why);
    // Header: text lines up to and including the DATA line.
    let mut pos = 0usize;
    let (mut names, mut sizes, mut types, mut counts): (Vec<String>, Vec<usize>, Vec<Kind>, Vec<usize>) =
        Default::default();
    let (mut width, mut height, mut points_n): (Option<usize>, Option<usize>, Option<usize>) = (None, None, None);
    let mut data = None;
    let mut line_no = 0;
    while data.is_none() {
        if pos >= bytes.len() {
            return Err(bad("the header ends before its DATA line".into()));
        }
        let end = bytes[pos..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |e| pos + e);
        let line = std::str::from_utf8(&bytes[pos..end])
            .map_err(|_| bad(format!("header line {} is not text", line_no + 1)))?;
        pos = (end + 1).min(bytes.len());
        line_no += 1;
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("").to_ascii_uppercase();
        let rest: Vec<&str> = words.collect();
        let at = |why: String| bad(format!("header line {line_no}: {why}"));
        let nums = |what: &str| -> Result<Vec<usize>> {
            rest.iter()
                .map(|w| w.parse::<usize>().map_err(|_| at(format!("{what}: {w:?} is not a whole number"))))
                .collect()
        };
        match key.as_str() {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" | "COLUMNS" => names = rest.iter().map(|s| s.to_string()).collect(),
            "SIZE" => sizes = nums("SIZE")?,
            "TYPE" => {
                types = rest
                    .iter()
                    .map(|t| match t.to_ascii_uppercase().as_str() {
                        "I" => Ok(Kind::I),
                        "U" => Ok(Kind::U),
                        "F" => Ok(Kind::F),
                        other => Err(at(format!("unknown TYPE {other:?} (I, U or F)"))),
                    })
                    .collect::<Result<_>>()?
            }
            "COUNT" => counts = nums("COUNT")?,
            "WIDTH" => width = nums("WIDTH")?.first().copied(),
            "HEIGHT" => height = nums("HEIGHT")?.first().copied(),
            "POINTS" => points_n = nums("POINTS")?.first().copied(),
            "DATA" => {
                data = Some(match rest.first().map(|s| s.to_ascii_lowercase()).as_deref() {
                    Some("ascii") => Data::Ascii,
                    Some("binary") => Data::Binary,
                    Some("binary_compressed") => Data::BinaryCompressed,
                    other => return Err(at(format!("unknown DATA {other:?}"))),
                })
            }
            other => return Err(at(format!("unknown header keyword {other:?}"))),
        }
    }
    let data = data.unwrap_or(Data::Ascii);
    let nf = names.len();
    if nf == 0 {
        return Err(bad("the header has no FIELDS".into()));
    }
    if counts.is_empty() {
        counts = vec![1; nf];
    }
    if sizes.len() != nf || types.len() != nf || counts.len() != nf {
        return Err(bad(format!(
            "FIELDS names {nf} fields but SIZE has {}, TYPE {}, COUNT {}",
            sizes.len(),
            types.len(),
            counts.len()
        )));
    }
    let mut fields = Vec::with_capacity(nf);
    for k in 0..nf {
        let ok = matches!((types[k], sizes[k]), (Kind::F, 4) | (Kind::F, 8) | (Kind::I | Kind::U, 1 | 2 | 4 | 8));
        if !ok {
            return Err(bad(format!(
                "field {:?}: TYPE {:?} with SIZE {} is not a number type",
                names[k], types[k], sizes[k]
            )));
        }
        fields.push(Field { name: names[k].clone(), size: sizes[k], kind: types[k], count: counts[k] });
    }
    let n = match (points_n, width, height) {
        (Some(p), _, _) => p,
        (None, Some(w), Some(h)) => w.checked_mul(h).ok_or_else(|| bad("WIDTH × HEIGHT overflows".into()))?,
        (None, Some(w), None) => w,
        _ => return Err(bad("the header gives neither POINTS nor WIDTH".into())),
    };
    let col = |name: &str| fields.iter().position(|f| f.name == name && f.count == 1);
    let (Some(ix), Some(iy), Some(iz)) = (col("x"), col("y"), col("z")) else {
        return Err(bad("no x, y and z fields".into()));
    };
    // Values per point, and where each field's first value sits in a record.
    let per_point: usize = fields.iter().map(|f| f.count).sum();
    let record: usize = fields.iter().map(|f| f.size * f.count).sum();
    let body = &bytes[pos..];
    // table[v] = all points' value v (v over every field value, count included).
    let table: Vec<Vec<f64>> = match data {
        Data::Ascii => {
            let text = std::str::from_utf8(body).map_err(|_| bad("the ASCII data is not text".into()))?;
            let lines: Vec<(usize, &str)> =
                text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()).take(n).collect();
            if lines.len() < n {
                return Err(bad(format!(
                    "truncated: the header declares {n} points but only {} data lines follow",
                    lines.len()
                )));
            }
            let rows: Vec<std::result::Result<Vec<f64>, String>> = lines
                .par_iter()
                .map(|(k, l)| {
                    let v: Vec<f64> = l
                        .split_whitespace()
                        .map(|t| {
                            parse_pcd_number(t)
                                .ok_or_else(|| format!("data line {}: {t:?} is not a number", line_no + k + 1))
                        })
                        .collect::<std::result::Result<_, _>>()?;
                    if v.len() < per_point {
                        return Err(format!(
                            "data line {}: {} values, the fields hold {per_point}",
                            line_no + k + 1,
                            v.len()
                        ));
                    }
                    Ok(v)
                })
                .collect();
            let mut table = vec![Vec::with_capacity(n); per_point];
            for r in rows {
                let v = r.map_err(bad)?;
                for c in 0..per_point {
                    table[c].push(v[c]);
                }
            }
            table
        }
        Data::Binary => {
            let need = n.checked_mul(record).ok_or_else(|| bad("the point count overflows".into()))?;
            if body.len() < need {
                return Err(bad(format!(
                    "truncated: the header declares {n} points ({need} bytes) but only {} bytes follow",
                    body.len()
                )));
            }
            let mut table = Vec::with_capacity(per_point);
            let mut off = 0;
            for f in &fields {
                for _ in 0..f.count {
                    let mut col = vec![0.0; n];
                    if record > 0 {
                        col.par_iter_mut()
                            .zip(body[..need].par_chunks_exact(record))
                            .for_each(|(v, r)| *v = f.decode(&r[off..]));
                    }
                    table.push(col);
                    off += f.size;
                }
            }
            table
        }
        Data::BinaryCompressed => {
            if body.len() < 8 {
                return Err(bad("truncated: no compressed sizes after DATA binary_compressed".into()));
            }
            let compressed = u32::from_le_bytes([body[0], body[1], body[2], body[3]]) as usize;
            let raw = u32::from_le_bytes([body[4], body[5], body[6], body[7]]) as usize;
            let need = n.checked_mul(record).ok_or_else(|| bad("the point count overflows".into()))?;
            if raw != need {
                return Err(bad(format!(
                    "the compressed block unpacks to {raw} bytes but {n} points of {record} bytes need {need}"
                )));
            }
            // LZF expands at most ~132× (a 2-byte back reference yields up to 264 bytes): a
            // larger announced size is a lie, refused before anything is allocated.
            if raw > compressed.saturating_mul(140).saturating_add(64) {
                return Err(bad(format!(
                    "bad LZF block: {compressed} compressed bytes cannot unpack to the {raw} announced"
                )));
            }
            if body.len() - 8 < compressed {
                return Err(bad(format!(
                    "truncated: {compressed} compressed bytes announced, {} present",
                    body.len() - 8
                )));
            }
            let unpacked = lzf_decompress(&body[8..8 + compressed], raw).map_err(bad)?;
            // Column-major: each field's values for all points, one after the other.
            let mut table = Vec::with_capacity(per_point);
            let mut start = 0;
            for f in &fields {
                let block = &unpacked[start..start + n * f.size * f.count];
                for c in 0..f.count {
                    let col: Vec<f64> =
                        (0..n).into_par_iter().map(|i| f.decode(&block[(i * f.count + c) * f.size..])).collect();
                    table.push(col);
                }
                start += n * f.size * f.count;
            }
            table
        }
    };
    // Map field index → first column in the table.
    let mut first = Vec::with_capacity(nf);
    let mut c = 0;
    for f in &fields {
        first.push(c);
        c += f.count;
    }
    let mut points = vec![0.0; 3 * n];
    for (k, &fi) in [ix, iy, iz].iter().enumerate() {
        for i in 0..n {
            points[3 * i + k] = table[first[fi]][i];
        }
    }
    let normal = match (col("normal_x"), col("normal_y"), col("normal_z")) {
        (Some(a), Some(b), Some(cz)) => Some([a, b, cz]),
        _ => None,
    };
    let normals = normal.map(|nc| {
        let mut v = vec![0.0; 3 * n];
        for (k, &fi) in nc.iter().enumerate() {
            for i in 0..n {
                v[3 * i + k] = table[first[fi]][i];
            }
        }
        v
    });
    let used: Vec<usize> = [ix, iy, iz].into_iter().chain(normal.into_iter().flatten()).collect();
    let mut scalars = Vec::new();
    for (fi, f) in fields.iter().enumerate() {
        if used.contains(&fi) || f.name == "_" {
            continue;
        }
        for c in 0..f.count {
            let name = if f.count == 1 { f.name.clone() } else { format!("{}_{c}", f.name) };
            scalars.push((name, table[first[fi] + c].clone()));
        }
    }
    Ok(CloudFile { points, normals, scalars, triangles: Vec::new(), dropped: 0 })
}

/// PCL writes nan as "nan" and sometimes "-nan"; Rust's parser takes "NaN"/"nan" but not "-nan".
fn parse_pcd_number(t: &str) -> Option<f64> {
    t.parse::<f64>().ok().or_else(|| if t.eq_ignore_ascii_case("-nan") { Some(f64::NAN) } else { None })
}

/// How a PCD file stores its data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PcdEncoding {
    Ascii,
    Binary,
    BinaryCompressed,
}

/// Writes x y z (and normal_x/y/z, and named scalars) as `dtype` fields (`data` checked by
/// `write_file`). `binary_compressed` stores the columns one after the other, LZF-framed, as PCL
/// does.
pub(super) fn write_pcd(path: &Path, data: &CloudRef<'_>, encoding: PcdEncoding, dtype: Dtype) -> Result<()> {
    use std::io::Write;
    let n = data.points.len() / 3;
    // Columns in field order.
    let mut names: Vec<&str> = vec!["x", "y", "z"];
    let mut cols: Vec<Vec<f64>> = (0..3).map(|k| (0..n).map(|i| data.points[3 * i + k]).collect()).collect();
    if let Some(nr) = data.normals {
        for (k, name) in ["normal_x", "normal_y", "normal_z"].into_iter().enumerate() {
            names.push(name);
            cols.push((0..n).map(|i| nr[3 * i + k]).collect());
        }
    }
    for (name, v) in data.scalars {
        names.push(name);
        cols.push(v.to_vec());
    }
    let f = names.len();
    let kind = match encoding {
        PcdEncoding::Ascii => "ascii",
        PcdEncoding::Binary => "binary",
        PcdEncoding::BinaryCompressed => "binary_compressed",
    };
    let size = match dtype {
        Dtype::F32 => "4",
        Dtype::F64 => "8",
    };
    let header = format!(
        "# .PCD v0.7 - Point Cloud Data file format (written by machscan {})\nVERSION 0.7\nFIELDS {}\nSIZE {}\nTYPE {}\nCOUNT {}\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {kind}\n",
        env!("CARGO_PKG_VERSION"),
        names.join(" "),
        vec![size; f].join(" "),
        vec!["F"; f].join(" "),
        vec!["1"; f].join(" "),
    );
    let io = |e: std::io::Error| Error::io(path, "write", &e);
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(path).map_err(io)?);
    w.write_all(header.as_bytes()).map_err(io)?;
    match encoding {
        PcdEncoding::Ascii => {
            for i in 0..n {
                let line: Vec<String> = cols.iter().map(|c| dtype.text(c[i])).collect();
                writeln!(w, "{}", line.join(" ")).map_err(io)?;
            }
        }
        PcdEncoding::Binary => {
            let mut row = Vec::with_capacity(8 * f);
            for i in 0..n {
                row.clear();
                for c in &cols {
                    dtype.put_le(&mut row, c[i]);
                }
                w.write_all(&row).map_err(io)?;
            }
        }
        PcdEncoding::BinaryCompressed => {
            let mut raw = Vec::with_capacity(8 * f * n);
            for c in &cols {
                for &v in c {
                    dtype.put_le(&mut raw, v);
                }
            }
            let comp = super::lzf::lzf_store(&raw);
            // The block sizes are 32-bit in the format.
            let (Ok(comp_len), Ok(raw_len)) = (u32::try_from(comp.len()), u32::try_from(raw.len())) else {
                return Err(Error::invalid(
                    "compressed",
                    format!("{n} points make a block over the 4 GiB binary_compressed can hold: write binary"),
                ));
            };
            w.write_all(&comp_len.to_le_bytes()).map_err(io)?;
            w.write_all(&raw_len.to_le_bytes()).map_err(io)?;
            w.write_all(&comp).map_err(io)?;
        }
    }
    w.flush().map_err(io)
}
