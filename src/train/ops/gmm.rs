//! GMM parameters from memberships (docs/design.md §5.1, the engine's [`crate::gmr::gmm_params`]):
//! `pi_j = (1/N) sum_i g_ij`, `mu_j = sum_i g_ij x_i / (N pi_j + eps)`,
//! `var_j = max(sum_i g_ij |x_i - mu_j|^2 / (N pi_j + eps), 1e-8)`, accumulated in `f64`.
//! The points are constants (raw input coordinates); the gradient goes to the memberships.
//!
//! [`Gmm64`] is the `f64` math (used by the fused [`super::gmr()`] op); [`gmm_params`] is a tape
//! op exposing the parameters as an `f32` node.

use crate::train::tape::{Backward, Id, Op, Tape};

/// Added to `N pi_j` before dividing (docs/design.md §5.1).
pub const GMM_EPS: f64 = 1e-8;
/// Lower clamp of the variances.
pub const MIN_VAR: f64 = 1e-8;

/// GMM parameters in `f64`, with what the backward pass needs.
#[derive(Clone, Debug)]
pub struct Gmm64 {
    /// Mixture weights.
    pub pi: Vec<f64>,
    /// Means.
    pub mu: Vec<[f64; 3]>,
    /// Variances (clamped at [`MIN_VAR`]).
    pub var: Vec<f64>,
    points: Vec<[f64; 3]>,
    j: usize,
    /// `N pi_j + eps`.
    mass: Vec<f64>,
    /// Unclamped variances.
    raw_var: Vec<f64>,
    /// `sum_i g_ij (x_i - mu_j)` (= eps mu_j up to rounding).
    e: Vec<[f64; 3]>,
}

impl Gmm64 {
    /// Parameters of `points` under memberships `gamma` (`[N, j]` row-major).
    pub fn new(points: &[[f32; 3]], gamma: &[f32], j: usize) -> Self {
        let n = points.len();
        assert_eq!(gamma.len(), n * j, "gmm: memberships vs points");
        let pts: Vec<[f64; 3]> = points.iter().map(|p| p.map(|v| v as f64)).collect();
        let mut mass = vec![0.0f64; j];
        let mut sum = vec![[0.0f64; 3]; j];
        for (x, gr) in pts.iter().zip(gamma.chunks_exact(j)) {
            for (k, &w) in gr.iter().enumerate() {
                let w = w as f64;
                mass[k] += w;
                for a in 0..3 {
                    sum[k][a] += w * x[a];
                }
            }
        }
        let pi: Vec<f64> = mass.iter().map(|m| if n > 0 { m / n as f64 } else { 0.0 }).collect();
        for m in mass.iter_mut() {
            *m += GMM_EPS;
        }
        let mu: Vec<[f64; 3]> = (0..j).map(|k| sum[k].map(|s| s / mass[k])).collect();
        let mut sq = vec![0.0f64; j];
        let mut e = vec![[0.0f64; 3]; j];
        for (x, gr) in pts.iter().zip(gamma.chunks_exact(j)) {
            for (k, &w) in gr.iter().enumerate() {
                let w = w as f64;
                let d = [x[0] - mu[k][0], x[1] - mu[k][1], x[2] - mu[k][2]];
                sq[k] += w * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for a in 0..3 {
                    e[k][a] += w * d[a];
                }
            }
        }
        let raw_var: Vec<f64> = (0..j).map(|k| sq[k] / mass[k]).collect();
        Self { pi, mu, var: raw_var.iter().map(|v| v.max(MIN_VAR)).collect(), points: pts, j, mass, raw_var, e }
    }

    /// Adds the membership gradient for parameter gradients `g_pi`, `g_mu`, `g_var` (any may be
    /// empty = zero) into `dgamma` (`[N, j]`).
    pub fn backward(&self, g_pi: &[f64], g_mu: &[[f64; 3]], g_var: &[f64], dgamma: &mut [f32]) {
        let j = self.j;
        let n = self.points.len();
        let gp = |k: usize| g_pi.get(k).copied().unwrap_or(0.0);
        // Effective gradient on mu, including the variance's dependence on mu through e_j.
        let mut gmu = vec![[0.0f64; 3]; j];
        let mut gvar = vec![0.0f64; j];
        for k in 0..j {
            let d = self.mass[k];
            gvar[k] = if self.raw_var[k] > MIN_VAR { g_var.get(k).copied().unwrap_or(0.0) } else { 0.0 };
            let gm = g_mu.get(k).copied().unwrap_or([0.0; 3]);
            for a in 0..3 {
                gmu[k][a] = gm[a] - 2.0 * gvar[k] * self.e[k][a] / d;
            }
        }
        for (x, dr) in self.points.iter().zip(dgamma.chunks_exact_mut(j)) {
            for k in 0..j {
                let d = self.mass[k];
                let m = &self.mu[k];
                let diff = [x[0] - m[0], x[1] - m[1], x[2] - m[2]];
                let mut v = gp(k) / n as f64;
                v += (gmu[k][0] * diff[0] + gmu[k][1] * diff[1] + gmu[k][2] * diff[2]) / d;
                let d2 = diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2];
                v += gvar[k] * (d2 - self.raw_var[k]) / d;
                dr[k] += v as f32;
            }
        }
    }
}

struct GmmOp {
    gamma: Id,
    gmm: Gmm64,
}

/// `gamma [N, J]` memberships of `points` -> `[J, 5]` rows `(pi, mu_x, mu_y, mu_z, var)`.
pub fn gmm_params(t: &mut Tape, gamma: Id, points: &[[f32; 3]]) -> Id {
    let (n, j) = t.shape(gamma);
    assert_eq!(points.len(), n, "gmm_params: points vs membership rows");
    let gmm = Gmm64::new(points, t.value(gamma), j);
    let mut y = t.uninit(j * 5);
    for k in 0..j {
        y[k * 5] = gmm.pi[k] as f32;
        for a in 0..3 {
            y[k * 5 + 1 + a] = gmm.mu[k][a] as f32;
        }
        y[k * 5 + 4] = gmm.var[k] as f32;
    }
    let needs = t.needs_grad(gamma);
    t.push(y, j, 5, Box::new(GmmOp { gamma, gmm }), needs)
}

impl Op for GmmOp {
    fn name(&self) -> &'static str {
        "gmm_params"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let j = self.gmm.j;
        let gpi: Vec<f64> = (0..j).map(|k| g[k * 5] as f64).collect();
        let gmu: Vec<[f64; 3]> = (0..j).map(|k| [1, 2, 3].map(|a| g[k * 5 + a] as f64)).collect();
        let gvar: Vec<f64> = (0..j).map(|k| g[k * 5 + 4] as f64).collect();
        self.gmm.backward(&gpi, &gmu, &gvar, ctx.grad(self.gamma));
    }
}
