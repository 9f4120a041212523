//! The training losses (docs/design.md §11), each behind a switch (a weight; 0 turns a term off).
//!
//! * `sup`: supervised DeepGMR loss `MSE(T_12 T_gt^-1, I) + MSE(T_21 T_gt, I)` (MSE over the 16
//!   entries).
//! * `ctr`: centroid loss on the reference points. [`CentroidMode::EveryLayer`] (deep
//!   supervision, the default) is the mean over layers `l` of
//!   `|v^_gt - sum_{k<=l} d^^k|^2 + |v_gt - sum_{k<=l} d^k|^2`; [`CentroidMode::FinalOnly`] is the
//!   paper's form (the last layer's cumulative shift only).
//! * `stp`: the paper's step penalty `eps * sum_l sigmoid(alpha^l)^2`; the weight *is* `eps`
//!   (paper: 1e-8).
//! * `aff`: `3 * MSE(T_12 T_21, I)` (cycle consistency).
//! * `reg`: squared Chamfer distance between `T_12 X^` and `X` (brute force).
//! * `consistency`: dense membership consistency. Source points whose ground-truth image
//!   `T_gt x^_i` has its nearest target point `x_k` within `consistency_radius` form pairs
//!   `(i, k)`; the term is the mean over pairs of a divergence between the membership rows
//!   `gamma^_i` and `gamma_k`. The default divergence is the symmetric KL (Jeffreys)
//!   divergence: zero only for equal rows, symmetric (both clouds learn), and sensitive to
//!   differences in small probabilities, where the squared difference is nearly blind; it has no
//!   entropy term, so it does not by itself push memberships to be confident.
//!   [`ConsistencyKind::Squared`] is the alternative. Like any agreement loss it is also
//!   minimised by constant memberships; the transform losses prevent that collapse, so use it
//!   together with `sup` (or `aff` + `reg`).
//! * `means`: GMM-means alignment under the ground truth ([`ops::alignment`]): how far each
//!   source component mean, moved by `T_gt`, lands from the target's component mean of the same
//!   index, relative to the components' spread. A dense signal on every membership about what
//!   GMR needs, without going through the 6-DoF Procrustes solve.
//! * `seg`: KL divergence of each cloud's memberships from the canonical partition of
//!   [`super::partition`] (soft cones around the ground-truth centroid, in the half-way frame
//!   of the two clouds): dense, non-degenerate supervision of the memberships themselves, which
//!   the transform losses leave nearly uniform.
//!
//! The total is `sum weight_k * L_k`. Terms with weight 0 are not computed, except the cheap
//! `sup`, `ctr`, `aff` and `means`, which are always reported for monitoring (with the
//! membership-row entropy).
//!
//! Gradient balance at initialisation (web config, N = 256, measured by the
//! `gradient_norms_at_init` diagnostic in tests/train_bench.rs): `sup` gives a gradient norm of
//! about 7, `reg` 0.7, `ctr` 0.07, `consistency` 2e-3 and `aff` 4e-5 (at initialisation
//! `T_12 T_21` is already close to I, and memberships are nearly uniform so the consistency
//! divergence is nearly 0). The step MLPs get ~1e-5 from `sup` and ~4e-4 from `ctr`. With
//! global-norm clipping the transform loss therefore dominates early; weigh `ctr` up (or clip
//! per term) if shifting should learn from the start. With the soft reference, uniform weights
//! put the reference point exactly at the (pre-centred) origin, so `d ctr / d s` starts near 0
//! and the first signal reaches the score heads.

use super::model::{from_matrix, Forward};
use super::ops::{self, ConsistencyKind};
use super::pair::Pair;
use super::partition::{self, Role};
use super::tape::{Id, Tape};
use crate::transform::{mapping, rigid_inverse};
use serde::{Deserialize, Serialize};

/// Which reference points the centroid loss supervises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CentroidMode {
    /// Every layer's cumulative shift (mean over layers).
    EveryLayer,
    /// Only the final cumulative shift (the paper).
    FinalOnly,
}

/// Weights of the loss terms (0 = off) and their options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LossConfig {
    /// Supervised DeepGMR transform loss.
    pub sup: f32,
    /// Centroid loss.
    pub ctr: f32,
    /// Which layers the centroid loss supervises.
    pub ctr_mode: CentroidMode,
    /// Step penalty coefficient epsilon.
    pub stp: f32,
    /// Affine (cycle) loss.
    pub aff: f32,
    /// Registration (squared Chamfer) loss.
    pub reg: f32,
    /// Dense membership-consistency loss.
    pub consistency: f32,
    /// Radius (normalised units) within which a GT-mapped source point and its nearest target
    /// point count as corresponding.
    pub consistency_radius: f32,
    /// Divergence of the consistency loss.
    pub consistency_kind: ConsistencyKind,
    /// GMM-means alignment loss (absent in checkpoints written before it existed: 0).
    #[serde(default)]
    pub means: f32,
    /// Canonical-partition loss (absent in older checkpoints: 0).
    #[serde(default)]
    pub seg: f32,
    /// Concentration `kappa` of the partition's soft cones (larger = sharper targets).
    #[serde(default = "default_seg_kappa")]
    pub seg_kappa: f32,
}

fn default_seg_kappa() -> f32 {
    8.0
}

impl Default for LossConfig {
    /// docs/design.md §11's starting point: supervised transform loss + centroid loss on every layer
    /// (+ the paper's negligible step penalty).
    fn default() -> Self {
        Self {
            sup: 1.0,
            ctr: 1.0,
            ctr_mode: CentroidMode::EveryLayer,
            stp: 1e-8,
            aff: 0.0,
            reg: 0.0,
            consistency: 0.0,
            consistency_radius: 0.05,
            consistency_kind: ConsistencyKind::SymmetricKl,
            means: 0.0,
            seg: 0.0,
            seg_kappa: default_seg_kappa(),
        }
    }
}

impl LossConfig {
    /// The paper's unsupervised-transform recipe: `L_aff + L_reg + L_ctr (final layer) + L_stp`.
    pub fn paper() -> Self {
        Self { sup: 0.0, ctr: 1.0, ctr_mode: CentroidMode::FinalOnly, stp: 1e-8, aff: 1.0, reg: 1.0, ..Self::default() }
    }
}

/// Values of the loss terms (unweighted) for one pair, or averaged over a batch.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LossParts {
    /// The weighted total that was differentiated.
    pub total: f64,
    /// Supervised transform loss (always computed).
    pub sup: f64,
    /// Centroid loss (always computed, in the configured mode).
    pub ctr: f64,
    /// The centroid loss's value with no shifting at all (`|v^_gt|^2 + |v_gt|^2`): compare
    /// with `ctr` to see whether shifting is alive.
    pub ctr_no_shift: f64,
    /// `sum_l sigmoid(alpha^l)^2` (before the epsilon).
    pub stp: f64,
    /// Affine loss (always computed).
    pub aff: f64,
    /// Registration loss (0 when off).
    pub reg: f64,
    /// Consistency loss (0 when off).
    pub consistency: f64,
    /// Number of corresponding point pairs the consistency loss used.
    pub consistency_pairs: f64,
    /// GMM-means alignment loss (always computed, for monitoring).
    pub means: f64,
    /// The component spread `S` of the alignment loss (squared normalised units): near 0 when
    /// the memberships are nearly uniform.
    pub means_spread: f64,
    /// Mean membership-row entropy over both clouds, divided by `ln J` (1 = uniform rows).
    pub gamma_entropy: f64,
    /// Canonical-partition KL (0 when off), mean of the two clouds.
    pub seg: f64,
    /// Step sizes per layer.
    pub steps: Vec<f64>,
}

impl LossParts {
    /// Element-wise mean of several parts (steps averaged per layer).
    pub fn mean(parts: &[LossParts]) -> LossParts {
        let n = parts.len().max(1) as f64;
        let mut m = LossParts::default();
        let layers = parts.iter().map(|p| p.steps.len()).max().unwrap_or(0);
        m.steps = vec![0.0; layers];
        for p in parts {
            m.total += p.total / n;
            m.sup += p.sup / n;
            m.ctr += p.ctr / n;
            m.ctr_no_shift += p.ctr_no_shift / n;
            m.stp += p.stp / n;
            m.aff += p.aff / n;
            m.reg += p.reg / n;
            m.consistency += p.consistency / n;
            m.consistency_pairs += p.consistency_pairs / n;
            m.means += p.means / n;
            m.means_spread += p.means_spread / n;
            m.gamma_entropy += p.gamma_entropy / n;
            m.seg += p.seg / n;
            for (a, b) in m.steps.iter_mut().zip(&p.steps) {
                *a += b / n;
            }
        }
        m
    }

    /// Whether every value is finite.
    pub fn is_finite(&self) -> bool {
        [self.total, self.sup, self.ctr, self.stp, self.aff, self.reg, self.consistency, self.means, self.seg]
            .iter()
            .all(|v| v.is_finite())
    }
}

const IDENTITY: [f32; 16] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];

/// Corresponding point pairs `(i, k)` for the consistency loss: `k` is the nearest target point
/// to `T_gt source[i]`, kept when closer than `radius` (brute force).
pub fn correspondences(pair: &Pair, radius: f32) -> Vec<(usize, usize)> {
    let r2 = radius * radius;
    let mut out = Vec::new();
    let to_target = mapping(&pair.t_gt);
    for (i, p) in pair.source.iter().enumerate() {
        let q = to_target(*p);
        let mut best = (f32::INFINITY, 0usize);
        for (k, x) in pair.target.iter().enumerate() {
            let d = (q[0] - x[0]).powi(2) + (q[1] - x[1]).powi(2) + (q[2] - x[2]).powi(2);
            if d < best.0 {
                best = (d, k);
            }
        }
        if best.0 < r2 {
            out.push((i, best.1));
        }
    }
    out
}

/// Records the losses of one pair after [`super::model::forward`]; returns the total node and
/// the term values.
pub fn record(t: &mut Tape, fwd: &Forward, pair: &Pair, cfg: &LossConfig) -> (Id, LossParts) {
    let mut parts = LossParts::default();
    let mut terms: Vec<(Id, f32)> = Vec::new();
    // supervised transform loss
    let gt = t.constant(&from_matrix(&pair.t_gt), 4, 4);
    let gt_inv = t.constant(&from_matrix(&rigid_inverse(&pair.t_gt)), 4, 4);
    let a = ops::matmul(t, fwd.t12, gt_inv);
    let b = ops::matmul(t, fwd.t21, gt);
    let la = ops::sq_err(t, a, &IDENTITY, 1.0 / 16.0);
    let lb = ops::sq_err(t, b, &IDENTITY, 1.0 / 16.0);
    let sup = ops::weighted_total(t, &[(la, 1.0), (lb, 1.0)]);
    parts.sup = t.scalar64(sup);
    if cfg.sup != 0.0 {
        terms.push((sup, cfg.sup));
    }
    // centroid loss
    let layers = fwd.shifts_source.len();
    let mut ctr_terms = Vec::new();
    for (shifts, v) in [(&fwd.shifts_source, pair.v_gt_source), (&fwd.shifts_target, pair.v_gt_target)] {
        parts.ctr_no_shift += v.iter().map(|x| (*x as f64).powi(2)).sum::<f64>();
        let mut cum: Option<Id> = None;
        for (l, &d) in shifts.iter().enumerate() {
            let c = match cum {
                None => d,
                Some(prev) => ops::add(t, prev, d),
            };
            cum = Some(c);
            let last = l + 1 == layers;
            match cfg.ctr_mode {
                CentroidMode::EveryLayer => ctr_terms.push((ops::sq_err(t, c, &v, 1.0), 1.0 / layers as f32)),
                CentroidMode::FinalOnly if last => ctr_terms.push((ops::sq_err(t, c, &v, 1.0), 1.0)),
                CentroidMode::FinalOnly => {}
            }
        }
    }
    if !ctr_terms.is_empty() {
        let ctr = ops::weighted_total(t, &ctr_terms);
        parts.ctr = t.scalar64(ctr);
        if cfg.ctr != 0.0 {
            terms.push((ctr, cfg.ctr));
        }
    }
    // step penalty
    let sq: Vec<(Id, f32)> = fwd.steps.iter().map(|&s| (ops::sq_err(t, s, &[0.0], 1.0), 1.0)).collect();
    parts.steps = fwd.steps.iter().map(|&s| t.scalar(s) as f64).collect();
    if !sq.is_empty() {
        let stp = ops::weighted_total(t, &sq);
        parts.stp = t.scalar64(stp);
        if cfg.stp != 0.0 {
            terms.push((stp, cfg.stp));
        }
    }
    // affine (cycle) loss
    let cyc = ops::matmul(t, fwd.t12, fwd.t21);
    let aff = ops::sq_err(t, cyc, &IDENTITY, 3.0 / 16.0);
    parts.aff = t.scalar64(aff);
    if cfg.aff != 0.0 {
        terms.push((aff, cfg.aff));
    }
    // registration (Chamfer) loss
    if cfg.reg != 0.0 {
        let src: Vec<f32> = pair.source.iter().flatten().copied().collect();
        let tgt: Vec<f32> = pair.target.iter().flatten().copied().collect();
        let s = t.constant(&src, pair.source.len(), 3);
        let x = t.constant(&tgt, pair.target.len(), 3);
        let moved = ops::transform_points(t, fwd.t12, s);
        let reg = ops::chamfer_sq(t, moved, x);
        parts.reg = t.scalar64(reg);
        terms.push((reg, cfg.reg));
    }
    // dense membership consistency
    if cfg.consistency != 0.0 {
        let pairs = correspondences(pair, cfg.consistency_radius);
        parts.consistency_pairs = pairs.len() as f64;
        let c = ops::membership_consistency(t, fwd.gamma_source, fwd.gamma_target, &pairs, cfg.consistency_kind);
        parts.consistency = t.scalar64(c);
        terms.push((c, cfg.consistency));
    }
    // GMM-means alignment (cheap: always computed for monitoring)
    let (means, mp) =
        ops::means_alignment(t, fwd.gamma_source, fwd.gamma_target, &pair.source, &pair.target, &pair.t_gt);
    parts.means = mp.loss;
    parts.means_spread = mp.spread;
    if cfg.means != 0.0 {
        terms.push((means, cfg.means));
    }
    // canonical partition
    if cfg.seg != 0.0 {
        let j = t.shape(fwd.gamma_source).1;
        let mut kls = Vec::new();
        for (gamma, points, centroid, role) in [
            (fwd.gamma_source, &pair.source, pair.source_centroid(), Role::Source),
            (fwd.gamma_target, &pair.target, pair.target_centroid(), Role::Target),
        ] {
            let p = partition::targets(points, centroid, &pair.t_gt, role, j, cfg.seg_kappa as f64);
            kls.push((ops::membership_kl(t, gamma, &p), 0.5));
        }
        let seg = ops::weighted_total(t, &kls);
        parts.seg = t.scalar64(seg);
        terms.push((seg, cfg.seg));
    }
    parts.gamma_entropy = 0.5
        * (row_entropy(t.value(fwd.gamma_source), t.shape(fwd.gamma_source).1)
            + row_entropy(t.value(fwd.gamma_target), t.shape(fwd.gamma_target).1));
    let total = ops::weighted_total(t, &terms);
    parts.total = t.scalar64(total);
    (total, parts)
}

/// Mean entropy of the rows of `gamma` (`[n, j]`, rows summing to 1), divided by `ln j`.
fn row_entropy(gamma: &[f32], j: usize) -> f64 {
    if j < 2 || gamma.is_empty() {
        return 0.0;
    }
    let h: f64 = gamma.iter().filter(|&&p| p > 0.0).map(|&p| -(p as f64) * (p as f64).ln()).sum();
    h / (gamma.len() / j) as f64 / (j as f64).ln()
}
