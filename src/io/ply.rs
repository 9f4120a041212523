//! PLY reader (ascii, binary_little_endian, binary_big_endian) and the binary PLY writer.
//!
//! An own parser rather than `ply-rs-bw`: that crate materialises every element instance as a
//! property map (an ordered hash map per vertex, so tens of bytes of bookkeeping per value),
//! reports errors without byte offsets, and sizes some reservations from the header; what arps
//! needs (x/y/z of `vertex`, one index list of `face`, everything else skipped) is small enough
//! to do directly, with every count checked against the bytes that remain.

use super::util::{bounded_capacity, check_index, fan, parse_count, parse_f64, parse_int, show, utf8_line, Lines};
use super::{Faces, Raw};
use crate::cloud::PointCloud;
use crate::{Error, Result};

pub(super) const F: &str = "PLY";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(super) fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Reads a value from exactly `size()` bytes.
    pub(super) fn read_f64(self, b: &[u8], big: bool) -> f64 {
        match self {
            Scalar::F32 => f32::from_bits(read_u32(b, big)) as f64,
            Scalar::F64 => f64::from_bits(read_u64(b, big)),
            _ => self.read_i64(b, big) as f64,
        }
    }

    /// Reads an integer value from exactly `size()` bytes (float types are rejected at header
    /// time wherever an integer is needed).
    fn read_i64(self, b: &[u8], big: bool) -> i64 {
        match self {
            Scalar::I8 => b[0] as i8 as i64,
            Scalar::U8 => b[0] as i64,
            Scalar::I16 => read_u16(b, big) as i16 as i64,
            Scalar::U16 => read_u16(b, big) as i64,
            Scalar::I32 => read_u32(b, big) as i32 as i64,
            Scalar::U32 => read_u32(b, big) as i64,
            Scalar::F32 => f32::from_bits(read_u32(b, big)) as i64,
            Scalar::F64 => f64::from_bits(read_u64(b, big)) as i64,
        }
    }
}

fn read_u16(b: &[u8], big: bool) -> u16 {
    let a = [b[0], b[1]];
    if big {
        u16::from_be_bytes(a)
    } else {
        u16::from_le_bytes(a)
    }
}

fn read_u32(b: &[u8], big: bool) -> u32 {
    let a = [b[0], b[1], b[2], b[3]];
    if big {
        u32::from_be_bytes(a)
    } else {
        u32::from_le_bytes(a)
    }
}

fn read_u64(b: &[u8], big: bool) -> u64 {
    let a = [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
    if big {
        u64::from_be_bytes(a)
    } else {
        u64::from_le_bytes(a)
    }
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: Kind,
}

#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) props: Vec<Property>,
}

impl Element {
    /// Bytes of one instance when it has no list property.
    pub(super) fn fixed_size(&self) -> Option<usize> {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => Some(s.size()),
                Kind::List { .. } => None,
            })
            .sum()
    }

    /// The fewest bytes one binary instance can take (lists empty).
    fn min_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) elements: Vec<Element>,
    /// Byte offset where the body starts.
    pub(super) body: usize,
    /// Number of the `end_header` line.
    pub(super) last_line: usize,
}

impl Header {
    /// The index of the `vertex` element; an error when there is none.
    pub(super) fn vertex_index(&self) -> Result<usize> {
        self.elements
            .iter()
            .position(|e| e.name == "vertex")
            .ok_or_else(|| Error::parse(F, "the file has no 'vertex' element"))
    }
}

pub(super) fn parse_header(bytes: &[u8]) -> Result<Header> {
    let mut lines = Lines::new(bytes);
    match lines.next() {
        Some((_, l)) if l.trim_ascii_end() == b"ply" => {}
        _ => return Err(Error::parse(F, "missing the 'ply' magic line at the start of the file")),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for (n, raw) in lines.by_ref() {
        let trimmed = raw.trim_ascii_start();
        // Comments may carry any bytes (some exporters write Latin-1 there).
        if trimmed.starts_with(b"comment") || trimmed.starts_with(b"obj_info") {
            continue;
        }
        let line =
            utf8_line(F, n, raw).map_err(|_| Error::parse(F, format!("header line {n} is not valid UTF-8 text")))?;
        let mut t = line.split_ascii_whitespace();
        let Some(keyword) = t.next() else { continue };
        match keyword {
            "end_header" => {
                let encoding = encoding.ok_or_else(|| Error::parse(F, "the header has no 'format' line"))?;
                return Ok(Header { encoding, elements, body: lines.offset(), last_line: n });
            }
            "format" => {
                let e = match t.next() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::BinaryLe,
                    Some("binary_big_endian") => Encoding::BinaryBe,
                    other => {
                        return Err(Error::parse(
                            F,
                            format!(
                            "line {n}: unknown format {} (expected ascii, binary_little_endian or binary_big_endian)",
                            show(other.unwrap_or(""))
                        ),
                        ))
                    }
                };
                encoding = Some(e);
            }
            "element" => {
                let (Some(name), Some(count)) = (t.next(), t.next()) else {
                    return Err(Error::parse(F, format!("line {n}: 'element' needs a name and a count")));
                };
                let count = parse_count(F, n, &format!("element '{name}' count"), count)?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(Error::parse(F, format!("line {n}: 'property' before any 'element'")));
                };
                let ty = |name: Option<&str>| -> Result<Scalar> {
                    let name = name.ok_or_else(|| Error::parse(F, format!("line {n}: incomplete property line")))?;
                    Scalar::from_name(name)
                        .ok_or_else(|| Error::parse(F, format!("line {n}: unknown property type {}", show(name))))
                };
                let first = t.next();
                let (kind, name) = if first == Some("list") {
                    let count = ty(t.next())?;
                    let item = ty(t.next())?;
                    if !count.is_int() {
                        return Err(Error::parse(F, format!("line {n}: list count type must be an integer type")));
                    }
                    (Kind::List { count, item }, t.next())
                } else {
                    (Kind::Scalar(ty(first)?), t.next())
                };
                let name = name.ok_or_else(|| Error::parse(F, format!("line {n}: property has no name")))?;
                el.props.push(Property { name: name.to_string(), kind });
            }
            other => return Err(Error::parse(F, format!("line {n}: unknown header keyword {}", show(other)))),
        }
    }
    Err(Error::parse(F, "the header has no 'end_header' line"))
}

/// What to take from an element.
#[derive(Clone, Copy)]
pub(super) enum Want {
    /// Property indices of x, y, z.
    Points([usize; 3]),
    /// Property index of the vertex index list; the vertex count to check against.
    Faces(usize, usize),
    Skip,
}

#[derive(Default)]
pub(super) struct Out {
    points: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
}

fn vertex_want(el: &Element) -> Result<Want> {
    let mut idx = [0usize; 3];
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        let i = el
            .props
            .iter()
            .position(|p| p.name == *axis)
            .ok_or_else(|| Error::parse(F, format!("element 'vertex' has no '{axis}' property")))?;
        if matches!(el.props[i].kind, Kind::List { .. }) {
            return Err(Error::parse(F, format!("vertex property '{axis}' is a list, expected a scalar")));
        }
        idx[a] = i;
    }
    Ok(Want::Points(idx))
}

fn face_want(el: &Element, n_vertices: usize) -> Result<Want> {
    let lists: Vec<usize> = (0..el.props.len()).filter(|&i| matches!(el.props[i].kind, Kind::List { .. })).collect();
    let i = el
        .props
        .iter()
        .position(|p| p.name == "vertex_indices" || p.name == "vertex_index")
        .or(if lists.len() == 1 { Some(lists[0]) } else { None })
        .ok_or_else(|| Error::parse(F, "element 'face' has no 'vertex_indices' list property"))?;
    match el.props[i].kind {
        Kind::List { item, .. } if item.is_int() => Ok(Want::Faces(i, n_vertices)),
        Kind::List { .. } => {
            Err(Error::parse(F, format!("face list '{}' has a floating-point item type", el.props[i].name)))
        }
        Kind::Scalar(_) => Err(Error::parse(F, format!("face property '{}' is not a list", el.props[i].name))),
    }
}

/// Reads the vertices (and the faces, as `faces` says) of a PLY file.
pub(crate) fn read(bytes: &[u8], faces: Faces) -> Result<Raw> {
    let h = parse_header(bytes)?;
    let vi = h.vertex_index()?;
    crate::limits::check_file_points(F, h.elements[vi].count)?;
    let n_vertices = usize::try_from(h.elements[vi].count).unwrap_or(usize::MAX);
    let face = h.elements.iter().position(|e| e.name == "face");
    let fi = match faces {
        Faces::Skip => None,
        Faces::IfAny => face,
        Faces::Required => {
            Some(face.ok_or_else(|| Error::parse(F, "the file has no 'face' element (a point cloud, not a mesh)"))?)
        }
    };
    let mut wants = vec![Want::Skip; h.elements.len()];
    wants[vi] = vertex_want(&h.elements[vi])?;
    if let Some(fi) = fi {
        wants[fi] = face_want(&h.elements[fi], n_vertices)?;
    }
    // Stop after the last element we need.
    let last = vi.max(fi.unwrap_or(0));
    let mut out = Out::default();
    match h.encoding {
        Encoding::Ascii => {
            let mut lines = Lines::at(bytes, h.body, h.last_line);
            for (el, want) in h.elements.iter().zip(&wants).take(last + 1) {
                read_ascii_element(&mut lines, el, *want, &mut out)?;
            }
        }
        Encoding::BinaryLe | Encoding::BinaryBe => {
            let big = h.encoding == Encoding::BinaryBe;
            let mut pos = h.body;
            for (el, want) in h.elements.iter().zip(&wants).take(last + 1) {
                read_binary_element(bytes, &mut pos, el, *want, big, &mut out)?;
            }
        }
    }
    Ok(Raw { vertices: out.points, triangles: out.triangles })
}

/// The values of the vertex property `name` (a scalar), in the vertices' order; `None` when the
/// vertex element has no such scalar property.
pub(crate) fn read_vertex_property(bytes: &[u8], name: &str) -> Result<Option<Vec<f64>>> {
    let h = parse_header(bytes)?;
    let vi = h.vertex_index()?;
    let el = &h.elements[vi];
    let Some(i) = el.props.iter().position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_))) else {
        return Ok(None);
    };
    let mut wants = vec![Want::Skip; vi + 1];
    // (the property read as a point's three coordinates: the readers' one path for every layout)
    wants[vi] = Want::Points([i; 3]);
    let mut out = Out::default();
    match h.encoding {
        Encoding::Ascii => {
            let mut lines = Lines::at(bytes, h.body, h.last_line);
            for (el, want) in h.elements.iter().zip(&wants) {
                read_ascii_element(&mut lines, el, *want, &mut out)?;
            }
        }
        Encoding::BinaryLe | Encoding::BinaryBe => {
            let big = h.encoding == Encoding::BinaryBe;
            let mut pos = h.body;
            for (el, want) in h.elements.iter().zip(&wants) {
                read_binary_element(bytes, &mut pos, el, *want, big, &mut out)?;
            }
        }
    }
    Ok(Some(out.points.into_iter().map(|p| p[0]).collect()))
}

pub(super) fn read_binary_element(
    bytes: &[u8],
    pos: &mut usize,
    el: &Element,
    want: Want,
    big: bool,
    out: &mut Out,
) -> Result<()> {
    if el.props.is_empty() || el.count == 0 {
        return Ok(());
    }
    let remaining = bytes.len() - *pos;
    let min = el.min_size() as u64;
    if el.count.checked_mul(min).is_none_or(|need| need > remaining as u64) {
        return Err(Error::parse(
            F,
            format!(
                "element '{}' declares {} instances of at least {min} bytes each, but only {remaining} bytes follow (from byte offset {}): truncated file or bad count",
                el.name, el.count, *pos
            ),
        ));
    }
    // From here count <= remaining bytes, so it fits in usize.
    let count = el.count as usize;
    if let Some(stride) = el.fixed_size() {
        let body = &bytes[*pos..*pos + count * stride];
        if let Want::Points(idx) = want {
            let layout: Vec<(usize, Scalar)> = idx
                .iter()
                .map(|&i| {
                    let off: usize =
                        el.props[..i].iter().map(|p| if let Kind::Scalar(s) = p.kind { s.size() } else { 0 }).sum();
                    let Kind::Scalar(s) = el.props[i].kind else { unreachable!("checked by vertex_want") };
                    (off, s)
                })
                .collect();
            out.points.reserve(count);
            for rec in body.chunks_exact(stride) {
                let v = |a: usize| {
                    let (off, s) = layout[a];
                    s.read_f64(&rec[off..off + s.size()], big)
                };
                out.points.push([v(0), v(1), v(2)]);
            }
        }
        *pos += count * stride;
        return Ok(());
    }
    // Elements with list properties: one instance at a time, every read bounds-checked.
    if let Want::Points(_) = want {
        out.points.reserve(bounded_capacity(el.count, remaining, min as usize));
    }
    let mut poly: Vec<u32> = Vec::new();
    for inst in 0..count {
        let mut xyz = [0.0f64; 3];
        for (pi, p) in el.props.iter().enumerate() {
            let truncated = |need: usize, at: usize| {
                Error::parse(
                    F,
                    format!(
                        "truncated: element '{}' instance {inst} property '{}' needs {need} bytes at byte offset {at}, but the file has {} bytes",
                        el.name,
                        p.name,
                        bytes.len()
                    ),
                )
            };
            match p.kind {
                Kind::Scalar(s) => {
                    let b = bytes.get(*pos..*pos + s.size()).ok_or_else(|| truncated(s.size(), *pos))?;
                    if let Want::Points(idx) = want {
                        for a in 0..3 {
                            if idx[a] == pi {
                                xyz[a] = s.read_f64(b, big);
                            }
                        }
                    }
                    *pos += s.size();
                }
                Kind::List { count: cs, item } => {
                    let b = bytes.get(*pos..*pos + cs.size()).ok_or_else(|| truncated(cs.size(), *pos))?;
                    let n = cs.read_i64(b, big);
                    if n < 0 {
                        return Err(Error::parse(
                            F,
                            format!(
                                "element '{}' instance {inst}: list '{}' has a negative length {n} (byte offset {})",
                                el.name, p.name, *pos
                            ),
                        ));
                    }
                    *pos += cs.size();
                    let len = (n as usize).checked_mul(item.size()).ok_or_else(|| truncated(usize::MAX, *pos))?;
                    let items = pos
                        .checked_add(len)
                        .and_then(|end| bytes.get(*pos..end))
                        .ok_or_else(|| truncated(len, *pos))?;
                    if let Want::Faces(fp, nv) = want {
                        if fp == pi {
                            poly.clear();
                            for c in items.chunks_exact(item.size()) {
                                let at = *pos;
                                poly.push(check_index(F, item.read_i64(c, big), nv, || {
                                    format!("face {inst} (byte offset {at})")
                                })?);
                            }
                            fan(&poly, &mut out.triangles);
                        }
                    }
                    *pos += len;
                }
            }
        }
        if let Want::Points(_) = want {
            out.points.push(xyz);
        }
    }
    Ok(())
}

pub(super) fn read_ascii_element(lines: &mut Lines, el: &Element, want: Want, out: &mut Out) -> Result<()> {
    if el.props.is_empty() || el.count == 0 {
        return Ok(());
    }
    if let Want::Points(_) = want {
        // An ascii instance takes at least two bytes per scalar ("0 ").
        out.points.reserve(bounded_capacity(el.count, lines.remaining(), 2 * el.props.len()));
    }
    let mut poly: Vec<u32> = Vec::new();
    let mut inst: u64 = 0;
    while inst < el.count {
        let Some((n, raw)) = lines.next() else {
            return Err(Error::parse(
                F,
                format!(
                    "the file ends after {inst} of the {} '{}' lines the header declares (line {})",
                    el.count,
                    el.name,
                    lines.line_no()
                ),
            ));
        };
        let line = utf8_line(F, n, raw)?;
        let mut t = line.split_ascii_whitespace().peekable();
        if t.peek().is_none() {
            continue; // blank line
        }
        let mut xyz = [0.0f64; 3];
        for (pi, p) in el.props.iter().enumerate() {
            let mut next = |what: &str| {
                t.next().ok_or_else(|| {
                    Error::parse(
                        F,
                        format!("line {n}: element '{}' is missing a value for {what} '{}'", el.name, p.name),
                    )
                })
            };
            match p.kind {
                Kind::Scalar(_) => {
                    let tok = next("property")?;
                    let slot = match want {
                        Want::Points(idx) => idx.iter().position(|&i| i == pi),
                        _ => None,
                    };
                    // Skipped values are still checked to be numbers (integers written as
                    // "255.0" are accepted), so a shifted column is caught.
                    let v = parse_f64(F, n, &format!("'{}'", p.name), tok)?;
                    if let Some(a) = slot {
                        xyz[a] = v;
                    }
                }
                Kind::List { .. } => {
                    let tok = next("the length of list")?;
                    let len = parse_count(F, n, &format!("length of list '{}'", p.name), tok)?;
                    let is_faces = matches!(want, Want::Faces(fp, _) if fp == pi);
                    poly.clear();
                    for k in 0..len {
                        let tok = t.next().ok_or_else(|| {
                            Error::parse(
                                F,
                                format!("line {n}: list '{}' declares {len} items but only {k} follow", p.name),
                            )
                        })?;
                        if is_faces {
                            let Want::Faces(_, nv) = want else { unreachable!() };
                            let v = parse_int(F, n, "vertex index", tok)?;
                            poly.push(check_index(F, v, nv, || format!("line {n} (face {inst})"))?);
                        } else {
                            parse_f64(F, n, &format!("item of list '{}'", p.name), tok)?;
                        }
                    }
                    if is_faces {
                        fan(&poly, &mut out.triangles);
                    }
                }
            }
        }
        // Extra values after the declared properties are ignored: real exporters (VCG's ascii
        // writer with per-wedge colours) write more than their header declares.
        if let Want::Points(_) = want {
            out.points.push(xyz);
        }
        inst += 1;
    }
    Ok(())
}

/// Binary little-endian PLY with `float x y z` per vertex.
pub(crate) fn write_binary(cloud: &PointCloud) -> Vec<u8> {
    let double = !cloud.origin_is_zero();
    let ty = if double { "double" } else { "float" };
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by arps\nelement vertex {}\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\nend_header\n",
        cloud.len()
    );
    let mut out = Vec::with_capacity(header.len() + cloud.len() * if double { 24 } else { 12 });
    out.extend_from_slice(header.as_bytes());
    for (i, p) in cloud.points.iter().enumerate() {
        if double {
            for v in cloud.point_f64(i) {
                out.extend_from_slice(&v.to_le_bytes());
            }
        } else {
            for v in p {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}
