//! Global registration hypotheses, for motions of any size: FPFH descriptors on a voxelised copy
//! of each cloud ([`fpfh`]), mutual nearest neighbours in descriptor space ([`matching`]), and a
//! seeded RANSAC with geometric pre-checks and early termination ([`ransac`]) that returns a few
//! ranked rigid motions. Each becomes a start of the pipeline's refinement
//! ([`crate::Start::Global`], [`crate::Start::GlobalNetwork`]).
//!
//! Cost grows gently with the point count: the feature voxel is chosen from the data so that each
//! voxelised cloud has at most [`MAX_FEATURE_POINTS`] points ([`feature_voxel`]), after which
//! descriptors, matching and RANSAC no longer depend on the input size; only the voxelisation
//! (O(n log n)) sees every point.

pub mod fpfh;
pub mod matching;
pub mod ransac;

use crate::cloud::PointCloud;
use crate::sampling::{voxel_downsample, voxel_downsample_at_most_in};
use crate::spatial::KdIndex;
pub use ransac::{Hypothesis, RansacParams};

/// Most points per voxelised cloud given to the descriptors: the voxel grows until both clouds
/// fit (matching is brute force, `n_s * n_t` descriptor distances).
pub const MAX_FEATURE_POINTS: usize = 1500;

/// Default feature voxel as a fraction of the larger cloud's largest half-extent (Open3D's
/// tutorials use 0.05 on unit-sized objects; on 100 any-pose validation pairs FPFH + RANSAC + ICP recalled 0.69 at 0.05, 0.79 at 0.08, 0.77 at 0.11 and 0.62 at 0.15).
pub const VOXEL_FRACTION: f64 = 0.08;

/// Settings of [`hypotheses`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalParams {
    /// The feature voxel's starting size as a fraction of the larger half-extent
    /// ([`VOXEL_FRACTION`]); it grows from there until [`MAX_FEATURE_POINTS`] is met.
    pub voxel_fraction: f64,
    /// RANSAC's most draws.
    pub max_iterations: u32,
    /// How many distinct hypotheses to return at most.
    pub hypotheses: usize,
    /// Seed of RANSAC's draws.
    pub seed: u64,
}

impl Default for GlobalParams {
    fn default() -> Self {
        Self { voxel_fraction: VOXEL_FRACTION, max_iterations: 20_000, hypotheses: 5, seed: 0 }
    }
}

/// The feature voxel for a pair: `fraction` of the larger largest half-extent, grown by 25% at a
/// time until both voxelised clouds have at most [`MAX_FEATURE_POINTS`] points.
pub fn feature_voxel(source: &PointCloud, target: &PointCloud, fraction: f64) -> f64 {
    feature_grid(source, target, fraction).0
}

/// [`feature_voxel`], and each cloud voxelised at it when the search had to voxelise it to see
/// that it fits (`None` for a cloud of at most [`MAX_FEATURE_POINTS`] points, which fits as it
/// is, or when no size fitted within the search's steps). A size that does not fit stops
/// voxelising a cloud as soon as it has more voxels than the budget.
fn feature_grid(
    source: &PointCloud,
    target: &PointCloud,
    fraction: f64,
) -> (f64, Option<PointCloud>, Option<PointCloud>) {
    let extent = source.half_extent().max(target.half_extent());
    let mut v = (fraction * extent).max(f64::MIN_POSITIVE);
    // each cloud's bounds once for every try (a try that does not fit stops early)
    let bounds = |c: &PointCloud| if c.len() <= MAX_FEATURE_POINTS { None } else { Some(c.bounds()) };
    let (source_bounds, target_bounds) = (bounds(source), bounds(target));
    // Some(None): fits as it is; Some(Some(c)): fits voxelised as c; None: does not fit
    let fit = |c: &PointCloud, bounds: &Option<([f32; 3], [f32; 3])>, v: f64| match bounds {
        None => Some(None),
        Some(b) => voxel_downsample_at_most_in(c, b, v as f32, MAX_FEATURE_POINTS).map(Some),
    };
    for _ in 0..60 {
        if let Some(s) = fit(source, &source_bounds, v) {
            if let Some(t) = fit(target, &target_bounds, v) {
                return (v, s, t);
            }
        }
        v *= 1.25;
    }
    (v, None, None)
}

/// A voxelised cloud with its FPFH descriptors.
#[derive(Clone, Debug)]
pub struct Described {
    /// The voxelised points.
    pub points: Vec<[f32; 3]>,
    /// One descriptor per point.
    pub descriptors: Vec<fpfh::Descriptor>,
}

/// Voxelises `cloud` at `voxel` and describes every point ([`fpfh::FpfhParams::for_voxel`]).
pub fn describe(cloud: &PointCloud, voxel: f64) -> Described {
    describe_voxelised(voxel_downsample(cloud, voxel as f32).points, voxel)
}

/// [`describe`] of points already voxelised at `voxel`.
fn describe_voxelised(points: Vec<[f32; 3]>, voxel: f64) -> Described {
    let index = KdIndex::new(&points);
    let p = fpfh::FpfhParams::for_voxel(voxel);
    let normals = fpfh::oriented_normals(&points, &index, p.normal_radius, p.normal_max);
    let descriptors = fpfh::describe(&points, &normals, &index, &p);
    Described { points, descriptors }
}

/// Both clouds voxelised and described at one feature voxel ([`feature_voxel`]), and their
/// mutual descriptor matches: what RANSAC draws from. Built once per pair; [`Matched::hypotheses`]
/// can then draw more than once (the adaptive search asks for more hypotheses when the first
/// ones were not enough) without describing the clouds again.
#[derive(Clone, Debug)]
pub struct Matched {
    source: Described,
    target: Described,
    matches: Vec<(u32, u32)>,
    voxel: f64,
}

impl Matched {
    /// Describes `source` and `target` (both in one unit, any relative pose) at the feature voxel
    /// of `voxel_fraction` and matches their descriptors.
    pub fn new(source: &PointCloud, target: &PointCloud, voxel_fraction: f64) -> Self {
        let (voxel, source_v, target_v) = feature_grid(source, target, voxel_fraction);
        // the search's voxelised clouds where it made them (the same as describing anew)
        let described = |c: &PointCloud, v: Option<PointCloud>| match v {
            Some(v) => describe_voxelised(v.points, voxel),
            None => describe(c, voxel),
        };
        let (source, target) = (described(source, source_v), described(target, target_v));
        let matches = matching::mutual_matches(&source.descriptors, &target.descriptors, 30);
        Self { source, target, matches, voxel }
    }

    /// Ranked rigid motions taking the source onto the target, best first (`params.hypotheses` at
    /// most; `params.voxel_fraction` is the one given to [`Matched::new`]); empty when the
    /// descriptors gave fewer than three correspondences. Deterministic for `params.seed`.
    pub fn hypotheses(&self, params: &GlobalParams) -> Vec<Hypothesis> {
        let rp = RansacParams {
            max_iterations: params.max_iterations,
            confidence: 0.999,
            inlier_distance: 1.5 * self.voxel,
            edge_ratio: 0.9,
            hypotheses: params.hypotheses,
            seed: params.seed,
        };
        ransac::ransac(&self.source.points, &self.target.points, &self.matches, &rp)
    }
}

/// Ranked rigid motions taking `source` onto `target` (both in one unit, any relative pose), best
/// first; empty when the descriptors give fewer than three correspondences. Deterministic for
/// `params.seed`. ([`Matched::new`], then [`Matched::hypotheses`].)
pub fn hypotheses(source: &PointCloud, target: &PointCloud, params: &GlobalParams) -> Vec<Hypothesis> {
    Matched::new(source, target, params.voxel_fraction).hypotheses(params)
}
