//! Rigid transforms as 4x4 matrices, and the error metrics of the paper.
//!
//! # Conventions (documented once, used everywhere)
//! * `T_target_source` maps a point expressed in the source frame into the target frame:
//!   `p_target = R * p_source + t`, with `T = [[R, t], [0, 0, 0, 1]]`.
//! * In Rust the transform is a [`nalgebra::Matrix4<f64>`].
//! * Across the JavaScript and JSON boundary ([`crate::contract`]) a 4x4 is 16 numbers in
//!   **column-major** order (element `(row r, col c)` at index `c * 4 + r`), exactly what three.js
//!   `Matrix4.fromArray` reads. [`from_column_major`] and [`to_column_major_f32`] convert.
//! * Four **row-major** rows (`[[r00, r01, r02, t0], ...]`), as people read matrices, are
//!   [`to_rows`] and [`from_rows`]; [`crate::Options::initial_transform`] holds them.

use nalgebra::{Matrix3, Matrix4, Vector3};

/// Builds `[[R, t], [0, 0, 0, 1]]`.
pub fn from_rotation_translation(r: &Matrix3<f64>, t: &Vector3<f64>) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(t);
    m
}

/// The rotation block `R` of a rigid transform.
pub fn rotation(m: &Matrix4<f64>) -> Matrix3<f64> {
    m.fixed_view::<3, 3>(0, 0).into_owned()
}

/// The translation `t` of a rigid transform.
pub fn translation(m: &Matrix4<f64>) -> Vector3<f64> {
    m.fixed_view::<3, 1>(0, 3).into_owned()
}

/// The inverse of a rigid transform, in closed form: `[[R^T, -R^T t], [0, 1]]`.
pub fn rigid_inverse(m: &Matrix4<f64>) -> Matrix4<f64> {
    let rt = rotation(m).transpose();
    let t = -(rt * translation(m));
    from_rotation_translation(&rt, &t)
}

/// Applies a rigid transform to a point.
pub fn apply(m: &Matrix4<f64>, p: [f32; 3]) -> [f32; 3] {
    mapping(m)(p)
}

/// [`apply`] with `m`'s rotation and translation taken out once, for mapping many points (the
/// same arithmetic, so the same bits).
pub fn mapping(m: &Matrix4<f64>) -> impl Fn([f32; 3]) -> [f32; 3] {
    let (r, t) = (rotation(m), translation(m));
    move |p| {
        let q = r * Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) + t;
        [q.x as f32, q.y as f32, q.z as f32]
    }
}

/// Geodesic rotation error in degrees: the angle of `R = R_a^T R_b`, the paper's
/// `acos((tr(R) - 1) / 2)`, computed as `atan2(|R - R^T| / 2, (tr(R) - 1) / 2)` (the sine from
/// `R`'s skew part). Both forms agree on rotations; this one stays exact near 0 and 180 degrees,
/// where `acos` loses half the digits, and a matrix a little off orthonormal (ground truth
/// written with few decimals) measures 0 against itself, where `acos` would read up to a degree.
pub fn rotation_error_deg(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
    let r = rotation(a).transpose() * rotation(b);
    let skew = Vector3::new(r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]);
    (skew.norm() / 2.0).atan2((r.trace() - 1.0) / 2.0).to_degrees()
}

/// Translation error: `|t_a - t_b|`.
pub fn translation_error(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
    (translation(a) - translation(b)).norm()
}

/// Rotation angle of a rigid transform in degrees (0 for the identity).
pub fn rotation_angle_deg(m: &Matrix4<f64>) -> f64 {
    rotation_error_deg(m, &Matrix4::identity())
}

/// Four row-major rows, as the CLI's JSON prints them.
pub fn to_rows(m: &Matrix4<f64>) -> [[f64; 4]; 4] {
    let mut rows = [[0.0; 4]; 4];
    for (r, row) in rows.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = m[(r, c)];
        }
    }
    rows
}

/// From four row-major rows.
pub fn from_rows(rows: &[[f64; 4]; 4]) -> Matrix4<f64> {
    Matrix4::from_fn(|r, c| rows[r][c])
}

/// Column-major `f32` array of 16, for three.js `Matrix4.fromArray`.
pub fn to_column_major_f32(m: &Matrix4<f64>) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    for c in 0..4 {
        for r in 0..4 {
            out[c * 4 + r] = m[(r, c)] as f32;
        }
    }
    out
}

/// From a column-major array of 16 (three.js `Matrix4.elements`).
pub fn from_column_major(a: &[f64; 16]) -> Matrix4<f64> {
    Matrix4::from_fn(|r, c| a[c * 4 + r])
}

/// Checks that `m` is a finite rigid transform: bottom row `[0, 0, 0, 1]`, `R^T R = I` and
/// `det R = +1` to within `tol`. Returns a message saying what is off.
pub fn check_rigid(m: &Matrix4<f64>, tol: f64) -> Result<(), String> {
    if m.iter().any(|v| !v.is_finite()) {
        return Err("transform has non-finite entries".into());
    }
    let bottom = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)]];
    if (bottom[0].abs() + bottom[1].abs() + bottom[2].abs() + (bottom[3] - 1.0).abs()) > tol {
        return Err(format!("bottom row is {bottom:?}, expected [0, 0, 0, 1]"));
    }
    let r = rotation(m);
    let ortho = (r.transpose() * r - Matrix3::identity()).abs().max();
    if ortho > tol {
        return Err(format!("rotation block is not orthonormal (|R^T R - I| = {ortho:.2e})"));
    }
    let det = r.determinant();
    if (det - 1.0).abs() > tol {
        return Err(format!("rotation block has determinant {det:.6}, expected +1"));
    }
    Ok(())
}

/// How far from rigid a transform a caller gives may be (`|R^T R - I|`, `|det R - 1|` and the
/// bottom row, each): matrices written with a few decimals (a benchmark's ground truth, a text
/// file) are within it, and are used as the rigid transform nearest them ([`nearest_rigid`]).
pub const RIGID_TOLERANCE: f64 = 1e-3;

/// Checks that `m` is within [`RIGID_TOLERANCE`] of rigid (the matrices [`nearest_rigid`]
/// accepts), for a caller that applies it as given: an error saying what is off.
pub fn check_near_rigid(m: &Matrix4<f64>) -> Result<(), String> {
    check_rigid(m, RIGID_TOLERANCE).map_err(|e| format!("{e}, beyond {RIGID_TOLERANCE:e}"))
}

/// The rigid transform nearest `m`: the rotation nearest its rotation block (its polar factor),
/// its translation, the bottom row `[0, 0, 0, 1]`; `m` itself when it is rigid to 1e-9 (a
/// computed transform, used bit for bit). An error saying what is off when `m` is further than
/// [`RIGID_TOLERANCE`] from rigid (or not finite).
pub fn nearest_rigid(m: &Matrix4<f64>) -> Result<Matrix4<f64>, String> {
    check_near_rigid(m)?;
    if check_rigid(m, 1e-9).is_ok() {
        return Ok(*m);
    }
    Ok(from_rotation_translation(&crate::rigid::nearest_rotation(&rotation(m)), &translation(m)))
}

/// Rotation from Euler angles in radians, `R = Rx(ax) * Ry(ay) * Rz(az)` (the DCP / paper protocol).
pub fn euler_xyz(ax: f64, ay: f64, az: f64) -> Matrix3<f64> {
    let (sx, cx) = ax.sin_cos();
    let (sy, cy) = ay.sin_cos();
    let (sz, cz) = az.sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cx, -sx, 0.0, sx, cx);
    let ry = Matrix3::new(cy, 0.0, sy, 0.0, 1.0, 0.0, -sy, 0.0, cy);
    let rz = Matrix3::new(cz, -sz, 0.0, sz, cz, 0.0, 0.0, 0.0, 1.0);
    rx * ry * rz
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_major_round_trip_and_layout() {
        let m = from_rotation_translation(&euler_xyz(0.1, -0.2, 0.3), &Vector3::new(1.0, 2.0, 3.0));
        let cm = to_column_major_f32(&m);
        // translation sits at indices 12, 13, 14 in column-major order (three.js layout)
        assert_eq!([cm[12], cm[13], cm[14], cm[15]], [1.0, 2.0, 3.0, 1.0]);
        let back = from_column_major(&cm.map(|v| v as f64));
        assert!((back - m).abs().max() < 1e-6);
        assert_eq!(from_rows(&to_rows(&m)), m);
    }

    #[test]
    fn inverse_and_errors() {
        let m = from_rotation_translation(&euler_xyz(0.3, 0.2, -0.5), &Vector3::new(0.1, -0.4, 0.2));
        let id = m * rigid_inverse(&m);
        assert!((id - Matrix4::identity()).abs().max() < 1e-12);
        assert!(check_rigid(&m, 1e-9).is_ok());
        let ten = from_rotation_translation(&euler_xyz(10f64.to_radians(), 0.0, 0.0), &Vector3::zeros());
        assert!((rotation_angle_deg(&ten) - 10.0).abs() < 1e-9);
        let mut bad = m;
        bad[(0, 0)] = 2.0;
        assert!(check_rigid(&bad, 1e-6).is_err());
    }

    #[test]
    fn rotation_error_is_the_angle_and_exact_near_zero() {
        for (deg, axis) in [
            (0.0f64, Vector3::x()),
            (1e-6, Vector3::y()),
            (0.5, Vector3::z()),
            (37.0, Vector3::x()),
            (90.0, Vector3::new(1.0, 1.0, 0.0)),
            (179.9, Vector3::y()),
            (180.0, Vector3::new(0.0, 1.0, 1.0)),
        ] {
            let r = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), deg.to_radians());
            let a = from_rotation_translation(&euler_xyz(0.3, -1.2, 2.0), &Vector3::new(1.0, 2.0, 3.0));
            let b = a * from_rotation_translation(r.matrix(), &Vector3::zeros());
            let e = rotation_error_deg(&a, &b);
            assert!((e - deg).abs() < 1e-9, "{deg}: {e}");
            assert!((rotation_error_deg(&b, &a) - deg).abs() < 1e-9, "{deg}: symmetric");
        }
        // a matrix a little off orthonormal (3DMatch's ground truth is 1e-4 off): 0 against itself,
        // where acos((tr - 1) / 2) can read most of a degree
        let mut m = from_rotation_translation(&euler_xyz(0.3, 0.2, -0.5), &Vector3::zeros());
        m[(0, 0)] *= 0.9999;
        assert_eq!(rotation_error_deg(&m, &m), 0.0);
    }

    #[test]
    fn a_rigid_matrix_written_with_few_decimals_is_made_exact() {
        let m = from_rotation_translation(&euler_xyz(0.3, 0.2, -0.5), &Vector3::new(0.1, -0.4, 0.2));
        // four decimals, as a benchmark's ground truth or a text file holds them
        let written = m.map(|v| (v * 1e4).round() / 1e4);
        assert!(check_rigid(&written, 1e-4).is_err());
        let exact = nearest_rigid(&written).unwrap();
        assert!(check_rigid(&exact, 1e-12).is_ok());
        assert!((exact - m).abs().max() < 1e-4 && translation(&exact) == translation(&written));
        // a scale of 1%, a shear, a mirror: not rigid
        for bad in [
            m * Matrix4::new_scaling(1.01),
            m + Matrix4::new(0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            m * Matrix4::new_nonuniform_scaling(&Vector3::new(-1.0, 1.0, 1.0)),
        ] {
            let e = nearest_rigid(&bad).unwrap_err();
            assert!(e.contains("beyond 1e-3"), "{e}");
        }
    }
}
