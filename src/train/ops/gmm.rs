//! GMM parameters from memberships (method.md B §4.1, the engine's [`crate::gmr::gmm_params`]):
//! `pi_j = (1/N) sum_i g_ij`, `mu_j = sum_i g_ij x_i / (N pi_j + eps)`,
//! `var_j = max(sum_i g_ij |x_i - mu_j|^2 / (N pi_j + eps), 1e-8)`, accumulated in `f64`.
//! The points are constants (raw input coordinates); the gradient goes to the memberships.

use crate::train::tape::{Backward, Id, Op, Tape};

/// Added to `N pi_j` before dividing (method.md §4.1).
pub const GMM_EPS: f64 = 1e-8;
/// Lower clamp of the variances.
pub const MIN_VAR: f64 = 1e-8;

struct GmmOp {
    gamma: Id,
    points: Vec<[f64; 3]>,
    j: usize,
    /// Per component: mass `D_j = sum_i g_ij + eps`, mean, variance (unclamped), `e_j = sum_i g_ij (x_i - mu_j)`.
    mass: Vec<f64>,
    mu: Vec<[f64; 3]>,
    var: Vec<f64>,
    e: Vec<[f64; 3]>,
}

/// `gamma [N, J]` memberships of `points` -> `[J, 5]` rows `(pi, mu_x, mu_y, mu_z, var)`.
pub fn gmm_params(t: &mut Tape, gamma: Id, points: &[[f32; 3]]) -> Id {
    let (n, j) = t.shape(gamma);
    assert_eq!(points.len(), n, "gmm_params: points vs membership rows");
    let g = t.value(gamma);
    let pts: Vec<[f64; 3]> = points.iter().map(|p| p.map(|v| v as f64)).collect();
    let mut mass = vec![0.0f64; j];
    let mut sum = vec![[0.0f64; 3]; j];
    for (x, gr) in pts.iter().zip(g.chunks_exact(j)) {
        for (k, &w) in gr.iter().enumerate() {
            let w = w as f64;
            mass[k] += w;
            for a in 0..3 {
                sum[k][a] += w * x[a];
            }
        }
    }
    let pi: Vec<f64> = mass.iter().map(|m| m / n as f64).collect();
    for m in mass.iter_mut() {
        *m += GMM_EPS;
    }
    let mu: Vec<[f64; 3]> = (0..j).map(|k| sum[k].map(|s| s / mass[k])).collect();
    let mut sq = vec![0.0f64; j];
    let mut e = vec![[0.0f64; 3]; j];
    for (x, gr) in pts.iter().zip(g.chunks_exact(j)) {
        for (k, &w) in gr.iter().enumerate() {
            let w = w as f64;
            let d = [x[0] - mu[k][0], x[1] - mu[k][1], x[2] - mu[k][2]];
            sq[k] += w * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for a in 0..3 {
                e[k][a] += w * d[a];
            }
        }
    }
    let var: Vec<f64> = (0..j).map(|k| sq[k] / mass[k]).collect();
    let mut y = t.uninit(j * 5);
    for k in 0..j {
        y[k * 5] = pi[k] as f32;
        for a in 0..3 {
            y[k * 5 + 1 + a] = mu[k][a] as f32;
        }
        y[k * 5 + 4] = var[k].max(MIN_VAR) as f32;
    }
    let needs = t.needs_grad(gamma);
    t.push(
        y,
        j,
        5,
        Box::new(GmmOp {
            gamma,
            points: pts,
            j,
            mass,
            mu,
            var,
            e,
        }),
        needs,
    )
}

impl Op for GmmOp {
    fn name(&self) -> &'static str {
        "gmm_params"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let j = self.j;
        let n = self.points.len();
        // Effective gradient on mu (including the variance's dependence on mu through e_j,
        // which is eps * mu_j: tiny but exact).
        let mut gmu = vec![[0.0f64; 3]; j];
        let mut gvar = vec![0.0f64; j];
        for k in 0..j {
            let d = self.mass[k];
            gvar[k] = if self.var[k] > MIN_VAR { g[k * 5 + 4] as f64 } else { 0.0 };
            for a in 0..3 {
                gmu[k][a] = g[k * 5 + 1 + a] as f64 - 2.0 * gvar[k] * self.e[k][a] / d;
            }
        }
        let dg = ctx.grad(self.gamma);
        for (x, dr) in self.points.iter().zip(dg.chunks_exact_mut(j)) {
            for k in 0..j {
                let d = self.mass[k];
                let m = &self.mu[k];
                let diff = [x[0] - m[0], x[1] - m[1], x[2] - m[2]];
                let mut v = g[k * 5] as f64 / n as f64;
                v += (gmu[k][0] * diff[0] + gmu[k][1] * diff[1] + gmu[k][2] * diff[2]) / d;
                let d2 = diff[0] * diff[0] + diff[1] * diff[1] + diff[2] * diff[2];
                v += gvar[k] * (d2 - self.var[k]) / d;
                dr[k] += v as f32;
            }
        }
    }
}
