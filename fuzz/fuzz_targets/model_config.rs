//! Any JSON given as a model config must validate quickly or fail; a config that validates is
//! within the budgets, and (when small enough to run in a fuzz execution) builds weights that
//! round-trip through the weights file and run a registration.
#![no_main]

use arps::limits::{MAX_MODEL_DIM, MAX_MODEL_PARAMETERS};
use arps::{ModelConfig, Options, PointCloud, Registrar, StoreAs, Weights};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(config) = serde_json::from_slice::<ModelConfig>(data) else { return };
    if config.validate().is_err() {
        return;
    }
    assert!(config.n_points <= MAX_MODEL_DIM && config.feature_dim <= MAX_MODEL_DIM);
    let params = config.parameter_count();
    assert!(params as u64 <= MAX_MODEL_PARAMETERS, "{params} parameters passed validation");
    if params > 20_000 || config.n_points > 64 {
        return;
    }
    let weights = Weights::random(&config, 1).expect("a valid config has weights");
    let back = Weights::from_bytes(&weights.to_bytes(StoreAs::F32).unwrap()).expect("own weights read back");
    assert_eq!(back.config, config);
    let mut reg = Registrar::new(&back).expect("a registrar for valid weights");
    let cloud = |k: f32| {
        PointCloud::new((0..100).map(|i| [(i % 10) as f32 * 0.1 + k, (i / 10) as f32 * 0.1, ((i * 7) % 5) as f32 * 0.05]).collect())
    };
    let options = Options { icp_max_iterations: 3, ..Options::default() };
    if let Ok(r) = reg.register(&cloud(0.0), &cloud(0.02), &options) {
        assert!(r.T_target_source.iter().all(|v| v.is_finite()));
    }
});
