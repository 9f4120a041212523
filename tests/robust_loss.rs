//! `icpLoss: "robust"`: two surveys of a terrain between which a stretch changed (a cliff that
//! retreated, a building that went up). Least squares lets the changed surface pull the answer;
//! the robust last refinement is held by the surfaces that stayed.

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
    // the option by its JSON name, and a wrong one refused
    let parsed: Options = serde_json::from_str(r#"{"icpLoss":"robust"}"#).unwrap();
    assert_eq!(parsed.icp_loss, IcpLoss::Robust);
    let e = serde_json::from_str::<Options>(r#"{"icpLoss":"huber"}"#).unwrap_err().to_string();
    assert!(e.contains("unknown variant `huber`") && e.contains("squared") && e.contains("robust"), "{e}");
}
