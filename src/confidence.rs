//! How sure the engine is of an answer: evidence that separates right from wrong alignments,
//! and a logistic model over it calibrated on validation pairs ([`confidence`]).
//!
//! Fitness at one tight distance is a poor verdict on partial, independently sampled, noisy
//! scans: right answers often score 0.15-0.30. The fitness *curve* says more (a right answer's
//! rises early and steeply), and so does the overlap measured both ways.

use crate::icp::IcpTarget;
use crate::refine::{even_sample, SCREEN_POINTS};
use crate::transform::rigid_inverse;
use nalgebra::Matrix4;
use serde::{Deserialize, Serialize};

/// The evidence behind [`confidence`], measured on the (voxelised) clouds under the answer, in
/// multiples of the final max correspondence distance `d`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
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
) -> Evidence {
    let source = even_sample(source, SCREEN_POINTS);
    let target_points = even_sample(target.points(), SCREEN_POINTS);
    let (fitness, rmse) = target.evaluate(&source, T_target_source, d);
    let f = |k: f64| target.evaluate(&source, T_target_source, k * d).0;
    let overlap_reverse = source_index.evaluate(&target_points, &rigid_inverse(T_target_source), d).0;
    Evidence {
        fitness,
        fitness_tight: f(0.5),
        fitness_loose: f(2.0),
        fitness_coarse: f(4.0),
        overlap_reverse,
        rmse_ratio: if d > 0.0 { rmse / d } else { 0.0 },
    }
}

/// The model's inputs: the evidence, plus how steeply the fitness curve rises (tight over coarse).
fn features(e: &Evidence) -> [f64; 7] {
    let rise = if e.fitness_coarse > 0.0 { e.fitness_tight / e.fitness_coarse } else { 0.0 };
    [e.fitness, e.fitness_tight, e.fitness_loose, e.fitness_coarse, e.overlap_reverse, e.rmse_ratio, rise]
}

/// Logistic-regression weights of [`features`] and the bias (last), fitted on validation pairs
/// (`BENCHMARK.md`).
const WEIGHTS: [f64; 8] = [4.0, 4.0, 0.0, 0.0, 4.0, -2.0, 8.0, -6.0];

/// The probability that the answer is right (within the evaluation's recall thresholds), in
/// [0, 1]: a logistic model over the [`Evidence`]. Below 0.5 the result carries a warning.
pub fn confidence(e: &Evidence) -> f64 {
    let x = features(e);
    let z: f64 = x.iter().zip(WEIGHTS.iter()).map(|(a, w)| a * w).sum::<f64>() + WEIGHTS[7];
    if z.is_finite() {
        1.0 / (1.0 + (-z).exp())
    } else {
        0.0
    }
}
