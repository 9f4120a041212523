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

/// The farthest a back-reference reaches, and the longest match it copies.
const MAX_BACK: usize = 1 << 13;
const MAX_MATCH: usize = 264;

/// Compresses `input` as LZF (what [`decompress`] reads; PCL's `binary_compressed` codec): a
/// greedy match finder over a hash of the next three bytes, literal runs of at most 32 bytes.
/// Input that does not compress grows by one byte in 32.
pub(crate) fn compress(input: &[u8]) -> Vec<u8> {
    const HASH_BITS: u32 = 14;
    let mut out = Vec::with_capacity(input.len() / 2 + 64);
    let mut table = vec![usize::MAX; 1 << HASH_BITS];
    let hash = |i: usize| {
        let v = u32::from_le_bytes([input[i], input[i + 1], input[i + 2], 0]);
        (v.wrapping_mul(2_654_435_761) >> (32 - HASH_BITS)) as usize
    };
    let flush = |out: &mut Vec<u8>, literals: &[u8]| {
        for run in literals.chunks(32) {
            out.push((run.len() - 1) as u8);
            out.extend_from_slice(run);
        }
    };
    let mut literal_start = 0;
    let mut i = 0;
    while i + 3 <= input.len() {
        let h = hash(i);
        let candidate = std::mem::replace(&mut table[h], i);
        let found = candidate < i && i - candidate <= MAX_BACK && input[candidate..candidate + 3] == input[i..i + 3];
        if !found {
            i += 1;
            continue;
        }
        let max = MAX_MATCH.min(input.len() - i);
        let mut len = 3;
        while len < max && input[candidate + len] == input[i + len] {
            len += 1;
        }
        flush(&mut out, &input[literal_start..i]);
        let back = i - candidate - 1;
        let l = len - 2;
        if l < 7 {
            out.push(((l << 5) | (back >> 8)) as u8);
        } else {
            out.push(((7 << 5) | (back >> 8)) as u8);
            out.push((l - 7) as u8);
        }
        out.push((back & 0xff) as u8);
        // The matched bytes enter the table too, so later data finds them.
        for k in i + 1..(i + len).min(input.len().saturating_sub(2)) {
            table[hash(k)] = k;
        }
        i += len;
        literal_start = i;
    }
    flush(&mut out, &input[literal_start..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compress_round_trips() {
        let mut state = 7u64;
        let noise: Vec<u8> = (0..5000)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 56) as u8
            })
            .collect();
        let repeats: Vec<u8> = (0..20_000u32).map(|i| (i % 7) as u8 * 3).collect();
        let floats: Vec<u8> = (0..4000).flat_map(|i| ((i / 10) as f32 * 0.5).to_le_bytes()).collect();
        for data in
            [&b""[..], b"a", b"ab", b"abc", b"aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa", &noise, &repeats, &floats]
        {
            let c = compress(data);
            assert_eq!(decompress(&c, data.len()).unwrap(), data, "{} bytes", data.len());
        }
        assert!(compress(&repeats).len() < repeats.len() / 50);
        assert!(compress(&noise).len() <= noise.len() + noise.len().div_ceil(32));
    }

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
