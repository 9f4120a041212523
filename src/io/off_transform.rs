//! An OFF file moved as it is: each vertex's x, y, z mapped and, in an `NOFF` file, its normal
//! (the three values after them) turned; every other byte kept (the header, colours, texture
//! coordinates, faces, comments), the values written as the file wrote its numbers. A vertex
//! record split over several lines is moved where its values are. The motion keeps the faces'
//! winding (it never mirrors). The file is read by the OFF reader first, so a file it refuses is
//! refused here too.

use super::motion::Motion;
use super::number_style::{Rewrite, Styles};
use super::off::vertex_records;
use super::text::values;
use crate::Result;
use nalgebra::Matrix4;

/// The three values of `toks` from `at`, when they are there and are finite numbers.
fn triple(toks: &[&str], at: usize) -> Option<[f64; 3]> {
    values(toks, [at, at + 1, at + 2]).filter(|v| v.iter().all(|v| v.is_finite()))
}

/// The OFF file `bytes` with its vertices moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale) and, in an `NOFF` file, its normals turned (see the module docs).
/// Errors: a file the OFF reader refuses, a transform that is not rigid (or uniformly scaled).
pub(crate) fn transform_off(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    super::off::read(bytes)?;
    // First pass: how the file writes its numbers, and whether its vertices carry normals.
    let mut styles = Styles::default();
    let prefix = vertex_records(bytes, &mut |_, toks| {
        toks[..3].iter().for_each(|t| styles.position.learn(t));
        if let Some(p) = triple(toks, 0) {
            styles.bound(p);
        }
        toks.iter().skip(3).take(3).for_each(|t| styles.normal.learn(t));
        Ok(())
    })?;
    let normals = prefix.contains('N');
    let styles = styles.for_writing(&motion);
    // Second pass: the values rewritten where they are, the bytes between them copied.
    let mut out = Rewrite::new(bytes);
    vertex_records(bytes, &mut |_, toks| {
        if let Some(p) = triple(toks, 0) {
            let moved = motion.point(p);
            (0..3).for_each(|a| out.token(toks[a], moved[a], styles.position));
        }
        if let Some(v) = triple(toks, 3).filter(|_| normals) {
            let turned = motion.normal(v);
            (0..3).for_each(|a| out.token(toks[3 + a], turned[a], styles.normal));
        }
        Ok(())
    })?;
    Ok(out.finish())
}
