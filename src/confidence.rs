//! How sure the engine is of an answer: evidence that separates right from wrong alignments,
//! and a logistic model over it calibrated on validation pairs ([`confidence`]).
//!
//! Fitness at one tight distance is a poor verdict on partial, independently sampled, noisy
//! scans: right answers often score 0.15-0.30. The fitness *curve* says more (a right answer's
//! rises early and steeply), and so does the overlap measured both ways.
//!
//! A good fit is not enough either: on a symmetric or featureless shape other poses fit as well,
//! and an answer that is one of `k` equally good poses is right with a probability of about
//! `1 / k`, however well it fits. So the evidence also looks for such poses: the answer turned
//! about the moved source's principal axes and refined by a short ICP ([`Evidence::ambiguity`],
//! [`Evidence::alternatives`]), and the answer slid along the motion its point-to-plane fit
//! constrains least ([`Evidence::slide`]: a surface of revolution turned about its axis, a plane
//! shifted in itself). The confidence is low on such answers, right or wrong.

use crate::icp::{IcpKind, IcpParams, IcpTarget};
use crate::refine::{even_sample, SCREEN_POINTS};
use crate::transform::rigid_inverse;
use crate::transform::{apply, from_rotation_translation, rotation_error_deg};
use nalgebra::Matrix4;
use nalgebra::{Matrix3, Matrix6, Rotation3, SymmetricEigen, Vector3, Vector6};
use serde::{Deserialize, Serialize};

/// The evidence behind [`confidence`], measured on the (voxelised) clouds under the answer, in
/// multiples of the final max correspondence distance `d`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationEvidence"))]
pub struct Evidence {
    /// Fraction of source points with a target point within `d` (the result's `fitness`).
    pub fitness: f64,
    /// The same within `d / 2`.
    pub fitness_tight: f64,
    /// The same within `2 d`.
    pub fitness_loose: f64,
    /// The same within `4 d`.
    pub fitness_coarse: f64,
    /// Fraction of target points with a source point within `d` (overlap the other way).
    pub overlap_reverse: f64,
    /// Inlier RMSE at `d`, divided by `d` (0 without inliers).
    pub rmse_ratio: f64,
    /// How well the best *different* pose fits, as a fraction of the answer's fitness (at most
    /// 2): the answer turned 90 degrees both ways and 180 degrees about each principal axis of
    /// the moved source (through its centroid), each refined by a short ICP; 0 when every one
    /// fell back onto the answer (within 15 degrees). Near 1 or above: the answer may fit and
    /// still not be unique.
    pub ambiguity: f64,
    /// How many distinct poses among those turns fit at least 0.9 as well as the answer: with
    /// `k` alternatives the answer is one of `k + 1` about equally good poses.
    pub alternatives: f64,
    /// Fitness after sliding the answer along the motion its point-to-plane fit constrains
    /// least (the weakest eigenvector of the fit's 6x6 information matrix, scaled to move the
    /// points 0.25 of the normalised half-extent on average), the better of both ways, as a
    /// fraction of the answer's fitness (at most 2). Near 1: the fit does not pin the pose down
    /// along that motion (a surface of revolution, a plane, a cylinder).
    pub slide: f64,
}

/// Measures the [`Evidence`] of `T_target_source` (source points moved into the target frame):
/// `target` and `source_index` are the prepared clouds (the source's as an [`IcpTarget`] too,
/// for the reverse overlap), `source` the source points, `d` the final distance, `kind` the ICP
/// of the probes ([`IcpKind::Off`] probes with point-to-point). On clouds of more than
/// [`crate::refine::SCREEN_POINTS`] points it is measured on that many, evenly spread, and the
/// probes on [`PROBE_POINTS`], so its cost does not grow with the point count beyond the
/// kd-tree queries' logarithm. It uses the target's normals (computed on first use).
#[allow(non_snake_case)]
pub fn evidence(
    target: &IcpTarget,
    source_index: &IcpTarget,
    source: &[[f32; 3]],
    T_target_source: &Matrix4<f64>,
    d: f64,
    kind: IcpKind,
) -> Evidence {
    let source = even_sample(source, SCREEN_POINTS);
    let target_points = even_sample(target.points(), SCREEN_POINTS);
    let (fitness, rmse) = target.evaluate(&source, T_target_source, d);
    let f = |k: f64| target.evaluate(&source, T_target_source, k * d).0;
    let overlap_reverse = source_index.evaluate(&target_points, &rigid_inverse(T_target_source), d).0;
    let probe = even_sample(&source, PROBE_POINTS);
    let (ambiguity, alternatives) = turns(target, &probe, T_target_source, d, kind);
    Evidence {
        fitness,
        fitness_tight: f(0.5),
        fitness_loose: f(2.0),
        fitness_coarse: f(4.0),
        overlap_reverse,
        rmse_ratio: if d > 0.0 { rmse / d } else { 0.0 },
        ambiguity,
        alternatives,
        slide: slide(target, &probe, T_target_source, d),
    }
}

/// Points of the probes ([`Evidence::ambiguity`], [`Evidence::slide`]).
pub const PROBE_POINTS: usize = 512;
/// A probe pose that ends within this many degrees of the answer has fallen back onto it; two
/// alternatives this close are one.
const SAME_POSE_DEGREES: f64 = 15.0;
/// The turns of the ambiguity probe, degrees, about each principal axis.
const TURNS: [f64; 3] = [180.0, 90.0, -90.0];
/// An alternative fitting at least this fraction of the answer's fitness counts in
/// [`Evidence::alternatives`].
const ALTERNATIVE_FIT: f64 = 0.9;
/// Each probe's ICP: iterations at `2 d`, then at `d`.
const PROBE_ITERATIONS: u32 = 10;
/// A probe whose fitness after the `2 d` stage is below this fraction of the answer's (at
/// `2 d`) stops there: it cannot come near the answer's fit.
const PROBE_CUT: f64 = 0.6;
/// How far [`Evidence::slide`] moves the points, on average (normalised units).
const SLIDE_RMS: f64 = 0.25;

/// [`Evidence::ambiguity`] and [`Evidence::alternatives`] of `t` on the probe points `sample`.
fn turns(target: &IcpTarget, sample: &[[f32; 3]], t: &Matrix4<f64>, d: f64, kind: IcpKind) -> (f64, f64) {
    let base = target.evaluate(sample, t, d).0;
    let base_loose = target.evaluate(sample, t, 2.0 * d).0;
    if base <= 0.0 || sample.len() < 3 {
        return (0.0, 0.0);
    }
    let (c, axes) = principal_axes(sample, t);
    let kind = if kind == IcpKind::Off { IcpKind::Point } else { kind };
    let params = |factor: f64| IcpParams { max_iterations: PROBE_ITERATIONS, ..IcpParams::new(kind, factor * d) };
    let mut best = 0.0f64;
    let mut alternatives: Vec<Matrix4<f64>> = Vec::new();
    for degrees in TURNS {
        for k in 0..3 {
            let axis = nalgebra::Unit::new_normalize(axes.column(k).into_owned());
            let r = Rotation3::from_axis_angle(&axis, degrees.to_radians()).into_inner();
            let start = from_rotation_translation(&r, &(c - r * c)) * t;
            let coarse = target.align(sample, &start, &params(2.0));
            let alt = if coarse.fitness < PROBE_CUT * base_loose {
                coarse.T_target_source
            } else {
                target.align(sample, &coarse.T_target_source, &params(1.0)).T_target_source
            };
            if rotation_error_deg(&alt, t) <= SAME_POSE_DEGREES {
                continue;
            }
            let ratio = target.evaluate(sample, &alt, d).0 / base;
            best = best.max(ratio);
            if ratio >= ALTERNATIVE_FIT
                && !alternatives.iter().any(|a| rotation_error_deg(a, &alt) <= SAME_POSE_DEGREES)
            {
                alternatives.push(alt);
            }
        }
    }
    (best.min(2.0), alternatives.len() as f64)
}

/// The centroid of `sample` moved by `t`, and its principal axes (the columns).
fn principal_axes(sample: &[[f32; 3]], t: &Matrix4<f64>) -> (Vector3<f64>, Matrix3<f64>) {
    let moved: Vec<Vector3<f64>> = sample.iter().map(|&p| Vector3::from(apply(t, p).map(|v| v as f64))).collect();
    let n = moved.len() as f64;
    let c = moved.iter().fold(Vector3::zeros(), |a, p| a + p) / n;
    let cov = moved.iter().fold(Matrix3::zeros(), |a, p| a + (p - c) * (p - c).transpose()) / n;
    (c, SymmetricEigen::new(cov).eigenvectors)
}

/// [`Evidence::slide`] of `t` on the probe points `sample`.
fn slide(target: &IcpTarget, sample: &[[f32; 3]], t: &Matrix4<f64>, d: f64) -> f64 {
    let base = target.evaluate(sample, t, d).0;
    if base <= 0.0 || sample.len() < 3 {
        return 0.0;
    }
    let normals = target.normals();
    let moved: Vec<Vector3<f64>> = sample.iter().map(|&p| Vector3::from(apply(t, p).map(|v| v as f64))).collect();
    // the inliers at d with their target normals
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = moved
        .iter()
        .filter_map(|p| {
            let j = target.nearest_within(&[p.x as f32, p.y as f32, p.z as f32], d)?;
            Some((*p, Vector3::from(normals[j].map(|v| v as f64))))
        })
        .collect();
    if pairs.len() < 6 {
        return 0.0;
    }
    let c = pairs.iter().fold(Vector3::zeros(), |a, p| a + p.0) / pairs.len() as f64;
    let mut info = Matrix6::<f64>::zeros();
    for (p, n) in &pairs {
        let a = (p - c).cross(n);
        let j = Vector6::new(a.x, a.y, a.z, n.x, n.y, n.z);
        info += j * j.transpose();
    }
    let eig = SymmetricEigen::new(info);
    let weakest = eig.eigenvalues.imin();
    let v = eig.eigenvectors.column(weakest).into_owned();
    let (w, shift) = (Vector3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5]));
    // the points' RMS displacement per unit of that motion
    let rms =
        (moved.iter().map(|p| (w.cross(&(p - c)) + shift).norm_squared()).sum::<f64>() / moved.len() as f64).sqrt();
    if rms.is_nan() || rms <= 0.0 {
        return 0.0;
    }
    let mut best = 0.0f64;
    for sign in [1.0, -1.0] {
        let s = sign * SLIDE_RMS / rms;
        let r = match nalgebra::Unit::try_new(w * s, 1e-12) {
            Some(axis) => Rotation3::from_axis_angle(&axis, (w * s).norm()).into_inner(),
            None => Matrix3::identity(),
        };
        let m = from_rotation_translation(&r, &(c - r * c + shift * s)) * t;
        best = best.max(target.evaluate(sample, &m, d).0 / base);
    }
    best.min(2.0)
}

/// The model's inputs: the evidence, plus how steeply the fitness curve rises (tight over coarse).
fn features(e: &Evidence) -> [f64; 10] {
    let rise = if e.fitness_coarse > 0.0 { e.fitness_tight / e.fitness_coarse } else { 0.0 };
    [
        e.fitness,
        e.fitness_tight,
        e.fitness_loose,
        e.fitness_coarse,
        e.overlap_reverse,
        e.rmse_ratio,
        rise,
        e.ambiguity,
        e.alternatives,
        e.slide,
    ]
}

/// Logistic-regression weights of [`features`] and the bias (last), fitted by
/// `scripts/fit-confidence.py` on 2,400 answers: network + ICP, FPFH + RANSAC + ICP and the
/// exhaustive search on 500 paper-protocol and 300 any-pose validation pairs (`BENCHMARK.md`,
/// "Confidence", where the cross-validated figures are).
const WEIGHTS: [f64; 11] = [2.257, 0.5685, 2.755, 0.6824, 2.431, -0.2873, 0.7299, -2.536, -0.6525, -2.881, 1.072];

/// The probability that the answer is right (within the evaluation's recall thresholds: rotation
/// error below 15 degrees and translation error below 0.2 of the normalised half-extent), in
/// [0, 1]: a logistic model over the [`Evidence`], calibrated on validation pairs, and at most
/// `1 / (1 + alternatives)`: an answer that is one of `k` poses fitting about as well is right
/// with a probability of about `1 / k` at best. So it is low when the clouds overlap poorly under
/// the answer, and also when other poses fit about as well (a symmetric or featureless shape):
/// then the answer may be right, but nothing in the clouds says so. Below 0.5 the result
/// carries a warning. Non-finite evidence gives 0.
pub fn confidence(e: &Evidence) -> f64 {
    let x = features(e);
    let z: f64 = x.iter().zip(WEIGHTS.iter()).map(|(a, w)| a * w).sum::<f64>() + WEIGHTS[x.len()];
    let cap = 1.0 / (1.0 + e.alternatives.max(0.0));
    if z.is_finite() && cap.is_finite() {
        (1.0 / (1.0 + (-z).exp())).min(cap)
    } else {
        0.0
    }
}
