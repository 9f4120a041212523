//! Shared helpers of the readers: a line cursor over bytes, number parsing with positions, and
//! the rule that bounds every reservation by what the remaining bytes could hold.

use crate::{Error, Result};

/// The little-endian `u32` at byte `at` of `b` (the caller has checked that four bytes are there).
pub(crate) fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

/// Iterates the lines of a byte slice (split on `\n`, a trailing `\r` stripped), numbering them
/// from 1, and remembers the byte offset of the next line (where a binary body starts).
#[derive(Clone)]
pub(crate) struct Lines<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, pos: 0, line: 0 }
    }

    /// Continues from byte `pos`, the next line being numbered `line + 1`.
    pub(crate) fn at(bytes: &'a [u8], pos: usize, line: usize) -> Self {
        Self { bytes, pos: pos.min(bytes.len()), line }
    }

    /// Byte offset of the start of the next line.
    pub(crate) fn offset(&self) -> usize {
        self.pos
    }

    /// Number of the last line returned (0 before the first).
    pub(crate) fn line_no(&self) -> usize {
        self.line
    }

    /// Bytes not yet returned.
    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
}

impl<'a> Iterator for Lines<'a> {
    /// `(line number, line without its terminator)`.
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.bytes.len() {
            return None;
        }
        let rest = &self.bytes[self.pos..];
        let (line, advance) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += advance;
        self.line += 1;
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        Some((self.line, line))
    }
}

/// The line as UTF-8 text, or an error naming the line.
pub(crate) fn utf8_line<'a>(format: &'static str, line_no: usize, line: &'a [u8]) -> Result<&'a str> {
    std::str::from_utf8(line).map_err(|e| {
        Error::parse(
            format,
            format!("line {line_no} is not valid UTF-8 text (invalid byte at column {})", e.valid_up_to() + 1),
        )
    })
}

/// Shortens a token for an error message (hostile input can hold megabyte-long "tokens").
pub(crate) fn show(token: &str) -> String {
    const MAX: usize = 40;
    if token.chars().count() <= MAX {
        format!("'{token}'")
    } else {
        let short: String = token.chars().take(MAX).collect();
        format!("'{short}...'")
    }
}

/// Parses a coordinate token in `f64` (`nan`, `inf` accepted: validation happens later).
pub(crate) fn parse_f64(format: &'static str, line_no: usize, what: &str, token: &str) -> Result<f64> {
    token
        .parse::<f64>()
        .map_err(|_| Error::parse(format, format!("line {line_no}: {what} {} is not a number", show(token))))
}

/// Parses an integer token.
pub(crate) fn parse_int(format: &'static str, line_no: usize, what: &str, token: &str) -> Result<i64> {
    token
        .parse::<i64>()
        .map_err(|_| Error::parse(format, format!("line {line_no}: {what} {} is not an integer", show(token))))
}

/// Parses a non-negative count token.
pub(crate) fn parse_count(format: &'static str, line_no: usize, what: &str, token: &str) -> Result<u64> {
    token.parse::<u64>().map_err(|_| {
        Error::parse(format, format!("line {line_no}: {what} {} is not a non-negative integer", show(token)))
    })
}

/// How many items to reserve room for: what the header claims, but never more than the
/// remaining bytes could hold at `min_item_bytes` each (a lying header cannot make us allocate).
pub(crate) fn bounded_capacity(claimed: u64, remaining_bytes: usize, min_item_bytes: usize) -> usize {
    let fit = remaining_bytes / min_item_bytes.max(1);
    usize::try_from(claimed).unwrap_or(usize::MAX).min(fit)
}

/// Resolves a 0-based vertex index of a face, checking it against the vertex count.
pub(crate) fn check_index(
    format: &'static str,
    index: i64,
    n_vertices: usize,
    where_: impl FnOnce() -> String,
) -> Result<u32> {
    if index < 0 || index as u64 >= n_vertices as u64 || index > u32::MAX as i64 {
        return Err(Error::parse(
            format,
            format!("{}: vertex index {index} is out of range ({n_vertices} vertices)", where_()),
        ));
    }
    Ok(index as u32)
}

/// Appends the fan triangulation of a polygon (`[a, b, c, d]` gives `abc`, `acd`); polygons with
/// fewer than 3 corners give nothing.
pub(crate) fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    if poly.len() >= 3 {
        for k in 1..poly.len() - 1 {
            out.push([poly[0], poly[k], poly[k + 1]]);
        }
    }
}

/// Puts `edits` (each replacing a byte range of a text) in the text's order, by the start of each
/// one's range (`start`): an insertion sort, for the few edits of a line or an XML section (the
/// library's sorts would add kilobytes to the WebAssembly module for this).
pub(crate) fn in_text_order<T>(edits: &mut [T], start: impl Fn(&T) -> usize) {
    for i in 1..edits.len() {
        let mut j = i;
        while j > 0 && start(&edits[j - 1]) > start(&edits[j]) {
            edits.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// Splits a text line into tokens separated by whitespace, commas or semicolons (empty tokens
/// dropped).
pub(crate) fn split_fields(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c.is_ascii_whitespace() || c == ',' || c == ';').filter(|t| !t.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_strip_cr_and_track_offsets() {
        let b = b"a\r\nbb\n\nc";
        let mut l = Lines::new(b);
        assert_eq!(l.next(), Some((1, &b"a"[..])));
        assert_eq!(l.offset(), 3);
        assert_eq!(l.next(), Some((2, &b"bb"[..])));
        assert_eq!(l.next(), Some((3, &b""[..])));
        assert_eq!(l.next(), Some((4, &b"c"[..])));
        assert_eq!(l.next(), None);
    }

    #[test]
    fn capacity_is_bounded_by_bytes() {
        assert_eq!(bounded_capacity(4_000_000_000, 1024, 12), 85);
        assert_eq!(bounded_capacity(10, 1024, 12), 10);
        assert_eq!(bounded_capacity(u64::MAX, 0, 0), 0);
    }

    #[test]
    fn fan_triangulates() {
        let mut t = Vec::new();
        fan(&[0, 1, 2, 3, 4], &mut t);
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
        fan(&[0, 1], &mut t);
        assert_eq!(t.len(), 3);
    }
}
