//! LayerNorm over the last dimension (the engine's [`crate::nn::LayerNorm`]).

use crate::train::simd;
use crate::train::tape::{Backward, Id, Op, Pool, Tape};

struct LayerNormOp {
    x: Id,
    gamma: Id,
    beta: Id,
    dim: usize,
    /// Per row: mean and `1 / sqrt(var + eps)`.
    stats: Vec<f32>,
}

/// `y = (x - mean) / sqrt(var + eps) * gamma + beta` per row; `gamma`, `beta` are `[1, dim]`.
pub fn layer_norm(t: &mut Tape, x: Id, gamma: Id, beta: Id, eps: f32) -> Id {
    let (rows, dim) = t.shape(x);
    assert_eq!(t.value(gamma).len(), dim, "layer_norm: gamma length");
    assert_eq!(t.value(beta).len(), dim, "layer_norm: beta length");
    let mut y = t.uninit(rows * dim);
    let mut stats = t.uninit(rows * 2);
    simd::layer_norm(t.value(x), t.value(gamma), t.value(beta), eps, &mut y, &mut stats);
    let needs = t.any_needs(&[x, gamma, beta]);
    t.push(y, rows, dim, Box::new(LayerNormOp { x, gamma, beta, dim, stats }), needs)
}

impl Op for LayerNormOp {
    fn name(&self) -> &'static str {
        "layer_norm"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let dim = self.dim;
        let x = ctx.value(self.x);
        let gamma = ctx.value(self.gamma);
        let mut dgamma = ctx.scratch(dim);
        let mut dbeta = ctx.scratch(dim);
        let mut scratch = ctx.scratch(2 * dim);
        let dx = if ctx.needs(self.x) { Some(ctx.grad(self.x)) } else { None };
        simd::layer_norm_backward(g, x, gamma, &self.stats, dx, &mut dgamma, &mut dbeta, &mut scratch);
        ctx.accumulate(self.gamma, &dgamma);
        ctx.accumulate(self.beta, &dbeta);
        for v in [dgamma, dbeta, scratch] {
            ctx.give(v);
        }
    }

    fn recycle(self: Box<Self>, pool: &mut Pool) {
        pool.give(self.stats);
    }
}
