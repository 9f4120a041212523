//! Global registration hypotheses, for motions of any size: FPFH descriptors on a voxelised copy
//! of each cloud ([`fpfh`]), mutual nearest neighbours in descriptor space ([`matching`]), and a
//! seeded RANSAC with geometric pre-checks and early termination ([`ransac`]) that returns a few
//! ranked rigid motions. Each becomes a start of the pipeline's refinement
//! ([`crate::Start::Global`], [`crate::Start::GlobalNetwork`]). For a given rotation, the matches
//! also vote for a translation ([`translation`], [`Matched::translations`]): the search puts back an
//! answer whose rotation is right and whose translation is not.
//!
//! Cost grows gently with the point count: the feature voxel is chosen from the data so that each
//! voxelised cloud has at most [`MAX_FEATURE_POINTS`] points ([`DENSE_FEATURE_POINTS`] on dense
//! scans; [`feature_voxels`]), after which
//! descriptors, matching and RANSAC no longer depend on the input size; only the voxelisation
//! (O(n)) sees every point, and for a large cloud not even that: the pipeline gives a finer
//! voxelised copy that stands in for its points ([`FeatureCloud`], [`standin`]).

pub mod fpfh;
pub mod matching;
pub mod ransac;
pub mod translation;

use crate::cloud::{centroid_of, half_extent_of, PointCloud};
use crate::sampling::{voxel_downsample, voxel_downsample_at_most_in};
use crate::spatial::KdIndex;
pub use ransac::{Hypothesis, RansacParams};
use std::sync::{Mutex, OnceLock};

/// Most points per voxelised cloud given to the descriptors: the voxel grows until both clouds
/// fit (matching is brute force, `n_s * n_t` descriptor distances).
pub const MAX_FEATURE_POINTS: usize = 1500;

/// Default feature voxel as a fraction of the larger cloud's largest half-extent (Open3D's
/// tutorials use 0.05 on unit-sized objects; on 100 any-pose validation pairs FPFH + RANSAC + ICP recalled 0.69 at 0.05, 0.79 at 0.08, 0.77 at 0.11 and 0.62 at 0.15).
pub const VOXEL_FRACTION: f64 = 0.08;

/// A cloud is *dense* when it has at least this many points per occupied voxel of the default
/// feature voxel ([`VOXEL_FRACTION`] of the pair's larger half-extent): a scan rather than a
/// sparse sample. A pair of dense clouds is described finer ([`DENSE_VOXEL_FRACTION`],
/// [`DENSE_FEATURE_POINTS`]; `BENCHMARK.md`, "Dense scans"). The synthetic 1,024-point
/// validation clouds have 1.3-3.8 points per voxel there, real scans of 15k-70k points 20-200.
pub const DENSE_OCCUPANCY: usize = 8;

/// A cloud between sparse and dense has at least this many points per occupied voxel of the
/// default feature voxel (and at least [`MID_MIN_POINTS`] points), fewer than
/// [`DENSE_OCCUPANCY`]: a clean scan thinned to a few thousand points (a room's 19,000-point scan
/// sampled down to 2,000-5,000 has 3-6.5), or a clean sample of an object of a few thousand.
/// Neither scale of descriptors is right for all of them (the coarse one misses a thinned room,
/// the fine one some objects), so a pair of such clouds is described at both ([`Density::Mid`];
/// the adaptive search only where its answer so far fits under half of the source,
/// [`Matched::onto_at`]; `BENCHMARK.md`, "Thinned scans").
pub const MID_OCCUPANCY: usize = 3;

/// A dense cloud has at least this many points too (twice [`MAX_FEATURE_POINTS`]): a sparse
/// sample of an elongated shape also crowds the few voxels its extent gives it.
pub const DENSE_MIN_POINTS: usize = 2 * MAX_FEATURE_POINTS;

/// A cloud between sparse and dense ([`MID_OCCUPANCY`]) has at least this many points too: a room
/// scan thinned to 2,000 points still crowds the default voxel 3 or more to a voxel, and the
/// coarse descriptors alone lose its structure (`BENCHMARK.md`, "Thinned scans of 2,000 points").
pub const MID_MIN_POINTS: usize = 2000;

/// The feature voxel's starting size on a dense pair, as a fraction of the larger half-extent
/// (with the default [`VOXEL_FRACTION`]; another fraction scales it alike).
pub const DENSE_VOXEL_FRACTION: f64 = 0.025;

/// Most points per voxelised cloud given to the descriptors on a dense pair.
pub const DENSE_FEATURE_POINTS: usize = 2500;

/// Settings of [`hypotheses`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalParams {
    /// The feature voxel's starting size as a fraction of the larger half-extent
    /// ([`VOXEL_FRACTION`]); it grows from there until [`MAX_FEATURE_POINTS`] is met (on a
    /// [`Density::Dense`] pair it starts finer, [`DENSE_VOXEL_FRACTION`], and the budget is
    /// [`DENSE_FEATURE_POINTS`]).
    pub voxel_fraction: f64,
    /// RANSAC's most draws ([`MAX_ITERATIONS`]).
    pub max_iterations: u32,
    /// How many distinct hypotheses to return at most, per scale the pair is described at.
    pub hypotheses: usize,
    /// Seed of RANSAC's draws.
    pub seed: u64,
}

impl Default for GlobalParams {
    fn default() -> Self {
        Self { voxel_fraction: VOXEL_FRACTION, max_iterations: MAX_ITERATIONS, hypotheses: 5, seed: 0 }
    }
}

/// RANSAC's most draws by default (Open3D's tutorial pipeline takes as many). A pair whose matches
/// are mostly right stops far sooner (the draws stop once a better one is unlikely); the cap
/// binds on scans of rooms, where a few percent of the matches are right: there three right
/// matches come together about once in 10,000 draws, and 20,000 draws missed the truth on about
/// one pair in eight (`BENCHMARK.md`, "RANSAC's draws on scans of rooms").
pub const MAX_ITERATIONS: u32 = 100_000;

/// The feature voxels for a pair, one per scale its [`density`] describes it at: `fraction` of
/// the larger largest half-extent, grown by 25% at a time until both voxelised clouds have at most
/// [`MAX_FEATURE_POINTS`] points; finer, from [`DENSE_VOXEL_FRACTION`] (scaled like `fraction`) to
/// at most [`DENSE_FEATURE_POINTS`].
///
/// Either cloud may be a stand-in ([`FeatureCloud`]).
pub fn feature_voxels<'s, 't>(
    source: impl Into<FeatureCloud<'s>>,
    target: impl Into<FeatureCloud<'t>>,
    fraction: f64,
) -> Vec<f64> {
    let memo = TargetFeatures::default();
    let pair = Pair::new(source.into(), target.into(), &memo);
    density_of(&pair, &memo, fraction).fine().iter().map(|&fine| feature_grid(&pair, &memo, fraction, fine).0).collect()
}

/// How densely a pair samples its surfaces, which sets the scales its descriptors are made at
/// ([`density`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Density {
    /// Either cloud is a sparse sample: described at the default feature voxel
    /// ([`VOXEL_FRACTION`], at most [`MAX_FEATURE_POINTS`] points).
    Sparse,
    /// Both clouds are between sparse and dense ([`MID_OCCUPANCY`]): described at both scales,
    /// each giving its hypotheses.
    Mid,
    /// Both clouds are dense ([`DENSE_OCCUPANCY`]): described finer ([`DENSE_VOXEL_FRACTION`], at
    /// most [`DENSE_FEATURE_POINTS`] points).
    Dense,
}

impl Density {
    /// The scales the pair is described at, in the order their hypotheses come, each whether it
    /// is the finer one ([`DENSE_VOXEL_FRACTION`], [`DENSE_FEATURE_POINTS`]; otherwise
    /// [`VOXEL_FRACTION`], [`MAX_FEATURE_POINTS`]): the default scale first.
    fn fine(self) -> &'static [bool] {
        match self {
            Density::Sparse => &[false],
            Density::Mid => &[false, true],
            Density::Dense => &[true],
        }
    }
}

/// How densely both clouds sample their surfaces ([`Density`]), by their points per occupied voxel
/// of the feature voxel of `fraction` (of the larger largest half-extent): a pass over each cloud
/// per occupancy tried, which stops once it has counted too many voxels. The target's side goes
/// through `memo` ([`TargetFeatures`]). Either cloud may be a stand-in ([`FeatureCloud`]): its own
/// points are counted, per voxel the stand-in occupies.
pub fn density<'s, 't>(
    source: impl Into<FeatureCloud<'s>>,
    target: impl Into<FeatureCloud<'t>>,
    memo: &TargetFeatures,
    fraction: f64,
) -> Density {
    density_of(&Pair::new(source.into(), target.into(), memo), memo, fraction)
}

/// [`density`] of two clouds as the global hypotheses see them.
fn density_of(pair: &Pair, memo: &TargetFeatures, fraction: f64) -> Density {
    let v = (fraction * pair.extent).max(f64::MIN_POSITIVE);
    let both = |occupancy, min_points| {
        pair.source.count >= min_points
            && pair.target.count >= min_points
            && occupied_at(pair.source, &pair.source_bounds, v, occupancy)
            && memo.occupied(pair.target, v, occupancy)
    };
    if both(DENSE_OCCUPANCY, DENSE_MIN_POINTS) {
        Density::Dense
    } else if both(MID_OCCUPANCY, MID_MIN_POINTS) {
        Density::Mid
    } else {
        Density::Sparse
    }
}

/// `cloud` has `occupancy` points per occupied voxel of size `v` (`bounds`: its points' bounds).
/// The voxels are those its [`FeatureCloud::points`] occupy; the points counted, all of its
/// [`FeatureCloud::count`].
fn occupied_at(cloud: FeatureCloud, bounds: &([f32; 3], [f32; 3]), v: f64, occupancy: usize) -> bool {
    voxel_downsample_at_most_in(cloud.points, bounds, v as f32, cloud.count / occupancy).is_some()
}

/// The two clouds of a feature voxel's search, with what its passes need of them, each computed
/// once: the source's bounds and the pair's larger half-extent (the target's through the memo).
struct Pair<'s, 't> {
    source: FeatureCloud<'s>,
    target: FeatureCloud<'t>,
    source_bounds: ([f32; 3], [f32; 3]),
    extent: f64,
}

impl<'s, 't> Pair<'s, 't> {
    fn new(source: FeatureCloud<'s>, target: FeatureCloud<'t>, memo: &TargetFeatures) -> Self {
        let source_bounds = source.points.bounds();
        let (lo, hi) = source_bounds;
        let extent = half_extent_of(lo, hi).max(memo.half_extent(target.points));
        Self { source, target, source_bounds, extent }
    }
}

/// A cloud as the global hypotheses see it ([`Matched::onto`]): its points, or for a large cloud a
/// finer voxelised copy of them standing in for them (the pipeline gives ICP's copy, at half the
/// final distance, where it holds at most half the points: [`standin`]), with how many
/// points the cloud itself has. The feature voxel's search voxelises the copy, each try a pass
/// over far fewer points; [`density`] counts the cloud's own points per voxel the copy occupies.
/// Voxelised again at the coarser feature voxel, the copy gives about the cloud's own voxel
/// centroids (a centroid of centroids, each weighted alike).
#[derive(Clone, Copy, Debug)]
pub struct FeatureCloud<'a> {
    /// The points that are voxelised at the feature voxel (or described as they are, when few).
    pub points: &'a PointCloud,
    /// How many points the cloud itself has (at least `points.len()`).
    pub count: usize,
}

impl<'a> From<&'a PointCloud> for FeatureCloud<'a> {
    fn from(cloud: &'a PointCloud) -> Self {
        Self { points: cloud, count: cloud.len() }
    }
}

/// A cloud voxelised at `voxel` stands in for `cloud` ([`FeatureCloud`]) when it has at most
/// `1 /` [`STANDIN_REDUCTION`] of its points and `voxel` is at most half the finest feature voxel
/// ([`DENSE_VOXEL_FRACTION`] of `extent`, the pair's larger half-extent, scaled like `fraction`
/// against [`VOXEL_FRACTION`]); otherwise the cloud stands for itself.
pub fn standin<'a>(
    cloud: &'a PointCloud,
    voxelised: &'a PointCloud,
    voxel: f64,
    extent: f64,
    fraction: f64,
) -> FeatureCloud<'a> {
    let finest = dense_fraction(fraction) * extent;
    if saves_enough(cloud.len(), voxelised.len()) && voxel > 0.0 && voxel <= 0.5 * finest * (1.0 + 1e-9) {
        FeatureCloud { points: voxelised, count: cloud.len() }
    } else {
        cloud.into()
    }
}

/// How many times fewer points a voxelised copy must have to stand in for a cloud ([`standin`]):
/// below that the passes it saves are few, and the protocol's clouds (voxelised for ICP they lose a
/// few of their points) are described from their own points.
pub const STANDIN_REDUCTION: usize = 2;

/// Whether a copy of `copy` points saves enough of a cloud's `points` to stand in for it
/// ([`STANDIN_REDUCTION`], [`standin`]).
pub fn saves_enough(points: usize, copy: usize) -> bool {
    copy.saturating_mul(STANDIN_REDUCTION) <= points
}

/// The feature voxel's starting fraction on a dense pair ([`DENSE_VOXEL_FRACTION`]), scaled like
/// `fraction` against [`VOXEL_FRACTION`].
fn dense_fraction(fraction: f64) -> f64 {
    fraction * DENSE_VOXEL_FRACTION / VOXEL_FRACTION
}

/// How a cloud fits the feature budget at one voxel size.
#[derive(Clone, Debug)]
enum Fit {
    /// It has at most the budget's points: it fits as it is.
    AsIs,
    /// Voxelised at that size it fits, as this cloud.
    Voxelised(PointCloud),
    /// It has more voxels than the budget at that size.
    No,
}

/// The search of [`feature_voxels`] at one scale (`fine`: the finer one), and each cloud
/// voxelised at the size found when the search had to voxelise it to see that it fits (`None` for
/// a cloud within the scale's point budget, which fits as it is, or when no size fitted within the
/// search's steps). A size that does not fit stops voxelising a cloud as soon as it has more voxels than
/// the budget. The target's side goes through `memo` ([`TargetFeatures`]).
fn feature_grid(
    pair: &Pair,
    memo: &TargetFeatures,
    fraction: f64,
    fine: bool,
) -> (f64, Option<PointCloud>, Option<PointCloud>) {
    let (source, target) = (pair.source.points, pair.target.points);
    let (fraction, cap) =
        if fine { (dense_fraction(fraction), DENSE_FEATURE_POINTS) } else { (fraction, MAX_FEATURE_POINTS) };
    let mut v = (fraction * pair.extent).max(f64::MIN_POSITIVE);
    for _ in 0..60 {
        // (a try that does not fit stops early)
        let fits_source = if source.len() > cap {
            voxel_downsample_at_most_in(source, &pair.source_bounds, v as f32, cap).map(Some)
        } else {
            Some(None)
        };
        if let Some(s) = fits_source {
            match memo.fit(target, v, cap) {
                Fit::AsIs => return (v, s, None),
                Fit::Voxelised(t) => return (v, s, Some(t)),
                Fit::No => {}
            }
        }
        v *= 1.25;
    }
    (v, None, None)
}

/// The target's side of the global hypotheses ([`Matched::onto`]), remembered so that
/// registrations onto the same target describe it once: its bounds, which feature voxel sizes it
/// fits (a pass over every point each), and its descriptors at the size last used. Only ever use
/// one with the same target cloud.
#[derive(Debug, Default)]
pub struct TargetFeatures {
    bounds: OnceLock<([f32; 3], [f32; 3])>,
    /// Per voxel size tried (its bits) and point budget, how the target fits it.
    fits: Mutex<Vec<(u64, usize, Fit)>>,
    /// Per voxel size (its bits) and occupancy, whether the target has that occupancy there
    /// ([`density`]).
    occupied: Mutex<Vec<(u64, usize, bool)>>,
    /// The target described at the voxel sizes (their bits) last used, at most one per scale.
    described: Mutex<Vec<(u64, Described)>>,
}

impl TargetFeatures {
    /// The bounds of `target` (computed once).
    fn bounds(&self, target: &PointCloud) -> &([f32; 3], [f32; 3]) {
        self.bounds.get_or_init(|| target.bounds())
    }

    /// The largest half-extent of `target`'s bounds.
    fn half_extent(&self, target: &PointCloud) -> f64 {
        let (lo, hi) = *self.bounds(target);
        half_extent_of(lo, hi)
    }

    /// How `target` fits the budget of `cap` points at voxel size `v` (computed once per size).
    fn fit(&self, target: &PointCloud, v: f64, cap: usize) -> Fit {
        let mut fits = self.fits.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, _, fit)) = fits.iter().find(|(bits, c, _)| *bits == v.to_bits() && *c == cap) {
            return fit.clone();
        }
        let fit = if target.len() <= cap {
            Fit::AsIs
        } else {
            match voxel_downsample_at_most_in(target, self.bounds(target), v as f32, cap) {
                Some(c) => Fit::Voxelised(c),
                None => Fit::No,
            }
        };
        fits.push((v.to_bits(), cap, fit.clone()));
        fit
    }

    /// Whether `target` has `occupancy` points per occupied voxel of size `v` ([`density`];
    /// computed once per size and occupancy).
    fn occupied(&self, target: FeatureCloud, v: f64, occupancy: usize) -> bool {
        let mut occupied = self.occupied.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, _, d)) = occupied.iter().find(|(bits, o, _)| *bits == v.to_bits() && *o == occupancy) {
            return *d;
        }
        let d = occupied_at(target, self.bounds(target.points), v, occupancy);
        occupied.push((v.to_bits(), occupancy, d));
        d
    }

    /// `target` described at `voxel` from its voxelised copy `voxelised` (`None`: from `target`
    /// itself), computed once per size (the sizes of the last two scales kept).
    fn described(&self, target: &PointCloud, voxel: f64, voxelised: Option<PointCloud>) -> Described {
        let mut described = self.described.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, d)) = described.iter().find(|(bits, _)| *bits == voxel.to_bits()) {
            return d.clone();
        }
        let d = match voxelised {
            Some(v) => describe_voxelised(v.points, voxel),
            None => describe(target, voxel),
        };
        if described.len() == KEPT_SCALES {
            described.remove(0);
        }
        described.push((voxel.to_bits(), d.clone()));
        d
    }
}

/// How many scales of the target's descriptors [`TargetFeatures`] keeps: both of a
/// [`Density::Mid`] pair.
const KEPT_SCALES: usize = 2;

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

/// Both clouds voxelised and described at each feature voxel of the pair ([`feature_voxels`]),
/// and their mutual descriptor matches: what RANSAC draws from. Built once per pair;
/// [`Matched::hypotheses`] can then draw more than once (the adaptive search asks for more
/// hypotheses when the first ones were not enough) without describing the clouds again.
#[derive(Clone, Debug)]
pub struct Matched {
    /// One per scale, the default one first (at least one).
    scales: Vec<Scale>,
}

/// Both clouds described at one feature voxel, and their matches.
#[derive(Clone, Debug)]
struct Scale {
    source: Described,
    target: Described,
    matches: Vec<(u32, u32)>,
    /// Every source point's nearest target descriptor (what [`Matched::translations`] votes with).
    nearest: Vec<(u32, u32)>,
    voxel: f64,
}

impl Scale {
    /// RANSAC's inlier distance, which is also the radius of [`Matched::translations`]'s clusters.
    fn inlier_distance(&self) -> f64 {
        INLIER_VOXELS * self.voxel
    }
}

impl Matched {
    /// Describes `source` and `target` (both in one unit, any relative pose) at the feature voxel
    /// of `voxel_fraction` and matches their descriptors.
    pub fn new(source: &PointCloud, target: &PointCloud, voxel_fraction: f64) -> Self {
        Self::onto(source, target, &TargetFeatures::default(), voxel_fraction)
    }

    /// [`Matched::new`], with the target's side taken from `memo` where an earlier pair onto the
    /// same `target` left it (the same result either way). Either cloud may be a stand-in
    /// ([`FeatureCloud`], [`standin`]); `memo` must always be given the target the same way.
    pub fn onto<'s, 't>(
        source: impl Into<FeatureCloud<'s>>,
        target: impl Into<FeatureCloud<'t>>,
        memo: &TargetFeatures,
        voxel_fraction: f64,
    ) -> Self {
        Self::onto_at(source, target, memo, voxel_fraction, true)
    }

    /// [`Matched::onto`]; without `finer`, a [`Density::Mid`] pair is described at the default
    /// scale only.
    pub fn onto_at<'s, 't>(
        source: impl Into<FeatureCloud<'s>>,
        target: impl Into<FeatureCloud<'t>>,
        memo: &TargetFeatures,
        voxel_fraction: f64,
        finer: bool,
    ) -> Self {
        let pair = Pair::new(source.into(), target.into(), memo);
        let density = match density_of(&pair, memo, voxel_fraction) {
            Density::Mid if !finer => Density::Sparse,
            d => d,
        };
        let scale = |fine: bool| {
            let (voxel, source_v, target_v) = feature_grid(&pair, memo, voxel_fraction, fine);
            // the search's voxelised clouds where it made them (the same as describing anew)
            let source = match source_v {
                Some(v) => describe_voxelised(v.points, voxel),
                None => describe(pair.source.points, voxel),
            };
            let target = memo.described(pair.target.points, voxel, target_v);
            let (nearest, matches) = matching::nearest_and_mutual(&source.descriptors, &target.descriptors, 30);
            Scale { source, target, matches, nearest, voxel }
        };
        Self { scales: density.fine().iter().map(|&fine| scale(fine)).collect() }
    }

    /// Ranked rigid motions taking the source onto the target, best first (`params.hypotheses` at
    /// most per scale, the default scale's first, less a finer scale's in the same basin as one
    /// before it); `params.voxel_fraction` is the one given to [`Matched::new`]); empty when the
    /// descriptors gave fewer than three correspondences. Deterministic for `params.seed`.
    pub fn hypotheses(&self, params: &GlobalParams) -> Vec<Hypothesis> {
        let mut all: Vec<Hypothesis> = Vec::new();
        // basins judged as the default scale's RANSAC judges them
        let first = &self.scales[0];
        let center = centroid_of(&first.source.points).map(|v| v as f32);
        let d = first.inlier_distance();
        for scale in &self.scales {
            let rp = RansacParams {
                max_iterations: params.max_iterations,
                confidence: 0.999,
                inlier_distance: scale.inlier_distance(),
                edge_ratio: 0.9,
                hypotheses: params.hypotheses,
                seed: params.seed,
            };
            let drawn = ransac::ransac(&scale.source.points, &scale.target.points, &scale.matches, &rp);
            let before = all.len();
            for h in drawn {
                let seen = |a: &Hypothesis| ransac::same_basin(&a.T_target_source, &h.T_target_source, &center, d);
                if !all[..before].iter().any(seen) {
                    all.push(h);
                }
            }
        }
        all
    }

    /// Up to `count` translations the matches agree on for the rotation `r`, densest first
    /// ([`translation::modes`]), with how many agree on each: one per alike part of a row. The
    /// matches of the finest scale vote.
    pub fn translations(&self, r: &nalgebra::Matrix3<f64>, count: usize) -> Vec<(nalgebra::Vector3<f64>, usize)> {
        let s = self.finest();
        translation::modes(&s.source.points, &s.target.points, &s.nearest, r, s.inlier_distance(), count)
    }

    /// The radius of [`Matched::translations`]'s clusters (the finest scale's RANSAC inlier
    /// distance).
    pub fn inlier_distance(&self) -> f64 {
        self.finest().inlier_distance()
    }

    /// The scale described finest (the last).
    fn finest(&self) -> &Scale {
        self.scales.last().expect("a pair is described at one scale at least")
    }
}

/// RANSAC's inlier distance, in feature voxels.
const INLIER_VOXELS: f64 = 1.5;

/// Ranked rigid motions taking `source` onto `target` (both in one unit, any relative pose), best
/// first; empty when the descriptors give fewer than three correspondences. Deterministic for
/// `params.seed`. ([`Matched::new`], then [`Matched::hypotheses`].)
pub fn hypotheses(source: &PointCloud, target: &PointCloud, params: &GlobalParams) -> Vec<Hypothesis> {
    Matched::new(source, target, params.voxel_fraction).hypotheses(params)
}
