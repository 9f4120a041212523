//! Surfaces of revolution (`fixtures/revolution`: two bowls, a cone and a bottle, the paper's
//! protocol): their fit pins the turn about the axis only weakly. The starts that are estimates
//! also take ICP's wide stage damped (`refine::WIDE_DAMPING`) and skip it once, which keeps the
//! truth, and an estimate a few degrees off it, right.

mod common;

use arps::refine::Start;
use arps::transform::{euler_xyz, from_rotation_translation, rotation_error_deg, to_rows, translation_error};
use arps::{Options, Registrar};
use common::fixture_pair_in;

const PAIRS: usize = 4;

/// Rotation error (degrees) and translation error of `t` against `truth`, within the recall
/// thresholds (15 degrees, 0.2 units).
fn right(t: &nalgebra::Matrix4<f64>, truth: &nalgebra::Matrix4<f64>) -> Result<(), String> {
    let (re, te) = (rotation_error_deg(t, truth), translation_error(t, truth));
    if re < 15.0 && te < 0.2 {
        Ok(())
    } else {
        Err(format!("{re:.1} deg, {te:.3}"))
    }
}

/// The options that refine `estimate` (the caller's initial transform) alone, without the
/// network: the estimate's start, which takes the wide stage as the network's would.
fn refined_alone(estimate: &nalgebra::Matrix4<f64>) -> Options {
    Options {
        network: false,
        starts: vec![Start::Initial],
        initial_transform: Some(to_rows(estimate)),
        ..Options::default()
    }
}

#[test]
fn icp_from_the_truth_stays_there() {
    // the truth as the caller's initial transform, refined alone (what `arps eval` reports as the
    // refinement's ceiling): with the plain wide stage alone, each of these ended 53-97 degrees
    // away
    let mut reg = Registrar::with_default_model().unwrap();
    for i in 0..PAIRS {
        let (source, target, truth) = fixture_pair_in("fixtures/revolution", i);
        let r = reg.register(&source, &target, &refined_alone(&truth)).unwrap();
        right(&r.T_target_source, &truth).unwrap_or_else(|e| panic!("pair {i}: {e}"));
    }
}

#[test]
fn icp_from_a_close_estimate_stays_right() {
    // estimates 3 and 6 degrees off the truth (turned about each axis through the source's centre
    // in turn, and shifted 0.03), refined alone as the network's estimate is (`starts: ["initial"]`
    // with the network off takes the same wide stage three ways): with the wide stage plain and
    // damped only, a bowl turned 3 degrees about z ended 111 degrees away and a cone 164, at fits
    // well below the truth's
    let mut reg = Registrar::with_default_model().unwrap();
    for i in 0..PAIRS {
        let (source, target, truth) = fixture_pair_in("fixtures/revolution", i);
        let c = nalgebra::Vector3::from(source.centroid());
        for degrees in [3.0f64, 6.0] {
            for axis in 0..3 {
                let mut angles = [0.0; 3];
                angles[axis] = degrees.to_radians();
                let turn = euler_xyz(angles[0], angles[1], angles[2]);
                let shift = nalgebra::Vector3::repeat(0.03 / 3f64.sqrt());
                let estimate = truth * from_rotation_translation(&turn, &(c - turn * c + shift));
                let r = reg.register(&source, &target, &refined_alone(&estimate)).unwrap();
                right(&r.T_target_source, &truth)
                    .unwrap_or_else(|e| panic!("pair {i}, {degrees} degrees about axis {axis}: {e}"));
            }
        }
    }
}

#[test]
fn icp_from_the_network_estimate_is_deterministic() {
    // `starts: ["network"]`, the network's estimate refined alone: the same input, the same output
    // (whether it is right depends on the model's estimate; the test above refines close ones)
    let mut reg = Registrar::with_default_model().unwrap();
    let options = Options { starts: vec![Start::Network], ..Options::default() };
    for i in 0..PAIRS {
        let (source, target, _) = fixture_pair_in("fixtures/revolution", i);
        let r = reg.register(&source, &target, &options).unwrap();
        assert_eq!(reg.register(&source, &target, &options).unwrap().T_target_source, r.T_target_source);
    }
}
