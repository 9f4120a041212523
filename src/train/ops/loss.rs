//! Loss ops: squared error against a constant, squared Chamfer distance, and the dense
//! membership-consistency divergence, and the KL divergence of memberships from target rows.

use crate::train::tape::{Backward, Id, Op, Tape};

struct SqErr {
    a: Id,
    target: Vec<f32>,
    scale: f32,
}

/// `scale * sum (a - target)^2` -> `[1, 1]` (accumulated in `f64`). With
/// `scale = 1 / len` this is the MSE.
pub fn sq_err(t: &mut Tape, a: Id, target: &[f32], scale: f32) -> Id {
    let v = t.value(a);
    assert_eq!(v.len(), target.len(), "sq_err: target length");
    let s: f64 = v.iter().zip(target).map(|(&x, &y)| ((x - y) as f64).powi(2)).sum();
    let mut y = t.uninit(1);
    let v64 = scale as f64 * s;
    y[0] = v64 as f32;
    let needs = t.needs_grad(a);
    let id = t.push(y, 1, 1, Box::new(SqErr { a, target: target.to_vec(), scale }), needs);
    t.set_scalar64(id, v64);
    id
}

impl Op for SqErr {
    fn name(&self) -> &'static str {
        "sq_err"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let a = ctx.value(self.a);
        let k = 2.0 * self.scale * g[0];
        for ((d, x), y) in ctx.grad(self.a).iter_mut().zip(a).zip(&self.target) {
            *d += k * (x - y);
        }
    }
}

struct Chamfer {
    a: Id,
    b: Id,
    /// Nearest `b` of each `a`, and nearest `a` of each `b`.
    nn_ab: Vec<usize>,
    nn_ba: Vec<usize>,
}

/// Squared Chamfer distance `mean_i min_k |a_i - b_k|^2 + mean_k min_i |a_i - b_k|^2` between
/// `a [n, 3]` and `b [m, 3]` -> `[1, 1]` (brute force, `O(n m)`; ties go to the lower index).
pub fn chamfer_sq(t: &mut Tape, a: Id, b: Id) -> Id {
    let (n, ca) = t.shape(a);
    let (m, cb) = t.shape(b);
    assert!(ca == 3 && cb == 3 && n > 0 && m > 0, "chamfer_sq: expects non-empty [n, 3] and [m, 3]");
    let (av, bv) = (t.value(a), t.value(b));
    let mut best_ab = vec![(f32::INFINITY, 0usize); n];
    let mut best_ba = vec![(f32::INFINITY, 0usize); m];
    for (i, p) in av.chunks_exact(3).enumerate() {
        for (k, q) in bv.chunks_exact(3).enumerate() {
            let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
            if d < best_ab[i].0 {
                best_ab[i] = (d, k);
            }
            if d < best_ba[k].0 {
                best_ba[k] = (d, i);
            }
        }
    }
    let s_ab: f64 = best_ab.iter().map(|&(d, _)| d as f64).sum::<f64>() / n as f64;
    let s_ba: f64 = best_ba.iter().map(|&(d, _)| d as f64).sum::<f64>() / m as f64;
    let mut y = t.uninit(1);
    y[0] = (s_ab + s_ba) as f32;
    let needs = t.any_needs(&[a, b]);
    let id = t.push(
        y,
        1,
        1,
        Box::new(Chamfer {
            a,
            b,
            nn_ab: best_ab.iter().map(|x| x.1).collect(),
            nn_ba: best_ba.iter().map(|x| x.1).collect(),
        }),
        needs,
    );
    t.set_scalar64(id, s_ab + s_ba);
    id
}

impl Op for Chamfer {
    fn name(&self) -> &'static str {
        "chamfer_sq"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let (av, bv) = (ctx.value(self.a), ctx.value(self.b));
        let (n, m) = (self.nn_ab.len(), self.nn_ba.len());
        let mut da = ctx.scratch(n * 3);
        let mut db = ctx.scratch(m * 3);
        let kab = 2.0 * g[0] / n as f32;
        for (i, &k) in self.nn_ab.iter().enumerate() {
            for c in 0..3 {
                let diff = av[i * 3 + c] - bv[k * 3 + c];
                da[i * 3 + c] += kab * diff;
                db[k * 3 + c] -= kab * diff;
            }
        }
        let kba = 2.0 * g[0] / m as f32;
        for (k, &i) in self.nn_ba.iter().enumerate() {
            for c in 0..3 {
                let diff = av[i * 3 + c] - bv[k * 3 + c];
                da[i * 3 + c] += kba * diff;
                db[k * 3 + c] -= kba * diff;
            }
        }
        ctx.accumulate(self.a, &da);
        ctx.accumulate(self.b, &db);
        ctx.give(da);
        ctx.give(db);
    }
}

/// Divergence used by [`membership_consistency`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConsistencyKind {
    /// `sum_j (a_j - b_j)^2`.
    Squared,
    /// Symmetric KL (Jeffreys) divergence `sum_j (a_j - b_j)(ln a_j - ln b_j)` (probabilities
    /// clamped at 1e-8 inside the logarithms).
    SymmetricKl,
}

const P_MIN: f32 = 1e-8;

struct Consistency {
    a: Id,
    b: Id,
    j: usize,
    pairs: Vec<(usize, usize)>,
    kind: ConsistencyKind,
}

/// Mean over `pairs (i, k)` of the divergence between membership rows `a_i` and `b_k`
/// (`a [n, J]`, `b [m, J]`) -> `[1, 1]`; 0 when there are no pairs.
pub fn membership_consistency(t: &mut Tape, a: Id, b: Id, pairs: &[(usize, usize)], kind: ConsistencyKind) -> Id {
    let (n, j) = t.shape(a);
    let (m, jb) = t.shape(b);
    assert_eq!(j, jb, "membership_consistency: J differs");
    assert!(pairs.iter().all(|&(i, k)| i < n && k < m), "membership_consistency: pair out of range");
    let (av, bv) = (t.value(a), t.value(b));
    let mut s = 0.0f64;
    for &(i, k) in pairs {
        let (ra, rb) = (&av[i * j..(i + 1) * j], &bv[k * j..(k + 1) * j]);
        for (&x, &y) in ra.iter().zip(rb) {
            s += match kind {
                ConsistencyKind::Squared => ((x - y) as f64).powi(2),
                ConsistencyKind::SymmetricKl => {
                    (x - y) as f64 * ((x.max(P_MIN) as f64).ln() - (y.max(P_MIN) as f64).ln())
                }
            };
        }
    }
    let mut y = t.uninit(1);
    let v64 = if pairs.is_empty() { 0.0 } else { s / pairs.len() as f64 };
    y[0] = v64 as f32;
    let needs = !pairs.is_empty() && t.any_needs(&[a, b]);
    let id = t.push(y, 1, 1, Box::new(Consistency { a, b, j, pairs: pairs.to_vec(), kind }), needs);
    t.set_scalar64(id, v64);
    id
}

impl Op for Consistency {
    fn name(&self) -> &'static str {
        "membership_consistency"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let j = self.j;
        let (av, bv) = (ctx.value(self.a), ctx.value(self.b));
        let mut da = ctx.scratch(av.len());
        let mut db = ctx.scratch(bv.len());
        let k0 = g[0] / self.pairs.len() as f32;
        for &(i, k) in &self.pairs {
            for c in 0..j {
                let (x, y) = (av[i * j + c], bv[k * j + c]);
                let (gx, gy) = match self.kind {
                    ConsistencyKind::Squared => (2.0 * (x - y), -2.0 * (x - y)),
                    ConsistencyKind::SymmetricKl => {
                        let l = x.max(P_MIN).ln() - y.max(P_MIN).ln();
                        let gx = l + if x > P_MIN { (x - y) / x } else { 0.0 };
                        let gy = -l - if y > P_MIN { (x - y) / y } else { 0.0 };
                        (gx, gy)
                    }
                };
                da[i * j + c] += k0 * gx;
                db[k * j + c] += k0 * gy;
            }
        }
        ctx.accumulate(self.a, &da);
        ctx.accumulate(self.b, &db);
        ctx.give(da);
        ctx.give(db);
    }
}

struct MembershipKl {
    gamma: Id,
    targets: Vec<f32>,
}

/// `mean_i KL(p_i || gamma_i) = mean_i sum_j p_ij (ln p_ij - ln gamma_ij)` of membership rows
/// `gamma [n, J]` against target rows `targets` (`[n, J]`, rows summing to 1) -> `[1, 1]`
/// (`gamma` clamped at `1e-8` inside the log).
pub fn membership_kl(t: &mut Tape, gamma: Id, targets: &[f32]) -> Id {
    let (n, j) = t.shape(gamma);
    assert_eq!(targets.len(), n * j, "membership_kl: targets vs memberships");
    let g = t.value(gamma);
    let mut s = 0.0f64;
    for (&p, &q) in targets.iter().zip(g) {
        if p > 0.0 {
            s += p as f64 * ((p as f64).ln() - (q.max(P_MIN) as f64).ln());
        }
    }
    let v64 = if n == 0 { 0.0 } else { s / n as f64 };
    let mut y = t.uninit(1);
    y[0] = v64 as f32;
    let needs = n > 0 && t.needs_grad(gamma);
    let id = t.push(y, 1, 1, Box::new(MembershipKl { gamma, targets: targets.to_vec() }), needs);
    t.set_scalar64(id, v64);
    id
}

impl Op for MembershipKl {
    fn name(&self) -> &'static str {
        "membership_kl"
    }
    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let (n, _) = ctx.shape(self.gamma);
        let k = g[0] / n as f32;
        let v = ctx.value(self.gamma);
        for ((d, &q), &p) in ctx.grad(self.gamma).iter_mut().zip(v).zip(&self.targets) {
            if q > P_MIN {
                *d -= k * p / q;
            }
        }
    }
}
