//! The fused Gaussian-mixture registration op: memberships of both clouds -> GMM parameters ->
//! weighted Procrustes -> `T_target_source`, all in `f64` (exactly the engine's
//! [`crate::gmr::gmm_params`] + [`crate::gmr::solve`] path, with no `f32` rounding of the GMM in
//! between: at initialisation the memberships are nearly uniform, the component means crowd
//! around the centroid, and the rotation is very sensitive to them).

use super::gmm::Gmm64;
use super::procrustes::{Solve, SolveInput};
use crate::train::tape::{Backward, Id, Op, Tape};
use nalgebra::{Matrix3, Vector3};

struct GmrOp {
    gamma_s: Id,
    gamma_t: Id,
    gs: Gmm64,
    gt: Gmm64,
    input: SolveInput,
    solve: Solve,
}

/// `T_target_source` (`[4, 4]` row-major) from source memberships `gamma_s [N_s, J]` of
/// `source` and target memberships `gamma_t [N_t, J]` of `target` (raw coordinates).
pub fn gmr(t: &mut Tape, gamma_s: Id, gamma_t: Id, source: &[[f32; 3]], target: &[[f32; 3]]) -> Id {
    let (ns, j) = t.shape(gamma_s);
    let (nt, jt) = t.shape(gamma_t);
    assert_eq!(j, jt, "gmr: J differs");
    assert!(ns == source.len() && nt == target.len(), "gmr: points vs membership rows");
    let gs = Gmm64::new(source, t.value(gamma_s), j);
    let gt = Gmm64::new(target, t.value(gamma_t), j);
    let input = SolveInput { pi: gs.pi.clone(), mu_s: gs.mu.clone(), mu_t: gt.mu.clone(), var_t: gt.var.clone() };
    let solve = Solve::new(&input);
    let mut y = t.zeros(16);
    for r in 0..3 {
        for c in 0..3 {
            y[r * 4 + c] = solve.r[(r, c)] as f32;
        }
        y[r * 4 + 3] = solve.t[r] as f32;
    }
    y[15] = 1.0;
    let needs = t.any_needs(&[gamma_s, gamma_t]);
    t.push(y, 4, 4, Box::new(GmrOp { gamma_s, gamma_t, gs, gt, input, solve }), needs)
}

impl Op for GmrOp {
    fn name(&self) -> &'static str {
        "gmr"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let g_r = Matrix3::from_fn(|r, c| g[r * 4 + c] as f64);
        let g_t = Vector3::new(g[3] as f64, g[7] as f64, g[11] as f64);
        let gr = self.solve.backward(&self.input, &g_r, &g_t);
        if ctx.needs(self.gamma_s) {
            self.gs.backward(&gr.pi, &gr.mu_s, &[], ctx.grad(self.gamma_s));
        }
        if ctx.needs(self.gamma_t) {
            self.gt.backward(&[], &gr.mu_t, &gr.var_t, ctx.grad(self.gamma_t));
        }
    }
}
