//! Point cloud, mesh and toolpath files (SPEC F formats). `read_file` and `write_file` choose
//! the format by the extension; the list of formats is `FileFormat::ALL`, the one place the
//! extensions are spelled.
//! The formats: docs/clouds.md.
mod apt;
mod e57;
mod las;
mod lzf;
mod obj;
mod pcd;
mod ply;
mod profiles;
mod stl;
mod table;
mod text;

pub use apt::{parse_apt, read_apt, write_apt, Toolpath};
pub use e57::{parse_e57, write_e57};
pub use las::{parse_las, write_las, LAS_SCALE};
pub use lzf::{lzf_decompress, lzf_store};
pub use obj::parse_obj;
pub use pcd::{parse_pcd, PcdEncoding};
pub use ply::parse_ply;
pub use profiles::{parse_profiles, read_profiles, ProfileExport};
pub use stl::parse_stl;
pub use table::{parse_table, read_table, Table, TableOptions};
pub use text::{parse_mesh_txt, read_xyz};

use crate::error::{Error, Result};
use std::path::Path;

/// What a point or mesh file holds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CloudFile {
    /// `(N, 3)` row-major coordinates, as stored (float32 values widened exactly).
    pub points: Vec<f64>,
    /// `(N, 3)` row-major normals: PLY nx/ny/nz, PCD normal_x/y/z, OBJ vn given per vertex.
    pub normals: Option<Vec<f64>>,
    /// Every other per-point property, by name, in file order.
    pub scalars: Vec<(String, Vec<f64>)>,
    /// Faces as triangles of vertex indices (polygons fanned from their first vertex); empty for
    /// point clouds.
    pub triangles: Vec<[u32; 3]>,
    /// Points the file marks invalid (E57), not returned.
    pub dropped: u64,
}

/// What to write: borrowed, row-major.
#[derive(Debug, Clone, Copy, Default)]
pub struct CloudRef<'a> {
    pub points: &'a [f64],
    pub normals: Option<&'a [f64]>,
    pub scalars: &'a [(&'a str, &'a [f64])],
    /// Triangles (PLY, STL, OBJ); `None` writes a point cloud.
    pub triangles: Option<&'a [[u32; 3]]>,
}

/// The file formats machscan knows, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileFormat {
    Ply,
    Pcd,
    /// Text, one point per line: .xyz, .csv, .pts, .asc, and .txt (a .txt that starts with
    /// `n_vertices n_faces` is the mesh text format of the geodesic test meshes).
    Text {
        comma: bool,
    },
    Stl,
    Obj,
    /// LAS, and LAZ (`compressed`).
    Las {
        compressed: bool,
    },
    /// ASTM E2807.
    E57,
}

impl FileFormat {
    /// Every extension read, with its format.
    pub const ALL: [(&'static str, FileFormat); 12] = [
        ("ply", FileFormat::Ply),
        ("pcd", FileFormat::Pcd),
        ("xyz", FileFormat::Text { comma: false }),
        ("csv", FileFormat::Text { comma: true }),
        ("txt", FileFormat::Text { comma: false }),
        ("pts", FileFormat::Text { comma: false }),
        ("asc", FileFormat::Text { comma: false }),
        ("stl", FileFormat::Stl),
        ("obj", FileFormat::Obj),
        ("las", FileFormat::Las { compressed: false }),
        ("laz", FileFormat::Las { compressed: true }),
        ("e57", FileFormat::E57),
    ];

    /// The format a file's first bytes announce, for the formats that start with a signature
    /// (LAS/LAZ, PLY, PCD): a file is read by what it holds, whatever its extension says.
    pub fn sniff(head: &[u8]) -> Option<FileFormat> {
        let starts = |magic: &[u8]| head.len() >= magic.len() && head[..magic.len()].eq_ignore_ascii_case(magic);
        if head.starts_with(b"LASF") {
            // Bit 7 (or 6) of the point format byte at 104 marks LAZ; the reader looks at it again.
            let compressed = head.get(104).is_some_and(|b| b & 0xC0 != 0);
            Some(FileFormat::Las { compressed })
        } else if head.starts_with(b"ASTM-E57") {
            Some(FileFormat::E57)
        } else if starts(b"ply\n") || starts(b"ply\r\n") {
            Some(FileFormat::Ply)
        } else if starts(b"# .PCD") || starts(b"VERSION") {
            Some(FileFormat::Pcd)
        } else {
            None
        }
    }

    fn list() -> String {
        let ext: Vec<String> = Self::ALL.iter().map(|(e, _)| format!(".{e}")).collect();
        ext.join(", ")
    }

    /// The format of `path` by its extension (any case); `write` words the message.
    pub fn of(path: &Path, write: bool) -> Result<FileFormat> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        match Self::ALL.iter().find(|(e, _)| *e == ext) {
            Some((_, f)) => Ok(*f),
            _ => Err(Error::invalid(
                "path",
                format!(
                    "{}: unknown file type {:?}; machscan {} {}",
                    path.display(),
                    ext,
                    if write { "writes" } else { "reads" },
                    Self::list()
                ),
            )),
        }
    }
}

/// Column choice for text point files.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextColumns {
    /// None splits on whitespace and commas.
    pub delimiter: Option<char>,
    /// Columns of x, y, z, 0-based.
    pub columns: [usize; 3],
}

impl Default for TextColumns {
    fn default() -> Self {
        TextColumns { delimiter: None, columns: [0, 1, 2] }
    }
}

/// Reads any file of `FileFormat::ALL`: by its signature where its format has one
/// ([`FileFormat::sniff`]), else by its extension. E57 scans are put in the file's frame by
/// their poses.
pub fn read_file(path: &Path, text: TextColumns) -> Result<CloudFile> {
    read_file_with(path, text, true)
}

/// [`read_file`], with E57 scans left in their own frames when `apply_pose` is false.
pub fn read_file_with(path: &Path, text: TextColumns, apply_pose: bool) -> Result<CloudFile> {
    let by_name = FileFormat::of(path, false);
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        // An unknown extension is the first thing to say, even of a file that is not there.
        Err(_) if by_name.is_err() => return Err(by_name.unwrap_err()),
        Err(e) => return Err(Error::io(path, "read", &e)),
    };
    let format = match (FileFormat::sniff(&bytes), by_name) {
        (Some(f), _) => f,
        (None, by_name) => by_name?,
    };
    match format {
        FileFormat::Ply => parse_ply(path, &bytes),
        FileFormat::Pcd => parse_pcd(path, &bytes),
        FileFormat::Stl => parse_stl(path, &bytes),
        FileFormat::Obj => parse_obj(path, &bytes),
        FileFormat::Las { .. } => parse_las(path, bytes),
        FileFormat::E57 => parse_e57(path, bytes, apply_pose),
        FileFormat::Text { .. } => {
            let b = bytes;
            let is_txt = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("txt"));
            if is_txt && text == TextColumns::default() {
                if let Some(mesh) = parse_mesh_txt(path, &b)? {
                    return Ok(mesh);
                }
            }
            Ok(CloudFile { points: read_xyz(path, &b, text)?, ..CloudFile::default() })
        }
    }
}

/// Number type of the written coordinates, normals and scalars.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dtype {
    F32,
    F64,
}

impl Dtype {
    pub fn parse(name: &str) -> Result<Dtype> {
        match name {
            "float32" | "f4" | "float" => Ok(Dtype::F32),
            "float64" | "f8" | "double" => Ok(Dtype::F64),
            other => Err(Error::invalid("dtype", format!("expected \"float32\" or \"float64\", got {other:?}"))),
        }
    }

    /// Appends `v` in this type, little-endian.
    #[inline]
    pub(crate) fn put_le(self, out: &mut Vec<u8>, v: f64) {
        match self {
            Dtype::F32 => out.extend_from_slice(&(v as f32).to_le_bytes()),
            Dtype::F64 => out.extend_from_slice(&v.to_le_bytes()),
        }
    }

    /// Shortest text that reads back to the written value.
    #[inline]
    pub(crate) fn text(self, v: f64) -> String {
        match self {
            Dtype::F32 => format!("{}", v as f32),
            Dtype::F64 => format!("{v}"),
        }
    }
}

/// How to write; `None` means the format's default.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WriteOptions {
    /// Binary (PLY, PCD, STL default) or ASCII; text formats refuse `Some(true)`.
    pub binary: Option<bool>,
    /// PCD `binary_compressed`.
    pub compressed: bool,
    /// float32 by default for PLY, PCD and STL, which is what Open3D's and PCL's readers take
    /// everywhere (Open3D's legacy PCD reader reads 8-byte coordinates as zeros); text formats
    /// default to full precision.
    pub dtype: Option<Dtype>,
    /// LAS/LAZ: the coordinate step, mm (default [`LAS_SCALE`]).
    pub scale: Option<f64>,
}

/// `(N, 3)` row-major values as their x, y and z columns (formats that store fields apart).
pub(crate) fn xyz_columns(rows: &[f64]) -> Vec<Vec<f64>> {
    (0..3).map(|k| rows.iter().skip(k).step_by(3).copied().collect()).collect()
}

/// Fields machscan writes itself: a scalar may not take their names.
const RESERVED: [&str; 9] = ["x", "y", "z", "nx", "ny", "nz", "normal_x", "normal_y", "normal_z"];

fn check_cloud(data: &CloudRef<'_>) -> Result<usize> {
    if !data.points.len().is_multiple_of(3) {
        return Err(Error::shape("points", "(N, 3)", format!("{} values", data.points.len())));
    }
    let n = data.points.len() / 3;
    if let Some(nr) = data.normals {
        if nr.len() != data.points.len() {
            return Err(Error::shape(
                "normals",
                format!("({n}, 3): one normal per point"),
                format!("({}, 3)", nr.len() / 3),
            ));
        }
    }
    let mut seen: Vec<&str> = Vec::new();
    for (name, values) in data.scalars {
        if values.len() != n {
            return Err(Error::shape(
                "scalars",
                format!("{name:?}: ({n},), one value per point"),
                format!("({},)", values.len()),
            ));
        }
        let word = !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !word {
            return Err(Error::invalid(
                "scalars",
                format!("field name {name:?} must be letters, digits and _ (PLY and PCD headers are words)"),
            ));
        }
        if RESERVED.contains(&name.to_ascii_lowercase().as_str()) {
            return Err(Error::invalid(
                "scalars",
                format!("{name:?} is a field machscan writes itself (points and normals); choose another name"),
            ));
        }
        if seen.iter().any(|s| s.eq_ignore_ascii_case(name)) {
            return Err(Error::invalid("scalars", format!("{name:?} is given twice (names are case-insensitive)")));
        }
        seen.push(name);
    }
    if let Some(t) = data.triangles {
        if let Some(k) = t.iter().position(|f| f.iter().any(|&v| v as usize >= n)) {
            return Err(Error::invalid(
                "triangles",
                format!("triangle {k} refers to vertex {} but there are {n} vertices", t[k].iter().max().unwrap_or(&0)),
            ));
        }
    }
    Ok(n)
}

/// Writes `data` in the format of `path`'s extension. Contradictory options and data the format
/// cannot hold raise instead of being dropped.
pub fn write_file(path: &Path, data: &CloudRef<'_>, options: WriteOptions) -> Result<()> {
    let format = FileFormat::of(path, true)?;
    check_cloud(data)?;
    let refuse = |name: &str, what: &str| Err(Error::invalid(name, format!("{what} ({} file)", path.display())));
    if options.compressed && format != FileFormat::Pcd {
        return refuse("compressed", "only PCD files are compressed (binary_compressed)");
    }
    if options.scale.is_some() && !matches!(format, FileFormat::Las { .. }) {
        return refuse("scale", "only LAS/LAZ files store coordinates as integer steps");
    }
    if options.compressed && options.binary == Some(false) {
        return refuse("compressed", "binary_compressed is a binary encoding: binary=False contradicts it");
    }
    let has_triangles = data.triangles.is_some();
    match format {
        FileFormat::Ply => {
            ply::write_ply(path, data, options.binary.unwrap_or(true), options.dtype.unwrap_or(Dtype::F32))
        }
        FileFormat::Pcd => {
            if has_triangles {
                return refuse("triangles", "a PCD file holds points only: write .ply, .stl or .obj for a mesh");
            }
            let encoding = match (options.binary.unwrap_or(true), options.compressed) {
                (_, true) => PcdEncoding::BinaryCompressed,
                (true, false) => PcdEncoding::Binary,
                (false, false) => PcdEncoding::Ascii,
            };
            pcd::write_pcd(path, data, encoding, options.dtype.unwrap_or(Dtype::F32))
        }
        FileFormat::Stl => {
            if !has_triangles {
                return refuse("triangles", "an STL file holds triangles: give them (or write .ply for points)");
            }
            if data.normals.is_some() || !data.scalars.is_empty() {
                return refuse(
                    "normals",
                    "STL stores facet normals, computed from the triangles, and no per-vertex data: write .ply to keep them",
                );
            }
            if options.dtype == Some(Dtype::F64) {
                return refuse("dtype", "STL stores float32 only: write .ply or .obj with dtype=\"float64\"");
            }
            stl::write_stl(path, data, options.binary.unwrap_or(true))
        }
        FileFormat::Obj => {
            if options.binary == Some(true) {
                return refuse("binary", "OBJ is a text format");
            }
            if !data.scalars.is_empty() {
                return refuse("scalars", "OBJ holds no per-vertex properties: write .ply or .pcd to keep them");
            }
            obj::write_obj(path, data, options.dtype.unwrap_or(Dtype::F64))
        }
        FileFormat::Text { comma } => {
            if options.binary == Some(true) {
                return refuse("binary", "a text point file is text");
            }
            if data.normals.is_some() || !data.scalars.is_empty() || has_triangles {
                return refuse(
                    "normals",
                    "a text point file holds x, y, z only: write .ply or .pcd to keep normals, scalars and triangles",
                );
            }
            text::write_xyz(path, data.points, if comma { ',' } else { ' ' }, options.dtype.unwrap_or(Dtype::F64))
        }
        FileFormat::Las { compressed } => {
            if has_triangles {
                return refuse("triangles", "a LAS file holds points only: write .ply, .stl or .obj for a mesh");
            }
            if options.binary == Some(false) {
                return refuse("binary", "LAS is a binary format");
            }
            if options.compressed {
                return refuse("compressed", "LAS is compressed by its extension: write .laz");
            }
            las::write_las(path, data, compressed, options.scale, options.dtype.unwrap_or(Dtype::F64))
        }
        FileFormat::E57 => {
            if has_triangles {
                return refuse("triangles", "an E57 file holds points only: write .ply, .stl or .obj for a mesh");
            }
            if options.binary == Some(false) || options.dtype.is_some() {
                return refuse("dtype", "E57 stores coordinates as float64 and its fields in their own types");
            }
            e57::write_e57(path, data)
        }
    }
}

#[cfg(test)]
mod robustness {
    //! Truncated and corrupted files: the parsers answer with an error or a result, never a
    //! panic. (A deterministic mutation sweep; the proptest fuzzing in `fuzz` goes further.)
    use super::*;
    use crate::testing::lcg_bits;
    use std::path::Path;

    fn sweep(valid: &[u8], parse: impl Fn(&[u8]) -> bool) {
        sweep_bytes(valid, valid.len(), parse)
    }

    /// Every truncation, and 3000 mutations of up to 4 of the first `mutable` bytes.
    fn sweep_bytes(valid: &[u8], mutable: usize, parse: impl Fn(&[u8]) -> bool) {
        assert!(parse(valid), "the valid file must parse");
        for cut in 0..valid.len() {
            let _ = parse(&valid[..cut]);
        }
        let mut s = 99u64;
        for _ in 0..3000 {
            let mut b = valid.to_vec();
            for _ in 0..1 + lcg_bits(&mut s) % 4 {
                let i = (lcg_bits(&mut s) as usize) % mutable;
                b[i] = lcg_bits(&mut s) as u8;
            }
            let _ = parse(&b);
        }
    }

    fn sample_ply(binary: bool) -> Vec<u8> {
        let dir = std::env::temp_dir().join(format!("machscan-ply-{}-{binary}.ply", std::process::id()));
        let pts: Vec<f64> = (0..30).map(|i| i as f64 * 0.37).collect();
        let s = [0.5; 10];
        let data = CloudRef { points: &pts, normals: Some(&pts), scalars: &[("a", &s)], triangles: None };
        write_file(&dir, &data, WriteOptions { binary: Some(binary), ..WriteOptions::default() }).unwrap();
        let mut b = std::fs::read(&dir).unwrap();
        std::fs::remove_file(&dir).ok();
        // A face element too, so list parsing is exercised.
        let header_end = b.windows(10).position(|w| w == b"end_header").unwrap();
        let face_decl = b"element face 2\nproperty list uchar int vertex_indices\n";
        b.splice(header_end..header_end, face_decl.iter().copied());
        if binary {
            for f in [[0i32, 1, 2], [2, 3, 4]] {
                b.push(3);
                for v in f {
                    b.extend_from_slice(&v.to_le_bytes());
                }
            }
        } else {
            b.extend_from_slice(b"3 0 1 2\n3 2 3 4\n");
        }
        b
    }

    #[test]
    fn ply_never_panics() {
        for binary in [true, false] {
            sweep(&sample_ply(binary), |b| parse_ply(Path::new("t.ply"), b).is_ok());
        }
    }

    #[test]
    fn las_and_laz_never_panic() {
        let pts: Vec<f64> = (0..60).map(|i| i as f64 * 0.37).collect();
        let s: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let scalars = [("intensity", s.as_slice()), ("a", s.as_slice())];
        for name in ["t.las", "t.laz"] {
            let path = std::env::temp_dir().join(format!("machscan-sweep-{}-{name}", std::process::id()));
            let data = CloudRef { points: &pts, normals: Some(&pts), scalars: &scalars, triangles: None };
            write_file(&path, &data, WriteOptions::default()).unwrap();
            let b = std::fs::read(&path).unwrap();
            std::fs::remove_file(&path).ok();
            // LAZ: the header, the VLRs and the chunk table's offset, which machscan reads. What
            // follows is the compressed stream, the `laz` crate's to decode: a corrupted layer
            // size there makes it allocate that size (up to 4 GiB) before it meets the file's
            // end, an error, but too slow a one for a debug-build sweep.
            let mutable = if name.ends_with(".laz") {
                u32::from_le_bytes(b[96..100].try_into().unwrap()) as usize + 8
            } else {
                b.len()
            };
            sweep_bytes(&b, mutable, |b| parse_las(Path::new(name), b.to_vec()).is_ok());
        }
    }

    #[test]
    fn e57_never_panics() {
        let pts: Vec<f64> = (0..60).map(|i| i as f64 * 0.37).collect();
        let s: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let scalars = [("intensity", s.as_slice())];
        let path = std::env::temp_dir().join(format!("machscan-sweep-{}.e57", std::process::id()));
        let data = CloudRef { points: &pts, normals: None, scalars: &scalars, triangles: None };
        write_file(&path, &data, WriteOptions::default()).unwrap();
        let b = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).ok();
        sweep(&b, |b| parse_e57(Path::new("t.e57"), b.to_vec(), true).is_ok());
    }

    #[test]
    fn pcd_never_panics() {
        let head =
            "VERSION 0.7\nFIELDS x y z i\nSIZE 4 4 4 2\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 8\nHEIGHT 1\nPOINTS 8\n";
        let ascii = format!("{head}DATA ascii\n") + &(0..8).map(|k| format!("{k} 1.5 -2 {k}\n")).collect::<String>();
        sweep(ascii.as_bytes(), |b| parse_pcd(Path::new("t.pcd"), b).is_ok());
        let mut raw = Vec::new();
        for _ in 0..3 {
            for k in 0..8 {
                raw.extend_from_slice(&(k as f32).to_le_bytes());
            }
        }
        for k in 0..8u16 {
            raw.extend_from_slice(&k.to_le_bytes());
        }
        let comp = lzf_store(&raw);
        let mut bc = format!("{head}DATA binary_compressed\n").into_bytes();
        bc.extend_from_slice(&(comp.len() as u32).to_le_bytes());
        bc.extend_from_slice(&(raw.len() as u32).to_le_bytes());
        bc.extend_from_slice(&comp);
        sweep(&bc, |b| parse_pcd(Path::new("t.pcd"), b).is_ok());
    }
}

#[cfg(test)]
mod fuzz {
    //! Property-based fuzzing of the readers (proptest): arbitrary bytes, and valid files with
    //! random truncations, byte changes and header counts replaced by huge numbers. A reader
    //! must return `Ok` or `Err`, never panic, hang or allocate what the data cannot back.
    use super::*;
    use proptest::prelude::*;
    use std::path::Path;

    fn valid_ply(binary: bool) -> Vec<u8> {
        let text = if binary { "binary_little_endian" } else { "ascii" };
        let mut b = format!(
            "ply\nformat {text} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar q\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        if binary {
            for i in 0..4u8 {
                for v in [i as f32, 1.0, 2.0] {
                    b.extend_from_slice(&v.to_le_bytes());
                }
                b.push(i);
            }
            b.push(4);
            for v in [0i32, 1, 2, 3] {
                b.extend_from_slice(&v.to_le_bytes());
            }
        } else {
            b.extend_from_slice(b"0 1 2 0\n1 1 2 1\n2 1 2 2\n3 1 2 3\n4 0 1 2 3\n");
        }
        b
    }

    fn valid_pcd(kind: &str) -> Vec<u8> {
        let mut b = format!("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA {kind}\n").into_bytes();
        let raw: Vec<u8> = (0..9).flat_map(|i| (i as f32).to_le_bytes()).collect();
        match kind {
            "ascii" => b.extend_from_slice(b"0 1 2\n3 4 5\n6 7 8\n"),
            "binary" => b.extend_from_slice(&raw),
            _ => {
                let comp = lzf_store(&raw);
                b.extend_from_slice(&(comp.len() as u32).to_le_bytes());
                b.extend_from_slice(&(raw.len() as u32).to_le_bytes());
                b.extend_from_slice(&comp);
            }
        }
        b
    }

    fn mutate(mut b: Vec<u8>, cut: usize, flips: &[(usize, u8)], huge: bool) -> Vec<u8> {
        if huge {
            let s = String::from_utf8_lossy(&b).replacen(" 4\n", " 4000000000\n", 1).replacen(
                "POINTS 3",
                "POINTS 99999999999",
                1,
            );
            b = s.into_bytes();
        }
        for &(i, v) in flips {
            let n = b.len();
            if n > 0 {
                b[i % n] = v;
            }
        }
        b.truncate(cut.min(b.len()));
        b
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

        #[test]
        fn arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            let _ = parse_ply(Path::new("f.ply"), &bytes);
            let _ = parse_pcd(Path::new("f.pcd"), &bytes);
            let mut with_header = b"ply\nformat binary_little_endian 1.0\n".to_vec();
            with_header.extend_from_slice(&bytes);
            let _ = parse_ply(Path::new("f.ply"), &with_header);
            // Behind the LAS and E57 signatures, so the crates' own header parsers see them.
            for magic in [&b"LASF"[..], b"ASTM-E57"] {
                let mut signed = magic.to_vec();
                signed.extend_from_slice(&bytes);
                let _ = parse_las(Path::new("f.las"), signed.clone());
                let _ = parse_e57(Path::new("f.e57"), signed, true);
            }
        }

        #[test]
        fn mutated_valid_files(which in 0usize..5, cut in 0usize..400, flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..6), huge in any::<bool>()) {
            let base = match which {
                0 => valid_ply(true),
                1 => valid_ply(false),
                2 => valid_pcd("ascii"),
                3 => valid_pcd("binary"),
                _ => valid_pcd("binary_compressed"),
            };
            let b = mutate(base, cut, &flips, huge);
            if which < 2 {
                let _ = parse_ply(Path::new("f.ply"), &b);
            } else {
                let _ = parse_pcd(Path::new("f.pcd"), &b);
            }
        }

        #[test]
        fn profile_exports_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300), cut in 0usize..900, flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..6)) {
            let _ = parse_profiles(Path::new("f.csv"), &bytes);
            // Behind a Gocator section and a Keyence row, and a valid Gocator export mutated.
            for prefix in [&b"Profile\nFrame Count\n1\nFrame,Y,Axis,0.0,0.1\n"[..], b"1234500\t"] {
                let mut b = prefix.to_vec();
                b.extend_from_slice(&bytes);
                let _ = parse_profiles(Path::new("f.csv"), &b);
            }
            let valid = b"Info\nXResolution\n0.1\nEnd\nProfile\nFrame Count\n2\nFrame,Source,Time,Encoder,Y,Axis,0.0,0.1\n0,0,5,1,0.0,Z,1.0,\n1,0,9,2,0.1,Z,-,2.0\nEnd\nPart\nRow Count\n1\nY\\X,0,1\n0,1,2\nEnd\n";
            let _ = parse_profiles(Path::new("f.csv"), &mutate(valid.to_vec(), cut, &flips, false));
        }

        #[test]
        fn lzf_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200), out_len in 0usize..2000) {
            let _ = lzf_decompress(&bytes, out_len);
        }
    }
}

#[cfg(test)]
mod round_trips {
    //! Every writable format read back; options that contradict each other refused.
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("machscan-io-{}-{name}", std::process::id()))
    }

    /// A tetrahedron with one vertex used by no face.
    fn mesh() -> (Vec<f64>, Vec<[u32; 3]>) {
        let points = vec![0.0, 0.0, 0.0, 1.5, 0.0, 0.0, 0.0, 2.25, 0.0, 0.0, 0.0, -3.125, 9.0, 9.0, 9.0];
        (points, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    #[test]
    fn meshes_round_trip_in_ply_stl_and_obj() {
        let (points, triangles) = mesh();
        let data = CloudRef { points: &points, triangles: Some(&triangles), ..CloudRef::default() };
        for (name, binary) in [("m.ply", true), ("m.ply", false), ("m.obj", false), ("m.stl", true), ("m.stl", false)] {
            let path = temp(&format!("{binary}-{name}"));
            write_file(&path, &data, WriteOptions { binary: Some(binary), ..WriteOptions::default() })
                .unwrap_or_else(|e| panic!("{name} {binary}: {e}"));
            let back = read_file(&path, TextColumns::default()).unwrap();
            std::fs::remove_file(&path).ok();
            // STL keeps only the vertices the faces use, in order of first use.
            let expect: Vec<[f64; 3]> = if name.ends_with("stl") {
                vec![[0.0, 0.0, 0.0], [0.0, 2.25, 0.0], [1.5, 0.0, 0.0], [0.0, 0.0, -3.125]]
            } else {
                points.chunks(3).map(|p| [p[0], p[1], p[2]]).collect()
            };
            let got: Vec<[f64; 3]> = back.points.chunks(3).map(|p| [p[0], p[1], p[2]]).collect();
            assert_eq!(got, expect, "{name} {binary}");
            let corners = |pts: &[[f64; 3]], t: &[[u32; 3]]| -> Vec<[[f64; 3]; 3]> {
                t.iter().map(|f| f.map(|v| pts[v as usize])).collect()
            };
            let original: Vec<[f64; 3]> = points.chunks(3).map(|p| [p[0], p[1], p[2]]).collect();
            assert_eq!(corners(&got, &back.triangles), corners(&original, &triangles), "{name} {binary}");
        }
    }

    #[test]
    fn stl_facet_normals_follow_the_right_hand_rule() {
        let points = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let path = temp("n.stl");
        let data = CloudRef { points: &points, triangles: Some(&[[0, 1, 2]]), ..CloudRef::default() };
        write_file(&path, &data, WriteOptions::default()).unwrap();
        let b = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(b.len(), 84 + 50);
        let nz = f32::from_le_bytes([b[92], b[93], b[94], b[95]]);
        assert_eq!(nz, 1.0);
    }

    #[test]
    fn obj_reads_slashes_negative_indices_polygons_and_normals() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvt 0 0\nf 1/1/1 2/1/2 3/1/3 4/1/4\nf -4//1 -2//3 -1//4\n";
        let m = parse_obj(Path::new("q.obj"), text.as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert_eq!(m.normals.unwrap().len(), 12);
        assert!(parse_obj(Path::new("q.obj"), b"v 0 0 0\nf 1 2 3\n").is_err());
        assert!(parse_obj(Path::new("q.obj"), b"v 0 0\n").is_err());
    }

    #[test]
    fn stl_that_is_neither_binary_nor_ascii_is_a_format_error() {
        let mut b = vec![0u8; 84];
        b[80] = 5; // five triangles announced, none present
        assert!(matches!(parse_stl(Path::new("x.stl"), &b), Err(Error::Format { .. })));
        let t = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n";
        assert!(parse_stl(Path::new("x.stl"), t.as_bytes()).is_err());
    }

    #[test]
    fn float32_is_the_default_of_ply_and_pcd_and_float64_is_kept_when_asked() {
        let points = [1000.123456789, -2.5, 0.1];
        let data = CloudRef { points: &points, ..CloudRef::default() };
        for ext in ["ply", "pcd"] {
            let path = temp(&format!("p.{ext}"));
            write_file(&path, &data, WriteOptions::default()).unwrap();
            let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).to_string();
            assert!(text.contains(if ext == "ply" { "property float x" } else { "SIZE 4 4 4" }), "{ext}");
            let back = read_file(&path, TextColumns::default()).unwrap();
            assert_eq!(back.points[0], 1000.123456789f64 as f32 as f64);
            write_file(&path, &data, WriteOptions { dtype: Some(Dtype::F64), ..WriteOptions::default() }).unwrap();
            assert_eq!(read_file(&path, TextColumns::default()).unwrap().points, points);
            std::fs::remove_file(&path).ok();
        }
    }

    #[test]
    fn contradictions_and_what_a_format_cannot_hold_are_refused() {
        let points = [0.0, 0.0, 0.0];
        let a = [1.0];
        type Fields<'a> = [(&'a str, &'a [f64]); 1];
        let x: Fields<'_> = [("x", &a)];
        let normal_x: Fields<'_> = [("Normal_X", &a)];
        let words: Fields<'_> = [("two words", &a)];
        let plain: Fields<'_> = [("a", &a)];
        let cases: Vec<(&str, CloudRef<'_>, WriteOptions, &str)> = vec![
            (
                "c.ply",
                CloudRef { points: &points, ..Default::default() },
                WriteOptions { compressed: true, ..Default::default() },
                "compressed",
            ),
            (
                "c.pcd",
                CloudRef { points: &points, ..Default::default() },
                WriteOptions { binary: Some(false), compressed: true, dtype: None, scale: None },
                "compressed",
            ),
            (
                "c.pcd",
                CloudRef { points: &points, scalars: &x, ..Default::default() },
                WriteOptions::default(),
                "scalars",
            ),
            (
                "c.ply",
                CloudRef { points: &points, scalars: &normal_x, ..Default::default() },
                WriteOptions::default(),
                "scalars",
            ),
            (
                "c.ply",
                CloudRef { points: &points, scalars: &words, ..Default::default() },
                WriteOptions::default(),
                "scalars",
            ),
            (
                "c.xyz",
                CloudRef { points: &points, ..Default::default() },
                WriteOptions { binary: Some(true), ..Default::default() },
                "binary",
            ),
            (
                "c.xyz",
                CloudRef { points: &points, scalars: &plain, ..Default::default() },
                WriteOptions::default(),
                "normals",
            ),
            ("c.stl", CloudRef { points: &points, ..Default::default() }, WriteOptions::default(), "triangles"),
            (
                "c.pcd",
                CloudRef { points: &points, triangles: Some(&[[0, 0, 0]]), ..Default::default() },
                WriteOptions::default(),
                "triangles",
            ),
            (
                "c.ply",
                CloudRef { points: &points, triangles: Some(&[[0, 1, 0]]), ..Default::default() },
                WriteOptions::default(),
                "triangles",
            ),
            (
                "c.obj",
                CloudRef { points: &points, ..Default::default() },
                WriteOptions { binary: Some(true), ..Default::default() },
                "binary",
            ),
            (
                "c.las",
                CloudRef { points: &points, triangles: Some(&[[0, 1, 2]]), ..Default::default() },
                WriteOptions::default(),
                "triangles",
            ),
            (
                "c.las",
                CloudRef { points: &points, ..Default::default() },
                WriteOptions { compressed: true, ..Default::default() },
                "compressed",
            ),
            (
                "c.ply",
                CloudRef { points: &points, ..Default::default() },
                WriteOptions { scale: Some(0.01), ..Default::default() },
                "scale",
            ),
            ("c.foo", CloudRef { points: &points, ..Default::default() }, WriteOptions::default(), "path"),
        ];
        for (name, data, options, arg) in cases {
            let path = temp(name);
            let e = write_file(&path, &data, options).unwrap_err();
            assert!(e.to_string().starts_with(&format!("{arg}:")), "{name}: {e}");
            assert!(!path.exists(), "{name}: nothing is written when the call is refused");
        }
    }

    #[test]
    fn unknown_extensions_list_every_format() {
        let e = read_file(Path::new("a.foo"), TextColumns::default()).unwrap_err().to_string();
        for (ext, _) in FileFormat::ALL {
            assert!(e.contains(&format!(".{ext}")), "{e}");
        }
        let e = read_file(Path::new("/nonexistent/machscan/a.ply"), TextColumns::default()).unwrap_err();
        assert!(matches!(e, Error::Io { kind: std::io::ErrorKind::NotFound, .. }), "{e:?}");
    }
}
