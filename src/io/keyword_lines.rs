//! Moving the coordinates of a line-based text format in which a keyword introduces three
//! values: OBJ's `v x y z` and `vn x y z`, ASCII STL's `vertex x y z` and `facet normal x y z`.
//! Every other byte is kept; the values are written as the file wrote its numbers
//! ([`NumberStyle`]).

use super::motion::Motion;
use super::number_style::{span, Rewrite, Styles};
use super::util::{parse_f64, utf8_line, Lines};
use crate::Result;

/// What the three values after a keyword are.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Triple {
    /// A position: mapped.
    Point,
    /// A direction: turned.
    Normal,
}

/// The keywords (as the tokens that start a line) and what follows them.
pub(super) type Keywords<'k> = &'k [(&'k [&'k str], Triple)];

/// The triple a line holds: what it is, and its three tokens.
fn triple<'a>(line: &'a str, keywords: Keywords) -> Option<(Triple, [&'a str; 3])> {
    let mut toks = line.split_ascii_whitespace();
    let first = toks.next()?;
    let (words, kind) = keywords.iter().find(|(words, _)| words[0] == first)?;
    for w in &words[1..] {
        if toks.next()? != *w {
            return None;
        }
    }
    Some((*kind, [toks.next()?, toks.next()?, toks.next()?]))
}

/// Calls `visit(line, kind, tokens, values)` for every line with a triple of numbers. A point
/// that is not three numbers is an error naming its line; a normal that is not is left out.
fn each_triple<'a>(
    bytes: &'a [u8],
    format: &'static str,
    keywords: Keywords,
    visit: &mut dyn FnMut(&'a str, Triple, [&'a str; 3], [f64; 3]),
) -> Result<()> {
    'lines: for (n, raw) in Lines::new(bytes) {
        if !keywords.iter().any(|(words, _)| raw.trim_ascii_start().starts_with(words[0].as_bytes())) {
            continue;
        }
        let line = utf8_line(format, n, raw)?;
        if let Some((kind, toks)) = triple(line, keywords) {
            let mut v = [0.0; 3];
            for a in 0..3 {
                match parse_f64(format, n, ["x", "y", "z"][a], toks[a]) {
                    Ok(x) => v[a] = x,
                    // the readers ignore normals: one that is not three numbers is kept as it is
                    Err(_) if kind == Triple::Normal => continue 'lines,
                    Err(e) => return Err(e),
                }
            }
            visit(line, kind, toks, v);
        }
    }
    Ok(())
}

/// The file with every keyword line's triple moved (points) or turned (normals): positions in
/// the style of the file's positions (shifted by the motion's scale), normals with at least six
/// decimals. A point that is not three numbers is an error naming its line (`format`); a normal
/// that is not, or a triple that is not finite, is kept as it is.
pub(super) fn move_keyword_lines(
    bytes: &[u8],
    format: &'static str,
    keywords: Keywords,
    motion: &Motion,
) -> Result<Vec<u8>> {
    // First pass: how the file writes its numbers.
    let mut styles = Styles::default();
    each_triple(bytes, format, keywords, &mut |_, kind, toks, v| {
        if kind == Triple::Normal {
            toks.iter().for_each(|t| styles.normal.learn(t));
        } else {
            toks.iter().for_each(|t| styles.position.learn(t));
            styles.bound(v);
        }
    })?;
    let styles = styles.for_writing(motion);
    // Second pass: the triples rewritten, the bytes between them copied.
    let mut out = Rewrite::new(bytes);
    each_triple(bytes, format, keywords, &mut |line, kind, toks, v| {
        if !v.iter().all(|v| v.is_finite()) {
            return;
        }
        let (moved, style) = match kind {
            Triple::Point => (motion.point(v), styles.position),
            Triple::Normal => (motion.normal(v), styles.normal),
        };
        let mut edits = [0, 1, 2].map(|a| (span(line, toks[a]), moved[a], style));
        out.line(line, &mut edits);
    })?;
    Ok(out.finish())
}
