#![cfg(feature = "train")]
//! The tape's forward pass reproduces the engine's, and exported weights reproduce the tape.

use arps::model::{ModelConfig, ModelWorkspace, Reference};
use arps::train::{self, synthetic, Tape};
use arps::{Model, StoreAs, Weights};

fn configs() -> Vec<ModelConfig> {
    let mut out = Vec::new();
    for reference in [Reference::Soft, Reference::TopH] {
        let mut tiny = ModelConfig::tiny();
        tiny.reference = reference;
        out.push(tiny);
        let mut web = ModelConfig::web();
        web.n_points = 64;
        web.top_h = 16;
        web.reference = reference;
        out.push(web);
    }
    out
}

fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}

#[test]
fn tape_forward_matches_engine() {
    for (ci, cfg) in configs().into_iter().enumerate() {
        let w = Weights::random(&cfg, 7 + ci as u64).unwrap();
        let model = Model::from_weights(&w).unwrap();
        for seed in 0..2u64 {
            let pair = synthetic::pair(synthetic::Shape::Box, cfg.n_points, 100 + seed);
            let engine = model.forward(&pair.source, &pair.target, &mut ModelWorkspace::default()).unwrap();
            let mut t = Tape::new();
            let fwd = train::forward(&mut t, &cfg, &w.tensors, &pair.source, &pair.target);
            let ours = fwd.output(&t);
            let what = format!("{} {:?} seed {seed}", cfg.preset, cfg.reference);
            let dg = max_diff(&ours.gamma_source, &engine.gamma_source)
                .max(max_diff(&ours.gamma_target, &engine.gamma_target));
            assert!(dg < 1e-4, "{what}: memberships differ by {dg}");
            let ds = max_diff(&ours.steps, &engine.steps);
            assert!(ds < 1e-4, "{what}: steps differ by {ds}");
            let flat = |v: &Vec<[f32; 3]>| v.iter().flatten().copied().collect::<Vec<f32>>();
            let dd = max_diff(&flat(&ours.shifts_source), &flat(&engine.shifts_source))
                .max(max_diff(&flat(&ours.shifts_target), &flat(&engine.shifts_target)));
            assert!(dd < 1e-4, "{what}: shifts differ by {dd}");
            // T from the tape is the engine's GMR solve on the engine's memberships
            let j = cfg.gaussians;
            let gs = arps::gmr::gmm_params(&pair.source, &engine.gamma_source, j);
            let gt = arps::gmr::gmm_params(&pair.target, &engine.gamma_target, j);
            for (ours, theirs, name) in
                [(fwd.t12(&t), arps::gmr::solve(&gs, &gt), "T12"), (fwd.t21(&t), arps::gmr::solve(&gt, &gs), "T21")]
            {
                arps::transform::check_rigid(&ours, 1e-4).unwrap();
                let d = (ours - theirs).abs().max();
                assert!(d < 1e-4, "{what}: {name} differs from the engine's by {d}\n{ours}\n{theirs}");
            }
        }
    }
}

#[test]
fn exported_weights_reproduce_tape() {
    for cfg in configs() {
        let params = train::init_params(&cfg, 3).unwrap();
        let w = train::to_weights(&params, &cfg, serde_json::json!({"kind": "test"})).unwrap();
        let bytes = w.to_bytes(StoreAs::F32).unwrap();
        let model = Model::from_weights(&Weights::from_bytes(&bytes).unwrap()).unwrap();
        let pair = synthetic::pair(synthetic::Shape::Cylinder, cfg.n_points, 5);
        let engine = model.forward(&pair.source, &pair.target, &mut ModelWorkspace::default()).unwrap();
        let mut t = Tape::new();
        let fwd = train::forward(&mut t, &cfg, &params, &pair.source, &pair.target);
        let ours = fwd.output(&t);
        assert!(max_diff(&ours.gamma_source, &engine.gamma_source) < 1e-4);
        assert!(max_diff(&ours.gamma_target, &engine.gamma_target) < 1e-4);
        let j = cfg.gaussians;
        let gs = arps::gmr::gmm_params(&pair.source, &engine.gamma_source, j);
        let gt = arps::gmr::gmm_params(&pair.target, &engine.gamma_target, j);
        assert!((fwd.t12(&t) - arps::gmr::solve(&gs, &gt)).abs().max() < 1e-4);
        // a wrong parameter set is rejected
        let mut bad = params.clone();
        bad.remove("head.0.bias");
        assert!(train::to_weights(&bad, &cfg, serde_json::Value::Null).is_err());
    }
}
