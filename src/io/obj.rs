//! Wavefront OBJ: `v` lines and `f` lines (`i`, `i/t`, `i//n`, `i/t/n`, negative = relative).
//! A line ending in `\` continues on the next (a comment does not). Everything else (normals,
//! texture coordinates, groups, materials) is ignored.
//!
//! An own reader rather than `tobj`: only positions and face indices are needed, and errors
//! here name the line.

use super::util::{check_index, fan, parse_f64, parse_int, utf8_line, Lines};
use super::Raw;
use crate::{Error, Result};
use std::borrow::Cow;

pub(crate) const F: &str = "OBJ";

pub(crate) fn read(bytes: &[u8]) -> Result<Raw> {
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    // Faces are resolved at the end (positive indices may point forward); keep the line.
    let mut faces: Vec<(usize, usize, usize)> = Vec::new(); // (line, start in `corners`, len)
    let mut corners: Vec<i64> = Vec::new();
    for (n, raw) in Statements(Lines::new(bytes)) {
        let raw = &*raw;
        let trimmed = raw.trim_ascii_start();
        let is = |kw: &[u8]| trimmed.starts_with(kw) && trimmed.get(kw.len()).is_none_or(|b| b.is_ascii_whitespace());
        if is(b"v") {
            let line = utf8_line(F, n, raw)?;
            let mut t = line.split_ascii_whitespace().skip(1);
            let mut p = [0.0f64; 3];
            for (a, v) in p.iter_mut().enumerate() {
                let axis = ["x", "y", "z"][a];
                let tok = t
                    .next()
                    .ok_or_else(|| Error::parse(F, format!("line {n}: vertex has {a} coordinates, expected 3")))?;
                *v = parse_f64(F, n, axis, tok)?;
            }
            if vertices.len() == crate::limits::MAX_FILE_POINTS {
                crate::limits::check_file_points(F, vertices.len() as u64 + 1)?;
            }
            vertices.push(p);
        } else if is(b"f") {
            let line = utf8_line(F, n, raw)?;
            let start = corners.len();
            for tok in line.split_ascii_whitespace().skip(1) {
                let idx = tok.split('/').next().unwrap_or_default();
                let i = parse_int(F, n, "face vertex index", idx)?;
                let resolved = if i > 0 {
                    i - 1
                } else if i < 0 {
                    vertices.len() as i64 + i
                } else {
                    return Err(Error::parse(
                        F,
                        format!("line {n}: face vertex index 0 is invalid (OBJ indices start at 1)"),
                    ));
                };
                // Negative relative indices that go before the first vertex are out of range now.
                if resolved < 0 {
                    return Err(Error::parse(
                        F,
                        format!(
                            "line {n}: relative face index {i} points before the first vertex ({} vertices so far)",
                            vertices.len()
                        ),
                    ));
                }
                corners.push(resolved);
            }
            faces.push((n, start, corners.len()));
        }
    }
    let mut triangles = Vec::with_capacity(faces.len());
    let mut poly = Vec::new();
    for &(n, start, end) in &faces {
        poly.clear();
        for &c in &corners[start..end] {
            poly.push(check_index(F, c, vertices.len(), || format!("line {n}"))?);
        }
        fan(&poly, &mut triangles);
    }
    Ok(Raw { vertices, triangles })
}

/// The file's statements: its lines, a line ending in `\` (not a comment) joined to the next
/// (with a space in place of the backslash), each numbered by its first line.
struct Statements<'a>(Lines<'a>);

impl<'a> Iterator for Statements<'a> {
    type Item = (usize, Cow<'a, [u8]>);

    fn next(&mut self) -> Option<Self::Item> {
        let (n, first) = self.0.next()?;
        let Some(mut head) = continued(first) else {
            return Some((n, Cow::Borrowed(first)));
        };
        let mut joined = Vec::new();
        loop {
            joined.extend_from_slice(head);
            joined.push(b' ');
            let Some((_, line)) = self.0.next() else { break };
            match continued(line) {
                Some(h) => head = h,
                None => {
                    joined.extend_from_slice(line);
                    break;
                }
            }
        }
        Some((n, Cow::Owned(joined)))
    }
}

/// The line without its continuation backslash, when it ends in one and is not a comment.
pub(crate) fn continued(line: &[u8]) -> Option<&[u8]> {
    if line.trim_ascii_start().starts_with(b"#") {
        return None;
    }
    line.trim_ascii_end().strip_suffix(b"\\")
}

/// True when the first non-comment lines look like OBJ statements.
pub(crate) fn sniff(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(64 * 1024)];
    for (_, raw) in Lines::new(head).take(200) {
        let l = raw.trim_ascii();
        if l.is_empty() || l.starts_with(b"#") {
            continue;
        }
        let kw = l.split(|b| b.is_ascii_whitespace()).next().unwrap_or_default();
        match kw {
            b"v" => return true,
            b"vn" | b"vt" | b"o" | b"g" | b"s" | b"mtllib" | b"usemtl" => continue,
            _ => return false,
        }
    }
    false
}
