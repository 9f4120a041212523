//! Multi-head attention and the post-norm Transformer block built on it.

use super::{
    activation::relu_inplace,
    linear::Linear,
    matmul::gemm,
    norm::LayerNorm,
    softmax::softmax_rows_unnormalized,
    workspace::{take, Workspace},
};

/// Query rows processed together: one head's `[QUERY_BLOCK, nk]` score block (512 KiB at
/// nk = 1024) stays in L2 between the two products and the softmax, and is large enough to
/// amortise packing `K_h` and `V_h` in each product.
pub const QUERY_BLOCK: usize = 128;

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
        let q = take(&mut ws.q, nq * d);
        self.q.forward(x_q, nq, q);
        // Keys transposed, [d, nk]: each head's K_h^T is then a contiguous block of rows, read
        // in place by the score product instead of being re-packed for every query block.
        let kt = take(&mut ws.k, nk * d);
        self.k.forward_transposed(x_kv, nk, kt);
        let v = take(&mut ws.v, nk * d);
        self.v.forward(x_kv, nk, v);
        let heads = take(&mut ws.heads, nq * d);
        let scores = take(&mut ws.scores, QUERY_BLOCK.min(nq) * nk);
        attend_impl(q, nq, Keys::Transposed(kt), v, nk, d, self.heads, heads, scores);
        self.o.forward(heads, nq, out);
    }
}

/// The layout of the keys given to [`attend_impl`].
#[derive(Clone, Copy)]
enum Keys<'a> {
    /// `[nk, d]` row-major.
    Rows(&'a [f32]),
    /// `[d, nk]` row-major (`K^T`).
    Transposed(&'a [f32]),
}

/// The attention core on projected tokens: for each head `h` (columns `h*dk..(h+1)*dk`),
/// `out_h = softmax(Q_h K_h^T / sqrt(dk)) V_h`. `q`, `out` are `[nq, d]`, `k`, `v` are `[nk, d]`;
/// `scores` holds at least `min(nq, QUERY_BLOCK) * nk` floats.
#[allow(clippy::too_many_arguments)]
pub fn attend(
    q: &[f32],
    nq: usize,
    k: &[f32],
    v: &[f32],
    nk: usize,
    d: usize,
    heads: usize,
    out: &mut [f32],
    scores: &mut [f32],
) {
    attend_impl(q, nq, Keys::Rows(k), v, nk, d, heads, out, scores);
}

/// [`attend`] with the keys `[nk, d]` given transposed, `kt = K^T [d, nk]`.
#[allow(clippy::too_many_arguments)]
pub fn attend_kt(
    q: &[f32],
    nq: usize,
    kt: &[f32],
    v: &[f32],
    nk: usize,
    d: usize,
    heads: usize,
    out: &mut [f32],
    scores: &mut [f32],
) {
    attend_impl(q, nq, Keys::Transposed(kt), v, nk, d, heads, out, scores);
}

#[allow(clippy::too_many_arguments)]
fn attend_impl(
    q: &[f32],
    nq: usize,
    keys: Keys,
    v: &[f32],
    nk: usize,
    d: usize,
    heads: usize,
    out: &mut [f32],
    scores: &mut [f32],
) {
    assert!(heads > 0 && d.is_multiple_of(heads), "attention: d = {d} not divisible by heads = {heads}");
    let dk = d / heads;
    let scale = 1.0 / (dk as f32).sqrt();
    let (di, nki) = (d as isize, nk as isize);
    for h in 0..heads {
        let off = h * dk;
        for q0 in (0..nq).step_by(QUERY_BLOCK) {
            let bq = QUERY_BLOCK.min(nq - q0);
            let s = &mut scores[..bq * nk];
            // s = scale * Q_h[q0..q0+bq] K_h^T
            let (kh, rsk, csk) = match keys {
                Keys::Rows(k) => (&k[off..], 1, di),
                Keys::Transposed(kt) => (&kt[off * nk..], nki, 1),
            };
            gemm(bq, dk, nk, scale, &q[q0 * d + off..], di, 1, kh, rsk, csk, 0.0, s, nki, 1);
            // s = exp(s - rowmax); the 1/rowsum factors are applied to the [bq, dk] output.
            let mut inv_sum = [0.0f32; QUERY_BLOCK];
            softmax_rows_unnormalized(s, nk, &mut inv_sum);
            // out[q0..q0+bq, off..off+dk] = diag(inv_sum) exp(S) V_h
            let o = &mut out[q0 * d + off..];
            gemm(bq, nk, dk, 1.0, s, nki, 1, &v[off..], di, 1, 0.0, o, di, 1);
            for (row, inv) in o.chunks_mut(d).zip(&inv_sum[..bq]) {
                for x in &mut row[..dk] {
                    *x *= inv;
                }
            }
        }
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
        self.norm1.forward_residual_inplace(a, &x[..nq * d]);
        let hidden = take(&mut ws.hidden, nq * self.ffn1.out_dim);
        self.ffn1.forward(a, nq, hidden);
        relu_inplace(hidden);
        let y = &mut y[..nq * d];
        self.ffn2.forward(hidden, nq, y);
        self.norm2.forward_residual_inplace(y, a);
        ws.tmp = tmp;
    }
}
