//! Reductions: weighted sum over points (the reference point), mean of all entries, a weighted
//! total of scalar nodes, and reshape.

use crate::train::tape::{Backward, Id, Op, Tape};

struct WeightedSum {
    w: Id,
    x: Id,
    n: usize,
    c: usize,
}

/// `sum_i w_i x_i`: `w` has `n` entries (`[1, n]` or `[n, 1]`), `x [n, c]` -> `[1, c]`.
/// Accumulates in `f32` in point order, skipping zero weights (as the engine does).
pub fn weighted_sum(t: &mut Tape, w: Id, x: Id) -> Id {
    let (n, c) = t.shape(x);
    assert_eq!(t.value(w).len(), n, "weighted_sum: weights vs points");
    let mut y = t.zeros(c);
    let (wv, xv) = (t.value(w), t.value(x));
    for i in 0..n {
        let wi = wv[i];
        if wi == 0.0 {
            continue;
        }
        for (m, v) in y.iter_mut().zip(&xv[i * c..(i + 1) * c]) {
            *m += wi * v;
        }
    }
    let needs = t.any_needs(&[w, x]);
    t.push(y, 1, c, Box::new(WeightedSum { w, x, n, c }), needs)
}

impl Op for WeightedSum {
    fn name(&self) -> &'static str {
        "weighted_sum"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let c = self.c;
        if ctx.needs(self.w) {
            let x = ctx.value(self.x);
            let dw = ctx.grad(self.w);
            for i in 0..self.n {
                dw[i] += x[i * c..(i + 1) * c].iter().zip(g).map(|(a, b)| a * b).sum::<f32>();
            }
        }
        if ctx.needs(self.x) {
            let w = ctx.value(self.w);
            let dx = ctx.grad(self.x);
            for i in 0..self.n {
                let wi = w[i];
                for (d, v) in dx[i * c..(i + 1) * c].iter_mut().zip(g) {
                    *d += wi * v;
                }
            }
        }
    }
}

struct Mean {
    a: Id,
}

/// Mean of all entries -> `[1, 1]` (accumulated in `f64`).
pub fn mean_all(t: &mut Tape, a: Id) -> Id {
    let v = t.value(a);
    let m = (v.iter().map(|&x| x as f64).sum::<f64>() / v.len().max(1) as f64) as f32;
    let mut y = t.uninit(1);
    y[0] = m;
    let needs = t.needs_grad(a);
    t.push(y, 1, 1, Box::new(Mean { a }), needs)
}

impl Op for Mean {
    fn name(&self) -> &'static str {
        "mean_all"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let da = ctx.grad(self.a);
        let s = g[0] / da.len().max(1) as f32;
        for d in da.iter_mut() {
            *d += s;
        }
    }
}

struct WeightedTotal {
    terms: Vec<(Id, f32)>,
}

/// `sum_k c_k a_k` over `1 x 1` nodes -> `[1, 1]` (accumulated in `f64`).
pub fn weighted_total(t: &mut Tape, terms: &[(Id, f32)]) -> Id {
    let mut s = 0.0f64;
    for &(a, c) in terms {
        assert_eq!(t.shape(a), (1, 1), "weighted_total: terms must be 1x1");
        s += c as f64 * t.scalar64(a);
    }
    let mut y = t.uninit(1);
    y[0] = s as f32;
    let ids: Vec<Id> = terms.iter().map(|&(a, _)| a).collect();
    let needs = t.any_needs(&ids);
    let id = t.push(y, 1, 1, Box::new(WeightedTotal { terms: terms.to_vec() }), needs);
    t.set_scalar64(id, s);
    id
}

impl Op for WeightedTotal {
    fn name(&self) -> &'static str {
        "weighted_total"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        for &(a, c) in &self.terms {
            if ctx.needs(a) {
                ctx.grad(a)[0] += c * g[0];
            }
        }
    }
}

struct Reshape {
    a: Id,
}

/// Same data, new shape (`rows * cols` must equal the old size).
pub fn reshape(t: &mut Tape, a: Id, rows: usize, cols: usize) -> Id {
    assert_eq!(t.value(a).len(), rows * cols, "reshape: size");
    let mut y = t.uninit(rows * cols);
    y.copy_from_slice(t.value(a));
    let needs = t.needs_grad(a);
    t.push(y, rows, cols, Box::new(Reshape { a }), needs)
}

impl Op for Reshape {
    fn name(&self) -> &'static str {
        "reshape"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        ctx.accumulate(self.a, g);
    }
}
