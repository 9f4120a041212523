//! Dense scans ([`arps::global::density`]): the global descriptors are made finer; and when either
//! cloud has at least [`GLOBAL_BEFORE_STOP_POINTS`] points (scans, or a small scan onto a large
//! model) the adaptive search does not stop before its global stage, however sure it is of an
//! earlier answer; sparse samples (the 1,024-point protocol) are searched as before.

mod common;

use arps::global::{self, density, Density, TargetFeatures, VOXEL_FRACTION};
use arps::io::read_mesh;
use arps::register::GLOBAL_BEFORE_STOP_POINTS;
use arps::transform::{rigid_inverse, rotation_error_deg};
use arps::{Options, PointCloud, Registrar, Start};
use common::{crop, fixture_pair, motion};

/// `n` points over the CAD part's surface (the committed STL fixture).
fn cad_surface(n: usize) -> PointCloud {
    let name = "angle_block_binary_solid.stl";
    let bytes = std::fs::read(format!("{}/fixtures/formats/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    read_mesh(&bytes, name).unwrap().sample_surface(n, 3).unwrap()
}

#[test]
fn scans_are_dense_and_sparse_samples_or_few_points_are_not() {
    let surface = cad_surface(60_000);
    let memo = TargetFeatures::default();
    let fresh = |s: &PointCloud, t: &PointCloud| density(s, t, &TargetFeatures::default(), VOXEL_FRACTION);
    assert_eq!(density(&surface, &surface, &memo, VOXEL_FRACTION), Density::Dense, "60,000 points");
    // asked again through the memo: the same answer
    assert_eq!(density(&surface, &surface, &memo, VOXEL_FRACTION), Density::Dense);
    // a fifth as many points over the part: between, described at both scales
    let thinned = cad_surface(12_000);
    assert_eq!(fresh(&thinned, &surface), Density::Mid, "12,000 points");
    assert_eq!(fresh(&surface, &thinned), Density::Mid, "12,000-point target");
    assert_eq!(global::feature_voxels(&thinned, &surface, VOXEL_FRACTION).len(), 2);
    let few = cad_surface(2_000);
    assert_eq!(fresh(&few, &surface), Density::Sparse, "2,000 points");
    assert_eq!(fresh(&surface, &few), Density::Sparse, "2,000-point target");
    assert_eq!(global::feature_voxels(&few, &surface, VOXEL_FRACTION).len(), 1);
    let (source, target, _) = fixture_pair(0);
    assert_eq!(fresh(&source, &target), Density::Sparse, "a 1,024-point pair");
}

#[test]
fn a_scan_thinned_to_two_thousand_points_is_between_and_fewer_are_sparse() {
    // an eighth of the part at 16,000 points over the whole, thinned to 2,000: 3 or more to a
    // voxel, as a room scan thinned that far, so it is described at both scales; with one point
    // fewer it counts as a sparse sample, whatever its crowding
    let model = cad_surface(60_000);
    let piece = crop(&cad_surface(16_000), [1.0, 0.2, 0.1], 0.125);
    assert_eq!(piece.len(), global::MID_MIN_POINTS);
    let fresh = |s: &PointCloud| density(s, &model, &TargetFeatures::default(), VOXEL_FRACTION);
    assert_eq!(fresh(&piece), Density::Mid);
    assert_eq!(global::feature_voxels(&piece, &model, VOXEL_FRACTION).len(), 2);
    let fewer = PointCloud::new(piece.points[1..].to_vec());
    assert_eq!(fresh(&fewer), Density::Sparse, "{} points", fewer.len());
}

/// A pair cropped from `n` points over the CAD part (each crop keeps 80%) and registered with
/// the network's start, then the global one: the number of points per cloud, the starts refined
/// by the network's start alone and by both, and whether the answer is right and sure.
#[allow(non_snake_case)]
fn network_then_global(n: usize) -> (usize, usize, usize) {
    let surface = cad_surface(n);
    let T_target_source = motion([8.0, -5.0, 6.0], [0.02, 0.01, -0.01]);
    let source = crop(&surface, [1.0, 0.2, 0.1], 0.8).transformed(&rigid_inverse(&T_target_source));
    let target = crop(&surface, [-1.0, 0.3, 0.0], 0.8);
    let mut registrar = Registrar::with_default_model().unwrap();
    // the network's start alone is already sure of its answer here
    let network = Options { starts: vec![Start::Network], ..Options::default() };
    let alone = registrar.register(&source, &target, &network).unwrap();
    assert!(alone.confidence >= 0.95, "precondition: a sure network answer ({})", alone.confidence);
    let both = Options { starts: vec![Start::Network, Start::Global], ..Options::default() };
    let r = registrar.register(&source, &target, &both).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &T_target_source) < 2.0);
    assert!(r.confidence >= 0.95, "confidence {}", r.confidence);
    (source.len().min(target.len()), alone.starts_refined, r.starts_refined)
}

#[test]
fn a_sure_answer_on_dense_scans_still_waits_for_the_global_stage() {
    // on sparse clouds the search would stop at the network's answer; here the global stage runs
    let (points, alone, both) = network_then_global(60_000);
    assert!(points >= GLOBAL_BEFORE_STOP_POINTS);
    assert!(both > alone, "the global stage did not run: {both} starts refined");
}

#[test]
fn so_does_one_on_clouds_of_a_few_thousand_points() {
    // not dense scans (few points per feature voxel), but beyond the sparse samples the
    // confidence is calibrated on: the global stage runs too
    let surface = cad_surface(4_096);
    let density = density(&surface, &surface, &TargetFeatures::default(), VOXEL_FRACTION);
    assert_ne!(density, Density::Dense, "precondition: not dense");
    let (points, alone, both) = network_then_global(4_096);
    assert!(points >= GLOBAL_BEFORE_STOP_POINTS, "{points} points");
    assert!(both > alone, "the global stage did not run: {both} starts refined");
    // just below the bound, the sure answer stops the search
    let (points, alone, both) = network_then_global(3_600);
    assert!(points < GLOBAL_BEFORE_STOP_POINTS, "{points} points");
    assert_eq!(both, alone, "the global stage ran on {points} points");
}

#[test]
#[allow(non_snake_case)]
fn a_sure_answer_on_a_sparse_pair_stops_the_search_at_once() {
    let (source, target, T_target_source) = fixture_pair(0);
    let both = Options { starts: vec![Start::Network, Start::Global], ..Options::default() };
    let r = Registrar::with_default_model().unwrap().register(&source, &target, &both).unwrap();
    assert!(r.confidence >= 0.95, "precondition: a sure network answer ({})", r.confidence);
    assert!(rotation_error_deg(&r.T_target_source, &T_target_source) < 5.0);
    assert_eq!(r.starts_refined, 1, "the global stage ran");
}

#[test]
#[allow(non_snake_case)]
fn a_sure_answer_for_a_small_scan_onto_a_large_model_waits_for_the_global_stage() {
    // a scan of a few thousand points of half the part onto 6,000 points over all of it: only
    // the model has many points, and the global stage still runs
    let model = cad_surface(6_000);
    let T_target_source = motion([8.0, -5.0, 6.0], [0.02, 0.01, -0.01]);
    let scan = crop(&cad_surface(4_000), [1.0, 0.2, 0.1], 0.5).transformed(&rigid_inverse(&T_target_source));
    assert!(scan.len() < GLOBAL_BEFORE_STOP_POINTS && model.len() >= GLOBAL_BEFORE_STOP_POINTS);
    let mut registrar = Registrar::with_default_model().unwrap();
    let network = Options { starts: vec![Start::Network], ..Options::default() };
    let alone = registrar.register(&scan, &model, &network).unwrap();
    assert!(alone.confidence >= 0.95, "precondition: a sure network answer ({})", alone.confidence);
    let both = Options { starts: vec![Start::Network, Start::Global], ..Options::default() };
    let r = registrar.register(&scan, &model, &both).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &T_target_source) < 2.0);
    assert!(r.starts_refined > alone.starts_refined, "the global stage did not run: {} starts", r.starts_refined);
}

#[test]
#[allow(non_snake_case)]
fn a_thinned_scan_is_described_at_both_scales_and_registered_from_any_pose() {
    // 12,000 points over the part (between sparse and dense) turned 150 degrees onto 60,000:
    // the global stage alone, its hypotheses drawn at both scales, recovers the motion
    let T_target_source = motion([150.0, -40.0, 70.0], [0.3, -0.1, 0.2]);
    let scan = crop(&cad_surface(12_000), [1.0, 0.2, 0.1], 0.7).transformed(&rigid_inverse(&T_target_source));
    let model = crop(&cad_surface(60_000), [-1.0, 0.3, 0.0], 0.8);
    assert_eq!(density(&scan, &model, &TargetFeatures::default(), VOXEL_FRACTION), Density::Mid, "precondition");
    let params = global::GlobalParams { seed: 3, hypotheses: 2, ..global::GlobalParams::default() };
    let hypotheses = global::hypotheses(&scan, &model, &params);
    assert!(hypotheses.len() <= 2 * params.hypotheses, "{} hypotheses", hypotheses.len());
    // described at the default scale alone (the adaptive search, when its answer so far fits at
    // least half of the source), its hypotheses are the first of both scales'
    let memo = TargetFeatures::default();
    let coarse = global::Matched::onto_at(&scan, &model, &memo, VOXEL_FRACTION, false).hypotheses(&params);
    assert!(!coarse.is_empty() && coarse.len() <= params.hypotheses);
    assert_eq!(coarse[..], hypotheses[..coarse.len()]);
    let global_only = Options { starts: vec![Start::Global], ..Options::default() };
    let r = Registrar::with_default_model().unwrap().register(&scan, &model, &global_only).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &T_target_source) < 2.0, "{:?}", r.T_target_source);
    assert!(r.confidence >= 0.5, "confidence {}", r.confidence);
}
