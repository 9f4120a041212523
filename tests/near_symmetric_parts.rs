//! A scan of a near-symmetric part onto its model: a gear of 17 teeth whose keyway alone breaks
//! the symmetry. Its turns by a tooth fit all but the keyway's few points, which the fitness
//! counts as a hair; the answer is the pose that leaves none off (`refine::TIE_MISFIT`), whether
//! the search refined it or the confidence's probes found it among the alternatives.

mod common;

use arps::{Options, PointCloud, Registrar};
use nalgebra::Matrix4;
use std::f64::consts::PI;

/// A deterministic stream in [0, 1).
fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

const TEETH: usize = 17;
const ROOT: f64 = 26.0;
const TIP: f64 = 30.0;
const BORE: f64 = 8.0;
const KEY_WIDTH: f64 = 4.0;
const KEY_DEPTH: f64 = 3.0;
const THICKNESS: f64 = 10.0;

/// The gear's outer radius at the angle `a`: a tooth over the first half of each pitch.
fn outer(a: f64) -> f64 {
    let pitch = 2.0 * PI / TEETH as f64;
    if a.rem_euclid(pitch) < 0.5 * pitch {
        TIP
    } else {
        ROOT
    }
}

/// Whether the point (x, y) of the gear's plane is solid: within its outline, outside its bore
/// and its keyway (a slot along +x from the bore).
fn solid(x: f64, y: f64) -> bool {
    let r = x.hypot(y);
    let key = x > 0.0 && y.abs() < 0.5 * KEY_WIDTH && r < BORE + KEY_DEPTH;
    r <= outer(y.atan2(x)) && r >= BORE && !key
}

/// `n` points on the gear's surface (millimetres), seeded, with their outward normals: its two
/// faces, and its walls found by stepping out of the solid along rays from the centre.
fn gear(n: usize, seed: u64) -> Vec<([f64; 3], [f64; 3])> {
    let mut r = stream(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let kind = r();
        if kind < 0.6 {
            // a face
            let (x, y) = ((2.0 * r() - 1.0) * TIP, (2.0 * r() - 1.0) * TIP);
            if solid(x, y) {
                let top = r() < 0.5;
                out.push(([x, y, if top { THICKNESS } else { 0.0 }], [0.0, 0.0, if top { 1.0 } else { -1.0 }]));
            }
        } else {
            // a wall: the edge of the solid along a ray, where it leaves the solid going out
            let (a, z) = (2.0 * PI * r(), THICKNESS * r());
            let (c, s) = (a.cos(), a.sin());
            let step = 0.02;
            let mut t = 0.0;
            while t < TIP + 1.0 {
                let (inside, next) = (solid(t * c, t * s), solid((t + step) * c, (t + step) * s));
                if inside != next && r() < 0.5 {
                    let sign = if inside { 1.0 } else { -1.0 };
                    out.push(([(t + 0.5 * step) * c, (t + 0.5 * step) * s, z], [sign * c, sign * s, 0.0]));
                    break;
                }
                t += step;
            }
        }
    }
    out
}

/// The model: points over the whole gear.
fn model() -> PointCloud {
    PointCloud::new(gear(60_000, 1).into_iter().map(|(p, _)| p.map(|v| v as f32)).collect())
}

/// A one-sided scan of the gear (the points facing `view`, other samples than the model's,
/// 0.05 mm of noise), moved by `pose`.
fn scan(view: [f64; 3], pose: &Matrix4<f64>) -> PointCloud {
    let mut r = stream(7);
    let points = gear(40_000, 2)
        .into_iter()
        .filter(|(_, n)| n[0] * view[0] + n[1] * view[1] + n[2] * view[2] > 0.2)
        .map(|(p, _)| {
            let p: [f64; 3] = std::array::from_fn(|k| p[k] + 0.05 * (2.0 * r() - 1.0));
            let q = pose.transform_point(&nalgebra::Point3::from(p));
            [q.x as f32, q.y as f32, q.z as f32]
        })
        .collect();
    PointCloud::new(points)
}

#[test]
fn a_gear_is_placed_by_its_keyway_not_by_a_turn_of_a_tooth() {
    let mut registrar = Registrar::with_default_model().unwrap();
    let model = model();
    for (view, deg, t) in [
        ([0.3, 0.2, 1.0], [30.0, -50.0, 120.0], [40.0, -25.0, 60.0]),
        ([-0.4, 0.1, 1.0], [170.0, 20.0, -75.0], [-10.0, 80.0, 5.0]),
    ] {
        let pose = common::motion(deg, t);
        let truth = arps::transform::rigid_inverse(&pose);
        let r = registrar.register(&scan(view, &pose), &model, &Options::default()).unwrap();
        let (re, te) = common::errors(&r.T_target_source, &truth);
        let alternatives: Vec<(f64, f64)> =
            r.alternatives.iter().map(|a| (common::errors(&a.T_target_source, &truth).0, a.fitness)).collect();
        assert!(
            re < 0.5 && te < 0.5,
            "{deg:?}: {re} deg, {te} mm, fitness {}, alternatives {alternatives:?}",
            r.fitness
        );
        // its look-alikes, the turns by a tooth, fit no better
        assert!(r.alternatives.iter().all(|a| a.fitness <= r.fitness), "{alternatives:?}");
    }
}
