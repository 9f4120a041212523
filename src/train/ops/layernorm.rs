//! LayerNorm over the last dimension (the engine's [`crate::nn::LayerNorm`]).

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
    let (g, b) = (t.value(gamma), t.value(beta));
    for ((yr, xr), st) in y.chunks_exact_mut(dim).zip(t.value(x).chunks_exact(dim)).zip(stats.chunks_exact_mut(2)) {
        let mean = xr.iter().sum::<f32>() / dim as f32;
        let var = xr.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / dim as f32;
        let inv = 1.0 / (var + eps).sqrt();
        for (((y, x), g), b) in yr.iter_mut().zip(xr).zip(g).zip(b) {
            *y = (*x - mean) * inv * g + b;
        }
        st[0] = mean;
        st[1] = inv;
    }
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
        let (need_x, need_g, need_b) = (ctx.needs(self.x), ctx.needs(self.gamma), ctx.needs(self.beta));
        let mut dgamma = ctx.scratch(dim);
        let mut dbeta = ctx.scratch(dim);
        let mut xhat = ctx.scratch(dim);
        let mut dxhat = ctx.scratch(dim);
        for (r, (gr, xr)) in g.chunks_exact(dim).zip(x.chunks_exact(dim)).enumerate() {
            let (mean, inv) = (self.stats[2 * r], self.stats[2 * r + 1]);
            let mut m1 = 0.0f32;
            let mut m2 = 0.0f32;
            for k in 0..dim {
                xhat[k] = (xr[k] - mean) * inv;
                dxhat[k] = gr[k] * gamma[k];
                m1 += dxhat[k];
                m2 += dxhat[k] * xhat[k];
                dgamma[k] += gr[k] * xhat[k];
                dbeta[k] += gr[k];
            }
            if need_x {
                m1 /= dim as f32;
                m2 /= dim as f32;
                let dx = &mut ctx.grad(self.x)[r * dim..(r + 1) * dim];
                for k in 0..dim {
                    dx[k] += inv * (dxhat[k] - m1 - xhat[k] * m2);
                }
            }
        }
        if need_g {
            ctx.accumulate(self.gamma, &dgamma);
        }
        if need_b {
            ctx.accumulate(self.beta, &dbeta);
        }
        for v in [dgamma, dbeta, xhat, dxhat] {
            ctx.give(v);
        }
    }

    fn recycle(self: Box<Self>, pool: &mut Pool) {
        pool.give(self.stats);
    }
}
