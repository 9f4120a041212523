//! One training pair, as the data pipeline hands it to [`super::train_step`].

use nalgebra::Matrix4;

/// A source/target pair with its ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct Pair {
    /// Source cloud, normalised units, N points.
    pub source: Vec<[f32; 3]>,
    /// Target cloud, normalised units, N points.
    pub target: Vec<[f32; 3]>,
    /// Ground truth `T_target_source` (maps source points into the target frame).
    pub t_gt: Matrix4<f64>,
    /// Ground-truth reference point (global-shape centroid) in the source's pre-centred frame,
    /// i.e. already minus the source's own mean.
    pub v_gt_source: [f32; 3],
    /// The same for the target, in the target's pre-centred frame.
    pub v_gt_target: [f32; 3],
}
