//! ICP refinement: point-to-point and point-to-plane.

use nalgebra::Matrix4;

/// Which ICP to run after the network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum IcpKind {
    /// No refinement: the network's transform is the answer.
    Off,
    /// Point-to-point ICP (Besl-McKay, closed-form Kabsch each iteration).
    Point,
    /// Point-to-plane ICP (linearised, target normals), the default.
    #[default]
    Plane,
}

/// Parameters of one ICP run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IcpParams {
    /// Point-to-point or point-to-plane (`Off` returns the initial transform unchanged).
    pub kind: IcpKind,
    /// Correspondences farther apart than this are rejected (same units as the points).
    pub max_correspondence_distance: f64,
    /// Iteration cap.
    pub max_iterations: u32,
    /// Stop when the relative change of fitness is below this ...
    pub relative_fitness: f64,
    /// ... and the relative change of inlier RMSE is below this.
    pub relative_rmse: f64,
}

/// What an ICP run returns.
#[allow(non_snake_case)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IcpResult {
    /// The refined transform, mapping source points into the target frame.
    pub T_target_source: Matrix4<f64>,
    /// Fraction of source points with a target point within the max correspondence distance.
    pub fitness: f64,
    /// RMS distance over those inlier correspondences (0 when there are none).
    pub inlier_rmse: f64,
    /// Iterations run.
    pub iterations: u32,
    /// True when the convergence criteria were met before the iteration cap.
    pub converged: bool,
}

/// A target prepared once (kd-tree, normals) and reused by several ICP runs.
pub struct IcpTarget {
    _private: (),
}

impl IcpTarget {
    /// Builds the kd-tree (and the normals, for point-to-plane) of the target.
    pub fn new(points: &[[f32; 3]], with_normals: bool) -> Self {
        let _ = (points, with_normals);
        todo!("helper: icp")
    }

    /// Runs ICP from `init` (`T_target_source`).
    pub fn align(&self, source: &[[f32; 3]], init: &Matrix4<f64>, params: &IcpParams) -> IcpResult {
        let _ = (source, init, params);
        todo!("helper: icp")
    }
}

impl IcpTarget {
    /// Fitness and inlier RMSE of `source` under `T_target_source` at `max_distance`
    /// (the definitions of [`IcpResult`]), without iterating.
    pub fn evaluate(&self, source: &[[f32; 3]], t: &Matrix4<f64>, max_distance: f64) -> (f64, f64) {
        let _ = (source, t, max_distance);
        todo!("helper: icp")
    }
}
