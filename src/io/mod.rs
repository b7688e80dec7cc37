//! Point cloud and scan files (SPEC F formats).
mod apt;
mod lzf;
mod pcd;
mod ply;
mod text;

pub use apt::{parse_apt, read_apt, write_apt, Toolpath};
pub use lzf::{lzf_decompress, lzf_store};
pub use pcd::{parse_pcd, read_pcd, write_pcd, PcdData, PcdEncoding};

pub use ply::{parse_ply, read_ply, write_ply, PlyData, PlyScalar};
pub use text::{parse_mesh_txt, read_xyz, write_xyz};

#[cfg(test)]
mod robustness {
    //! Truncated and corrupted files: the parsers answer with an error or a result, never a
    //! panic. (A deterministic mutation sweep; the cargo-fuzz targets go further.)
    use super::*;
    use std::path::Path;

    fn lcg(s: &mut u64) -> u64 {
        *s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        *s >> 33
    }

    fn sweep(valid: &[u8], parse: impl Fn(&[u8]) -> bool) {
        assert!(parse(valid), "the valid file must parse");
        for cut in 0..valid.len() {
            let _ = parse(&valid[..cut]);
        }
        let mut s = 99u64;
        for _ in 0..3000 {
            let mut b = valid.to_vec();
            for _ in 0..1 + lcg(&mut s) % 4 {
                let i = (lcg(&mut s) as usize) % b.len();
                b[i] = lcg(&mut s) as u8;
            }
            let _ = parse(&b);
        }
    }

    fn sample_ply(binary: bool) -> Vec<u8> {
        let dir = std::env::temp_dir().join(format!("machscan-ply-{}-{binary}", std::process::id()));
        let pts: Vec<f64> = (0..30).map(|i| i as f64 * 0.37).collect();
        let s = [0.5; 10];
        write_ply(&dir, &pts, Some(&pts), &[PlyScalar { name: "a", values: &s }], binary).unwrap();
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
        fn lzf_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200), out_len in 0usize..2000) {
            let _ = lzf_decompress(&bytes, out_len);
        }
    }
}
