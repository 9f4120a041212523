//! The `up` option: clouds captured level (sharing an up axis) get an answer that only turns the
//! source about that axis, look-alikes tilted off it ruled out.

mod common;

use arps::transform::{rotation, rotation_error_deg, translation_error};
use arps::{Options, Registrar};
use common::{bumpy_surface, fixture_pair_in};
use nalgebra::{Matrix4, Vector3};

/// How far `t` tilts `up` (the same direction in both frames) off itself, degrees.
fn tilt_deg(t: &Matrix4<f64>, up: Vector3<f64>) -> f64 {
    (rotation(t) * up).angle(&up).to_degrees()
}

#[test]
fn a_shared_up_axis_rules_out_an_upside_down_look_alike() {
    // fixtures/any pair 7: any turn about z; without `up` the answer is upside down
    let (source, target, truth) = fixture_pair_in("fixtures/any", 7);
    let z = Vector3::z();
    let mut reg = Registrar::with_default_model().unwrap();
    let free = reg.register(&source, &target, &Options::default()).unwrap();
    assert!(tilt_deg(&free.T_target_source, z) > 90.0, "the fixture no longer shows the flip: {free:?}");
    let up = Options { up: Some([0.0, 0.0, 2.0]), ..Options::default() };
    let r = reg.register(&source, &target, &up).unwrap();
    let (re, te) = (rotation_error_deg(&r.T_target_source, &truth), translation_error(&r.T_target_source, &truth));
    assert!(re < 5.0 && te < 0.05, "{re} deg, {te}");
    assert!(tilt_deg(&r.T_target_source, z) <= arps::register::UP_TOLERANCE_DEG);
    for a in &r.alternatives {
        assert!(tilt_deg(&a.T_target_source, z) <= arps::register::UP_TOLERANCE_DEG, "{a:?}");
    }
    // the same input, the same output
    assert_eq!(reg.register(&source, &target, &up).unwrap().T_target_source, r.T_target_source);
}

#[test]
fn a_tilted_guess_does_not_tilt_the_answer() {
    // `up` is the same direction in both clouds' frames, whatever the guess: a guess tilted 25
    // degrees off it still gives an answer that keeps it (the pipeline turns the source by the
    // guess first, and must turn its up too)
    let (source, target, truth) = fixture_pair_in("fixtures/any", 7);
    let tilt = common::motion([25.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let guess = truth * tilt;
    let options = Options {
        up: Some([0.0, 0.0, 1.0]),
        initial_transform: Some(arps::transform::to_rows(&guess)),
        ..Options::default()
    };
    let r = Registrar::with_default_model().unwrap().register(&source, &target, &options).unwrap();
    assert!(tilt_deg(&r.T_target_source, Vector3::z()) <= arps::register::UP_TOLERANCE_DEG, "{}", r.T_target_source);
    let (re, te) = (rotation_error_deg(&r.T_target_source, &truth), translation_error(&r.T_target_source, &truth));
    assert!(re < 5.0 && te < 0.05, "{re} deg, {te}");
}

#[test]
fn an_up_axis_that_is_not_a_direction_is_an_error() {
    let cloud = bumpy_surface(600, 0.0);
    let mut reg = Registrar::with_default_model().unwrap();
    for up in [[0.0, 0.0, 0.0], [f64::NAN, 0.0, 1.0], [0.0, f64::INFINITY, 0.0]] {
        let e = reg.register(&cloud, &cloud, &Options { up: Some(up), ..Options::default() }).unwrap_err();
        assert!(matches!(e, arps::Error::InvalidOption(_)) && e.to_string().contains("up ="), "{up:?}: {e}");
    }
    // the registrar is still usable, and any finite length is a direction (no square overflows)
    for up in [[0.0, 1.0, 0.0], [1e308, -1e308, 0.0], [0.0, 0.0, 1e-300]] {
        let r = reg.register(&cloud, &cloud, &Options { up: Some(up), ..Options::default() }).unwrap();
        let axis = Vector3::from(up) / Vector3::from(up).amax();
        assert!(tilt_deg(&r.T_target_source, axis.normalize()) <= arps::register::UP_TOLERANCE_DEG, "{up:?}");
    }
}

/// Clouds that do not share `up`: `fixtures/any` pair 1 (a bookshelf turned any way, its truth
/// tilted far off z). With `up: z` every upright answer is wrong, and a tilted refinement fits
/// clearly better: the result says `up` may not hold, and is not confident. Without `up`, no
/// such warning.
#[test]
fn an_up_that_does_not_hold_is_doubted() {
    let (source, target, truth) = fixture_pair_in("fixtures/any", 1);
    let z = Vector3::z();
    assert!(tilt_deg(&truth, z) > 45.0, "{}", tilt_deg(&truth, z));
    let mut reg = Registrar::with_default_model().unwrap();
    let r = reg.register(&source, &target, &Options { up: Some([0.0, 0.0, 1.0]), ..Options::default() }).unwrap();
    assert!(r.confidence <= 0.25, "{}", r.confidence);
    let warned = |w: &Vec<String>| w.iter().any(|w| w.contains("off `up` fits clearly better than the upright answer"));
    assert!(warned(&r.warnings), "{:?}", r.warnings);
    let free = reg.register(&source, &target, &Options::default()).unwrap();
    assert!(!warned(&free.warnings), "{:?}", free.warnings);
}
