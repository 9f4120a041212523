//! PCD reader (DATA ascii, binary, binary_compressed), organised clouds included.
//!
//! An own parser rather than `pcd-rs`: that crate decodes into typed or dynamic records with
//! owned field vectors per point, and its LZF path allocates the size the header declares
//! before checking it; here x/y/z are read straight from their offsets and every size is
//! checked against the bytes present first.

use super::util::{bounded_capacity, parse_count, parse_f64, show, utf8_line, Lines};
use super::{lzf, Raw};
use crate::{Error, Result};

pub(crate) const F: &str = "PCD";

#[derive(Clone, Debug)]
pub(crate) struct Field {
    pub(crate) name: String,
    pub(crate) size: usize,
    pub(crate) ty: char,
    pub(crate) count: usize,
}

impl Field {
    fn bytes(&self) -> usize {
        self.size * self.count
    }

    /// Decodes one little-endian value of this field.
    pub(crate) fn read_f64(&self, b: &[u8]) -> f64 {
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

impl Field {
    /// Writes `v` as this field's little-endian value; only for floating-point fields (`F`).
    pub(crate) fn write_float(&self, v: f64, b: &mut [u8]) {
        if self.size == 8 {
            b[..8].copy_from_slice(&v.to_le_bytes());
        } else {
            b[..4].copy_from_slice(&(v as f32).to_le_bytes());
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Data {
    Ascii,
    Binary,
    Compressed,
}

/// The ascii token index of the first value of field `i`.
pub(crate) fn token_index(fields: &[Field], i: usize) -> usize {
    fields[..i].iter().map(|f| f.count).fold(0, usize::saturating_add)
}

/// The byte offset of field `i` in a binary record.
pub(crate) fn byte_offset(fields: &[Field], i: usize) -> usize {
    fields[..i].iter().map(|f| f.size.saturating_mul(f.count)).fold(0, usize::saturating_add)
}

/// A parsed PCD header: the fields, the point count, the encoding, where the body starts.
pub(crate) struct Header {
    pub(crate) fields: Vec<Field>,
    pub(crate) n_points: u64,
    pub(crate) data: Data,
    /// Byte offset of the body (after the DATA line).
    pub(crate) body_at: usize,
    /// Number of the DATA line (an ascii body's lines are numbered after it).
    data_line: usize,
    /// Where x, y, z are: field index, value index (in ascii tokens), byte offset in a record.
    pub(crate) axes: [(usize, usize, usize); 3],
    /// Bytes per point record.
    pub(crate) stride: usize,
}

pub(crate) fn parse_header(bytes: &[u8]) -> Result<Header> {
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
                    .map(|s| parse_count(F, n, "SIZE", s).map(|v| usize::try_from(v).unwrap_or(usize::MAX)))
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
        axes[a] = (i, token_index(&fields, i), byte_offset(&fields, i));
    }
    let stride = fields
        .iter()
        .try_fold(0usize, |acc, f| f.size.checked_mul(f.count).and_then(|b| acc.checked_add(b)))
        .ok_or_else(|| Error::parse(F, "the point record size (SIZE x COUNT summed) overflows"))?;
    Ok(Header { fields, n_points, data, body_at: lines.offset(), data_line: lines.line_no(), axes, stride })
}

impl Header {
    /// The decompressed body of a `binary_compressed` file (field-major: all points' values of
    /// field 0, then of field 1, ...) and the byte offset where its compressed data ends.
    pub(crate) fn decompress(&self, bytes: &[u8]) -> Result<(Vec<u8>, usize)> {
        let Header { n_points, body_at, stride, .. } = *self;
        let body = &bytes[body_at..];
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
        let raw = lzf::decompress(payload, uncomp as usize)
            .map_err(|e| Error::parse(F, format!("binary_compressed data (from byte offset {}): {e}", body_at + 8)))?;
        Ok((raw, body_at + 8 + comp))
    }
}

/// What [`Header::ascii_rows`] calls for each point: `(line number, line, tokens)`.
pub(crate) type AsciiRow<'v, 'a> = dyn FnMut(usize, &'a str, &[&'a str]) -> Result<()> + 'v;

impl Header {
    /// Calls `visit(line number, line, tokens)` for each point of an ascii body (blank lines
    /// skipped; `tokens` holds the point's values, at least as many as the fields declare).
    /// Returns the byte offset after the last point's line.
    pub(crate) fn ascii_rows<'a>(&self, bytes: &'a [u8], visit: &mut AsciiRow<'_, 'a>) -> Result<usize> {
        let n_points = self.n_points;
        let n_tokens: usize = self.fields.iter().map(|f| f.count).fold(0, usize::saturating_add);
        let mut lines = Lines::at(bytes, self.body_at, self.data_line);
        let mut toks: Vec<&'a str> = Vec::new();
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
            toks.clear();
            toks.extend(line.split_ascii_whitespace().take(n_tokens));
            if toks.is_empty() {
                continue;
            }
            if toks.len() < n_tokens {
                return Err(Error::parse(
                    F,
                    format!("line {n}: expected {n_tokens} values per point, found {}", toks.len()),
                ));
            }
            visit(n, line, &toks)?;
            read += 1;
        }
        Ok(lines.offset())
    }

    /// The point records of a binary body (`n_points` records of `stride` bytes), checked
    /// against the bytes present.
    pub(crate) fn records<'a>(&self, bytes: &'a [u8]) -> Result<&'a [u8]> {
        let Header { n_points, body_at, stride, .. } = *self;
        let body = &bytes[body_at..];
        let need = n_points.checked_mul(stride as u64);
        match need {
            Some(need) if need <= body.len() as u64 && stride > 0 => Ok(&body[..need as usize]),
            _ => Err(Error::parse(
                F,
                format!(
                    "truncated binary data: {n_points} points of {stride} bytes need {} bytes after byte offset {body_at}, but only {} remain",
                    need.map_or("too many".to_string(), |v| v.to_string()),
                    body.len()
                ),
            )),
        }
    }

    /// Where field `i`'s values start in a decompressed (field-major) body.
    pub(crate) fn column_start(&self, i: usize) -> usize {
        self.fields[..i].iter().map(|f| f.bytes() * self.n_points as usize).sum()
    }
}

pub(crate) fn read(bytes: &[u8]) -> Result<Raw> {
    let h = parse_header(bytes)?;
    let Header { ref fields, n_points, data, body_at, axes, .. } = h;
    let mut out = Vec::new();
    match data {
        Data::Ascii => {
            let n_tokens: usize = fields.iter().map(|f| f.count).fold(0, usize::saturating_add);
            out.reserve(bounded_capacity(n_points, bytes.len() - body_at, n_tokens.saturating_mul(2)));
            h.ascii_rows(bytes, &mut |n, _, toks| {
                let mut p = [0.0f64; 3];
                for a in 0..3 {
                    p[a] = parse_f64(F, n, &format!("field '{}'", fields[axes[a].0].name), toks[axes[a].1])?;
                }
                out.push(p);
                Ok(())
            })?;
        }
        Data::Binary => {
            let records = h.records(bytes)?;
            out.reserve(n_points as usize);
            for rec in records.chunks_exact(h.stride) {
                out.push([0, 1, 2].map(|a| {
                    let (fi, _, off) = axes[a];
                    fields[fi].read_f64(&rec[off..off + fields[fi].size])
                }));
            }
        }
        Data::Compressed => {
            let (raw, _) = h.decompress(bytes)?;
            let n = n_points as usize;
            let starts = axes.map(|(fi, _, _)| h.column_start(fi));
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
