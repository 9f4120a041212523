//! `y = x W^T + b` (the PyTorch layout, `W` is `[out, in]`).

use crate::nn::matmul::gemm;
use crate::train::tape::{Backward, Id, Op, Tape};

struct Linear {
    x: Id,
    w: Id,
    b: Option<Id>,
    rows: usize,
    din: usize,
    dout: usize,
}

/// `x [n, in]`, `w [out, in]`, `b [1, out]` (optional) -> `[n, out]`.
pub fn linear(t: &mut Tape, x: Id, w: Id, b: Option<Id>) -> Id {
    let (rows, din) = t.shape(x);
    let (dout, win) = t.shape(w);
    assert_eq!(win, din, "linear: weight is [{dout}, {win}] but input has {din} columns");
    if let Some(b) = b {
        assert_eq!(t.value(b).len(), dout, "linear: bias length");
    }
    let mut y = t.uninit(rows * dout);
    gemm(rows, din, dout, 1.0, t.value(x), din as isize, 1, t.value(w), 1, din as isize, 0.0, &mut y, dout as isize, 1);
    if let Some(b) = b {
        let bv = t.value(b);
        for row in y.chunks_exact_mut(dout) {
            for (v, bi) in row.iter_mut().zip(bv) {
                *v += bi;
            }
        }
    }
    let needs = t.needs_grad(x) || t.needs_grad(w) || b.is_some_and(|b| t.needs_grad(b));
    t.push(y, rows, dout, Box::new(Linear { x, w, b, rows, din, dout }), needs)
}

impl Op for Linear {
    fn name(&self) -> &'static str {
        "linear"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let (rows, din, dout) = (self.rows, self.din, self.dout);
        if ctx.needs(self.x) {
            let w = ctx.value(self.w);
            let dx = ctx.grad(self.x);
            // dx[n, in] += g[n, out] W[out, in]
            gemm(rows, dout, din, 1.0, g, dout as isize, 1, w, din as isize, 1, 1.0, dx, din as isize, 1);
        }
        if ctx.needs(self.w) {
            let x = ctx.value(self.x);
            let dw = ctx.grad(self.w);
            // dW[out, in] += g^T[out, n] x[n, in]
            gemm(dout, rows, din, 1.0, g, 1, dout as isize, x, din as isize, 1, 1.0, dw, din as isize, 1);
        }
        if let Some(b) = self.b.filter(|&b| ctx.needs(b)) {
            let db = ctx.grad(b);
            for row in g.chunks_exact(dout) {
                for (d, v) in db.iter_mut().zip(row) {
                    *d += v;
                }
            }
        }
    }
}
