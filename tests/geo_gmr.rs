//! GMR: GMM parameters + weighted Procrustes recover known transforms exactly, and degenerate
//! inputs give finite proper rotations.

use arps::gmr::{gmm_params, kabsch, solve, Gmm};
use arps::transform::{
    check_rigid, euler_xyz, from_rotation_translation, rotation, rotation_error_deg, translation, translation_error,
};
use arps::PointCloud;
use nalgebra::{Matrix4, Unit, UnitQuaternion, Vector3};
use rand::Rng;

fn rng(seed: u64) -> rand_chacha::ChaCha8Rng {
    arps::sampling::rng(seed)
}

/// A lumpy unit-scale cloud: points around a few random centres.
fn cloud(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut r = rng(seed);
    let centres: Vec<[f32; 3]> = (0..6).map(|_| [0; 3].map(|_| r.random_range(-0.8f32..0.8))).collect();
    (0..n)
        .map(|i| {
            let c = centres[i % centres.len()];
            c.map(|v| v + r.random_range(-0.3f32..0.3))
        })
        .collect()
}

/// Random memberships: softmax of random logits, `[n, j]` row-major.
fn softmax_gamma(n: usize, j: usize, seed: u64) -> Vec<f32> {
    let mut r = rng(seed);
    let mut g = Vec::with_capacity(n * j);
    for _ in 0..n {
        let logits: Vec<f32> = (0..j).map(|_| r.random_range(-3.0f32..3.0)).collect();
        let m = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let e: Vec<f32> = logits.iter().map(|l| (l - m).exp()).collect();
        let s: f32 = e.iter().sum();
        g.extend(e.iter().map(|v| v / s));
    }
    g
}

fn random_transform(r: &mut impl Rng, angle: f64, t_norm: f64) -> Matrix4<f64> {
    let axis = Unit::new_normalize(Vector3::new(
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
    ));
    let dir = Unit::new_normalize(Vector3::new(
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
        r.random_range(-1.0..1.0),
    ));
    let rot = UnitQuaternion::from_axis_angle(&axis, angle).to_rotation_matrix().into_inner();
    from_rotation_translation(&rot, &(dir.into_inner() * t_norm))
}

fn apply_all(m: &Matrix4<f64>, pts: &[[f32; 3]]) -> Vec<[f32; 3]> {
    PointCloud::new(pts.to_vec()).transformed(m).points
}

/// Rotation error in radians (the crate's metric is in degrees).
fn rot_err_rad(a: &Matrix4<f64>, b: &Matrix4<f64>) -> f64 {
    rotation_error_deg(a, b).to_radians()
}

#[test]
fn recovers_random_transforms_exactly() {
    // Same memberships for the cloud and its transformed copy: the GMMs are related by the
    // transform exactly (up to f32 rounding of the moved points), so the solve must be exact.
    // Units: the cloud spans about [-1.1, 1.1]^3; errors are radians and cloud units.
    let pts = cloud(1024, 1);
    let gamma = softmax_gamma(1024, 16, 2);
    let gs = gmm_params(&pts, &gamma, 16);
    let mut r = rng(3);
    let mut angles: Vec<f64> = (0..12).map(|_| r.random_range(0.0..std::f64::consts::PI)).collect();
    // near and at a half-turn, and tiny
    angles.extend([179.0f64.to_radians(), 179.99f64.to_radians(), std::f64::consts::PI, 1e-6]);
    let mut worst = (0.0f64, 0.0f64);
    for (k, &angle) in angles.iter().enumerate() {
        let t_gt = random_transform(&mut r, angle, 0.5 + k as f64 * 0.3);
        let gt = gmm_params(&apply_all(&t_gt, &pts), &gamma, 16);
        let est = solve(&gs, &gt);
        check_rigid(&est, 1e-12).unwrap();
        let (er, et) = (rot_err_rad(&est, &t_gt), translation_error(&est, &t_gt));
        worst = (worst.0.max(er), worst.1.max(et));
        assert!(
            er <= 1e-5 && et <= 1e-5,
            "angle {:.4} deg: rotation error {er:.2e} rad, translation error {et:.2e}",
            angle.to_degrees()
        );
    }
    eprintln!("worst: rotation {:.2e} rad, translation {:.2e}", worst.0, worst.1);
}

#[test]
fn variances_are_rigid_invariant_and_pi_sums_to_one() {
    let pts = cloud(500, 4);
    let gamma = softmax_gamma(500, 8, 5);
    let a = gmm_params(&pts, &gamma, 8);
    let t = from_rotation_translation(&euler_xyz(0.4, -1.0, 2.0), &Vector3::new(3.0, -2.0, 1.0));
    let b = gmm_params(&apply_all(&t, &pts), &gamma, 8);
    assert!((a.pi.iter().sum::<f64>() - 1.0).abs() < 1e-6);
    assert_eq!(a.pi, b.pi);
    for (va, vb) in a.var.iter().zip(&b.var) {
        assert!((va - vb).abs() < 1e-5 * va.max(1.0), "{va} vs {vb}");
    }
}

fn assert_finite_rigid(m: &Matrix4<f64>) {
    check_rigid(m, 1e-9).unwrap_or_else(|e| panic!("{e}: {m}"));
}

#[test]
fn all_mass_in_one_component_gives_pure_translation() {
    let pts = cloud(200, 6);
    let j = 4;
    let gamma: Vec<f32> = (0..200).flat_map(|_| [0.0f32, 1.0, 0.0, 0.0]).collect();
    let t_gt = from_rotation_translation(&euler_xyz(0.3, 0.2, 0.1), &Vector3::new(1.0, 2.0, 3.0));
    let gs = gmm_params(&pts, &gamma, j);
    let gt = gmm_params(&apply_all(&t_gt, &pts), &gamma, j);
    let est = solve(&gs, &gt);
    assert_finite_rigid(&est);
    assert_eq!(rotation(&est), nalgebra::Matrix3::identity());
    let want = Vector3::from(gt.mu[1]) - Vector3::from(gs.mu[1]);
    assert!((translation(&est) - want).norm() < 1e-12);
}

#[test]
fn zero_variance_components_still_solve() {
    // Every point sits exactly on one of 5 sites: all variances clamp to 1e-8.
    let sites = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.5]];
    let pts: Vec<[f32; 3]> = (0..100).map(|i| sites[i % 5]).collect();
    let gamma: Vec<f32> = (0..100).flat_map(|i| (0..5).map(move |k| if k == i % 5 { 1.0f32 } else { 0.0 })).collect();
    let gs = gmm_params(&pts, &gamma, 5);
    assert!(gs.var.iter().all(|&v| v == 1e-8));
    let t_gt = from_rotation_translation(&euler_xyz(0.5, -0.2, 0.9), &Vector3::new(0.1, 0.2, -0.3));
    let est = solve(&gs, &gmm_params(&apply_all(&t_gt, &pts), &gamma, 5));
    assert_finite_rigid(&est);
    assert!(rot_err_rad(&est, &t_gt) < 1e-5 && translation_error(&est, &t_gt) < 1e-5);

    // All points at one spot: no spread at all.
    let same = vec![[0.3f32, 0.3, 0.3]; 50];
    let g = softmax_gamma(50, 4, 7);
    let est = solve(&gmm_params(&same, &g, 4), &gmm_params(&apply_all(&t_gt, &same), &g, 4));
    assert_finite_rigid(&est);
    assert!(
        (arps::transform::apply(&est, [0.3, 0.3, 0.3])[0] as f64
            - arps::transform::apply(&t_gt, [0.3, 0.3, 0.3])[0] as f64)
            .abs()
            < 1e-5
    );
}

#[test]
fn collinear_points_give_a_proper_rotation_aligning_the_line() {
    let dir = Vector3::new(1.0f64, 2.0, -0.5).normalize();
    let pts: Vec<[f32; 3]> = (0..300)
        .map(|i| {
            let s = i as f64 / 300.0 - 0.5;
            let p = dir * s;
            [p.x as f32, p.y as f32, p.z as f32]
        })
        .collect();
    let gamma = softmax_gamma(300, 8, 8);
    for angle in [0.3, 2.0, std::f64::consts::PI] {
        let t_gt = random_transform(&mut rng(9), angle, 0.4);
        let moved = apply_all(&t_gt, &pts);
        let est = solve(&gmm_params(&pts, &gamma, 8), &gmm_params(&moved, &gamma, 8));
        assert_finite_rigid(&est);
        // The rotation about the line is unobservable, but the line itself must land on its image.
        for (p, q) in pts.iter().zip(&moved).step_by(37) {
            let e = arps::transform::apply(&est, *p);
            let d = ((e[0] - q[0]).powi(2) + (e[1] - q[1]).powi(2) + (e[2] - q[2]).powi(2)).sqrt();
            assert!(d < 1e-4, "angle {angle}: {d}");
        }
    }
}

#[test]
fn two_components_rank_one_and_empty_components() {
    // J = 8 but only components 2 and 5 hold mass: M has rank one, six components are empty.
    let pts = cloud(100, 10);
    let gamma: Vec<f32> =
        (0..100).flat_map(|i| (0..8).map(move |k| if k == [2, 5][i % 2] { 1.0f32 } else { 0.0 })).collect();
    let t_gt = from_rotation_translation(&euler_xyz(0.5, 0.5, 0.5), &Vector3::new(0.0, 0.0, 1.0));
    let gs = gmm_params(&pts, &gamma, 8);
    let gt = gmm_params(&apply_all(&t_gt, &pts), &gamma, 8);
    assert_eq!(gs.pi.iter().filter(|&&p| p == 0.0).count(), 6);
    let est = solve(&gs, &gt);
    assert_finite_rigid(&est);
    for k in [2, 5] {
        let m = gs.mu[k];
        let e = arps::transform::apply(&est, m.map(|v| v as f32));
        let d: f64 = (0..3).map(|a| (e[a] as f64 - gt.mu[k][a]).powi(2)).sum::<f64>().sqrt();
        assert!(d < 1e-5, "component {k} mean off by {d}");
    }
}

#[test]
fn garbage_mixtures_never_give_nan() {
    let ok = gmm_params(&cloud(64, 11), &softmax_gamma(64, 4, 12), 4);
    let mut nan = ok.clone();
    nan.mu[1] = [f64::NAN, 0.0, 0.0];
    nan.var[2] = f64::NAN;
    let mut inf_pi = ok.clone();
    inf_pi.pi[0] = f64::INFINITY;
    let empty = Gmm { pi: vec![], mu: vec![], var: vec![] };
    let zero = Gmm { pi: vec![0.0; 4], mu: vec![[0.0; 3]; 4], var: vec![0.0; 4] };
    let short = Gmm { pi: ok.pi[..2].to_vec(), mu: ok.mu[..2].to_vec(), var: ok.var[..2].to_vec() };
    for (a, b) in
        [(&ok, &nan), (&nan, &ok), (&inf_pi, &ok), (&empty, &ok), (&ok, &empty), (&zero, &zero), (&short, &ok)]
    {
        assert_finite_rigid(&solve(a, b));
    }
    assert_eq!(solve(&empty, &empty), Matrix4::identity());
    // NaN memberships poison only what they touch; the solve still returns something rigid.
    let mut g = softmax_gamma(64, 4, 13);
    g[5] = f32::NAN;
    let bad = gmm_params(&cloud(64, 11), &g, 4);
    assert_finite_rigid(&solve(&bad, &ok));
    assert_finite_rigid(&solve(&ok, &bad));
}

#[test]
fn kabsch_matches_solve_conventions() {
    let pts = cloud(300, 14);
    let t_gt = random_transform(&mut rng(15), 3.0, 2.0);
    let moved = apply_all(&t_gt, &pts);
    let a: Vec<[f64; 3]> = pts.iter().map(|p| p.map(|v| v as f64)).collect();
    let b: Vec<[f64; 3]> = moved.iter().map(|p| p.map(|v| v as f64)).collect();
    let est = kabsch(&a, &b, None);
    assert_finite_rigid(&est);
    assert!(rot_err_rad(&est, &t_gt) < 1e-6 && translation_error(&est, &t_gt) < 1e-6);
    // collinear and coincident point sets
    let line: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 0.0, 0.0]).collect();
    let line2: Vec<[f64; 3]> = (0..10).map(|i| [0.0, -(i as f64), 5.0]).collect();
    let est = kabsch(&line, &line2, None);
    assert_finite_rigid(&est);
    let e = arps::transform::apply(&est, [9.0, 0.0, 0.0]);
    assert!((e[1] + 9.0).abs() < 1e-9 && (e[2] - 5.0).abs() < 1e-9, "{e:?}");
    assert_finite_rigid(&kabsch(&[[1.0; 3]; 5], &[[2.0; 3]; 5], None));
    assert_finite_rigid(&kabsch(&a, &b, Some(&[0.0; 300])));
}
