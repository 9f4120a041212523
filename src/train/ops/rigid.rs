//! Small matrix algebra for 4x4 rigid transforms: product, closed-form rigid inverse, and
//! applying a transform to points.

use crate::nn::matmul::gemm;
use crate::train::tape::{Backward, Id, Op, Tape};

struct MatMul {
    a: Id,
    b: Id,
    m: usize,
    k: usize,
    n: usize,
}

/// `a [m, k] * b [k, n]` -> `[m, n]`.
pub fn matmul(t: &mut Tape, a: Id, b: Id) -> Id {
    let (m, k) = t.shape(a);
    let (kb, n) = t.shape(b);
    assert_eq!(k, kb, "matmul: inner sizes differ");
    let mut y = t.zeros(m * n);
    gemm(m, k, n, 1.0, t.value(a), k as isize, 1, t.value(b), n as isize, 1, 0.0, &mut y, n as isize, 1);
    let needs = t.any_needs(&[a, b]);
    t.push(y, m, n, Box::new(MatMul { a, b, m, k, n }), needs)
}

impl Op for MatMul {
    fn name(&self) -> &'static str {
        "matmul"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let (m, k, n) = (self.m, self.k, self.n);
        if ctx.needs(self.a) {
            let b = ctx.value(self.b);
            let mut da = ctx.scratch(m * k);
            // da[m, k] = g[m, n] b^T
            gemm(m, n, k, 1.0, g, n as isize, 1, b, 1, n as isize, 0.0, &mut da, k as isize, 1);
            ctx.accumulate(self.a, &da);
            ctx.give(da);
        }
        if ctx.needs(self.b) {
            let a = ctx.value(self.a);
            let mut db = ctx.scratch(k * n);
            // db[k, n] = a^T g
            gemm(k, m, n, 1.0, a, 1, k as isize, g, n as isize, 1, 0.0, &mut db, n as isize, 1);
            ctx.accumulate(self.b, &db);
            ctx.give(db);
        }
    }
}

struct RigidInverse {
    a: Id,
}

/// `[[R, t], [0, 1]]^-1 = [[R^T, -R^T t], [0, 1]]` (closed form; assumes a rigid input).
pub fn rigid_inverse(t: &mut Tape, a: Id) -> Id {
    assert_eq!(t.shape(a), (4, 4), "rigid_inverse: expects 4x4");
    let mut y = t.zeros(16);
    let m = t.value(a);
    for r in 0..3 {
        for c in 0..3 {
            y[r * 4 + c] = m[c * 4 + r];
        }
        y[r * 4 + 3] = -(0..3).map(|k| m[k * 4 + r] * m[k * 4 + 3]).sum::<f32>();
    }
    y[15] = 1.0;
    let needs = t.needs_grad(a);
    t.push(y, 4, 4, Box::new(RigidInverse { a }), needs)
}

impl Op for RigidInverse {
    fn name(&self) -> &'static str {
        "rigid_inverse"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let m = ctx.value(self.a);
        let da = ctx.grad(self.a);
        for r in 0..3 {
            for c in 0..3 {
                // out R^T
                da[c * 4 + r] += g[r * 4 + c];
            }
        }
        // out_t[i] = -sum_k R[k][i] t[k]
        for i in 0..3 {
            let gi = g[i * 4 + 3];
            for k in 0..3 {
                da[k * 4 + i] -= m[k * 4 + 3] * gi;
                da[k * 4 + 3] -= m[k * 4 + i] * gi;
            }
        }
    }
}

struct TransformPoints {
    m: Id,
    p: Id,
    n: usize,
}

/// `R p_i + t` for `T [4, 4]` and points `p [n, 3]` -> `[n, 3]`.
pub fn transform_points(t: &mut Tape, m: Id, p: Id) -> Id {
    assert_eq!(t.shape(m), (4, 4), "transform_points: expects a 4x4");
    let (n, c) = t.shape(p);
    assert_eq!(c, 3, "transform_points: points are [n, 3]");
    let mut y = t.uninit(n * 3);
    let mv = t.value(m);
    for (yr, pr) in y.chunks_exact_mut(3).zip(t.value(p).chunks_exact(3)) {
        for r in 0..3 {
            yr[r] = mv[r * 4] * pr[0] + mv[r * 4 + 1] * pr[1] + mv[r * 4 + 2] * pr[2] + mv[r * 4 + 3];
        }
    }
    let needs = t.any_needs(&[m, p]);
    t.push(y, n, 3, Box::new(TransformPoints { m, p, n }), needs)
}

impl Op for TransformPoints {
    fn name(&self) -> &'static str {
        "transform_points"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let (mv, pv) = (ctx.value(self.m), ctx.value(self.p));
        if ctx.needs(self.m) {
            let mut acc = [0.0f64; 12];
            for (gr, pr) in g.chunks_exact(3).zip(pv.chunks_exact(3)) {
                for r in 0..3 {
                    let gi = gr[r] as f64;
                    acc[r * 4] += gi * pr[0] as f64;
                    acc[r * 4 + 1] += gi * pr[1] as f64;
                    acc[r * 4 + 2] += gi * pr[2] as f64;
                    acc[r * 4 + 3] += gi;
                }
            }
            let dm = ctx.grad(self.m);
            for (d, a) in dm.iter_mut().zip(acc) {
                *d += a as f32;
            }
        }
        if ctx.needs(self.p) {
            let dp = ctx.grad(self.p);
            for i in 0..self.n {
                for c in 0..3 {
                    dp[i * 3 + c] += (0..3).map(|r| mv[r * 4 + c] * g[i * 3 + r]).sum::<f32>();
                }
            }
        }
    }
}
