//! The DeepGMR weighted Procrustes solve (docs/design.md §5.2, the engine's [`crate::gmr::solve`])
//! and its derivative, in `f64`.
//!
//! Forward: `p_j = pi^_j / sum pi^`, `c^ = sum p_j mu^_j`, `c = sum p_j mu_j`,
//! `M = sum (p_j / var_j) (mu^_j - c^)(mu_j - c)^T = U S V^T`, `R = V D U^T` with
//! `D = diag(1, 1, det(V U^T))`, `t = c - R c^`.
//!
//! Backward through the rotation: `R` is the special polar factor of `A = M^T = R P`,
//! `P = U S' U^T` with `S' = diag(s1, s2, det * s3)`. Differentiating `A = R P` and taking the
//! skew part gives `R^T dR` in the `U` basis as `X_ij / (s'_i + s'_j)`, so the vector-Jacobian
//! product is `dL/dA = R U K U^T` with `K_ij = (H_ij - H_ji) / (s'_i + s'_j)`,
//! `H = U^T R^T (dL/dR) U`. The denominators are sums of singular values (only `s2 - s3`
//! can get small, and only when the reflection fix is active), far better conditioned than the
//! `1/(s_i^2 - s_j^2)` of a generic SVD backward; they are guarded by a tiny relative epsilon.
//! Rank-deficient `M` (where the engine falls back to a fixed rule) gets no rotation gradient.

use crate::train::tape::{Backward, Id, Op, Tape};
use nalgebra::{Matrix3, Vector3};

/// Lower clamp of the variances (as in the engine).
pub const MIN_VAR: f64 = 1e-8;
/// Singular-value ratio below which `M` counts as rank one (as in the engine).
pub const RANK_ONE_TOL: f64 = 1e-7;

/// Inputs of one solve: source weights and means, target means and variances.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveInput {
    /// Source mixture weights `pi^_j`.
    pub pi: Vec<f64>,
    /// Source means `mu^_j`.
    pub mu_s: Vec<[f64; 3]>,
    /// Target means `mu_j`.
    pub mu_t: Vec<[f64; 3]>,
    /// Target variances `var_j`.
    pub var_t: Vec<f64>,
}

/// Gradients with respect to a [`SolveInput`].
#[derive(Clone, Debug, PartialEq)]
pub struct SolveGrad {
    /// d/d pi^.
    pub pi: Vec<f64>,
    /// d/d mu^.
    pub mu_s: Vec<[f64; 3]>,
    /// d/d mu.
    pub mu_t: Vec<[f64; 3]>,
    /// d/d var.
    pub var_t: Vec<f64>,
}

/// A solved transform with what the backward pass needs.
#[derive(Clone, Debug)]
pub struct Solve {
    /// Rotation.
    pub r: Matrix3<f64>,
    /// Translation.
    pub t: Vector3<f64>,
    usable: Vec<bool>,
    total: f64,
    p: Vec<f64>,
    cs: Vector3<f64>,
    ct: Vector3<f64>,
    /// `M`'s left singular vectors and the signed singular values `S'` (None: no rotation gradient).
    polar: Option<(Matrix3<f64>, [f64; 3])>,
}

impl Solve {
    /// Solves (the engine's rules for unusable components and degenerate `M`).
    pub fn new(x: &SolveInput) -> Self {
        let j = x.pi.len();
        let usable: Vec<bool> = (0..j)
            .map(|k| {
                let p = x.pi[k];
                p.is_finite()
                    && p > 0.0
                    && x.mu_s[k].iter().chain(x.mu_t[k].iter()).all(|v| v.is_finite())
                    && !x.var_t[k].is_nan()
            })
            .collect();
        let total: f64 = (0..j).filter(|&k| usable[k]).map(|k| x.pi[k]).sum();
        let mut out = Self {
            r: Matrix3::identity(),
            t: Vector3::zeros(),
            usable,
            total,
            p: vec![0.0; j],
            cs: Vector3::zeros(),
            ct: Vector3::zeros(),
            polar: None,
        };
        if !(total > 0.0 && total.is_finite()) {
            return out;
        }
        for k in (0..j).filter(|&k| out.usable[k]) {
            out.p[k] = x.pi[k] / total;
            out.cs += Vector3::from(x.mu_s[k]) * out.p[k];
            out.ct += Vector3::from(x.mu_t[k]) * out.p[k];
        }
        let mut m = Matrix3::zeros();
        for k in (0..j).filter(|&k| out.usable[k]) {
            let w = out.p[k] / x.var_t[k].max(MIN_VAR);
            let a = Vector3::from(x.mu_s[k]) - out.cs;
            let b = Vector3::from(x.mu_t[k]) - out.ct;
            m += (a * b.transpose()) * w;
        }
        out.rotation(&m);
        out.t = out.ct - out.r * out.cs;
        if !out.t.iter().all(|v| v.is_finite()) {
            out.r = Matrix3::identity();
            out.t = Vector3::zeros();
            out.polar = None;
        }
        out
    }

    #[allow(clippy::neg_cmp_op_on_partial_ord)] // written to send NaN to the early returns
    fn rotation(&mut self, m: &Matrix3<f64>) {
        if !m.iter().all(|v| v.is_finite()) {
            return;
        }
        let scale = m.abs().max();
        if !(scale > 0.0) {
            return;
        }
        let ms = m / scale;
        let Some(svd) = ms.try_svd(true, true, f64::EPSILON, 500) else {
            return;
        };
        let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
            return;
        };
        let s = svd.singular_values;
        if !(s[0] > 0.0) {
            return;
        }
        let v = v_t.transpose();
        if s[1] <= RANK_ONE_TOL * s[0] {
            // The engine's rank-one rule: the smallest rotation taking u1 onto v1.
            self.r = crate::gmr::rotation_from_cross_covariance(m);
            return;
        }
        let det = if (v * u.transpose()).determinant() < 0.0 { -1.0 } else { 1.0 };
        let mut dm = Matrix3::identity();
        dm[(2, 2)] = det;
        let r = v * dm * u.transpose();
        if r.iter().all(|x| x.is_finite()) {
            self.r = r;
            self.polar = Some((u, [s[0] * scale, s[1] * scale, det * s[2] * scale]));
        }
    }

    /// The vector-Jacobian product: gradients of the inputs given `dL/dR` and `dL/dt`.
    pub fn backward(&self, x: &SolveInput, g_r: &Matrix3<f64>, g_t: &Vector3<f64>) -> SolveGrad {
        let j = x.pi.len();
        let mut out =
            SolveGrad { pi: vec![0.0; j], mu_s: vec![[0.0; 3]; j], mu_t: vec![[0.0; 3]; j], var_t: vec![0.0; j] };
        if !(self.total > 0.0 && self.total.is_finite()) {
            return out;
        }
        // t = ct - R cs
        let mut g_ct = *g_t;
        let mut g_cs = -(self.r.transpose() * g_t);
        let g_r = g_r - g_t * self.cs.transpose();
        // R -> M
        let g_m = match &self.polar {
            Some((u, sp)) => {
                let h = u.transpose() * self.r.transpose() * g_r * u;
                let eps = 1e-12 * sp[0].abs();
                let mut k = Matrix3::zeros();
                for a in 0..3 {
                    for b in 0..3 {
                        if a != b {
                            let den = sp[a] + sp[b];
                            let den = if den.abs() < eps { eps.copysign(den) } else { den };
                            k[(a, b)] = (h[(a, b)] - h[(b, a)]) / den;
                        }
                    }
                }
                (self.r * u * k * u.transpose()).transpose()
            }
            None => Matrix3::zeros(),
        };
        // M = sum w_j a_j b_j^T
        let mut g_p = vec![0.0f64; j];
        for k in (0..j).filter(|&k| self.usable[k]) {
            let v = x.var_t[k].max(MIN_VAR);
            let w = self.p[k] / v;
            let a = Vector3::from(x.mu_s[k]) - self.cs;
            let b = Vector3::from(x.mu_t[k]) - self.ct;
            let gw = a.dot(&(g_m * b));
            let ga = g_m * b * w;
            let gb = g_m.transpose() * a * w;
            for i in 0..3 {
                out.mu_s[k][i] += ga[i];
                out.mu_t[k][i] += gb[i];
            }
            g_cs -= ga;
            g_ct -= gb;
            g_p[k] += gw / v;
            if x.var_t[k] > MIN_VAR {
                out.var_t[k] -= gw * self.p[k] / (v * v);
            }
        }
        // cs = sum p mu_s, ct = sum p mu_t
        for k in (0..j).filter(|&k| self.usable[k]) {
            g_p[k] += Vector3::from(x.mu_s[k]).dot(&g_cs) + Vector3::from(x.mu_t[k]).dot(&g_ct);
            for i in 0..3 {
                out.mu_s[k][i] += self.p[k] * g_cs[i];
                out.mu_t[k][i] += self.p[k] * g_ct[i];
            }
        }
        // p = pi / total
        let dot: f64 = (0..j).filter(|&k| self.usable[k]).map(|k| g_p[k] * self.p[k]).sum();
        for k in (0..j).filter(|&k| self.usable[k]) {
            out.pi[k] = (g_p[k] - dot) / self.total;
        }
        out
    }
}

struct ProcrustesOp {
    source: Id,
    target: Id,
    input: SolveInput,
    solve: Solve,
}

fn input_of(src: &[f32], tgt: &[f32]) -> SolveInput {
    let j = src.len() / 5;
    let row = |v: &[f32], k: usize| [v[k * 5 + 1] as f64, v[k * 5 + 2] as f64, v[k * 5 + 3] as f64];
    SolveInput {
        pi: (0..j).map(|k| src[k * 5] as f64).collect(),
        mu_s: (0..j).map(|k| row(src, k)).collect(),
        mu_t: (0..j).map(|k| row(tgt, k)).collect(),
        var_t: (0..j).map(|k| tgt[k * 5 + 4] as f64).collect(),
    }
}

/// `T_target_source` (`[4, 4]`, row-major) from a source and a target GMM node (`[J, 5]` rows
/// `(pi, mu, var)` as made by [`super::gmm_params`]). Uses the source's `pi` and means, and the
/// target's means and variances.
pub fn procrustes(t: &mut Tape, source: Id, target: Id) -> Id {
    let (j, c) = t.shape(source);
    assert_eq!(c, 5, "procrustes: GMM nodes are [J, 5]");
    assert_eq!(t.shape(target), (j, 5), "procrustes: GMM sizes differ");
    let input = input_of(t.value(source), t.value(target));
    let solve = Solve::new(&input);
    let mut y = t.zeros(16);
    for r in 0..3 {
        for c in 0..3 {
            y[r * 4 + c] = solve.r[(r, c)] as f32;
        }
        y[r * 4 + 3] = solve.t[r] as f32;
    }
    y[15] = 1.0;
    let needs = t.any_needs(&[source, target]);
    t.push(y, 4, 4, Box::new(ProcrustesOp { source, target, input, solve }), needs)
}

impl Op for ProcrustesOp {
    fn name(&self) -> &'static str {
        "procrustes"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let g_r = Matrix3::from_fn(|r, c| g[r * 4 + c] as f64);
        let g_t = Vector3::new(g[3] as f64, g[7] as f64, g[11] as f64);
        let gr = self.solve.backward(&self.input, &g_r, &g_t);
        let j = gr.pi.len();
        if ctx.needs(self.source) {
            let ds = ctx.grad(self.source);
            for k in 0..j {
                ds[k * 5] += gr.pi[k] as f32;
                for a in 0..3 {
                    ds[k * 5 + 1 + a] += gr.mu_s[k][a] as f32;
                }
            }
        }
        if ctx.needs(self.target) {
            let dt = ctx.grad(self.target);
            for k in 0..j {
                for a in 0..3 {
                    dt[k * 5 + 1 + a] += gr.mu_t[k][a] as f32;
                }
                dt[k * 5 + 4] += gr.var_t[k] as f32;
            }
        }
    }
}
