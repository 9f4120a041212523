//! Gaussian splats (3D Gaussian Splatting's PLY layout) moved with their positions: each splat's
//! orientation, size and view-dependent colour turned and scaled as the motion turns and scales
//! the scene, so that a moved splat file renders as the scene moved.
//!
//! The layout is the one the reference implementation writes and splat viewers read: per vertex
//! `rot_0..rot_3` (a quaternion, `w x y z`, not necessarily of unit length), `scale_0..scale_2`
//! (the natural logarithms of the Gaussian's extents along its own axes) and `f_rest_0..` (the
//! spherical-harmonic colour coefficients past the constant band: for each of the three colour
//! channels in turn, those of degree 1, then 2, then 3, in the reference's real basis). A motion
//! `s R` maps a splat's quaternion `q` to `q_R q`, its log-extents to `log s` more, and its
//! colour function `f` to `f(Rᵀ d)` of the view direction `d`: each band's coefficients by the
//! band's rotation matrix ([`band_rotation`]). Positions and normals are the PLY mover's own; the
//! constant band (`f_dc_*`) and `opacity` do not change.

use super::ply::{Element, Kind};
use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

/// The largest band's size (degree 3: 7 coefficients).
const MAX_BAND: usize = 7;

/// A band's rotation matrix, its first `2l + 1` rows and columns used.
type Band = [[f64; MAX_BAND]; MAX_BAND];

/// Where a vertex's splat attributes are (property indices), when the element has them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Splat {
    /// `rot_0..rot_3`, `scale_0..scale_2`, then `f_rest_0..f_rest_{3k-1}`, `k` coefficients per
    /// channel (3, 8 or 15: degree 1, 2 or 3; none when the element has none, or a count of no
    /// whole degree): the order [`SplatMotion::apply`] takes their values in.
    indices: Vec<usize>,
}

/// How many of [`Splat::indices`] come before the colour coefficients (the quaternion's 4, the
/// log-extents' 3).
const SHAPE: usize = 7;

impl Splat {
    /// The splat attributes of the vertex element `el`: `rot_0..3` and `scale_0..2` as
    /// floating-point scalars (else `None`: not a splat file), and `f_rest_*` when they make
    /// whole degrees.
    pub(super) fn of(el: &Element) -> Option<Self> {
        let find = |name: String| {
            el.props.iter().position(|p| p.name == name && matches!(p.kind, Kind::Scalar(s) if !s.is_int()))
        };
        let [r0, r1, r2, r3] = [0, 1, 2, 3].map(|k| find(format!("rot_{k}")));
        let [s0, s1, s2] = [0, 1, 2].map(|k| find(format!("scale_{k}")));
        let rest: Vec<usize> = (0..).map_while(|k| find(format!("f_rest_{k}"))).collect();
        let rest = if [9, 24, 45].contains(&rest.len()) { rest } else { Vec::new() };
        Some(Self { indices: [r0?, r1?, r2?, r3?, s0?, s1?, s2?].into_iter().chain(rest).collect() })
    }

    /// The property indices the mover reads and writes, in the order [`SplatMotion::apply`]
    /// takes their values: the quaternion, the log-extents, the colour coefficients.
    pub(super) fn indices(&self) -> &[usize] {
        &self.indices
    }
}

/// A motion's action on splat attributes ([`Splat::indices`]'s values).
pub(super) struct SplatMotion {
    /// `q_R`.
    turn: UnitQuaternion<f64>,
    /// `log s`.
    log_scale: f64,
    /// Each band's rotation matrix, degree 1 first.
    bands: Vec<Band>,
}

impl SplatMotion {
    /// The action of the motion `s R` (`rotation` `R`, `scale` `s`) on the attributes of `splat`.
    pub(super) fn new(rotation: &Matrix3<f64>, scale: f64, splat: &Splat) -> Self {
        let turn = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*rotation));
        let degrees = match (splat.indices.len() - SHAPE) / 3 {
            3 => 1,
            8 => 2,
            15 => 3,
            _ => 0,
        };
        let bands = (1..=degrees).map(|l| band_rotation(l, rotation)).collect();
        Self { turn, log_scale: scale.abs().ln(), bands }
    }

    /// Moves one splat's attributes, given in [`Splat::indices`]'s order.
    pub(super) fn apply(&self, values: &mut [f64]) {
        let [w, x, y, z] = [values[0], values[1], values[2], values[3]];
        let q = self.turn.quaternion() * Quaternion::new(w, x, y, z);
        values[..4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
        for v in &mut values[4..SHAPE] {
            *v += self.log_scale;
        }
        let rest = &mut values[SHAPE..];
        let per = rest.len() / 3;
        for channel in rest.chunks_exact_mut(per.max(1)) {
            let mut at = 0;
            for (l, m) in self.bands.iter().enumerate() {
                let n = 2 * l + 3;
                let mut turned = [0.0; MAX_BAND];
                for (r, t) in turned.iter_mut().enumerate().take(n) {
                    *t = (0..n).map(|c| m[r][c] * channel[at + c]).sum();
                }
                channel[at..at + n].copy_from_slice(&turned[..n]);
                at += n;
            }
        }
    }
}

/// The real spherical harmonics of degree `l` (1 to 3) at the unit direction `d`, in the basis
/// and order 3D Gaussian Splatting evaluates them (the first `2l + 1` entries).
fn basis(l: usize, d: Vector3<f64>) -> [f64; MAX_BAND] {
    let (x, y, z) = (d.x, d.y, d.z);
    let (xx, yy, zz) = (x * x, y * y, z * z);
    match l {
        1 => {
            let c = 0.488_602_511_902_919_9;
            [-c * y, c * z, -c * x, 0.0, 0.0, 0.0, 0.0]
        }
        2 => [
            1.092_548_430_592_079_2 * x * y,
            -1.092_548_430_592_079_2 * y * z,
            0.315_391_565_252_520_05 * (2.0 * zz - xx - yy),
            -1.092_548_430_592_079_2 * x * z,
            0.546_274_215_296_039_6 * (xx - yy),
            0.0,
            0.0,
        ],
        _ => [
            -0.590_043_589_926_643_5 * y * (3.0 * xx - yy),
            2.890_611_442_640_554 * x * y * z,
            -0.457_045_799_464_465_8 * y * (4.0 * zz - xx - yy),
            0.373_176_332_590_115_4 * z * (2.0 * zz - 3.0 * xx - 3.0 * yy),
            -0.457_045_799_464_465_8 * x * (4.0 * zz - xx - yy),
            1.445_305_721_320_277 * z * (xx - yy),
            -0.590_043_589_926_643_5 * x * (xx - 3.0 * yy),
        ],
    }
}

/// The matrix `M` that turns a colour function's coefficients of degree `l` by `rotation`: with
/// `f(d) = Σ c_m Y_m(d)`, `f(Rᵀ d) = Σ (M c)_m Y_m(d)`. Exact (each band is closed under
/// rotations), found by least squares over 64 directions spread over the sphere: `(AᵀA) M =
/// AᵀB`, `A` the basis at the directions and `B` at the directions turned back, solved by
/// Gauss-Jordan elimination (`AᵀA`, the band's Gram matrix over the directions, is well
/// conditioned).
fn band_rotation(l: usize, rotation: &Matrix3<f64>) -> Band {
    const DIRECTIONS: usize = 64;
    let n = 2 * l + 1;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    // [AᵀA | AᵀB], accumulated direction by direction
    let mut g = [[0.0f64; 2 * MAX_BAND]; MAX_BAND];
    for j in 0..DIRECTIONS {
        let z = 1.0 - 2.0 * (j as f64 + 0.5) / DIRECTIONS as f64;
        let r = (1.0 - z * z).sqrt();
        let d = Vector3::new(r * (golden * j as f64).cos(), r * (golden * j as f64).sin(), z);
        let (a, b) = (basis(l, d), basis(l, rotation.transpose() * d));
        for (row, ar) in g.iter_mut().zip(a).take(n) {
            for c in 0..n {
                row[c] += ar * a[c];
                row[MAX_BAND + c] += ar * b[c];
            }
        }
    }
    for k in 0..n {
        let pivot = (k..n).fold(k, |p, r| if g[r][k].abs() > g[p][k].abs() { r } else { p });
        g.swap(k, pivot);
        let diagonal = g[k][k];
        for v in g[k].iter_mut() {
            *v /= diagonal;
        }
        let here = g[k];
        for (r, row) in g.iter_mut().enumerate().take(n) {
            if r != k {
                let f = row[k];
                for (v, h) in row.iter_mut().zip(here) {
                    *v -= f * h;
                }
            }
        }
    }
    let mut m = [[0.0; MAX_BAND]; MAX_BAND];
    for (row, solved) in m.iter_mut().zip(g) {
        row[..n].copy_from_slice(&solved[MAX_BAND..MAX_BAND + n]);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rotation() -> Matrix3<f64> {
        *Rotation3::from_euler_angles(0.7, -1.9, 2.6).matrix()
    }

    #[test]
    fn a_turned_colour_function_reads_the_old_one_from_the_old_direction() {
        let r = rotation();
        for l in 1..=3 {
            let (m, n) = (band_rotation(l, &r), 2 * l + 1);
            let c: Vec<f64> = (0..n).map(|k| (k as f64 * 1.7 + 0.3).sin()).collect();
            let turned: Vec<f64> = (0..n).map(|i| (0..n).map(|k| m[i][k] * c[k]).sum()).collect();
            for d in [Vector3::new(0.3, -0.5, 0.81), Vector3::new(-0.9, 0.1, 0.2), Vector3::new(0.0, 0.0, 1.0)] {
                let d = d.normalize();
                let f = |coeffs: &[f64], dir: Vector3<f64>| -> f64 {
                    basis(l, dir).iter().zip(coeffs).map(|(y, c)| y * c).sum()
                };
                let (new, old) = (f(&turned, d), f(&c, r.transpose() * d));
                assert!((new - old).abs() < 1e-12, "degree {l}: {new} vs {old}");
            }
        }
    }

    #[test]
    fn a_splat_is_turned_and_scaled_with_the_scene() {
        let r = rotation();
        let splat = Splat { indices: (0..52).collect() };
        let motion = SplatMotion::new(&r, 2.5, &splat);
        // an unnormalised quaternion, log-extents, and degree-3 colour
        let q = Quaternion::new(0.8, -0.4, 1.1, 0.3);
        let mut v: Vec<f64> = vec![q.w, q.i, q.j, q.k, -3.0, -4.0, -5.0];
        v.extend((0..45).map(|k| (k as f64 * 0.37).cos()));
        let before = v.clone();
        motion.apply(&mut v);
        // its axes turned by R: the rotation of the new quaternion is R times the old one's
        let axes = |v: &[f64]| {
            *UnitQuaternion::from_quaternion(Quaternion::new(v[0], v[1], v[2], v[3])).to_rotation_matrix().matrix()
        };
        assert!((axes(&v) - r * axes(&before)).abs().max() < 1e-12);
        let norm = |v: &[f64]| v[..4].iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm(&v) - norm(&before)).abs() < 1e-12);
        // its extents 2.5 times larger
        for k in 4..7 {
            assert!((v[k] - before[k] - 2.5f64.ln()).abs() < 1e-12);
        }
        // each channel's degree-1 band turned as the band's matrix turns it
        let m1 = band_rotation(1, &r);
        for c in 0..3 {
            let old = &before[7 + 15 * c..7 + 15 * c + 3];
            let want: Vec<f64> = (0..3).map(|i| (0..3).map(|k| m1[i][k] * old[k]).sum()).collect();
            assert!((0..3).all(|k| (v[7 + 15 * c + k] - want[k]).abs() < 1e-12));
        }
    }
}
