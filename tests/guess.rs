//! The caller's guess (`Options::initial_transform`): an answer that turns far from it says so and
//! is held below the low-confidence line; an answer near it does not.

mod common;

use arps::transform::rotation_error_deg;
use arps::{Options, Registrar};
use common::{fixture_pair, motion};

fn guessed(guess: &nalgebra::Matrix4<f64>) -> Options {
    Options { initial_transform: Some(arps::transform::to_rows(guess)), ..Options::default() }
}

fn says_far(r: &arps::Registration) -> bool {
    r.warnings.iter().any(|w| w.contains("away from initialTransform"))
}

#[test]
fn an_answer_far_from_the_guess_says_so_and_is_held_low() {
    let (source, target, truth) = fixture_pair(4);
    let mut reg = Registrar::with_default_model().unwrap();
    let plain = reg.register(&source, &target, &Options::default()).unwrap();
    assert!(rotation_error_deg(&plain.T_target_source, &truth) < 5.0, "the pair is found without a guess");
    assert!(plain.confidence > 0.5 && !says_far(&plain), "{} {:?}", plain.confidence, plain.warnings);

    // a guess 10 degrees off the truth: the answer is near it
    let near = truth * motion([6.0, -5.0, 5.0], [0.0, 0.0, 0.0]);
    let r = reg.register(&source, &target, &guessed(&near)).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &truth) < 5.0);
    assert!(r.confidence > 0.5 && !says_far(&r), "{} {:?}", r.confidence, r.warnings);

    // a guess half a turn off, where the search finds the truth all the same: the answer
    // contradicts the guess, and the result says so
    let far = truth * motion([180.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let r = reg.register(&source, &target, &guessed(&far)).unwrap();
    if rotation_error_deg(&r.T_target_source, &far) > arps::register::GUESS_TURN_DEG {
        assert!(says_far(&r), "{:?}", r.warnings);
        assert!(r.confidence <= 0.25, "{}", r.confidence);
    } else {
        panic!(
            "the answer stayed at the wrong guess: {:.1} deg off the truth",
            rotation_error_deg(&r.T_target_source, &truth)
        );
    }
}

/// A bumpy surface made symmetric under a half turn about z: every point and its turned twin.
fn half_turn_symmetric(n: usize, phase: f64) -> arps::PointCloud {
    let one = common::bumpy_surface(n, phase);
    let points: Vec<[f32; 3]> = one.points.iter().flat_map(|&[x, y, z]| [[x, y, z], [-x, -y, z]]).collect();
    arps::PointCloud::new(points)
}

#[test]
fn a_guess_rules_out_the_look_alikes_that_contradict_it() {
    let target = half_turn_symmetric(3000, 0.0);
    let truth = motion([10.0, -6.0, 25.0], [0.1, -0.05, 0.2]);
    let source = half_turn_symmetric(3000, 0.41).transformed(&arps::transform::rigid_inverse(&truth));
    let mut reg = Registrar::with_default_model().unwrap();
    let flipped = |r: &arps::Registration| {
        let half = motion([0.0, 0.0, 180.0], [0.0, 0.0, 0.0]) * truth;
        [r.T_target_source]
            .iter()
            .chain(r.alternatives.iter().map(|a| &a.T_target_source))
            .any(|t| rotation_error_deg(t, &half) < 5.0)
    };
    // without a guess the half turn fits as well: the answer is one of the two, held at 0.5
    let plain = reg.register(&source, &target, &Options::default()).unwrap();
    assert!(flipped(&plain) && plain.confidence <= 0.5, "{} {}", plain.confidence, plain.alternatives.len());
    // a guess 10 degrees off the truth: the half turn contradicts it, and is no look-alike
    let near = truth * motion([6.0, -5.0, 5.0], [0.0, 0.0, 0.0]);
    let r = reg.register(&source, &target, &guessed(&near)).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &truth) < 1.0);
    assert!(!flipped(&r) && r.confidence > 0.5, "{} {:?}", r.confidence, r.warnings);
}

#[test]
fn an_answer_far_from_where_the_guess_puts_the_source_says_so() {
    let (source, target, truth) = fixture_pair(4);
    let says_moved =
        |r: &arps::Registration| r.warnings.iter().any(|w| w.contains("from where initialTransform puts it"));
    let mut reg = Registrar::with_default_model().unwrap();
    // the truth's rotation, a hand's placement off: no word
    let near = motion([0.0, 0.0, 0.0], [0.1 * source.half_extent(), 0.0, 0.0]) * truth;
    let r = reg.register(&source, &target, &guessed(&near)).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &truth) < 5.0 && !says_moved(&r), "{:?}", r.warnings);
    // two of the source's half-extents off: the search finds the truth, and says how far that is
    let far = motion([0.0, 0.0, 0.0], [2.0 * source.half_extent(), 0.0, 0.0]) * truth;
    let r = reg.register(&source, &target, &guessed(&far)).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &truth) < 5.0, "the truth is found");
    assert!(says_moved(&r), "{:?}", r.warnings);
}
