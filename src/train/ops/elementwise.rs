//! Element-wise ops: sum, difference, scaling, ReLU, sigmoid, scaling by a scalar node, and
//! subtracting one row from every row.

use crate::train::tape::{Backward, Id, Op, Tape};

fn same_shape(t: &Tape, a: Id, b: Id, what: &str) -> (usize, usize) {
    let sa = t.shape(a);
    assert_eq!(sa, t.shape(b), "{what}: shapes differ");
    sa
}

struct AddSub {
    a: Id,
    b: Id,
    sign: f32,
}

impl Op for AddSub {
    fn name(&self) -> &'static str {
        if self.sign > 0.0 {
            "add"
        } else {
            "sub"
        }
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        ctx.accumulate(self.a, g);
        if ctx.needs(self.b) {
            let s = self.sign;
            for (d, v) in ctx.grad(self.b).iter_mut().zip(g) {
                *d += s * v;
            }
        }
    }
}

fn add_sub(t: &mut Tape, a: Id, b: Id, sign: f32) -> Id {
    let (r, c) = same_shape(t, a, b, if sign > 0.0 { "add" } else { "sub" });
    let mut y = t.uninit(r * c);
    for ((y, x), z) in y.iter_mut().zip(t.value(a)).zip(t.value(b)) {
        *y = if sign > 0.0 { x + z } else { x - z };
    }
    let needs = t.any_needs(&[a, b]);
    t.push(y, r, c, Box::new(AddSub { a, b, sign }), needs)
}

/// `a + b` (same shapes).
pub fn add(t: &mut Tape, a: Id, b: Id) -> Id {
    add_sub(t, a, b, 1.0)
}

/// `a - b` (same shapes).
pub fn sub(t: &mut Tape, a: Id, b: Id) -> Id {
    add_sub(t, a, b, -1.0)
}

struct Scale {
    a: Id,
    s: f32,
}

impl Op for Scale {
    fn name(&self) -> &'static str {
        "scale"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let s = self.s;
        for (d, v) in ctx.grad(self.a).iter_mut().zip(g) {
            *d += s * v;
        }
    }
}

/// `s * a` for a constant `s`.
pub fn scale(t: &mut Tape, a: Id, s: f32) -> Id {
    let (r, c) = t.shape(a);
    let mut y = t.uninit(r * c);
    for (y, x) in y.iter_mut().zip(t.value(a)) {
        *y = s * x;
    }
    let needs = t.needs_grad(a);
    t.push(y, r, c, Box::new(Scale { a, s }), needs)
}

struct Relu {
    a: Id,
}

impl Op for Relu {
    fn name(&self) -> &'static str {
        "relu"
    }
    fn backward(&self, ctx: &mut Backward<'_>, out: Id, g: &[f32]) {
        let y = ctx.value(out);
        crate::train::simd::relu_backward(ctx.grad(self.a), g, y);
    }
}

/// `max(a, 0)`.
pub fn relu(t: &mut Tape, a: Id) -> Id {
    let (r, c) = t.shape(a);
    let mut y = t.uninit(r * c);
    for (y, x) in y.iter_mut().zip(t.value(a)) {
        *y = x.max(0.0);
    }
    let needs = t.needs_grad(a);
    t.push(y, r, c, Box::new(Relu { a }), needs)
}

struct Sigmoid {
    a: Id,
}

impl Op for Sigmoid {
    fn name(&self) -> &'static str {
        "sigmoid"
    }
    fn backward(&self, ctx: &mut Backward<'_>, out: Id, g: &[f32]) {
        let y = ctx.value(out);
        for ((d, v), y) in ctx.grad(self.a).iter_mut().zip(g).zip(y) {
            *d += v * y * (1.0 - y);
        }
    }
}

/// The logistic sigmoid (the engine's [`crate::nn::sigmoid`]).
pub fn sigmoid(t: &mut Tape, a: Id) -> Id {
    let (r, c) = t.shape(a);
    let mut y = t.uninit(r * c);
    for (y, x) in y.iter_mut().zip(t.value(a)) {
        *y = crate::nn::sigmoid(*x);
    }
    let needs = t.needs_grad(a);
    t.push(y, r, c, Box::new(Sigmoid { a }), needs)
}

struct MulScalar {
    a: Id,
    s: Id,
}

impl Op for MulScalar {
    fn name(&self) -> &'static str {
        "mul_scalar"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let s = ctx.value(self.s)[0];
        if ctx.needs(self.a) {
            for (d, v) in ctx.grad(self.a).iter_mut().zip(g) {
                *d += s * v;
            }
        }
        if ctx.needs(self.s) {
            let a = ctx.value(self.a);
            let ds: f32 = g.iter().zip(a).map(|(v, x)| v * x).sum();
            ctx.grad(self.s)[0] += ds;
        }
    }
}

/// `s * a` where `s` is a `1 x 1` node.
pub fn mul_scalar(t: &mut Tape, a: Id, s: Id) -> Id {
    assert_eq!(t.shape(s), (1, 1), "mul_scalar: s must be 1x1");
    let (r, c) = t.shape(a);
    let sv = t.value(s)[0];
    let mut y = t.uninit(r * c);
    for (y, x) in y.iter_mut().zip(t.value(a)) {
        *y = sv * x;
    }
    let needs = t.any_needs(&[a, s]);
    t.push(y, r, c, Box::new(MulScalar { a, s }), needs)
}

struct SubRow {
    x: Id,
    r: Id,
    cols: usize,
}

impl Op for SubRow {
    fn name(&self) -> &'static str {
        "sub_row"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        ctx.accumulate(self.x, g);
        if ctx.needs(self.r) {
            let dr = ctx.grad(self.r);
            for row in g.chunks_exact(self.cols) {
                for (d, v) in dr.iter_mut().zip(row) {
                    *d -= v;
                }
            }
        }
    }
}

/// `x [n, c] - r [1, c]` (the row subtracted from every row).
pub fn sub_row(t: &mut Tape, x: Id, r: Id) -> Id {
    let (n, c) = t.shape(x);
    assert_eq!(t.shape(r), (1, c), "sub_row: r must be [1, {c}]");
    let mut y = t.uninit(n * c);
    let rv = t.value(r);
    for (yr, xr) in y.chunks_exact_mut(c).zip(t.value(x).chunks_exact(c)) {
        for ((y, x), r) in yr.iter_mut().zip(xr).zip(rv) {
            *y = x - r;
        }
    }
    let needs = t.any_needs(&[x, r]);
    t.push(y, n, c, Box::new(SubRow { x, r, cols: c }), needs)
}
