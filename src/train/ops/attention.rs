//! Multi-head scaled dot-product attention on projected queries, keys and values (the core of
//! the engine's [`crate::nn::MultiHeadAttention`]; the Q/K/V/O projections are [`super::linear()`]
//! ops). The per-head probabilities are kept for the backward pass.

use crate::nn::matmul::gemm;
use crate::train::simd;
use crate::train::tape::{Backward, Id, Op, Pool, Tape};

struct Attention {
    q: Id,
    k: Id,
    v: Id,
    heads: usize,
    nq: usize,
    nk: usize,
    d: usize,
    /// `[heads, nq, nk]` softmax probabilities.
    probs: Vec<f32>,
}

/// `q [nq, d]`, `k [nk, d]`, `v [nk, d]` -> `[nq, d]`: for each head `h` (columns
/// `h*d/heads ..`), `softmax(Q_h K_h^T / sqrt(d/heads)) V_h`.
pub fn attention(t: &mut Tape, q: Id, k: Id, v: Id, heads: usize) -> Id {
    let (nq, d) = t.shape(q);
    let (nk, dk_) = t.shape(k);
    assert_eq!(dk_, d, "attention: key width");
    assert_eq!(t.shape(v), (nk, d), "attention: value shape");
    assert!(heads > 0 && d % heads == 0, "attention: width {d} not divisible by {heads} heads");
    let dk = d / heads;
    let scale = 1.0 / (dk as f32).sqrt();
    let mut probs = t.uninit(heads * nq * nk);
    let mut out = t.uninit(nq * d);
    let (qv, kv, vv) = (t.value(q), t.value(k), t.value(v));
    for h in 0..heads {
        let off = h * dk;
        let p = &mut probs[h * nq * nk..(h + 1) * nq * nk];
        gemm(nq, dk, nk, scale, &qv[off..], d as isize, 1, &kv[off..], 1, d as isize, 0.0, p, nk as isize, 1);
        crate::nn::softmax_rows_inplace(p, nk);
        gemm(nq, nk, dk, 1.0, p, nk as isize, 1, &vv[off..], d as isize, 1, 0.0, &mut out[off..], d as isize, 1);
    }
    let needs = t.any_needs(&[q, k, v]);
    t.push(out, nq, d, Box::new(Attention { q, k, v, heads, nq, nk, d, probs }), needs)
}

impl Op for Attention {
    fn name(&self) -> &'static str {
        "attention"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let (nq, nk, d, heads) = (self.nq, self.nk, self.d, self.heads);
        let dk = d / heads;
        let scale = 1.0 / (dk as f32).sqrt();
        let (qv, kv, vv) = (ctx.value(self.q), ctx.value(self.k), ctx.value(self.v));
        let mut dq = ctx.scratch(nq * d);
        let mut dkb = ctx.scratch(nk * d);
        let mut dv = ctx.scratch(nk * d);
        let mut ds = ctx.scratch(nq * nk);
        for h in 0..heads {
            let off = h * dk;
            let p = &self.probs[h * nq * nk..(h + 1) * nq * nk];
            // dV_h += P^T dO_h
            gemm(nk, nq, dk, 1.0, p, 1, nk as isize, &g[off..], d as isize, 1, 1.0, &mut dv[off..], d as isize, 1);
            // dP = dO_h V_h^T
            gemm(nq, dk, nk, 1.0, &g[off..], d as isize, 1, &vv[off..], 1, d as isize, 0.0, &mut ds, nk as isize, 1);
            // dS = scale * P * (dP - rowsum(dP * P))
            simd::softmax_backward(&mut ds, p, nk, scale);
            // dQ_h += dS K_h ; dK_h += dS^T Q_h
            gemm(nq, nk, dk, 1.0, &ds, nk as isize, 1, &kv[off..], d as isize, 1, 1.0, &mut dq[off..], d as isize, 1);
            gemm(nk, nq, dk, 1.0, &ds, 1, nk as isize, &qv[off..], d as isize, 1, 1.0, &mut dkb[off..], d as isize, 1);
        }
        ctx.accumulate(self.q, &dq);
        ctx.accumulate(self.k, &dkb);
        ctx.accumulate(self.v, &dv);
        for b in [dq, dkb, dv, ds] {
            ctx.give(b);
        }
    }

    fn recycle(self: Box<Self>, pool: &mut Pool) {
        pool.give(self.probs);
    }
}
