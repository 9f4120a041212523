//! A PCD file moved as it is: its points' x, y, z mapped, its normals (`normal_x`, `normal_y`,
//! `normal_z`) turned, every other byte kept (the header, VIEWPOINT included, other fields such as
//! rgb, intensity and curvature, the encoding).
//!
//! Binary bodies are rewritten in place, in each field's own type (`F 4` stays `float`), except
//! that `float` coordinates moved where float would hold them more coarsely than the file did (a
//! local scan moved onto a map grid: [`Bounds::f32_coarsens`], the rule a PLY follows) become
//! `double` (`SIZE 8`, the records 12 bytes longer; an ascii body's header says `SIZE 8` for
//! them); a
//! `binary_compressed` body is decompressed, rewritten and compressed again (LZF); an ascii body
//! has its coordinate tokens rewritten as the file wrote its numbers
//! ([`super::number_style::NumberStyle`]). Points whose coordinates are not finite (the holes of
//! an organised cloud) are kept as they are. The header is read by the PCD reader's own parser,
//! so a file it refuses is refused here too.

use super::lzf;
use super::motion::{Bounds, Motion};
use super::number_style::{span, Rewrite, Styles};
use super::pcd::{byte_offset, parse_header, Data, Header, F};
use crate::{Error, Result};
use nalgebra::Matrix4;

/// The field indices of the normal, when the file has `normal_x`, `normal_y` and `normal_z` as
/// single floating-point values.
fn normal_fields(h: &Header) -> Option<[usize; 3]> {
    let find = |name: &str| h.fields.iter().position(|f| f.name == name && f.ty == 'F' && f.count == 1);
    Some([find("normal_x")?, find("normal_y")?, find("normal_z")?])
}

/// The PCD file `bytes` with its points moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale) and its normals turned, everything else as it was (see the module
/// docs). Errors: a file the PCD reader refuses, integer x, y or z fields, a transform that is
/// not rigid (or uniformly scaled).
pub fn transform_pcd(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    let h = parse_header(bytes)?;
    for (fi, _, _) in h.axes {
        let f = &h.fields[fi];
        if f.ty != 'F' {
            return Err(Error::unmovable(
                F,
                format!(
                    "field '{}' is an integer (TYPE {}): it cannot hold moved coordinates (TYPE F needed)",
                    f.name, f.ty
                ),
            ));
        }
    }
    let xyz = h.axes.map(|(fi, _, _)| fi);
    let normal = normal_fields(&h);
    match h.data {
        Data::Ascii => move_ascii(bytes, &h, xyz, normal, &motion),
        Data::Binary => {
            let end = h.body_at + h.records(bytes)?.len();
            let offset: Vec<usize> = (0..h.fields.len()).map(|f| h.body_at + byte_offset(&h.fields, f)).collect();
            let at = |i: usize, f: usize| offset[f] + i * h.stride;
            if coarsened(bytes, &h, xyz, &motion, &at) {
                // the records rebuilt with double coordinates, after the header that declares them
                let (mut out, body) = widened(bytes, &bytes[..h.body_at], &h, xyz, normal, &motion, &at, false);
                out.extend_from_slice(&body);
                out.extend_from_slice(&bytes[end..]);
                return Ok(out);
            }
            let mut out = bytes.to_vec();
            move_values(&mut out, &h, xyz, normal, &motion, &at);
            Ok(out)
        }
        Data::Compressed => {
            let (mut raw, end) = h.decompress(bytes)?;
            let start: Vec<usize> = (0..h.fields.len()).map(|f| h.column_start(f)).collect();
            let at = |i: usize, f: usize| start[f] + i * h.fields[f].size;
            let (header, raw) = if coarsened(&raw, &h, xyz, &motion, &at) {
                // the columns rebuilt with double coordinates
                widened(&raw, &bytes[..h.body_at], &h, xyz, normal, &motion, &at, true)
            } else {
                move_values(&mut raw, &h, xyz, normal, &motion, &at);
                (bytes[..h.body_at].to_vec(), raw)
            };
            let packed = lzf::compress(&raw);
            let mut out = Vec::with_capacity(header.len() + 8 + packed.len() + (bytes.len() - end));
            out.extend_from_slice(&header);
            out.extend_from_slice(&(packed.len() as u32).to_le_bytes());
            out.extend_from_slice(&(raw.len() as u32).to_le_bytes());
            out.extend_from_slice(&packed);
            out.extend_from_slice(&bytes[end..]);
            Ok(out)
        }
    }
}

/// Whether `float` (`SIZE 4`) `xyz` fields would hold the points of `bounds` moved by `motion`
/// more coarsely than the file did ([`Bounds::f32_coarsens`]).
fn coarsens(bounds: &Bounds, h: &Header, xyz: [usize; 3], motion: &Motion) -> bool {
    let single = xyz.map(|k| h.fields[k].size == 4);
    single.contains(&true) && bounds.f32_coarsens(motion, single)
}

/// [`coarsens`] for the points of a binary or decompressed body `buf`; `at` as for
/// [`move_values`].
fn coarsened(buf: &[u8], h: &Header, xyz: [usize; 3], motion: &Motion, at: &dyn Fn(usize, usize) -> usize) -> bool {
    if xyz.iter().all(|&k| h.fields[k].size != 4) {
        return false;
    }
    let mut bounds = Bounds::default();
    for i in 0..h.n_points as usize {
        bounds.add([0, 1, 2].map(|a| h.fields[xyz[a]].read_f64(&buf[at(i, xyz[a])..])));
    }
    coarsens(&bounds, h, xyz, motion)
}

/// The fields' sizes with x, y, z `double` (8).
fn widened_sizes(h: &Header, xyz: [usize; 3]) -> Vec<usize> {
    h.fields.iter().enumerate().map(|(f, field)| if xyz.contains(&f) { 8 } else { field.size }).collect()
}

/// The header `head` with its `SIZE` line declaring x, y, z `double` (8), and the body of `src`
/// (laid out as `h` says, field `f` of point `i` at `at(i, f)`) rebuilt so: as records, or as
/// columns (`columns`, a decompressed `binary_compressed` body); x, y, z moved by `motion`, the
/// normal turned, every other value copied. A point whose coordinates are not finite (a hole)
/// keeps them.
#[allow(clippy::too_many_arguments)]
fn widened(
    src: &[u8],
    head: &[u8],
    h: &Header,
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
    motion: &Motion,
    at: &dyn Fn(usize, usize) -> usize,
    columns: bool,
) -> (Vec<u8>, Vec<u8>) {
    let n = h.n_points as usize;
    let sizes = widened_sizes(h, xyz);
    let width = |f: usize| sizes[f] * h.fields[f].count;
    let stride: usize = (0..sizes.len()).map(width).sum();
    // where each field starts: in a record, or (columns) in the body
    let mut start = Vec::with_capacity(sizes.len());
    let mut next = 0;
    for f in 0..sizes.len() {
        start.push(next);
        next += if columns { width(f) * n } else { width(f) };
    }
    let new_at = |i: usize, f: usize| start[f] + i * if columns { sizes[f] } else { stride };
    let mut body = vec![0u8; n * stride];
    for i in 0..n {
        for f in (0..sizes.len()).filter(|f| !xyz.contains(f)) {
            let (from, to, len) = (at(i, f), new_at(i, f), width(f));
            body[to..to + len].copy_from_slice(&src[from..from + len]);
        }
        let p = [0, 1, 2].map(|a| h.fields[xyz[a]].read_f64(&src[at(i, xyz[a])..]));
        let q = if p.iter().all(|v| v.is_finite()) { motion.point(p) } else { p };
        for a in 0..3 {
            body[new_at(i, xyz[a])..][..8].copy_from_slice(&q[a].to_le_bytes());
        }
        if let Some(nf) = normal {
            let v = [0, 1, 2].map(|a| h.fields[nf[a]].read_f64(&body[new_at(i, nf[a])..]));
            if v.iter().all(|v| v.is_finite()) {
                let turned = motion.normal(v);
                (0..3).for_each(|a| h.fields[nf[a]].write_float(turned[a], &mut body[new_at(i, nf[a])..]));
            }
        }
    }
    (sized_header(head, &sizes), body)
}

/// The header `head` with its `SIZE` line declaring `sizes`, every other byte as it was.
fn sized_header(head: &[u8], sizes: &[usize]) -> Vec<u8> {
    let mut header = Vec::with_capacity(head.len() + 8);
    for line in head.split_inclusive(|&b| b == b'\n') {
        let t = line.trim_ascii_start();
        if t.len() > 4 && t[..4].eq_ignore_ascii_case(b"SIZE") && t[4].is_ascii_whitespace() {
            header.extend_from_slice(b"SIZE");
            // (sizes are 1, 2, 4 or 8: the header's check)
            for &s in sizes {
                header.extend_from_slice(&[b' ', b'0' + s as u8]);
            }
            header.extend_from_slice(if line.ends_with(b"\r\n") { b"\r\n" } else { b"\n" });
        } else {
            header.extend_from_slice(line);
        }
    }
    header
}

/// Each point's `xyz` fields in `buf` moved and its `normal` fields turned, in their own type;
/// `at(i, f)`: where field `f` of point `i` is (a binary body's records, or a decompressed body's
/// columns). A point whose values are not finite (a hole) is kept as it was.
fn move_values(
    buf: &mut [u8],
    h: &Header,
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
    motion: &Motion,
    at: &dyn Fn(usize, usize) -> usize,
) {
    let triples = [Some((xyz, false)), normal.map(|f| (f, true))];
    for i in 0..h.n_points as usize {
        for (f, turn) in triples.iter().flatten() {
            let fields = f.map(|k| &h.fields[k]);
            let at = f.map(|k| at(i, k));
            let v = [0, 1, 2].map(|a| fields[a].read_f64(&buf[at[a]..]));
            if v.iter().all(|v| v.is_finite()) {
                let moved = if *turn { motion.normal(v) } else { motion.point(v) };
                (0..3).for_each(|a| fields[a].write_float(moved[a], &mut buf[at[a]..]));
            }
        }
    }
}

/// An ascii body: each point's coordinate (and normal) tokens rewritten in the file's style.
fn move_ascii(
    bytes: &[u8],
    h: &Header,
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
    motion: &Motion,
) -> Result<Vec<u8>> {
    let tokens = |f: [usize; 3]| f.map(|i| super::pcd::token_index(&h.fields, i));
    let (xyz_at, normal_at) = (tokens(xyz), normal.map(tokens));
    let name = |i: usize| format!("field '{}'", h.fields[i].name);
    let parse = |n: usize, toks: &[&str], f: [usize; 3], at: [usize; 3]| -> Result<[f64; 3]> {
        let mut v = [0.0; 3];
        for a in 0..3 {
            v[a] = super::util::parse_f64(F, n, &name(f[a]), toks[at[a]])?;
        }
        Ok(v)
    };
    // First pass: how the file writes its numbers, and where its points are.
    let mut styles = Styles::default();
    h.ascii_rows(bytes, &mut |n, _, toks| {
        styles.bound(parse(n, toks, xyz, xyz_at)?);
        xyz_at.iter().for_each(|&k| styles.position.learn(toks[k]));
        if let Some(at) = normal_at {
            at.iter().for_each(|&k| styles.normal.learn(toks[k]));
        }
        Ok(())
    })?;
    // values written with the digits they need, declared `double` where a reader that takes the
    // header's `float` would round them (as the binary encodings are widened)
    let widen = coarsens(styles.bounds(), h, xyz, motion);
    let styles = styles.for_writing(motion);
    // Second pass: the point lines rewritten, the bytes between them copied.
    let mut out = Rewrite::new(bytes);
    let mut edits = Vec::with_capacity(6);
    h.ascii_rows(bytes, &mut |n, line, toks| {
        edits.clear();
        let p = parse(n, toks, xyz, xyz_at)?;
        if p.iter().all(|v| v.is_finite()) {
            let moved = motion.point(p);
            edits.extend((0..3).map(|a| (span(line, toks[xyz_at[a]]), moved[a], styles.position)));
        }
        if let (Some(f), Some(at)) = (normal, normal_at) {
            if let Some(v) = parse(n, toks, f, at).ok().filter(|v| v.iter().all(|v| v.is_finite())) {
                let turned = motion.normal(v);
                edits.extend((0..3).map(|a| (span(line, toks[at[a]]), turned[a], styles.normal)));
            }
        }
        out.line(line, &mut edits);
        Ok(())
    })?;
    let moved = out.finish();
    if !widen {
        return Ok(moved);
    }
    let mut widened = sized_header(&moved[..h.body_at], &widened_sizes(h, xyz));
    widened.extend_from_slice(&moved[h.body_at..]);
    Ok(widened)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_compressed_organised_cloud_keeps_its_colours_and_holes() {
        // 80 x 60, x y z (float) rgba (uint), holes as NaN
        let bytes = include_bytes!("../../fixtures/formats/table_scene_80x60_compressed.pcd");
        let m = Matrix4::new_translation(&nalgebra::Vector3::new(1.0, -2.0, 0.5))
            * nalgebra::Rotation3::from_euler_angles(0.4, -0.2, 1.1).to_homogeneous();
        let moved = transform_pcd(bytes, &m).unwrap();
        let (h, g) = (parse_header(bytes).unwrap(), parse_header(&moved).unwrap());
        let ((a, a_end), (b, b_end)) = (h.decompress(bytes).unwrap(), g.decompress(&moved).unwrap());
        assert_eq!((bytes.len() - a_end, moved.len() - b_end), (0, 0));
        let rgba = h.column_start(3);
        assert_eq!(a[rgba..], b[rgba..], "the colours are kept");
        let (mut holes, motion) = (0, Motion::new(&m).unwrap());
        for i in 0..4800 {
            let at = |c: usize, raw: &[u8]| h.fields[c].read_f64(&raw[h.column_start(c) + 4 * i..]);
            let (p, q) = ([0, 1, 2].map(|c| at(c, &a)), [0, 1, 2].map(|c| at(c, &b)));
            if p.iter().any(|v| v.is_nan()) {
                holes += 1;
                assert_eq!(p.map(f64::to_bits), q.map(f64::to_bits), "a hole stays as it was");
            } else {
                let want = motion.point(p);
                assert!((0..3).all(|k| (q[k] - want[k]).abs() < 1e-5), "{q:?} vs {want:?}");
            }
        }
        assert!(holes > 100, "{holes} holes");
    }
}
