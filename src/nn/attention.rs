//! Multi-head attention and the post-norm Transformer block built on it.

use super::{
    activation::relu_inplace,
    linear::Linear,
    matmul::gemm,
    norm::LayerNorm,
    softmax::softmax_rows_inplace,
    workspace::{take, Workspace},
};

/// Multi-head scaled dot-product attention with Q/K/V/O projections (all with bias).
#[derive(Clone, Debug, PartialEq)]
pub struct MultiHeadAttention {
    /// Query projection `[d, d]`.
    pub q: Linear,
    /// Key projection `[d, d]`.
    pub k: Linear,
    /// Value projection `[d, d]`.
    pub v: Linear,
    /// Output projection `[d, d]`.
    pub o: Linear,
    /// Number of heads; `d` must be divisible by it.
    pub heads: usize,
}

impl MultiHeadAttention {
    /// Model width `d`.
    pub fn dim(&self) -> usize {
        self.q.out_dim
    }

    /// `out[nq, d] = MHA(x_q, x_kv, x_kv)`: queries from `x_q [nq, d]`, keys and values from
    /// `x_kv [nk, d]`.
    pub fn forward(&self, x_q: &[f32], nq: usize, x_kv: &[f32], nk: usize, out: &mut [f32], ws: &mut Workspace) {
        let d = self.dim();
        let dk = d / self.heads;
        let q = take(&mut ws.q, nq * d);
        self.q.forward(x_q, nq, q);
        let k = take(&mut ws.k, nk * d);
        self.k.forward(x_kv, nk, k);
        let v = take(&mut ws.v, nk * d);
        self.v.forward(x_kv, nk, v);
        let heads = take(&mut ws.heads, nq * d);
        let scores = take(&mut ws.scores, nq * nk);
        let scale = 1.0 / (dk as f32).sqrt();
        for h in 0..self.heads {
            let off = h * dk;
            // scores = scale * Q_h K_h^T
            gemm(nq, dk, nk, scale, &q[off..], d as isize, 1, &k[off..], 1, d as isize, 0.0, scores, nk as isize, 1);
            softmax_rows_inplace(scores, nk);
            // heads[:, off..off+dk] = P V_h
            gemm(
                nq,
                nk,
                dk,
                1.0,
                scores,
                nk as isize,
                1,
                &v[off..],
                d as isize,
                1,
                0.0,
                &mut heads[off..],
                d as isize,
                1,
            );
        }
        self.o.forward(heads, nq, out);
    }
}

/// Post-norm Transformer block: `a = LN1(x + MHA(x, kv)); y = LN2(a + FFN(a))`,
/// `FFN = Linear(d, ffn) -> ReLU -> Linear(ffn, d)`. Self-attention when `kv` is `x`.
#[derive(Clone, Debug, PartialEq)]
pub struct AttentionBlock {
    /// The attention.
    pub attn: MultiHeadAttention,
    /// Norm after the attention residual.
    pub norm1: LayerNorm,
    /// FFN first layer `[ffn, d]`.
    pub ffn1: Linear,
    /// FFN second layer `[d, ffn]`.
    pub ffn2: Linear,
    /// Norm after the FFN residual.
    pub norm2: LayerNorm,
}

impl AttentionBlock {
    /// Writes the block's output for queries `x [nq, d]` attending to `kv [nk, d]` into `y [nq, d]`.
    pub fn forward(&self, x: &[f32], nq: usize, kv: &[f32], nk: usize, y: &mut [f32], ws: &mut Workspace) {
        let d = self.attn.dim();
        let mut tmp = std::mem::take(&mut ws.tmp);
        let a = take(&mut tmp, nq * d);
        self.attn.forward(x, nq, kv, nk, a, ws);
        for (ai, xi) in a.iter_mut().zip(x) {
            *ai += xi;
        }
        self.norm1.forward_inplace(a);
        let hidden = take(&mut ws.hidden, nq * self.ffn1.out_dim);
        self.ffn1.forward(a, nq, hidden);
        relu_inplace(hidden);
        self.ffn2.forward(hidden, nq, y);
        for (yi, ai) in y.iter_mut().zip(a.iter()) {
            *yi += ai;
        }
        self.norm2.forward_inplace(y);
        ws.tmp = tmp;
    }
}
