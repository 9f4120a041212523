//! A PLY file moved as it is: the positions of its `vertex` element mapped by a rigid (or
//! uniformly scaled) transform, its normals turned, a Gaussian splat file's splats turned and
//! scaled with them ([`super::splat`]: `rot_*`, `scale_*`, `f_rest_*`), every other byte kept
//! (colours, intensity, other properties, faces and other elements, comments, the encoding).
//! What saves a registered scan in the target's frame without losing what the registration did
//! not read.
//!
//! Binary files are copied and the vertex records rewritten in place; ASCII files get their
//! vertex lines rewritten (values separated by one space) and every other line as it was. Values
//! are computed in f64 and written back in the property's own type: a `float` file stays `float`
//! (its own precision), a `double` file keeps every digit; except where `float` would hold the
//! moved positions much more coarsely than the file held its own (a local scan moved onto a map
//! grid: steps of 0.5 at 5.4e6; a scan in metres scaled onto plant millimetres: steps of 0.25 at
//! 2.4e6), where `x`, `y` and `z` become `double` (in the header and in every vertex), the rest of
//! the file as it was. The header and the elements before the
//! vertices are read by the PLY reader's own parser, so a file it refuses is refused here too.

use super::motion::{Bounds, Motion};
use super::ply::{
    parse_header, read_ascii_element, read_binary_element, Element, Encoding, Kind, Out, Scalar, Want, F,
};
use super::splat::{Splat, SplatMotion};
use super::util::{parse_f64, utf8_line, Lines};
use crate::{Error, Result};
use nalgebra::Matrix4;

/// Where a vertex's position and normal are: property indices of x, y, z and, when the element
/// has all three as floating-point scalars, of nx, ny, nz.
struct Layout {
    position: [usize; 3],
    normal: Option<[usize; 3]>,
    /// A Gaussian splat file's splat attributes, turned with the scene.
    splat: Option<Splat>,
    /// The positions are written as `double` (declared so by [`widened_header`]).
    widened: bool,
}

/// The vertex element's layout; an error when x, y or z is missing, not a floating-point
/// scalar, or the element has a list property (a vertex of variable size).
fn layout(el: &Element) -> Result<Layout> {
    if let Some(list) = el.props.iter().find(|p| matches!(p.kind, Kind::List { .. })) {
        return Err(Error::unmovable(
            F,
            format!(
                "element 'vertex' has a list property ('{}'), so its vertices differ in size; save the moved points as a new PLY instead (in JS: \
                 writePly(transformPointCloud(...)), which keeps only the points)",
                list.name
            ),
        ));
    }
    let find = |name: &str| el.props.iter().position(|p| p.name == name);
    let float = |i: usize| matches!(el.props[i].kind, Kind::Scalar(s) if !s.is_int());
    let mut position = [0usize; 3];
    for (a, axis) in ["x", "y", "z"].into_iter().enumerate() {
        let i = find(axis).ok_or_else(|| Error::parse(F, format!("element 'vertex' has no '{axis}' property")))?;
        if !float(i) {
            return Err(Error::unmovable(
                F,
                format!(
                    "vertex property '{axis}' is an integer: it cannot hold moved coordinates (float or double needed)"
                ),
            ));
        }
        position[a] = i;
    }
    let normal = match (find("nx"), find("ny"), find("nz")) {
        (Some(x), Some(y), Some(z)) if float(x) && float(y) && float(z) => Some([x, y, z]),
        _ => None,
    };
    Ok(Layout { position, normal, splat: Splat::of(el), widened: false })
}

impl Layout {
    /// The splat attributes' property indices ([`Splat::indices`]); none in other files.
    fn splat_indices(&self) -> &[usize] {
        self.splat.as_ref().map_or(&[], Splat::indices)
    }
}

/// The PLY file `bytes` with its vertices moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale), normals (`nx`, `ny`, `nz`) turned by its rotation, everything else
/// as it was (see the module docs). Errors: a file the PLY reader refuses, a `vertex` element
/// that is missing, has a list property or integer coordinates, a transform that is not rigid
/// (or uniformly scaled).
pub fn transform_ply(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    let h = parse_header(bytes)?;
    let vi = h.vertex_index()?;
    let vertex = &h.elements[vi];
    let layout = layout(vertex)?;
    let position = |p| motion.point(p);
    let normal = |n| motion.normal(n);
    let splat = layout.splat.as_ref().map(|s| SplatMotion::new(&motion.rotation, motion.scale(), s));
    let attrs = |v: &mut [f64]| {
        if let Some(s) = &splat {
            s.apply(v)
        }
    };
    let single = layout.position.map(|i| matches!(vertex.props[i].kind, Kind::Scalar(Scalar::F32)));
    match h.encoding {
        Encoding::Ascii => {
            let mut lines = Lines::at(bytes, h.body, h.last_line);
            for el in &h.elements[..vi] {
                read_ascii_element(&mut lines, el, Want::Skip, &mut Out::default())?;
            }
            let start = lines.offset();
            // float positions: their bounds first, to see whether float holds them moved
            let widen = single.contains(&true) && {
                let bounds = std::cell::Cell::new(Bounds::default());
                let record = |p: [f64; 3]| {
                    let mut b = bounds.get();
                    b.add(p);
                    bounds.set(b);
                    p
                };
                let mut scratch = lines.clone();
                move_ascii(bytes, &mut scratch, vertex, &layout, (&record, &|n| n, &|_| {}), None)?;
                bounds.get().f32_coarsens(&motion, single)
            };
            let mut out = Vec::with_capacity(bytes.len() + bytes.len() / 4);
            if widen {
                out.extend_from_slice(&widened_header(&bytes[..h.body], vi, &layout));
                out.extend_from_slice(&bytes[h.body..start]);
            } else {
                out.extend_from_slice(&bytes[..start]);
            }
            let layout = Layout { widened: widen, ..layout };
            move_ascii(bytes, &mut lines, vertex, &layout, (&position, &normal, &attrs), Some(&mut out))?;
            out.extend_from_slice(&bytes[lines.offset()..]);
            Ok(out)
        }
        Encoding::BinaryLe | Encoding::BinaryBe => {
            let big = h.encoding == Encoding::BinaryBe;
            let mut pos = h.body;
            for el in &h.elements[..vi] {
                read_binary_element(bytes, &mut pos, el, Want::Skip, big, &mut Out::default())?;
            }
            let need = records_bytes(bytes.len(), pos, vertex)?;
            let bounds = || binary_bounds(&bytes[pos..pos + need], vertex, &layout, big);
            if single.contains(&true) && bounds().f32_coarsens(&motion, single) {
                let mut out = widened_header(&bytes[..h.body], vi, &layout);
                out.extend_from_slice(&bytes[h.body..pos]);
                widen_binary(&mut out, &bytes[pos..pos + need], vertex, &layout, big, (&position, &normal, &attrs));
                out.extend_from_slice(&bytes[pos + need..]);
                return Ok(out);
            }
            let mut out = bytes.to_vec();
            move_binary(&mut out, pos, vertex, &layout, big, (&position, &normal, &attrs))?;
            Ok(out)
        }
    }
}

/// The header `header` (up to its body) with the vertex element's (the `vi`-th element's) `x`,
/// `y` and `z` (the properties `layout.position` indexes) declared `double` (`float64` where the
/// file named them `float32`), every other byte as it was: each `property` line of that element is
/// counted, so a property's extra words, a duplicate name or a comment cannot mislead it.
fn widened_header(header: &[u8], vi: usize, layout: &Layout) -> Vec<u8> {
    let mut out = Vec::with_capacity(header.len() + 16);
    // (the element a line belongs to, and the index of a property line within it)
    let (mut element, mut property) = (None::<usize>, 0usize);
    let mut elements = 0usize;
    for line in header.split_inclusive(|&b| b == b'\n') {
        let mut words = line.split(u8::is_ascii_whitespace).filter(|w| !w.is_empty());
        match words.next() {
            Some(b"element") => {
                (element, property) = (Some(elements), 0);
                elements += 1;
            }
            Some(b"property") if element == Some(vi) => {
                let index = property;
                property += 1;
                // the type word replaced where it stands (checked by `layout`: a float)
                if let Some(ty) = words.next().filter(|_| layout.position.contains(&index)) {
                    let at = ty.as_ptr() as usize - line.as_ptr() as usize;
                    let wide: &[u8] = if ty == b"float32" { b"float64" } else { b"double" };
                    out.extend_from_slice(&line[..at]);
                    out.extend_from_slice(wide);
                    out.extend_from_slice(&line[at + ty.len()..]);
                    continue;
                }
            }
            _ => {}
        }
        out.extend_from_slice(line);
    }
    out
}

/// The bytes the vertex records take from byte `pos` of a file of `len` bytes; an error when they
/// do not fit (a truncated file or a bad count).
fn records_bytes(len: usize, pos: usize, el: &Element) -> Result<usize> {
    let stride = el.fixed_size().unwrap_or(0);
    let remaining = len - pos;
    let need = usize::try_from(el.count).ok().and_then(|n| n.checked_mul(stride));
    need.filter(|&need| need <= remaining).ok_or_else(|| {
        Error::parse(
            F,
            format!(
                "element 'vertex' declares {} records of {stride} bytes, but only {remaining} bytes follow (from byte offset {pos}): truncated file or bad count",
                el.count
            ),
        )
    })
}

/// The bounds of the positions of the vertex `records`.
fn binary_bounds(records: &[u8], el: &Element, layout: &Layout, big: bool) -> Bounds {
    let mut bounds = Bounds::default();
    let stride = el.fixed_size().unwrap_or(0);
    if stride == 0 {
        return bounds;
    }
    let offsets = offsets(el);
    let p = layout.position.map(|i| offsets[i]);
    for record in records.chunks_exact(stride) {
        bounds.add(p.map(|(off, s)| s.read_f64(&record[off..off + s.size()], big)));
    }
    bounds
}

/// Appends the vertex `records` to `out` moved, their positions widened to `double` (the other
/// properties as they were, normals turned in their own type).
fn widen_binary(
    out: &mut Vec<u8>,
    records: &[u8],
    el: &Element,
    layout: &Layout,
    big: bool,
    (position, normal, attrs): Movers,
) {
    let stride = el.fixed_size().unwrap_or(0);
    if stride == 0 {
        return;
    }
    let offsets = offsets(el);
    let p = layout.position.map(|i| offsets[i]);
    let n = layout.normal.map(|idx| idx.map(|i| offsets[i]));
    out.reserve(records.len() + records.len() / stride * 12);
    let mut scratch = vec![0u8; stride];
    let mut values = vec![0.0; layout.splat_indices().len()];
    for record in records.chunks_exact(stride) {
        let read = |slot: [(usize, Scalar); 3]| slot.map(|(off, s)| s.read_f64(&record[off..off + s.size()], big));
        let moved = position(read(p));
        scratch.copy_from_slice(record);
        if let Some(n) = n {
            let turned = normal(read(n));
            for a in 0..3 {
                put(&mut scratch, n[a], turned[a], big);
            }
        }
        turn_splat(&mut scratch, &offsets, layout.splat_indices(), &mut values, big, attrs);
        for (i, &(off, s)) in offsets.iter().enumerate() {
            match layout.position.iter().position(|&k| k == i) {
                Some(a) => out.extend_from_slice(&if big { moved[a].to_be_bytes() } else { moved[a].to_le_bytes() }),
                None => out.extend_from_slice(&scratch[off..off + s.size()]),
            }
        }
    }
}

/// Byte offset of each property in a record of `el` (no list properties) and its type.
fn offsets(el: &Element) -> Vec<(usize, Scalar)> {
    let mut at = 0;
    el.props
        .iter()
        .map(|p| {
            let Kind::Scalar(s) = p.kind else { unreachable!("checked by layout") };
            let here = (at, s);
            at += s.size();
            here
        })
        .collect()
}

/// Writes `v` as the float type `s` (`layout` admits no other for moved values).
fn put(record: &mut [u8], (off, s): (usize, Scalar), v: f64, big: bool) {
    match s {
        Scalar::F64 => {
            let b = if big { v.to_be_bytes() } else { v.to_le_bytes() };
            record[off..off + 8].copy_from_slice(&b);
        }
        _ => {
            let v = v as f32;
            let b = if big { v.to_be_bytes() } else { v.to_le_bytes() };
            record[off..off + 4].copy_from_slice(&b);
        }
    }
}

/// Rewrites the vertex records of `out` (a copy of the file) from byte `pos`, in place.
fn move_binary(
    out: &mut [u8],
    pos: usize,
    el: &Element,
    layout: &Layout,
    big: bool,
    (position, normal, attrs): Movers,
) -> Result<()> {
    let stride = el.fixed_size().unwrap_or(0);
    let need = records_bytes(out.len(), pos, el)?;
    if stride == 0 {
        return Ok(());
    }
    let offsets = offsets(el);
    let slots = |idx: [usize; 3]| idx.map(|i| offsets[i]);
    let (p, n) = (slots(layout.position), layout.normal.map(slots));
    let mut values = vec![0.0; layout.splat_indices().len()];
    for record in out[pos..pos + need].chunks_exact_mut(stride) {
        let read = |slot: [(usize, Scalar); 3]| slot.map(|(off, s)| s.read_f64(&record[off..off + s.size()], big));
        let moved = position(read(p));
        let turned = n.map(|n| normal(read(n)));
        for a in 0..3 {
            put(record, p[a], moved[a], big);
        }
        if let (Some(n), Some(turned)) = (n, turned) {
            for a in 0..3 {
                put(record, n[a], turned[a], big);
            }
        }
        turn_splat(record, &offsets, layout.splat_indices(), &mut values, big, attrs);
    }
    Ok(())
}

/// What moves a vertex: its position, its normal, its splat attributes ([`SplatMotion::apply`];
/// nothing in other files).
type Movers<'a> = (&'a dyn Fn([f64; 3]) -> [f64; 3], &'a dyn Fn([f64; 3]) -> [f64; 3], &'a dyn Fn(&mut [f64]));

/// A binary record's splat attributes (the properties `indices`) read into `values`, moved by
/// `attrs` and written back in their own types; nothing without them.
fn turn_splat(
    record: &mut [u8],
    offsets: &[(usize, Scalar)],
    indices: &[usize],
    values: &mut [f64],
    big: bool,
    attrs: &dyn Fn(&mut [f64]),
) {
    if indices.is_empty() {
        return;
    }
    for (v, &i) in values.iter_mut().zip(indices) {
        let (off, s) = offsets[i];
        *v = s.read_f64(&record[off..off + s.size()], big);
    }
    attrs(values);
    for (&v, &i) in values.iter().zip(indices) {
        put(record, offsets[i], v, big);
    }
}

/// A value for an ASCII file, in the property's type: the shortest text that reads back the same.
fn text(v: f64, s: Scalar) -> String {
    if s == Scalar::F64 {
        format!("{v}")
    } else {
        format!("{}", v as f32)
    }
}

/// Copies the vertex lines from `lines` (over `bytes`) to `out`, each with its position and normal
/// rewritten (blank lines as they are, each line's own terminator kept). Without `out`, only reads
/// them (checked) and passes their positions to `position` (a first pass that takes their bounds).
fn move_ascii(
    bytes: &[u8],
    lines: &mut Lines,
    el: &Element,
    layout: &Layout,
    (position, normal, attrs): Movers,
    mut out: Option<&mut Vec<u8>>,
) -> Result<()> {
    let types: Vec<Scalar> = el
        .props
        .iter()
        .enumerate()
        .map(|(i, p)| match p.kind {
            // widened positions are written as doubles (`widened_header` declares them so)
            Kind::Scalar(_) if layout.widened && layout.position.contains(&i) => Scalar::F64,
            Kind::Scalar(s) => s,
            Kind::List { .. } => unreachable!("checked by layout"),
        })
        .collect();
    let mut done = 0u64;
    while done < el.count {
        let start = lines.offset();
        let Some((n, raw)) = lines.next() else {
            return Err(Error::parse(
                F,
                format!("the file ends after {done} of the {} 'vertex' lines the header declares", el.count),
            ));
        };
        let terminator = start + raw.len()..lines.offset();
        let line = utf8_line(F, n, raw)?;
        let mut tokens: Vec<String> = line.split_ascii_whitespace().map(str::to_string).collect();
        if tokens.is_empty() {
            if let Some(out) = out.as_deref_mut() {
                out.extend_from_slice(raw);
            }
        } else {
            if tokens.len() < types.len() {
                return Err(Error::parse(
                    F,
                    format!("line {n}: a vertex needs {} values, the line has {}", types.len(), tokens.len()),
                ));
            }
            let read = |tokens: &[String], idx: [usize; 3]| -> Result<[f64; 3]> {
                let mut v = [0.0; 3];
                for a in 0..3 {
                    v[a] = parse_f64(F, n, &format!("'{}'", el.props[idx[a]].name), &tokens[idx[a]])?;
                }
                Ok(v)
            };
            let moved = position(read(&tokens, layout.position)?);
            let turned = match layout.normal {
                Some(idx) => Some((idx, normal(read(&tokens, idx)?))),
                None => None,
            };
            if let Some(out) = out.as_deref_mut() {
                let (position, normal) = (Some((layout.position, moved)), turned);
                for (idx, values) in [position, normal].into_iter().flatten() {
                    for (i, v) in idx.into_iter().zip(values) {
                        tokens[i] = text(v, types[i]);
                    }
                }
                let splat = layout.splat_indices();
                if !splat.is_empty() {
                    let mut values = Vec::with_capacity(splat.len());
                    for &i in splat {
                        values.push(parse_f64(F, n, &format!("'{}'", el.props[i].name), &tokens[i])?);
                    }
                    attrs(&mut values);
                    for (&i, v) in splat.iter().zip(values) {
                        tokens[i] = text(v, types[i]);
                    }
                }
                out.extend_from_slice(tokens.join(" ").as_bytes());
            }
            done += 1;
        }
        if let Some(out) = out.as_deref_mut() {
            out.extend_from_slice(&bytes[terminator]);
        }
    }
    Ok(())
}
