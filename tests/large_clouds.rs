//! Large clouds: the work of every stage is bounded whatever the point count. The voxel grid
//! gives the same clouds as the sort-based grid it replaced, target normals are estimated only
//! where ICP needs them (and equal the eager ones), refinement runs on a capped, evenly spread
//! source, the feature voxel follows the data's scale, a large cloud's voxelised copy stands in
//! for it in the global stage, and a 280k-point pair is registered.

mod common;

use arps::icp::{IcpKind, IcpTarget};
use arps::refine::{self, Refinement, Start};
use arps::sampling::{rng, voxel_downsample};
use arps::transform::{rigid_inverse, rotation_error_deg, translation_error};
use arps::{global, normals, Options, PointCloud, Registrar};
use common::{bumpy_surface, crop, motion};
use rand::Rng;

/// The grid as it was computed before (every point keyed, all keys sorted, runs averaged).
fn voxel_reference(points: &[[f32; 3]], voxel: f32) -> Vec<[f32; 3]> {
    let inv = 1.0 / voxel as f64;
    let mut keyed: Vec<([i64; 3], usize)> = points
        .iter()
        .enumerate()
        .filter(|(_, p)| p.iter().all(|v| v.is_finite()))
        .map(|(i, p)| (p.map(|v| (v as f64 * inv).floor() as i64), i))
        .collect();
    keyed.sort_unstable();
    let mut out = Vec::new();
    let mut run = keyed.as_slice();
    while let Some(&(key, _)) = run.first() {
        let len = run.iter().take_while(|(k, _)| *k == key).count();
        let mut s = [0.0f64; 3];
        for &(_, i) in &run[..len] {
            for a in 0..3 {
                s[a] += points[i][a] as f64;
            }
        }
        out.push(s.map(|v| (v / len as f64) as f32));
        run = &run[len..];
    }
    out
}

#[test]
fn the_voxel_grid_equals_the_sorting_reference() {
    let mut r = rng(7);
    for (n, spread, voxel) in [(5_000usize, 1.0f32, 0.05f32), (20_000, 300.0, 0.7), (3_000, 0.01, 0.002)] {
        let mut pts: Vec<[f32; 3]> =
            (0..n).map(|_| [0, 1, 2].map(|_| (r.random::<f32>() * 2.0 - 1.0) * spread)).collect();
        // repeats, points on voxel boundaries and a non-finite point
        pts.extend_from_within(..100);
        pts.push([0.0, -voxel, 2.0 * voxel]);
        pts.push([f32::NAN, 0.0, 0.0]);
        let got = voxel_downsample(&PointCloud::new(pts.clone()), voxel).points;
        assert_eq!(got, voxel_reference(&pts, voxel), "n = {n}, voxel = {voxel}");
    }
}

#[test]
fn normals_are_estimated_only_where_icp_needs_them_and_equal_the_eager_ones() {
    let cloud = bumpy_surface(30_000, 0.0).points;
    let target = IcpTarget::new(&cloud, false);
    assert_eq!(target.normals_estimated(), 0);
    let truth = motion([3.0, -2.0, 1.0], [0.02, 0.0, -0.01]);
    let source = PointCloud::new(refine::even_sample(&cloud, 1000)).transformed(&rigid_inverse(&truth)).points;
    let how = Refinement::new(IcpKind::Plane, 0.03, 0.03, 30);
    let c = refine::refine_best(&target, &source, &[(Start::Initial, nalgebra::Matrix4::identity())], &how).unwrap();
    assert!(rotation_error_deg(&c.T_target_source, &truth) < 0.05, "{}", c.T_target_source);
    let used = target.normals_estimated();
    assert!(used > 0 && used < cloud.len() / 5, "{used} of {} normals estimated", cloud.len());
    // the confidence's evidence estimates normals only where its probes' ICP and its slide (the
    // inliers') need them: its turns reach much of the target, but not every point of it
    let source_index = IcpTarget::new(&source, false);
    let e = arps::confidence::evidence(&target, &source_index, &source, &c.T_target_source, 0.03, IcpKind::Plane);
    assert!(e.fitness > 0.9, "{e:?}");
    let used = target.normals_estimated();
    assert!(used < cloud.len() * 4 / 5, "{used} of {} normals estimated with the evidence", cloud.len());
    assert_eq!(target.normals(), normals::estimate_normals(&cloud, arps::icp::NORMAL_NEIGHBOURS));
    assert_eq!(target.normals_estimated(), cloud.len());
}

#[test]
fn refinement_of_a_large_source_is_capped_and_recovers_the_motion() {
    let cloud = bumpy_surface(120_000, 0.3).points;
    let target = IcpTarget::new(&cloud, false);
    let truth = motion([8.0, -6.0, 5.0], [0.05, -0.04, 0.03]);
    let source = PointCloud::new(cloud.clone()).transformed(&rigid_inverse(&truth)).points;
    assert!(source.len() > 10 * refine::REFINE_POINTS);
    let how = Refinement::new(IcpKind::Plane, 0.02, 0.02, 30);
    let one = [(Start::Network, nalgebra::Matrix4::identity())];
    let c = refine::refine_best(&target, &source, &one, &how).unwrap();
    assert!(rotation_error_deg(&c.T_target_source, &truth) < 0.05, "{}", c.T_target_source);
    assert!(translation_error(&c.T_target_source, &truth) < 1e-3);
    // scored on the capped, evenly spread source
    let capped = refine::even_sample(&source, refine::REFINE_POINTS);
    assert_eq!((c.fitness, c.inlier_rmse), target.evaluate(&capped, &c.T_target_source, how.d_final));
    // every normal ICP asked for lies near a capped source point: a small share of the target
    let used = target.normals_estimated();
    assert!(used <= 2 * refine::REFINE_POINTS, "{used} normals for a {}-point target", cloud.len());
    // deterministic
    assert_eq!(refine::refine_best(&target, &source, &one, &how), Some(c));
}

#[test]
fn the_feature_voxel_follows_the_data() {
    let cloud = bumpy_surface(40_000, 0.6);
    let other = PointCloud::new(refine::even_sample(&cloud.points, 30_000));
    // dense scans: the finer start and the larger budget
    assert_eq!(
        global::density(&cloud, &other, &global::TargetFeatures::default(), global::VOXEL_FRACTION),
        global::Density::Dense
    );
    let v = global::feature_voxels(&cloud, &other, global::VOXEL_FRACTION)[0];
    for c in [&cloud, &other] {
        assert!(voxel_downsample(c, v as f32).len() <= global::DENSE_FEATURE_POINTS);
    }
    // no smaller than the fraction of the extent, and not grown past one 25% step too many
    let extent = cloud.half_extent().max(other.half_extent());
    let start = global::DENSE_VOXEL_FRACTION * extent;
    assert!(
        v >= start * (1.0 - 1e-12) && voxel_downsample(&cloud, (v / 1.25) as f32).len() > global::DENSE_FEATURE_POINTS
    );
    assert!(v < global::VOXEL_FRACTION * extent, "{v}: not finer than a sparse pair's");
    // too few points to be a dense scan: the default start and budget
    let fewer = PointCloud::new(refine::even_sample(&cloud.points, 2_900));
    assert_ne!(
        global::density(&fewer, &fewer, &global::TargetFeatures::default(), global::VOXEL_FRACTION),
        global::Density::Dense
    );
    let v_few = global::feature_voxels(&fewer, &fewer, global::VOXEL_FRACTION)[0];
    assert!(v_few >= global::VOXEL_FRACTION * fewer.half_extent());
    assert!(voxel_downsample(&fewer, v_few as f32).len() <= global::MAX_FEATURE_POINTS);
    // the same shape in millimetres: the voxel in millimetres
    let mm = |c: &PointCloud| PointCloud::new(c.points.iter().map(|p| p.map(|x| x * 1000.0)).collect());
    let v_mm = global::feature_voxels(&mm(&cloud), &mm(&other), global::VOXEL_FRACTION)[0];
    assert!((v_mm / (1000.0 * v) - 1.0).abs() < 1e-3, "{v_mm} vs {v}");
    // a sparse cloud is described as it is
    let sparse = PointCloud::new(refine::even_sample(&cloud.points, 800));
    let own = global::VOXEL_FRACTION * sparse.half_extent();
    assert_eq!(global::feature_voxels(&sparse, &sparse, global::VOXEL_FRACTION)[0], own);
}

/// A large cloud's voxelised copy, at half the finest feature voxel, stands in for its points in
/// the global stage (`global::standin`): the dense verdict counts the cloud's own points, the
/// feature voxel is about the one of the points themselves, and the hypotheses from the copies
/// recover a motion of any size as those from the points do. A copy that saves few points, or
/// one voxelised coarser, does not stand in.
#[test]
fn a_voxelised_copy_stands_in_for_a_large_cloud_in_the_global_stage() {
    let full = bumpy_surface(300_000, 0.4);
    let source_full = crop(&full, [1.0, 0.3, 0.0], 0.7);
    let target = crop(&full, [-0.2, 1.0, 0.4], 0.7);
    let truth = motion([150.0, -60.0, 95.0], [0.3, -0.2, 0.1]);
    let source = source_full.transformed(&rigid_inverse(&truth));
    let extent = source.half_extent().max(target.half_extent());
    let fraction = global::VOXEL_FRACTION;
    let voxel = 0.5 * global::DENSE_VOXEL_FRACTION * extent;
    let (source_v, target_v) = (voxel_downsample(&source, voxel as f32), voxel_downsample(&target, voxel as f32));
    assert!(source_v.len() * global::STANDIN_REDUCTION <= source.len(), "{} of {}", source_v.len(), source.len());
    let s = global::standin(&source, &source_v, voxel, extent, fraction);
    let t = global::standin(&target, &target_v, voxel, extent, fraction);
    assert!(std::ptr::eq(s.points, &source_v) && s.count == source.len());
    assert!(std::ptr::eq(t.points, &target_v) && t.count == target.len());
    // the copy voxelised coarser than half the finest feature voxel, or one that saves too few
    // points: the cloud stands for itself
    let coarse = global::standin(&source, &source_v, 1.5 * voxel, extent, fraction);
    assert!(std::ptr::eq(coarse.points, &source) && coarse.count == source.len());
    let few = PointCloud::new(refine::even_sample(&source.points, 2 * source_v.len() - 1));
    let same = global::standin(&few, &source_v, voxel, extent, fraction);
    assert!(std::ptr::eq(same.points, &few));
    // dense as the points are: by the cloud's own count, per voxel the copy occupies
    let memo = global::TargetFeatures::default;
    assert_eq!(global::density(&source, &target, &memo(), fraction), global::Density::Dense);
    assert_eq!(global::density(s, t, &memo(), fraction), global::Density::Dense);
    let sparse_count = global::FeatureCloud { points: &source_v, count: source_v.len() / 100 };
    assert_ne!(global::density(sparse_count, t, &memo(), fraction), global::Density::Dense);
    // about the feature voxel of the points themselves
    let (v_points, v_copies) =
        (global::feature_voxels(&source, &target, fraction)[0], global::feature_voxels(s, t, fraction)[0]);
    assert!((v_copies / v_points - 1.0).abs() < 0.3, "{v_copies} against {v_points}");
    // the hypotheses from the copies are those from the points (here the truth and the shape's
    // half-turned look-alike), and recover the motion
    let params = global::GlobalParams::default();
    let poses = |m: global::Matched| m.hypotheses(&params).iter().map(|h| h.T_target_source).collect::<Vec<_>>();
    let from_points = poses(global::Matched::new(&source, &target, fraction));
    let from_copies = poses(global::Matched::onto(s, t, &memo(), fraction));
    assert!(from_points.len() >= 2, "{} hypotheses", from_points.len());
    for p in &from_points {
        let near = |c: &&nalgebra::Matrix4<f64>| rotation_error_deg(c, p) < 2.0 && translation_error(c, p) < 0.02;
        assert!(from_copies.iter().any(|c| near(&c)), "no hypothesis of the copies near {p}");
    }
    let recovers =
        |t: &nalgebra::Matrix4<f64>| rotation_error_deg(t, &truth) < 2.0 && translation_error(t, &truth) < 0.02;
    assert!(from_copies.iter().any(recovers), "the copies' hypotheses miss the truth");
}

/// A 280k + 280k-point pair (70% crops of a noisy bumpy surface against another, 25 degrees
/// apart) registers with the default options and the embedded model.
#[test]
fn a_large_pair_registers_with_the_default_options() {
    let full = bumpy_surface(400_000, 0.9);
    let mut r = rng(3);
    let mut noisy = |c: PointCloud| {
        PointCloud::new(c.points.iter().map(|p| p.map(|x| x + (r.random::<f32>() - 0.5) * 0.004)).collect())
    };
    let source_full = noisy(crop(&full, [1.0, 0.3, 0.0], 0.7));
    let target = noisy(crop(&full, [-0.2, 1.0, 0.4], 0.7));
    let truth = motion([25.0, -10.0, 15.0], [0.3, -0.2, 0.1]);
    let source = source_full.transformed(&rigid_inverse(&truth));
    assert!(source.len() >= 270_000 && target.len() >= 270_000);
    let mut reg = Registrar::with_default_model().unwrap();
    let out = reg.register(&source, &target, &Options::default()).unwrap();
    let re = rotation_error_deg(&out.T_target_source, &truth);
    let te = translation_error(&out.T_target_source, &truth);
    assert!(re < 1.0 && te < 0.02, "RE {re:.3} deg, TE {te:.4}, start {:?}", out.start);
}

/// A pose refined only where it lands somewhere new (`refine::refine_final_screened`): the next of
/// two alike parts side by side is refined onto it, while a pose a little off the answer (it comes
/// back onto the answer) and one beside both parts (it fits nothing) are dropped after a run on a
/// sample, before any refinement on every point.
#[test]
fn a_pose_is_refined_on_every_point_only_where_it_lands_somewhere_new() {
    let part = bumpy_surface(6_000, 0.2).points;
    let truth = motion([10.0, -5.0, 20.0], [0.1, 0.0, -0.1]);
    let beside = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(4.0, 0.0, 0.0)) * truth;
    let placed = |t| PointCloud::new(part.clone()).transformed(t).points;
    let target = IcpTarget::new(&[placed(&truth), placed(&beside)].concat(), false);
    let source = crop(&PointCloud::new(part.clone()), [0.0, 0.0, 1.0], 0.7).points;
    assert!(source.len() > refine::SCREEN_POINTS);
    let how = Refinement::new(IcpKind::Plane, 0.02, 0.02, 30);
    let refined = |from: &nalgebra::Matrix4<f64>| {
        refine::refine_final_screened(&target, &source, Start::Global, from, &how, &truth)
    };
    // the next part, placed a little off: refined onto it, as `refine_final` would
    let off = motion([1.0, 0.5, 0.0], [0.01, 0.0, 0.0]);
    let next = refined(&(beside * off)).expect("the next part is somewhere new");
    assert!(
        rotation_error_deg(&next.T_target_source, &beside) < 0.05
            && translation_error(&next.T_target_source, &beside) < 1e-3
    );
    assert!(next.fitness > 0.95, "{}", next.fitness);
    assert_eq!(Some(next), refined(&(beside * off)), "deterministic");
    // back onto the answer, and nowhere at all
    assert_eq!(refined(&(truth * off)), None);
    let away = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(0.0, 3.0, 0.0)) * truth;
    assert_eq!(refined(&away), None);
    // ICP off: nothing to run, the pose is scored where it is
    let off_how = Refinement::new(IcpKind::Off, 0.02, 0.02, 30);
    let scored = refine::refine_final_screened(&target, &source, Start::Global, &away, &off_how, &truth).unwrap();
    assert_eq!((scored.T_target_source, scored.iterations), (away, 0));
}
