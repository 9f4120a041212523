//! GMM-means alignment under the ground truth: the dense loss on what GMR actually consumes.
//!
//! GMR (docs/design.md §5.2) recovers `T` exactly when every source component mean, moved by the
//! true transform, lands on the target component mean with the same index. This op measures
//! how far that is from true, relative to how spread out the components are:
//!
//! ```text
//! d_j = R_gt mu^_j + t_gt - mu_j
//! A   = sum_j w_j |d_j|^2                                    (misalignment)
//! S   = 1/2 sum_j w_j (|mu^_j - c^|^2 + |mu_j - c|^2)       (spread; c^, c: w-weighted centres)
//! L   = A / (S + S0)
//! ```
//!
//! with `w_j = (pi^_j + pi_j) / 2` (differentiated too: giving little mass to components that
//! cannot be matched, e.g. on a part only one crop sees, is also what GMR needs) and the floor
//! `S0` ([`SPREAD_FLOOR`]) keeping near-uniform memberships (all means at the centroid) finite. Every membership gets a gradient through the
//! means, unlike the transform losses, which reach the memberships only through the 6 degrees
//! of freedom of the Procrustes solve. Dividing by the spread makes the loss scale-free and
//! rewards well-separated components, which is what makes the Procrustes solve well
//! conditioned; crowding every mean at the centroid does not minimise it because the partial
//! crops' centroids differ.

use super::gmm::Gmm64;
use crate::train::tape::{Backward, Id, Op, Tape};
use nalgebra::{Matrix3, Matrix4, Vector3};

/// `S0`, in squared normalised units (a component spread of 0.1 in clouds of half-extent 1).
pub const SPREAD_FLOOR: f64 = 0.01;

struct MeansAlignment {
    gamma_s: Id,
    gamma_t: Id,
    gs: Gmm64,
    gt: Gmm64,
    /// `dL/dmu^_j` and `dL/dmu_j` for an upstream gradient of 1.
    g_mu_s: Vec<[f64; 3]>,
    g_mu_t: Vec<[f64; 3]>,
    /// `dL/dpi^_j` (= `dL/dpi_j`) for an upstream gradient of 1.
    g_pi: Vec<f64>,
}

/// `L`, its parts and its gradients with respect to the GMM parameters.
struct Evaluated {
    parts: AlignmentParts,
    g_mu_s: Vec<[f64; 3]>,
    g_mu_t: Vec<[f64; 3]>,
    g_pi: Vec<f64>,
}

/// Values of the alignment loss's parts (for logging).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AlignmentParts {
    /// `L = A / (S + S0)`.
    pub loss: f64,
    /// The misalignment `A` (squared normalised units).
    pub misalignment: f64,
    /// The spread `S` (squared normalised units).
    pub spread: f64,
}

/// Computes `L`, its parts, and its gradients for both GMMs.
fn evaluate(gs: &Gmm64, gt: &Gmm64, t_gt: &Matrix4<f64>) -> Evaluated {
    let j = gs.pi.len();
    let r: Matrix3<f64> = t_gt.fixed_view::<3, 3>(0, 0).into_owned();
    let tr = Vector3::new(t_gt[(0, 3)], t_gt[(1, 3)], t_gt[(2, 3)]);
    let w: Vec<f64> = (0..j).map(|k| 0.5 * (gs.pi[k] + gt.pi[k])).collect();
    let wsum: f64 = w.iter().sum::<f64>().max(1e-12);
    let v = |m: &[f64; 3]| Vector3::new(m[0], m[1], m[2]);
    let ms: Vec<Vector3<f64>> = gs.mu.iter().map(v).collect();
    let mt: Vec<Vector3<f64>> = gt.mu.iter().map(v).collect();
    let cs = ms.iter().zip(&w).map(|(m, &wk)| m * wk).sum::<Vector3<f64>>() / wsum;
    let ct = mt.iter().zip(&w).map(|(m, &wk)| m * wk).sum::<Vector3<f64>>() / wsum;
    let d: Vec<Vector3<f64>> = (0..j).map(|k| r * ms[k] + tr - mt[k]).collect();
    let a: f64 = (0..j).map(|k| w[k] * d[k].norm_squared()).sum();
    let s: f64 = 0.5 * (0..j).map(|k| w[k] * ((ms[k] - cs).norm_squared() + (mt[k] - ct).norm_squared())).sum::<f64>();
    let den = s + SPREAD_FLOOR;
    let loss = a / den;
    // The centres are w-weighted means, so sum_k w_k (mu_k - c) = 0 and their own dependence on
    // mu_j and w_j drops out of dS: dS/dmu_j = w_j (mu_j - c),
    // dS/dw_j = (|mu^_j - c^|^2 + |mu_j - c|^2) / 2.
    let k_s = a / (den * den);
    let mut g_s = vec![[0.0; 3]; j];
    let mut g_t = vec![[0.0; 3]; j];
    let mut g_pi = vec![0.0; j];
    for k in 0..j {
        let gs_k = r.transpose() * d[k] * (2.0 * w[k] / den) - (ms[k] - cs) * (k_s * w[k]);
        let gt_k = -d[k] * (2.0 * w[k] / den) - (mt[k] - ct) * (k_s * w[k]);
        g_s[k] = [gs_k.x, gs_k.y, gs_k.z];
        g_t[k] = [gt_k.x, gt_k.y, gt_k.z];
        let ds_dw = 0.5 * ((ms[k] - cs).norm_squared() + (mt[k] - ct).norm_squared());
        let dl_dw = d[k].norm_squared() / den - k_s * ds_dw;
        g_pi[k] = 0.5 * dl_dw;
    }
    Evaluated { parts: AlignmentParts { loss, misalignment: a, spread: s }, g_mu_s: g_s, g_mu_t: g_t, g_pi }
}

/// The means-alignment loss (module docs) of source memberships `gamma_s [N_s, J]` over
/// `source` and target memberships `gamma_t [N_t, J]` over `target` (raw normalised
/// coordinates) under `t_gt` (`T_target_source`) -> `[1, 1]`, plus its parts.
pub fn means_alignment(
    t: &mut Tape,
    gamma_s: Id,
    gamma_t: Id,
    source: &[[f32; 3]],
    target: &[[f32; 3]],
    t_gt: &Matrix4<f64>,
) -> (Id, AlignmentParts) {
    let (ns, j) = t.shape(gamma_s);
    let (nt, jt) = t.shape(gamma_t);
    assert_eq!(j, jt, "means_alignment: J differs");
    assert!(ns == source.len() && nt == target.len(), "means_alignment: points vs membership rows");
    let gs = Gmm64::new(source, t.value(gamma_s), j);
    let gt = Gmm64::new(target, t.value(gamma_t), j);
    let Evaluated { parts, g_mu_s, g_mu_t, g_pi } = evaluate(&gs, &gt, t_gt);
    let mut y = t.uninit(1);
    y[0] = parts.loss as f32;
    let needs = t.any_needs(&[gamma_s, gamma_t]);
    let id = t.push(y, 1, 1, Box::new(MeansAlignment { gamma_s, gamma_t, gs, gt, g_mu_s, g_mu_t, g_pi }), needs);
    t.set_scalar64(id, parts.loss);
    (id, parts)
}

impl Op for MeansAlignment {
    fn name(&self) -> &'static str {
        "means_alignment"
    }

    fn backward(&self, ctx: &mut Backward<'_>, _out: Id, g: &[f32]) {
        let k = g[0] as f64;
        let scale = |v: &[[f64; 3]]| -> Vec<[f64; 3]> { v.iter().map(|m| m.map(|x| x * k)).collect() };
        let g_pi: Vec<f64> = self.g_pi.iter().map(|x| x * k).collect();
        if ctx.needs(self.gamma_s) {
            self.gs.backward(&g_pi, &scale(&self.g_mu_s), &[], ctx.grad(self.gamma_s));
        }
        if ctx.needs(self.gamma_t) {
            self.gt.backward(&g_pi, &scale(&self.g_mu_t), &[], ctx.grad(self.gamma_t));
        }
    }
}
