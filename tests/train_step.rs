#![cfg(feature = "train")]
//! Adam + the data-parallel step: determinism across thread counts, skipping non-finite steps,
//! and a short run on the tiny config that lowers the loss.

use arps::model::ModelConfig;
use arps::train::{self, optim, synthetic, LossConfig, TrainState};

#[test]
fn gradients_do_not_depend_on_threads() {
    let cfg = ModelConfig::tiny();
    let params = train::init_params(&cfg, 1).unwrap();
    let pairs = synthetic::pairs(5, cfg.n_points, 40);
    let loss = LossConfig { consistency: 0.5, reg: 0.5, aff: 0.5, ..LossConfig::default() };
    let (p1, g1) = train::batch_gradients(&cfg, &params, &pairs, &loss, 1);
    let (p2, g2) = train::batch_gradients(&cfg, &params, &pairs, &loss, 2);
    let (p3, g3) = train::batch_gradients(&cfg, &params, &pairs, &loss, 2);
    assert_eq!(g1, g2);
    assert_eq!(g2, g3);
    assert_eq!(p1, p2);
    assert_eq!(p2, p3);
    assert!(p1.total > 0.0 && p1.is_finite());
    assert!(optim::grad_norm(&g1) > 0.0);
}

#[test]
fn adam_matches_closed_form_first_step() {
    // first Adam step moves every parameter by lr * sign(g) (bias-corrected m / sqrt(v))
    let mut p = train::Params::new();
    p.insert("a".into(), vec![1.0, -2.0, 0.5]);
    let mut g = train::Params::new();
    g.insert("a".into(), vec![0.3, -4.0, 0.0]);
    let mut adam = train::Adam::new(0.1);
    adam.update(&mut p, &g);
    let a = &p["a"];
    assert!((a[0] - 0.9).abs() < 1e-5 && (a[1] + 1.9).abs() < 1e-5 && (a[2] - 0.5).abs() < 1e-6, "{a:?}");
    let (n, clipped) = optim::clip_grad_norm(&mut g, 1.0);
    assert!(clipped && (n - (0.09f64 + 16.0).sqrt()).abs() < 1e-5);
    assert!((optim::grad_norm(&g) - 1.0).abs() < 1e-5);
}

#[test]
fn moving_average_follows_the_closed_form() {
    // avg_k = d^k avg_0 + (1 - d^k) p for parameters held at p
    let mut p = train::Params::new();
    p.insert("a".into(), vec![0.0, 4.0]);
    let mut ema = train::Ema::new(0.5, &p);
    p.insert("a".into(), vec![2.0, 0.0]);
    p.insert("new".into(), vec![7.0]);
    ema.update(&p);
    ema.update(&p);
    assert_eq!(ema.params["a"], vec![1.5, 1.0]);
    // a parameter the average did not hold starts at its current value
    assert_eq!(ema.params["new"], vec![7.0]);
}

#[test]
fn steps_update_the_moving_average_and_skipped_steps_do_not() {
    let cfg = ModelConfig::tiny();
    let params = train::init_params(&cfg, 2).unwrap();
    let mut state = TrainState::new(cfg.clone(), params.clone(), 1e-2, Some(1.0));
    state.ema = Some(train::Ema::new(0.75, &params));
    let pairs = synthetic::pairs(2, cfg.n_points, 7);
    let r = train::train_step(&mut state, &pairs, &LossConfig::default(), 2);
    assert!(!r.skipped);
    let ema = &state.ema.as_ref().unwrap().params;
    for (name, p0) in &params {
        let p1 = &state.params[name];
        for ((a, x0), x1) in ema[name].iter().zip(p0).zip(p1) {
            assert!((a - (0.75 * x0 + 0.25 * x1)).abs() < 1e-6, "{name}: {a} vs {x0} -> {x1}");
        }
    }
    assert!(std::ptr::eq(state.eval_params(), ema));
    let before = state.ema.clone();
    let mut bad = pairs.clone();
    bad[0].source[0][1] = f32::INFINITY;
    assert!(train::train_step(&mut state, &bad, &LossConfig::default(), 2).skipped);
    assert_eq!(state.ema, before);
}

#[test]
fn non_finite_step_is_skipped() {
    let cfg = ModelConfig::tiny();
    let params = train::init_params(&cfg, 2).unwrap();
    let mut state = TrainState::new(cfg.clone(), params.clone(), 1e-3, Some(1.0));
    let mut pairs = synthetic::pairs(2, cfg.n_points, 7);
    pairs[1].source[3][0] = f32::NAN;
    let report = train::train_step(&mut state, &pairs, &LossConfig::default(), 2);
    assert!(report.skipped);
    assert_eq!(state.params, params);
    assert_eq!((state.steps, state.skipped_steps, state.adam.t), (1, 1, 0));
}

#[test]
fn short_run_lowers_the_loss() {
    let cfg = ModelConfig::tiny();
    let params = train::init_params(&cfg, 3).unwrap();
    let pairs = synthetic::pairs(6, cfg.n_points, 1000);
    let loss = LossConfig::default();
    let mut state = TrainState::new(cfg.clone(), params, 3e-3, Some(5.0));
    let before = train::batch_gradients(&cfg, &state.params, &pairs, &loss, 2).0;
    let mut last = None;
    for _ in 0..60 {
        let r = train::train_step(&mut state, &pairs, &loss, 2);
        assert!(!r.skipped && r.grad_norm.is_finite());
        last = Some(r);
    }
    let after = train::batch_gradients(&cfg, &state.params, &pairs, &loss, 2).0;
    eprintln!("before {before:?}\nafter  {after:?}\nlast step {:?}", last.map(|r| (r.grad_norm, r.seconds)));
    assert!(after.total < 0.7 * before.total, "loss {} -> {}", before.total, after.total);
    // the export of the trained parameters loads in the engine
    let w = train::to_weights(&state.params, &cfg, serde_json::json!({"steps": state.steps})).unwrap();
    arps::Weights::from_bytes(&w.to_bytes(arps::StoreAs::F32).unwrap()).unwrap();
}

#[test]
fn data_pipeline_pairs_convert() {
    use arps::data::pairs::{pair_from_dense, PairParams};
    let dense = arps::PointCloud::new(synthetic::pair(synthetic::Shape::Cylinder, 1024, 3).source);
    let params = PairParams { points: 32, dense_points: 1024, ..PairParams::default() };
    let dp = pair_from_dense(&dense, "test", &params, 9);
    let p = train::Pair::from(&dp);
    assert_eq!(p.t_gt, dp.T_target_source);
    // the GT centroids, moved by T_gt, agree (the pre-centred v_gt differ by the clouds' means)
    let mean = |c: &[[f32; 3]]| [0, 1, 2].map(|a| c.iter().map(|q| q[a] as f64).sum::<f64>() / c.len() as f64);
    let (ms, mt) = (mean(&p.source), mean(&p.target));
    let cs = [0, 1, 2].map(|a| p.v_gt_source[a] + ms[a] as f32);
    let ct = arps::transform::apply(&p.t_gt, cs);
    for a in 0..3 {
        assert!((ct[a] - (p.v_gt_target[a] + mt[a] as f32)).abs() < 1e-4);
    }
    let cfg = ModelConfig::tiny();
    let (parts, _) = train::pair_gradients(&cfg, &train::init_params(&cfg, 0).unwrap(), &p, &LossConfig::default());
    assert!(parts.is_finite());
}
