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
