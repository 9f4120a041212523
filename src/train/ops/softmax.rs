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
        let mut tmp = ctx.scratch(g.len());
        tmp.copy_from_slice(g);
        crate::train::simd::softmax_backward(&mut tmp, y, c, 1.0);
        ctx.accumulate(self.a, &tmp);
        ctx.give(tmp);
    }
}

/// Row-wise softmax (the engine's [`crate::nn::softmax_rows_inplace`], with the trainer's fast
/// `exp`, see [`crate::train::simd`]).
pub fn softmax_rows(t: &mut Tape, a: Id) -> Id {
    let (r, c) = t.shape(a);
    let mut y = t.uninit(r * c);
    y.copy_from_slice(t.value(a));
    crate::nn::softmax_rows_inplace(&mut y, c);
    let needs = t.needs_grad(a);
    t.push(y, r, c, Box::new(Softmax { a, cols: c }), needs)
}
