//! The default correspondence distance on a dense scene: a share of the clouds' size spans tens of
//! their point spacings there, and an answer off by a fraction of it fits as well as the right
//! one; the default is then a few spacings (`arps::grain`), as a caller who knew the scan would
//! give. A sparse pair keeps the share.

mod common;
use arps::{Options, PointCloud, Registrar};

/// Bumps on a 200 x 24 m road corridor: (x, y, height, radius) of 60 mounds, stones and hollows
/// strewn at random (seed 7).
fn bumps() -> Vec<[f64; 4]> {
    use rand::Rng;
    let mut rng = arps::sampling::rng(7);
    (0..60)
        .map(|_| {
            let mut r = || rng.random::<f64>();
            [200.0 * r(), 24.0 * r(), 1.6 * r() - 0.5, 0.8 + 2.5 * r()]
        })
        .collect()
}

/// Heights of the corridor at `(x, y)`: rolling ground, a kerb and the `bumps`.
fn corridor_height(bumps: &[[f64; 4]], x: f64, y: f64) -> f64 {
    let kerb = if y > 14.0 { 0.15 } else { 0.0 };
    let strewn: f64 =
        bumps.iter().map(|b| b[2] * (-((x - b[0]).powi(2) + (y - b[1]).powi(2)) / (b[3] * b[3])).exp()).sum();
    0.6 * (x * 0.05).sin() + 0.3 * (y * 0.2 + x * 0.03).cos() + kerb + strewn
}

/// The corridor from `from` to `from + 150` m along it, sampled on a 0.15 m grid, jittered and
/// with 1 cm of noise across it by `seed`.
fn corridor(seed: u64, from: usize) -> PointCloud {
    use rand::Rng;
    let mut rng = arps::sampling::rng(seed);
    let mut pts = Vec::new();
    let bumps = bumps();
    let step = 0.15;
    let rows = |m: usize| (m as f64 / step).round() as usize;
    for i in rows(from)..rows(from + 150) {
        for j in 0..rows(24) {
            let (x, y) = ((i as f64 + rng.random::<f64>()) * step, (j as f64 + rng.random::<f64>()) * step);
            let z = corridor_height(&bumps, x, y) + 0.01 * (rng.random::<f64>() - 0.5) * 3.4;
            pts.push([x as f32, y as f32, z as f32]);
        }
    }
    PointCloud::new(pts)
}

#[test]
fn a_dense_scene_is_registered_at_a_few_point_spacings() {
    let truth = common::motion([0.2, -0.3, 0.5], [0.8, -0.5, 0.2]);
    let source = corridor(2, 50).transformed(&truth.try_inverse().unwrap());
    let target = corridor(1, 0);
    let mut reg = Registrar::with_default_model().unwrap();
    let dense = reg.register(&source, &target, &Options::default()).unwrap();
    // the size-based default: 2.5% of the shared half-extent (about 75 m)
    let share = 0.025 * 75.0;
    let sized = reg
        .register(&source, &target, &Options { max_correspondence_distance: Some(share), ..Options::default() })
        .unwrap();
    let d = dense.max_correspondence_distance;
    assert!(d < 0.6 * share && d >= 0.25 * share * 0.99, "default distance {d} m");
    let (rd, td) = common::errors(&dense.T_target_source, &truth);
    let (rs, ts) = common::errors(&sized.T_target_source, &truth);
    assert!(rd < 0.01 && td < 0.01, "dense default: {rd} degrees, {td} m");
    // (a corridor of low relief: both answers report the turn about up as nearly free)
    assert!(td * 3.0 < ts && rd * 2.0 < rs, "dense default {rd} degrees, {td} m; the share {rs} degrees, {ts} m");
}

#[test]
fn a_sparse_pair_keeps_the_share_of_its_size() {
    let (source, target, _) = common::fixture_pair(0);
    let r = Registrar::with_default_model().unwrap().register(&source, &target, &Options::default()).unwrap();
    let half = |c: &PointCloud| c.half_extent();
    let scale = half(&source).max(half(&target));
    assert!((r.max_correspondence_distance - 0.025 * scale).abs() < 1e-9 * scale, "{}", r.max_correspondence_distance);
}
