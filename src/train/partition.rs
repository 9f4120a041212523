//! Target memberships for the `seg` loss: a canonical partition of the shape into `J` cones
//! around its ground-truth centroid, expressed in both clouds' frames consistently.
//!
//! Why: the transform losses are (to first order) blind to how confident the memberships are:
//! the Procrustes rotation does not change when every component mean moves towards the
//! centroid by the same factor. Trained with them alone, the network keeps memberships almost
//! uniform (row entropy 0.995 of the maximum in run `web-1`) and encodes the rotation in
//! component means that differ by less than 1e-3, so GMR works from tiny differences, and
//! translation degenerates to centroid alignment. Dense losses on the memberships (means
//! alignment, consistency) cannot leave that point either: at uniform memberships their
//! gradients are the same for every component and vanish through the softmax.
//!
//! The partition gives every point a label that (a) is the same for corresponding points in the
//! two clouds, (b) splits the shape into well-separated regions (component means far apart, so
//! the Procrustes solve is well conditioned), and (c) is symmetric in the two clouds, so the
//! Siamese network can predict it for either role. Point `x` of a cloud with ground-truth shape
//! centroid `v` gets the direction `u = Q (x - v)`, with `Q = R_half` for the source and
//! `Q = R_halfᵀ` for the target, where `R_half` is the half rotation of `R_gt`
//! (`R_half² = R_gt`): corresponding points get the same `u`, since
//! `R_halfᵀ (R_gt x^ + t - R_gt v^ - t) = R_half (x^ - v^)`. The target row is
//! `p_j ∝ exp(kappa · <a_j, u / |u|>)` over `J` fixed unit anchors `a_j` (a Fibonacci sphere):
//! soft cones around the centroid. Predicting it needs the reference point (ARPS's job) and half
//! the relative rotation (through cross-attention): the registration task itself, supervised at
//! every point.

use nalgebra::{Matrix3, Matrix4, Rotation3, Vector3};

/// `J` unit vectors spread evenly over the sphere (Fibonacci lattice), deterministic.
pub fn anchors(j: usize) -> Vec<Vector3<f64>> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..j)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as f64 + 0.5) / j as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * k as f64;
            Vector3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The half rotation `R_half` of the rotation part of `t_gt` (`R_half² = R_gt`).
pub fn half_rotation(t_gt: &Matrix4<f64>) -> Matrix3<f64> {
    let r: Matrix3<f64> = t_gt.fixed_view::<3, 3>(0, 0).into_owned();
    let rot = Rotation3::from_matrix(&r);
    match rot.axis_angle() {
        Some((axis, angle)) => *Rotation3::from_axis_angle(&axis, 0.5 * angle).matrix(),
        None => Matrix3::identity(),
    }
}

/// Which cloud of the pair the points belong to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The source (`Q = R_half`).
    Source,
    /// The target (`Q = R_halfᵀ`).
    Target,
}

/// Target membership rows (`[n, J]`, row-major, rows summing to 1) of `points` whose shape
/// centroid is `centroid` (same frame), for a pair with ground truth `t_gt`.
pub fn targets(
    points: &[[f32; 3]],
    centroid: [f64; 3],
    t_gt: &Matrix4<f64>,
    role: Role,
    j: usize,
    kappa: f64,
) -> Vec<f32> {
    let half = half_rotation(t_gt);
    let q = match role {
        Role::Source => half,
        Role::Target => half.transpose(),
    };
    let a = anchors(j);
    let c = Vector3::from(centroid);
    let mut out = Vec::with_capacity(points.len() * j);
    let mut logits = vec![0.0f64; j];
    for p in points {
        let u = q * (Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) - c);
        let len = u.norm();
        if len < 1e-9 {
            out.extend(std::iter::repeat_n(1.0 / j as f32, j));
            continue;
        }
        let u = u / len;
        for (l, ak) in logits.iter_mut().zip(&a) {
            *l = kappa * ak.dot(&u);
        }
        let m = logits.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let z: f64 = logits.iter().map(|l| (l - m).exp()).sum();
        out.extend(logits.iter().map(|l| ((l - m).exp() / z) as f32));
    }
    out
}
