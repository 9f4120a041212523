//! Column concatenation `[a ; b]`, and the membership head's `[f ; max_k f]`.

use crate::train::tape::{Backward, Id, Op, Pool, Tape};

struct Concat {
    a: Id,
    b: Id,
    ca: usize,
    cb: usize,
}

/// `[a ; b]` along columns: `a [n, ca]`, `b [n, cb]` -> `[n, ca + cb]`.
pub fn concat_cols(t: &mut Tape, a: Id, b: Id) -> Id {
    let (n, ca) = t.shape(a);
    let (nb, cb) = t.shape(b);
    assert_eq!(n, nb, "concat_cols: row counts differ");
    let w = ca + cb;
    let mut y = t.uninit(n * w);
    for ((yr, ar), br) in
        y.chunks_exact_mut(w).zip(t.value(a).chunks_exact(ca.max(1))).zip(t.value(b).chunks_exact(cb.max(1)))
    {
        yr[..ca].copy_from_slice(&ar[..ca]);
        yr[ca..].copy_from_slice(&br[..cb]);
    }
    let needs = t.any_needs(&[a, b]);
    t.push(y, n, w, Box::new(Concat { a, b, ca, cb }), needs)
}

impl Op for Concat {
    fn name(&self) -> &'static str {
        "concat_cols"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let (ca, cb) = (self.ca, self.cb);
        let w = ca + cb;
        if ctx.needs(self.a) {
            for (d, gr) in ctx.grad(self.a).chunks_exact_mut(ca).zip(g.chunks_exact(w)) {
                for (d, v) in d.iter_mut().zip(&gr[..ca]) {
                    *d += v;
                }
            }
        }
        if ctx.needs(self.b) {
            for (d, gr) in ctx.grad(self.b).chunks_exact_mut(cb).zip(g.chunks_exact(w)) {
                for (d, v) in d.iter_mut().zip(&gr[ca..]) {
                    *d += v;
                }
            }
        }
    }
}

struct ConcatColmax {
    f: Id,
    c: usize,
    /// Row index of each column's maximum (first one on ties, as a sequential scan finds it).
    argmax: Vec<usize>,
}

/// `[f ; max_k f_k]`: each row of `f [n, c]` followed by the column-wise maximum over all rows
/// -> `[n, 2c]`. The gradient of the maximum goes to the (first) maximising row.
pub fn concat_colmax(t: &mut Tape, f: Id) -> Id {
    let (n, c) = t.shape(f);
    let fv = t.value(f);
    let mut max = vec![f32::NEG_INFINITY; c];
    let mut argmax = vec![0usize; c];
    for (i, row) in fv.chunks_exact(c).enumerate() {
        for k in 0..c {
            if row[k] > max[k] {
                max[k] = row[k];
                argmax[k] = i;
            }
        }
    }
    let mut y = t.uninit(n * 2 * c);
    let fv = t.value(f);
    for (yr, fr) in y.chunks_exact_mut(2 * c).zip(fv.chunks_exact(c)) {
        yr[..c].copy_from_slice(fr);
        yr[c..].copy_from_slice(&max);
    }
    let needs = t.needs_grad(f);
    t.push(y, n, 2 * c, Box::new(ConcatColmax { f, c, argmax }), needs)
}

impl Op for ConcatColmax {
    fn name(&self) -> &'static str {
        "concat_colmax"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let c = self.c;
        let mut colsum = ctx.scratch(c);
        let df = ctx.grad(self.f);
        for (d, gr) in df.chunks_exact_mut(c).zip(g.chunks_exact(2 * c)) {
            for k in 0..c {
                d[k] += gr[k];
                colsum[k] += gr[c + k];
            }
        }
        for k in 0..c {
            df[self.argmax[k] * c + k] += colsum[k];
        }
        ctx.give(colsum);
    }
    fn recycle(self: Box<Self>, _pool: &mut Pool) {}
}
