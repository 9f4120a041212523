//! Text point lists: XYZ, PTS, CSV, TXT.
//!
//! Values are separated by whitespace, commas or semicolons; the first three numbers of a row
//! are x, y, z and extra columns (intensity, colour, normals) are ignored. Before the first data
//! row, lines that are not data (column names, a PTS point-count line, anything with fewer than
//! three leading numbers) are skipped as a header. Blank lines and `#` / `//` comments are
//! skipped anywhere. After data has started, a row without three leading numbers is an error
//! naming its line.

use super::util::{parse_f64, show, split_fields, utf8_line, Lines};
use crate::{Error, Result};

const F: &str = "XYZ";

fn data_row(line: &str) -> Option<[f64; 3]> {
    let mut t = split_fields(line);
    let mut p = [0.0f64; 3];
    for v in &mut p {
        *v = t.next()?.parse::<f64>().ok()?;
    }
    Some(p)
}

/// True when the line holds no data (blank or a comment).
fn is_comment(line: &str) -> bool {
    let l = line.trim_start();
    l.is_empty() || l.starts_with('#') || l.starts_with("//")
}

pub(crate) fn read(bytes: &[u8]) -> Result<Vec<[f64; 3]>> {
    let mut out = Vec::new();
    let mut started = false;
    for (n, raw) in Lines::new(bytes) {
        let line = utf8_line(F, n, raw)?;
        if is_comment(line) {
            continue;
        }
        match data_row(line) {
            Some(p) => {
                started = true;
                if out.len() == crate::limits::MAX_FILE_POINTS {
                    crate::limits::check_file_points(F, out.len() as u64 + 1)?;
                }
                out.push(p);
            }
            None if !started => {} // header
            None => {
                let toks: Vec<&str> = split_fields(line).take(3).collect();
                // Name the offending value when there is one.
                for (k, t) in toks.iter().enumerate() {
                    parse_f64(F, n, ["x", "y", "z"][k], t)?;
                }
                return Err(Error::parse(
                    F,
                    format!(
                        "line {n}: expected at least 3 numbers (x y z), found {} in {}",
                        toks.len(),
                        show(line.trim())
                    ),
                ));
            }
        }
    }
    if !started {
        return Err(Error::parse(F, "no line with three numbers (x y z) found: not a text point list"));
    }
    Ok(out)
}

/// True when the content looks like a text point list (for sniffing): valid UTF-8 in the first
/// lines and a row of three numbers among the first 50 non-comment lines.
pub(crate) fn sniff(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(64 * 1024)];
    let mut seen = 0;
    for (_, raw) in Lines::new(head) {
        let Ok(line) = std::str::from_utf8(raw) else {
            return false;
        };
        if is_comment(line) {
            continue;
        }
        if data_row(line).is_some() {
            return true;
        }
        seen += 1;
        if seen >= 50 {
            return false;
        }
    }
    false
}
