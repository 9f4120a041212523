//! An STL file moved as it is: its corners mapped and its facet normals turned, every other byte
//! kept (the 80-byte header, each facet's attribute bytes, the solid's name). Binary files are
//! rewritten in place in `float` (refused when the motion takes them so far from zero that
//! `float` would round them: [`super::motion::check_f32`]); ASCII files have their `vertex` and `facet normal` values
//! rewritten as the file wrote its numbers. The motion keeps the facets' winding (it never
//! mirrors). The file is read by the STL reader first, so a file it refuses is refused here too.

use super::keyword_lines::{move_keyword_lines, Triple};
use super::motion::{check_f32, Bounds, Motion};
use super::stl::{is_binary, F};
use crate::Result;
use nalgebra::Matrix4;

/// The STL file `bytes` with its corners moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale) and its facet normals turned (see the module docs). Errors: a file
/// the STL reader refuses, a transform that is not rigid (or uniformly scaled).
pub(crate) fn transform_stl(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    super::stl::read(bytes)?;
    if !is_binary(bytes) {
        let keywords: &[(&[&str], Triple)] = &[(&["vertex"], Triple::Point), (&["facet", "normal"], Triple::Normal)];
        return move_keyword_lines(bytes, F, keywords, &motion);
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let corner = |rec: &[u8], k: usize| {
        [0, 1, 2].map(|a| {
            let o = 12 * k + 4 * a;
            f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]) as f64
        })
    };
    let mut bounds = Bounds::default();
    for rec in bytes[84..84 + 50 * n].chunks_exact(50) {
        (1..4).for_each(|k| bounds.add(corner(rec, k)));
    }
    check_f32(&bounds, &motion, [true; 3], "binary STL")?;
    let mut out = bytes.to_vec();
    for rec in out[84..84 + 50 * n].chunks_exact_mut(50) {
        for k in 0..4 {
            let at = 12 * k;
            let v = corner(rec, k);
            if !v.iter().all(|v| v.is_finite()) {
                continue;
            }
            let moved = if k == 0 { motion.normal(v) } else { motion.point(v) };
            for a in 0..3 {
                rec[at + 4 * a..at + 4 * a + 4].copy_from_slice(&(moved[a] as f32).to_le_bytes());
            }
        }
    }
    Ok(out)
}
