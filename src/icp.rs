//! ICP refinement: point-to-point and point-to-plane.

use crate::spatial::KdIndex;
use crate::{normals, rigid, transform};
use nalgebra::{Matrix4, Matrix6, Rotation3, SymmetricEigen, Vector3, Vector6};
use std::sync::OnceLock;

/// Which ICP to run after the network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "IcpKind"))]
pub enum IcpKind {
    /// No refinement: the network's transform is the answer.
    Off,
    /// Point-to-point ICP (Besl-McKay, closed-form Kabsch each iteration).
    Point,
    /// Point-to-plane ICP (linearised, target normals), the default.
    #[default]
    Plane,
}

/// How ICP weighs the answer's pairs (`Options::icp_loss`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "IcpLoss"))]
pub enum IcpLoss {
    /// Every pair within the distance alike (least squares), throughout.
    Squared,
    /// Least squares in the search, then each pair weighed by Tukey's biweight of its residual
    /// ([`IcpParams::robust`]): in every stage of the refinement of the caller's
    /// `initialTransform`, and in one more refinement of the search's answer, at the scale of
    /// the pairs' spread and by a graduated descent of fixed scales (a half to a sixteenth of the
    /// distance) from the answer and from `initialTransform`, whose pose replaces the answer only
    /// where clearly more of the source lies on the target's surfaces (to within a few times the
    /// residuals' noise) than under it. A surface that changed between the scans (erosion,
    /// construction, a moved object, a bent part) no longer pulls the answer; the surfaces that
    /// stayed hold it. Where nothing changed the answer is, but for a few pairs in a hundred,
    /// least squares'. The default.
    #[default]
    Robust,
}

impl IcpKind {
    /// The kind of a short search run (a probe, a screen of starts): this one, or point-to-point
    /// when refinement is off, since a search run that does not move finds nothing.
    pub fn or_point(self) -> IcpKind {
        if self == IcpKind::Off {
            IcpKind::Point
        } else {
            self
        }
    }
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
    /// Stop when the change of fitness between iterations is below this ... (an absolute
    /// difference, as Open3D's `relative_fitness` is, despite the name)
    pub relative_fitness: f64,
    /// ... and the change of inlier RMSE is below this (likewise absolute).
    pub relative_rmse: f64,
    /// Levenberg-Marquardt damping of the point-to-plane step, as a fraction of the largest
    /// eigenvalue of its normal matrix: each step solves `(AᵀA + damping · λmax · I) x = Aᵀb`, so a
    /// motion the pairs pin only weakly (eigenvalue well below `damping · λmax`) moves a small part
    /// of the way each iteration instead of all of it, while well-pinned ones move as before.
    /// `0` (what [`IcpParams::new`] sets) is the plain Gauss-Newton step. Point-to-point ICP
    /// ignores it.
    pub damping: f64,
    /// Stop a run that is going nowhere ([`GiveUp`]); `None` (what [`IcpParams::new`] sets)
    /// runs to convergence or the cap.
    pub give_up: Option<GiveUp>,
    /// Weigh each pair by Tukey's biweight of its residual (point-to-plane: along the normal;
    /// point-to-point: the distance), at [`TUKEY_C`] times the pairs' robust spread (1.4826 times
    /// their median absolute residual): pairs far beyond the spread of the rest (a surface that
    /// changed between the scans) no longer pull the step. `false` (what [`IcpParams::new`] sets):
    /// every pair within the distance counts alike.
    pub robust: bool,
    /// With [`IcpParams::robust`]: the biweight's scale (the residual whose weight is zero), fixed,
    /// instead of [`TUKEY_C`] robust spreads of the pairs' residuals. A graduated descent of
    /// fixed scales leaves out a changed surface that the spread alone counts in, when it moved
    /// the pose enough to spread every residual. `None` (what [`IcpParams::new`] sets): the
    /// spread's.
    pub robust_scale: Option<f64>,
}

/// Tukey's biweight constant of [`IcpParams::robust`], in robust spreads: 95% efficiency on
/// Gaussian residuals.
pub const TUKEY_C: f64 = 4.685;

/// When an ICP run stops early for fitting too little: after at least `after` iterations, at the
/// first whose fitness is below `below` (the run is then not `converged`). For a search run whose
/// result counts only if it fits nearly as well as a known pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GiveUp {
    /// Iterations before the test applies.
    pub after: u32,
    /// The fitness (at the run's max correspondence distance) below which the run stops.
    pub below: f64,
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

impl IcpParams {
    /// Parameters for the given ICP kind and max correspondence distance, with Open3D's
    /// convergence defaults: at most 30 iterations, stopping when the changes of fitness and of
    /// inlier RMSE between iterations both fall below 1e-6; undamped steps.
    pub fn new(kind: IcpKind, max_correspondence_distance: f64) -> Self {
        Self {
            kind,
            max_correspondence_distance,
            max_iterations: 30,
            relative_fitness: 1e-6,
            relative_rmse: 1e-6,
            damping: 0.0,
            give_up: None,
            robust: false,
            robust_scale: None,
        }
    }
}

/// Tukey's biweights of `residuals` ([`IcpParams::robust`]) at the scale `fixed`, or without one
/// at [`TUKEY_C`] robust spreads; `None` when that scale is zero or not finite (every pair
/// alike: the plain step).
fn tukey_weights(residuals: &[f64], fixed: Option<f64>) -> Option<Vec<f64>> {
    if residuals.is_empty() {
        return None;
    }
    let c = match fixed {
        Some(c) => c,
        None => {
            let mut abs: Vec<f64> = residuals.iter().map(|r| r.abs()).collect();
            TUKEY_C * 1.4826 * crate::stats::median(&mut abs)?
        }
    };
    if !(c.is_finite() && c > 0.0) {
        return None;
    }
    Some(
        residuals
            .iter()
            .map(|r| {
                let u = r / c;
                if u.abs() < 1.0 {
                    (1.0 - u * u).powi(2)
                } else {
                    0.0
                }
            })
            .collect(),
    )
}

/// Neighbours used for the target normals of point-to-plane ICP (the point itself and the
/// neighbours its searches start from, [`crate::spatial::neighbourhood::NEIGHBOURS`]: one search
/// finds both).
pub const NORMAL_NEIGHBOURS: usize = 20;
const _: () = assert!(NORMAL_NEIGHBOURS == crate::spatial::neighbourhood::NEIGHBOURS + 1);

/// Eigenvalues of the point-to-plane normal matrix below this fraction of the largest are
/// treated as zero (no motion along those directions): a planar or otherwise degenerate target
/// leaves some motions unconstrained, and they are left alone rather than guessed.
pub const PLANE_RANK_TOL: f64 = 1e-9;

/// A target prepared once (kd-tree, normals) and reused by several ICP runs.
///
/// Normals are estimated point by point as point-to-plane ICP first pairs a source point with
/// them, and kept: on a large target only the points that take part in a correspondence (a few
/// per sampled source point) ever need one, so their cost follows the source sample, not the
/// target's size. A normal's value does not depend on when it is estimated.
pub struct IcpTarget {
    /// Unique per target built: what [`Partners`]' floors are about (never 0).
    id: u64,
    points: Vec<[f32; 3]>,
    index: KdIndex,
    normals: Vec<OnceLock<[f32; 3]>>,
    /// Coarser copies for runs at wide distances ([`IcpTarget::with_levels`]), if any.
    levels: Option<Levels>,
}

/// Points a target needs before it gets coarser copies ([`IcpTarget::with_levels`]): below this
/// the searches of the wide stages are cheap already.
pub const LEVELS_MIN_POINTS: usize = 8192;

/// How many coarser copies a target may have: voxels of 2 and 4 times its own.
const LEVELS: usize = 2;

/// A run at max correspondence distance `D` uses the coarsest copy whose voxel is at most this
/// fraction of `D`.
const LEVEL_VOXEL_FRACTION: f64 = 0.5;

/// The coarser copies of a target voxelised at `voxel`: copy `k` (from 1) is its points
/// voxelised at `voxel * 2^k`, built when a run first needs it, and kept only when it has at most
/// `1 / 2^k` of the target's points (else the coarser voxel saves nothing and the run uses the
/// target itself).
struct Levels {
    voxel: f64,
    coarser: [OnceLock<Option<Box<IcpTarget>>>; LEVELS],
}

impl std::fmt::Debug for IcpTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("IcpTarget")
            .field("points", &self.points.len())
            .field("normals", &self.normals.iter().filter(|n| n.get().is_some()).count())
            .finish()
    }
}

/// Each source point's nearest target point in the last correspondence pass of an
/// [`IcpTarget::align_warm`] or [`IcpTarget::evaluate_warm`] (empty at first): the next pass over
/// the same source points starts its searches there. It is only a hint: a pass finds the same
/// partners with or without it (among points at exactly equal distance, possibly another), and
/// one made for other source points is ignored where its length differs.
///
/// It also keeps each point's floor (`Floor`): how far the other target points were from it. A
/// later pass skips the search of a point that has not moved far enough since to change its answer
/// (the same partner, or still none), with the same result; the floors are forgotten when the
/// partners are used with another target.
#[derive(Clone, Debug, Default)]
pub struct Partners {
    prev: Vec<u32>,
    floors: Vec<Floor>,
    /// The [`IcpTarget::id`] the floors are about.
    floors_of: u64,
}

impl Partners {
    /// Runs `pass` on fresh scratch buffers that start from these partners, and keeps the
    /// partners `pass` leaves there.
    fn lend<T>(&mut self, pass: impl FnOnce(&mut Scratch) -> T) -> T {
        let mut scratch = Scratch {
            prev: std::mem::take(&mut self.prev),
            floors: std::mem::take(&mut self.floors),
            floors_of: self.floors_of,
            ..Scratch::default()
        };
        let out = pass(&mut scratch);
        (self.prev, self.floors, self.floors_of) = (scratch.prev, scratch.floors, scratch.floors_of);
        out
    }
}

/// What a search told about a source point's surroundings
/// ([`crate::spatial::KdIndex::nearest_within_and_floor`]): no target point other than its
/// partner (every target point, when it had none) is within `reach` of `at`, the moved point
/// then. Until the point moves farther than the gap between its partner and `reach`, its search
/// would give the same answer, and is skipped: in late ICP iterations points move by a small
/// fraction of the point spacing, and the many points of a partial scan without a partner stay
/// far from the target.
#[derive(Clone, Copy, Debug, Default)]
struct Floor {
    /// The distance, already lowered by [`FLOOR_MARGIN`] (0: nothing known).
    reach: f64,
    at: [f32; 3],
}

impl Floor {
    /// The search's answer for the point now at `q` (target frame), when this floor shows that
    /// it cannot have changed since: `Some(prev)` when the point had no partner (`prev` is
    /// `None`) and is still beyond `skip_beyond` of every target point, or when its partner
    /// `prev` (an index into `points`) is still strictly the nearest and within `search2` (the
    /// tree's squared bound); `Some(None)` when that partner is the nearest but now beyond the
    /// bound (the floor is then forgotten); `None` when the point must be searched.
    fn answer(
        &mut self,
        q: &[f32; 3],
        prev: Option<usize>,
        points: &[[f32; 3]],
        search2: f32,
        skip_beyond: f64,
    ) -> Option<Option<usize>> {
        if self.reach <= 0.0 {
            return None;
        }
        let distance = |p: &[f32; 3]| (0..3).map(|a| (q[a] as f64 - p[a] as f64).powi(2)).sum::<f64>().sqrt();
        // every target point but the partner is at least this far from `q`
        let others = self.reach - distance(&self.at);
        let Some(j) = prev else {
            return (others > skip_beyond).then_some(None);
        };
        let partner = points[j];
        if distance(&partner) * (1.0 + FLOOR_MARGIN) >= others {
            return None;
        }
        // still strictly the nearest: the search finds it when within its bound
        if crate::spatial::dist2(&partner, q) < search2 {
            Some(Some(j))
        } else {
            *self = Floor::default();
            Some(None)
        }
    }
}

/// Relative margin by which a [`Floor`] is lowered, and the partner's distance and the search
/// radius raised, before a search is skipped: the tree computes its bounds in `f32` (a few units
/// in the last place, about 1e-7), so a skipped search is always one that would have given the
/// same answer.
const FLOOR_MARGIN: f64 = 1e-5;

/// Buffers reused across the iterations of one run.
#[derive(Default)]
struct Scratch {
    /// Inlier pairs: the moved source point and its target partner's index.
    moved: Vec<[f64; 3]>,
    target: Vec<usize>,
    /// Per source point, its partner in the previous pass (`u32::MAX`: none): warm-starts the
    /// nearest-neighbour search.
    prev: Vec<u32>,
    /// Per source point, its [`Floor`] (about the target `floors_of`).
    floors: Vec<Floor>,
    floors_of: u64,
    /// Contiguous copies for [`rigid::kabsch`].
    target_xyz: Vec<[f64; 3]>,
}

/// Where the [`IcpTarget::id`]s come from.
static NEXT_TARGET_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl IcpTarget {
    /// Builds the kd-tree of the target; with `with_normals`, every normal too.
    ///
    /// Otherwise each normal is estimated when a point-to-plane run first needs it (the same
    /// value either way: [`normals::normal_at`] with [`NORMAL_NEIGHBOURS`] neighbours).
    pub fn new(points: &[[f32; 3]], with_normals: bool) -> Self {
        let target = Self {
            id: NEXT_TARGET_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            points: points.to_vec(),
            index: KdIndex::new(points),
            normals: (0..points.len()).map(|_| OnceLock::new()).collect(),
            levels: None,
        };
        if with_normals {
            target.normals();
        }
        target
    }

    /// A target with caller-supplied normals (one per point, any orientation; they are
    /// normalised, and a zero or non-finite one is replaced by [`normals::DEFAULT_NORMAL`]).
    /// If the counts differ the normals are estimated instead.
    pub fn with_normals(points: &[[f32; 3]], normals: &[[f32; 3]]) -> Self {
        let target = Self::new(points, false);
        if normals.len() == points.len() {
            for (cell, n) in target.normals.iter().zip(normals) {
                let len = (n[0] as f64).hypot(n[1] as f64).hypot(n[2] as f64);
                let clean = if len > 0.0 && len.is_finite() {
                    n.map(|v| (v as f64 / len) as f32)
                } else {
                    normals::DEFAULT_NORMAL
                };
                let _ = cell.set(clean);
            }
        }
        target
    }

    /// A target whose points were voxelised at `voxel` (a grid's centroids, as
    /// [`crate::sampling::voxel_downsample`] gives them), with normals estimated as runs need
    /// them. With at least [`LEVELS_MIN_POINTS`] points it also has coarser copies, voxelised
    /// at 2 and 4 times `voxel`, for the runs at wide distances: a search costs about the number
    /// of target points within the distance of its query, and a run at `4 voxel` or more pairs
    /// its points as well with fewer target points. [`IcpTarget::align`] and
    /// [`IcpTarget::align_warm`] run on the coarsest copy whose voxel is at most half their max
    /// correspondence distance; the other methods always use every point. The copies hold at
    /// most 3/4 of the points again ([`crate::limits::icp_copies_fit`] tells whether they fit).
    pub fn with_levels(points: &[[f32; 3]], voxel: f64) -> Self {
        let mut target = Self::new(points, false);
        if points.len() >= LEVELS_MIN_POINTS && voxel.is_finite() && voxel > 0.0 {
            target.levels = Some(Levels { voxel, coarser: Default::default() });
        }
        target
    }

    /// The copy a run at max correspondence distance `distance` searches ([`IcpTarget::with_levels`]).
    fn for_distance(&self, distance: f64) -> &IcpTarget {
        let Some(levels) = &self.levels else { return self };
        for k in (1..=LEVELS).rev() {
            let voxel = levels.voxel * (1u32 << k) as f64;
            if voxel > distance * LEVEL_VOXEL_FRACTION {
                continue;
            }
            let coarser = levels.coarser[k - 1].get_or_init(|| {
                let points = crate::sampling::voxel_downsample_points(&self.points, voxel as f32);
                (points.len() <= self.points.len() >> k).then(|| Box::new(IcpTarget::new(&points, false)))
            });
            if let Some(coarser) = coarser {
                return coarser;
            }
        }
        self
    }

    /// The target points.
    pub fn points(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// Every target normal (one per point), estimating those not yet estimated.
    pub fn normals(&self) -> Vec<[f32; 3]> {
        (0..self.points.len()).map(|j| self.normal(j)).collect()
    }

    /// How many target normals have been estimated (or given) so far.
    pub fn normals_estimated(&self) -> usize {
        self.normals.iter().filter(|n| n.get().is_some()).count()
    }

    /// The unit normal of target point `j` (an index into [`IcpTarget::points`]), estimated now
    /// if it was not yet, as [`IcpTarget::normals`] estimates it.
    ///
    /// # Panics
    /// If `j` is not below the number of points.
    pub fn normal(&self, j: usize) -> [f32; 3] {
        *self.normals[j].get_or_init(|| normals::normal_at(&self.points, &self.index, j, NORMAL_NEIGHBOURS))
    }

    /// Runs ICP from `init` (`T_target_source`).
    ///
    /// Each iteration: move the source by the current transform, pair every moved point with
    /// its nearest target point, keep pairs closer than `max_correspondence_distance`
    /// (strictly), solve an update on them and compose it on the left (`T <- dT * T`).
    /// * [`IcpKind::Point`]: the closed-form [`rigid::kabsch`] fit of the inlier pairs.
    /// * [`IcpKind::Plane`]: minimises `sum ((R p + t - q) . n_q)^2` linearised about the
    ///   inliers' centroid (small-angle `R ~ I + [w]x`), a 6x6 least-squares problem in `f64`
    ///   solved by a truncated eigen-decomposition (directions with eigenvalue below
    ///   [`PLANE_RANK_TOL`] times the largest are not moved, and each kept one is damped by
    ///   [`IcpParams::damping`]); the rotation is then built exactly
    ///   from `w` (axis-angle), and the composed rotation re-orthonormalised every iteration.
    /// * Stops as Open3D's `ICPConvergenceCriteria` does: after an update, when the change of
    ///   fitness is below `relative_fitness` **and** the change of inlier RMSE below
    ///   `relative_rmse` (Open3D compares absolute differences of the two figures, and so does
    ///   this), or after `max_iterations` updates; with [`IcpParams::give_up`], also after an
    ///   update that leaves the fitness below its bound (not converged).
    /// * [`IcpKind::Off`], `max_iterations == 0`, or no inlier pair at `init`: returns `init`
    ///   with its fitness and RMSE, 0 iterations, `converged = false`. If a step would lose every
    ///   inlier, or is not finite, it is discarded and the run stops (`converged = false`) with
    ///   the last transform that had inliers.
    ///
    /// The result's `fitness` and `inlier_rmse` are those of the returned transform.
    pub fn align(&self, source: &[[f32; 3]], init: &Matrix4<f64>, params: &IcpParams) -> IcpResult {
        self.align_warm(source, init, params, &mut Partners::default())
    }

    /// [`IcpTarget::align`], starting each source point's nearest-neighbour search from its
    /// partner in `partners` (those of an earlier pass over the same `source`: the previous
    /// stage of a coarse-to-fine run) and leaving the last pass's partners there. The result is
    /// that of [`IcpTarget::align`]; only the searches are cheaper.
    pub fn align_warm(
        &self,
        source: &[[f32; 3]],
        init: &Matrix4<f64>,
        params: &IcpParams,
        partners: &mut Partners,
    ) -> IcpResult {
        let target = self.for_distance(params.max_correspondence_distance);
        partners.lend(|scratch| target.align_scratch(source, init, params, scratch))
    }

    /// [`IcpTarget::align`] on the given scratch buffers.
    fn align_scratch(
        &self,
        source: &[[f32; 3]],
        init: &Matrix4<f64>,
        params: &IcpParams,
        scratch: &mut Scratch,
    ) -> IcpResult {
        let d = params.max_correspondence_distance;
        let (mut fitness, mut rmse) = self.correspond(source, init, d, scratch);
        let mut result =
            IcpResult { T_target_source: *init, fitness, inlier_rmse: rmse, iterations: 0, converged: false };
        if params.kind == IcpKind::Off || scratch.moved.is_empty() {
            return result;
        }
        let mut t = *init;
        for it in 1..=params.max_iterations {
            // a cancelled registration stops here (`crate::cancel`): its answer is not returned
            if crate::cancel::cancelled() {
                break;
            }
            let update = match params.kind {
                IcpKind::Plane => self.plane_update(scratch, params),
                _ => self.point_update(scratch, params),
            };
            let Some(update) = update else { break };
            let next = compose_rigid(&update, &t);
            if next.iter().any(|v| !v.is_finite()) {
                break;
            }
            let (f, r) = self.correspond(source, &next, d, scratch);
            result.iterations = it;
            if scratch.moved.is_empty() {
                // Every pair lost: keep the last transform that had some.
                break;
            }
            t = next;
            result.T_target_source = t;
            let done = (f - fitness).abs() < params.relative_fitness && (r - rmse).abs() < params.relative_rmse;
            fitness = f;
            rmse = r;
            result.fitness = f;
            result.inlier_rmse = r;
            if done {
                result.converged = true;
                break;
            }
            if params.give_up.is_some_and(|g| it >= g.after && f < g.below) {
                break;
            }
        }
        result
    }

    /// Fitness and inlier RMSE of `source` under `T_target_source` at `max_distance`
    /// (the definitions of [`IcpResult`]), without iterating.
    ///
    /// `fitness` = (source points whose nearest target point is closer than `max_distance`) /
    /// (all source points); `inlier_rmse` = the RMS of those distances (0 when there are none).
    /// An empty source or target, or a `max_distance` that is not positive, gives `(0, 0)`.
    pub fn evaluate(&self, source: &[[f32; 3]], t: &Matrix4<f64>, max_distance: f64) -> (f64, f64) {
        self.correspond(source, t, max_distance, &mut Scratch::default())
    }

    /// [`IcpTarget::evaluate`], warm-started from `partners` like [`IcpTarget::align_warm`]
    /// (same result, cheaper searches), leaving this pass's partners there.
    pub fn evaluate_warm(
        &self,
        source: &[[f32; 3]],
        t: &Matrix4<f64>,
        max_distance: f64,
        partners: &mut Partners,
    ) -> (f64, f64) {
        partners.lend(|scratch| self.correspond(source, t, max_distance, scratch))
    }

    /// The residuals (absolute, along the target point's normal) of the points of `source`
    /// under `T_target_source` whose nearest target point lies within `max_distance`, in the
    /// source's order: how far the source lies off the target's surfaces, however sparsely the
    /// target samples them (the distance to the nearest point counts the sampling too).
    pub fn plane_residuals(&self, source: &[[f32; 3]], t: &Matrix4<f64>, max_distance: f64) -> Vec<f64> {
        let mut scratch = Scratch::default();
        self.correspond(source, t, max_distance, &mut scratch);
        let along = |p: &[f64; 3], j: usize| {
            let (q, n) = (self.points[j], self.normal(j));
            (0..3).map(|a| (q[a] as f64 - p[a]) * n[a] as f64).sum::<f64>().abs()
        };
        scratch.moved.iter().zip(&scratch.target).map(|(p, &j)| along(p, j)).collect()
    }

    /// One correspondence pass: fills `scratch` with the inlier pairs and returns
    /// `(fitness, inlier_rmse)`.
    fn correspond(
        &self,
        source: &[[f32; 3]],
        t: &Matrix4<f64>,
        max_distance: f64,
        scratch: &mut Scratch,
    ) -> (f64, f64) {
        scratch.moved.clear();
        scratch.target.clear();
        if source.is_empty() || self.index.is_empty() || max_distance.is_nan() || max_distance <= 0.0 {
            return (0.0, 0.0);
        }
        let max2 = max_distance * max_distance;
        // The tree works in f32: search a hair wider, then decide in f64.
        let search2 = (max2 * (1.0 + 1e-5)) as f32;
        let search2 = if search2.is_finite() { search2 } else { f32::INFINITY };
        let r = transform::rotation(t);
        let tr = transform::translation(t);
        // partners found in another target (a coarser copy) say nothing about this one
        if scratch.prev.len() != source.len() || scratch.floors_of != self.id {
            scratch.prev.clear();
            scratch.prev.resize(source.len(), u32::MAX);
        }
        if scratch.floors.len() != source.len() || scratch.floors_of != self.id {
            scratch.floors.clear();
            scratch.floors.resize(source.len(), Floor::default());
            scratch.floors_of = self.id;
        }
        // a point whose floor lies beyond this distance would find no partner
        let skip_beyond = (search2 as f64).sqrt() * (1.0 + FLOOR_MARGIN);
        let mut sum2 = 0.0f64;
        for ((s, prev), floor) in source.iter().zip(scratch.prev.iter_mut()).zip(scratch.floors.iter_mut()) {
            let p = r * Vector3::new(s[0] as f64, s[1] as f64, s[2] as f64) + tr;
            let q32 = [p.x as f32, p.y as f32, p.z as f32];
            let prev_partner = (*prev != u32::MAX).then_some(*prev as usize);
            let partner = match floor.answer(&q32, prev_partner, &self.points, search2, skip_beyond) {
                Some(unchanged) => unchanged,
                None => {
                    let (found, f) = self.index.nearest_within_and_floor(&q32, search2, prev_partner);
                    *floor = Floor { reach: (f as f64).sqrt() * (1.0 - FLOOR_MARGIN), at: q32 };
                    found.map(|(j, _)| j)
                }
            };
            let Some(j) = partner else {
                *prev = u32::MAX;
                continue;
            };
            *prev = j as u32;
            let q = self.points[j];
            let d2 = (p.x - q[0] as f64).powi(2) + (p.y - q[1] as f64).powi(2) + (p.z - q[2] as f64).powi(2);
            if d2 < max2 {
                sum2 += d2;
                scratch.moved.push([p.x, p.y, p.z]);
                scratch.target.push(j);
            }
        }
        let inliers = scratch.moved.len();
        if inliers == 0 {
            return (0.0, 0.0);
        }
        (inliers as f64 / source.len() as f64, (sum2 / inliers as f64).sqrt())
    }

    /// The distance from target point `j` to its nearest other target point (infinite when it
    /// has none): the cloud's spacing there.
    pub(crate) fn spacing_at(&self, j: usize) -> f64 {
        let mut out = Vec::with_capacity(2);
        self.index.knn_into(&self.points[j], 2, &mut out);
        out.iter().find(|(i, _)| *i != j).map_or(f64::INFINITY, |(_, d2)| (*d2 as f64).sqrt())
    }

    /// The target's spacing: the median, over up to `samples` of its points spread evenly, of
    /// the distance to the `k`th nearest other point (a point repeated counts as a neighbour at
    /// 0); infinite for a target of `k` points or fewer.
    pub(crate) fn median_reach(&self, k: usize, samples: usize) -> f64 {
        if self.points.len() <= k || samples == 0 {
            return f64::INFINITY;
        }
        let mut out = Vec::with_capacity(k + 1);
        let mut reach: Vec<f64> = crate::refine::even_sample(&self.points, samples)
            .iter()
            .map(|q| {
                // the point itself first, at 0
                self.index.knn_into(q, k + 1, &mut out);
                out.last().map_or(f64::INFINITY, |&(_, d2)| (d2 as f64).sqrt())
            })
            .collect();
        crate::stats::median(&mut reach).unwrap_or(f64::INFINITY)
    }

    /// The target point nearest to `q` (target frame) if it is closer than `max_distance`
    /// (strictly): its index into [`IcpTarget::points`].
    // one copy, not one per caller (the confidence's probes, the walls: none on ICP's own path),
    // for the wasm engine's size
    #[inline(never)]
    pub fn nearest_within(&self, q: &[f32; 3], max_distance: f64) -> Option<usize> {
        let max2 = max_distance * max_distance;
        let search2 = (max2 * (1.0 + 1e-5)) as f32;
        let (j, _) = self.index.nearest_within(q, search2, None)?;
        let p = self.points[j];
        let d2: f64 = (0..3).map(|a| (q[a] as f64 - p[a] as f64).powi(2)).sum();
        (d2 < max2).then_some(j)
    }

    /// Point-to-point update: Kabsch on the current inlier pairs.
    fn point_update(&self, scratch: &mut Scratch, params: &IcpParams) -> Option<Matrix4<f64>> {
        scratch.target_xyz.clear();
        scratch.target_xyz.extend(scratch.target.iter().map(|&j| self.points[j].map(|v| v as f64)));
        let weights = params
            .robust
            .then(|| {
                let residuals: Vec<f64> = scratch
                    .moved
                    .iter()
                    .zip(&scratch.target_xyz)
                    .map(|(p, q)| (Vector3::from(*q) - Vector3::from(*p)).norm())
                    .collect();
                tukey_weights(&residuals, params.robust_scale)
            })
            .flatten();
        Some(rigid::kabsch(&scratch.moved, &scratch.target_xyz, weights.as_deref()))
    }

    /// Point-to-plane update on the current inlier pairs, damped by `params.damping` (see
    /// [`IcpTarget::align`]).
    fn plane_update(&self, scratch: &Scratch, params: &IcpParams) -> Option<Matrix4<f64>> {
        let n = scratch.moved.len();
        if n == 0 {
            return None;
        }
        let along_normal = |p: &[f64; 3], j: usize| {
            let nq = Vector3::from(self.normal(j).map(|v| v as f64));
            (Vector3::from(self.points[j].map(|v| v as f64)) - Vector3::from(*p)).dot(&nq)
        };
        let weights = params
            .robust
            .then(|| {
                let residuals: Vec<f64> =
                    scratch.moved.iter().zip(&scratch.target).map(|(p, &j)| along_normal(p, j)).collect();
                tukey_weights(&residuals, params.robust_scale)
            })
            .flatten();
        // Linearise about the centroid of the moved source: better conditioned far from the
        // origin, and the rotation part is then about the data, not about (0, 0, 0).
        let mut c = Vector3::zeros();
        for p in &scratch.moved {
            c += Vector3::from(*p);
        }
        c /= n as f64;
        let mut ata = Matrix6::<f64>::zeros();
        let mut atb = Vector6::<f64>::zeros();
        for (i, (p, &j)) in scratch.moved.iter().zip(&scratch.target).enumerate() {
            let w = weights.as_ref().map_or(1.0, |w| w[i]);
            if w == 0.0 {
                continue;
            }
            let p = Vector3::from(*p) - c;
            let q = Vector3::from(self.points[j].map(|v| v as f64)) - c;
            let nq = Vector3::from(self.normal(j).map(|v| v as f64));
            let pxn = p.cross(&nq);
            let sw = w.sqrt();
            let a = Vector6::new(pxn.x, pxn.y, pxn.z, nq.x, nq.y, nq.z) * sw;
            let b = (q - p).dot(&nq) * sw;
            // Upper triangle only; mirrored below.
            for r in 0..6 {
                let ar = a[r];
                for s in r..6 {
                    ata[(r, s)] += ar * a[s];
                }
                atb[r] += ar * b;
            }
        }
        for r in 0..6 {
            for s in 0..r {
                ata[(r, s)] = ata[(s, r)];
            }
        }
        if !ata.iter().chain(atb.iter()).all(|v| v.is_finite()) {
            return None;
        }
        let scale = ata.abs().max();
        if scale.is_nan() || scale <= 0.0 {
            return None;
        }
        let eig = SymmetricEigen::new(ata / scale);
        let rhs = atb / scale;
        let lmax = eig.eigenvalues.max();
        if lmax.is_nan() || lmax <= 0.0 {
            return None;
        }
        let mut x = Vector6::<f64>::zeros();
        let damp = params.damping.max(0.0) * lmax;
        for k in 0..6 {
            let l = eig.eigenvalues[k];
            if l > PLANE_RANK_TOL * lmax {
                let v = eig.eigenvectors.column(k);
                x += v * (v.dot(&rhs) / (l + damp));
            }
        }
        let w = Vector3::new(x[0], x[1], x[2]);
        let dt = Vector3::new(x[3], x[4], x[5]);
        let r = Rotation3::new(w).into_inner();
        // x -> R (x - c) + c + dt
        let t = c + dt - r * c;
        let m = transform::from_rotation_translation(&r, &t);
        m.iter().all(|v| v.is_finite()).then_some(m)
    }
}

/// `a * b` for rigid transforms, with the rotation re-orthonormalised so that many
/// compositions do not drift.
fn compose_rigid(a: &Matrix4<f64>, b: &Matrix4<f64>) -> Matrix4<f64> {
    let m = a * b;
    let r = rigid::nearest_rotation(&transform::rotation(&m));
    transform::from_rotation_translation(&r, &transform::translation(&m))
}
