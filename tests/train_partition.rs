#![cfg(feature = "train")]
//! The `seg` loss's canonical partition: corresponding points get the same target row in both
//! clouds, the anchors are spread over the sphere, and the half rotation squares to the truth.

use arps::train::partition::{anchors, half_rotation, targets, Role};
use arps::transform::{euler_xyz, from_rotation_translation};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn anchors_are_unit_and_spread() {
    let a = anchors(16);
    assert_eq!(a.len(), 16);
    for (i, x) in a.iter().enumerate() {
        assert!((x.norm() - 1.0).abs() < 1e-12);
        for y in &a[i + 1..] {
            assert!(x.dot(y) < 0.8, "two anchors closer than 37 degrees");
        }
    }
    let mean: Vector3<f64> = a.iter().sum::<Vector3<f64>>() / 16.0;
    assert!(mean.norm() < 0.05, "anchors lopsided: mean {mean:?}");
}

#[test]
fn half_rotation_squares_to_the_rotation() {
    for (i, e) in [[0.3, -0.5, 0.7], [0.0, 0.0, 0.0], [0.78, 0.78, -0.78], [3.0, 0.1, 0.0]].iter().enumerate() {
        let m = from_rotation_translation(&euler_xyz(e[0], e[1], e[2]), &Vector3::new(0.1, 0.2, 0.3));
        let h = half_rotation(&m);
        let r = m.fixed_view::<3, 3>(0, 0).into_owned();
        assert!((h * h - r).norm() < 1e-9, "case {i}");
        assert!((h.determinant() - 1.0).abs() < 1e-9, "case {i}");
    }
}

#[test]
fn corresponding_points_get_the_same_rows() {
    let mut r = ChaCha8Rng::seed_from_u64(5);
    let m = from_rotation_translation(&euler_xyz(0.6, -0.4, 0.3), &Vector3::new(0.3, -0.2, 0.1));
    let src: Vec<[f32; 3]> =
        (0..50).map(|_| [r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(-1.0..1.0)]).collect();
    let c_src = [0.1, -0.05, 0.2];
    let map = |p: [f64; 3]| {
        let v = m * nalgebra::Vector4::new(p[0], p[1], p[2], 1.0);
        [v.x, v.y, v.z]
    };
    let tgt: Vec<[f32; 3]> = src.iter().map(|p| map(p.map(|v| v as f64)).map(|v| v as f32)).collect();
    let c_tgt = map(c_src);
    let (j, kappa) = (16, 8.0);
    let ps = targets(&src, c_src, &m, Role::Source, j, kappa);
    let pt = targets(&tgt, c_tgt, &m, Role::Target, j, kappa);
    assert_eq!(ps.len(), 50 * j);
    let worst = ps.iter().zip(&pt).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "rows differ by {worst}");
    for row in ps.chunks_exact(j) {
        assert!((row.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert!(row.iter().copied().fold(0.0f32, f32::max) > 0.2, "kappa 8 cones should be peaked");
    }
    // the source's own frame is not the answer: with the rotation dropped the rows change
    let wrong = targets(&tgt, c_tgt, &nalgebra::Matrix4::identity(), Role::Target, j, kappa);
    let diff = ps.iter().zip(&wrong).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(diff > 0.1, "rotation had no effect ({diff})");
}
