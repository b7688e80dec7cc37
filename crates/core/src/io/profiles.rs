//! Line-profiler exports: the files plants already have from their profilers' own software,
//! read into frames of heights on a fixed x grid (what a `Scan` holds).
//!
//! - LMI Gocator CSV (Gocator line-profiler user manual, "CSV File Format"): sections, each a
//!   line with its name and closed by `End` — `Info` (XResolution, YResolution, ZResolution, mm),
//!   `DeviceInfo` (ID = serial, Model), then the data. `Profile` (resampled profiles): an
//!   attribute header and row (Frame Count, Column Count, X/Y/Z Offset), then a data header
//!   `Frame, Source, Time, Encoder, Z Encoder, Inputs, Exposure, Y, Axis, x0, x1, …` whose cells
//!   after `Axis` are the readings' x (mm), and a row per frame and axis (`Z` heights in mm, `I`
//!   intensities, skipped). `Part` (a resampled surface): an attribute row (Frame, Source, Time,
//!   Encoder, …, Row Count, Column Count, X/Y/Z Offset), a grid header `Y\X, x0, x1, …`, and a
//!   row per y: `y, z0, z1, …`. Values are mm with the offsets applied; an empty cell (or `-`)
//!   is no reading. `RawProfile` and `SurfacePointCloud` (points not on an x grid) are refused:
//!   a `Scan` is readings on a grid.
//! - Keyence LJ-X / LJ-V height exports as the communication library's samples write them
//!   (`…_height.csv`): one profile per line, tab (or comma) separated, UTF-16 or ASCII, no
//!   header. Integers are heights in 0.01 µm, the codes −2147483648…−2147483645 (alarm,
//!   invalid, blind, unprocessed) and their 20-bit forms −524288…−524285 no reading; numbers
//!   with a decimal point are mm, as LJ-Navigator writes them, with −999.99… no reading. The file
//!   holds neither the x grid nor the frame spacing: the caller gives them.
use crate::error::{Error, Result};
use std::path::Path;

/// One profiler export.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProfileExport {
    /// "Gocator Profile", "Gocator Part" or "Keyence height".
    pub layout: String,
    /// The readings' x, mm (empty for a Keyence file: the caller's grid).
    pub x: Vec<f64>,
    /// Heights, frame by frame (`frames` × readings), mm; NaN where there is no reading.
    pub heights: Vec<f64>,
    pub frames: usize,
    /// Per frame, where the file has them: the position along the scan (mm), the time stamp
    /// (µs, as written), the encoder count, the sensor's frame index.
    pub y: Option<Vec<f64>>,
    pub time: Option<Vec<f64>>,
    pub encoder: Option<Vec<f64>>,
    pub frame: Option<Vec<f64>>,
    /// Info and DeviceInfo: XResolution, YResolution (mm), model, serial.
    pub x_resolution: Option<f64>,
    pub y_resolution: Option<f64>,
    pub model: Option<String>,
    pub serial: Option<String>,
}

/// Reads a Gocator CSV or Keyence height export, by content.
pub fn read_profiles(path: &Path) -> Result<ProfileExport> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", &e))?;
    parse_profiles(path, &bytes)
}

/// Parses the bytes of a profile export (`read_profiles`).
pub fn parse_profiles(path: &Path, bytes: &[u8]) -> Result<ProfileExport> {
    let text = decode(bytes);
    let lines: Vec<&str> =
        text.lines().map(|l| l.trim_end_matches(['\r', '\u{feff}']).trim_start_matches('\u{feff}')).collect();
    let first = lines.iter().position(|l| !l.trim().is_empty());
    let Some(first) = first else {
        return Err(Error::format(path, "is empty: expected a Gocator CSV export or a Keyence height export"));
    };
    let head = lines[first].trim();
    if head.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) {
        gocator(path, &lines)
    } else {
        keyence(path, &lines, first)
    }
}

/// The text of the file: UTF-16 when it starts with a byte-order mark or its second byte is a
/// NUL (the Keyence samples write UTF-16), UTF-8 where it is, else Latin-1.
fn decode(bytes: &[u8]) -> String {
    let utf16 = |le: bool, body: &[u8]| {
        let units: Vec<u16> = body
            .chunks_exact(2)
            .map(|c| if le { u16::from_le_bytes([c[0], c[1]]) } else { u16::from_be_bytes([c[0], c[1]]) })
            .collect();
        String::from_utf16_lossy(&units)
    };
    match bytes {
        [0xff, 0xfe, rest @ ..] => utf16(true, rest),
        [0xfe, 0xff, rest @ ..] => utf16(false, rest),
        [a, 0, ..] if *a != 0 => utf16(true, bytes),
        [0, b, ..] if *b != 0 => utf16(false, bytes),
        _ => match std::str::from_utf8(bytes) {
            Ok(s) => s.to_string(),
            Err(_) => bytes.iter().map(|&b| b as char).collect(),
        },
    }
}

fn cells(line: &str) -> Vec<&str> {
    line.split(',').map(str::trim).collect()
}

/// A cell's number: None for an empty cell or `-` (no reading); an error naming the line and
/// column for anything else that is not a number.
fn number(path: &Path, line: usize, column: usize, cell: &str, what: &str) -> Result<Option<f64>> {
    if cell.is_empty() || cell == "-" {
        return Ok(None);
    }
    match cell.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        _ => Err(Error::format(path, format!("line {line}, column {}: expected {what}, got {cell:?}", column + 1))),
    }
}

/// A Gocator section: its name, the 1-based line of its name, and its lines up to `End`.
struct Section<'a> {
    name: &'a str,
    line: usize,
    body: Vec<&'a str>,
}

fn sections<'a>(path: &Path, lines: &[&'a str]) -> Result<Vec<Section<'a>>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let name = lines[i].trim().trim_end_matches(',');
        if name.is_empty() {
            i += 1;
            continue;
        }
        if name.contains(',') {
            return Err(Error::format(
                path,
                format!(
                    "line {}: expected the name of a section (Info, DeviceInfo, Profile, Part, …), got {name:?}",
                    i + 1
                ),
            ));
        }
        let start = i;
        let mut body = Vec::new();
        i += 1;
        while i < lines.len() && lines[i].trim().trim_end_matches(',') != "End" {
            body.push(lines[i]);
            i += 1;
        }
        if i == lines.len() {
            return Err(Error::format(path, format!("line {}: section {name} has no End line", start + 1)));
        }
        out.push(Section { name, line: start + 1, body });
        i += 1;
    }
    Ok(out)
}

/// The value under `key` in a header line and a value line (None when absent or empty).
fn field(path: &Path, s: &Section, header: usize, key: &str) -> Result<Option<f64>> {
    let (Some(h), Some(v)) = (s.body.get(header), s.body.get(header + 1)) else { return Ok(None) };
    let (h, v) = (cells(h), cells(v));
    match h.iter().position(|c| c.eq_ignore_ascii_case(key)) {
        Some(k) => number(path, s.line + header + 2, k, v.get(k).copied().unwrap_or(""), key),
        None => Ok(None),
    }
}

fn gocator(path: &Path, lines: &[&str]) -> Result<ProfileExport> {
    let all = sections(path, lines)?;
    let find = |name: &str| all.iter().find(|s| s.name.eq_ignore_ascii_case(name));
    let mut out = ProfileExport::default();
    if let Some(info) = find("Info") {
        out.x_resolution = field(path, info, 0, "XResolution")?;
        out.y_resolution = field(path, info, 0, "YResolution")?;
    }
    if let Some(dev) = find("DeviceInfo") {
        if let (Some(h), Some(v)) = (dev.body.first(), dev.body.get(1)) {
            let (h, v) = (cells(h), cells(v));
            let text = |key: &str| {
                h.iter().position(|c| c.eq_ignore_ascii_case(key)).and_then(|k| v.get(k)).map(|s| s.to_string())
            };
            out.model = text("Model");
            out.serial = text("ID");
        }
    }
    for refused in ["RawProfile", "SurfacePointCloud"] {
        if let (Some(s), None, None) = (find(refused), find("Profile"), find("Part")) {
            return Err(Error::format(
                path,
                format!(
                    "line {}: a {refused} section holds points that are not on an x grid; machscan reads the \
                     resampled Profile or Part sections (export with uniform spacing on)",
                    s.line
                ),
            ));
        }
    }
    if let Some(s) = find("Profile") {
        gocator_profile(path, s, &mut out)?;
    } else if let Some(s) = find("Part") {
        gocator_part(path, s, &mut out)?;
    } else {
        let names: Vec<&str> = all.iter().map(|s| s.name).collect();
        return Err(Error::format(
            path,
            format!("expected a Profile or Part section (a Gocator CSV export), found {}", names.join(", ")),
        ));
    }
    Ok(out)
}

/// The `Profile` section: attribute header and row, data header, rows per frame and axis.
fn gocator_profile(path: &Path, s: &Section, out: &mut ProfileExport) -> Result<()> {
    out.layout = "Gocator Profile".into();
    // The data header is the line naming an Axis column (after the attribute header and row
    // the manual shows; found by its content, so an export without them reads too).
    let Some(at) = s.body.iter().position(|l| cells(l).iter().any(|c| c.eq_ignore_ascii_case("Axis"))) else {
        return Err(Error::format(
            path,
            format!(
                "line {}: expected the Profile data header (Frame, Source, Time, …, Y, Axis, x…) in the section",
                s.line + 1
            ),
        ));
    };
    let names = cells(s.body[at]);
    let header_line = s.line + at + 1;
    let axis = names.iter().position(|c| c.eq_ignore_ascii_case("Axis")).unwrap_or(0);
    let col = |key: &str| names[..axis].iter().position(|c| c.eq_ignore_ascii_case(key));
    out.x = names[axis + 1..]
        .iter()
        .enumerate()
        .filter(|(_, c)| !c.is_empty())
        .map(|(k, c)| x_position(path, header_line, axis + 1 + k, c))
        .collect::<Result<_>>()?;
    let n = out.x.len();
    if n == 0 {
        return Err(Error::format(path, format!("line {header_line}: the Profile data header names no x position")));
    }
    let (source, time, encoder, y, frame) = (col("Source"), col("Time"), col("Encoder"), col("Y"), col("Frame"));
    let (mut ys, mut ts, mut es, mut fs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut first_source: Option<String> = None;
    for (k, line) in s.body[at + 1..].iter().enumerate() {
        let at = header_line + 1 + k;
        if line.trim().is_empty() {
            continue;
        }
        let c = cells(line);
        if c.get(axis).is_none_or(|a| !a.eq_ignore_ascii_case("Z")) {
            continue; // intensity rows
        }
        if let Some(i) = source {
            let here = c.get(i).copied().unwrap_or("").to_string();
            match &first_source {
                None => first_source = Some(here),
                Some(f) if *f != here => {
                    return Err(Error::format(
                        path,
                        format!(
                        "line {at}: rows of source {here} after source {f}: an export of several sensors is not one \
                             scan; export each sensor on its own"
                    ),
                    ))
                }
                _ => {}
            }
        }
        let values = &c[axis + 1..];
        if values.len() < n || values[n..].iter().any(|v| !v.is_empty()) {
            return Err(Error::format(
                path,
                format!("line {at}: expected {n} heights after the Axis column, got {}", values.len()),
            ));
        }
        for (j, v) in values[..n].iter().enumerate() {
            out.heights.push(number(path, at, axis + 1 + j, v, "a height (mm)")?.unwrap_or(f64::NAN));
        }
        let get = |i: Option<usize>, what: &str| -> Result<Option<f64>> {
            match i {
                Some(i) => number(path, at, i, c.get(i).copied().unwrap_or(""), what),
                None => Ok(None),
            }
        };
        ys.push(get(y, "Y (mm)")?);
        ts.push(get(time, "a time stamp")?);
        es.push(get(encoder, "an encoder count")?);
        fs.push(get(frame, "a frame index")?);
        out.frames += 1;
    }
    if out.frames == 0 {
        return Err(Error::format(path, format!("line {}: the Profile section holds no Z row", s.line)));
    }
    let whole = |v: Vec<Option<f64>>| v.iter().all(Option::is_some).then(|| v.into_iter().flatten().collect());
    (out.y, out.time, out.encoder, out.frame) = (whole(ys), whole(ts), whole(es), whole(fs));
    Ok(())
}

/// A header cell that must be a reading's x (a `-` is not one).
fn x_position(path: &Path, line: usize, column: usize, cell: &str) -> Result<f64> {
    number(path, line, column, cell, "an x position (mm)")?.ok_or_else(|| {
        Error::format(path, format!("line {line}, column {}: expected an x position (mm), got {cell:?}", column + 1))
    })
}

/// The `Part` section: attribute header and row, then the grid `Y\X, x…` and a row per y.
fn gocator_part(path: &Path, s: &Section, out: &mut ProfileExport) -> Result<()> {
    out.layout = "Gocator Part".into();
    let rows = field(path, s, 0, "Row Count")?;
    let time = field(path, s, 0, "Time")?;
    let encoder = field(path, s, 0, "Encoder")?;
    let Some(grid) = s.body.iter().position(|l| cells(l).first().is_some_and(|c| c.eq_ignore_ascii_case("Y\\X")))
    else {
        return Err(Error::format(path, format!("line {}: the Part section has no grid header (Y\\X, x…)", s.line)));
    };
    let header_line = s.line + grid + 2;
    let names = cells(s.body[grid]);
    let last = names.iter().rposition(|c| !c.is_empty()).unwrap_or(0);
    out.x = names[1..=last]
        .iter()
        .enumerate()
        .map(|(k, c)| x_position(path, header_line, k + 1, c))
        .collect::<Result<_>>()?;
    let n = out.x.len();
    if n == 0 {
        return Err(Error::format(path, format!("line {header_line}: the grid header names no x position")));
    }
    let mut ys = Vec::new();
    for (k, line) in s.body[grid + 1..].iter().enumerate() {
        let at = header_line + 1 + k;
        if line.trim().is_empty() {
            continue;
        }
        let c = cells(line);
        let Some(y) = number(path, at, 0, c[0], "the row's y (mm)")? else {
            return Err(Error::format(path, format!("line {at}: a grid row without its y")));
        };
        if c.len() - 1 < n || c[n + 1..].iter().any(|v| !v.is_empty()) {
            return Err(Error::format(path, format!("line {at}: expected {n} heights after y, got {}", c.len() - 1)));
        }
        for (j, v) in c[1..=n].iter().enumerate() {
            out.heights.push(number(path, at, j + 1, v, "a height (mm)")?.unwrap_or(f64::NAN));
        }
        ys.push(y);
        out.frames += 1;
    }
    if let Some(r) = rows {
        if r != out.frames as f64 {
            return Err(Error::format(
                path,
                format!("line {}: Row Count says {r} rows, the grid holds {}", s.line + 2, out.frames),
            ));
        }
    }
    if out.frames == 0 {
        return Err(Error::format(path, format!("line {header_line}: the grid holds no row")));
    }
    out.y = Some(ys);
    // One snapshot: every row has the part's time and encoder count.
    out.time = time.map(|t| vec![t; out.frames]);
    out.encoder = encoder.map(|e| vec![e; out.frames]);
    Ok(())
}

/// Keyence height rows: a profile per line.
fn keyence(path: &Path, lines: &[&str], first: usize) -> Result<ProfileExport> {
    let mut heights = Vec::new();
    let mut n = None;
    let mut frames = 0;
    for (k, line) in lines.iter().enumerate().skip(first) {
        if line.trim().is_empty() {
            continue;
        }
        let at = k + 1;
        let delimiter = if line.contains('\t') { '\t' } else { ',' };
        let mut cells: Vec<&str> = line.split(delimiter).map(str::trim).collect();
        while cells.last().is_some_and(|c| c.is_empty()) {
            cells.pop(); // the samples end every value with a tab
        }
        match n {
            None => n = Some(cells.len()),
            Some(m) if m != cells.len() => {
                return Err(Error::format(
                    path,
                    format!("line {at}: {} values, expected {m} as on the first profile", cells.len()),
                ))
            }
            _ => {}
        }
        for (j, c) in cells.iter().enumerate() {
            heights.push(keyence_height(path, at, j, c)?);
        }
        frames += 1;
    }
    Ok(ProfileExport { layout: "Keyence height".into(), heights, frames, ..ProfileExport::default() })
}

/// A Keyence value in mm, NaN for the no-reading codes (module docs).
fn keyence_height(path: &Path, line: usize, column: usize, cell: &str) -> Result<f64> {
    let bad = || {
        Error::format(
            path,
            format!(
                "line {line}, column {}: expected a height (an integer in 0.01 µm, or mm with a decimal point), got {cell:?}",
                column + 1
            ),
        )
    };
    if cell.contains(['.', 'e', 'E']) {
        let v: f64 = cell.parse().map_err(|_| bad())?;
        if !v.is_finite() {
            return Err(bad());
        }
        return Ok(if v <= -999.99 { f64::NAN } else { v });
    }
    let v: i64 = cell.parse().map_err(|_| bad())?;
    Ok(match v {
        -2_147_483_648..=-2_147_483_645 | -524_288..=-524_285 => f64::NAN,
        _ => v as f64 * 1e-5,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const PROFILE: &str = "Info\n\
CSV Version,Sensor Count,Trigger Mode,Trigger Rate,Trigger Delay Domain,Trigger Delay,Operation Mode,XResolution,YResolution,ZResolution,YSpeed,Layout\n\
2,1,1,200.00000,0,0.00000,2,0.10000,0.20000,0.00200,20.00000,0\n\
End\n\
\n\
DeviceInfo\n\
ID,Model,Version,Exposure Mode\n\
41234,2340,5.3.19.50,0\n\
End\n\
\n\
Profile\n\
Frame Count,Column Count,X Offset,Y Offset,Z Offset\n\
2,4,-0.15000,0.00000,0.00000\n\
Frame,Source,Time,Encoder,Z Encoder,Inputs,Exposure,Y,Axis,-0.15000,-0.05000,0.05000,0.15000\n\
0,0,1024000,0,0,0,250,0.00000,Z,12.50100,12.49800,,12.50300\n\
0,0,1024000,0,0,0,250,0.00000,I,100,120,0,90\n\
1,0,1029120,100,0,0,250,0.20000,Z,12.50000,-,12.49900,12.50200\n\
End\n";

    #[test]
    fn a_gocator_profile_export_reads_its_grid_heights_and_frame_columns() {
        let p = parse_profiles(Path::new("p.csv"), PROFILE.as_bytes()).unwrap();
        assert_eq!(p.layout, "Gocator Profile");
        assert_eq!(p.x, vec![-0.15, -0.05, 0.05, 0.15]);
        assert_eq!(p.frames, 2);
        assert_eq!(p.heights[..2], [12.501, 12.498]);
        assert!(p.heights[2].is_nan() && p.heights[5].is_nan());
        assert_eq!(p.y, Some(vec![0.0, 0.2]));
        assert_eq!(p.time, Some(vec![1024000.0, 1029120.0]));
        assert_eq!(p.encoder, Some(vec![0.0, 100.0]));
        assert_eq!((p.x_resolution, p.y_resolution), (Some(0.1), Some(0.2)));
        assert_eq!((p.model.as_deref(), p.serial.as_deref()), (Some("2340"), Some("41234")));
        // UTF-16 with a byte-order mark and CRLF lines read the same.
        let mut utf16 = vec![0xff, 0xfe];
        for u in PROFILE.replace('\n', "\r\n").encode_utf16() {
            utf16.extend(u.to_le_bytes());
        }
        // (Compared as text: NaN is not equal to itself.)
        assert_eq!(format!("{:?}", parse_profiles(Path::new("p.csv"), &utf16).unwrap()), format!("{p:?}"));
    }

    #[test]
    fn a_profile_section_without_its_attribute_rows_reads_too() {
        let text = "Profile\nFrame,Time,Y,Axis,0.0,0.1\n0,10,0.0,Z,1.0,1.5\n1,20,0.2,Z,,1.25\nEnd\n";
        let p = parse_profiles(Path::new("p.csv"), text.as_bytes()).unwrap();
        assert_eq!((p.frames, p.x.clone(), p.y.clone()), (2, vec![0.0, 0.1], Some(vec![0.0, 0.2])));
        assert!(p.heights[2].is_nan() && p.heights[3] == 1.25);
    }

    #[test]
    fn a_gocator_part_grid_reads_a_frame_per_row() {
        let text = "Part\n\
Frame,Source,Time,Encoder,Z Encoder,Inputs,Row Count,Column Count,X Offset,Y Offset,Z Offset\n\
1,0,544820424776,7,0,0,2,3,-0.30000,-0.30000,1.69400\n\
Y\\X,-0.30000,0.00000,0.30000\n\
-0.30000,,27.95300,27.93500\n\
0.00000,27.88100,,27.86600\n\
End\n";
        let p = parse_profiles(Path::new("s.csv"), text.as_bytes()).unwrap();
        assert_eq!((p.layout.as_str(), p.frames, p.x.len()), ("Gocator Part", 2, 3));
        assert_eq!(p.y, Some(vec![-0.3, 0.0]));
        assert_eq!(p.encoder, Some(vec![7.0, 7.0]));
        assert!(p.heights[0].is_nan() && p.heights[4].is_nan() && p.heights[1] == 27.953);
    }

    #[test]
    fn keyence_heights_are_read_in_mm_with_the_codes_dropped() {
        let text = "1234500\t1234800\t-2147483648\t1235100\t\n1234400\t-524288\t1234950\t-2147483645\t\n";
        let p = parse_profiles(Path::new("k_height.csv"), text.as_bytes()).unwrap();
        assert_eq!((p.layout.as_str(), p.frames), ("Keyence height", 2));
        assert!((p.heights[0] - 12.345).abs() < 1e-12 && p.heights[2].is_nan());
        assert!(p.heights[5].is_nan() && p.heights[7].is_nan());
        let mm = parse_profiles(Path::new("k.csv"), b"12.5,-999.999,12.25\n").unwrap();
        assert!(mm.heights[1].is_nan() && mm.heights[2] == 12.25);
    }

    #[test]
    fn malformed_exports_name_the_file_the_line_and_what_was_expected() {
        let cases: [(&str, &str); 6] = [
            (
                "Profile\nFrame Count\n1\nFrame,Y,Axis,0.0,0.1\n0,0,Z,1.0,abc\nEnd\n",
                "line 5, column 5: expected a height",
            ),
            ("Profile\nFrame Count\n1\nFrame,Y,Axis,0.0,0.1\n0,0,Z,1.0\nEnd\n", "line 5: expected 2 heights"),
            ("Info\nX\n1\n", "section Info has no End"),
            ("RawProfile\na\nb\nEnd\n", "not on an x grid"),
            ("Info\nX\n1\nEnd\n", "expected a Profile or Part section"),
            ("1,2,3\n1,2\n", "line 2: 2 values, expected 3"),
        ];
        for (text, want) in cases {
            let e = parse_profiles(Path::new("bad.csv"), text.as_bytes()).unwrap_err().to_string();
            assert!(e.contains("bad.csv") && e.contains(want), "{e}");
        }
    }
}
