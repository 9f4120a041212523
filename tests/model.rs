//! The network (random weights): shapes, determinism, invariances, and the network + GMR transform.

use arps::gmr;
use arps::model::{ModelConfig, ModelWorkspace, Reference};
use arps::transform::{check_rigid, euler_xyz, from_rotation_translation, rotation_error_deg, translation_error};
use arps::{Model, Weights};
use nalgebra::{Matrix4, Vector3};

/// A deterministic blob of `n` points on a bumpy sphere-ish surface in roughly [-1, 1]^3.
fn blob(n: usize, phase: f32) -> Vec<[f32; 3]> {
    (0..n)
        .map(|i| {
            let t = i as f32 * 0.618_034 + phase;
            let u = (t.fract()) * std::f32::consts::TAU;
            let v = ((i as f32 + 0.5) / n as f32 * 2.0 - 1.0).acos();
            let r = 0.8 + 0.15 * (3.0 * u).sin() * (2.0 * v).cos();
            [r * v.sin() * u.cos(), r * v.sin() * u.sin() * 0.7, r * v.cos()]
        })
        .collect()
}

fn shift(pts: &[[f32; 3]], d: [f32; 3]) -> Vec<[f32; 3]> {
    pts.iter().map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]]).collect()
}

fn model(reference: Reference) -> Model {
    let mut c = ModelConfig::tiny();
    c.n_points = 64;
    c.reference = reference;
    Model::from_weights(&Weights::random(&c, 3).unwrap()).unwrap()
}

fn network_transform(m: &Model, s: &[[f32; 3]], t: &[[f32; 3]]) -> Matrix4<f64> {
    let out = m.forward(s, t, &mut ModelWorkspace::default()).unwrap();
    let j = m.config.gaussians;
    gmr::solve(&gmr::gmm_params(s, &out.gamma_source, j), &gmr::gmm_params(t, &out.gamma_target, j))
}

#[test]
fn memberships_are_distributions_and_deterministic() {
    for reference in [Reference::Soft, Reference::TopH] {
        let m = model(reference);
        let (s, t) = (blob(64, 0.0), blob(80, 0.3));
        let mut ws = ModelWorkspace::default();
        let a = m.forward(&s, &t, &mut ws).unwrap();
        assert_eq!(a.gamma_source.len(), 64 * m.config.gaussians);
        assert_eq!(a.gamma_target.len(), 80 * m.config.gaussians);
        for row in a.gamma_source.chunks(m.config.gaussians).chain(a.gamma_target.chunks(m.config.gaussians)) {
            let sum: f32 = row.iter().sum();
            assert!((sum - 1.0).abs() < 1e-5 && row.iter().all(|v| v.is_finite() && *v >= 0.0));
        }
        assert_eq!(a.steps.len(), m.config.layers);
        assert!(a.steps.iter().all(|s| (0.0..=1.0).contains(s)));
        // the same workspace reused, and a fresh one, give identical results
        let b = m.forward(&s, &t, &mut ws).unwrap();
        let c = m.forward(&s, &t, &mut ModelWorkspace::default()).unwrap();
        assert_eq!(a, b);
        assert_eq!(a, c);
    }
}

#[test]
fn memberships_do_not_depend_on_where_each_cloud_sits() {
    let m = model(Reference::Soft);
    let (s, t) = (blob(64, 0.0), blob(64, 0.4));
    let a = m.forward(&s, &t, &mut ModelWorkspace::default()).unwrap();
    let b = m
        .forward(&shift(&s, [0.3, -0.2, 0.1]), &shift(&t, [-0.4, 0.25, 0.05]), &mut ModelWorkspace::default())
        .unwrap();
    for (x, y) in a.gamma_source.iter().zip(&b.gamma_source).chain(a.gamma_target.iter().zip(&b.gamma_target)) {
        assert!((x - y).abs() < 1e-4, "{x} vs {y}");
    }
}

#[test]
fn network_plus_gmr_is_translation_equivariant_and_proper() {
    for reference in [Reference::Soft, Reference::TopH] {
        let m = model(reference);
        let s = blob(64, 0.0);
        let motion = from_rotation_translation(&euler_xyz(0.3, -0.2, 0.25), &Vector3::new(0.1, 0.2, -0.1));
        let t: Vec<[f32; 3]> = blob(64, 0.2).iter().map(|&p| arps::transform::apply(&motion, p)).collect();
        let base = network_transform(&m, &s, &t);
        check_rigid(&base, 1e-6).unwrap();
        // translate both inputs by the same vector a: T' = Tr(a) T Tr(-a)
        let a = Vector3::new(0.37, -0.21, 0.44);
        let moved = network_transform(&m, &shift(&s, [0.37, -0.21, 0.44]), &shift(&t, [0.37, -0.21, 0.44]));
        let tr = |v: Vector3<f64>| from_rotation_translation(&nalgebra::Matrix3::identity(), &v);
        let expected = tr(a) * base * tr(-a);
        assert!(rotation_error_deg(&moved, &expected) < 1e-3, "{}", rotation_error_deg(&moved, &expected));
        assert!(translation_error(&moved, &expected) < 1e-4, "{}", translation_error(&moved, &expected));
        check_rigid(&moved, 1e-6).unwrap();
    }
}

#[test]
fn too_few_points_is_an_error() {
    let m = model(Reference::Soft);
    let e = m.forward(&blob(10, 0.0), &blob(64, 0.0), &mut ModelWorkspace::default()).unwrap_err().to_string();
    assert!(e.contains("source has 10 points"), "{e}");
}

#[test]
fn flop_count_grows_faster_than_linearly_with_points() {
    let m = model(Reference::Soft);
    let f = m.flops(64, 64);
    assert!(f > 0);
    // doubling points roughly quadruples the attention part: more than doubles the total
    assert!(m.flops(128, 128) > 2 * f);
}
