//! LAS 1.0–1.4 and LAZ point clouds (ASPRS LAS specification; LAZ is LASzip's compression of
//! the same records). The records, the header and the compression are the `las` crate's (with
//! its `laz` feature); this module maps them to machscan's cloud: the coordinates as stored
//! (X·scale + offset, the file's own units, taken as mm), every point field as a scalar named as
//! laspy names it, the extra bytes the Extra Bytes VLR describes as scalars of their own names
//! (scaled and offset where the descriptor says so), and extra bytes named `normal_x/y/z` (what
//! machscan writes) as the normals.
//!
//! machscan writes LAS 1.4 with point format 6 (7 when red, green and blue are given): the
//! point fields given as scalars by their LAS names, everything else as extra bytes (float64 by
//! default, float32 with `dtype`), normals as `normal_x/y/z`. Coordinates are stored as integer
//! steps of `scale` (default 0.1 µm) from an offset of whole mm below the cloud.
use super::{CloudFile, CloudRef, Dtype};
use crate::error::{Error, Result};
use las::point::{Classification, Format, ScanDirection};
use las::{Builder, Point, Reader, Transform, Vector, Version, Vlr, Writer};
use std::io::{BufWriter, Cursor};
use std::path::Path;

/// The default coordinate step of written files, mm: far below any profiler's resolution, and
/// ±214 m about the offset fits LAS's 32-bit integers.
pub const LAS_SCALE: f64 = 1e-4;

/// The Extra Bytes VLR (LAS 1.4 R15 §2.6.1): one 192-byte descriptor per extra dimension.
const EXTRA_USER: &str = "LASF_Spec";
const EXTRA_RECORD: u16 = 4;
const DESCRIPTOR: usize = 192;

/// The extended formats' scan angle is stored in steps of 0.006°.
const SCAN_ANGLE_STEP: f64 = 0.006;

/// Points decoded at a time: memory follows what the file holds, not what its header claims.
const CHUNK: u64 = 1 << 16;

/// The bytes are in memory, so a read error is the content's: cut short or not LAS.
fn las_error(path: &Path, e: las::Error) -> Error {
    match e {
        las::Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            Error::format(path, "the point records are cut short (the header promises more points)")
        }
        other => Error::format(path, format!("not a readable LAS/LAZ file: {other}")),
    }
}

/// One extra dimension of a point record.
#[derive(Debug, Clone)]
struct ExtraDim {
    name: String,
    /// Byte offset in the record's extra bytes and bytes per element.
    offset: usize,
    size: usize,
    kind: u8,
    count: usize,
    scale: [f64; 3],
    shift: [f64; 3],
}

impl ExtraDim {
    fn value(&self, bytes: &[u8], k: usize) -> f64 {
        let b = &bytes[self.offset + k * self.size..self.offset + (k + 1) * self.size];
        macro_rules! le {
            ($t:ty) => {
                <$t>::from_le_bytes(b.try_into().expect("size follows the type")) as f64
            };
        }
        let raw = match self.kind {
            1 => b[0] as f64,
            2 => b[0] as i8 as f64,
            3 => le!(u16),
            4 => le!(i16),
            5 => le!(u32),
            6 => le!(i32),
            7 => le!(u64),
            8 => le!(i64),
            9 => le!(f32),
            _ => le!(f64),
        };
        raw * self.scale[k] + self.shift[k]
    }
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// The extra dimensions a file's Extra Bytes VLR describes, within `record` extra bytes per
/// point. Undocumented bytes (data type 0) are skipped; the deprecated two- and three-element
/// types (11–30) give `name_0`, `name_1`, ...
fn extra_dims(path: &Path, header: &las::Header, record: usize) -> Result<Vec<ExtraDim>> {
    let Some(vlr) = header.all_vlrs().find(|v| v.user_id == EXTRA_USER && v.record_id == EXTRA_RECORD) else {
        return Ok(Vec::new());
    };
    let mut dims = Vec::new();
    let mut offset = 0;
    for (i, d) in vlr.data.chunks(DESCRIPTOR).enumerate() {
        if d.len() < DESCRIPTOR {
            return Err(Error::format(path, format!("extra-bytes descriptor {i} is cut short ({} bytes)", d.len())));
        }
        let (kind, options) = (d[2], d[3]);
        let name: String = String::from_utf8_lossy(&d[4..36]).trim_end_matches('\0').trim().to_string();
        let (base, count) = match kind {
            0 => {
                offset += options as usize;
                continue;
            }
            1..=30 => ((kind - 1) % 10 + 1, ((kind - 1) / 10 + 1) as usize),
            _ => return Err(Error::format(path, format!("extra dimension {name:?} has unknown data type {kind}"))),
        };
        let size = [1, 1, 2, 2, 4, 4, 8, 8, 4, 8][base as usize - 1];
        // Scale and offset are doubles for every type (the descriptor's `anytype` of 3 × 8 bytes).
        let (mut scale, mut shift) = ([1.0; 3], [0.0; 3]);
        for k in 0..count {
            if options & 8 != 0 {
                scale[k] = f64_at(d, 112 + 8 * k);
            }
            if options & 16 != 0 {
                shift[k] = f64_at(d, 136 + 8 * k);
            }
        }
        dims.push(ExtraDim { name, offset, size, kind: base, count, scale, shift });
        offset += size * count;
    }
    if offset > record {
        return Err(Error::format(
            path,
            format!("the extra-bytes descriptors describe {offset} bytes, but each point has {record}"),
        ));
    }
    Ok(dims)
}

/// The LASzip chunk table's count of chunks, checked before the `laz` crate allocates a table of
/// that many entries (a corrupted count would ask for gigabytes): each chunk starts with one
/// uncompressed point record, so the file holds at most `len / record_len` of them. The table's
/// offset is the first 8 bytes of the point data (−1: in the file's last 8 bytes), the count the
/// second u32 there (LASzip's laszip_dll.cpp, `read_chunk_table`).
fn check_chunk_table(path: &Path, bytes: &[u8]) -> Result<()> {
    let u32_at = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")));
    let i64_at = |at: usize| bytes.get(at..at + 8).map(|b| i64::from_le_bytes(b.try_into().expect("8 bytes")));
    let (Some(start), Some(record)) = (u32_at(96), bytes.get(105..107)) else {
        return Ok(()); // a header this short is the reader's to refuse
    };
    let record = u16::from_le_bytes([record[0], record[1]]).max(1) as usize;
    let table = match i64_at(start as usize) {
        Some(-1) => bytes.len().checked_sub(8).and_then(i64_at),
        other => other,
    };
    let count = table.and_then(|t| usize::try_from(t).ok()).and_then(|t| u32_at(t + 4));
    match count {
        Some(c) if c as usize > bytes.len() / record => Err(Error::format(
            path,
            format!("the LAZ chunk table counts {c} chunks, more than a file of {} bytes holds", bytes.len()),
        )),
        _ => Ok(()),
    }
}

/// The LASzip VLR's items (laszip_dll.cpp: 32 bytes of settings, a u16 count, then type, size and
/// version, u16 each) must make up the point record: the `laz` crate splits each record by their
/// sizes and panics where they overrun it.
fn check_laszip_items(path: &Path, header: &las::Header) -> Result<()> {
    let Some(vlr) = header.all_vlrs().find(|v| v.user_id == "laszip encoded" && v.record_id == 22204) else {
        return Err(Error::format(path, "compressed points without the LASzip VLR that says how"));
    };
    let d = &vlr.data;
    let items = d.get(32..34).map(|b| u16::from_le_bytes([b[0], b[1]]) as usize);
    let record = header.point_format().len() as usize;
    let size = |i: usize| d.get(36 + 6 * i..38 + 6 * i).map(|b| u16::from_le_bytes([b[0], b[1]]) as usize);
    match items.and_then(|k| (0..k).map(size).sum::<Option<usize>>()) {
        Some(total) if total == record => Ok(()),
        Some(total) => Err(Error::format(
            path,
            format!("the LASzip items make records of {total} bytes, the header's point format {record}"),
        )),
        None => Err(Error::format(path, "the LASzip VLR is cut short")),
    }
}

/// Reads a LAS or LAZ file's bytes (module docs).
pub fn parse_las(path: &Path, bytes: Vec<u8>) -> Result<CloudFile> {
    // The header is read here and again by the reader: the LAZ checks must come before the
    // reader, whose constructor already trusts the chunk table.
    let header = las::Header::new(Cursor::new(&bytes)).map_err(|e| las_error(path, e))?;
    let format = *header.point_format();
    if format.is_compressed {
        check_laszip_items(path, &header)?;
        check_chunk_table(path, &bytes)?;
    }
    // LAZ is decoded in turn: the crate's parallel decoder trusts the chunk table's byte and
    // point counts (a corrupted one asks for any amount of memory, or asserts).
    let mut reader = Reader::new(Cursor::new(bytes)).map_err(|e| las_error(path, e))?;
    let dims = extra_dims(path, &header, format.extra_bytes as usize)?;
    let fields = point_fields(&format);
    let record_len = format.len() as usize;
    let extra_at = record_len - format.extra_bytes as usize;
    let transforms = *header.transforms();
    let mut remaining = header.number_of_points();
    let mut points = Vec::new();
    let mut columns: Vec<Vec<f64>> = fields.iter().map(|_| Vec::new()).collect();
    let mut extra: Vec<Vec<f64>> = dims.iter().flat_map(|d| (0..d.count).map(|_| Vec::new())).collect();
    let mut data = las::PointDataBuilder::new().for_header(&header).build();
    while remaining > 0 {
        let got = reader.fill_points(remaining.min(CHUNK), &mut data).map_err(|e| las_error(path, e))?;
        if got == 0 {
            return Err(las_error(path, las::Error::Io(std::io::ErrorKind::UnexpectedEof.into())));
        }
        remaining -= got;
        for r in data.raw_bytes().chunks_exact(record_len) {
            let int = |at: usize| i32::from_le_bytes([r[at], r[at + 1], r[at + 2], r[at + 3]]);
            // X·scale + offset, the operations laspy and the crate do, so the same bits.
            points.extend_from_slice(&[
                transforms.x.scale * f64::from(int(0)) + transforms.x.offset,
                transforms.y.scale * f64::from(int(4)) + transforms.y.offset,
                transforms.z.scale * f64::from(int(8)) + transforms.z.offset,
            ]);
            for (column, (_, read)) in columns.iter_mut().zip(&fields) {
                column.push(read.value(r));
            }
            let mut column = 0;
            for d in &dims {
                for k in 0..d.count {
                    extra[column].push(d.value(&r[extra_at..], k));
                    column += 1;
                }
            }
        }
    }
    let mut scalars: Vec<(String, Vec<f64>)> = fields.iter().map(|(n, _)| n.to_string()).zip(columns).collect();
    let mut column = 0;
    for d in &dims {
        for k in 0..d.count {
            let name = if d.count == 1 { d.name.clone() } else { format!("{}_{k}", d.name) };
            scalars.push((name, std::mem::take(&mut extra[column])));
            column += 1;
        }
    }
    let normals = take_normals(&mut scalars);
    Ok(CloudFile { points, normals, scalars, triangles: Vec::new(), dropped: 0 })
}

/// Moves `normal_x/y/z` (or `nx/ny/nz`) out of the scalars into `(N, 3)` normals.
fn take_normals(scalars: &mut Vec<(String, Vec<f64>)>) -> Option<Vec<f64>> {
    let find = |scalars: &[(String, Vec<f64>)], n: &str| scalars.iter().position(|(s, _)| s.eq_ignore_ascii_case(n));
    let names = [["normal_x", "normal_y", "normal_z"], ["nx", "ny", "nz"]]
        .into_iter()
        .find(|names| names.iter().all(|n| find(scalars, n).is_some()))?;
    let [x, y, z] = names.map(|n| scalars.remove(find(scalars, n).expect("all three present")).1);
    Some((0..x.len()).flat_map(|i| [x[i], y[i], z[i]]).collect())
}

/// One point field: its laspy name and how it is read from a stored record.
#[derive(Clone, Copy)]
enum Read {
    U8(usize),
    I8(usize),
    U16(usize),
    I16(usize),
    F64(usize),
    /// Bits `shift..shift + width` of the byte at `at`.
    Bits {
        at: usize,
        shift: u8,
        width: u8,
    },
}

impl Read {
    #[inline]
    fn value(self, r: &[u8]) -> f64 {
        let two = |at: usize| [r[at], r[at + 1]];
        match self {
            Read::U8(at) => r[at] as f64,
            Read::I8(at) => r[at] as i8 as f64,
            Read::U16(at) => u16::from_le_bytes(two(at)) as f64,
            Read::I16(at) => i16::from_le_bytes(two(at)) as f64,
            Read::F64(at) => f64_at(r, at),
            Read::Bits { at, shift, width } => ((r[at] >> shift) & ((1u8 << width) - 1)) as f64,
        }
    }
}

/// The point fields of a format, named as laspy names them, read from the stored records (LAS
/// 1.4 R15 tables 7–17) rather than through the crate's `Point`, which turns class 12 into an
/// overlap flag and allocates per point.
fn point_fields(format: &Format) -> Vec<(&'static str, Read)> {
    let bits = |at, shift, width| Read::Bits { at, shift, width };
    let mut f = vec![("intensity", Read::U16(12))];
    // Where the colour starts: after the GPS time, if any.
    let mut at;
    if format.is_extended {
        f.extend([
            ("return_number", bits(14, 0, 4)),
            ("number_of_returns", bits(14, 4, 4)),
            ("synthetic", bits(15, 0, 1)),
            ("key_point", bits(15, 1, 1)),
            ("withheld", bits(15, 2, 1)),
            ("overlap", bits(15, 3, 1)),
            ("scanner_channel", bits(15, 4, 2)),
            ("scan_direction_flag", bits(15, 6, 1)),
            ("edge_of_flight_line", bits(15, 7, 1)),
            ("classification", Read::U8(16)),
            ("user_data", Read::U8(17)),
            // In the stored steps of 0.006°, as laspy gives it.
            ("scan_angle", Read::I16(18)),
            ("point_source_id", Read::U16(20)),
            ("gps_time", Read::F64(22)),
        ]);
        at = 30;
    } else {
        f.extend([
            ("return_number", bits(14, 0, 3)),
            ("number_of_returns", bits(14, 3, 3)),
            ("scan_direction_flag", bits(14, 6, 1)),
            ("edge_of_flight_line", bits(14, 7, 1)),
            ("classification", bits(15, 0, 5)),
            ("synthetic", bits(15, 5, 1)),
            ("key_point", bits(15, 6, 1)),
            ("withheld", bits(15, 7, 1)),
            ("scan_angle_rank", Read::I8(16)),
            ("user_data", Read::U8(17)),
            ("point_source_id", Read::U16(18)),
        ]);
        at = 20;
        if format.has_gps_time {
            f.push(("gps_time", Read::F64(20)));
            at = 28;
        }
    }
    if format.has_color {
        f.extend([("red", Read::U16(at)), ("green", Read::U16(at + 2)), ("blue", Read::U16(at + 4))]);
        at += 6;
    }
    if format.has_nir {
        f.push(("nir", Read::U16(at)));
    }
    f
}

/// A point field of format 6/7 that a scalar of this name fills, with its range.
fn standard_field(name: &str) -> Option<(f64, f64)> {
    Some(match name {
        "intensity" | "point_source_id" | "red" | "green" | "blue" => (0.0, u16::MAX as f64),
        "classification" | "user_data" => (0.0, u8::MAX as f64),
        "return_number" | "number_of_returns" => (0.0, 15.0),
        "scanner_channel" => (0.0, 3.0),
        "scan_angle" => (i16::MIN as f64, i16::MAX as f64),
        "synthetic" | "key_point" | "withheld" | "overlap" | "scan_direction_flag" | "edge_of_flight_line" => {
            (0.0, 1.0)
        }
        "gps_time" => (f64::MIN, f64::MAX),
        _ => return None,
    })
}

/// Writes `data` as LAS 1.4 (LAZ when `compressed`), module docs. `scale`: the coordinate
/// step, mm (default [`LAS_SCALE`]); `dtype`: the extra bytes' type (default float64).
pub fn write_las(path: &Path, data: &CloudRef<'_>, compressed: bool, scale: Option<f64>, dtype: Dtype) -> Result<()> {
    let n = data.points.len() / 3;
    let scale = scale.unwrap_or(LAS_SCALE);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::invalid("scale", format!("must be a positive step in mm, got {scale}")));
    }
    let mut transforms = [Transform { scale, offset: 0.0 }; 3];
    for (axis, t) in transforms.iter_mut().enumerate() {
        let (lo, hi) = (0..n)
            .map(|i| data.points[3 * i + axis])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
        t.offset = if n == 0 { 0.0 } else { lo.floor() };
        if n > 0 && (hi - t.offset) / scale > i32::MAX as f64 {
            return Err(Error::invalid(
                "points",
                format!(
                    "they span {:.1} mm along {}, more than LAS's 32-bit steps hold at scale = {scale} mm; give a larger scale",
                    hi - lo,
                    ["x", "y", "z"][axis]
                ),
            ));
        }
    }
    for (name, values) in data.scalars {
        if let Some((lo, hi)) = standard_field(name) {
            let integral = *name != "gps_time";
            if let Some(v) = values.iter().find(|&&v| !(v >= lo && v <= hi && (!integral || v.fract() == 0.0))) {
                return Err(Error::invalid(
                    "scalars",
                    format!("{name:?} is a LAS point field of whole numbers {lo}..{hi}; {v} does not fit"),
                ));
            }
        }
    }
    let get = |name: &str| data.scalars.iter().find(|(s, _)| *s == name).map(|(_, v)| *v);
    let colour = match (get("red"), get("green"), get("blue")) {
        (Some(r), Some(g), Some(b)) => Some([r, g, b]),
        (None, None, None) => None,
        _ => return Err(Error::invalid("scalars", "red, green and blue are LAS colour: give all three or none")),
    };
    let mut extra: Vec<(&str, &[f64])> =
        data.scalars.iter().filter(|(s, _)| standard_field(s).is_none()).copied().collect();
    let normal_columns = data.normals.map(super::xyz_columns).unwrap_or_default();
    let normal_names = ["normal_x", "normal_y", "normal_z"];
    for (name, column) in normal_names.iter().zip(&normal_columns) {
        extra.push((name, column));
    }
    for (name, _) in &extra {
        if name.len() > 32 {
            return Err(Error::invalid(
                "scalars",
                format!("{name:?}: LAS extra-dimension names hold 32 bytes at most"),
            ));
        }
    }
    let (kind, size) = match dtype {
        Dtype::F32 => (9u8, 4usize),
        Dtype::F64 => (10u8, 8usize),
    };
    let mut descriptors = Vec::with_capacity(extra.len() * DESCRIPTOR);
    for (name, _) in &extra {
        let mut d = [0u8; DESCRIPTOR];
        d[2] = kind;
        d[4..4 + name.len()].copy_from_slice(name.as_bytes());
        descriptors.extend_from_slice(&d);
    }

    let mut builder = Builder::from(Version::new(1, 4));
    let mut format = Format::new(if colour.is_some() { 7 } else { 6 }).expect("formats 6 and 7 exist");
    format.extra_bytes = u16::try_from(extra.len() * size)
        .map_err(|_| Error::invalid("scalars", format!("{} extra dimensions exceed a LAS record", extra.len())))?;
    format.is_compressed = compressed;
    builder.point_format = format;
    builder.transforms = Vector { x: transforms[0], y: transforms[1], z: transforms[2] };
    builder.generating_software = "machscan".into();
    builder.system_identifier = "machscan".into();
    if !extra.is_empty() {
        builder.vlrs.push(Vlr {
            user_id: EXTRA_USER.into(),
            record_id: EXTRA_RECORD,
            description: "machscan scalars".into(),
            data: descriptors,
        });
    }
    let header = builder.into_header().map_err(|e| Error::invalid("scalars", format!("LAS header: {e}")))?;
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, "write", &e))?;
    let write_error = |e: las::Error| match e {
        las::Error::Io(io) => Error::io(path, "write", &io),
        other => Error::invalid("scalars", format!("{}: {other}", path.display())),
    };
    let mut writer = Writer::new(BufWriter::new(file), header).map_err(write_error)?;
    // Each point field's column, looked up once rather than per point.
    let [intensity, return_number, number_of_returns, scan_direction, edge, classification] = [
        "intensity",
        "return_number",
        "number_of_returns",
        "scan_direction_flag",
        "edge_of_flight_line",
        "classification",
    ]
    .map(get);
    let [synthetic, key_point, withheld, overlap, channel, scan_angle, user_data, source, gps_time] = [
        "synthetic",
        "key_point",
        "withheld",
        "overlap",
        "scanner_channel",
        "scan_angle",
        "user_data",
        "point_source_id",
        "gps_time",
    ]
    .map(get);
    for i in 0..n {
        let value = |column: Option<&[f64]>, default: f64| column.map_or(default, |v| v[i]);
        let flag = |column: Option<&[f64]>| value(column, 0.0) != 0.0;
        let mut bytes = Vec::with_capacity(extra.len() * size);
        for (_, column) in &extra {
            dtype.put_le(&mut bytes, column[i]);
        }
        let raw_angle = value(scan_angle, 0.0);
        let point = Point {
            x: data.points[3 * i],
            y: data.points[3 * i + 1],
            z: data.points[3 * i + 2],
            intensity: value(intensity, 0.0) as u16,
            return_number: value(return_number, 1.0) as u8,
            number_of_returns: value(number_of_returns, 1.0) as u8,
            scan_direction: if flag(scan_direction) { ScanDirection::LeftToRight } else { ScanDirection::RightToLeft },
            is_edge_of_flight_line: flag(edge),
            classification: Classification::new(value(classification, 0.0) as u8)
                .map_err(|e| Error::invalid("scalars", format!("classification of point {i}: {e}")))?,
            is_synthetic: flag(synthetic),
            is_key_point: flag(key_point),
            is_withheld: flag(withheld),
            is_overlap: flag(overlap),
            scanner_channel: value(channel, 0.0) as u8,
            // The crate truncates angle / 0.006 to the stored step: half a step away from zero
            // lands on the integer given.
            scan_angle: ((raw_angle + 0.5 * raw_angle.signum()) * SCAN_ANGLE_STEP) as f32,
            user_data: value(user_data, 0.0) as u8,
            point_source_id: value(source, 0.0) as u16,
            gps_time: Some(value(gps_time, 0.0)),
            color: colour.map(|[r, g, b]| las::Color::new(r[i] as u16, g[i] as u16, b[i] as u16)),
            waveform: None,
            nir: None,
            extra_bytes: bytes,
        };
        writer.write_point(point).map_err(write_error)?;
    }
    writer.close().map_err(write_error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("machscan-las-{}-{name}", std::process::id()))
    }

    #[test]
    fn writes_and_reads_back_points_fields_extra_bytes_and_normals() {
        let pts: Vec<f64> = (0..30).map(|i| 100.0 + i as f64 * 0.3721).collect();
        let normals: Vec<f64> = (0..30).map(|i| (i % 3) as f64).collect();
        let intensity: Vec<f64> = (0..10).map(|i| i as f64 * 7.0).collect();
        let allowance: Vec<f64> = (0..10).map(|i| 0.1 + i as f64 * 1e-3).collect();
        let scalars = [("intensity", intensity.as_slice()), ("allowance", allowance.as_slice())];
        let data = CloudRef { points: &pts, normals: Some(&normals), scalars: &scalars, triangles: None };
        for (name, compressed) in [("a.las", false), ("a.laz", true)] {
            let path = temp(name);
            write_las(&path, &data, compressed, None, Dtype::F64).unwrap();
            let back = parse_las(&path, std::fs::read(&path).unwrap()).unwrap();
            std::fs::remove_file(&path).ok();
            for (a, b) in back.points.iter().zip(&pts) {
                assert!((a - b).abs() <= 0.5 * LAS_SCALE + 1e-12, "{a} {b}");
            }
            assert_eq!(back.normals.as_deref(), Some(normals.as_slice()));
            let get = |n: &str| back.scalars.iter().find(|(s, _)| s == n).unwrap().1.clone();
            assert_eq!(get("intensity"), intensity);
            assert_eq!(get("allowance"), allowance);
            assert_eq!(get("return_number"), vec![1.0; 10]);
        }
    }

    #[test]
    fn refuses_fields_out_of_range_and_spans_past_the_integers() {
        let pts = [0.0, 0.0, 0.0, 1e6, 0.0, 0.0];
        let data = CloudRef { points: &pts, ..CloudRef::default() };
        let err = write_las(&temp("span.las"), &data, false, None, Dtype::F64).unwrap_err().to_string();
        assert!(err.contains("scale"), "{err}");
        let bad = [70_000.0, 1.0];
        let scalars = [("intensity", bad.as_slice())];
        let data = CloudRef { points: &pts, scalars: &scalars, ..CloudRef::default() };
        let err = write_las(&temp("int.las"), &data, false, Some(1.0), Dtype::F64).unwrap_err().to_string();
        assert!(err.contains("intensity"), "{err}");
    }
}
