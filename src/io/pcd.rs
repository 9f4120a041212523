//! PCD reader (DATA ascii, binary, binary_compressed), organised clouds included.
//!
//! An own parser rather than `pcd-rs`: that crate decodes into typed or dynamic records with
//! owned field vectors per point, and its LZF path allocates the size the header declares
//! before checking it; here x/y/z are read straight from their offsets and every size is
//! checked against the bytes present first.

use super::util::{bounded_capacity, parse_count, parse_f64, show, utf8_line, Lines};
use super::{lzf, Raw};
use crate::{Error, Result};

const F: &str = "PCD";

#[derive(Clone, Debug)]
struct Field {
    name: String,
    size: usize,
    ty: char,
    count: usize,
}

impl Field {
    fn bytes(&self) -> usize {
        self.size * self.count
    }

    /// Decodes one little-endian value of this field.
    fn read_f64(&self, b: &[u8]) -> f64 {
        match (self.ty, self.size) {
            ('F', 4) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            ('F', 8) => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
            ('I', 1) => b[0] as i8 as f64,
            ('U', 1) => b[0] as f64,
            ('I', 2) => i16::from_le_bytes([b[0], b[1]]) as f64,
            ('U', 2) => u16::from_le_bytes([b[0], b[1]]) as f64,
            ('I', 4) => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            ('U', 4) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            ('I', 8) => i64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]) as f64,
            // Checked at header time: only U8 is left.
            _ => u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]) as f64,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Data {
    Ascii,
    Binary,
    Compressed,
}

pub(crate) fn read(bytes: &[u8]) -> Result<Raw> {
    let mut lines = Lines::new(bytes);
    let mut names: Option<Vec<String>> = None;
    let mut sizes: Option<(usize, Vec<usize>)> = None;
    let mut types: Option<(usize, Vec<char>)> = None;
    let mut counts: Option<(usize, Vec<usize>)> = None;
    let mut width: Option<u64> = None;
    let mut height: Option<u64> = None;
    let mut points: Option<u64> = None;
    let mut data = None;
    let mut fields_line = 0;
    for (n, raw) in lines.by_ref() {
        let line =
            utf8_line(F, n, raw).map_err(|_| Error::parse(F, format!("header line {n} is not valid UTF-8 text")))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut t = line.split_ascii_whitespace();
        let key = t.next().unwrap_or_default();
        let values: Vec<&str> = t.collect();
        let one = |what: &str| -> Result<u64> {
            match values.as_slice() {
                [v] => parse_count(F, n, what, v),
                _ => Err(Error::parse(F, format!("line {n}: {key} needs exactly one value"))),
            }
        };
        match key.to_ascii_uppercase().as_str() {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" | "COLUMNS" => {
                names = Some(values.iter().map(|s| s.to_string()).collect());
                fields_line = n;
            }
            "SIZE" => {
                let v = values
                    .iter()
                    .map(|s| parse_count(F, n, "SIZE", s).map(|v| v as usize))
                    .collect::<Result<Vec<_>>>()?;
                sizes = Some((n, v));
            }
            "TYPE" => {
                let v = values
                    .iter()
                    .map(|s| match *s {
                        "F" | "I" | "U" => Ok(s.chars().next().unwrap_or('F')),
                        _ => Err(Error::parse(F, format!("line {n}: unknown TYPE {} (expected F, I or U)", show(s)))),
                    })
                    .collect::<Result<Vec<_>>>()?;
                types = Some((n, v));
            }
            "COUNT" => {
                let v = values
                    .iter()
                    .map(|s| parse_count(F, n, "COUNT", s).map(|v| usize::try_from(v).unwrap_or(usize::MAX)))
                    .collect::<Result<Vec<_>>>()?;
                counts = Some((n, v));
            }
            "WIDTH" => width = Some(one("WIDTH")?),
            "HEIGHT" => height = Some(one("HEIGHT")?),
            "POINTS" => points = Some(one("POINTS")?),
            "DATA" => {
                data = Some(match values.first().map(|s| s.to_ascii_lowercase()).as_deref() {
                    Some("ascii") => Data::Ascii,
                    Some("binary") => Data::Binary,
                    Some("binary_compressed") => Data::Compressed,
                    _ => {
                        return Err(Error::parse(
                            F,
                            format!(
                                "line {n}: unknown DATA {} (expected ascii, binary or binary_compressed)",
                                show(values.first().copied().unwrap_or(""))
                            ),
                        ))
                    }
                });
                break;
            }
            _ => return Err(Error::parse(F, format!("line {n}: unknown header keyword {}", show(key)))),
        }
    }
    let data = data.ok_or_else(|| Error::parse(F, "the header has no DATA line"))?;
    let names = names.ok_or_else(|| Error::parse(F, "the header has no FIELDS line"))?;
    let nf = names.len();
    let check_len = |what: &str, got: Option<(usize, usize)>| -> Result<()> {
        match got {
            Some((line, len)) if len != nf => Err(Error::parse(
                F,
                format!("line {line}: {what} has {len} entries but FIELDS (line {fields_line}) names {nf}"),
            )),
            _ => Ok(()),
        }
    };
    let (sizes_line, sizes) = sizes.ok_or_else(|| Error::parse(F, "the header has no SIZE line"))?;
    let (types_line, types) = types.ok_or_else(|| Error::parse(F, "the header has no TYPE line"))?;
    check_len("SIZE", Some((sizes_line, sizes.len())))?;
    check_len("TYPE", Some((types_line, types.len())))?;
    check_len("COUNT", counts.as_ref().map(|(l, c)| (*l, c.len())))?;
    let counts = counts.map(|(_, c)| c).unwrap_or_else(|| vec![1; nf]);
    let mut fields = Vec::with_capacity(nf);
    for i in 0..nf {
        let f = Field { name: names[i].clone(), size: sizes[i], ty: types[i], count: counts[i] };
        let ok = match f.ty {
            'F' => f.size == 4 || f.size == 8,
            _ => matches!(f.size, 1 | 2 | 4 | 8),
        };
        if !ok {
            return Err(Error::parse(
                F,
                format!("field '{}' has TYPE {} with SIZE {}, which is not a valid combination", f.name, f.ty, f.size),
            ));
        }
        fields.push(f);
    }
    let width = width.ok_or_else(|| Error::parse(F, "the header has no WIDTH line"))?;
    let height = height.unwrap_or(1);
    let wh = width
        .checked_mul(height)
        .ok_or_else(|| Error::parse(F, format!("WIDTH {width} x HEIGHT {height} overflows")))?;
    let n_points = points.unwrap_or(wh);
    if n_points != wh {
        return Err(Error::parse(F, format!("WIDTH {width} x HEIGHT {height} = {wh}, but POINTS is {n_points}")));
    }
    crate::limits::check_file_points(F, n_points)?;
    // Where x, y, z are: field index, value index (in ascii tokens), byte offset in a record.
    let mut axes = [(0usize, 0usize, 0usize); 3];
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        let i = fields
            .iter()
            .position(|f| f.name == *axis)
            .ok_or_else(|| Error::parse(F, format!("FIELDS has no '{axis}' field")))?;
        if fields[i].count != 1 {
            return Err(Error::parse(F, format!("field '{axis}' has COUNT {}, expected 1", fields[i].count)));
        }
        let token: usize = fields[..i].iter().map(|f| f.count).fold(0, usize::saturating_add);
        let offset: usize = fields[..i].iter().map(|f| f.size.saturating_mul(f.count)).fold(0, usize::saturating_add);
        axes[a] = (i, token, offset);
    }
    let stride = fields
        .iter()
        .try_fold(0usize, |acc, f| f.size.checked_mul(f.count).and_then(|b| acc.checked_add(b)))
        .ok_or_else(|| Error::parse(F, "the point record size (SIZE x COUNT summed) overflows"))?;
    let body_at = lines.offset();
    let body = &bytes[body_at..];
    let mut out = Vec::new();
    match data {
        Data::Ascii => {
            let n_tokens: usize = fields.iter().map(|f| f.count).fold(0, usize::saturating_add);
            out.reserve(bounded_capacity(n_points, body.len(), n_tokens.saturating_mul(2)));
            let mut read = 0u64;
            while read < n_points {
                let Some((n, raw)) = lines.next() else {
                    return Err(Error::parse(
                        F,
                        format!(
                            "the file ends after {read} of the {n_points} points the header declares (line {})",
                            lines.line_no()
                        ),
                    ));
                };
                let line = utf8_line(F, n, raw)?;
                let toks: Vec<&str> = line.split_ascii_whitespace().take(n_tokens).collect();
                if toks.is_empty() {
                    continue;
                }
                if toks.len() < n_tokens {
                    return Err(Error::parse(
                        F,
                        format!("line {n}: expected {n_tokens} values per point, found {}", toks.len()),
                    ));
                }
                let mut p = [0.0f64; 3];
                for a in 0..3 {
                    p[a] = parse_f64(F, n, &format!("field '{}'", fields[axes[a].0].name), toks[axes[a].1])?;
                }
                out.push(p);
                read += 1;
            }
        }
        Data::Binary => {
            let need = n_points.checked_mul(stride as u64);
            if need.is_none_or(|need| need > body.len() as u64) {
                return Err(Error::parse(
                    F,
                    format!(
                        "truncated binary data: {n_points} points of {stride} bytes need {} bytes after byte offset {body_at}, but only {} remain",
                        need.map_or("too many".to_string(), |v| v.to_string()),
                        body.len()
                    ),
                ));
            }
            if stride > 0 {
                let n = n_points as usize;
                out.reserve(n);
                for rec in body[..n * stride].chunks_exact(stride) {
                    out.push([0, 1, 2].map(|a| {
                        let (fi, _, off) = axes[a];
                        fields[fi].read_f64(&rec[off..off + fields[fi].size])
                    }));
                }
            } else {
                // Only reachable when x/y/z have SIZE... never: x/y/z have a valid nonzero size.
                return Err(Error::parse(F, "point records have zero size"));
            }
        }
        Data::Compressed => {
            let head = body.get(..8).ok_or_else(|| {
                Error::parse(
                    F,
                    format!(
                        "binary_compressed data is cut off at byte offset {body_at}: the 8-byte size header is missing"
                    ),
                )
            })?;
            let comp = u32::from_le_bytes([head[0], head[1], head[2], head[3]]) as usize;
            let uncomp = u32::from_le_bytes([head[4], head[5], head[6], head[7]]) as u64;
            let payload = 8usize.checked_add(comp).and_then(|end| body.get(8..end)).ok_or_else(|| {
                Error::parse(
                    F,
                    format!(
                        "truncated binary_compressed data: the header declares {comp} compressed bytes after byte offset {}, but only {} remain",
                        body_at + 8,
                        body.len() - 8
                    ),
                )
            })?;
            let need = n_points.checked_mul(stride as u64);
            if need != Some(uncomp) {
                return Err(Error::parse(
                    F,
                    format!(
                        "binary_compressed data declares {uncomp} uncompressed bytes, but {n_points} points of {stride} bytes need {}",
                        need.map_or("more".to_string(), |v| v.to_string())
                    ),
                ));
            }
            if uncomp > crate::limits::MAX_DECODED_BYTES {
                return Err(Error::TooLarge(format!(
                    "PCD binary_compressed data declares {uncomp} uncompressed bytes, more than the {} the reader decodes (WebAssembly has 4 GiB of memory): downsample the cloud or drop fields before saving",
                    crate::limits::MAX_DECODED_BYTES
                )));
            }
            if uncomp > comp as u64 * lzf::MAX_RATIO {
                return Err(Error::parse(
                    F,
                    format!("binary_compressed data declares {uncomp} uncompressed bytes from {comp} compressed bytes, more than LZF can produce"),
                ));
            }
            let raw = lzf::decompress(payload, uncomp as usize).map_err(|e| {
                Error::parse(F, format!("binary_compressed data (from byte offset {}): {e}", body_at + 8))
            })?;
            // Field-major layout: all points' values of field 0, then of field 1, ...
            let n = n_points as usize;
            let starts: Vec<usize> = (0..3).map(|a| fields[..axes[a].0].iter().map(|f| f.bytes() * n).sum()).collect();
            out.reserve(n);
            for i in 0..n {
                out.push([0, 1, 2].map(|a| {
                    let f = &fields[axes[a].0];
                    let at = starts[a] + i * f.size;
                    f.read_f64(&raw[at..at + f.size])
                }));
            }
        }
    }
    Ok(Raw { vertices: out, triangles: Vec::new() })
}
