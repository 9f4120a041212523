//! Object File Format: `OFF` and its `C`/`N`/`ST` variants (`COFF`, `NOFF`, `CNOFF`, `STOFF`, ...).
//!
//! Read line by line: one vertex per line (the first three numbers; colour, normal and texture
//! columns ignored), one face per line (`k i1 .. ik`, trailing face colours ignored). `#`
//! comments and blank lines are skipped. The counts may share the header line, as in
//! `OFF 8 6 0` or ModelNet's `OFF490 518 0`. `4OFF`, `nOFF` and `OFF BINARY` are rejected.

use super::util::{bounded_capacity, check_index, fan, parse_count, parse_f64, parse_int, show, utf8_line, Lines};
use super::Raw;
use crate::{Error, Result};

const F: &str = "OFF";

/// The next line holding something other than a comment, as its tokens.
fn next_tokens<'a>(lines: &mut Lines<'a>) -> Result<Option<(usize, Vec<&'a str>)>> {
    for (n, raw) in lines.by_ref() {
        let line = utf8_line(F, n, raw)?;
        let line = line.split('#').next().unwrap_or_default();
        let toks: Vec<&str> = line.split_ascii_whitespace().collect();
        if !toks.is_empty() {
            return Ok(Some((n, toks)));
        }
    }
    Ok(None)
}

/// Completes a record split over several lines (some writers put one face index per line):
/// appends the tokens of following lines until there are `need`; tokens past `need` on the last
/// line (colours) are left in place and ignored by the caller.
fn continue_record<'a>(
    lines: &mut Lines<'a>,
    mut toks: Vec<&'a str>,
    need: usize,
    what: impl Fn() -> String,
) -> Result<Vec<&'a str>> {
    while toks.len() < need {
        match next_tokens(lines)? {
            Some((_, more)) => toks.extend(more),
            None => {
                return Err(Error::parse(
                    F,
                    format!("the file ends inside {}: {} of {need} values present", what(), toks.len()),
                ))
            }
        }
    }
    Ok(toks)
}

/// Splits a header keyword like `CNOFF` or `OFF490` into (prefix, glued digits).
fn header_keyword(tok: &str) -> Option<(&str, &str)> {
    let i = tok.find("OFF")?;
    let (prefix, rest) = (&tok[..i], &tok[i + 3..]);
    if prefix.chars().all(|c| matches!(c, 'S' | 'T' | 'C' | 'N' | '4' | 'n'))
        && rest.chars().all(|c| c.is_ascii_digit())
    {
        Some((prefix, rest))
    } else {
        None
    }
}

/// The header's prefix (`C`, `N`, `ST`, ... before `OFF`), the vertex and face counts, and where
/// the vertices start.
struct Header<'a> {
    prefix: String,
    nv: u64,
    nf: u64,
    lines: Lines<'a>,
}

pub(crate) fn read(bytes: &[u8]) -> Result<Raw> {
    let Header { nv, nf, mut lines, .. } = header(bytes)?;
    // "0 0 0\n" is the shortest vertex line.
    let mut vertices = Vec::with_capacity(bounded_capacity(nv, lines.remaining(), 6));
    each_vertex(&mut lines, nv, &mut |n, toks| {
        vertices.push([parse_f64(F, n, "x", toks[0])?, parse_f64(F, n, "y", toks[1])?, parse_f64(F, n, "z", toks[2])?]);
        Ok(())
    })?;
    read_faces(&mut lines, nf, vertices)
}

/// Calls `visit(line number, tokens)` for each of the `nv` vertex records (at least three
/// tokens, a record split over lines joined; tokens are sub-slices of the file).
fn each_vertex<'a>(
    lines: &mut Lines<'a>,
    nv: u64,
    visit: &mut dyn FnMut(usize, &[&'a str]) -> Result<()>,
) -> Result<()> {
    for i in 0..nv {
        let (n, toks) = next_tokens(lines)?.ok_or_else(|| {
            Error::parse(
                F,
                format!("the file ends after {i} of the {nv} vertices the header declares (line {})", lines.line_no()),
            )
        })?;
        let toks = continue_record(lines, toks, 3, || format!("vertex {i} (line {n})"))?;
        visit(n, &toks)?;
    }
    Ok(())
}

/// The file's vertices, in order: `visit(line number, tokens)` for each (see [`each_vertex`]);
/// returns the header's prefix (`N` in it: a normal follows x, y, z).
pub(crate) fn vertex_records<'a>(
    bytes: &'a [u8],
    visit: &mut dyn FnMut(usize, &[&'a str]) -> Result<()>,
) -> Result<String> {
    let Header { prefix, nv, mut lines, .. } = header(bytes)?;
    each_vertex(&mut lines, nv, visit)?;
    Ok(prefix)
}

fn header(bytes: &[u8]) -> Result<Header<'_>> {
    let mut lines = Lines::new(bytes);
    let mut kind = String::new();
    let (hn, htoks) = next_tokens(&mut lines)?.ok_or_else(|| Error::parse(F, "the file is empty"))?;
    let mut count_toks: Vec<String> = Vec::new();
    let count_line;
    if htoks[0].chars().all(|c| c.is_ascii_digit()) {
        // No header keyword: the counts come first.
        count_line = hn;
        count_toks.extend(htoks.iter().map(|s| s.to_string()));
    } else {
        let (prefix, glued) = header_keyword(htoks[0])
            .ok_or_else(|| Error::parse(F, format!("line {hn}: expected an OFF header, found {}", show(htoks[0]))))?;
        if prefix.contains('4') || prefix.contains('n') {
            return Err(Error::parse(F, format!("line {hn}: {} (4D or n-dimensional OFF) is not supported", htoks[0])));
        }

        if htoks.get(1).is_some_and(|t| t.eq_ignore_ascii_case("BINARY")) {
            return Err(Error::parse(F, format!("line {hn}: binary OFF is not supported")));
        }
        kind = prefix.to_string();
        if !glued.is_empty() {
            count_toks.push(glued.to_string());
        }
        count_toks.extend(htoks[1..].iter().map(|s| s.to_string()));
        if count_toks.is_empty() {
            let (n, toks) = next_tokens(&mut lines)?.ok_or_else(|| {
                Error::parse(F, format!("the file ends after the header (line {hn}): no counts line"))
            })?;
            count_line = n;
            count_toks.extend(toks.iter().map(|s| s.to_string()));
        } else {
            count_line = hn;
        }
    }
    if count_toks.len() < 2 {
        return Err(Error::parse(F, format!("line {count_line}: expected the vertex and face counts")));
    }
    let nv = parse_count(F, count_line, "vertex count", &count_toks[0])?;
    crate::limits::check_file_points(F, nv)?;
    let nf = parse_count(F, count_line, "face count", &count_toks[1])?;
    Ok(Header { prefix: kind, nv, nf, lines })
}

/// The `nf` faces after the vertices, fan-triangulated, their indices checked.
fn read_faces(lines: &mut Lines, nf: u64, vertices: Vec<[f64; 3]>) -> Result<Raw> {
    let mut triangles = Vec::with_capacity(bounded_capacity(nf, lines.remaining(), 8));
    let mut poly = Vec::new();
    for f in 0..nf {
        let (n, toks) = next_tokens(lines)?.ok_or_else(|| {
            Error::parse(
                F,
                format!("the file ends after {f} of the {nf} faces the header declares (line {})", lines.line_no()),
            )
        })?;
        let k = parse_count(F, n, "face corner count", toks[0])?;
        let need = usize::try_from(k).unwrap_or(usize::MAX).saturating_add(1);
        let toks = continue_record(lines, toks, need, || format!("face {f} (line {n}, {k} corners)"))?;
        poly.clear();
        for tok in &toks[1..=k as usize] {
            let i = parse_int(F, n, "vertex index", tok)?;
            poly.push(check_index(F, i, vertices.len(), || format!("line {n} (face {f})"))?);
        }
        fan(&poly, &mut triangles);
    }
    Ok(Raw { vertices, triangles })
}

/// True when the first non-comment token is an OFF header keyword.
pub(crate) fn sniff(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(4096)];
    for (_, raw) in Lines::new(head) {
        let l = raw.trim_ascii();
        if l.is_empty() || l.starts_with(b"#") {
            continue;
        }
        let tok = l.split(|b| b.is_ascii_whitespace()).next().unwrap_or_default();
        return std::str::from_utf8(tok).ok().and_then(header_keyword).is_some();
    }
    false
}
