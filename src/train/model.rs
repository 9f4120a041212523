//! The DGMR-ARPS forward pass on the tape: exactly the engine's [`crate::Model::forward`]
//! (pre-centring, `f0 = 0`, tokens `[f ; pos(x)]`, post-norm self then cross attention, `out`
//! projection, reference weights, step MLP, shifting, membership head), followed by the GMM
//! parameters on the raw input coordinates and the two weighted Procrustes solves
//! (the engine's [`crate::gmr`]).

use super::ops;
use super::tape::{Id, Tape};
use crate::model::{ForwardOutput, ModelConfig, Reference};
use crate::{Error, Result};
use nalgebra::Matrix4;
use std::collections::BTreeMap;

/// Trainable parameters by tensor name ([`ModelConfig::tensor_specs`] names and sizes,
/// row-major `f32`): the same map as [`crate::Weights::tensors`].
pub type Params = BTreeMap<String, Vec<f32>>;

/// Checks that `params` holds exactly the tensors of `config` with the right sizes.
pub fn check_params(config: &ModelConfig, params: &Params) -> Result<()> {
    let specs = config.tensor_specs();
    for (name, shape) in &specs {
        let len: usize = shape.iter().product();
        match params.get(name) {
            None => return Err(Error::Weights(format!("parameter '{name}' is missing"))),
            Some(v) if v.len() != len => {
                return Err(Error::Weights(format!("parameter '{name}' has {} values, expected {len}", v.len())))
            }
            _ => {}
        }
    }
    if params.len() != specs.len() {
        let extra = params.keys().find(|k| !specs.iter().any(|(n, _)| n == *k)).cloned().unwrap_or_default();
        return Err(Error::Weights(format!("parameter '{extra}' is not part of the config")));
    }
    Ok(())
}

/// Nodes of one forward pass.
#[derive(Clone, Debug)]
pub struct Forward {
    /// Parameter leaves by name.
    pub params: BTreeMap<String, Id>,
    /// Source memberships `[N_s, J]`.
    pub gamma_source: Id,
    /// Target memberships `[N_t, J]`.
    pub gamma_target: Id,
    /// Step logits `alpha^l` (`[1, 1]` each).
    pub alphas: Vec<Id>,
    /// Step sizes `s^l = sigmoid(alpha^l)` (`[1, 1]` each).
    pub steps: Vec<Id>,
    /// Source shifts `d^l = s^l mu_x^l` (`[1, 3]` each, pre-centred source frame).
    pub shifts_source: Vec<Id>,
    /// Target shifts (`[1, 3]` each).
    pub shifts_target: Vec<Id>,
    /// `T_12` (source -> target), `[4, 4]` row-major.
    pub t12: Id,
    /// `T_21` (target -> source), `[4, 4]` row-major.
    pub t21: Id,
}

impl Forward {
    /// The network outputs in the engine's format.
    pub fn output(&self, t: &Tape) -> ForwardOutput {
        let v3 = |id: &Id| {
            let v = t.value(*id);
            [v[0], v[1], v[2]]
        };
        ForwardOutput {
            gamma_source: t.value(self.gamma_source).to_vec(),
            gamma_target: t.value(self.gamma_target).to_vec(),
            steps: self.steps.iter().map(|s| t.scalar(*s)).collect(),
            shifts_source: self.shifts_source.iter().map(v3).collect(),
            shifts_target: self.shifts_target.iter().map(v3).collect(),
        }
    }

    /// `T_12` as a matrix.
    pub fn t12(&self, t: &Tape) -> Matrix4<f64> {
        to_matrix(t.value(self.t12))
    }

    /// `T_21` as a matrix.
    pub fn t21(&self, t: &Tape) -> Matrix4<f64> {
        to_matrix(t.value(self.t21))
    }
}

/// A row-major 16-vector as a matrix.
pub fn to_matrix(v: &[f32]) -> Matrix4<f64> {
    Matrix4::from_fn(|r, c| v[r * 4 + c] as f64)
}

/// A matrix as a row-major 16-vector.
pub fn from_matrix(m: &Matrix4<f64>) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    for r in 0..4 {
        for c in 0..4 {
            out[r * 4 + c] = m[(r, c)] as f32;
        }
    }
    out
}

struct Net<'a> {
    cfg: &'a ModelConfig,
    ids: &'a BTreeMap<String, Id>,
}

impl Net<'_> {
    fn p(&self, name: &str) -> Id {
        *self.ids.get(name).unwrap_or_else(|| panic!("parameter {name} missing"))
    }

    fn linear(&self, t: &mut Tape, x: Id, name: &str) -> Id {
        ops::linear(t, x, self.p(&format!("{name}.weight")), Some(self.p(&format!("{name}.bias"))))
    }

    /// `layers` Linear layers `prefix.0 ..`, ReLU between them (and after the last if asked).
    fn mlp(&self, t: &mut Tape, mut x: Id, prefix: &str, layers: usize, relu_last: bool) -> Id {
        for i in 0..layers {
            x = self.linear(t, x, &format!("{prefix}.{i}"));
            if i + 1 < layers || relu_last {
                x = ops::relu(t, x);
            }
        }
        x
    }

    /// Post-norm block: `a = LN1(x + MHA(x, kv)); y = LN2(a + FFN(a))`.
    fn block(&self, t: &mut Tape, x: Id, kv: Id, name: &str) -> Id {
        let eps = self.cfg.layer_norm_eps;
        let q = self.linear(t, x, &format!("{name}.q"));
        let k = self.linear(t, kv, &format!("{name}.k"));
        let v = self.linear(t, kv, &format!("{name}.v"));
        let h = ops::attention(t, q, k, v, self.cfg.heads);
        let o = self.linear(t, h, &format!("{name}.o"));
        let r = ops::add(t, x, o);
        let a =
            ops::layer_norm(t, r, self.p(&format!("{name}.norm1.weight")), self.p(&format!("{name}.norm1.bias")), eps);
        let h1 = self.linear(t, a, &format!("{name}.ffn1"));
        let h1 = ops::relu(t, h1);
        let h2 = self.linear(t, h1, &format!("{name}.ffn2"));
        let r2 = ops::add(t, a, h2);
        ops::layer_norm(t, r2, self.p(&format!("{name}.norm2.weight")), self.p(&format!("{name}.norm2.bias")), eps)
    }

    /// Reference weights over the points, `[1, n]`.
    fn reference(&self, t: &mut Tape, f: Id, layer: &str) -> Id {
        let (n, c) = t.shape(f);
        match self.cfg.reference {
            Reference::Soft => {
                let s = self.linear(t, f, &format!("{layer}.score"));
                let s = ops::scale(t, s, 1.0 / self.cfg.soft_temperature);
                let s = ops::reshape(t, s, 1, n);
                ops::softmax_rows(t, s)
            }
            Reference::TopH => {
                let h = self.cfg.top_h.min(n);
                let norms: Vec<f32> = t.value(f).chunks_exact(c).map(|r| r.iter().map(|v| v * v).sum()).collect();
                let mut idx: Vec<usize> = (0..n).collect();
                idx.sort_by(|&a, &b| norms[b].total_cmp(&norms[a]).then(a.cmp(&b)));
                let mut w = vec![0.0f32; n];
                for &i in &idx[..h] {
                    w[i] = 1.0 / h as f32;
                }
                t.constant(&w, 1, n)
            }
        }
    }
}

/// Pre-centred positions (the engine's rule: `f64` mean rounded to `f32`, then subtracted).
fn centred(points: &[[f32; 3]]) -> Vec<f32> {
    let n = points.len();
    let mut mean = [0.0f64; 3];
    for p in points {
        for a in 0..3 {
            mean[a] += p[a] as f64;
        }
    }
    let mean = mean.map(|m| (m / n as f64) as f32);
    points.iter().flat_map(|p| [p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]]).collect()
}

/// Records the full forward pass of a pair on `t`: parameters become leaves (with gradients),
/// the clouds constants. Clouds are in normalised units (the trainer's pairs already are).
pub fn forward(
    t: &mut Tape,
    config: &ModelConfig,
    params: &Params,
    source: &[[f32; 3]],
    target: &[[f32; 3]],
) -> Forward {
    let mut ids = BTreeMap::new();
    for (name, shape) in config.tensor_specs() {
        let v = params.get(&name).unwrap_or_else(|| panic!("parameter {name} missing"));
        let (r, c) = if shape.len() == 2 { (shape[0], shape[1]) } else { (1, shape[0]) };
        ids.insert(name, t.param(v, r, c));
    }
    let net = Net { cfg: config, ids: &ids };
    let c = config.feature_dim;
    let (ns, nt) = (source.len(), target.len());
    let mut x = [t.constant(&centred(source), ns, 3), t.constant(&centred(target), nt, 3)];
    let zs = vec![0.0f32; ns.max(nt) * c];
    let mut f = [t.constant(&zs[..ns * c], ns, c), t.constant(&zs[..nt * c], nt, c)];
    let (mut alphas, mut steps, mut shifts_s, mut shifts_t) = (vec![], vec![], vec![], vec![]);
    for l in 0..config.layers {
        let p = format!("layers.{l}");
        let npos = config.pos_hidden.len() + 1;
        let mut g = [x[0]; 2];
        for s in 0..2 {
            let phi = net.mlp(t, x[s], &format!("{p}.pos"), npos, true);
            g[s] = ops::concat_cols(t, f[s], phi);
        }
        let g1 = [0, 1].map(|s| net.block(t, g[s], g[s], &format!("{p}.self_attn")));
        let g2 = [
            net.block(t, g1[0], g1[1], &format!("{p}.cross_attn")),
            net.block(t, g1[1], g1[0], &format!("{p}.cross_attn")),
        ];
        let mut mux = [x[0]; 2];
        let mut muf = [x[0]; 2];
        for s in 0..2 {
            f[s] = net.linear(t, g2[s], &format!("{p}.out"));
            let w = net.reference(t, f[s], &p);
            mux[s] = ops::weighted_sum(t, w, x[s]);
            muf[s] = ops::weighted_sum(t, w, f[s]);
        }
        let dx = ops::sub(t, mux[0], mux[1]);
        let df = ops::sub(t, muf[0], muf[1]);
        let step_in = ops::concat_cols(t, dx, df);
        let alpha = net.mlp(t, step_in, &format!("{p}.step"), 2, false);
        let s = ops::sigmoid(t, alpha);
        let mut d = [x[0]; 2];
        for k in 0..2 {
            d[k] = ops::mul_scalar(t, mux[k], s);
            x[k] = ops::sub_row(t, x[k], d[k]);
        }
        alphas.push(alpha);
        steps.push(s);
        shifts_s.push(d[0]);
        shifts_t.push(d[1]);
    }
    let nhead = config.head_hidden.len() + 1;
    let gamma = [0, 1].map(|s| {
        let h = ops::concat_colmax(t, f[s]);
        let logits = net.mlp(t, h, "head", nhead, false);
        ops::softmax_rows(t, logits)
    });
    let t12 = ops::gmr(t, gamma[0], gamma[1], source, target);
    let t21 = ops::gmr(t, gamma[1], gamma[0], target, source);
    Forward {
        params: ids,
        gamma_source: gamma[0],
        gamma_target: gamma[1],
        alphas,
        steps,
        shifts_source: shifts_s,
        shifts_target: shifts_t,
        t12,
        t21,
    }
}
