//! An OBJ file moved as it is: its `v` positions mapped and its `vn` normals turned, every other
//! byte kept (faces, texture coordinates, groups, materials, comments, a vertex's `w` or colour
//! values). Values are written as the file wrote its numbers. The motion keeps the faces' winding
//! (it never mirrors). The file is read by the OBJ reader first, so a file it refuses is refused
//! here too.

use super::keyword_lines::{move_keyword_lines, Triple};
use super::motion::Motion;
use super::obj::F;
use crate::Result;
use nalgebra::Matrix4;

/// The OBJ file `bytes` with its vertices moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale) and its normals turned (see the module docs). Errors: a file the
/// OBJ reader refuses, a transform that is not rigid (or uniformly scaled).
pub(crate) fn transform_obj(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    super::obj::read(bytes)?;
    move_keyword_lines(bytes, F, &[(&["v"], Triple::Point), (&["vn"], Triple::Normal)], &motion)
}
