//! Text point lists: XYZ, PTS, CSV, TXT.
//!
//! Values are separated by whitespace, commas or semicolons. Before the first data row, lines
//! that are not data (column names, a PTS point-count line, anything with fewer than three
//! leading numbers) are skipped as a header. When a header line names the coordinate columns
//! (`x`, `y`, `z`, or `easting`, `northing`, `elevation`/`height`, case-insensitive; a `//` or
//! `#` comment line such as CloudCompare's `//X,Y,Z,R,G,B` counts), those columns are read, so a
//! survey's `PointID,Easting,Northing,Elevation` reads its coordinates, not its point numbers;
//! otherwise the first three numbers of a row are x, y, z; a header that names two of them but
//! not the third (`time easting northing depth`) is an error, since the first three numbers would
//! not be the coordinates. Other columns (intensity, colour,
//! normals) are ignored. Blank lines and `#` / `//` comments are skipped anywhere. After data has
//! started, a row without numbers in its coordinate columns is an error naming its line. A row
//! whose values, separated by whitespace or semicolons, are numbers written with decimal commas or
//! thousands separators (`1,5 2,5 3,5`, `1,000.5 2,000.5 3,000.5`) is an error too: the comma separator would
//! silently split them into other values.

use super::util::{parse_f64, show, split_fields, utf8_line, Lines};
use crate::{Error, Result};

const F: &str = "XYZ";

/// Where a row's values are: the columns (0-based fields) of x, y, z, and of a normal when the
/// header names one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Columns {
    pub(crate) xyz: [usize; 3],
    pub(crate) normal: Option<[usize; 3]>,
    /// Whether a header line named the columns (then a normal is where it names one, and only
    /// there).
    pub(crate) named: bool,
}

/// The first three fields, no normal: a list without column names.
const UNNAMED: Columns = Columns { xyz: [0, 1, 2], normal: None, named: false };

/// What a header line says about the coordinate columns.
enum Header {
    /// It names all three.
    Named(Columns),
    /// It names two of them: which, and which is missing (for the error).
    Partly(String),
    /// It names fewer (a title, a point count, other columns).
    Unnamed,
}

/// The names each coordinate column goes by (case-insensitive).
const COORDINATE_NAMES: [&[&str]; 3] =
    [&["x", "easting", "east"], &["y", "northing", "north"], &["z", "elevation", "elev", "height", "altitude", "alt"]];

/// The columns a header line names ([`Header`]).
fn named_columns(line: &str) -> Header {
    let names: Vec<String> =
        split_fields(line).map(|t| t.trim_matches(['"', '\'']).trim_start_matches("//").to_ascii_lowercase()).collect();
    let find = |aliases: &[&str]| names.iter().position(|n| aliases.contains(&n.as_str()));
    let found = COORDINATE_NAMES.map(find);
    let [Some(x), Some(y), Some(z)] = found else {
        if found.iter().flatten().count() < 2 {
            return Header::Unnamed;
        }
        let named: Vec<String> = found.iter().flatten().map(|&c| format!("{} (column {})", names[c], c + 1)).collect();
        let missing = ["x", "y", "z"][found.iter().position(Option::is_none).unwrap_or(2)];
        return Header::Partly(format!("{} but no {missing} column", named.join(" and ")));
    };
    let xyz = [x, y, z];
    let normal = match (
        find(&["nx", "normal_x", "normalx"]),
        find(&["ny", "normal_y", "normaly"]),
        find(&["nz", "normal_z", "normalz"]),
    ) {
        (Some(x), Some(y), Some(z)) => Some([x, y, z]),
        _ => None,
    };
    Header::Named(Columns { xyz, normal, named: true })
}

/// True when the line holds no data (blank or a comment).
fn is_comment(line: &str) -> bool {
    let l = line.trim_start();
    l.is_empty() || l.starts_with('#') || l.starts_with("//")
}

/// The line's text after its comment marker.
fn comment_text(line: &str) -> &str {
    let l = line.trim_start();
    l.strip_prefix("//").or_else(|| l.strip_prefix('#')).unwrap_or(l)
}

/// The three values of `fields` in `columns` (a point's, a normal's), when all three are numbers.
pub(crate) fn values(fields: &[&str], columns: [usize; 3]) -> Option<[f64; 3]> {
    let mut p = [0.0f64; 3];
    for (v, c) in p.iter_mut().zip(columns) {
        *v = fields.get(c)?.parse::<f64>().ok()?;
    }
    Some(p)
}

/// One data row, as [`scan`] hands it over.
pub(crate) struct Row<'a, 'b> {
    /// The line (without its terminator), a sub-slice of the file's bytes.
    pub(crate) line: &'a str,
    /// Its fields, sub-slices of `line`.
    pub(crate) fields: &'b [&'a str],
    /// Where its values are.
    pub(crate) columns: Columns,
    /// Its coordinates.
    pub(crate) point: [f64; 3],
}

/// Calls `visit` with every data row of a text point list, in order (see the module docs for
/// what a row is). Errors: a line that is not UTF-8, a row after the data started without
/// numbers in its coordinate columns, a file without any data row.
pub(crate) fn scan<'a>(bytes: &'a [u8], visit: &mut dyn FnMut(&Row<'a, '_>) -> Result<()>) -> Result<()> {
    let mut columns = UNNAMED;
    // a header that names two coordinate columns but not the third (a `depth`, a `height` spelt
    // otherwise): its rows' first three numbers are not the coordinates
    let mut partly: Option<(usize, String)> = None;
    let header =
        |n: usize, line: &str, columns: &mut Columns, partly: &mut Option<(usize, String)>| match named_columns(line) {
            Header::Named(c) => (*columns, *partly) = (c, None),
            Header::Partly(what) => *partly = Some((n, what)),
            Header::Unnamed => {}
        };
    let mut started = false;
    let mut fields: Vec<&'a str> = Vec::new();
    for (n, raw) in Lines::new(bytes) {
        let line = utf8_line(F, n, raw)?;
        if is_comment(line) {
            if !started {
                header(n, comment_text(line), &mut columns, &mut partly);
            }
            continue;
        }
        fields.clear();
        fields.extend(split_fields(line));
        match values(&fields, columns.xyz) {
            Some(_) if decimal_commas(line) => {
                return Err(Error::parse(
                    F,
                    format!(
                        "line {n}: {} holds numbers written with decimal commas (1,5 for 1.5) or thousands \
                         separators, which the comma separator would read as separate values: write the numbers \
                         with a decimal point (and no thousands separators) first",
                        show(line.trim())
                    ),
                ))
            }
            Some(_) if !started && partly.is_some() => {
                let (h, what) = partly.take().unwrap_or_default();
                return Err(Error::parse(
                    F,
                    format!(
                        "line {h}: the header names {what} (x, y, z, or easting, northing, elevation, \
                         case-insensitive), so the rows' first three numbers need not be the coordinates: name the \
                         missing column (a depth below the surface: negate it into an elevation, or name it z in \
                         every file registered with this one), or remove the header to read the first three numbers"
                    ),
                ));
            }
            Some(point) => {
                started = true;
                visit(&Row { line, fields: &fields, columns, point })?;
            }
            None if !started => header(n, line, &mut columns, &mut partly),
            None => return Err(bad_row(n, line, &fields, &columns)),
        }
    }
    if !started {
        return Err(Error::parse(F, "no line with three numbers (x y z) found: not a text point list"));
    }
    Ok(())
}

/// True when `line`, split at whitespace and semicolons into at least two numbers, holds a number
/// written with a decimal comma (`1,5`, `-0,25e3`) or thousands separators (`1,000`, `12,345.5`),
/// and no other token with a comma: numbers the comma separator would silently split into other
/// values (`1,5 2,5 3,5`, `1,5;2,5;3,5`). Comma-separated values (`1,2,3`, `12,345,678`,
/// `1.5, 2.5, 3.5`, `1,2,3,2024-01-01 12:00`, `1 2 3 255,0,0`) are not.
pub(crate) fn decimal_commas(line: &str) -> bool {
    // (every row is read through here: a row without a comma costs one scan of its bytes)
    if !line.contains(',') {
        return false;
    }
    let tokens = || line.split(|c: char| c.is_ascii_whitespace() || c == ';').filter(|t| !t.is_empty());
    if !tokens().filter(|t| t.contains(',')).all(|t| comma_decimal(t) || thousands(t)) {
        return false;
    }
    tokens().filter(|t| t.contains(',') || t.parse::<f64>().is_ok()).nth(1).is_some()
}

/// `[+-]digits,digits[e[+-]digits]`: a number with a decimal comma.
fn comma_decimal(t: &str) -> bool {
    let t = t.strip_prefix(['+', '-']).unwrap_or(t);
    let (mantissa, exponent) = match t.find(['e', 'E']) {
        Some(i) => (&t[..i], Some(&t[i + 1..])),
        None => (t, None),
    };
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let exponent_ok = exponent.is_none_or(|e| digits(e.strip_prefix(['+', '-']).unwrap_or(e)));
    mantissa.split_once(',').is_some_and(|(a, b)| digits(a) && digits(b)) && exponent_ok
}

/// `[+-]d[d[d]],ddd[,ddd...][.digits]`: a number with thousands separators.
fn thousands(t: &str) -> bool {
    let t = t.strip_prefix(['+', '-']).unwrap_or(t);
    let (int, frac) = t.split_once('.').unwrap_or((t, "0"));
    let mut groups = int.split(',');
    let first = groups.next().unwrap_or("");
    let digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    (1..=3).contains(&first.len())
        && digits(first)
        && int.contains(',')
        && groups.all(|g| g.len() == 3 && digits(g))
        && !frac.is_empty()
        && digits(frac)
}

/// The error for a row after the data started whose coordinates are not all numbers.
fn bad_row(n: usize, line: &str, fields: &[&str], columns: &Columns) -> Error {
    // Name the offending value when there is one.
    for (k, &c) in columns.xyz.iter().enumerate() {
        if let Some(t) = fields.get(c) {
            if let Err(e) = parse_f64(F, n, ["x", "y", "z"][k], t) {
                return e;
            }
        }
    }
    let wanted = if *columns == UNNAMED {
        "at least 3 numbers (x y z)".to_string()
    } else {
        format!("x, y, z in columns {:?} (named in the header)", columns.xyz.map(|c| c + 1))
    };
    Error::parse(F, format!("line {n}: expected {wanted}, found {} fields in {}", fields.len(), show(line.trim())))
}

pub(crate) fn read(bytes: &[u8]) -> Result<Vec<[f64; 3]>> {
    let mut out = Vec::new();
    scan(bytes, &mut |row| {
        if out.len() == crate::limits::MAX_FILE_POINTS {
            crate::limits::check_file_points(F, out.len() as u64 + 1)?;
        }
        out.push(row.point);
        Ok(())
    })?;
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
        let fields: Vec<&str> = split_fields(line).take(3).collect();
        if values(&fields, UNNAMED.xyz).is_some() {
            return true;
        }
        seen += 1;
        if seen >= 50 {
            return false;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_names_pick_the_columns() {
        let csv = b"PointID,Easting,Northing,Elevation,Code\n1,500000.25,4100000.5,12.0,TREE\n2,500001.0,4100001.0,13.5,POLE\n";
        assert_eq!(read(csv).unwrap(), vec![[500000.25, 4100000.5, 12.0], [500001.0, 4100001.0, 13.5]]);
        let cc = b"//X,Y,Z,R,G,B,Nx,Ny,Nz\n1,2,3,255,0,0,0,0,1\n";
        let mut cols = None;
        scan(cc, &mut |r: &Row| {
            cols = Some(r.columns);
            Ok(())
        })
        .unwrap();
        assert_eq!(cols, Some(Columns { xyz: [0, 1, 2], normal: Some([6, 7, 8]), named: true }));
        // Named columns, and a later row without a number there: the error names the column.
        let e = read(b"id x y z\n7 1 2 3\n8 1 y 3\n").unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("'y'"), "{e}");
        let e = read(b"id x y z\n7 1 2 3\n8 1\n").unwrap_err().to_string();
        assert!(e.contains("columns [2, 3, 4]"), "{e}");
        // Unnamed: the first three numbers, as before.
        assert_eq!(read(b"12\n1 2 3 9 9 9\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"survey of x\n1 2 3\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        // Two coordinates named, the third not: not the first three numbers (a time column first)
        let e = read(b"time easting northing depth\n1700000000.5 512202.86 5712095.35 -25.1\n").unwrap_err();
        let e = e.to_string();
        assert!(e.contains("line 1") && e.contains("easting (column 2) and northing (column 3) but no z"), "{e}");
        let e = read(b"# X;Y;Depth\n1;2;3\n").unwrap_err().to_string();
        assert!(e.contains("x (column 1) and y (column 2) but no z"), "{e}");
        // a later header that names all three is read
        assert_eq!(read(b"x y depth\nid x y z\n7 1 2 3\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
    }

    #[test]
    fn decimal_commas_are_refused_not_split() {
        for text in [
            &b"1,5 2,5 3,5\n"[..],
            b"x;y;z\n1,5;2,5;3,5\n",
            b"1,5\t2,5\t3,5\n",
            b"1 2 3\n1 000,5 2 3\n",
            b"-1,5e-3 2,5 3,5 12.03.2024\n",
            b"1,000.5 2,000.5 3,000.5\n",
            b"1,5 2,5\n",
        ] {
            let e = read(text).unwrap_err().to_string();
            assert!(e.contains("decimal commas"), "{e}");
        }
        let e = read(b"1.5 2.5 3.5\n4 5 6\n1,5 2,5 3,5\n").unwrap_err().to_string();
        assert!(e.contains("line 3"), "{e}");
        // comma-separated values, with or without spaces, decimal points or labels
        assert_eq!(read(b"1,2,3\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"1.5, 2.5, 3.5\n").unwrap(), vec![[1.5, 2.5, 3.5]]);
        assert_eq!(read(b"1,2,3,Big tree\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"1;2;3\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"1,5,2,5,3,5\n").unwrap(), vec![[1.0, 5.0, 2.0]]);
        // comma-separated values beside a field with spaces, a note, a colour
        assert_eq!(read(b"x,y,z,time\n1,2,3,2024-01-01 12:00:00\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"1,2,3 # note\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"1 2 3 255,0,0\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"1\t2\t3\tOak, big\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
        assert_eq!(read(b"1e-3,2e-3,3e-3\n").unwrap(), vec![[1e-3, 2e-3, 3e-3]]);
        // one token of integers in groups of three is three values, not one number with
        // thousands separators (which would leave the row without y and z)
        assert_eq!(read(b"12,345,678\n").unwrap(), vec![[12.0, 345.0, 678.0]]);
        assert_eq!(read(b"-12,345,678 # a note\n").unwrap(), vec![[-12.0, 345.0, 678.0]]);
        // a header line is not data
        assert_eq!(read(b"Created 30,11 2026\n1 2 3\n").unwrap(), vec![[1.0, 2.0, 3.0]]);
    }
}
