//! A registrar keeps the last target it prepared and reuses it for the same target: every
//! registration gives what a fresh registrar gives, bit for bit, whatever came between (other
//! scans of the same model, a larger source, other options, another target, the same points at
//! another origin, a failed call, `forget_target`).

mod common;

use arps::io::{read_mesh, read_point_cloud_with, ReadOptions};
use arps::transform::rigid_inverse;
use arps::{NonFinite, Options, PointCloud, Registrar, Registration, Search, Timings};
use common::{bumpy_surface, crop, motion};

/// The CAD model (an STL read as 20,000 surface points) and three close-ups of it: other points of
/// its surface within 60% of its half-extent of one of them, moved by a known motion (one far
/// beyond the network's range). In any pose a close-up is smaller than the model in its own axes
/// (largest bounding-box half-extent), so a registrar keeps the model from one to the next.
fn model_and_scans() -> (PointCloud, Vec<PointCloud>) {
    let name = "angle_block_binary_solid.stl";
    let bytes = std::fs::read(format!("{}/fixtures/formats/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let model = read_point_cloud_with(
        &bytes,
        name,
        &ReadOptions { surface_points: Some(20_000), seed: 0, scan: None, classes: None, min_opacity: None },
    )
    .unwrap();
    let dense = read_mesh(&bytes, name).unwrap().sample_surface(6_000, 7).unwrap();
    let reach = 0.6 * model.half_extent() as f32;
    let close_up = |c: [f32; 3]| {
        let near = |p: &&[f32; 3]| (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f32>() < reach * reach;
        PointCloud::new(dense.points.iter().filter(near).copied().collect())
    };
    let scans = [
        (100, [10.0, -20.0, 30.0], [0.5, 0.2, -0.3]),
        (2_000, [-5.0, 15.0, 8.0], [0.1, 0.0, 0.2]),
        (4_000, [120.0, 40.0, -70.0], [1.0, 0.0, 0.5]),
    ]
    .map(|(at, degrees, shift)| close_up(dense.points[at]).transformed(&rigid_inverse(&motion(degrees, shift))));
    for (k, scan) in scans.iter().enumerate() {
        assert!(scan.half_extent() < model.half_extent(), "scan {k} is not smaller than the model");
    }
    (model, scans.to_vec())
}

/// `r` without its timings (the only part that may differ between runs).
fn untimed(r: Registration) -> Registration {
    Registration { timings: Timings::default(), ..r }
}

/// What a registrar that never saw another pair answers.
fn fresh(source: &PointCloud, target: &PointCloud, options: &Options) -> arps::Result<Registration> {
    Registrar::with_default_model().unwrap().register(source, target, options).map(untimed)
}

#[test]
fn registrations_onto_a_kept_target_equal_fresh_ones() {
    let (model, scans) = model_and_scans();
    let defaults = Options::default();
    let seeded = Options { seed: 3, ..Options::default() };
    let voxel = Options { voxel_size: Some(0.01), ..Options::default() };
    let exhaustive = Options { search: Search::Exhaustive, ..Options::default() };
    // the close-ups are smaller than the model, and the model is kept from one call to the next
    // (reused, or resized for another seed or voxel); a source larger than the model: the
    // normalisation's scale is the source's, and the model is prepared anew
    let large = PointCloud::new(bumpy_surface(3_000, 0.3).points.iter().map(|p| p.map(|v| v * 2.0)).collect());
    // the model's points at another origin: another target
    let moved = PointCloud::with_origin(model.points.clone(), [1000.0, -20.0, 5.0]);
    let other = bumpy_surface(4_000, 0.7);
    let calls: Vec<(&PointCloud, &PointCloud, &Options)> = vec![
        (&scans[0], &model, &defaults),
        (&scans[1], &model, &defaults),
        (&scans[2], &model, &defaults), // any pose: the global stage describes the model
        (&scans[2], &model, &defaults), // and uses its descriptors again
        (&scans[0], &model, &defaults),
        (&scans[0], &model, &seeded),
        (&scans[1], &model, &voxel),
        (&large, &model, &defaults),
        (&scans[1], &model, &defaults),
        (&scans[2], &model, &exhaustive),
        (&scans[1], &moved, &defaults),
        (&scans[1], &other, &defaults),
        (&scans[2], &model, &defaults),
    ];
    let mut kept = Registrar::with_default_model().unwrap();
    for (k, (source, target, options)) in calls.into_iter().enumerate() {
        let again = untimed(kept.register(source, target, options).unwrap());
        assert_eq!(again, fresh(source, target, options).unwrap(), "call {k}");
    }
}

/// A large target (the CAD model read as 400,000 surface points), whose ICP copy stands in for
/// its points in the global stage (`global::standin`): kept from call to call, through another
/// ICP voxel (another copy, which no longer stands in) and back, every registration equals a
/// fresh one.
#[test]
fn registrations_onto_a_kept_large_target_equal_fresh_ones_through_another_voxel() {
    let name = "angle_block_binary_solid.stl";
    let bytes = std::fs::read(format!("{}/fixtures/formats/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let model = read_point_cloud_with(
        &bytes,
        name,
        &ReadOptions { surface_points: Some(400_000), seed: 1, scan: None, classes: None, min_opacity: None },
    )
    .unwrap();
    let (_, scans) = model_and_scans();
    // the default ICP voxel (half of 0.025 of the scale, the model's half-extent) keeps at most
    // half the model's points, so its copy stands in; at a tenth of that voxel, it does not
    let scale = model.half_extent();
    let copy = arps::sampling::voxel_downsample(&model, (0.0125 * scale) as f32);
    assert!(copy.len() * arps::global::STANDIN_REDUCTION <= model.len(), "{} of {}", copy.len(), model.len());
    let defaults = Options::default();
    let fine = Options { voxel_size: Some(0.00125 * scale), ..Options::default() };
    let calls: Vec<(&PointCloud, &Options)> = vec![
        (&scans[2], &defaults), // any pose: the global stage describes the model's copy
        (&scans[2], &fine),     // another copy, the model's own points described
        (&scans[2], &defaults), // the default copy again
        (&scans[1], &defaults),
    ];
    let mut kept = Registrar::with_default_model().unwrap();
    for (k, (source, options)) in calls.into_iter().enumerate() {
        let again = untimed(kept.register(source, &model, options).unwrap());
        assert_eq!(again, fresh(source, &model, options).unwrap(), "call {k}");
    }
}

#[test]
fn a_failed_call_or_forget_target_leaves_the_next_registration_as_a_fresh_one() {
    let (model, scans) = model_and_scans();
    let defaults = Options::default();
    let mut kept = Registrar::with_default_model().unwrap();
    let first = untimed(kept.register(&scans[0], &model, &defaults).unwrap());
    assert_eq!(first, fresh(&scans[0], &model, &defaults).unwrap());
    // a source with a NaN: an error, and the model's next registration is as a fresh one's
    let mut bad = scans[1].clone();
    bad.points[5][1] = f32::NAN;
    let err = kept.register(&bad, &model, &defaults).unwrap_err().to_string();
    assert!(err.contains("source point 5"), "{err}");
    assert_eq!(
        untimed(kept.register(&scans[1], &model, &defaults).unwrap()),
        fresh(&scans[1], &model, &defaults).unwrap()
    );
    // a bad option after the model was kept
    let bad_option = Options { max_correspondence_distance: Some(-1.0), ..Options::default() };
    assert!(kept.register(&scans[1], &model, &bad_option).is_err());
    assert_eq!(
        untimed(kept.register(&scans[2], &model, &defaults).unwrap()),
        fresh(&scans[2], &model, &defaults).unwrap()
    );
    kept.forget_target();
    assert_eq!(untimed(kept.register(&scans[0], &model, &defaults).unwrap()), first);
}

#[test]
fn the_same_points_with_a_nan_follow_the_non_finite_option_each_time() {
    let (model, scans) = model_and_scans();
    let mut target = model.clone();
    target.points[11] = [f32::NAN, 0.0, 0.0];
    let drop = Options { non_finite: NonFinite::Drop, ..Options::default() };
    let mut kept = Registrar::with_default_model().unwrap();
    let dropped = untimed(kept.register(&scans[0], &target, &drop).unwrap());
    assert_eq!(dropped, fresh(&scans[0], &target, &drop).unwrap());
    // the target kept from the call that dropped its NaN is not taken for the one that must fail
    let err = kept.register(&scans[0], &target, &Options::default()).unwrap_err().to_string();
    assert!(err.contains("target point 11"), "{err}");
    assert_eq!(untimed(kept.register(&scans[0], &target, &drop).unwrap()), dropped);
}

/// Each scan registered onto `target` by a registrar that kept the target from the scan before,
/// and by one told to forget it, alternated, twice over the scans. Prints the median milliseconds
/// per call of each (the whole call, and its preparation), their ratio, and how many answers of
/// each were right (under `degrees` of rotation error).
fn time_kept_and_anew(what: &str, target: &PointCloud, scans: &[(PointCloud, nalgebra::Matrix4<f64>)], degrees: f64) {
    use arps::transform::rotation_error_deg;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (mut kept, mut forgetting) =
        (Registrar::with_default_model().unwrap(), Registrar::with_default_model().unwrap());
    kept.register(&scans[0].0, target, &Options::default()).unwrap();
    // per registrar (kept, anew): whole-call ms, preparation ms, right answers
    let mut tally: [(Vec<f64>, Vec<f64>, usize); 2] = Default::default();
    for round in 0..2 {
        for (k, (scan, gt)) in scans.iter().enumerate() {
            let order = if (round + k) % 2 == 0 { [0, 1] } else { [1, 0] };
            for which in order {
                let t0 = std::time::Instant::now();
                let r = if which == 0 {
                    kept.register(scan, target, &Options::default()).unwrap()
                } else {
                    forgetting.forget_target();
                    forgetting.register(scan, target, &Options::default()).unwrap()
                };
                let t = &mut tally[which];
                t.0.push(t0.elapsed().as_secs_f64() * 1e3);
                t.1.push(r.timings.preprocess_ms);
                t.2 += (rotation_error_deg(&r.T_target_source, gt) < degrees) as usize;
            }
        }
    }
    let [(a, pa, ra), (b, pb, rb)] = tally;
    let n = a.len();
    let (a, b, pa, pb) = (median(a), median(b), median(pa), median(pb));
    println!(
        "{what} ({} target points), {n} calls: kept {a:.1} ms (preparation {pa:.1}), prepared anew {b:.1} ms ({pb:.1}); ratio {:.2}; right {ra} / {rb}",
        target.len(),
        a / b
    );
}

/// The measurement behind `BENCHMARK.md`, "Many scans onto one target", through
/// [`time_kept_and_anew`]:
/// - local captures onto a LiDAR map: the small_gicp Velodyne target scan (69,000 points, from
///   `../shared/data/scans`; skipped when absent) and six parts of the other scan (the points
///   within 15 m of six of its points), each turned up to 30 degrees about the vertical and moved
///   up to 5 m, with the pair's ground truth;
/// - scans of a CAD model: the STL fixture read as 200,000 and 1,000,000 surface points; six scans
///   of it (20,000 other surface points each, the 70% on one side of a plane), moved by any
///   rotation, six by at most 30 degrees per axis, and six close-ups (the points of such a scan
///   within 40% of the model's half-extent of one of them) moved by at most 30 degrees per axis.
///
/// `cargo test --release --test target_reuse -- --ignored --nocapture`.
#[test]
#[ignore]
fn many_scans_onto_one_target() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let scans_dir = format!("{}/../shared/data/scans", env!("CARGO_MANIFEST_DIR"));
    if let Ok(pairs) = std::fs::read_to_string(format!("{scans_dir}/pairs.tsv")) {
        let line = pairs.lines().find(|l| l.starts_with("velodyne-outdoor")).unwrap();
        let fields: Vec<&str> = line.split('\t').collect();
        let v: Vec<f64> = fields[5].split_whitespace().map(|x| x.parse().unwrap()).collect();
        let t_target_source = nalgebra::Matrix4::from_row_slice(&v);
        let read = |name: &str| {
            arps::io::read_point_cloud(&std::fs::read(format!("{scans_dir}/{name}")).unwrap(), name).unwrap()
        };
        let (source, map) = (read(fields[1]), read(fields[2]));
        let captures: Vec<(PointCloud, nalgebra::Matrix4<f64>)> = (0..6)
            .map(|_| {
                let c = source.points[rng.random_range(0..source.len())];
                let near = |p: &&[f32; 3]| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) < 15.0f32.powi(2);
                let part = PointCloud::with_origin(source.points.iter().filter(near).copied().collect(), source.origin);
                let m = motion(
                    [0.0, 0.0, rng.random_range(-30.0..30.0)],
                    [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0), 0.0],
                );
                (part.transformed(&rigid_inverse(&m)), t_target_source * m)
            })
            .collect();
        time_kept_and_anew("local captures onto a LiDAR map", &map, &captures, 2.0);
    } else {
        eprintln!("no {scans_dir}/pairs.tsv: the LiDAR map skipped");
    }
    let name = "angle_block_binary_solid.stl";
    let bytes = std::fs::read(format!("{}/fixtures/formats/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mesh = read_mesh(&bytes, name).unwrap();
    let mut scans = |max_degrees: f64| -> Vec<(PointCloud, nalgebra::Matrix4<f64>)> {
        (0..6)
            .map(|k| {
                let dense = mesh.sample_surface(28_572, 100 + k).unwrap();
                let dir = [0; 3].map(|_| rng.random_range(-1.0f32..1.0));
                let degrees = [0; 3].map(|_| rng.random_range(-max_degrees..max_degrees));
                let shift = [0; 3].map(|_| rng.random_range(-0.5..0.5));
                let gt = motion(degrees, shift);
                (crop(&dense, dir, 0.7).transformed(&rigid_inverse(&gt)), gt)
            })
            .collect()
    };
    let (any_pose, small_turns) = (scans(180.0), scans(30.0));
    // close-ups: the points of a scan within 40% of the model's half-extent of one of them
    let close_ups: Vec<(PointCloud, nalgebra::Matrix4<f64>)> = (0..6)
        .map(|k| {
            let dense = mesh.sample_surface(28_572, 200 + k).unwrap();
            let reach = 0.4 * dense.half_extent() as f32;
            let c = dense.points[rng.random_range(0..dense.len())];
            let near = |p: &&[f32; 3]| (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f32>() < reach * reach;
            let part = PointCloud::new(dense.points.iter().filter(near).copied().collect());
            let degrees = [0; 3].map(|_| rng.random_range(-30.0..30.0));
            let gt = motion(degrees, [0; 3].map(|_| rng.random_range(-0.5..0.5)));
            (part.transformed(&rigid_inverse(&gt)), gt)
        })
        .collect();
    let sets = [
        ("CAD model, scans in any pose", any_pose),
        ("CAD model, scans up to 30 degrees", small_turns),
        ("CAD model, close-ups up to 30 degrees", close_ups),
    ];
    for points in [200_000, 1_000_000] {
        let model = read_point_cloud_with(
            &bytes,
            name,
            &ReadOptions { surface_points: Some(points), seed: 0, scan: None, classes: None, min_opacity: None },
        )
        .unwrap();
        for (what, scans) in &sets {
            time_kept_and_anew(what, &model, scans, 5.0);
        }
    }
}
