//! LZF decompression (Marc Lehmann's liblzf format), as PCL's `binary_compressed` PCD uses it.
//!
//! Written here: the format is forty lines, and the crates that have it pull in C code or are
//! unmaintained. Every read and back-reference is bounds-checked: a bad stream is an error,
//! never a panic or garbage.

/// Decompresses `input` into exactly `out_len` bytes.
pub fn lzf_decompress(input: &[u8], out_len: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(out_len);
    let mut ip = 0usize;
    while ip < input.len() {
        let ctrl = input[ip] as usize;
        ip += 1;
        if ctrl < 32 {
            // Literal run of ctrl + 1 bytes.
            let len = ctrl + 1;
            if ip + len > input.len() {
                return Err(format!(
                    "bad LZF stream: a literal run of {len} bytes at input byte {} runs past the end",
                    ip - 1
                ));
            }
            if out.len() + len > out_len {
                return Err(format!("bad LZF stream: it decompresses to more than the {out_len} bytes announced"));
            }
            out.extend_from_slice(&input[ip..ip + len]);
            ip += len;
        } else {
            // Back reference: length (ctrl >> 5) + 2, offset from the low bits and the next byte.
            let mut len = ctrl >> 5;
            if len == 7 {
                let extra = *input.get(ip).ok_or("bad LZF stream: truncated back reference")?;
                len += extra as usize;
                ip += 1;
            }
            len += 2;
            let low = *input.get(ip).ok_or("bad LZF stream: truncated back reference")? as usize;
            ip += 1;
            let back = ((ctrl & 0x1f) << 8) + low + 1;
            if back > out.len() {
                return Err(format!(
                    "bad LZF stream: a back reference reaches {back} bytes back with only {} written",
                    out.len()
                ));
            }
            if out.len() + len > out_len {
                return Err(format!("bad LZF stream: it decompresses to more than the {out_len} bytes announced"));
            }
            let start = out.len() - back;
            // Byte by byte: the source may overlap what is being written (runs).
            for k in 0..len {
                let b = out[start + k];
                out.push(b);
            }
        }
    }
    if out.len() != out_len {
        return Err(format!("bad LZF stream: it decompresses to {} bytes, the header announces {out_len}", out.len()));
    }
    Ok(out)
}

/// LZF compression, literal runs only (valid LZF any decoder reads; used to write test files and
/// `binary_compressed` PCD without a compressor's complexity).
pub fn lzf_store(input: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(input.len() + input.len() / 32 + 1);
    for chunk in input.chunks(32) {
        out.push((chunk.len() - 1) as u8);
        out.extend_from_slice(chunk);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_runs() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        assert_eq!(lzf_decompress(&lzf_store(&data), data.len()).unwrap(), data);
        // "abc" then a back reference of length 9 at distance 3: "abcabcabcabc".
        let stream = [2u8, b'a', b'b', b'c', 7 << 5, 0, 2];
        // len = 7 + 0 + 2 = 9, back = (0 << 8) + 2 + 1 = 3
        assert_eq!(lzf_decompress(&stream, 12).unwrap(), b"abcabcabcabc");
    }

    #[test]
    fn bad_streams_are_errors() {
        assert!(lzf_decompress(&[5, 1, 2], 6).is_err()); // literal past the end
        assert!(lzf_decompress(&[0, 1, 0x20, 9], 4).is_err()); // reference before the start
        assert!(lzf_decompress(&[0, 1], 5).is_err()); // too short
        assert!(lzf_decompress(&[0, 1, 0x20], 4).is_err()); // truncated reference
    }
}
