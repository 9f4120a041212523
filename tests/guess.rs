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

/// A carved panel of low relief (40 smooth bumps of 4 mm over 600 x 400 mm) seen in two windows of
/// 360 x 240 mm that overlap 70%, 0.1 mm noise: `(source, target, T_target_source)`.
fn relief_pair() -> (arps::PointCloud, arps::PointCloud, nalgebra::Matrix4<f64>) {
    use rand::Rng;
    let mut rng = arps::sampling::rng(7);
    let bumps: Vec<[f64; 4]> = (0..40)
        .map(|_| {
            let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
            [600.0 * rng.random::<f64>(), 400.0 * rng.random::<f64>(), 15.0 + 55.0 * rng.random::<f64>(), sign]
        })
        .collect();
    let h = |x: f64, y: f64| -> f64 {
        bumps
            .iter()
            .map(|[bx, by, s, a]| 4.0 * a * (-((x - bx).powi(2) + (y - by).powi(2)) / (2.0 * s * s)).exp())
            .sum()
    };
    let mut window = |x0: f64, y0: f64| -> Vec<[f64; 3]> {
        (0..30_000)
            .map(|_| {
                let (x, y) = (x0 + 360.0 * rng.random::<f64>(), y0 + 240.0 * rng.random::<f64>());
                [x, y, h(x, y) + 0.1 * (rng.random::<f64>() - 0.5) * 3.46]
            })
            .collect()
    };
    // shifted along (1, 0.3) so that 70% of the window overlaps
    let (target, source) = (window(0.0, 0.0), window(56.0, 16.8));
    let truth = motion([25.0, -40.0, 70.0], [120.0, -300.0, 45.0]);
    let inverse = truth.try_inverse().unwrap();
    let moved: Vec<[f64; 3]> = source.iter().map(|&p| common::apply(&inverse, p)).collect();
    (arps::PointCloud::from_points_f64(&moved), arps::PointCloud::from_points_f64(&target), truth)
}

/// A low relief pins the pose by its gentle slopes, which ICP follows from a guess to the truth,
/// though a slid pose keeps most of the fit at the default distance (`evidence.slide`): the answer
/// is not held at the guess's error (it was: 0.76 degrees off, "heldByGuess", from a guess about
/// 2 degrees and 10 mm off; 0.007 degrees now).
#[test]
fn a_low_relief_is_refined_from_a_near_guess_not_held_at_it() {
    let (source, target, truth) = relief_pair();
    let near = motion([1.2, -1.0, 1.2], [6.0, -5.0, 6.0]) * truth;
    assert!(rotation_error_deg(&near, &truth) > 1.5);
    let mut reg = Registrar::with_default_model().unwrap();
    for search in [arps::Search::Adaptive, arps::Search::Local] {
        let options = Options { starts: vec![arps::Start::Initial], search, ..guessed(&near) };
        let r = reg.register(&source, &target, &options).unwrap();
        let off = rotation_error_deg(&r.T_target_source, &truth);
        assert!(off < 0.2, "{search:?}: {off} degrees off the truth: {:?} {:?}", r.evidence, r.warnings);
        assert!(!r.warning_codes.contains(&arps::WarningCode::HeldByGuess), "{:?}", r.warnings);
    }
}

/// A bowl whose fit barely holds the turn about its axis (`evidence.slide` above the free-motion
/// line, its constraint above the unpinned one): from a guess a degree off, the least-squares
/// search's answer turned 53 degrees about the axis; the guess now holds it there (a nearly round teapot's views,
/// 25-30 degrees from a guess 1 degree off, came back within 0.6-2.6 degrees).
#[test]
fn a_guess_holds_an_answer_that_turned_far_along_a_barely_held_motion() {
    let (source, target, truth) = common::fixture_pair_in("fixtures/revolution", 1);
    let r = arps::gmr::nearest_rotation(&arps::transform::rotation(&truth));
    let truth = arps::transform::from_rotation_translation(&r, &arps::transform::translation(&truth));
    let mut reg = Registrar::with_default_model().unwrap();
    let guess = truth * motion([1.0, -1.0, 1.0], [0.01, 0.0, 0.0]);
    // least squares throughout: the search's answer turned far, and the guess holds it
    let squared = Options { icp_loss: arps::IcpLoss::Squared, ..guessed(&guess) };
    let r = reg.register(&source, &target, &squared).unwrap();
    let err = rotation_error_deg(&r.T_target_source, &truth);
    assert!(err < 3.0, "{err} degrees off: {:?} {:?}", r.evidence, r.warnings);
    assert!(r.warning_codes.contains(&arps::WarningCode::HeldByGuess), "{:?}", r.warning_codes);
    // the default refines the guess robustly: it stays near the truth, held or not
    let r = reg.register(&source, &target, &guessed(&guess)).unwrap();
    let err = rotation_error_deg(&r.T_target_source, &truth);
    assert!(err < 3.0, "default: {err} degrees off: {:?} {:?}", r.evidence, r.warnings);
}

/// A jar 5% oval, its source a 160-degree arc of the target's whole jar: a guess 20 degrees off
/// about its axis holds the answer along the turn the fit barely holds; the result then names that
/// motion and stays at 0.25 or below, even where the held pose's own probe finds the turn a little
/// firmer (a user's: `"heldByGuess"` alone, no motion in `freeMotions`, 0.333).
#[test]
fn an_answer_held_by_the_guess_names_the_motion_and_is_not_sure() {
    use nalgebra::Vector3;
    use rand::Rng;
    let jar = |n: usize, from: f64, to: f64, seed: u64| {
        let mut rng = arps::sampling::rng(seed);
        let pts = (0..n)
            .map(|_| {
                let h = 2.0 * rng.random::<f64>() - 1.0;
                let a = (from + (to - from) * rng.random::<f64>()).to_radians();
                let r = (0.5 + 0.15 * (2.2 * h).sin()) * (1.0 + 0.05 * (2.0 * a).cos());
                let noise = |rng: &mut rand_chacha::ChaCha8Rng| 0.002 * (2.0 * rng.random::<f64>() - 1.0);
                [r * a.cos() + noise(&mut rng), r * a.sin() + noise(&mut rng), h + noise(&mut rng)].map(|v| v as f32)
            })
            .collect();
        arps::PointCloud::new(pts)
    };
    let truth = motion([25.0, -10.0, 5.0], [0.4, 0.3, -0.2]);
    let target = jar(20_000, 0.0, 360.0, 21);
    let source = jar(8_000, 20.0, 180.0, 22).transformed(&truth.try_inverse().unwrap());
    let mut reg = Registrar::with_default_model().unwrap();
    let mut held = 0;
    for deg in [12.0, 16.0, 20.0, 25.0] {
        let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), f64::to_radians(deg)).into_inner();
        let guess = arps::transform::from_rotation_translation(&turn, &Vector3::zeros()) * truth;
        let r = reg.register(&source, &target, &guessed(&guess)).unwrap();
        if r.warning_codes.contains(&arps::WarningCode::HeldByGuess) {
            held += 1;
            assert!(r.warning_codes.contains(&arps::WarningCode::FreeMotion), "{deg}: {:?}", r.warnings);
            assert!(!r.free_motions.is_empty() && r.confidence <= 0.25, "{deg}: {} {:?}", r.confidence, r.warnings);
        }
    }
    assert!(held > 0, "no guess held the answer");
}
