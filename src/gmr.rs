//! Gaussian mixture registration: GMM parameters from memberships, and the weighted Procrustes
//! solve (docs/design.md §5).
//!
//! Everything here accumulates in `f64`. Every solve returns a finite rigid transform with a
//! proper rotation (`det R = +1`), whatever the input: degenerate configurations get a defined
//! answer (see [`rotation_from_cross_covariance`]) instead of NaN. The rigid fits shared with ICP
//! live in [`crate::rigid`] and are re-exported here.

use crate::rigid::rigid_from_parts;
pub use crate::rigid::{kabsch, nearest_rotation, rotation_from_cross_covariance, RANK_ONE_TOL};
use nalgebra::{Matrix3, Matrix4, Vector3};

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
