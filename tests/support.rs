//! Support planes (`Options::support_plane`, `arps::support`): a real capture of a mug on a table
//! (PCL's table scene) registered onto the mug alone and the other way round, and onto a second
//! capture with the mug turned over. The tables are left out, the transform of the mug recovered
//! with a sure verdict; kept, they pull the answer away.

mod common;

use arps::transform::rigid_inverse;
use arps::{Options, PointCloud, Registrar, Support};
use nalgebra::Matrix4;

/// The table top with the mug on it (camera frame, metres).
fn scene() -> PointCloud {
    arps::io::read_point_cloud(include_bytes!("../fixtures/scans/table-mug-scene.ply"), "scene.ply").unwrap()
}

/// The mug alone, from other pixels of the same capture (camera frame, metres).
fn mug() -> PointCloud {
    arps::io::read_point_cloud(include_bytes!("../fixtures/scans/table-mug-object.ply"), "mug.ply").unwrap()
}

/// The scene's points split in two captures of the same table and mug (alternate points).
fn two_captures() -> (PointCloud, PointCloud) {
    let scene = scene();
    let (even, odd): (Vec<_>, Vec<_>) = scene.points.iter().enumerate().partition(|(i, _)| i % 2 == 0);
    let capture = |half: Vec<(usize, &[f32; 3])>| PointCloud::new(half.into_iter().map(|(_, p)| *p).collect());
    (capture(even), capture(odd))
}

fn keep() -> Options {
    Options { support_plane: Support::Keep, ..Options::default() }
}

/// The motions the mug is moved by (degrees about x, y, z; metres).
const MOTIONS: [([f64; 3], [f64; 3]); 3] = [
    ([20.0, -10.0, 30.0], [0.1, -0.05, 0.2]),
    ([0.0, 0.0, 90.0], [-0.3, 0.1, 0.0]),
    ([-40.0, 25.0, 10.0], [0.0, 0.4, -0.2]),
];

#[test]
fn the_table_under_a_captured_mug_is_left_out_and_the_mug_registered_onto_its_model() {
    let mut registrar = Registrar::with_default_model().unwrap();
    let plane = arps::support::find(&scene().points).expect("the table is a support plane");
    // the table holds most of the capture; the mug (a tenth of it) stays
    assert!(plane.indices.len() > scene().len() * 4 / 5 && plane.indices.len() < scene().len() * 9 / 10);
    assert_eq!(arps::support::find(&mug().points), None);
    for (deg, t) in MOTIONS {
        let gt = common::motion(deg, t);
        let model = mug().transformed(&gt);
        // the capture onto the model, and the model into the capture
        for (source, target, truth, what) in
            [(scene(), model.clone(), gt, "source"), (model.clone(), scene(), rigid_inverse(&gt), "target")]
        {
            let r = registrar.register(&source, &target, &Options::default()).unwrap();
            let (re, te) = common::errors(&r.T_target_source, &truth);
            assert!(re < 0.3 && te < 0.003, "{deg:?} {what}: {re} deg, {te} m");
            assert!(r.confidence > 0.9, "{deg:?} {what}: confidence {}", r.confidence);
            let warning = format!("left out a plane of {} of the {what}'s", plane.indices.len());
            assert!(r.warnings.iter().any(|w| w.starts_with(&warning)), "{:?}", r.warnings);
            // kept, the table is most of the capture and finds no counterpart: the same pose
            // (the mug leads ICP), but an unsure verdict (confidence 0.36, measured)
            let kept = registrar.register(&source, &target, &keep()).unwrap();
            if what == "source" {
                assert!(kept.confidence < 0.5, "{deg:?}: kept, confidence {}", kept.confidence);
            }
            assert!(kept.warnings.iter().all(|w| !w.contains("left out a plane")), "{:?}", kept.warnings);
        }
    }
}

#[test]
fn two_captures_of_a_mug_that_stood_still_are_registered_with_or_without_their_tables() {
    // two captures of the same table and mug (alternate points), one moved
    let (first, second) = two_captures();
    let gt = common::motion([15.0, -20.0, 35.0], [0.2, 0.1, -0.1]);
    let second = second.transformed(&gt);
    let mut registrar = Registrar::with_default_model().unwrap();
    let r = registrar.register(&first, &second, &Options::default()).unwrap();
    for what in ["source", "target"] {
        let warning = format!("of the {what}'s");
        assert!(r.warnings.iter().any(|w| w.contains("left out a plane") && w.contains(&warning)), "{:?}", r.warnings);
    }
    let (re, te) = common::errors(&r.T_target_source, &gt);
    assert!(re < 0.5 && te < 0.005, "{re} deg, {te} m");
    let kept = registrar.register(&first, &second, &keep()).unwrap();
    assert!(kept.warnings.iter().all(|w| !w.contains("left out a plane")), "{:?}", kept.warnings);
    let (re, te) = common::errors(&kept.T_target_source, &gt);
    assert!(re < 0.3 && te < 0.003, "kept: {re} deg, {te} m");
}

/// The scene's points split in two captures (alternate points), the second with the mug tipped
/// over onto its side on the table and the whole capture moved by `camera`: the second capture,
/// and the truth for the mug (the first capture's mug onto the second's).
fn tipped_over(camera: &Matrix4<f64>) -> (PointCloud, PointCloud, Matrix4<f64>) {
    use nalgebra::{Rotation3, Translation3, Unit, Vector3};
    let (first, second) = two_captures();
    let plane = arps::support::find(&second.points).expect("a table");
    let n = Vector3::from(plane.normal);
    let on = Vector3::from(plane.point);
    let is_table: std::collections::HashSet<usize> = plane.indices.iter().copied().collect();
    let mug: Vec<Vector3<f64>> =
        (0..second.len()).filter(|i| !is_table.contains(i)).map(|i| second.points[i].map(f64::from).into()).collect();
    let c = mug.iter().sum::<Vector3<f64>>() / mug.len() as f64;
    // a quarter turn about an axis along the table, through the mug's centre, then down onto it
    let axis = Unit::new_normalize(n.cross(&Vector3::new(1.0, 0.0, 0.0)));
    let turn =
        Translation3::from(c) * Rotation3::from_axis_angle(&axis, std::f64::consts::FRAC_PI_2) * Translation3::from(-c);
    let lowest = mug
        .iter()
        .map(|p| (turn * nalgebra::Point3::from(*p) - nalgebra::Point3::from(on)).dot(&n))
        .fold(f64::INFINITY, f64::min);
    let tip = Translation3::from(-n * (lowest - 0.002)).to_homogeneous() * turn.to_homogeneous();
    let points = (0..second.len())
        .map(|i| {
            let p = nalgebra::Point3::from(second.points[i].map(f64::from));
            let p = if is_table.contains(&i) { p } else { tip.transform_point(&p) };
            let q = camera.transform_point(&p);
            [q.x as f32, q.y as f32, q.z as f32]
        })
        .collect();
    (first, PointCloud::new(points), camera * tip)
}

#[test]
fn a_mug_turned_over_on_the_table_between_two_captures_is_registered_without_the_tables() {
    // what a second scan of an object sees when it was turned over to scan its other side
    let camera = common::motion([10.0, -15.0, 25.0], [0.1, 0.05, -0.1]);
    let (first, second, truth) = tipped_over(&camera);
    let mut registrar = Registrar::with_default_model().unwrap();
    let r = registrar.register(&first, &second, &Options::default()).unwrap();
    let (re, te) = common::errors(&r.T_target_source, &truth);
    assert!(re < 1.0 && te < 0.005, "{re} deg, {te} m: {:?}", r.warnings);
    assert_eq!(r.warnings.iter().filter(|w| w.contains("left out a plane")).count(), 2, "{:?}", r.warnings);
    // kept, the tables pull the mug's answer onto the table's motion
    let kept = registrar.register(&first, &second, &keep()).unwrap();
    let (re, _) = common::errors(&kept.T_target_source, &truth);
    assert!(re > 15.0, "kept: {re} deg");
}

/// `capture` seen wider: its table repeated in `tiles` by `tiles` tiles (odd) about itself, so
/// that the mug is a small part of the view.
fn widened(capture: &PointCloud, tiles: i32) -> PointCloud {
    use nalgebra::Vector3;
    let plane = arps::support::find(&capture.points).expect("a table");
    let n = Vector3::from(plane.normal);
    let u = n.cross(&Vector3::new(1.0, 0.0, 0.0)).normalize();
    let v = n.cross(&u);
    let table: Vec<Vector3<f64>> = plane.indices.iter().map(|&i| capture.points[i].map(f64::from).into()).collect();
    let width = |axis: &Vector3<f64>| {
        let along = table.iter().map(|p| p.dot(axis));
        along.clone().fold(f64::NEG_INFINITY, f64::max) - along.fold(f64::INFINITY, f64::min)
    };
    let (wu, wv) = (width(&u), width(&v));
    let mut points = capture.points.clone();
    let reach = tiles / 2;
    for (a, b) in (-reach..=reach).flat_map(|a| (-reach..=reach).map(move |b| (a, b))).filter(|&ab| ab != (0, 0)) {
        let shift = u * (a as f64 * wu) + v * (b as f64 * wv);
        points.extend(table.iter().map(|p| p + shift).map(|q| [q.x as f32, q.y as f32, q.z as f32]));
    }
    PointCloud::with_origin(points, capture.origin)
}

#[test]
fn a_view_that_is_nearly_all_table_loses_its_table_when_the_other_view_does() {
    // the second capture seen wider, the mug a small part of it: alone its table is no support
    // (too little stands on it: a flat object or a wall), but the first capture stands on one,
    // so both tables are left out and the mug registered
    let (first, second) = two_captures();
    let gt = common::motion([15.0, -20.0, 35.0], [0.2, 0.1, -0.1]);
    let wide = widened(&second, 3).transformed(&gt);
    let sample = arps::spacing::Spacing::of(&wide.points);
    assert_eq!(arps::support::find_with(&wide.points, &sample), None);
    assert!(arps::support::find_paired(&wide.points, &sample).is_some());
    let mut registrar = Registrar::with_default_model().unwrap();
    for (source, target, truth) in [(&first, &wide, gt), (&wide, &first, rigid_inverse(&gt))] {
        let r = registrar.register(source, target, &Options::default()).unwrap();
        let (re, te) = common::errors(&r.T_target_source, &truth);
        assert!(re < 0.5 && te < 0.005, "{re} deg, {te} m");
        assert!(r.confidence > 0.9, "confidence {}", r.confidence);
        assert_eq!(r.warnings.iter().filter(|w| w.contains("left out a plane")).count(), 2, "{:?}", r.warnings);
    }
    // the wide view kept between calls: searched for a table as the pair of a source that
    // stands on one, and then not (the mug alone), each as a registrar's first call
    for source in [&first, &mug(), &first] {
        let again = registrar.register(source, &wide, &Options::default()).unwrap();
        let fresh = Registrar::with_default_model().unwrap().register(source, &wide, &Options::default()).unwrap();
        assert_eq!(again.T_target_source, fresh.T_target_source);
        assert_eq!(again.warnings, fresh.warnings);
    }
}

#[test]
fn two_views_that_are_nearly_all_table_lose_both_tables() {
    // a small object on a turntable or a desk: the mug a small part of both captures, neither
    // table a support alone, each the pair of the other
    let (first, second) = two_captures();
    let first = widened(&first, 3);
    let gt = common::motion([-25.0, 10.0, 40.0], [0.1, -0.2, 0.05]);
    let second = widened(&second, 3).transformed(&gt);
    assert_eq!(arps::support::find(&first.points), None);
    assert_eq!(arps::support::find(&second.points), None);
    let r = Registrar::with_default_model().unwrap().register(&first, &second, &Options::default()).unwrap();
    let (re, te) = common::errors(&r.T_target_source, &gt);
    assert!(re < 0.5 && te < 0.005, "{re} deg, {te} m");
    assert!(r.confidence > 0.9, "confidence {}", r.confidence);
    assert_eq!(r.warnings.iter().filter(|w| w.contains("left out a plane")).count(), 2, "{:?}", r.warnings);
}

#[test]
fn a_mug_turned_over_in_a_view_that_is_nearly_all_table_is_registered_without_the_tables() {
    let camera = common::motion([10.0, -15.0, 25.0], [0.1, 0.05, -0.1]);
    let (first, second, truth) = tipped_over(&camera);
    let wide = widened(&second, 3);
    assert_eq!(arps::support::find(&wide.points), None);
    let r = Registrar::with_default_model().unwrap().register(&first, &wide, &Options::default()).unwrap();
    let (re, te) = common::errors(&r.T_target_source, &truth);
    assert!(re < 1.0 && te < 0.005, "{re} deg, {te} m: {:?}", r.warnings);
    assert_eq!(r.warnings.iter().filter(|w| w.contains("left out a plane")).count(), 2, "{:?}", r.warnings);
}

#[test]
fn a_target_kept_between_calls_gives_the_answers_of_a_fresh_registrar() {
    // the capture, its table left out once, as the target of three calls; each answer as a
    // registrar's first call
    let gt = common::motion([10.0, 5.0, -30.0], [0.05, 0.0, 0.1]);
    let target = scene().transformed(&gt);
    let sources = [mug(), scene(), mug()];
    let mut kept = Registrar::with_default_model().unwrap();
    for source in &sources {
        let again = kept.register(source, &target, &Options::default()).unwrap();
        let fresh = Registrar::with_default_model().unwrap().register(source, &target, &Options::default()).unwrap();
        assert_eq!(again.T_target_source, fresh.T_target_source);
        assert_eq!(again.warnings, fresh.warnings);
        let (re, te) = common::errors(&again.T_target_source, &gt);
        assert!(re < 0.3 && te < 0.003, "{re} deg, {te} m");
    }
}

#[test]
fn a_capture_with_stray_returns_loses_them_and_then_its_table() {
    // the capture with 40 stray returns 4-8 m out (its points span about a metre): the strays go
    // first, then the table is found on what is left, which is the capture itself again
    let capture = scene();
    let mut points = capture.points.clone();
    let (lo, hi) = capture.bounds();
    let centre: [f32; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
    for i in 0..40 {
        let (u, v) = (i as f32 * 2.399, i as f32 * 0.7);
        let r = 4.0 + (i % 5) as f32;
        points.push([centre[0] + r * u.cos() * v.sin(), centre[1] + r * u.sin() * v.sin(), centre[2] + r * v.cos()]);
    }
    let noisy = PointCloud::with_origin(points, capture.origin);
    assert_eq!(arps::outliers::far_outliers(&noisy.points), (capture.len()..noisy.len()).collect::<Vec<_>>());
    let plane = arps::support::find(&capture.points).expect("the table is a support plane");
    let gt = common::motion([20.0, -10.0, 30.0], [0.1, -0.05, 0.2]);
    let r = Registrar::with_default_model()
        .unwrap()
        .register(&noisy, &mug().transformed(&gt), &Options::default())
        .unwrap();
    let (re, te) = common::errors(&r.T_target_source, &gt);
    assert!(re < 0.3 && te < 0.003, "{re} deg, {te} m");
    let strays = format!("left out 40 of the source's {} points", noisy.len());
    let table = format!("left out a plane of {} of the source's {} points", plane.indices.len(), capture.len());
    for warning in [strays, table] {
        assert!(r.warnings.iter().any(|w| w.starts_with(&warning)), "{warning}: {:?}", r.warnings);
    }
}

#[test]
fn a_cloud_without_a_support_plane_is_registered_as_with_every_point_kept() {
    let mut registrar = Registrar::with_default_model().unwrap();
    for index in [0, 3, 8] {
        let (source, target, _) = common::fixture_pair(index);
        assert_eq!(arps::support::find(&source.points), None);
        assert_eq!(arps::support::find(&target.points), None);
        let dropped = registrar.register(&source, &target, &Options::default()).unwrap();
        let kept = registrar.register(&source, &target, &keep()).unwrap();
        assert_eq!(dropped.T_target_source, kept.T_target_source, "pair {index}");
    }
}

#[test]
fn the_option_is_read_from_json_and_a_bad_value_is_a_clear_error() {
    common::drop_or_keep_from_json("supportPlane", |o| o.support_plane, Support::Drop, Support::Keep);
}
