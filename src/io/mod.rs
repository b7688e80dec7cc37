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
pub use text::{read_xyz, write_xyz};

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
        let head = "VERSION 0.7\nFIELDS x y z i\nSIZE 4 4 4 2\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 8\nHEIGHT 1\nPOINTS 8\n";
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
