//! Softmax over each row.

use crate::train::tape::{Backward, Id, Op, Tape};

struct Softmax {
    a: Id,
    cols: usize,
}

impl Op for Softmax {
    fn name(&self) -> &'static str {
        "softmax_rows"
    }
    fn backward(&self, ctx: &mut Backward<'_>, out: Id, g: &[f32]) {
        let y = ctx.value(out);
        let c = self.cols;
        let da = ctx.grad(self.a);
        for ((dr, gr), yr) in da.chunks_exact_mut(c).zip(g.chunks_exact(c)).zip(y.chunks_exact(c)) {
            let dot: f32 = gr.iter().zip(yr).map(|(g, y)| g * y).sum();
            for ((d, g), y) in dr.iter_mut().zip(gr).zip(yr) {
                *d += y * (g - dot);
            }
        }
    }
}

/// Row-wise softmax (the engine's [`crate::nn::softmax_rows_inplace`]).
pub fn softmax_rows(t: &mut Tape, a: Id) -> Id {
    let (r, c) = t.shape(a);
    let mut y = t.uninit(r * c);
    y.copy_from_slice(t.value(a));
    crate::nn::softmax_rows_inplace(&mut y, c);
    let needs = t.needs_grad(a);
    t.push(y, r, c, Box::new(Softmax { a, cols: c }), needs)
}
