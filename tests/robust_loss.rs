//! `icpLoss: "robust"` (the default): two surveys of a terrain between which a stretch changed (a
//! cliff that retreated, a building that went up, a fill pad within the distance, a raised corner).
//! Least squares lets the changed surface pull the answer; the robust refinements are held by the
//! surfaces that stayed.

mod common;
use arps::{IcpLoss, Options, PointCloud, Registrar, Start};
use nalgebra::Matrix4;

/// Heights of a rolling terrain (hills and a ridge) at `(x, y)`, units of metres over 100 m.
fn ground(x: f64, y: f64) -> f64 {
    3.0 * (x * 0.07).sin() * (y * 0.05).cos() + 2.0 * (0.11 * x + 0.06 * y).sin() + 0.02 * x
}

/// A 100 x 100 survey on a 1 m grid, jittered by `seed`; with `changed`, a 30 x 30 stretch raised
/// by 4 (a new building block) and another slid 3 seaward (a cliff edge that retreated).
fn survey(seed: u64, changed: bool) -> PointCloud {
    use rand::Rng;
    let mut rng = arps::sampling::rng(seed);
    let mut pts = Vec::new();
    for i in 0..100 {
        for j in 0..100 {
            let (x, y) = (i as f64 + rng.random::<f64>(), j as f64 + rng.random::<f64>());
            let mut z = ground(x, y);
            if changed && (60.0..90.0).contains(&x) && (10.0..40.0).contains(&y) {
                z += 4.0;
            }
            if changed && (10.0..40.0).contains(&x) && (60.0..90.0).contains(&y) {
                z = ground(x + 3.0, y);
            }
            pts.push([x as f32, y as f32, z as f32]);
        }
    }
    PointCloud::new(pts)
}

#[test]
fn a_changed_stretch_pulls_least_squares_and_not_the_robust_refinement() {
    let truth = common::motion([0.3, -0.2, 1.0], [1.5, -2.0, 0.6]);
    let inverse = truth.try_inverse().unwrap();
    // the second epoch, in its own slightly misaligned frame: source = inverse(truth) * epoch 2
    let source = survey(2, true).transformed(&inverse);
    let target = survey(1, false);
    let rows = |m: &Matrix4<f64>| std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]));
    let options = |loss| Options {
        initial_transform: Some(rows(&Matrix4::identity())),
        network: false,
        starts: vec![Start::Initial],
        max_correspondence_distance: Some(5.0),
        icp_loss: loss,
        ..Options::default()
    };
    let mut reg = Registrar::with_default_model().unwrap();
    let squared = reg.register(&source, &target, &options(IcpLoss::Squared)).unwrap();
    let robust = reg.register(&source, &target, &options(IcpLoss::Robust)).unwrap();
    let (rs, ts) = common::errors(&squared.T_target_source, &truth);
    let (rr, tr) = common::errors(&robust.T_target_source, &truth);
    assert!(rr < 0.05 && tr < 0.1, "robust: {rr} degrees, {tr}");
    assert!(tr * 3.0 < ts, "squared {rs} degrees, {ts}; robust {rr} degrees, {tr}");
    // without a change both agree to within noise
    let same = survey(2, false).transformed(&inverse);
    let a = reg.register(&same, &target, &options(IcpLoss::Squared)).unwrap();
    let b = reg.register(&same, &target, &options(IcpLoss::Robust)).unwrap();
    assert!(common::errors(&a.T_target_source, &truth).1 < 0.1 && common::errors(&b.T_target_source, &truth).1 < 0.1);
    // the option by its JSON name, the default, and a wrong one refused
    let parsed: Options = serde_json::from_str(r#"{"icpLoss":"squared"}"#).unwrap();
    assert_eq!(parsed.icp_loss, IcpLoss::Squared);
    assert_eq!(Options::default().icp_loss, IcpLoss::Robust);
    let e = serde_json::from_str::<Options>(r#"{"icpLoss":"huber"}"#).unwrap_err().to_string();
    assert!(e.contains("unknown variant `huber`") && e.contains("squared") && e.contains("robust"), "{e}");
}

/// Heights of a 300 x 300 site with a quarry pit's benches (4 steps of 4 down, 10 wide), three
/// stockpiles and two buildings on rolling ground (units of metres).
fn site_height(x: f64, y: f64) -> f64 {
    let mut h = 8.0 * (x / 60.0).sin()
        + 5.0 * (y / 45.0).cos()
        + 3.0 * ((x + y) / 25.0).sin()
        + 0.8 * (x / 7.0).sin() * (y / 9.0).cos();
    h -= ((60.0 - (x - 80.0).hypot(y - 90.0)) / 10.0).floor().max(0.0) * 4.0;
    for (cx, cy, r, top) in [(200.0, 60.0, 25.0, 12.0), (240.0, 200.0, 18.0, 9.0), (150.0, 240.0, 15.0, 7.0)] {
        h += (top * (1.0 - (x - cx).hypot(y - cy) / r)).max(0.0);
    }
    for (bx, by, w, l, top) in [(30.0, 230.0, 20.0, 12.0, 8.0), (260.0, 120.0, 15.0, 25.0, 10.0)] {
        if x > bx && x < bx + w && y > by && y < by + l {
            h += top;
        }
    }
    h
}

/// `n` points of the site ([`site_height`]) from `seed`, with 3 cm of noise; with `fill`, the
/// quarter x, y < 150 (the pit's) raised by it (earthworks: a fill pad).
fn site(seed: u64, n: usize, fill: Option<f64>) -> PointCloud {
    use rand::Rng;
    let mut rng = arps::sampling::rng(seed);
    let pts = (0..n)
        .map(|_| {
            let (x, y) = (300.0 * rng.random::<f64>(), 300.0 * rng.random::<f64>());
            let mut z = site_height(x, y) + 0.03 * 1.7 * (rng.random::<f64>() * 2.0 - 1.0);
            if let Some(f) = fill.filter(|_| x < 150.0 && y < 150.0) {
                z += f;
            }
            [x as f32, y as f32, z as f32]
        })
        .collect();
    PointCloud::new(pts)
}

#[test]
fn a_fill_pad_as_high_as_the_distance_does_not_tilt_the_robust_answer() {
    // a quarter of the site raised by the distance: at that distance its points pair with the old
    // ground and tilt the least-squares fit, and a robust run from that tilt at its residuals'
    // spread stays near it; the graduated descent comes back
    let given = Options {
        up: Some([0.0, 0.0, 1.0]),
        support_plane: arps::Support::Keep,
        max_correspondence_distance: Some(1.0),
        ..Options::default()
    };
    let (s, r, degrees) = fill_pad(1.0, given);
    assert!(s > 0.5, "the pad tilts least squares: {s} at the far corner");
    assert!(r < 0.1 && degrees < 0.01, "robust: {degrees} degrees, {r} at the far corner");
}

#[test]
fn a_fill_pad_within_the_distance_does_not_tilt_the_robust_answer() {
    // a quarter of the site raised 1.5 m at the default distance (several metres): the pad pairs
    // with the old ground and tilts least squares so far that every residual spreads, and a
    // robust run at that spread stays near the tilt; the graduated descent comes back
    let (s, r, degrees) = fill_pad(1.5, Options::default());
    assert!(s > 0.5, "the pad tilts least squares: {s} at the far corner");
    assert!(r < 0.1, "robust: {r} at the far corner ({degrees} degrees)");
}

/// The misplaced site with a fill pad `height` high over its quarter, registered with `given`
/// and least squares, then the robust loss: how far each puts the far corner, and the robust
/// answer's rotation error in degrees.
fn fill_pad(height: f64, given: Options) -> (f64, f64, f64) {
    let misplaced = misplacement();
    let truth = misplaced.try_inverse().unwrap();
    let source = site(2, 100_000, Some(height)).transformed(&misplaced);
    let target = site(1, 100_000, None);
    let mut reg = Registrar::with_default_model().unwrap();
    let mut with = |icp_loss| reg.register(&source, &target, &Options { icp_loss, ..given.clone() }).unwrap();
    let (squared, robust) = (with(IcpLoss::Squared), with(IcpLoss::Robust));
    let degrees = common::errors(&robust.T_target_source, &truth).0;
    (far_corner(&squared.T_target_source, &truth), far_corner(&robust.T_target_source, &truth), degrees)
}

#[test]
fn a_right_guess_is_held_by_the_ground_that_stayed() {
    // a third of the site (one corner) raised 2 m, the second epoch misplaced and the guess right:
    // refining the guess, the wide stages pair the raised corner with the old ground and pull
    // least squares metres off; weighed robustly from the first stage the guess stays
    let (s, r) = raised_corner_from_guess(2.0, Matrix4::identity());
    assert!(s > 1.0, "the raised corner pulls least squares off the guess: {s} at the far corner");
    assert!(r < 0.05, "robust: {r} at the far corner");
}

#[test]
fn a_guess_a_little_off_is_not_tilted_by_a_low_fill_over_a_third() {
    // a third of the site filled 1.5 m (above the distance, below the wide stages' reach), the
    // guess tilted 0.05 degrees and 0.3 m low: the refinement of the guess counts the fill in and
    // tilts metres off, the descent from the answer stays on the tilt, and the descent from the
    // guess comes back
    let off = Matrix4::new_translation(&nalgebra::Vector3::new(0.0, 0.0, 0.3))
        * nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::x_axis(), 0.05f64.to_radians()).to_homogeneous();
    let (s, r) = raised_corner_from_guess(1.5, off);
    assert!(s > 1.0, "the fill tilts least squares: {s} at the far corner");
    assert!(r < 0.05, "robust: {r} at the far corner");
}

/// The survey recipe (the guess `off` times the truth as `initialTransform`, its refinement alone,
/// `up`, the support kept, 1 m) on the misplaced site whose corner third (x, y > 135) was raised by
/// `height`: how far least squares and the robust loss put the far corner.
fn raised_corner_from_guess(height: f32, off: Matrix4<f64>) -> (f64, f64) {
    let misplaced = misplacement();
    let truth = misplaced.try_inverse().unwrap();
    let mut raised = site(2, 100_000, None);
    for p in raised.points.iter_mut().filter(|p| p[0] > 135.0 && p[1] > 135.0) {
        p[2] += height;
    }
    let source = raised.transformed(&misplaced);
    let target = site(1, 100_000, None);
    let rows = |m: &Matrix4<f64>| std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]));
    let options = |loss| Options {
        initial_transform: Some(rows(&(off * truth))),
        starts: vec![Start::Initial],
        search: arps::Search::Local,
        up: Some([0.0, 0.0, 1.0]),
        support_plane: arps::Support::Keep,
        max_correspondence_distance: Some(1.0),
        icp_loss: loss,
        ..Options::default()
    };
    let mut reg = Registrar::with_default_model().unwrap();
    let mut far = |loss| far_corner(&reg.register(&source, &target, &options(loss)).unwrap().T_target_source, &truth);
    (far(IcpLoss::Squared), far(IcpLoss::Robust))
}

/// The second epoch's misplacement: 0.35 degrees about a tilted axis through the site's centre,
/// then (1.2, -0.8, 0.4).
fn misplacement() -> Matrix4<f64> {
    let about = Matrix4::new_translation(&nalgebra::Vector3::new(150.0, 150.0, 0.0));
    let turn = nalgebra::Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(nalgebra::Vector3::new(0.2, -0.1, 1.0)),
        0.35f64.to_radians(),
    );
    Matrix4::new_translation(&nalgebra::Vector3::new(1.2, -0.8, 0.4))
        * about
        * turn.to_homogeneous()
        * about.try_inverse().unwrap()
}

/// How far `t` puts the site's far corner from where `truth` does: the largest error a tilt makes.
fn far_corner(t: &Matrix4<f64>, truth: &Matrix4<f64>) -> f64 {
    let p = nalgebra::Point3::new(300.0, 300.0, 0.0);
    (t.transform_point(&p) - truth.transform_point(&p)).norm()
}
