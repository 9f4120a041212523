//! How sure the engine is of an answer: evidence that separates right from wrong alignments,
//! and a logistic model over it calibrated on validation pairs ([`confidence`]).
//!
//! Fitness at one tight distance is a poor verdict on partial, independently sampled, noisy
//! scans: right answers often score 0.15-0.30. The fitness *curve* says more (a right answer's
//! rises early and steeply), and so does the overlap measured both ways.

use crate::icp::{IcpKind, IcpParams, IcpTarget};
use crate::refine::{even_sample, SCREEN_POINTS};
use crate::transform::rigid_inverse;
use crate::transform::{apply, from_rotation_translation, rotation_error_deg};
use nalgebra::Matrix4;
use nalgebra::{Matrix3, Rotation3, SymmetricEigen, Vector3};
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
    /// How well the best *different* pose fits, as a fraction of the answer's fitness: the
    /// answer turned 180 degrees about each principal axis of the moved source (through its
    /// centroid), each refined by a short ICP; 0 when every one fell back onto the answer.
    /// Near 1 or above: a symmetric shape, the answer may fit and still not be unique.
    pub ambiguity: f64,
}

/// Measures the [`Evidence`] of `T_target_source` (source points moved into the target frame):
/// `target` and `source_index` are the prepared clouds (the source's as an [`IcpTarget`] too,
/// for the reverse overlap), `source` the source points, `d` the final distance. On clouds of
/// more than [`crate::refine::SCREEN_POINTS`] points it is measured on that many, evenly spread,
/// so its cost does not grow with the point count beyond the kd-tree queries' logarithm.
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
    let ambiguity = ambiguity(target, &source, T_target_source, d, kind);
    Evidence {
        ambiguity,
        fitness,
        fitness_tight: f(0.5),
        fitness_loose: f(2.0),
        fitness_coarse: f(4.0),
        overlap_reverse,
        rmse_ratio: if d > 0.0 { rmse / d } else { 0.0 },
    }
}

/// Points of the [`Evidence::ambiguity`] probe.
const PROBE_POINTS: usize = 512;
/// A probe pose that ends within this many degrees of the answer has fallen back onto it.
const SAME_POSE_DEGREES: f64 = 15.0;

/// [`Evidence::ambiguity`] of `t` on an even sample of `source`.
fn ambiguity(target: &IcpTarget, source: &[[f32; 3]], t: &Matrix4<f64>, d: f64, kind: IcpKind) -> f64 {
    let sample = even_sample(source, PROBE_POINTS);
    let base = target.evaluate(&sample, t, d).0;
    if base <= 0.0 || sample.len() < 3 {
        return 0.0;
    }
    let moved: Vec<Vector3<f64>> = sample.iter().map(|&p| Vector3::from(apply(t, p).map(|v| v as f64))).collect();
    let n = moved.len() as f64;
    let c = moved.iter().fold(Vector3::zeros(), |a, p| a + p) / n;
    let cov = moved.iter().fold(Matrix3::zeros(), |a, p| a + (p - c) * (p - c).transpose()) / n;
    let axes = SymmetricEigen::new(cov).eigenvectors;
    let kind = if kind == IcpKind::Off { IcpKind::Point } else { kind };
    let mut worst = 0.0f64;
    for k in 0..3 {
        let axis = nalgebra::Unit::new_normalize(axes.column(k).into_owned());
        let r = Rotation3::from_axis_angle(&axis, std::f64::consts::PI).into_inner();
        let mut alt = from_rotation_translation(&r, &(c - r * c)) * t;
        for factor in [2.0, 1.0] {
            alt = target
                .align(&sample, &alt, &IcpParams { max_iterations: 15, ..IcpParams::new(kind, factor * d) })
                .T_target_source;
        }
        if rotation_error_deg(&alt, t) > SAME_POSE_DEGREES {
            worst = worst.max(target.evaluate(&sample, &alt, d).0 / base);
        }
    }
    worst.min(2.0)
}

/// The model's inputs: the evidence, plus how steeply the fitness curve rises (tight over coarse).
fn features(e: &Evidence) -> [f64; 8] {
    let rise = if e.fitness_coarse > 0.0 { e.fitness_tight / e.fitness_coarse } else { 0.0 };
    [e.fitness, e.fitness_tight, e.fitness_loose, e.fitness_coarse, e.overlap_reverse, e.rmse_ratio, rise, e.ambiguity]
}

/// Logistic-regression weights of [`features`] and the bias (last), fitted by
/// `scripts/fit-confidence.py` on 1,440 answers (network + ICP, FPFH + RANSAC + ICP and the
/// exhaustive search on 240 paper-protocol and 240 any-pose validation pairs; `BENCHMARK.md`).
const WEIGHTS: [f64; 9] = [2.355, 0.6752, 2.385, 1.153, 2.599, -0.5323, 0.8626, -4.74, 0.1596];

/// The probability that the answer is right (within the evaluation's recall thresholds), in
/// [0, 1]: a logistic model over the [`Evidence`]. Below 0.5 the result carries a warning.
pub fn confidence(e: &Evidence) -> f64 {
    let x = features(e);
    let z: f64 = x.iter().zip(WEIGHTS.iter()).map(|(a, w)| a * w).sum::<f64>() + WEIGHTS[x.len()];
    if z.is_finite() {
        1.0 / (1.0 + (-z).exp())
    } else {
        0.0
    }
}
