//! Any JSON given as registration options must give a registration or an error (never a panic,
//! never a non-finite or non-rigid answer), and the registrar stays usable after an error.
//! Iteration caps up to 10,000 (the accepted range) are lowered to 10 to keep executions fast.
#![no_main]

use arps::{ModelConfig, Options, PointCloud, Registrar, Weights};
use libfuzzer_sys::fuzz_target;
use std::cell::RefCell;

/// A small bumpy closed surface, deterministic.
fn surface(n: usize, phase: f64) -> PointCloud {
    PointCloud::new(
        (0..n)
            .map(|i| {
                let (a, b) = ((i as f64 * 0.754_877 + phase) % 1.0, (i as f64 * 0.569_840 + phase) % 1.0);
                let (u, v) = (a * std::f64::consts::TAU, (2.0 * b - 1.0).acos());
                let r = 0.8 + 0.1 * (3.0 * u).sin() * (2.0 * v).cos();
                [(r * v.sin() * u.cos() * 1.2) as f32, (r * v.sin() * u.sin() * 0.8) as f32, (r * v.cos()) as f32]
            })
            .collect(),
    )
}

thread_local! {
    static STATE: RefCell<(Registrar, PointCloud, PointCloud)> = RefCell::new((
        Registrar::new(&Weights::random(&ModelConfig::tiny(), 0).unwrap()).unwrap(),
        surface(200, 0.0),
        surface(200, 0.37),
    ));
}

fuzz_target!(|data: &[u8]| {
    let Ok(mut options) = serde_json::from_slice::<Options>(data) else { return };
    if options.icp_max_iterations <= 10_000 {
        options.icp_max_iterations = options.icp_max_iterations.min(10);
    }
    STATE.with(|s| {
        let (reg, source, target) = &mut *s.borrow_mut();
        match reg.register(source, target, &options) {
            Ok(r) => {
                assert!(r.T_target_source.iter().all(|v| v.is_finite()));
                arps::transform::check_rigid(&r.T_target_source, 1e-3).expect("a rigid answer");
                assert!((0.0..=1.0).contains(&r.fitness), "fitness {}", r.fitness);
                assert!(r.inlier_rmse.is_finite() && r.max_correspondence_distance.is_finite());
            }
            Err(_) => {
                // still usable
                reg.register(source, target, &Options { icp_max_iterations: 5, ..Options::default() }).expect("usable after an error");
            }
        }
    });
});
