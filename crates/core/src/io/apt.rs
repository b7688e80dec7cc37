//! APT/CL toolpath files (SPEC F; paper 000 takes its scan path from the engraving program's
//! APT file; SPEC P writes grinding paths as CL).
//!
//! Reader: statements may run over several lines (a trailing `$` continues them), `$$` starts
//! a comment; `GOTO/x, y, z[, i, j, k]` gives a point (and a tool axis), `FEDRAT/f` the feed of
//! what follows, `RAPID` marks the next move rapid, which starts a new segment; other statements
//! (`PARTNO`, `MULTAX`, `PPRINT`, `CUTTER`, …) are skipped. machscan works in millimetres and
//! feeds per minute: `UNITS/INCHES` and feeds in any other unit (`FEDRAT/…, IPM`, `IPR`, `MMPR`,
//! `MMPS`, `INVERS`, …: every word but `MMPM`) are refused rather than read as mm and mm/min, and
//! so is a file without a GOTO (not a toolpath, or not this format); the writer writes none.
use crate::error::{Error, Result};
use std::path::Path;

#[derive(Debug, Clone, PartialEq, Default)]
pub struct Toolpath {
    /// `(N, 3)` row-major GOTO points, mm.
    pub points: Vec<f64>,
    /// `(N, 3)` tool axes where the GOTO gave i, j, k (NaN otherwise).
    pub axes: Vec<f64>,
    /// Feed in force at each point (NaN before any FEDRAT).
    pub feeds: Vec<f64>,
    /// Segment of each point: a new one starts after every RAPID.
    pub segments: Vec<u32>,
}

pub fn parse_apt(path: &Path, text: &str) -> Result<Toolpath> {
    let mut tp = Toolpath::default();
    let (mut feed, mut segment, mut rapid) = (f64::NAN, 0u32, false);
    let mut statement = String::new();
    let mut start_line = 0;
    // A byte-order mark (Windows editors write one) is not part of the first statement; lines
    // may end in LF, CR LF or CR alone (old Mac controllers).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text).replace("\r\n", "\n").replace('\r', "\n");
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split("$$").next().unwrap_or("").trim_end();
        if statement.is_empty() {
            start_line = k + 1;
        }
        if let Some(body) = line.strip_suffix('$') {
            statement.push_str(body);
            statement.push(' ');
            continue;
        }
        statement.push_str(line);
        let s = std::mem::take(&mut statement);
        let s = s.trim();
        if s.is_empty() {
            continue;
        }
        // The major word ends at the slash, or at the first blank where a writer left the slash out
        // (`GOTO 1, 2, 3`).
        let cut = s.find(|c: char| c == '/' || c.is_whitespace()).unwrap_or(s.len());
        let (word, args) = (s[..cut].to_ascii_uppercase(), s[cut..].trim_start().trim_start_matches('/'));
        let numbers = |what: &str| -> Result<Vec<f64>> {
            let mut values = Vec::new();
            for field in args.split(',') {
                let field = field.trim();
                if field.is_empty() {
                    // `GOTO/1,,2,3`: a value left out, not a separator to skip.
                    return Err(Error::format(path, format!("line {start_line}: {what}: an empty value in {args:?}")));
                }
                for t in field.split_whitespace() {
                    match t.parse::<f64>() {
                        // Rust reads "nan", "inf" and 1e400 as numbers; no machine can go there.
                        Ok(v) if v.is_finite() => values.push(v),
                        _ => {
                            return Err(Error::format(
                                path,
                                format!("line {start_line}: {what}: {t:?} is not a finite number"),
                            ))
                        }
                    }
                }
            }
            Ok(values)
        };
        match word.as_str() {
            "GOTO" => {
                let v = numbers("GOTO")?;
                if v.len() != 3 && v.len() != 6 {
                    return Err(Error::format(
                        path,
                        format!("line {start_line}: GOTO needs x, y, z or x, y, z, i, j, k; got {} values", v.len()),
                    ));
                }
                if rapid && !tp.segments.is_empty() {
                    segment += 1;
                }
                rapid = false;
                if v.len() == 6 && v[3..].iter().all(|&c| c == 0.0) {
                    return Err(Error::format(
                        path,
                        format!("line {start_line}: GOTO tool axis (0, 0, 0) is not a direction"),
                    ));
                }
                tp.points.extend_from_slice(&v[..3]);
                tp.axes.extend_from_slice(if v.len() == 6 { &v[3..6] } else { &[f64::NAN; 3] });
                tp.feeds.push(feed);
                tp.segments.push(segment);
            }
            "UNITS" => {
                let unit = args.trim().to_ascii_uppercase();
                if !matches!(unit.as_str(), "MM" | "MILLIMETERS" | "MILLIMETRES") {
                    return Err(Error::format(
                        path,
                        format!("line {start_line}: UNITS/{}: machscan reads toolpaths in millimetres (UNITS/MM); convert the file", args.trim()),
                    ));
                }
            }
            "FEDRAT" => {
                // FEDRAT/f, FEDRAT/MMPM, f or FEDRAT/f, MMPM: the number is the feed, per minute. A
                // RAPTO part (the feed of rapid approaches, in some CLSF dialects) is not this feed.
                let words: Vec<&str> = args
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|t| !t.is_empty())
                    .take_while(|t| !t.eq_ignore_ascii_case("RAPTO"))
                    .collect();
                // Only mm per minute is read: IPM, IPR, MMPR, MMPS, INVERS… would be taken for it.
                if let Some(mode) = words.iter().find(|t| t.parse::<f64>().is_err() && !t.eq_ignore_ascii_case("MMPM"))
                {
                    return Err(Error::format(
                        path,
                        format!("line {start_line}: FEDRAT in {mode}: machscan reads feeds in mm per minute (MMPM)"),
                    ));
                }
                let v: Vec<f64> = words.iter().filter_map(|t| t.parse::<f64>().ok()).collect();
                feed = match v[..] {
                    [f] => f,
                    [] => return Err(Error::format(path, format!("line {start_line}: FEDRAT without a feed"))),
                    _ => {
                        return Err(Error::format(
                            path,
                            format!("line {start_line}: FEDRAT/{}: more than one feed", args.trim()),
                        ))
                    }
                };
                if !(feed.is_finite() && feed > 0.0) {
                    return Err(Error::format(
                        path,
                        format!("line {start_line}: FEDRAT {feed}: a feed is a positive number"),
                    ));
                }
            }
            "RAPID" => rapid = true,
            _ => {}
        }
    }
    if !statement.trim().is_empty() {
        return Err(Error::format(
            path,
            format!("line {start_line}: the last statement is continued ($) past the end of the file"),
        ));
    }
    if tp.points.is_empty() {
        return Err(Error::format(path, "no GOTO statement: not an APT/CL toolpath"));
    }
    Ok(tp)
}

pub fn read_apt(path: &Path) -> Result<Toolpath> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", &e))?;
    let text = String::from_utf8_lossy(&bytes);
    parse_apt(path, &text)
}

/// Writes a CL file: `GOTO/x, y, z[, i, j, k]` per point (tool axes when given), `FEDRAT/MMPM,f`
/// (`feeds` in mm per minute, the unit word written so no post-processor has to assume it)
/// whenever the feed changes, `RAPID` before the first point of every segment but the first
/// (`segments` labels each point; a new label starts a segment).
pub fn write_apt(
    path: &Path,
    points: &[f64],
    axes: Option<&[f64]>,
    feeds: Option<&[f64]>,
    segments: Option<&[f64]>,
) -> Result<()> {
    use std::io::Write;
    let n = points.len() / 3;
    if n == 0 {
        // A CL file without a GOTO is not a toolpath (the reader refuses one).
        return Err(Error::invalid("points", "no points to write"));
    }
    crate::error::check_finite("points", points, 3)?;
    if let Some(a) = axes {
        if a.len() != points.len() {
            return Err(Error::shape(
                "axes",
                format!("({n}, 3): one tool axis per point"),
                format!("({}, 3)", a.len() / 3),
            ));
        }
        // A row of NaN is a point without a tool axis (as the reader gives a GOTO of x, y, z):
        // it is written so. Anything else must be a direction.
        for (i, r) in a.chunks_exact(3).enumerate() {
            if r.iter().all(|v| v.is_nan()) {
                continue;
            }
            if !r.iter().all(|v| v.is_finite()) {
                return Err(Error::invalid(
                    "axes",
                    format!("row {i} is {r:?}: a tool axis is finite, or all NaN for a point without one"),
                ));
            }
            if r.iter().map(|v| v * v).sum::<f64>() == 0.0 {
                return Err(Error::invalid("axes", format!("row {i} is (0, 0, 0), not a direction")));
            }
        }
    }
    for (name, v) in [("feeds", feeds), ("segments", segments)] {
        if let Some(v) = v {
            if v.len() != n {
                return Err(Error::shape(name, format!("({n},): one per point"), format!("({},)", v.len())));
            }
        }
    }
    if let Some(s) = segments {
        crate::error::check_finite("segments", s, 1)?;
    }
    if let Some(f) = feeds {
        // NaN stands for "no feed yet" (as read before the first FEDRAT); once a FEDRAT is
        // written a CL file keeps it, so a NaN after a feed could not be written back.
        let first = f.iter().position(|v| !v.is_nan()).unwrap_or(n);
        if let Some(i) = (first..n).find(|&i| !(f[i].is_finite() && f[i] > 0.0)) {
            let why = if f[i].is_nan() { "NaN (no feed) after a feed was given" } else { "not a positive finite feed" };
            return Err(Error::invalid("feeds", format!("point {i}: {} is {why}", f[i])));
        }
    }
    let io = |e: std::io::Error| Error::io(path, "write", &e);
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    // The units said in the file, so that a post-processor assumes neither: mm, feeds per minute.
    writeln!(w, "PARTNO/ MACHSCAN TOOLPATH\n$$ written by machscan {}\nUNITS/MM", env!("CARGO_PKG_VERSION"))
        .map_err(io)?;
    if axes.is_some() {
        writeln!(w, "MULTAX").map_err(io)?;
    }
    let mut last_feed = f64::NAN;
    for i in 0..n {
        if let Some(s) = segments {
            if i > 0 && s[i] != s[i - 1] {
                writeln!(w, "RAPID").map_err(io)?;
            }
        }
        if let Some(f) = feeds {
            if f[i].is_finite() && f[i] != last_feed {
                writeln!(w, "FEDRAT/MMPM,{}", f[i]).map_err(io)?;
                last_feed = f[i];
            }
        }
        let p = &points[3 * i..3 * i + 3];
        match axes.map(|a| &a[3 * i..3 * i + 3]) {
            Some(a) if !a[0].is_nan() => writeln!(w, "GOTO/{},{},{},{},{},{}", p[0], p[1], p[2], a[0], a[1], a[2]),
            _ => writeln!(w, "GOTO/{},{},{}", p[0], p[1], p[2]),
        }
        .map_err(io)?;
    }
    writeln!(w, "FINI").map_err(io)?;
    w.flush().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_what_post_processors_write() {
        let text = "PARTNO/ DEMO $$ a comment\nMULTAX\nFEDRAT/MMPM, 1200\nGOTO/1,2,3, $\n  0,0,1\nGOTO/4,5,6,0,0,1\nRAPID\nGOTO/10,10,10\nFEDRAT/800\nGOTO/11,10,10\nFINI\n";
        let tp = parse_apt(Path::new("t.apt"), text).unwrap();
        assert_eq!(tp.points, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 10.0, 10.0, 10.0, 11.0, 10.0, 10.0]);
        assert_eq!(tp.segments, vec![0, 0, 1, 1]);
        assert_eq!(&tp.feeds[..3], &[1200.0, 1200.0, 1200.0]);
        assert_eq!(tp.feeds[3], 800.0);
        assert!(tp.axes[6].is_nan() && tp.axes[2] == 1.0);
        assert!(parse_apt(Path::new("t.apt"), "GOTO/1,2\n").is_err());
        assert!(parse_apt(Path::new("t.apt"), "GOTO/1,2,x\n").is_err());
        assert!(parse_apt(Path::new("t.apt"), "GOTO/1,2, $\n").is_err());
        assert!(parse_apt(Path::new("t.apt"), "GOTO/1,,2,3\n").is_err());
        assert!(parse_apt(Path::new("t.apt"), "GOTO/1,2,3,\n").is_err());
    }

    #[test]
    fn reads_a_byte_order_mark_any_line_ending_and_a_left_out_slash() {
        let points = |text: &str| parse_apt(Path::new("t.apt"), text).unwrap().points;
        let two = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        assert_eq!(points("\u{feff}GOTO/1,2,3\nGOTO/4,5,6\n"), two);
        assert_eq!(points("PARTNO/X\rGOTO/1,2,3\rGOTO/4,5,6\r"), two);
        assert_eq!(points("PARTNO/X\r\nGOTO/1,2,3 $\r\n ,0,0,1\r\n"), vec![1.0, 2.0, 3.0]);
        assert_eq!(points("GOTO 1, 2, 3\ngoto/4 5 6\n"), two);
        let feeds = parse_apt(Path::new("t.apt"), "\u{feff}FEDRAT/50\nGOTO/1,2,3\n").unwrap().feeds;
        assert_eq!(feeds, vec![50.0]);
        assert!(parse_apt(Path::new("t.apt"), "GOTO/1,2,3,0,0,0\n").is_err());
    }

    /// Inches and feeds per revolution are refused, not read as mm and mm/min; a file without a
    /// GOTO is not a toolpath.
    #[test]
    fn refuses_other_units_and_files_without_a_goto() {
        let read = |text: &str| parse_apt(Path::new("t.apt"), text);
        assert!(read("UNITS/MM\nFEDRAT/MMPM,500\nFEDRAT/300,MMPM\nGOTO/1,2,3\n").is_ok());
        let rapto = read("FEDRAT/MMPM,1200,RAPTO,500\nGOTO/1,2,3\n").unwrap();
        assert_eq!(rapto.feeds, vec![1200.0]);
        for text in [
            "UNITS/INCHES\nGOTO/1,2,3\n",
            "FEDRAT/IPM,50\nGOTO/1,2,3\n",
            "FEDRAT/0.2,MMPR\nGOTO/1,2,3\n",
            "FEDRAT/MMPS,20\n",
        ] {
            let e = read(text).unwrap_err().to_string();
            assert!(e.contains("t.apt") && e.contains("line 1"), "{e}");
        }
        for text in ["", "PARTNO/X\nFINI\n", "ply\nformat ascii 1.0\nend_header\n1 2 3\n"] {
            assert!(read(text).unwrap_err().to_string().contains("no GOTO"), "{text:?}");
        }
    }

    /// What the reader gives, the writer takes back: points with and without tool axes mixed.
    #[test]
    fn a_path_read_is_written_back_as_it_was() {
        let dir = std::env::temp_dir().join(format!("machscan-apt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("mixed.cl");
        let text = "FEDRAT/800\nGOTO/1,2,3,0,0,1\nGOTO/4,5,6\nRAPID\nGOTO/7,8,9,0,1,0\n";
        let tp = parse_apt(Path::new("t.apt"), text).unwrap();
        let segments: Vec<f64> = tp.segments.iter().map(|&s| s as f64).collect();
        write_apt(&path, &tp.points, Some(&tp.axes), Some(&tp.feeds), Some(&segments)).unwrap();
        let back = read_apt(&path).unwrap();
        let written = std::fs::read_to_string(&path).unwrap();
        assert!(written.contains("UNITS/MM\n") && written.contains("FEDRAT/MMPM,800\n"), "{written}");
        assert_eq!(back.points, tp.points);
        assert_eq!((back.feeds, back.segments), (tp.feeds, tp.segments));
        assert!(back.axes.iter().zip(&tp.axes).all(|(a, b)| a == b || (a.is_nan() && b.is_nan())));
        let (half_nan, zero) = ([0.0, f64::NAN, 1.0], [0.0; 3]);
        assert!(write_apt(&path, &tp.points[..3], Some(&half_nan), None, None).is_err());
        assert!(write_apt(&path, &tp.points[..3], Some(&zero), None, None).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
