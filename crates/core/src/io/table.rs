//! The one reader of numeric tables (CSV, TSV, whitespace): a plant's exports of frames and
//! poses, probe plans, locating and matching points, contours. One set of rules, so that every
//! table machscan reads is read alike and every problem is named by file and line:
//!
//! - blank lines are skipped; `#` starts a comment anywhere on a line, as does `//` at its start;
//! - the first line left may be a header: it is one when a cell of it is not a number and it
//!   holds a letter (`x,y,z`, `t,X,Y,Z,A,C,C2`); any other line that is not numbers is an error;
//! - a line that is not UTF-8 is read as Latin-1, so a header or comment written in cp1252
//!   (`Höhe µm`, `°`) reads; numbers are ASCII either way;
//! - cells split on the delimiter given (each cell trimmed; an empty cell is an error, but a
//!   delimiter ending the line is not, as spreadsheets write them), or with none given on runs
//!   of whitespace and commas;
//! - every data row has as many cells as the first, and that count is one the caller takes;
//! - values are finite except in the columns a caller lets hold NaN (missing readings).
use crate::error::{Error, Result};
use std::path::Path;

/// How a table is read: the argument it is named by in messages, the delimiter (None: runs of
/// whitespace and commas), the column counts taken (empty: any), which columns may hold values
/// that are not finite (None: every column), and the most data rows read (None: all; the rest
/// of the file is not looked at).
#[derive(Debug, Clone, Copy)]
pub struct TableOptions<'a> {
    pub name: &'a str,
    pub delimiter: Option<char>,
    pub widths: &'a [usize],
    pub nan_columns: Option<&'a [usize]>,
    pub max_rows: Option<usize>,
}

/// A numeric table: `values` row-major with `columns` per row, the 1-based line of the file each
/// row came from, and the header's cells when the file has one.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub values: Vec<f64>,
    pub columns: usize,
    pub lines: Vec<usize>,
    pub header: Option<Vec<String>>,
}

impl Table {
    pub fn rows(&self) -> usize {
        self.lines.len()
    }
}

/// Reads the table in `path` (module docs). The OS's refusal is an `Error::Io`; a content that
/// breaks the rules an `Error::Format` naming the file, the line (and column) and `name`.
pub fn read_table(path: &Path, options: &TableOptions) -> Result<Table> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", &e))?;
    parse_table(path, &bytes, options)
}

/// A line as text: UTF-8 where it is, else Latin-1 (every byte a character).
fn decode(line: &[u8]) -> String {
    match std::str::from_utf8(line) {
        Ok(s) => s.to_string(),
        Err(_) => line.iter().map(|&b| b as char).collect(),
    }
}

/// The part of a line before its comment.
fn content(line: &str) -> &str {
    if line.trim_start().starts_with("//") {
        return "";
    }
    line.split('#').next().unwrap_or("")
}

/// [`read_table`] on the bytes of a file.
pub fn parse_table(path: &Path, bytes: &[u8], options: &TableOptions) -> Result<Table> {
    let name = options.name;
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    let fail = |line: usize, column: Option<usize>, why: String| {
        let at = match column {
            Some(c) => format!("line {line}, column {}", c + 1),
            None => format!("line {line}"),
        };
        Error::format(path, format!("{at} ({name}): {why}"))
    };
    let split = |text: &str| -> Vec<String> {
        match options.delimiter {
            Some(d) => text.trim_end().strip_suffix(d).unwrap_or(text).split(d).map(|c| c.trim().to_string()).collect(),
            None => text
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|c| !c.is_empty())
                .map(String::from)
                .collect(),
        }
    };
    let mut table = Table { values: Vec::new(), columns: 0, lines: Vec::new(), header: None };
    let mut first = true;
    for (k, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        if options.max_rows.is_some_and(|m| table.lines.len() >= m) {
            break;
        }
        let line = k + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let text = decode(raw);
        let body = content(&text);
        if body.trim().is_empty() {
            continue;
        }
        let cells = split(body);
        let parsed: Vec<Option<f64>> = cells.iter().map(|c| c.parse::<f64>().ok()).collect();
        if first {
            first = false;
            if parsed.iter().any(Option::is_none) && body.chars().any(char::is_alphabetic) {
                table.header = Some(cells);
                continue;
            }
        }
        if table.lines.is_empty() {
            table.columns = cells.len();
            if !options.widths.is_empty() && !options.widths.contains(&cells.len()) {
                let widths: Vec<String> = options.widths.iter().map(usize::to_string).collect();
                return Err(fail(line, None, format!("{} cells, expected {}", cells.len(), widths.join(" or "))));
            }
        } else if cells.len() != table.columns {
            return Err(fail(
                line,
                None,
                format!("ragged row: {} cells, where the first data row has {}", cells.len(), table.columns),
            ));
        }
        for (j, (cell, value)) in cells.iter().zip(&parsed).enumerate() {
            let value = match value {
                Some(v) => *v,
                None if cell.is_empty() => {
                    return Err(fail(line, Some(j), "empty cell (write a missing value as nan)".into()))
                }
                None => return Err(fail(line, Some(j), format!("{cell:?} is not a number"))),
            };
            let may_be_missing = options.nan_columns.is_none_or(|c| c.contains(&j));
            if !value.is_finite() && !may_be_missing {
                return Err(fail(line, Some(j), format!("{cell} is not finite")));
            }
            table.values.push(value);
        }
        table.lines.push(line);
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &[u8], delimiter: Option<char>, widths: &[usize], nan: Option<&[usize]>) -> Result<Table> {
        let options = TableOptions { name: "plan", delimiter, widths, nan_columns: nan, max_rows: None };
        parse_table(Path::new("t.csv"), text, &options)
    }

    #[test]
    fn headers_comments_blank_lines_and_encodings_are_read() {
        let text = b"\xef\xbb\xbf# probe plan\r\nx,y,z\r\n\r\n1,2,3 # first\r\n// a note\r\n4, 5 ,6\r\n";
        let t = read(text, Some(','), &[3], Some(&[])).unwrap();
        assert_eq!(t.values, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(read(b"1,2,\n3,4,\n", Some(','), &[2], None).unwrap().values, vec![1.0, 2.0, 3.0, 4.0]);
        assert_eq!((t.columns, t.lines.clone()), (3, vec![4, 6]));
        assert_eq!(t.header, Some(vec!["x".into(), "y".into(), "z".into()]));
        // A cp1252 header (µ is 0xB5) and whitespace-separated rows without a header.
        let t = read(b"t\tH\xf6he \xb5m\n0 1.5\n0.1\t-2e-3\n", None, &[], None).unwrap();
        assert_eq!(t.header.unwrap()[1], "Höhe");
        assert_eq!(t.values, vec![0.0, 1.5, 0.1, -2e-3]);
        let none = read(b"# nothing\n\n", Some(','), &[3], None).unwrap();
        assert_eq!((none.rows(), none.header), (0, None));
        let nan = read(b"1,nan\n2,3\n", Some(','), &[], Some(&[1])).unwrap();
        assert!(nan.values[1].is_nan());
        // The first row alone: a broken line after it is not read.
        let options =
            TableOptions { name: "plan", delimiter: Some(','), widths: &[], nan_columns: None, max_rows: Some(1) };
        let first = parse_table(Path::new("t.csv"), b"t,a,b\n0,1,2\n0.1,x\n", &options).unwrap();
        assert_eq!((first.values, first.header.map(|h| h.len())), (vec![0.0, 1.0, 2.0], Some(3)));
    }

    #[test]
    fn problems_are_named_by_file_line_and_column() {
        let err = |text: &[u8], widths: &[usize], nan: Option<&[usize]>| {
            read(text, Some(','), widths, nan).unwrap_err().to_string()
        };
        assert_eq!(
            err(b"x,y\n1,2\n3\n", &[], None),
            "t.csv: line 3 (plan): ragged row: 1 cells, where the first data row has 2"
        );
        assert_eq!(err(b"1,2\n3,x4\n", &[], None), "t.csv: line 2, column 2 (plan): \"x4\" is not a number");
        assert_eq!(
            err(b"1,,2\n", &[], None),
            "t.csv: line 1, column 2 (plan): empty cell (write a missing value as nan)"
        );
        assert_eq!(err(b"a,b\n1,2,3,4\n", &[3, 6], None), "t.csv: line 2 (plan): 4 cells, expected 3 or 6");
        assert_eq!(err(b"1,2\n3,nan\n", &[], Some(&[0])), "t.csv: line 2, column 2 (plan): nan is not finite");
        // Only the first line may be a header.
        assert!(err(b"x,y\nu,v\n", &[], None).starts_with("t.csv: line 2, column 1 (plan): \"u\" is not a number"));
        assert!(matches!(
            read_table(
                Path::new("/nonexistent/t.csv"),
                &TableOptions { name: "plan", delimiter: None, widths: &[], nan_columns: None, max_rows: None }
            ),
            Err(Error::Io { .. })
        ));
    }
}
