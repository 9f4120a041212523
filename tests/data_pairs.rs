//! The pair protocol (docs/design.md §8), the engine-frame mapping, and the shape source split.
#![cfg(feature = "cli")]

use arps::data::pairs::{normalize_shape, pair_from_dense};
use arps::data::source::{ShapeSource, Split};
use arps::data::{generate, make_pair, Bank, Category, NamedMesh, PairParams, CATEGORIES};
use arps::transform::{apply, check_rigid, rotation, translation};
use nalgebra::Vector4;

fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= tol)
}

fn quiet() -> PairParams {
    PairParams { noise_sigma: 0.0, ..PairParams::default() }
}

/// Euler angles of R = Rx(ax) Ry(ay) Rz(az).
fn euler(r: &nalgebra::Matrix3<f64>) -> [f64; 3] {
    let ay = r[(0, 2)].clamp(-1.0, 1.0).asin();
    let ax = (-r[(1, 2)]).atan2(r[(2, 2)]);
    let az = (-r[(0, 1)]).atan2(r[(0, 0)]);
    [ax, ay, az].map(f64::to_degrees)
}

/// Counterparts (equal dense indices) coincide under `t_target_source` (no noise); returns how
/// many there are. `source`/`target` are the pair's clouds in any frames `t_target_source` maps
/// between.
fn counterparts_match(
    pair: &arps::data::Pair,
    t_target_source: &nalgebra::Matrix4<f64>,
    source: &[[f32; 3]],
    target: &[[f32; 3]],
) -> usize {
    let pos: std::collections::HashMap<u32, usize> =
        pair.target_dense_index.iter().enumerate().map(|(k, &i)| (i, k)).collect();
    let mut matched = 0;
    for (j, i) in pair.source_dense_index.iter().enumerate() {
        if let Some(&k) = pos.get(i) {
            matched += 1;
            assert!(close(apply(t_target_source, source[j]), target[k], 1e-5));
        }
    }
    matched
}

#[test]
fn protocol_sizes_overlap_and_ranges() {
    let p = PairParams::default();
    for (k, c) in CATEGORIES.iter().enumerate() {
        let mesh = generate(*c, k as u64);
        for seed in 0..3 {
            let pair = make_pair(&mesh, c.name(), &p, seed).unwrap();
            assert_eq!(pair.source.len(), 1024);
            assert_eq!(pair.target.len(), 1024);
            assert_eq!(pair.source_dense_index.len(), 1024);
            assert!(pair.overlap >= 0.7, "{c} {seed}: overlap {}", pair.overlap);
            check_rigid(&pair.T_target_source, 1e-9).unwrap();
            let e = euler(&rotation(&pair.T_target_source));
            assert!(e.iter().all(|a| a.abs() <= 45.0 + 1e-9), "{c}: euler {e:?}");
            assert!(translation(&pair.T_target_source).norm() <= 0.5 + 1e-12);
            // no resampled index repeats (without replacement)
            let mut s = pair.source_dense_index.clone();
            s.sort_unstable();
            s.dedup();
            assert_eq!(s.len(), 1024);
            assert!(pair.source.iter().chain(&pair.target).all(|q| q.iter().all(|v| v.is_finite())));
        }
    }
}

#[test]
fn angles_span_the_range() {
    let mesh = generate(Category::Chair, 1);
    let mut max = [0.0f64; 3];
    for seed in 0..60 {
        let pair = make_pair(&mesh, "chair", &quiet(), seed).unwrap();
        let e = euler(&rotation(&pair.T_target_source));
        for a in 0..3 {
            max[a] = max[a].max(e[a].abs());
        }
    }
    assert!(max.iter().all(|&m| m > 35.0), "angles never get large: {max:?}");
}

#[test]
fn ground_truth_maps_source_onto_target_counterparts_without_noise() {
    let mesh = generate(Category::Car, 3);
    let dense = mesh.sample_surface(4096, 11).unwrap();
    let (normed, _, _) = normalize_shape(&dense);
    for seed in 0..5 {
        let pair = pair_from_dense(&dense, "car", &quiet(), seed);
        // every source point is a dense point; every target point is a moved dense point
        for (q, &i) in pair.source.iter().zip(&pair.source_dense_index) {
            assert!(close(*q, normed.points[i as usize], 1e-6));
        }
        for (q, &i) in pair.target.iter().zip(&pair.target_dense_index) {
            assert!(close(*q, apply(&pair.T_target_source, normed.points[i as usize]), 1e-5));
        }
        let matched = counterparts_match(&pair, &pair.T_target_source, &pair.source, &pair.target);
        assert!(matched > 200, "only {matched} shared samples");
        // the full-shape centroid
        let c = normed.centroid();
        assert!((0..3).all(|a| (pair.centroid_source[a] - c[a]).abs() < 1e-9));
        let ct = pair.T_target_source * Vector4::new(c[0], c[1], c[2], 1.0);
        assert!((0..3).all(|a| (pair.centroid_target[a] - ct[a]).abs() < 1e-9));
    }
}

#[test]
fn noise_is_clipped_and_has_the_right_scale() {
    let mesh = generate(Category::Bed, 0);
    let dense = mesh.sample_surface(4096, 5).unwrap();
    let (normed, _, _) = normalize_shape(&dense);
    let pair = pair_from_dense(&dense, "bed", &PairParams::default(), 9);
    let mut sq = 0.0;
    for (q, &i) in pair.source.iter().zip(&pair.source_dense_index) {
        let p = normed.points[i as usize];
        for a in 0..3 {
            let d = (q[a] - p[a]) as f64;
            assert!(d.abs() <= 0.05 + 1e-6);
            sq += d * d;
        }
    }
    let sigma = (sq / (3.0 * 1024.0)).sqrt();
    assert!((sigma - 0.01).abs() < 0.001, "noise sigma {sigma}");
}

#[test]
fn deterministic_per_seed() {
    let mesh = generate(Category::Lamp, 2);
    let p = PairParams::default();
    assert_eq!(make_pair(&mesh, "lamp", &p, 4).unwrap(), make_pair(&mesh, "lamp", &p, 4).unwrap());
    assert_ne!(make_pair(&mesh, "lamp", &p, 4).unwrap().source, make_pair(&mesh, "lamp", &p, 5).unwrap().source);
}

#[test]
fn curriculum_knobs() {
    let mesh = generate(Category::Desk, 0);
    let p = PairParams {
        max_angle_deg: 0.0,
        max_translation: 0.0,
        noise_sigma: 0.0,
        keep_ratio: 0.9,
        min_overlap: 0.9,
        ..PairParams::default()
    };
    let pair = make_pair(&mesh, "desk", &p, 1).unwrap();
    assert!((pair.T_target_source - nalgebra::Matrix4::identity()).abs().max() < 1e-12);
    assert!(pair.overlap >= 0.9);
    let p = PairParams { max_angle_deg: 10.0, ..quiet() };
    for seed in 0..10 {
        let pair = make_pair(&mesh, "desk", &p, seed).unwrap();
        assert!(euler(&rotation(&pair.T_target_source)).iter().all(|a| a.abs() <= 10.0 + 1e-9));
    }
    // upright pairs: any turn about z, none about x and y; the rest of the pair is the same
    let upright = PairParams { max_angle_deg: 180.0, max_tilt_deg: Some(0.0), ..quiet() };
    let any = PairParams { max_angle_deg: 180.0, ..quiet() };
    let mut turns = Vec::new();
    for seed in 0..10 {
        let (pair, other) =
            (make_pair(&mesh, "desk", &upright, seed).unwrap(), make_pair(&mesh, "desk", &any, seed).unwrap());
        let [ax, ay, az] = euler(&rotation(&pair.T_target_source));
        assert!(ax.abs() < 1e-9 && ay.abs() < 1e-9, "{ax} {ay}");
        assert_eq!(pair.source_dense_index, other.source_dense_index);
        turns.push(az.abs());
    }
    assert!(turns.iter().any(|&a| a > 90.0), "{turns:?}");
}

#[test]
fn engine_frames_are_consistent() {
    let mesh = generate(Category::Guitar, 4);
    for seed in 0..4 {
        let pair = make_pair(&mesh, "guitar", &quiet(), seed).unwrap();
        let e = pair.engine_frames();
        check_rigid(&e.T_target_source, 1e-9).unwrap();
        for c in [&e.source, &e.target] {
            let (lo, hi) = c.bounds();
            assert!(lo.iter().chain(&hi).all(|v| v.abs() <= 1.0 + 1e-5));
        }
        // the engine-frame GT maps the normalised source onto the normalised target
        assert!(counterparts_match(&pair, &e.T_target_source, &e.source.points, &e.target.points) > 100);
        let cs = e.centroid_source;
        let ct = e.T_target_source * Vector4::new(cs[0], cs[1], cs[2], 1.0);
        assert!((0..3).all(|a| (ct[a] - e.centroid_target[a]).abs() < 1e-9));
        // and maps back to the pair's units
        assert!((e.norm.denormalize(&e.T_target_source) - pair.T_target_source).abs().max() < 1e-9);
    }
}

#[test]
fn shape_source_splits_by_shape() {
    let src = ShapeSource::procedural();
    let train: std::collections::HashSet<String> = (0..400).map(|i| src.shape(Split::Train, i).unwrap().name).collect();
    let val: std::collections::HashSet<String> = (0..400).map(|i| src.shape(Split::Val, i).unwrap().name).collect();
    assert!(train.is_disjoint(&val));
    assert_eq!(val.len(), 200, "10 validation shapes per category");
    assert_eq!(train.len(), 400, "a new training shape per pair");
    let p = PairParams::default();
    assert_eq!(src.pair(Split::Val, 3, &p).unwrap(), src.pair(Split::Val, 3, &p).unwrap());

    // a bank: names decide the split, independently of the rest of the bank
    let meshes: Vec<NamedMesh> = (0..40)
        .map(|i| NamedMesh { name: format!("dir/mesh{i}.obj"), mesh: generate(CATEGORIES[i % 20], i as u64) })
        .collect();
    let bank = Bank { meshes, skipped: vec![] };
    let src = ShapeSource::with_bank(bank.clone(), 0.25);
    assert!(!src.bank_val.is_empty() && !src.bank_train.is_empty());
    assert_eq!(src.bank_val.len(), bank.split(Split::Val, 0.25).len());
    let bank_train: std::collections::HashSet<String> =
        src.bank_train.iter().map(|m| format!("bank/{}", m.name)).collect();
    let mut seen_bank = 0;
    for i in 0..300 {
        let name = src.shape(Split::Val, i).unwrap().name;
        assert!(!bank_train.contains(&name), "validation pair {i} uses training shape {name}");
        seen_bank += name.starts_with("bank/") as usize;
    }
    assert!(seen_bank > 40 && seen_bank < 150, "bank fraction off: {seen_bank}/300");
}

#[test]
fn network_sample_draws_from_the_engine_clouds() {
    let mesh = generate(Category::Cup, 0);
    let pair = make_pair(&mesh, "cup", &PairParams::default(), 2).unwrap();
    let e = pair.engine_frames();
    let (s, t) = e.network_sample(512, 7);
    assert_eq!((s.len(), t.len()), (512, 512));
    assert!(s.points.iter().all(|p| e.source.points.contains(p)));
    assert!(t.points.iter().all(|p| e.target.points.contains(p)));
    assert_eq!(e.network_sample(512, 7), (s.clone(), t));
    assert_ne!(e.network_sample(512, 8).0, s);
}

#[test]
fn pose_angle_turns_the_whole_shape_and_keeps_the_ground_truth() {
    let mesh = generate(Category::Chair, 2);
    let dense = mesh.sample_surface(4096, 5).unwrap();
    let (normed, _, _) = normalize_shape(&dense);
    for seed in 0..4 {
        let turned = pair_from_dense(&dense, "chair", &PairParams { pose_angle_deg: 180.0, ..quiet() }, seed);
        // the source is the dense shape turned by one rotation R_pose about the origin
        let a = normed.points[turned.source_dense_index[0] as usize];
        let b = normed.points[turned.source_dense_index[1] as usize];
        let (ta, tb) = (turned.source[0], turned.source[1]);
        let len = |p: [f32; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let diff = |p: [f32; 3], q: [f32; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        assert!((len(ta) - len(a)).abs() < 1e-5, "distances to the origin kept");
        assert!((len(diff(ta, tb)) - len(diff(a, b))).abs() < 1e-5, "distances kept");
        assert!(!close(ta, a, 1e-3), "seed {seed}: the source was not turned");
        // the ground truth still maps each source point onto its target counterpart
        let matched = counterparts_match(&turned, &turned.T_target_source, &turned.source, &turned.target);
        assert!(matched > 200, "only {matched} shared samples");
        let c = turned.centroid_source;
        let ct = turned.T_target_source * Vector4::new(c[0], c[1], c[2], 1.0);
        assert!((0..3).all(|k| (turned.centroid_target[k] - ct[k]).abs() < 1e-9));
    }
    // 0, the default, is the paper's protocol: the very same pair
    let zero = PairParams { pose_angle_deg: 0.0, ..quiet() };
    assert_eq!(pair_from_dense(&dense, "chair", &zero, 3), pair_from_dense(&dense, "chair", &quiet(), 3));
}
