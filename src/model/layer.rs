//! One ARPS layer (docs/design.md §4.1-§4.3).

use super::config::{ModelConfig, Reference};
use crate::nn::{
    sigmoid, softmax_rows_inplace, workspace::take, AttentionBlock, LayerNorm, Linear, Mlp, MultiHeadAttention,
    QuantWeight, Workspace,
};
use crate::weights::Weights;

/// Weights of one ARPS layer (shared by source and target).
#[derive(Clone, Debug)]
pub struct ArpsLayer {
    /// Position MLP `3 -> ... -> C` (ReLU after every layer).
    pub pos: Mlp,
    /// Self-attention block on `2C`-wide tokens.
    pub self_attn: AttentionBlock,
    /// Cross-attention block (queries from one cloud, keys/values from the other).
    pub cross_attn: AttentionBlock,
    /// Projection `2C -> C` giving the layer's features `f^l`.
    pub out: Linear,
    /// Per-point score `C -> 1` of the soft reference point (absent for top-H).
    pub score: Option<Linear>,
    /// Step MLP `(3 + C) -> hidden -> 1`.
    pub step: Mlp,
}

/// Per-cloud state carried through the layers.
#[derive(Default, Debug, Clone)]
pub struct CloudState {
    /// Current (shifted) positions, `[n, 3]`.
    pub x: Vec<f32>,
    /// Features `f^l`, `[n, C]`.
    pub f: Vec<f32>,
    /// Tokens `[f ; phi]`, `[n, 2C]`.
    pub g: Vec<f32>,
    /// Self-attended tokens, `[n, 2C]`.
    pub g1: Vec<f32>,
    /// Cross-attended tokens, `[n, 2C]`.
    pub g2: Vec<f32>,
    /// Reference weights over points, `[n]`.
    pub w: Vec<f32>,
    /// Number of points.
    pub n: usize,
}

/// Buffers of the layer loop.
#[derive(Default, Debug, Clone)]
pub struct LayerWorkspace {
    /// Source state.
    pub source: CloudState,
    /// Target state.
    pub target: CloudState,
    attn: Workspace,
    phi: Vec<f32>,
    a: Vec<f32>,
    b: Vec<f32>,
}

impl LayerWorkspace {
    /// Loads pre-centred positions and zero features.
    pub fn reset(&mut self, source: &[[f32; 3]], target: &[[f32; 3]], c: usize) {
        for (st, pts) in [(&mut self.source, source), (&mut self.target, target)] {
            let n = pts.len();
            st.n = n;
            let mut mean = [0.0f64; 3];
            for p in pts {
                for a in 0..3 {
                    mean[a] += p[a] as f64;
                }
            }
            let mean = mean.map(|m| (m / n as f64) as f32);
            let x = take(&mut st.x, n * 3);
            for (xi, p) in x.chunks_exact_mut(3).zip(pts) {
                for a in 0..3 {
                    xi[a] = p[a] - mean[a];
                }
            }
            take(&mut st.f, n * c).fill(0.0);
        }
    }
}

pub(crate) fn linear(w: &Weights, name: &str) -> Linear {
    let weight_name = format!("{name}.weight");
    let weight = w.get(&weight_name).to_vec();
    let bias = w.get(&format!("{name}.bias")).to_vec();
    let out_dim = bias.len();
    let in_dim = weight.len() / out_dim;
    Linear { in_dim, out_dim, quant: quant(w, &weight_name, &weight, out_dim, in_dim), weight, bias: Some(bias) }
}

/// The weight `name` as integers when it was read from int8 storage and `values` are still the
/// values those integers stand for (otherwise the layer computes in `f32`).
fn quant(w: &Weights, name: &str, values: &[f32], out_dim: usize, in_dim: usize) -> Option<QuantWeight> {
    let (q, scale) = w.int8.get(name)?;
    let same = q.len() == values.len()
        && q.chunks(in_dim.max(1))
            .zip(scale)
            .zip(values.chunks(in_dim.max(1)))
            .all(|((row, s), v)| row.iter().zip(v).all(|(qi, vi)| (f32::from(*qi) * s).to_bits() == vi.to_bits()));
    same.then(|| QuantWeight::new(q, scale, out_dim, in_dim)).flatten()
}

pub(crate) fn mlp(w: &Weights, prefix: &str, layers: usize, relu_last: bool) -> Mlp {
    Mlp { layers: (0..layers).map(|i| linear(w, &format!("{prefix}.{i}"))).collect(), relu_last }
}

fn norm(w: &Weights, name: &str, eps: f32) -> LayerNorm {
    LayerNorm { gamma: w.get(&format!("{name}.weight")).to_vec(), beta: w.get(&format!("{name}.bias")).to_vec(), eps }
}

fn block(w: &Weights, name: &str, cfg: &ModelConfig) -> AttentionBlock {
    AttentionBlock {
        attn: MultiHeadAttention {
            q: linear(w, &format!("{name}.q")),
            k: linear(w, &format!("{name}.k")),
            v: linear(w, &format!("{name}.v")),
            o: linear(w, &format!("{name}.o")),
            heads: cfg.heads,
        },
        norm1: norm(w, &format!("{name}.norm1"), cfg.layer_norm_eps),
        ffn1: linear(w, &format!("{name}.ffn1")),
        ffn2: linear(w, &format!("{name}.ffn2")),
        norm2: norm(w, &format!("{name}.norm2"), cfg.layer_norm_eps),
    }
}

impl ArpsLayer {
    /// Layer `l` of validated weights.
    pub fn from_weights(w: &Weights, l: usize) -> Self {
        let cfg = &w.config;
        let p = format!("layers.{l}");
        Self {
            pos: mlp(w, &format!("{p}.pos"), cfg.pos_hidden.len() + 1, true),
            self_attn: block(w, &format!("{p}.self_attn"), cfg),
            cross_attn: block(w, &format!("{p}.cross_attn"), cfg),
            out: linear(w, &format!("{p}.out")),
            score: (cfg.reference == Reference::Soft).then(|| linear(w, &format!("{p}.score"))),
            step: mlp(w, &format!("{p}.step"), 2, false),
        }
    }

    /// Runs the layer on both clouds in `ws`, shifting their positions in place.
    /// Returns the step size and the two shifts `s * mu_x`.
    pub fn forward(&self, cfg: &ModelConfig, ws: &mut LayerWorkspace) -> (f32, [f32; 3], [f32; 3]) {
        let c = cfg.feature_dim;
        let d = 2 * c;
        // tokens g = [f ; pos(x)]
        for st in [&mut ws.source, &mut ws.target] {
            let n = st.n;
            let phi = take(&mut ws.phi, n * c);
            self.pos.forward(&st.x[..n * 3], n, phi, &mut ws.a, &mut ws.b);
            let g = take(&mut st.g, n * d);
            for ((gr, fr), pr) in g.chunks_exact_mut(d).zip(st.f.chunks_exact(c)).zip(phi.chunks_exact(c)) {
                gr[..c].copy_from_slice(fr);
                gr[c..].copy_from_slice(pr);
            }
        }
        // self attention
        for st in [&mut ws.source, &mut ws.target] {
            let n = st.n;
            let g1 = take(&mut st.g1, n * d);
            self.self_attn.forward(&st.g[..n * d], n, &st.g[..n * d], n, g1, &mut ws.attn);
        }
        // cross attention: each cloud's self-attended tokens attend to the other's
        let (s, t) = (&mut ws.source, &mut ws.target);
        let gs2 = take(&mut s.g2, s.n * d);
        self.cross_attn.forward(&s.g1[..s.n * d], s.n, &t.g1[..t.n * d], t.n, gs2, &mut ws.attn);
        let gt2 = take(&mut t.g2, t.n * d);
        self.cross_attn.forward(&t.g1[..t.n * d], t.n, &s.g1[..s.n * d], s.n, gt2, &mut ws.attn);
        // features and reference points
        let mut mu = [([0.0f32; 3], vec![0.0f32; c]), ([0.0f32; 3], vec![0.0f32; c])];
        for (st, (mx, mf)) in [&mut ws.source, &mut ws.target].into_iter().zip(mu.iter_mut()) {
            let n = st.n;
            let f = take(&mut st.f, n * c);
            self.out.forward(&st.g2[..n * d], n, f);
            let w = take(&mut st.w, n);
            reference_weights(self, cfg, f, n, w);
            for i in 0..n {
                let wi = w[i];
                if wi == 0.0 {
                    continue;
                }
                for (m, x) in mx.iter_mut().zip(&st.x[i * 3..i * 3 + 3]) {
                    *m += wi * x;
                }
                for (m, v) in mf.iter_mut().zip(&f[i * c..(i + 1) * c]) {
                    *m += wi * v;
                }
            }
        }
        // step size from the differences of the two reference points
        let step_in: Vec<f32> =
            (0..3).map(|a| mu[0].0[a] - mu[1].0[a]).chain(mu[0].1.iter().zip(&mu[1].1).map(|(s, t)| s - t)).collect();
        let mut alpha = [0.0f32];
        self.step.forward(&step_in, 1, &mut alpha, &mut ws.a, &mut ws.b);
        let s = sigmoid(alpha[0]);
        let mut shifts = [[0.0f32; 3]; 2];
        for ((st, (mx, _)), shift) in [&mut ws.source, &mut ws.target].into_iter().zip(mu.iter()).zip(shifts.iter_mut())
        {
            *shift = mx.map(|v| s * v);
            for xi in st.x[..st.n * 3].chunks_exact_mut(3) {
                for a in 0..3 {
                    xi[a] -= shift[a];
                }
            }
        }
        (s, shifts[0], shifts[1])
    }
}

/// Weights of the reference point over the points (they sum to 1).
/// Top-H: `1/H` on the H largest feature norms (ties broken by lower index), 0 elsewhere.
/// Soft: `softmax(score(f) / temperature)`.
fn reference_weights(layer: &ArpsLayer, cfg: &ModelConfig, f: &[f32], n: usize, w: &mut [f32]) {
    let c = cfg.feature_dim;
    match (&layer.score, cfg.reference) {
        (Some(score), Reference::Soft) => {
            score.forward(f, n, w);
            let inv_t = 1.0 / cfg.soft_temperature;
            for v in w.iter_mut() {
                *v *= inv_t;
            }
            softmax_rows_inplace(w, n);
        }
        _ => {
            let h = cfg.top_h.min(n);
            let norms: Vec<f32> = f.chunks_exact(c).map(|r| r.iter().map(|v| v * v).sum()).collect();
            let mut idx: Vec<usize> = (0..n).collect();
            idx.sort_by(|&a, &b| norms[b].total_cmp(&norms[a]).then(a.cmp(&b)));
            w.fill(0.0);
            for &i in &idx[..h] {
                w[i] = 1.0 / h as f32;
            }
        }
    }
}
