//! LZF decompression (the codec of PCD `binary_compressed`).
//!
//! Own code rather than the `lzf` crate: the format is a dozen lines to decode, and this version
//! checks every run and back-reference, never writes past the declared size, and reports the
//! compressed byte offset of the first bad token.

/// The largest expansion LZF can achieve: a 3-byte back-reference yields at most 264 bytes.
pub(crate) const MAX_RATIO: u64 = 88;

/// Decompresses `input` into exactly `out_len` bytes. The output grows with the bytes actually
/// produced (the reservation up front is at most 4 times the input), so a header that promises
/// more than the data holds fails before it costs memory.
pub(crate) fn decompress(input: &[u8], out_len: usize) -> Result<Vec<u8>, String> {
    let mut out: Vec<u8> = Vec::with_capacity(out_len.min(input.len().saturating_mul(4)));
    let mut i = 0usize;
    while i < input.len() {
        let at = i;
        let ctrl = input[i] as usize;
        i += 1;
        if ctrl < 32 {
            let len = ctrl + 1;
            let lit = input.get(i..i + len).ok_or_else(|| {
                format!("a literal run of {len} bytes at compressed byte {at} runs past the end of the data")
            })?;
            if out.len() + len > out_len {
                return Err(format!(
                    "the data at compressed byte {at} decompresses past the declared size of {out_len} bytes"
                ));
            }
            out.extend_from_slice(lit);
            i += len;
        } else {
            let mut len = ctrl >> 5;
            if len == 7 {
                len += *input.get(i).ok_or_else(|| format!("a back-reference at compressed byte {at} is cut off"))?
                    as usize;
                i += 1;
            }
            len += 2;
            let low =
                *input.get(i).ok_or_else(|| format!("a back-reference at compressed byte {at} is cut off"))? as usize;
            i += 1;
            let back = ((ctrl & 0x1f) << 8) + low + 1;
            if back > out.len() {
                return Err(format!(
                    "a back-reference at compressed byte {at} points {back} bytes back, before the start of the output ({} bytes so far)",
                    out.len()
                ));
            }
            if out.len() + len > out_len {
                return Err(format!(
                    "the data at compressed byte {at} decompresses past the declared size of {out_len} bytes"
                ));
            }
            let start = out.len() - back;
            if back >= len {
                out.extend_from_within(start..start + len);
            } else {
                // Overlapping copy: byte by byte, as it repeats a pattern.
                for k in 0..len {
                    let b = out[start + k];
                    out.push(b);
                }
            }
        }
    }
    if out.len() != out_len {
        return Err(format!("the data decompresses to {} bytes, but the header declares {out_len}", out.len()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literal_and_backref() {
        // "abc" literal, then a back-reference of length 6 at distance 3 (overlapping).
        let data = [2u8, b'a', b'b', b'c', (4 << 5), 2];
        assert_eq!(decompress(&data, 9).unwrap(), b"abcabcabc");
        assert!(decompress(&data, 8).is_err());
        assert!(decompress(&data, 10).is_err());
        assert!(decompress(&[0x20, 5], 3).unwrap_err().contains("before the start"));
        assert!(decompress(&[5, 1], 6).unwrap_err().contains("past the end"));
        assert!(decompress(&[0xe0], 9).unwrap_err().contains("cut off"));
    }
}
