#![cfg(feature = "train")]
#![allow(clippy::cloned_ref_to_slice_refs)]
//! Every op's backward against central finite differences, the f64 Procrustes solve near
//! degenerate singular values, and the whole model + losses on the tiny config.

use arps::model::{ModelConfig, Reference};
use arps::train::ops::{
    self,
    procrustes::{Solve, SolveInput},
    ConsistencyKind,
};
use arps::train::{self, losses, synthetic, CentroidMode, Id, LossConfig, Tape};
use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn randv(r: &mut ChaCha8Rng, n: usize, s: f32) -> Vec<f32> {
    (0..n).map(|_| r.random_range(-s..s)).collect()
}

/// Checks `build`'s backward for every element of every input against central differences of
/// `sum_k proj_k out_k` (accumulated in f64). Inputs are parameter leaves of the given shapes.
fn check<F>(what: &str, inputs: &[(Vec<f32>, usize, usize)], h: f32, tol: f64, build: F)
where
    F: Fn(&mut Tape, &[Id]) -> Id,
{
    let mut r = rng(99);
    let mut t = Tape::new();
    let ids: Vec<Id> = inputs.iter().map(|(v, a, b)| t.param(v, *a, *b)).collect();
    let out = build(&mut t, &ids);
    let n_out = t.value(out).len();
    let proj: Vec<f32> = randv(&mut r, n_out, 1.0);
    t.backward_seeded(out, &proj);
    let analytic: Vec<Vec<f32>> =
        ids.iter().zip(inputs).map(|(&id, (v, _, _))| t.grad(id).map_or(vec![0.0; v.len()], |g| g.to_vec())).collect();
    let eval = |vals: &[Vec<f32>]| -> f64 {
        let mut t = Tape::new();
        let ids: Vec<Id> = vals.iter().zip(inputs).map(|(v, (_, a, b))| t.param(v, *a, *b)).collect();
        let out = build(&mut t, &ids);
        t.value(out).iter().zip(&proj).map(|(&a, &b)| a as f64 * b as f64).sum()
    };
    let scale = analytic.iter().flatten().map(|g| g.abs() as f64).fold(0.0, f64::max).max(1e-3);
    // rounding noise of the f32 outputs in a central difference
    let mag: f64 = t.value(out).iter().zip(&proj).map(|(&a, &b)| (a as f64 * b as f64).abs()).sum();
    let noise = 4.0 * f32::EPSILON as f64 * mag / h as f64;
    let mut worst = 0.0f64;
    for (k, (v, _, _)) in inputs.iter().enumerate() {
        for i in 0..v.len() {
            let mut vals: Vec<Vec<f32>> = inputs.iter().map(|x| x.0.clone()).collect();
            vals[k][i] = v[i] + h;
            let fp = eval(&vals);
            vals[k][i] = v[i] - h;
            let fm = eval(&vals);
            let num = (fp - fm) / (2.0 * h as f64);
            let ana = analytic[k][i] as f64;
            let err = ((num - ana).abs() - noise).max(0.0) / (num.abs().max(ana.abs()) + 1e-2 * scale);
            worst = worst.max(err);
            assert!(
                err < tol,
                "{what}: input {k} element {i}: analytic {ana:.6e} vs numeric {num:.6e} (rel err {err:.2e})"
            );
        }
    }
    eprintln!("{what}: worst rel err {worst:.2e}");
}

#[test]
fn elementwise_and_reductions() {
    let mut r = rng(1);
    let a = (randv(&mut r, 12, 1.0), 3, 4);
    let b = (randv(&mut r, 12, 1.0), 3, 4);
    let s = (vec![0.7f32], 1, 1);
    let row = (randv(&mut r, 4, 1.0), 1, 4);
    check("add", &[a.clone(), b.clone()], 1e-2, 1e-3, |t, x| ops::add(t, x[0], x[1]));
    check("sub", &[a.clone(), b.clone()], 1e-2, 1e-3, |t, x| ops::sub(t, x[0], x[1]));
    check("scale", &[a.clone()], 1e-2, 1e-3, |t, x| ops::scale(t, x[0], -1.7));
    check("relu", &[a.clone()], 1e-3, 1e-3, |t, x| ops::relu(t, x[0]));
    check("sigmoid", &[a.clone()], 1e-2, 1e-3, |t, x| ops::sigmoid(t, x[0]));
    check("mul_scalar", &[a.clone(), s], 1e-2, 1e-3, |t, x| ops::mul_scalar(t, x[0], x[1]));
    check("sub_row", &[a.clone(), row], 1e-2, 1e-3, |t, x| ops::sub_row(t, x[0], x[1]));
    check("concat_cols", &[a.clone(), (randv(&mut r, 6, 1.0), 3, 2)], 1e-2, 1e-3, |t, x| {
        ops::concat_cols(t, x[0], x[1])
    });
    check("concat_colmax", &[(randv(&mut r, 15, 1.0), 5, 3)], 1e-3, 1e-3, |t, x| ops::concat_colmax(t, x[0]));
    check("weighted_sum", &[(randv(&mut r, 5, 1.0), 1, 5), (randv(&mut r, 15, 1.0), 5, 3)], 1e-2, 1e-3, |t, x| {
        ops::weighted_sum(t, x[0], x[1])
    });
    check("mean_all", &[a.clone()], 1e-2, 1e-3, |t, x| ops::mean_all(t, x[0]));
    check("reshape", &[a.clone()], 1e-2, 1e-3, |t, x| ops::reshape(t, x[0], 2, 6));
    check("weighted_total", &[(vec![0.3], 1, 1), (vec![-1.2], 1, 1)], 1e-2, 1e-3, |t, x| {
        ops::weighted_total(t, &[(x[0], 2.0), (x[1], -0.5)])
    });
    check("softmax_rows", &[a.clone()], 1e-2, 1e-3, |t, x| ops::softmax_rows(t, x[0]));
    check("sq_err", &[a], 1e-2, 1e-3, |t, x| ops::sq_err(t, x[0], &[0.5; 12], 0.3));
}

#[test]
fn linear_layernorm_attention() {
    let mut r = rng(2);
    let x = (randv(&mut r, 5 * 6, 1.0), 5, 6);
    let w = (randv(&mut r, 4 * 6, 0.5), 4, 6);
    let b = (randv(&mut r, 4, 0.5), 1, 4);
    check("linear", &[x.clone(), w.clone(), b], 1e-2, 1e-3, |t, v| ops::linear(t, v[0], v[1], Some(v[2])));
    check("linear (no bias)", &[x.clone(), w], 1e-2, 1e-3, |t, v| ops::linear(t, v[0], v[1], None));
    let g = (randv(&mut r, 6, 1.0).iter().map(|v| 1.0 + v).collect(), 1, 6);
    let be = (randv(&mut r, 6, 0.5), 1, 6);
    check("layer_norm", &[x.clone(), g, be], 1e-2, 2e-3, |t, v| ops::layer_norm(t, v[0], v[1], v[2], 1e-5));
    // cross attention: 5 queries, 7 keys, width 8, 2 heads
    let q = (randv(&mut r, 5 * 8, 1.0), 5, 8);
    let k = (randv(&mut r, 7 * 8, 1.0), 7, 8);
    let v = (randv(&mut r, 7 * 8, 1.0), 7, 8);
    check("attention", &[q.clone(), k, v], 1e-2, 1e-3, |t, x| ops::attention(t, x[0], x[1], x[2], 2));
    // self attention with the same node as q, k and v
    check("attention (self, shared input)", &[q], 1e-2, 1e-3, |t, x| ops::attention(t, x[0], x[0], x[0], 4));
}

fn memberships(r: &mut ChaCha8Rng, n: usize, j: usize) -> Vec<f32> {
    let mut g = randv(r, n * j, 2.0);
    arps::nn::softmax_rows_inplace(&mut g, j);
    g
}

#[test]
fn gmm_procrustes_rigid_losses() {
    let mut r = rng(3);
    let (n, j) = (20, 4);
    let pts: Vec<[f32; 3]> =
        (0..n).map(|_| [r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(-1.0..1.0)]).collect();
    let gam = memberships(&mut r, n, j);
    let p2 = pts.clone();
    check("gmm_params", &[(gam.clone(), n, j)], 1e-2, 1e-3, move |t, x| ops::gmm_params(t, x[0], &p2));
    // procrustes on GMM-like inputs: pi > 0, var > 0
    let gm = |r: &mut ChaCha8Rng| -> Vec<f32> {
        (0..j)
            .flat_map(|_| {
                [
                    r.random_range(0.1f32..0.4),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(0.2f32..0.6),
                ]
            })
            .collect()
    };
    let (gs, gt) = (gm(&mut r), gm(&mut r));
    check("procrustes", &[(gs, j, 5), (gt, j, 5)], 1e-3, 5e-3, |t, x| ops::procrustes(t, x[0], x[1]));
    // full chain gamma -> GMM -> T
    let p3 = pts.clone();
    let pts_t: Vec<[f32; 3]> = pts.iter().map(|p| [p[1] + 0.1, -p[0], p[2] * 0.9]).collect();
    let gam_t = memberships(&mut r, n, j);
    check("gmm -> procrustes", &[(gam, n, j), (gam_t, n, j)], 1e-3, 5e-3, move |t, x| {
        let a = ops::gmm_params(t, x[0], &p3);
        let b = ops::gmm_params(t, x[1], &pts_t);
        ops::procrustes(t, a, b)
    });
    // rigid algebra
    let rot = arps::transform::euler_xyz(0.3, -0.2, 0.5);
    let m = arps::transform::from_rotation_translation(&rot, &Vector3::new(0.1, -0.3, 0.2));
    let mv = train::model::from_matrix(&m).to_vec();
    let m2 = randv(&mut r, 16, 1.0);
    check("matmul", &[(mv.clone(), 4, 4), (m2, 4, 4)], 1e-2, 1e-3, |t, x| ops::matmul(t, x[0], x[1]));
    check("rigid_inverse", &[(mv.clone(), 4, 4)], 1e-2, 1e-3, |t, x| ops::rigid_inverse(t, x[0]));
    let p = randv(&mut r, 18, 1.0);
    check("transform_points", &[(mv, 4, 4), (p.clone(), 6, 3)], 1e-2, 1e-3, |t, x| {
        ops::transform_points(t, x[0], x[1])
    });
    check("chamfer_sq", &[(p, 6, 3), (randv(&mut r, 24, 1.0), 8, 3)], 1e-3, 1e-3, |t, x| {
        ops::chamfer_sq(t, x[0], x[1])
    });
    // GMM-means alignment under a known transform (gradients through the means and the weights)
    let p4 = pts.clone();
    let gt_m = arps::transform::from_rotation_translation(
        &arps::transform::euler_xyz(0.2, 0.4, -0.3),
        &Vector3::new(0.2, -0.1, 0.3),
    );
    let pts_m: Vec<[f32; 3]> = pts.iter().map(|p| [p[2] * 0.8, p[0] + 0.2, -p[1]]).collect();
    let (ga4, gb4) = (memberships(&mut r, n, j), memberships(&mut r, n, j));
    check("means_alignment", &[(ga4, n, j), (gb4, n, j)], 1e-3, 2e-3, move |t, x| {
        ops::means_alignment(t, x[0], x[1], &p4, &pts_m, &gt_m).0
    });
    let (gk, pk) = (memberships(&mut r, 7, j), memberships(&mut r, 7, j));
    check("membership_kl", &[(gk, 7, j)], 1e-3, 1e-3, move |t, x| ops::membership_kl(t, x[0], &pk));
    let (ga, gb) = (memberships(&mut r, 5, j), memberships(&mut r, 6, j));
    let pairs = [(0, 1), (2, 2), (4, 5), (3, 0)];
    for kind in [ConsistencyKind::Squared, ConsistencyKind::SymmetricKl] {
        check(&format!("consistency {kind:?}"), &[(ga.clone(), 5, j), (gb.clone(), 6, j)], 1e-3, 1e-3, |t, x| {
            ops::membership_consistency(t, x[0], x[1], &pairs, kind)
        });
    }
}

/// Central differences of the f64 solve for every input, against `Solve::backward`.
fn check_solve(what: &str, x: &SolveInput, tol: f64) {
    let mut r = rng(5);
    let gr = Matrix3::from_fn(|_, _| r.random_range(-1.0..1.0));
    let gt = Vector3::new(r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(-1.0..1.0));
    let f = |x: &SolveInput| {
        let s = Solve::new(x);
        s.r.component_mul(&gr).sum() + s.t.dot(&gt)
    };
    let g = Solve::new(x).backward(x, &gr, &gt);
    let gmax =
        g.pi.iter()
            .chain(&g.var_t)
            .chain(g.mu_s.iter().flatten())
            .chain(g.mu_t.iter().flatten())
            .fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-6;
    let mut worst = 0.0f64;
    let mut cmp = |ana: f64, plus: SolveInput, minus: SolveInput, label: String| {
        let num = (f(&plus) - f(&minus)) / (2.0 * h);
        let err = (num - ana).abs() / (num.abs().max(ana.abs()) + 1e-4 * gmax);
        worst = worst.max(err);
        assert!(err < tol, "{what} {label}: analytic {ana:.8e} vs numeric {num:.8e} (rel err {err:.2e})");
    };
    for k in 0..x.pi.len() {
        let (mut p, mut m) = (x.clone(), x.clone());
        p.pi[k] += h;
        m.pi[k] -= h;
        cmp(g.pi[k], p, m, format!("pi[{k}]"));
        let (mut p, mut m) = (x.clone(), x.clone());
        p.var_t[k] += h;
        m.var_t[k] -= h;
        cmp(g.var_t[k], p, m, format!("var[{k}]"));
        for a in 0..3 {
            let (mut p, mut m) = (x.clone(), x.clone());
            p.mu_s[k][a] += h;
            m.mu_s[k][a] -= h;
            cmp(g.mu_s[k][a], p, m, format!("mu_s[{k}][{a}]"));
            let (mut p, mut m) = (x.clone(), x.clone());
            p.mu_t[k][a] += h;
            m.mu_t[k][a] -= h;
            cmp(g.mu_t[k][a], p, m, format!("mu_t[{k}][{a}]"));
        }
    }
    eprintln!("{what}: worst rel err {worst:.2e}");
}

/// Six components at +-sigma_a e_a (so the weighted source covariance is diag(sigma^2) / 3),
/// mapped to the target by `Q`, plus a small random perturbation: `M`'s singular values are
/// close to `sigma^2 / 3` (times the variances) and the reflection fix is active when `det Q < 0`.
fn solve_input(sig2: [f64; 3], q: Matrix3<f64>, seed: u64) -> SolveInput {
    let mut r = rng(seed);
    let mut x = SolveInput { pi: vec![], mu_s: vec![], mu_t: vec![], var_t: vec![] };
    for a in 0..3 {
        for sign in [1.0, -1.0] {
            let mut v = Vector3::zeros();
            v[a] = sign * sig2[a].sqrt();
            let w = q * v + Vector3::new(0.3, -0.1, 0.2);
            let jit = |r: &mut ChaCha8Rng| r.random_range(-1e-4..1e-4);
            x.pi.push(1.0 / 6.0 + jit(&mut r));
            x.mu_s.push([v.x + jit(&mut r), v.y + jit(&mut r), v.z + jit(&mut r)]);
            x.mu_t.push([w.x + jit(&mut r), w.y + jit(&mut r), w.z + jit(&mut r)]);
            x.var_t.push(0.5 + jit(&mut r));
        }
    }
    x
}

#[test]
fn procrustes_f64_including_near_degenerate() {
    let rot = arps::transform::euler_xyz(0.4, -0.3, 0.7);
    let mut flip = Matrix3::identity();
    flip[(2, 2)] = -1.0;
    // generic, well separated
    check_solve("generic", &solve_input([1.0, 0.5, 0.2], rot, 1), 1e-5);
    // s2 ~ s3 (gap ~1e-3 relative), no reflection: denominators s2 + s3, harmless
    check_solve("s2 ~ s3", &solve_input([1.0, 0.5, 0.5005], rot, 2), 1e-5);
    // s1 ~ s2 ~ s3 (near-isotropic)
    check_solve("s1 ~ s2 ~ s3", &solve_input([0.5, 0.501, 0.502], rot, 3), 1e-5);
    // reflection fix active, s2 - s3 small (1e-2): the one genuinely ill-conditioned direction
    check_solve("reflection, s2 - s3 = 1e-2", &solve_input([1.0, 0.5, 0.49], rot * flip, 4), 1e-4);
    // random GMM-like input
    let mut r = rng(6);
    let x = SolveInput {
        pi: (0..5).map(|_| r.random_range(0.05..0.4)).collect(),
        mu_s: (0..5)
            .map(|_| [r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(-1.0..1.0)])
            .collect(),
        mu_t: (0..5)
            .map(|_| [r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(-1.0..1.0)])
            .collect(),
        var_t: (0..5).map(|_| r.random_range(0.1..0.5)).collect(),
    };
    check_solve("random", &x, 1e-5);
}

/// Directional derivatives of the whole model + all losses, per parameter tensor, against
/// central differences in random directions over a few random elements of each tensor.
///
/// The tape is `f32` and the network is only piecewise smooth (ReLU kinks, the head's max, the
/// Chamfer nearest neighbours, the top-H selection), so a finite difference is trusted only
/// where it is consistent: the differences at `h` and `h/2` must agree (otherwise a kink lies in
/// the interval and another random direction is drawn). The rounding noise is measured on
/// directions whose true derivative is exactly zero (the attention key biases: softmax is
/// invariant to them). A tensor passes when analytic and numeric agree within 3 % plus five
/// times that noise.
fn model_check_with(reference: Reference, loss: LossConfig, strict: bool) -> f64 {
    let mut cfg = ModelConfig::tiny();
    cfg.reference = reference;
    let mut params = train::init_params(&cfg, 11).unwrap();
    // Sharper memberships than at initialisation, so the GMM solve is well conditioned.
    let last = format!("head.{}.weight", cfg.head_hidden.len());
    params.get_mut(&last).unwrap().iter_mut().for_each(|w| *w *= 6.0);
    let pair = synthetic::pair(synthetic::Shape::Box, cfg.n_points, 21);
    let (parts, grads) = train::pair_gradients(&cfg, &params, &pair, &loss);
    assert!(loss.consistency == 0.0 || parts.consistency_pairs > 0.0, "the test pair should have correspondences");
    let eval = |p: &train::Params| -> f64 {
        let mut t = Tape::new();
        let fwd = train::forward(&mut t, &cfg, p, &pair.source, &pair.target);
        let (total, _) = losses::record(&mut t, &fwd, &pair, &loss);
        t.scalar64(total)
    };
    // top-H switches its selection (a jump) under larger steps
    let h = if reference == Reference::TopH { 2e-4f32 } else { 1e-3 };
    let fd = |name: &str, dir: &[(usize, f32)], h: f32| {
        let shifted = |sign: f32| {
            let mut p = params.clone();
            for &(i, d) in dir {
                p.get_mut(name).unwrap()[i] += sign * h * d;
            }
            eval(&p)
        };
        (shifted(1.0) - shifted(-1.0)) / (2.0 * h as f64)
    };
    let mut r = rng(8);
    let mut draw = |len: usize| -> Vec<(usize, f32)> {
        let k = len.min(3);
        let mut idx: Vec<usize> = (0..len).collect();
        for i in 0..k {
            let s = r.random_range(i..idx.len());
            idx.swap(i, s);
        }
        idx[..k].iter().map(|&i| (i, if r.random_bool(0.5) { 1.0 } else { -1.0 })).collect()
    };
    // rounding noise of a difference at h/2, from exactly-invariant directions
    let mut noise = 1e-6f64;
    for (name, g) in grads.iter().filter(|(n, _)| n.ends_with(".k.bias")) {
        let dir = draw(g.len());
        noise = noise.max(fd(name, &dir, h / 2.0).abs()).max(fd(name, &dir, h).abs());
    }
    let mut worst = 0.0f64;
    let mut unchecked = Vec::new();
    for (name, g) in &grads {
        let mut done = false;
        for _attempt in 0..6 {
            let dir = draw(g.len());
            let ana: f64 = dir.iter().map(|&(i, d)| g[i] as f64 * d as f64).sum();
            let (n1, n2) = (fd(name, &dir, h), fd(name, &dir, h / 2.0));
            if (n1 - n2).abs() > 0.01 * n1.abs().max(n2.abs()) + 2.0 * noise {
                continue; // a kink or a selection change inside the interval
            }
            let err = (n2 - ana).abs() / (0.03 * n2.abs().max(ana.abs()) + 5.0 * noise);
            worst = worst.max(err);
            if !strict {
                eprintln!("{name}: analytic {ana:.6e} numeric {n2:.6e} score {err:.2}");
            } else {
                assert!(err < 1.0, "{reference:?} {name}: analytic {ana:.6e} vs numeric {n2:.6e} (noise {noise:.1e})");
            }
            done = true;
            break;
        }
        if !done {
            unchecked.push(name.clone());
        }
    }
    let max_g = grads.values().flatten().map(|g| g.abs() as f64).fold(0.0, f64::max);
    eprintln!(
        "model {reference:?}: {} tensors, {} without a smooth direction {unchecked:?}, FD noise {noise:.1e} (largest gradient {max_g:.1e}), worst score {worst:.2} (< 1 passes)",
        grads.len(),
        unchecked.len()
    );
    assert!(unchecked.len() * 10 <= grads.len(), "too many tensors without a smooth direction: {unchecked:?}");
    noise
}

fn all_losses() -> LossConfig {
    LossConfig {
        sup: 1.0,
        ctr: 1.0,
        ctr_mode: CentroidMode::EveryLayer,
        stp: 0.1,
        aff: 1.0,
        reg: 1.0,
        consistency: 1.0,
        consistency_radius: 0.1,
        consistency_kind: ConsistencyKind::SymmetricKl,
        means: 1.0,
        seg: 1.0,
        seg_kappa: 6.0,
    }
}

fn model_check(reference: Reference) {
    model_check_with(reference, all_losses(), true);
}

#[test]
fn whole_model_soft() {
    model_check(Reference::Soft);
}

#[test]
fn whole_model_top_h() {
    model_check(Reference::TopH);
}

/// Diagnostic: central differences of one tensor's first elements at several step sizes
/// (`GC_NAME=tensor GC_TERM=sup|ctr|stp|aff|reg|consistency|means|seg|all GC_TOPH=1`), to tell kinks and
/// rounding from a wrong gradient.
#[test]
#[ignore]
fn fd_sweep_one_tensor() {
    let name = std::env::var("GC_NAME").unwrap_or("layers.0.pos.1.bias".into());
    let term = std::env::var("GC_TERM").unwrap_or("all".into());
    let mut cfg = ModelConfig::tiny();
    if std::env::var("GC_TOPH").is_ok() {
        cfg.reference = Reference::TopH;
    }
    let mut params = train::init_params(&cfg, 11).unwrap();
    let last = format!("head.{}.weight", cfg.head_hidden.len());
    params.get_mut(&last).unwrap().iter_mut().for_each(|w| *w *= 6.0);
    let pair = synthetic::pair(synthetic::Shape::Box, cfg.n_points, 21);
    let mut loss = all_losses();
    if term != "all" {
        loss.sup = 0.0;
        loss.ctr = 0.0;
        loss.stp = 0.0;
        loss.aff = 0.0;
        loss.reg = 0.0;
        loss.consistency = 0.0;
        loss.means = 0.0;
        loss.seg = 0.0;
        match term.as_str() {
            "sup" => loss.sup = 1.0,
            "ctr" => loss.ctr = 1.0,
            "stp" => loss.stp = 1.0,
            "aff" => loss.aff = 1.0,
            "reg" => loss.reg = 1.0,
            "means" => loss.means = 1.0,
            "seg" => loss.seg = 1.0,
            _ => loss.consistency = 1.0,
        }
    }
    let (_, grads) = train::pair_gradients(&cfg, &params, &pair, &loss);
    let eval = |p: &train::Params| -> f64 {
        let mut t = Tape::new();
        let fwd = train::forward(&mut t, &cfg, p, &pair.source, &pair.target);
        let (total, _) = losses::record(&mut t, &fwd, &pair, &loss);
        t.scalar64(total)
    };
    for (i, gi) in grads[&name].iter().enumerate().take(4) {
        let mut line = format!("{name}[{i}] analytic {gi:.6e}:");
        for h in [3e-2f32, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4] {
            let mut p = params.clone();
            p.get_mut(&name).unwrap()[i] += h;
            let fp = eval(&p);
            p.get_mut(&name).unwrap()[i] -= 2.0 * h;
            let fm = eval(&p);
            line += &format!(" {:.6e}", (fp - fm) / (2.0 * h as f64));
        }
        eprintln!("{line}");
    }
}
