//! Gaussian mixture registration: GMM parameters from memberships, and the weighted Procrustes
//! solve (method.md B §4).

use nalgebra::Matrix4;

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

/// GMM parameters of `points` under memberships `gamma` (`[N, J]` row-major, rows sum to 1).
pub fn gmm_params(points: &[[f32; 3]], gamma: &[f32], j: usize) -> Gmm {
    let _ = (points, gamma, j);
    todo!("helper: gmr")
}

/// `T_target_source` from the source and target GMMs (DeepGMR weighted Procrustes with the
/// reflection fix). Always a proper rotation; degenerate input gives a defined result.
pub fn solve(source: &Gmm, target: &Gmm) -> Matrix4<f64> {
    let _ = (source, target);
    todo!("helper: gmr")
}
