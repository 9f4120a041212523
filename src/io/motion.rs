//! The motions a file can be moved by as it is ([`super::transform_file`]): rigid, or rigid
//! times one uniform scale (a change of unit).

use crate::transform::RIGID_TOLERANCE;
use crate::{Error, Result};
use nalgebra::{Matrix3, Matrix4, Vector3};

/// `m`'s linear part as `s R` (`R` a rotation, `s > 0`), checked: finite, the bottom row
/// `[0, 0, 0, 1]`, and `R` orthonormal to [`RIGID_TOLERANCE`]. As for the other transforms a
/// caller gives (`transform::nearest_rigid`), `R` is then the rotation nearest it, and a scale
/// within that tolerance of 1 (a rigid matrix written with a few decimals) is 1. Returns
/// `(s R, R, t)`.
fn similarity(m: &Matrix4<f64>) -> Result<(Matrix3<f64>, Matrix3<f64>, Vector3<f64>)> {
    let bad = |why: &str| Err(Error::InvalidOption(format!("the transform is not rigid (or uniformly scaled): {why}")));
    if m.iter().any(|v| !v.is_finite()) {
        return bad("it has a non-finite entry");
    }
    let bottom = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)] - 1.0];
    if bottom.iter().map(|v| v.abs()).sum::<f64>() > RIGID_TOLERANCE {
        return bad("its bottom row is not [0, 0, 0, 1]");
    }
    let linear: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let det = linear.determinant();
    if det <= 0.0 {
        return bad("it mirrors or flattens (determinant not > 0)");
    }
    let scale = det.cbrt();
    let rotation = linear / scale;
    if (rotation.transpose() * rotation - Matrix3::identity()).abs().max() > RIGID_TOLERANCE {
        return bad("its linear part is not a rotation times one scale");
    }
    // (a computed transform, rigid to 1e-9, is used bit for bit)
    let t = m.fixed_view::<3, 1>(0, 3).into_owned();
    if (scale - 1.0).abs() <= 1e-9 && crate::transform::check_rigid(m, 1e-9).is_ok() {
        return Ok((linear, linear, t));
    }
    let rotation = crate::rigid::nearest_rotation(&rotation);
    let scale = if (scale - 1.0).abs() <= RIGID_TOLERANCE { 1.0 } else { scale };
    Ok((rotation * scale, rotation, t))
}

/// A checked motion ([`similarity`]) that maps points and turns normals.
pub(super) struct Motion {
    /// `s R`.
    pub(super) linear: Matrix3<f64>,
    /// `R`.
    pub(super) rotation: Matrix3<f64>,
    /// The translation.
    pub(super) t: Vector3<f64>,
}

impl Motion {
    /// `m` checked as [`similarity`] checks it.
    pub(super) fn new(m: &Matrix4<f64>) -> Result<Self> {
        let (linear, rotation, t) = similarity(m)?;
        Ok(Self { linear, rotation, t })
    }

    /// The uniform scale `s`.
    pub(super) fn scale(&self) -> f64 {
        self.linear.determinant().cbrt()
    }

    /// A point mapped: `s R p + t`.
    pub(super) fn point(&self, p: [f64; 3]) -> [f64; 3] {
        (self.linear * Vector3::from(p) + self.t).into()
    }

    /// A normal turned: `R n`.
    pub(super) fn normal(&self, n: [f64; 3]) -> [f64; 3] {
        (self.rotation * Vector3::from(n)).into()
    }
}
