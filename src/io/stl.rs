//! STL, ascii and binary. Vertices are merged by exact position (STL repeats every corner per
//! facet), so the mesh is indexed and the point cloud holds each corner once.
//!
//! An own reader rather than `stl_io`: the binary layout is 50 bytes per facet, and telling
//! ascii from a binary file whose 80-byte header happens to start with `solid` needs the size
//! rule used by [`is_binary`] anyway.

use super::util::{fan, parse_f64, show, utf8_line, Lines};
use super::Raw;
use crate::{Error, Result};
use std::collections::HashMap;

pub(crate) const F: &str = "STL";

/// True when the length matches the binary layout exactly: 80-byte header, `u32` facet count,
/// 50 bytes per facet.
pub(crate) fn binary_size_matches(bytes: &[u8]) -> bool {
    bytes.len() >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        84 + 50 * n == bytes.len() as u64
    }
}

/// Binary when the size rule holds, or when the file does not start with `solid`.
pub(crate) fn is_binary(bytes: &[u8]) -> bool {
    binary_size_matches(bytes) || !bytes.trim_ascii_start().starts_with(b"solid")
}

/// Merges corners by exact position (`-0.0` and `0.0` are one position).
#[derive(Default)]
struct Welder {
    vertices: Vec<[f32; 3]>,
    index: HashMap<[u32; 3], u32>,
}

impl Welder {
    fn add(&mut self, p: [f32; 3]) -> u32 {
        let key = p.map(|v| (v + 0.0).to_bits());
        let next = self.vertices.len() as u32;
        *self.index.entry(key).or_insert_with(|| {
            self.vertices.push(p);
            next
        })
    }
}

pub(crate) fn read(bytes: &[u8]) -> Result<Raw> {
    if is_binary(bytes) {
        return read_binary(bytes);
    }
    read_ascii(bytes).map_err(|e| match e {
        // A binary file whose header starts with "solid" but whose size is off (truncated).
        Error::Parse { format, message } if bytes.len() >= 84 && bytes[..bytes.len().min(1024)].contains(&0) => {
            let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
            Error::parse(
                format,
                format!(
                    "{message} (if this is a binary STL: its header declares {n} facets, {} bytes, but the file has {} bytes)",
                    84 + 50 * n,
                    bytes.len()
                ),
            )
        }
        e => e,
    })
}

fn read_binary(bytes: &[u8]) -> Result<Raw> {
    if bytes.len() < 84 {
        return Err(Error::parse(
            F,
            format!(
                "binary STL needs an 84-byte header (80 bytes, then the facet count), but the file has {} bytes",
                bytes.len()
            ),
        ));
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    let need = 84 + 50 * n;
    if need > bytes.len() as u64 {
        return Err(Error::parse(
            F,
            format!(
                "truncated binary STL: the header declares {n} facets ({need} bytes), but the file has {} bytes",
                bytes.len()
            ),
        ));
    }
    let n = n as usize;
    let mut w = Welder::default();
    w.vertices.reserve(n / 2 + 3);
    let mut triangles = Vec::with_capacity(n);
    for rec in bytes[84..84 + 50 * n].chunks_exact(50) {
        let v = |k: usize| {
            let o = 12 + 12 * k;
            [0, 1, 2].map(|a| {
                f32::from_le_bytes([rec[o + 4 * a], rec[o + 4 * a + 1], rec[o + 4 * a + 2], rec[o + 4 * a + 3]])
            })
        };
        let t = [w.add(v(0)), w.add(v(1)), w.add(v(2))];
        triangles.push(t);
    }
    Ok(Raw { vertices: w.vertices.iter().map(|p| p.map(f64::from)).collect(), triangles })
}

fn read_ascii(bytes: &[u8]) -> Result<Raw> {
    let mut w = Welder::default();
    let mut triangles = Vec::new();
    let mut loop_: Option<(usize, Vec<u32>)> = None; // (line of `outer loop`, corners)
    let mut facets = 0usize;
    for (n, raw) in Lines::new(bytes) {
        let line = utf8_line(F, n, raw)?;
        let mut t = line.split_ascii_whitespace();
        let Some(kw) = t.next() else { continue };
        match kw {
            "solid" | "endsolid" | "facet" | "endfacet" => {}
            "outer" => {
                if let Some((start, _)) = loop_ {
                    return Err(Error::parse(
                        F,
                        format!("line {n}: 'outer loop' inside the loop opened at line {start}"),
                    ));
                }
                loop_ = Some((n, Vec::with_capacity(3)));
            }
            "vertex" => {
                let Some((_, corners)) = loop_.as_mut() else {
                    return Err(Error::parse(F, format!("line {n}: 'vertex' outside an 'outer loop'")));
                };
                let mut p = [0.0f32; 3];
                for (a, v) in p.iter_mut().enumerate() {
                    let axis = ["x", "y", "z"][a];
                    let tok = t
                        .next()
                        .ok_or_else(|| Error::parse(F, format!("line {n}: vertex has {a} coordinates, expected 3")))?;
                    *v = parse_f64(F, n, axis, tok)? as f32; // STL is single precision
                }
                corners.push(w.add(p));
            }
            "endloop" => {
                let Some((start, corners)) = loop_.take() else {
                    return Err(Error::parse(F, format!("line {n}: 'endloop' without 'outer loop'")));
                };
                if corners.len() < 3 {
                    return Err(Error::parse(
                        F,
                        format!(
                            "line {n}: the facet loop opened at line {start} has {} vertices, expected 3",
                            corners.len()
                        ),
                    ));
                }
                fan(&corners, &mut triangles);
                facets += 1;
            }
            other => return Err(Error::parse(F, format!("line {n}: unexpected keyword {} in ascii STL", show(other)))),
        }
    }
    if let Some((start, _)) = loop_ {
        return Err(Error::parse(F, format!("the file ends inside the facet loop opened at line {start}")));
    }
    if facets == 0 {
        return Err(Error::parse(F, "ascii STL has no facets"));
    }
    Ok(Raw { vertices: w.vertices.iter().map(|p| p.map(f64::from)).collect(), triangles })
}

/// True when the content is STL: the binary size rule, or `solid` followed by `facet`.
pub(crate) fn sniff(bytes: &[u8]) -> bool {
    if binary_size_matches(bytes) {
        return true;
    }
    let t = bytes.trim_ascii_start();
    t.starts_with(b"solid") && {
        let head = &t[..t.len().min(1024)];
        head.windows(5).any(|w| w == b"facet") || head.windows(8).any(|w| w == b"endsolid")
    }
}
