//! E57 files (ASTM E2807), through the `e57` crate. E57 stores metres; machscan's unit is the mm,
//! so coordinates and ranges are multiplied by 1000 on reading and divided on writing.
//!
//! Read: every scan of the file, its pose applied (by default) so the scans share the file's
//! frame, one after another; a point whose Cartesian coordinates are marked invalid (or only a
//! direction) is dropped and counted (`CloudFile::dropped`); spherical scans are converted to
//! Cartesian. Scalars, named as the standard names them: `intensity`, `colorRed/Green/Blue`,
//! `rowIndex`, `columnIndex` (as stored, not normalised), `sphericalRange` (mm),
//! `sphericalAzimuth`, `sphericalElevation` (rad), and `scan` (the scan's index) when the file
//! holds more than one. Normals of the E57 surface-normals extension (`nor:normalX/Y/Z`) are the
//! normals.
//!
//! Written: one scan without a pose, Cartesian float64 coordinates; the scalars `intensity`
//! (float32), `colorRed/Green/Blue` and `rowIndex`/`columnIndex` (integers) in the standard's
//! fields, the normals in the surface-normals extension, every other scalar as a float64 field
//! of a `machscan` extension (readers that do not know it skip it, as the standard requires).
use super::{CloudFile, CloudRef};
use crate::error::{Error, Result};
use e57::{E57Reader, E57Writer, Extension, Record, RecordDataType, RecordName, RecordValue};
use std::io::Cursor;
use std::path::Path;

/// Millimetres per metre.
const MM: f64 = 1000.0;
const NORMALS: (&str, &str) = ("nor", "http://www.libe57.org/E57_NOR_surface_normals.txt");
const MACHSCAN: (&str, &str) = ("machscan", "https://github.com/machscan/machscan/blob/main/docs/clouds.md#e57");

fn e57_error(path: &Path, e: e57::Error) -> Error {
    Error::format(path, format!("not a readable E57 file: {e}"))
}

/// Where each field of a scan's records is, by the standard's names.
struct Layout {
    at: Vec<(RecordName, usize)>,
}

impl Layout {
    fn new(pc: &e57::PointCloud) -> Layout {
        Layout { at: pc.prototype.iter().enumerate().map(|(i, r)| (r.name.clone(), i)).collect() }
    }

    fn find(&self, name: &RecordName) -> Option<usize> {
        self.at.iter().find(|(n, _)| n == name).map(|&(_, i)| i)
    }
}

/// The scalars a scan gives, in order: the standard's names and where their values are.
const STANDARD: [(&str, RecordName); 6] = [
    ("intensity", RecordName::Intensity),
    ("colorRed", RecordName::ColorRed),
    ("colorGreen", RecordName::ColorGreen),
    ("colorBlue", RecordName::ColorBlue),
    ("rowIndex", RecordName::RowIndex),
    ("columnIndex", RecordName::ColumnIndex),
];

/// Reads an E57 file's bytes (module docs); `apply_pose: false` keeps each scan in its own frame.
///
/// Through the crate's raw records rather than its simple reader, which gives up on a scan whose
/// first data packet holds no whole point (a scan of two or three points with bit-packed fields,
/// as machscan writes them, read by pye57 without trouble).
pub fn parse_e57(path: &Path, bytes: Vec<u8>, apply_pose: bool) -> Result<CloudFile> {
    let mut reader = E57Reader::new(Cursor::new(bytes)).map_err(|e| e57_error(path, e))?;
    let scans = reader.pointclouds();
    let layouts: Vec<Layout> = scans.iter().map(Layout::new).collect();
    let mut out = CloudFile::default();
    let mut columns: Vec<(String, Vec<f64>)> = Vec::new();
    let normal_name = |axis: &str| RecordName::Unknown { namespace: NORMALS.0.into(), name: format!("normal{axis}") };
    let all_normals = !scans.is_empty()
        && layouts.iter().all(|layout| ["X", "Y", "Z"].iter().all(|a| layout.find(&normal_name(a)).is_some()));
    let mut normals = Vec::new();
    for (index, pc) in scans.iter().enumerate() {
        let layout = &layouts[index];
        let find = |name: RecordName| layout.find(&name);
        let cartesian = match (find(RecordName::CartesianX), find(RecordName::CartesianY), find(RecordName::CartesianZ))
        {
            (Some(x), Some(y), Some(z)) => Some([x, y, z]),
            _ => None,
        };
        let spherical = match (
            find(RecordName::SphericalRange),
            find(RecordName::SphericalAzimuth),
            find(RecordName::SphericalElevation),
        ) {
            (Some(r), Some(a), Some(e)) => Some([r, a, e]),
            _ => None,
        };
        let (cartesian_invalid, spherical_invalid) =
            (find(RecordName::CartesianInvalidState), find(RecordName::SphericalInvalidState));
        let (intensity_invalid, colour_invalid) =
            (find(RecordName::IsIntensityInvalid), find(RecordName::IsColorInvalid));
        let normal_at: Option<Vec<usize>> =
            all_normals.then(|| ["X", "Y", "Z"].iter().filter_map(|a| layout.find(&normal_name(a))).collect());
        let pose = pc.transform.as_ref().filter(|_| apply_pose).map(|t| {
            let q = &t.rotation;
            let rotation = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z));
            (rotation, nalgebra::Vector3::new(t.translation.x, t.translation.y, t.translation.z))
        });
        let mut scan_columns: Vec<(&str, Vec<f64>)> = Vec::new();
        let wanted: Vec<(&str, usize, Option<usize>)> = STANDARD
            .iter()
            .filter_map(|(name, record)| {
                let invalid = match record {
                    RecordName::Intensity => intensity_invalid,
                    RecordName::ColorRed | RecordName::ColorGreen | RecordName::ColorBlue => colour_invalid,
                    _ => None,
                };
                layout.find(record).map(|i| (*name, i, invalid))
            })
            .collect();
        for (name, _, _) in &wanted {
            scan_columns.push((name, Vec::new()));
        }
        if spherical.is_some() {
            for name in ["sphericalRange", "sphericalAzimuth", "sphericalElevation"] {
                scan_columns.push((name, Vec::new()));
            }
        }
        if scans.len() > 1 {
            scan_columns.push(("scan", Vec::new()));
        }
        let prototype = &pc.prototype;
        let value = |values: &[RecordValue], i: usize| values[i].to_f64(&prototype[i].data_type);
        let state =
            |values: &[RecordValue], i: Option<usize>| i.map_or(Ok(0), |i| values[i].to_i64(&prototype[i].data_type));
        let raw = reader.pointcloud_raw(pc).map_err(|e| e57_error(path, e))?;
        for values in raw {
            let values = values.map_err(|e| e57_error(path, e))?;
            let fail = |e| e57_error(path, e);
            let sph = match spherical {
                Some([r, a, e]) if state(&values, spherical_invalid).map_err(fail)? == 0 => Some([
                    value(&values, r).map_err(fail)?,
                    value(&values, a).map_err(fail)?,
                    value(&values, e).map_err(fail)?,
                ]),
                _ => None,
            };
            // Cartesian where valid (state 0; 1 is a direction only, 2 nothing), else from the
            // spherical coordinates where those are valid.
            let xyz = match cartesian {
                Some([x, y, z]) if state(&values, cartesian_invalid).map_err(fail)? == 0 => Some([
                    value(&values, x).map_err(fail)?,
                    value(&values, y).map_err(fail)?,
                    value(&values, z).map_err(fail)?,
                ]),
                Some(_) => None,
                None => sph.map(|[r, a, e]| [r * e.cos() * a.cos(), r * e.cos() * a.sin(), r * e.sin()]),
            };
            let Some(xyz) = xyz else {
                out.dropped += 1;
                continue;
            };
            let mut p = nalgebra::Vector3::from(xyz);
            if let Some((rotation, translation)) = &pose {
                p = rotation * p + translation;
            }
            out.points.extend_from_slice(&[p.x * MM, p.y * MM, p.z * MM]);
            let mut k = 0;
            for &(_, i, invalid) in &wanted {
                let v = if state(&values, invalid).map_err(fail)? == 0 {
                    value(&values, i).map_err(fail)?
                } else {
                    f64::NAN
                };
                scan_columns[k].1.push(v);
                k += 1;
            }
            if spherical.is_some() {
                let [r, a, e] = sph.unwrap_or([f64::NAN; 3]);
                for v in [r * MM, a, e] {
                    scan_columns[k].1.push(v);
                    k += 1;
                }
            }
            if scans.len() > 1 {
                scan_columns[k].1.push(index as f64);
            }
            if let Some(at) = &normal_at {
                let mut n = nalgebra::Vector3::zeros();
                for (c, &i) in at.iter().enumerate() {
                    n[c] = value(&values, i).map_err(fail)?;
                }
                if let Some((rotation, _)) = &pose {
                    n = rotation * n;
                }
                normals.extend_from_slice(&[n.x, n.y, n.z]);
            }
        }
        // A field one scan lacks is NaN for its points: the rule for missing values.
        let before = out.points.len() / 3 - scan_columns.first().map_or(0, |(_, c)| c.len());
        for (name, values) in scan_columns {
            match columns.iter_mut().find(|(n, _)| n == name) {
                Some((_, c)) => c.extend(values),
                None => {
                    let mut c = vec![f64::NAN; before];
                    c.extend(values);
                    columns.push((name.to_string(), c));
                }
            }
        }
        let n = out.points.len() / 3;
        columns.iter_mut().for_each(|(_, c)| c.resize(n, f64::NAN));
    }
    if all_normals {
        out.normals = Some(normals);
    }
    out.scalars = columns;
    Ok(out)
}

/// Writes `data` as one E57 scan (module docs).
pub fn write_e57(path: &Path, data: &CloudRef<'_>) -> Result<()> {
    let n = data.points.len() / 3;
    let get = |name: &str| data.scalars.iter().find(|(s, _)| *s == name).map(|(_, v)| *v);
    let integers = |name: &str, lo: f64, hi: f64| -> Result<Option<(i64, i64)>> {
        let Some(v) = get(name) else { return Ok(None) };
        if let Some(x) = v.iter().find(|&&x| !(x >= lo && x <= hi && x.fract() == 0.0)) {
            return Err(Error::invalid(
                "scalars",
                format!("{name:?} is an E57 integer field ({lo}..{hi}); {x} does not fit"),
            ));
        }
        // The values' range, or the field's where there are none (the standard needs one).
        let (min, max) = if v.is_empty() {
            (lo, hi)
        } else {
            v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)))
        };
        Ok(Some((min as i64, max as i64)))
    };
    let colour = ["colorRed", "colorGreen", "colorBlue"];
    match colour.iter().filter(|c| get(c).is_some()).count() {
        0 | 3 => {}
        _ => {
            return Err(Error::invalid(
                "scalars",
                "colorRed, colorGreen and colorBlue are E57 colour: give all three or none",
            ))
        }
    }
    let mut prototype = vec![Record::CARTESIAN_X_F64, Record::CARTESIAN_Y_F64, Record::CARTESIAN_Z_F64];
    // The columns in prototype order after x, y, z, with how each is stored.
    let mut fields: Vec<(&[f64], Stored)> = Vec::new();
    let mut standard = vec![];
    if let Some(v) = get("intensity") {
        prototype.push(Record { name: RecordName::Intensity, data_type: RecordDataType::F32 });
        fields.push((v, Stored::F32));
        standard.push("intensity");
    }
    for (name, record) in colour.iter().zip([RecordName::ColorRed, RecordName::ColorGreen, RecordName::ColorBlue]) {
        if let Some((_, max)) = integers(name, 0.0, u16::MAX as f64)? {
            // 8-bit colour where it fits: what scanners and pye57 write.
            let data_type = if max <= 255 { RecordDataType::U8 } else { RecordDataType::U16 };
            prototype.push(Record { name: record, data_type });
            fields.push((get(name).expect("present"), Stored::Integer));
            standard.push(name);
        }
    }
    for (name, record) in [("rowIndex", RecordName::RowIndex), ("columnIndex", RecordName::ColumnIndex)] {
        if let Some((min, max)) = integers(name, 0.0, i32::MAX as f64)? {
            prototype.push(Record { name: record, data_type: RecordDataType::Integer { min, max } });
            fields.push((get(name).expect("present"), Stored::Integer));
            standard.push(name);
        }
    }
    let normal_columns = data.normals.map(super::xyz_columns).unwrap_or_default();
    for (axis, column) in ["X", "Y", "Z"].iter().zip(&normal_columns) {
        prototype.push(Record {
            name: RecordName::Unknown { namespace: NORMALS.0.into(), name: format!("normal{axis}") },
            data_type: RecordDataType::Single { min: Some(-1.0), max: Some(1.0) },
        });
        fields.push((column, Stored::F32));
    }
    let others: Vec<(&str, &[f64])> = data.scalars.iter().filter(|(s, _)| !standard.contains(s)).copied().collect();
    for (name, values) in &others {
        prototype.push(Record {
            name: RecordName::Unknown { namespace: MACHSCAN.0.into(), name: name.to_string() },
            data_type: RecordDataType::F64,
        });
        fields.push((values, Stored::F64));
    }
    let write_error = |e: e57::Error| Error::invalid("path", format!("{}: {e}", path.display()));
    let guid = format!("machscan-{:016x}", fingerprint(data.points));
    let mut writer = E57Writer::from_file(path, &guid).map_err(write_error)?;
    if !normal_columns.is_empty() {
        writer
            .register_extension(Extension { namespace: NORMALS.0.into(), url: NORMALS.1.into() })
            .map_err(write_error)?;
    }
    if !others.is_empty() {
        writer
            .register_extension(Extension { namespace: MACHSCAN.0.into(), url: MACHSCAN.1.into() })
            .map_err(write_error)?;
    }
    let mut scan = writer.add_pointcloud(&format!("{guid}-scan"), prototype).map_err(write_error)?;
    for i in 0..n {
        let mut values: Vec<RecordValue> = (0..3).map(|k| RecordValue::Double(data.points[3 * i + k] / MM)).collect();
        for (column, stored) in &fields {
            let v = column[i];
            values.push(match stored {
                Stored::Integer => RecordValue::Integer(v as i64),
                Stored::F32 => RecordValue::Single(v as f32),
                Stored::F64 => RecordValue::Double(v),
            });
        }
        scan.add_point(values).map_err(write_error)?;
    }
    scan.finalize().map_err(write_error)?;
    writer.finalize().map_err(write_error)?;
    Ok(())
}

#[derive(Clone, Copy)]
enum Stored {
    Integer,
    F32,
    F64,
}

/// A file's GUID must be unique; one from its content keeps the written bytes a function of
/// the data (FNV-1a of the coordinates' bits).
fn fingerprint(points: &[f64]) -> u64 {
    points.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| (h ^ v.to_bits()).wrapping_mul(0x0000_0100_0000_01b3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_reads_back_in_mm_with_fields_normals_and_others() {
        let pts: Vec<f64> = (0..30).map(|i| -50.0 + i as f64 * 3.7).collect();
        let normals: Vec<f64> = (0..30).map(|i| [0.0, 0.6, 0.8][i % 3]).collect();
        let intensity: Vec<f64> = (0..10).map(|i| i as f64 * 0.5).collect();
        let red: Vec<f64> = (0..10).map(|i| i as f64 * 20.0).collect();
        let allowance: Vec<f64> = (0..10).map(|i| 0.1 + i as f64 * 1e-3).collect();
        let scalars = [
            ("intensity", intensity.as_slice()),
            ("colorRed", red.as_slice()),
            ("colorGreen", red.as_slice()),
            ("colorBlue", red.as_slice()),
            ("allowance", allowance.as_slice()),
        ];
        let data = CloudRef { points: &pts, normals: Some(&normals), scalars: &scalars, triangles: None };
        let path = std::env::temp_dir().join(format!("machscan-e57-{}.e57", std::process::id()));
        write_e57(&path, &data).unwrap();
        let back = parse_e57(&path, std::fs::read(&path).unwrap(), true).unwrap();
        std::fs::remove_file(&path).ok();
        for (a, b) in back.points.iter().zip(&pts) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} {b}");
        }
        assert_eq!(back.points.len(), pts.len());
        let get = |n: &str| back.scalars.iter().find(|(s, _)| s == n).map(|(_, v)| v.clone()).expect(n);
        assert_eq!(get("intensity"), intensity);
        assert_eq!(get("colorRed"), red);
        let stored: Vec<f64> = normals.iter().map(|&v| v as f32 as f64).collect(); // float32 in the file
        assert_eq!(back.normals, Some(stored));
        assert_eq!(back.dropped, 0);
        assert!(back.scalars.iter().all(|(s, _)| s != "allowance"), "an extension field the reader does not know");
    }

    #[test]
    fn spherical_scans_become_cartesian_mm_and_invalid_points_are_counted() {
        let path = std::env::temp_dir().join(format!("machscan-e57-sph-{}.e57", std::process::id()));
        let mut w = E57Writer::from_file(&path, "sph").unwrap();
        let proto = vec![
            Record { name: RecordName::SphericalRange, data_type: RecordDataType::F64 },
            Record { name: RecordName::SphericalAzimuth, data_type: RecordDataType::F64 },
            Record { name: RecordName::SphericalElevation, data_type: RecordDataType::F64 },
            Record { name: RecordName::SphericalInvalidState, data_type: RecordDataType::Integer { min: 0, max: 2 } },
        ];
        let mut scan = w.add_pointcloud("sph-scan", proto).unwrap();
        let mut rows = vec![(2.0, 0.3, -0.2, 0), (1.5, -2.0, 0.7, 0), (3.0, 1.0, 0.1, 2)];
        rows.extend((0..997).map(|i| (1.0 + i as f64 * 1e-3, -3.0 + i as f64 * 6e-3, -1.5 + i as f64 * 3e-3, 0)));
        for &(r, a, e, invalid) in &rows {
            let values = vec![
                RecordValue::Double(r),
                RecordValue::Double(a),
                RecordValue::Double(e),
                RecordValue::Integer(invalid),
            ];
            scan.add_point(values).unwrap();
        }
        scan.finalize().unwrap();
        w.finalize().unwrap();
        let back = parse_e57(&path, std::fs::read(&path).unwrap(), true).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(back.dropped, 1, "the point marked invalid");
        let valid: Vec<_> = rows.iter().filter(|row| row.3 == 0).collect();
        assert_eq!(back.points.len(), 3 * valid.len());
        for (k, &&(r, a, e, _)) in valid.iter().enumerate() {
            let want = [r * e.cos() * a.cos(), r * e.cos() * a.sin(), r * e.sin()].map(|v| v * MM);
            for (got, want) in back.points[3 * k..3 * k + 3].iter().zip(want) {
                assert!((got - want).abs() < 1e-9, "{got} {want}");
            }
        }
        let range = &back.scalars.iter().find(|(n, _)| n == "sphericalRange").unwrap().1;
        assert_eq!(range[..2], [2000.0, 1500.0]);
    }

    #[test]
    fn scans_of_a_few_points_with_packed_fields_read_back() {
        for n in 1..6 {
            let pts: Vec<f64> = (0..3 * n).map(|i| i as f64 * 0.25).collect();
            let row: Vec<f64> = (0..n).map(|i| (i % 3) as f64).collect();
            let scalars = [("rowIndex", row.as_slice())];
            let data = CloudRef { points: &pts, normals: None, scalars: &scalars, triangles: None };
            let path = std::env::temp_dir().join(format!("machscan-e57-few-{}-{n}.e57", std::process::id()));
            write_e57(&path, &data).unwrap();
            let back = parse_e57(&path, std::fs::read(&path).unwrap(), true).unwrap();
            std::fs::remove_file(&path).ok();
            assert_eq!(back.points.len(), 3 * n, "{n} points");
            assert_eq!(back.scalars[0].1, row);
        }
    }
}
