//! Gaussian mixture registration: GMM parameters from memberships, and the weighted Procrustes
//! solve (docs/design.md §5).
//!
//! Everything here accumulates in `f64`. Every solve returns a finite rigid transform with a
//! proper rotation (`det R = +1`), whatever the input: degenerate configurations get a defined
//! answer (see [`rotation_from_cross_covariance`]) instead of NaN.

use crate::transform::from_rotation_translation;
use nalgebra::{Matrix3, Matrix4, Unit, UnitQuaternion, Vector3};

/// An isotropic Gaussian mixture of J components.
#[derive(Clone, Debug, PartialEq)]
pub struct Gmm {
    /// Mixture weights `pi_j` (sum to 1).
    pub pi: Vec<f64>,
    /// Means `mu_j`.
    pub mu: Vec<[f64; 3]>,
    /// Isotropic variances `sigma_j^2` (DeepGMR convention, without the 1/3), clamped >= 1e-8.
    pub var: Vec<f64>,
}

impl Gmm {
    /// Number of components.
    pub fn len(&self) -> usize {
        self.pi.len()
    }

    /// True when the mixture has no components.
    pub fn is_empty(&self) -> bool {
        self.pi.is_empty()
    }
}

/// Added to `N * pi_j` before dividing by it (docs/design.md §5.1), so empty components give finite
/// means (zero) rather than NaN.
pub const GMM_EPS: f64 = 1e-8;
/// Lower clamp of the variances `sigma_j^2` (docs/design.md §5.1).
pub const MIN_VAR: f64 = 1e-8;

/// GMM parameters of `points` under memberships `gamma` (`[N, J]` row-major, rows sum to 1).
///
/// Exactly docs/design.md §5.1 (DeepGMR `gmm_params`), accumulated in `f64`:
/// `pi_j = (1/N) sum_i gamma_ij`, `mu_j = sum_i gamma_ij x_i / (N pi_j + eps)`,
/// `sigma_j^2 = max(sum_i gamma_ij |x_i - mu_j|^2 / (N pi_j + eps), 1e-8)` (two passes, no 1/3),
/// with `eps = 1e-8`.
///
/// Uses the first `min(points.len(), gamma.len() / j)` points. `j == 0` or no points gives
/// zero components (`j == 0`) or `j` empty components (`pi = 0`, `mu = 0`, `var = 1e-8`).
pub fn gmm_params(points: &[[f32; 3]], gamma: &[f32], j: usize) -> Gmm {
    if j == 0 {
        return Gmm { pi: Vec::new(), mu: Vec::new(), var: Vec::new() };
    }
    let n = points.len().min(gamma.len() / j);
    let rows = || points[..n].iter().zip(gamma.chunks_exact(j));
    let mut mass = vec![0.0f64; j];
    let mut sum = vec![[0.0f64; 3]; j];
    for (p, g) in rows() {
        let x = p.map(|v| v as f64);
        for (k, &w) in g.iter().enumerate() {
            let w = w as f64;
            mass[k] += w;
            for a in 0..3 {
                sum[k][a] += w * x[a];
            }
        }
    }
    let mu: Vec<[f64; 3]> = (0..j)
        .map(|k| {
            let d = mass[k] + GMM_EPS;
            sum[k].map(|s| s / d)
        })
        .collect();
    let mut sq = vec![0.0f64; j];
    for (p, g) in rows() {
        let x = p.map(|v| v as f64);
        for (k, &w) in g.iter().enumerate() {
            let m = &mu[k];
            let d2 = (x[0] - m[0]).powi(2) + (x[1] - m[1]).powi(2) + (x[2] - m[2]).powi(2);
            sq[k] += w as f64 * d2;
        }
    }
    let var = (0..j).map(|k| (sq[k] / (mass[k] + GMM_EPS)).max(MIN_VAR)).collect();
    let inv_n = if n > 0 { 1.0 / n as f64 } else { 0.0 };
    let pi = mass.iter().map(|m| m * inv_n).collect();
    Gmm { pi, mu, var }
}

/// `T_target_source` from the source and target GMMs (DeepGMR weighted Procrustes with the
/// reflection fix). Always a proper rotation; degenerate input gives a defined result.
///
/// docs/design.md §5.2, with the source weights `pi^_j` (normalised to sum to 1, a no-op for
/// memberships whose rows sum to 1) and the target variances `sigma_j^2`:
/// `c^ = sum pi^_j mu^_j`, `c = sum pi^_j mu_j`,
/// `M = sum (pi^_j / sigma_j^2) (mu^_j - c^)(mu_j - c)^T`, `M = U S V^T`,
/// `R = V diag(1, 1, det(V U^T)) U^T`, `t = c - R c^`.
///
/// Components whose weight, mean or variance is not finite, or whose source weight is not
/// positive, are skipped; if the mixtures differ in length the extra components are ignored.
/// No usable component gives the identity. A rank-deficient `M` gives the rotation described at
/// [`rotation_from_cross_covariance`] (identity when all mass sits in one component, so then
/// `T` is the pure translation between the two means).
pub fn solve(source: &Gmm, target: &Gmm) -> Matrix4<f64> {
    let j = source.pi.len().min(source.mu.len()).min(target.mu.len()).min(target.var.len());
    let usable = |k: usize| {
        let p = source.pi[k];
        p.is_finite()
            && p > 0.0
            && source.mu[k].iter().chain(target.mu[k].iter()).all(|v| v.is_finite())
            && !target.var[k].is_nan()
    };
    let mut total = 0.0f64;
    let mut cs = Vector3::zeros();
    let mut ct = Vector3::zeros();
    for k in (0..j).filter(|&k| usable(k)) {
        let p = source.pi[k];
        total += p;
        cs += Vector3::from(source.mu[k]) * p;
        ct += Vector3::from(target.mu[k]) * p;
    }
    if !(total > 0.0 && total.is_finite()) {
        return Matrix4::identity();
    }
    cs /= total;
    ct /= total;
    let mut m = Matrix3::zeros();
    for k in (0..j).filter(|&k| usable(k)) {
        let w = (source.pi[k] / total) / target.var[k].max(MIN_VAR);
        let a = Vector3::from(source.mu[k]) - cs;
        let b = Vector3::from(target.mu[k]) - ct;
        m += (a * b.transpose()) * w;
    }
    rigid_from_parts(&m, &cs, &ct)
}

/// Closed-form point-to-point rigid fit (weighted Kabsch / Umeyama without scale):
/// the `T_target_source` minimising `sum_i w_i |R s_i + t - t_i|^2`, with the same reflection fix
/// and degenerate handling as [`solve`].
///
/// `weights = None` weighs every pair equally. Pairs with a non-finite coordinate, or a weight
/// that is not finite and positive, are skipped; if the slices differ in length the extra
/// points are ignored. No usable pair gives the identity; a single pair (or all pairs at one
/// point) a pure translation.
pub fn kabsch(source: &[[f64; 3]], target: &[[f64; 3]], weights: Option<&[f64]>) -> Matrix4<f64> {
    let mut n = source.len().min(target.len());
    if let Some(w) = weights {
        n = n.min(w.len());
    }
    let weight = |i: usize| -> f64 {
        let w = weights.map_or(1.0, |w| w[i]);
        let ok = w.is_finite() && w > 0.0 && source[i].iter().chain(target[i].iter()).all(|v| v.is_finite());
        if ok {
            w
        } else {
            0.0
        }
    };
    let mut total = 0.0f64;
    let mut cs = Vector3::zeros();
    let mut ct = Vector3::zeros();
    for i in 0..n {
        let w = weight(i);
        if w > 0.0 {
            total += w;
            cs += Vector3::from(source[i]) * w;
            ct += Vector3::from(target[i]) * w;
        }
    }
    if !(total > 0.0 && total.is_finite()) {
        return Matrix4::identity();
    }
    cs /= total;
    ct /= total;
    let mut m = Matrix3::zeros();
    for i in 0..n {
        let w = weight(i);
        if w > 0.0 {
            let a = Vector3::from(source[i]) - cs;
            let b = Vector3::from(target[i]) - ct;
            m += (a * b.transpose()) * (w / total);
        }
    }
    rigid_from_parts(&m, &cs, &ct)
}

/// `[[R, ct - R cs], [0, 1]]` with `R` from the cross-covariance `m`; identity if anything is
/// not finite.
fn rigid_from_parts(m: &Matrix3<f64>, cs: &Vector3<f64>, ct: &Vector3<f64>) -> Matrix4<f64> {
    let r = rotation_from_cross_covariance(m);
    let t = ct - r * cs;
    if t.iter().all(|v| v.is_finite()) {
        from_rotation_translation(&r, &t)
    } else {
        Matrix4::identity()
    }
}

/// Singular-value ratio `s_2 / s_1` below which the cross-covariance counts as rank one.
pub const RANK_ONE_TOL: f64 = 1e-7;

/// The proper rotation `R` minimising `sum w |R a_i - b_i|^2` (equivalently maximising
/// `tr(R M)`) for the cross-covariance `M = sum w a_i b_i^T` (source on the left): with `M = U S V^T`
/// (singular values descending), `R = V diag(1, 1, det(V U^T)) U^T`.
///
/// Defined answers where the optimum is not unique:
/// * `M` zero or not finite (no spread, e.g. all mass in one component): the identity.
/// * `M` of rank one (`s_2 <= 1e-7 s_1`: the points/means are collinear): the smallest rotation
///   taking the source direction `u_1` onto the target direction `v_1` (a half-turn about an
///   axis perpendicular to `u_1` when they are opposite). Any rotation about the line would be
///   as good; this one moves least.
/// * Rank two (coplanar): the SVD answer is unique once the reflection is fixed, and is used.
pub fn rotation_from_cross_covariance(m: &Matrix3<f64>) -> Matrix3<f64> {
    if !m.iter().all(|v| v.is_finite()) {
        return Matrix3::identity();
    }
    let scale = m.abs().max();
    if scale.is_nan() || scale <= 0.0 {
        return Matrix3::identity();
    }
    // Scale to unit size first: the SVD is scale-invariant, and this keeps tiny or huge
    // entries (weights pi / sigma^2 up to 1e8) away from under/overflow.
    let ms = m / scale;
    let Some(svd) = ms.try_svd(true, true, f64::EPSILON, 500) else {
        return Matrix3::identity();
    };
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Matrix3::identity();
    };
    let s = svd.singular_values;
    if s[0].is_nan() || s[0] <= 0.0 {
        return Matrix3::identity();
    }
    let v = v_t.transpose();
    if s[1] <= RANK_ONE_TOL * s[0] {
        return smallest_rotation_between(&u.column(0).into_owned(), &v.column(0).into_owned());
    }
    let d = (v * u.transpose()).determinant().signum();
    let mut dm = Matrix3::identity();
    dm[(2, 2)] = if d < 0.0 { -1.0 } else { 1.0 };
    let r = v * dm * u.transpose();
    if r.iter().all(|x| x.is_finite()) {
        r
    } else {
        Matrix3::identity()
    }
}

/// The smallest rotation taking direction `a` onto direction `b` (half-turn about a
/// perpendicular axis when they are opposite; identity for zero vectors).
fn smallest_rotation_between(a: &Vector3<f64>, b: &Vector3<f64>) -> Matrix3<f64> {
    let (Some(a), Some(b)) = (Unit::try_new(*a, 1e-300), Unit::try_new(*b, 1e-300)) else {
        return Matrix3::identity();
    };
    let axis = a.cross(&b);
    let cos = a.dot(&b).clamp(-1.0, 1.0);
    let sin = axis.norm();
    let q = if sin > 1e-12 {
        UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), sin.atan2(cos))
    } else if cos > 0.0 {
        UnitQuaternion::identity()
    } else {
        // Opposite: half-turn about any axis perpendicular to a (the one built from the
        // coordinate axis least aligned with a, so it is well conditioned).
        let e = if a.x.abs() <= a.y.abs() && a.x.abs() <= a.z.abs() {
            Vector3::x()
        } else if a.y.abs() <= a.z.abs() {
            Vector3::y()
        } else {
            Vector3::z()
        };
        UnitQuaternion::from_axis_angle(&Unit::new_normalize(a.cross(&e)), std::f64::consts::PI)
    };
    q.to_rotation_matrix().into_inner()
}

/// The rotation closest to `r` (polar factor, reflection fixed): re-orthonormalises a rotation
/// block that has drifted after many compositions. Non-finite input gives the identity.
pub fn nearest_rotation(r: &Matrix3<f64>) -> Matrix3<f64> {
    // The rotation Q closest to R maximises tr(Q R^T); with M = R^T = U S V^T the solver
    // returns V D U^T, the polar factor of R.
    rotation_from_cross_covariance(&r.transpose())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::{check_rigid, euler_xyz, rotation, translation};

    #[test]
    fn gmm_params_of_hard_assignments() {
        let pts = [[0.0f32, 0.0, 0.0], [2.0, 0.0, 0.0], [10.0, 10.0, 10.0], [10.0, 10.0, 12.0]];
        let gamma = [1.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0];
        let g = gmm_params(&pts, &gamma, 2);
        assert!((g.pi[0] - 0.5).abs() < 1e-12 && (g.pi[1] - 0.5).abs() < 1e-12);
        assert!((g.mu[0][0] - 1.0).abs() < 1e-7 && (g.mu[1][2] - 11.0).abs() < 1e-7);
        // DeepGMR variance: mean squared distance to the mean, no 1/3.
        assert!((g.var[0] - 1.0).abs() < 1e-7 && (g.var[1] - 1.0).abs() < 1e-7);
    }

    #[test]
    fn empty_component_is_finite() {
        let pts = [[1.0f32, 2.0, 3.0]; 4];
        let gamma = [1.0f32, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0];
        let g = gmm_params(&pts, &gamma, 2);
        assert_eq!(g.pi[1], 0.0);
        assert_eq!(g.mu[1], [0.0; 3]);
        assert_eq!(g.var[1], MIN_VAR);
        assert_eq!(g.var[0], MIN_VAR);
        assert!(g.mu.iter().flatten().all(|v| v.is_finite()));
        assert!(gmm_params(&[], &[], 3).mu.iter().flatten().all(|v| *v == 0.0));
        assert!(gmm_params(&pts, &gamma, 0).is_empty());
    }

    #[test]
    fn kabsch_recovers_transform() {
        let src: Vec<[f64; 3]> = (0..50)
            .map(|i| {
                let f = i as f64;
                [(f * 0.7).sin(), (f * 1.3).cos(), (f * 0.3).sin() * 0.5]
            })
            .collect();
        let t = from_rotation_translation(&euler_xyz(2.5, -0.4, 1.0), &Vector3::new(0.3, -1.0, 2.0));
        let dst: Vec<[f64; 3]> = src
            .iter()
            .map(|p| {
                let q = rotation(&t) * Vector3::from(*p) + translation(&t);
                [q.x, q.y, q.z]
            })
            .collect();
        let est = kabsch(&src, &dst, None);
        assert!((est - t).abs().max() < 1e-10);
        let w: Vec<f64> = (0..50).map(|i| 1.0 + i as f64).collect();
        assert!((kabsch(&src, &dst, Some(&w)) - t).abs().max() < 1e-10);
        assert_eq!(kabsch(&[], &[], None), Matrix4::identity());
        let one = kabsch(&src[..1], &dst[..1], None);
        assert!(check_rigid(&one, 1e-12).is_ok());
        assert!((rotation(&one) - Matrix3::identity()).abs().max() < 1e-15);
    }

    #[test]
    fn nearest_rotation_repairs_drift() {
        let r = euler_xyz(0.3, 0.2, 0.1);
        let drifted = r * 1.001 + Matrix3::from_element(1e-4);
        let fixed = nearest_rotation(&drifted);
        assert!((fixed.transpose() * fixed - Matrix3::identity()).abs().max() < 1e-12);
        assert!((fixed.determinant() - 1.0).abs() < 1e-12);
        assert!((fixed - r).abs().max() < 1e-3);
        assert!((nearest_rotation(&r) - r).abs().max() < 1e-12);
    }
}
