//! An OBJ file moved as it is: its `v` positions mapped and its `vn` normals turned, every other
//! byte kept (faces, texture coordinates, groups, materials, comments, a vertex's `w` or colour
//! values). Values are written as the file wrote its numbers. The motion keeps the faces' winding
//! (it never mirrors). The file is read by the OBJ reader first, so a file it refuses is refused
//! here too, and so is a `v` or `vn` line continued on the next (its values cannot be rewritten
//! in place).

use super::keyword_lines::{move_keyword_lines, Triple};
use super::motion::Motion;
use super::obj::{continued, F};
use super::util::Lines;
use crate::{Error, Result};
use nalgebra::Matrix4;

/// The OBJ file `bytes` with its vertices moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale) and its normals turned (see the module docs). Errors: a file the
/// OBJ reader refuses, a transform that is not rigid (or uniformly scaled).
pub(crate) fn transform_obj(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    super::obj::read(bytes)?;
    refuse_continued_vertices(bytes)?;
    move_keyword_lines(bytes, F, &[(&["v"], Triple::Point), (&["vn"], Triple::Normal)], &motion)
}

/// An error naming the first `v` or `vn` line that continues on the next.
fn refuse_continued_vertices(bytes: &[u8]) -> Result<()> {
    for (n, raw) in Lines::new(bytes) {
        let kw = raw.trim_ascii_start().split(|b| b.is_ascii_whitespace()).next().unwrap_or_default();
        if (kw == b"v" || kw == b"vn") && continued(raw).is_some() {
            return Err(Error::unmovable(
                F,
                format!(
                    "line {n}: a vertex continued on the next line (a trailing '\\') cannot be moved in place; \
                     join the line to write this file moved"
                ),
            ));
        }
    }
    Ok(())
}
