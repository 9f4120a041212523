//! `search: "local"` with a tight `maxCorrespondenceDistance`: a refinement of the caller's
//! pose that reaches only a few times that distance. A survey swath that hangs partly off the
//! reference's edge, over a seabed of sand waves: the default search's wide stages pair the
//! overhanging points with the reference's edge and pull the swath onto it, a whole sand-wave
//! wavelength away (25 m), where the local refinement stays at the truth.
#![allow(non_snake_case)]

mod common;

use arps::{IcpLoss, Options, PointCloud, Registrar, Search, Start};
use nalgebra::Matrix4;

/// The seabed's depth at (x, y), in metres: a regional slope, sand waves of 25 m wavelength
/// travelling 20 degrees from x, megaripples, and a wreck.
fn seabed(x: f64, y: f64) -> f64 {
    let (wx, wy) = (20f64.to_radians().cos(), 20f64.to_radians().sin());
    let (u, v) = (x * wx + y * wy, -x * wy + y * wx);
    let tau = std::f64::consts::TAU;
    let mut z = -25.0 - 0.01 * x + 0.005 * y;
    z += 0.6 * (0.7 + 0.3 * (tau * v / 300.0).sin()) * (tau * (u + 3.0 * (tau * v / 180.0).sin()) / 25.0).sin();
    z += 0.15 * (tau * u / 7.0).sin();
    // a wreck: a hull 50 m by 10 m, 5 m high, heading 35 degrees, centred at (275, 300)
    let (dx, dy, h) = (x - 275.0, y - 300.0, 35f64.to_radians());
    let (along, across) = (dx * h.cos() + dy * h.sin(), -dx * h.sin() + dy * h.cos());
    if along.abs() < 25.0 && across.abs() < 5.0 {
        z += 5.0 * (1.0 - (across / 5.0).powi(2)).sqrt() * ((25.0 - along.abs()) / 6.0).min(1.0);
    }
    z
}

/// Deterministic noise in [-1, 1] for index `i` (a hash, no RNG).
fn jitter(i: u64, salt: u64) -> f64 {
    let mut h = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ salt.wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    (h >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// The reference: a 300 x 600 m grid at 2 m, 5 cm of noise.
fn reference() -> PointCloud {
    let mut points = Vec::new();
    for i in 0..150 {
        for j in 0..300 {
            let (x, y) = (2.0 * i as f64, 2.0 * j as f64);
            let k = (i * 300 + j) as u64;
            points.push([x, y, seabed(x, y) + 0.05 * jitter(k, 1)]);
        }
    }
    PointCloud::from_points_f64(&points)
}

/// A swath along y at x = 290 (its beams out to 65 degrees reach about 55 m each side, so 40%
/// of it hangs past the reference's edge at x = 300), pings every 2 m over 400 m, 64 beams.
fn swath() -> Vec<[f64; 3]> {
    let mut points = Vec::new();
    for ping in 0..200 {
        for beam in 0..64 {
            let angle = (-65.0 + 130.0 * beam as f64 / 63.0f64).to_radians();
            let y = 100.0 + 2.0 * ping as f64;
            let x = 290.0 + 25.0 * angle.tan();
            let k = (ping * 64 + beam) as u64;
            points.push([x, y, seabed(x, y) + 0.05 * jitter(k, 2)]);
        }
    }
    points
}

#[test]
fn a_local_refinement_at_a_tight_distance_stays_where_the_guess_put_it() {
    let target = reference();
    // the swath as navigation placed it: 3 m east, 2 m south, 0.4 m up, rolled 1 degree,
    // pitched 0.5 and turned 3 about its centre (its ends 10 m from where they belong)
    let true_swath = swath();
    let centre = true_swath.iter().fold([0.0; 3], |c, p| [0, 1, 2].map(|a| c[a] + p[a] / true_swath.len() as f64));
    let about = |c: [f64; 3]| common::motion([0.0; 3], c);
    let misplaced = about([centre[0] + 3.0, centre[1] - 2.0, centre[2] + 0.4])
        * common::motion([1.0, 0.5, 3.0], [0.0; 3])
        * about(centre.map(|v| -v));
    let T_target_source: Matrix4<f64> = arps::transform::rigid_inverse(&misplaced);
    let source =
        PointCloud::from_points_f64(&true_swath.iter().map(|&p| common::apply(&misplaced, p)).collect::<Vec<_>>());
    let mut reg = Registrar::with_default_model().unwrap();
    let survey = Options {
        network: false,
        starts: vec![Start::Initial],
        initial_transform: Some(arps::transform::to_rows(&T_target_source)),
        up: Some([0.0, 0.0, 1.0]),
        max_correspondence_distance: Some(1.0),
        icp_loss: IcpLoss::Robust,
        search: Search::Local,
        ..Options::default()
    };
    // from the truth it stays there (with stages from the default distance, 7 m here, ICP slid
    // it a wavelength on: 25 m)
    let r = reg.register(&source, &target, &survey).unwrap();
    let deg = arps::transform::rotation_error_deg(&r.T_target_source, &T_target_source);
    // how far the swath's centre lands from where the truth puts it
    let at = |t: &Matrix4<f64>| nalgebra::Vector3::from(common::apply(t, common::apply(&misplaced, centre)));
    let shift = (at(&r.T_target_source) - at(&T_target_source)).norm();
    assert!(deg < 0.1 && shift < 0.2, "{deg} degrees, {shift} m off (confidence {})", r.confidence);
}
