//! Multi-start refinement: coarse-to-fine ICP from several starting transforms, keeping the one
//! that fits best.
//!
//! The network, the initial transform and a centroid alignment fail on partly different pairs, and
//! once the target is prepared (kd-tree, normals) each extra start costs only its ICP iterations,
//! so the pipeline refines every start in [`crate::Options::starts`] against one shared
//! [`IcpTarget`] and keeps the best by [`choose`] ([`refine_best`]). Three things keep that cheap:
//! starts that meet are merged ([`MERGE_FRACTION`]), starts far behind the best after a coarse
//! stage are dropped ([`CUT_BEHIND`]), and large sources are compared on a sample of
//! [`SCREEN_POINTS`] points, only the winner being refined on more (at most [`REFINE_POINTS`]).
//! A single pose that may land nowhere new (the next of alike parts, a wall's other face) is
//! refined on every point only when a run on such a sample comes near the answer's fit
//! ([`refine_final_screened`]).

use crate::icp::{IcpKind, IcpParams, IcpTarget, Partners};
use crate::transform::rotation_angle_deg;
use nalgebra::Matrix4;
use serde::{Deserialize, Serialize};

/// A transform ICP starts from (the options' `starts`, which describe each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationStart"))]
pub enum Start {
    /// The network + GMR estimate. With `network: false` there is none: this start is then the
    /// initial transform, reported as [`Start::Initial`].
    Network,
    /// The initial transform's rotation with the translation that moves the source's centroid onto
    /// the target's (centroids of all the points, after the initial transform).
    Centroids,
    /// The initial transform itself (the identity unless `initialTransform` is set).
    Initial,
    /// Six starts: the network estimate (the initial transform with `network: false`) turned by
    /// [`TURN_DEGREES`] both ways about each axis of the target frame, through the moved source's
    /// centroid ([`turned`]). For estimates that landed outside ICP's basin.
    Turned,
    /// Six starts: the initial transform turned like [`Start::Turned`], through the source's
    /// centroid (after the initial transform). Beside the network's turns, for pairs where the
    /// network's estimate is far off; with `network: false` it is [`Start::Turned`].
    TurnedInitial,
    /// Up to [`crate::global::GlobalParams::hypotheses`] starts from global registration: FPFH
    /// descriptors, mutual correspondences and a seeded RANSAC ([`crate::global::hypotheses`]),
    /// for motions of any size. None when the descriptors match too little.
    Global,
    /// The [`Start::Global`] hypotheses, each refined by the network first (it estimates the
    /// motion left after the hypothesis, which is what it is trained for); with `network: false`
    /// it is [`Start::Global`].
    GlobalNetwork,
    /// Twenty-four starts: the source's centroid moved onto the target's, turned by each of the
    /// 24 rotations of a cube onto itself ([`cube_rotations`]), in the frame of the initial
    /// transform. A blind search over every orientation, for pairs in unrelated frames whose
    /// descriptors match poorly (repetitive, smooth or symmetric shapes). The adaptive search
    /// adds them to its last stage (see `search`).
    Rotations,
    /// The [`Start::Rotations`] turns, each refined by the network first: it estimates the motion
    /// left after the turn, and every orientation lies within about 63 degrees of one of the 24,
    /// near the 45 degrees per axis it is trained for. Twenty-four network passes, so the adaptive
    /// search refines them only for an answer still unsure after every other stage
    /// ([`Start::is_for_unsure`]). It needs the network: with `network: false` it is left out
    /// (the adaptive search's last stage then has the blind rotations, which it leaves out when
    /// this start is named), and naming it alone is an error.
    RotationsNetwork,
}

impl Start {
    /// Every start, in declaration order.
    pub const ALL: [Start; 9] = [
        Start::Network,
        Start::Centroids,
        Start::Initial,
        Start::Turned,
        Start::TurnedInitial,
        Start::Global,
        Start::GlobalNetwork,
        Start::Rotations,
        Start::RotationsNetwork,
    ];

    /// The name used in options and results (`"network"`, `"centroids"`, `"initial"`, `"turned"`,
    /// `"turnedInitial"`, `"global"`, `"globalNetwork"`, `"rotations"`, `"rotationsNetwork"`).
    pub fn name(self) -> &'static str {
        match self {
            Start::Network => "network",
            Start::Centroids => "centroids",
            Start::Initial => "initial",
            Start::Turned => "turned",
            Start::TurnedInitial => "turnedInitial",
            Start::Global => "global",
            Start::GlobalNetwork => "globalNetwork",
            Start::Rotations => "rotations",
            Start::RotationsNetwork => "rotationsNetwork",
        }
    }

    /// True for the starts from global registration ([`Start::Global`], [`Start::GlobalNetwork`]):
    /// each run of them is one stage of the adaptive search.
    pub fn is_global(self) -> bool {
        matches!(self, Start::Global | Start::GlobalNetwork)
    }

    /// True for the starts that [`crate::Search::Adaptive`] refines only for an answer below
    /// [`crate::register::UNSURE_CONFIDENCE`] after every other stage, as its very last stage
    /// ([`Start::RotationsNetwork`]: costly, and needed only where the other starts found nothing
    /// convincing).
    pub fn is_for_unsure(self) -> bool {
        self == Start::RotationsNetwork
    }
}

impl std::str::FromStr for Start {
    type Err = String;
    /// A start by its [`Start::name`].
    fn from_str(s: &str) -> Result<Self, String> {
        Start::ALL.into_iter().find(|x| x.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Start::ALL.iter().map(|x| x.name()).collect();
            format!("unknown start `{s}` (expected one of {})", names.join(", "))
        })
    }
}

/// Rejects an empty or repeating [`crate::Options::starts`].
pub fn check_starts(starts: &[Start]) -> crate::Result<()> {
    if starts.is_empty() {
        let names: Vec<String> = Start::ALL.iter().map(|s| format!("\"{}\"", s.name())).collect();
        return Err(crate::Error::InvalidOption(format!("starts is empty: list at least one of {}", names.join(", "))));
    }
    for (i, s) in starts.iter().enumerate() {
        if starts[..i].contains(s) {
            return Err(crate::Error::InvalidOption(format!("starts lists \"{}\" twice", s.name())));
        }
    }
    Ok(())
}

/// The angle of the [`Start::Turned`] starts, degrees. On 500 validation pairs (`arps eval`,
/// default starts otherwise) 45 recalled 0.940, 30 0.928 and 60 0.938: point-to-plane ICP's
/// basin reaches about 20-30 degrees, so 45-degree turns cover the gaps between the basins of the
/// estimate and its turns.
pub const TURN_DEGREES: f64 = 45.0;

/// `base` followed by turns of `degrees` both ways about the x, y and z axes through `pivot`
/// (a point in the target frame): six transforms, in the order +x, -x, +y, -y, +z, -z.
pub fn turned(base: &Matrix4<f64>, pivot: [f64; 3], degrees: f64) -> [Matrix4<f64>; 6] {
    let c = nalgebra::Vector3::from(pivot);
    let a = degrees.to_radians();
    let axes = [nalgebra::Vector3::x_axis(), nalgebra::Vector3::y_axis(), nalgebra::Vector3::z_axis()];
    std::array::from_fn(|i| {
        let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
        let r = nalgebra::Rotation3::from_axis_angle(&axes[i / 2], sign * a).into_inner();
        // x -> R (x - c) + c
        crate::transform::from_rotation_translation(&r, &(c - r * c)) * base
    })
}

/// The 24 rotations that map a cube onto itself (the signed permutation matrices of determinant
/// 1), the identity first: [`Start::Rotations`] turns the centroid alignment by each. Every
/// rotation lies within about 63 degrees of one of them; ICP's coarse stage at four times the
/// final distance covers the rest on most shapes.
pub fn cube_rotations() -> [nalgebra::Matrix3<f64>; 24] {
    let mut out = [nalgebra::Matrix3::identity(); 24];
    let mut k = 0;
    for perm in [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
        for signs in 0..8u32 {
            let mut r = nalgebra::Matrix3::zeros();
            for (row, &col) in perm.iter().enumerate() {
                r[(row, col)] = if signs & (1 << row) != 0 { -1.0 } else { 1.0 };
            }
            if r.determinant() > 0.0 {
                out[k] = r;
                k += 1;
            }
        }
    }
    out
}

/// Points of the short ICP runs of [`shortlist`].
pub const SHORTLIST_POINTS: usize = 256;
/// Iterations of each short ICP run of [`shortlist`], at the first distance of [`SCHEDULE`].
pub const SHORTLIST_ITERATIONS: u32 = 5;

/// An answer that [`shortlist`] screens the starts against: a start is kept only when its short
/// run fits at least `fit` as well as the same short run from the answer (`keep_best` of the best
/// starts are kept whatever their fit). A start that does not come near the answer's fit even at
/// the coarse distance seldom ends better than it.
#[derive(Clone, Copy, Debug)]
#[allow(non_snake_case)]
pub struct Screen<'a> {
    /// The answer, `T_target_source`.
    pub T_target_source: &'a Matrix4<f64>,
    /// The share of the answer's short-run fitness that a start's short run must reach.
    pub fit: f64,
    /// How many of the best starts are kept whatever their fit.
    pub keep_best: usize,
}

/// The `keep` of `starts` that fit best after a short ICP run each ([`SHORTLIST_ITERATIONS`] at
/// the coarsest distance of [`SCHEDULE`], on [`SHORTLIST_POINTS`] of the `source` points, evenly
/// spread), in their original order; all of them when there are no more than `keep` and no
/// `screen`. Ties keep the earlier start. A cheap first cut of many blind starts, most of which
/// land nowhere. With a `screen`, of those only the ones that come near its answer's fit
/// ([`Screen`]).
pub fn shortlist(
    target: &IcpTarget,
    source: &[[f32; 3]],
    starts: Vec<(Start, Matrix4<f64>)>,
    how: &Refinement,
    keep: usize,
    screen: Option<Screen>,
) -> Vec<(Start, Matrix4<f64>)> {
    // every start kept, whatever the short runs would say
    if starts.len() <= keep && screen.is_none_or(|s| starts.len() <= s.keep_best) {
        return starts;
    }
    let sample = even_sample(source, SHORTLIST_POINTS);
    let params = IcpParams {
        max_iterations: SHORTLIST_ITERATIONS,
        ..IcpParams::new(how.kind.or_point(), SCHEDULE[0] * how.d_coarse)
    };
    let (bar, keep_best) = match screen {
        Some(s) => (s.fit * target.align(&sample, s.T_target_source, &params).fitness, s.keep_best),
        None => (f64::NEG_INFINITY, 0),
    };
    let mut scored: Vec<(f64, usize)> =
        starts.iter().enumerate().map(|(i, (_, t))| (target.align(&sample, t, &params).fitness, i)).collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut kept: Vec<usize> = scored
        .into_iter()
        .take(keep)
        .enumerate()
        .filter(|&(rank, (fitness, _))| rank < keep_best || fitness >= bar)
        .map(|(_, (_, i))| i)
        .collect();
    kept.sort_unstable();
    kept.into_iter().map(|i| starts[i]).collect()
}

/// ICP runs coarse to fine at these multiples of the final max correspondence distance (of
/// [`Refinement::d_coarse`], then halving down to the final distance, when the caller's final
/// distance is tighter than the default: [`Refinement::stages`]).
pub const SCHEDULE: [f64; 3] = [4.0, 2.0, 1.0];

/// Damping ([`IcpParams::damping`]) of a second run of the widest ICP stage ([`SCHEDULE`]'s
/// first) for the start that is an estimate of the answer ([`Refinement::estimate`]). At four times
/// the final distance many pairs join points of different surface patches; on a shape that pins
/// some motion only weakly (a bowl or a bottle turned about its axis, a door or a curtain slid
/// along itself) their pull drags the fit along that motion, up to a half turn away from an
/// estimate that was right, and the closer stages cannot bring it back. Damped, such motions move
/// little in the wide stage and are settled by the closer stages' pairs. But an estimate that is
/// off along a weakly pinned motion (a room's scan shifted along its floor) needs the plain stage
/// to travel there, so the estimate takes the wide stage both ways, and a third time not at all
/// (only the closer stages): from an estimate a few degrees off, even the damped stage can leave
/// a bowl turned about its axis in a basin that fits worse. The runs go on as candidates, merged
/// by the next stage where they end alike, and the fit chooses between them ([`choose`]). The
/// other starts are guesses that must travel, and take the plain stage only. `BENCHMARK.md`, "The
/// estimate's wide ICP stage, also damped" and "ICP from a close estimate on surfaces of
/// revolution".
pub const WIDE_DAMPING: f64 = 0.03;

/// The last stage of [`SCHEDULE`] alone: what runs again on a screened winner's full points, and
/// what `converge` continues.
const FINAL_STAGE: &[f64] = &[SCHEDULE[SCHEDULE.len() - 1]];

/// How every start is refined: the ICP kind, the final max correspondence distance (the stages of
/// [`SCHEDULE`] are multiples of it; candidates are scored at it) and each stage's iteration cap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refinement {
    /// Point-to-plane, point-to-point, or off (the starts are only scored).
    pub kind: IcpKind,
    /// The final max correspondence distance, in the clouds' units.
    pub d_final: f64,
    /// The distance the stages start from: the first is [`SCHEDULE`]'s first multiple of it. At
    /// least `d_final`; larger when the caller's final distance is tighter than the default one,
    /// so that the starts travel as far as at the default (a tight distance sets the precision,
    /// not how far the search reaches), then halve down to `d_final` ([`Refinement::stages`]);
    /// [`refine_starts`] then also refines every start through [`SCHEDULE`] alone (when `d_coarse`
    /// is at least [`SCHEDULE_ALONE_RATIO`] times `d_final`), and the fit chooses.
    pub d_coarse: f64,
    /// Iteration cap of each ICP stage.
    pub max_iterations: u32,
    /// The start that is an estimate of the answer, not a guess (the pipeline's: the network's, or
    /// with the network off the initial transform), if any: it takes the widest stage plainly,
    /// damped ([`WIDE_DAMPING`]) and not at all (the closer stages only), as three candidates.
    pub estimate: Option<Start>,
    /// Weigh the pairs of the [`Start::Initial`] start by Tukey's biweight ([`IcpParams::robust`])
    /// in every stage (the pipeline's with `icpLoss: "robust"` and the caller's
    /// `initialTransform`): a surface that changed between the scans, within the wide stages'
    /// distances of the guess, would pull a guess that is already right off it (a third of a
    /// survey raised 2 m: 9 m at the corners). The pipeline's other starts, and its identity
    /// start without a guess, are refined by least squares, as the search compares them.
    pub robust_guess: bool,
}

impl Refinement {
    /// A refinement at the final distance `d_final` whose stages start from `d_coarse` (the
    /// larger of the two: [`Refinement::d_coarse`]); no estimate, no robust guess.
    pub fn new(kind: IcpKind, d_final: f64, d_coarse: f64, max_iterations: u32) -> Self {
        Self { kind, d_final, d_coarse: d_coarse.max(d_final), max_iterations, estimate: None, robust_guess: false }
    }

    /// The stages, as multiples of `d_final`: [`SCHEDULE`] when `d_coarse` is `d_final`; else
    /// [`SCHEDULE`] times `d_coarse / d_final`, then halving down to 1 (the last stage a
    /// half-step or less after the one before).
    pub fn stages(&self) -> Vec<f64> {
        let r = self.d_coarse / self.d_final;
        let mut stages: Vec<f64> = SCHEDULE.iter().map(|f| f * r).collect();
        let mut f = r;
        // (at most 64 halvings: a ratio beyond f64's range, from distances no caller can set,
        // still ends)
        while f > 1.0 && stages.len() < SCHEDULE.len() + 64 {
            f = (f / 2.0).max(1.0);
            // a last step shorter than a quarter of the halving is merged into the final stage
            if f < 1.25 {
                f = 1.0;
            }
            stages.push(f);
        }
        stages
    }
}

/// One start after refinement, scored at the final distance.
#[allow(non_snake_case)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// Where it started.
    pub start: Start,
    /// The refined transform (the frames of the clouds given to [`refine_starts`]).
    pub T_target_source: Matrix4<f64>,
    /// [`IcpTarget::evaluate`]'s fitness at the final distance.
    pub fitness: f64,
    /// [`IcpTarget::evaluate`]'s inlier RMSE at the final distance.
    pub inlier_rmse: f64,
    /// ICP iterations over the stages of [`SCHEDULE`] (0 with ICP off).
    pub iterations: u32,
    /// True when the last stage met its convergence criteria (false with ICP off).
    pub converged: bool,
}

/// Starts whose transforms move no source point farther than this fraction of the final distance
/// from an earlier start's are merged into it before each ICP stage: from there they would
/// converge to the same answer, and refining them again would only cost time.
pub const MERGE_FRACTION: f64 = 0.5;

/// With more source points than this, the starts go through the coarse stages and are compared
/// on an evenly spread sample of this many, and only the winner is refined on more (at most
/// [`REFINE_POINTS`]; [`refine_best`]).
pub const SCREEN_POINTS: usize = 2048;

/// Most source points any start is refined and scored on: larger (voxelised) sources are
/// replaced by this many evenly spread points ([`even_sample`]) before anything else, so the
/// cost of refinement stops growing with the point count. 8,192 points pin a rigid motion far
/// below the recall thresholds (`BENCHMARK.md`, "Large clouds").
pub const REFINE_POINTS: usize = 8192;

/// The best start after refinement: [`refine_starts`] then [`choose`]. `None` for no starts.
///
/// The source is first capped at [`REFINE_POINTS`] evenly spread points. With more than
/// [`SCREEN_POINTS`] left (large scans), the starts (even a single one) are refined through the
/// coarse stages and compared on [`SCREEN_POINTS`] evenly spread source points, and only the
/// winner is refined again on all the capped points, from where the sample left it, at the final
/// distance only (the sample's run has been through the coarse stages); its figures are those of
/// that run (its `iterations` count both runs). So each start costs an ICP run on at most
/// [`SCREEN_POINTS`] points, and the answer one final stage on at most [`REFINE_POINTS`].
/// Either way, the winner's final stage runs on past the cap when it has not converged
/// ([`CONVERGE_ROUNDS`]).
pub fn refine_best(
    target: &IcpTarget,
    source: &[[f32; 3]],
    starts: &[(Start, Matrix4<f64>)],
    how: &Refinement,
) -> Option<Candidate> {
    let capped = even_sample(source, REFINE_POINTS);
    let source = capped.as_slice();
    if how.kind != IcpKind::Off && source.len() > SCREEN_POINTS && !starts.is_empty() {
        let sample = even_sample(source, SCREEN_POINTS);
        let screened = refine_starts(target, &sample, starts, how);
        let w = screened[choose(&screened)?];
        // the sample left it converged at the final distance: only the final stage runs again
        let c = refine_final(target, source, w.start, &w.T_target_source, how);
        return Some(Candidate { iterations: w.iterations + c.iterations, ..c });
    }
    let all = refine_starts(target, source, starts, how);
    choose(&all).map(|i| converge(target, source, all[i], how))
}

/// The pose `T_target_source` (already near a fit: a probe pose, a refined answer) refined like
/// [`refine_best`]'s winner on large clouds: at the final distance only, run on until it
/// converges ([`CONVERGE_ROUNDS`]). Reported as coming from `start`. `source` should already be capped
/// like [`refine_best`]'s (at most [`REFINE_POINTS`] evenly spread points, [`even_sample`]).
#[allow(non_snake_case)]
pub fn refine_final(
    target: &IcpTarget,
    source: &[[f32; 3]],
    start: Start,
    T_target_source: &Matrix4<f64>,
    how: &Refinement,
) -> Candidate {
    let c = refine_stages(target, source, &[(start, *T_target_source)], how, FINAL_STAGE)[0];
    converge(target, source, c, how)
}

/// [`refine_final`] for a pose that may land nowhere new (the next of a row of alike parts, the
/// other face of a wall): first one run of the final stage (no rounds past the cap) on
/// [`SCREEN_POINTS`] evenly spread points of the capped `source`; `None` when that run fits less
/// than [`SCREENED_FIT`] as well as the `answer` (`T_target_source`) on the same points, or
/// comes back onto it ([`coincide`]): neither can replace the answer or be its look-alike. Else
/// [`refine_final`] on every capped point from where the run left it. At the final distance a
/// pose off any basin crawls: on 1M-point clouds one took four rounds of 30 iterations on 8,192
/// points and still fit 0.74 to the answer's 0.96, and a wall's other face that slid back onto
/// the answer's took 25 iterations to say so (`BENCHMARK.md`, "Large clouds: poses that land
/// nowhere new, screened").
#[allow(non_snake_case)]
pub fn refine_final_screened(
    target: &IcpTarget,
    source: &[[f32; 3]],
    start: Start,
    T_target_source: &Matrix4<f64>,
    how: &Refinement,
    answer: &Matrix4<f64>,
) -> Option<Candidate> {
    let sample = even_sample(source, SCREEN_POINTS);
    let mut from = *T_target_source;
    // (with no more points than the sample, the screening run would be the refinement itself)
    if how.kind != IcpKind::Off && sample.len() < source.len() {
        let run = refine_stages(target, &sample, &[(start, from)], how, FINAL_STAGE)[0];
        let back = coincide(&run.T_target_source, answer, &sample, how.d_final);
        if back || run.fitness < SCREENED_FIT * target.evaluate(&sample, answer, how.d_final).0 {
            return None;
        }
        from = run.T_target_source;
    }
    Some(refine_final(target, source, start, &from, how))
}

/// [`refine_final_screened`] refines a pose on every point only when its run on the sample fits at
/// least this share as well as the answer there: below the share of a look-alike (0.9,
/// [`crate::confidence::count_search_alternatives`]), with a margin for a run not yet converged.
pub const SCREENED_FIT: f64 = 0.8;

/// The answer's final stage, when it has not converged within the cap, runs on in rounds of
/// `max_iterations` for at most this many rounds more ([`refine_best`]).
pub const CONVERGE_ROUNDS: u32 = 3;

/// A round past the cap ([`CONVERGE_ROUNDS`]) that moved no source point farther than this
/// fraction of the final distance has settled: the fit oscillates between near-equal
/// correspondences rather than moving.
pub const SETTLED_FRACTION: f64 = 0.1;

/// `c` itself when its final stage converged; otherwise that stage continued from where it
/// stopped, in rounds of `how.max_iterations` iterations, until it converges, a round moves no
/// point farther than [`SETTLED_FRACTION`] of the final distance, or after [`CONVERGE_ROUNDS`]
/// rounds. A slow ICP (a long scene whose fit pins one motion only weakly) would otherwise be
/// judged where the cap cut it, degrees short of its minimum.
fn converge(target: &IcpTarget, source: &[[f32; 3]], mut c: Candidate, how: &Refinement) -> Candidate {
    for _ in 0..CONVERGE_ROUNDS {
        if how.kind == IcpKind::Off || c.converged {
            break;
        }
        let next = refine_stages(target, source, &[(c.start, c.T_target_source)], how, FINAL_STAGE)[0];
        let moved = max_displacement(&c.T_target_source, &next.T_target_source, source);
        c = Candidate { iterations: c.iterations + next.iterations, ..next };
        if moved <= SETTLED_FRACTION * how.d_final {
            break;
        }
    }
    c
}

/// `n` points of `points` (all of them if there are not more), evenly spaced in its order; the
/// voxel grid's order (`sampling::voxel_downsample`) makes that an even spread in space.
pub fn even_sample(points: &[[f32; 3]], n: usize) -> Vec<[f32; 3]> {
    if points.len() <= n {
        return points.to_vec();
    }
    // in u64: 8192 samples of a 600k-point cloud overflow wasm32's usize (the sample then
    // covered the cloud's first part only)
    let (len, n64) = (points.len() as u64, n as u64);
    (0..n as u64).map(|i| points[(i * len / n64) as usize]).collect()
}

/// Refines every start with coarse-to-fine ICP against one prepared target ([`Refinement::stages`]:
/// [`SCHEDULE`] times `how.d_final` unless the final distance is tighter than the coarse one,
/// each stage capped at `how.max_iterations`; `how.estimate` takes the widest stage
/// plainly, damped ([`WIDE_DAMPING`]) and not at all, as three candidates) and scores
/// each result at `how.d_final`. With a coarse distance at least [`SCHEDULE_ALONE_RATIO`] times
/// the final one, the starts are refined a second time through [`SCHEDULE`] alone, and those
/// candidates follow the first ones.
///
/// The starts advance stage by stage together; before each stage a start that has come within
/// [`MERGE_FRACTION`] of `how.d_final` of an earlier one (largest displacement of a source point) is
/// dropped, so each run has one candidate per distinct basin, in the order of `starts`; after
/// each coarse stage a start below [`CUT_BEHIND`] of the best fitness at that stage's distance is
/// dropped too. With
/// [`IcpKind::Off`] nothing moves: every start is scored as it is.
pub fn refine_starts(
    target: &IcpTarget,
    source: &[[f32; 3]],
    starts: &[(Start, Matrix4<f64>)],
    how: &Refinement,
) -> Vec<Candidate> {
    let mut all = refine_stages(target, source, starts, how, &how.stages());
    if how.d_coarse >= SCHEDULE_ALONE_RATIO * how.d_final {
        // and through the caller's own schedule alone: a start already near the answer (a guess
        // placed by hand) can be pulled off it by the wide stages in a scene of repeated
        // structure (a corridor's walls paired with the next ones), where the starts that must
        // travel need them; the fit at the final distance chooses ([`choose`])
        all.extend(refine_stages(target, source, starts, how, &SCHEDULE));
    }
    all
}

/// [`refine_starts`] refines the starts through [`SCHEDULE`] alone too only when the stages start
/// from at least this many times the final distance's ([`Refinement::d_coarse`]): nearer, the two
/// schedules nearly coincide (a dense object's default distance at 0.73 of the size-based one:
/// stages of 5.5, 2.7, 1.4 and 1 times it against 4, 2 and 1), and the second run only doubled
/// the time (`BENCHMARK.md`, "Large clouds: poses that land nowhere new, screened").
pub const SCHEDULE_ALONE_RATIO: f64 = 2.0;

/// [`refine_starts`] with the given stages (multiples of `how.d_final`) instead of [`SCHEDULE`].
fn refine_stages(
    target: &IcpTarget,
    source: &[[f32; 3]],
    starts: &[(Start, Matrix4<f64>)],
    how: &Refinement,
    schedule: &[f64],
) -> Vec<Candidate> {
    let Refinement { kind, d_final, max_iterations, estimate, robust_guess, .. } = *how;
    // each start with its points' partners in the previous stage (warm-starts the next)
    let mut live: Vec<(Candidate, Partners)> = starts
        .iter()
        .map(|&(start, t)| {
            let c = Candidate {
                start,
                T_target_source: t,
                fitness: 0.0,
                inlier_rmse: 0.0,
                iterations: 0,
                converged: false,
            };
            (c, Partners::default())
        })
        .collect();
    if kind != IcpKind::Off {
        for (k, &factor) in schedule.iter().enumerate() {
            merge_coincident(&mut live, source, MERGE_FRACTION * d_final);
            let params = IcpParams { max_iterations, ..IcpParams::new(kind, d_final * factor) };
            let mut wide = vec![Wide::Plain; live.len()];
            // (the widest stage of a coarse-to-fine schedule, not a final stage run alone)
            if k == 0 && schedule.len() > 1 {
                (live, wide) = with_estimate_twins(live, estimate);
            }
            for ((c, partners), &wide) in live.iter_mut().zip(&wide) {
                if wide == Wide::Skipped {
                    // left where it is: scored at this stage's distance for the cut below
                    c.fitness = target.evaluate_warm(source, &c.T_target_source, d_final * factor, partners).0;
                    continue;
                }
                let params = IcpParams {
                    damping: if wide == Wide::Damped { WIDE_DAMPING } else { 0.0 },
                    robust: robust_guess && c.start == Start::Initial,
                    ..params
                };
                let r = target.align_warm(source, &c.T_target_source, &params, partners);
                c.T_target_source = r.T_target_source;
                c.iterations += r.iterations;
                c.converged = r.converged;
                // this stage's fitness, for the cut below (scored again at the end)
                c.fitness = r.fitness;
            }
            if factor > 1.0 {
                cut_behind(&mut live);
            }
        }
    }
    live.into_iter()
        .map(|(mut c, mut partners)| {
            (c.fitness, c.inlier_rmse) = target.evaluate_warm(source, &c.T_target_source, d_final, &mut partners);
            c
        })
        .collect()
}

/// How a candidate takes the widest ICP stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Wide {
    /// Plain ICP: every start.
    Plain,
    /// Damped ([`WIDE_DAMPING`]): a twin of the estimate.
    Damped,
    /// Not at all, the closer stages only: a second twin of the estimate.
    Skipped,
}

/// `live` with two twins after each entry of the `estimate` start, and how each entry takes the
/// widest stage: the start itself plainly, its twins damped and not at all.
fn with_estimate_twins(
    live: Vec<(Candidate, Partners)>,
    estimate: Option<Start>,
) -> (Vec<(Candidate, Partners)>, Vec<Wide>) {
    let mut out = Vec::with_capacity(live.len() + 2);
    let mut wide = Vec::with_capacity(live.len() + 2);
    for (c, partners) in live {
        let ways: &[Wide] =
            if Some(c.start) == estimate { &[Wide::Plain, Wide::Damped, Wide::Skipped] } else { &[Wide::Plain] };
        out.extend(ways[1..].iter().map(|_| (c, partners.clone())));
        out.push((c, partners));
        wide.extend_from_slice(ways);
    }
    (out, wide)
}

/// After a coarse stage, a start whose fitness at that stage's distance is below this fraction of
/// the best start's is dropped: it cannot come near the best fit, and refining it further would
/// only cost time.
pub const CUT_BEHIND: f64 = 0.6;

/// Drops the candidates whose `fitness` is below [`CUT_BEHIND`] times the best one's.
fn cut_behind<X>(live: &mut Vec<(Candidate, X)>) {
    let best = live.iter().map(|c| c.0.fitness).fold(0.0, f64::max);
    live.retain(|c| c.0.fitness >= CUT_BEHIND * best);
}

/// Drops every candidate whose transform moves no point of `source` farther than `tolerance`
/// from where an earlier (kept) candidate's moves it.
fn merge_coincident<X>(live: &mut Vec<(Candidate, X)>, source: &[[f32; 3]], tolerance: f64) {
    let mut kept: Vec<(Candidate, X)> = Vec::with_capacity(live.len());
    for c in live.drain(..) {
        if !kept.iter().any(|k| max_displacement(&k.0.T_target_source, &c.0.T_target_source, source) <= tolerance) {
            kept.push(c);
        }
    }
    *live = kept;
}

/// True when `a` and `b` move no point of `source` farther than [`MERGE_FRACTION`] of `d_final`
/// apart: the same answer (ICP from one would converge to the other).
pub fn coincide(a: &Matrix4<f64>, b: &Matrix4<f64>, source: &[[f32; 3]], d_final: f64) -> bool {
    max_displacement(a, b, source) <= MERGE_FRACTION * d_final
}

/// The largest distance between `a p` and `b p` over the points `p`.
fn max_displacement(a: &Matrix4<f64>, b: &Matrix4<f64>, points: &[[f32; 3]]) -> f64 {
    let d = a - b;
    let (r, t) = (d.fixed_view::<3, 3>(0, 0), d.fixed_view::<3, 1>(0, 3));
    points
        .iter()
        .map(|p| (r * nalgebra::Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) + t).norm())
        .fold(0.0, f64::max)
}

/// Fitnesses within this fraction of each other are a near tie for [`better`]: the clouds
/// cannot tell such poses apart (a half turn of a near-symmetric shape fits within a few percent
/// of the truth, either way).
pub const TIE_FITNESS: f64 = 0.10;

/// Fitnesses within [`TIE_FITNESS`] of each other are a near tie only while the worse leaves at
/// most this many times the share of the source off the target (`1 - fitness`) that the better
/// one leaves: two poses that put nearly all of the source on the target (a scan inside its
/// model) are told apart by the few points the worse one leaves off (a notch, a keyway, a
/// locating pin), which fitness alone counts as a hair.
pub const TIE_MISFIT: f64 = 2.0;

/// Near ties ([`TIE_FITNESS`]) between poses whose turns away from the initial guess
/// ([`turn_deg`]) differ by more than this many degrees go to the smaller turn ([`better`]).
pub const TIE_TURN_DEG: f64 = 60.0;

/// How far `T_target_source` turns away from the initial guess, in degrees: the angle of its
/// rotation (the pipeline's frames turn the source by the guess's rotation first, so there the
/// identity rotation is the guess; with no guess, the clouds as given).
#[allow(non_snake_case)]
pub fn turn_deg(T_target_source: &Matrix4<f64>) -> f64 {
    rotation_angle_deg(T_target_source)
}

/// True when `c` is a better answer than `b`. Normally the higher fitness at the final distance;
/// among equal fitness (the same number of inliers), the lower inlier RMSE. But when the two fit
/// within [`TIE_FITNESS`] (and [`TIE_MISFIT`]) of each other and turn away from the initial guess
/// by amounts more than [`TIE_TURN_DEG`] apart, the one that turns less: the poses fit alike, and a
/// motion no larger than needed is the likelier one (scans of one object from one device, a guess
/// that was roughly right). On pairs in arbitrary poses the rule favours neither the truth nor its
/// look-alike; on pairs turned by at most 45 degrees per axis it picks the truth over a flip of a
/// near-symmetric shape (`BENCHMARK.md`, "Near ties go to the smaller turn").
pub fn better(c: &Candidate, b: &Candidate) -> bool {
    if near_tie(c, b) {
        let (turn_c, turn_b) = (turn_deg(&c.T_target_source), turn_deg(&b.T_target_source));
        if (turn_c - turn_b).abs() > TIE_TURN_DEG {
            return turn_c < turn_b;
        }
    }
    c.fitness > b.fitness || (c.fitness == b.fitness && c.inlier_rmse < b.inlier_rmse)
}

/// True when `c` and `b` fit within [`TIE_FITNESS`] and [`TIE_MISFIT`] of each other: a near
/// tie for [`better`].
fn near_tie(c: &Candidate, b: &Candidate) -> bool {
    let (lo, hi) = (c.fitness.min(b.fitness), c.fitness.max(b.fitness));
    hi <= lo * (1.0 + TIE_FITNESS) && !leaves_far_less_off(c, b) && !leaves_far_less_off(b, c)
}

/// True when `c` leaves less than a [`TIE_MISFIT`]th of the share of the source off the target
/// that `b` leaves (`1 - fitness`): better than `b` beyond any near tie, whatever the turns.
pub fn leaves_far_less_off(c: &Candidate, b: &Candidate) -> bool {
    c.fitness > b.fitness && 1.0 - b.fitness > TIE_MISFIT * (1.0 - c.fitness)
}

/// True when `c` fits more than [`TIE_FITNESS`] better than `b`: better beyond a near tie.
pub fn clearly_better(c: &Candidate, b: &Candidate) -> bool {
    c.fitness > b.fitness * (1.0 + TIE_FITNESS)
}

/// The index of the best candidate by [`better`], each compared with the best so far in list
/// order (so among equals, the first). `None` for no candidates.
///
/// Measured on 1000 validation pairs (`arps eval`, README): the fitness order chose as well as or
/// better than treating near-equal fitness (within 0.5% to 5%) as a tie decided by RMSE, than a
/// truncated-quadratic (MSAC) score, and than scoring at a coarser distance; RMSE alone chose worst.
pub fn choose(candidates: &[Candidate]) -> Option<usize> {
    let mut chosen: Option<usize> = None;
    for (i, c) in candidates.iter().enumerate() {
        if chosen.is_none_or(|j| better(c, &candidates[j])) {
            chosen = Some(i);
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tight_final_distance_starts_at_the_default_and_halves_down() {
        let stages = |d_final: f64, d_coarse: f64| Refinement::new(IcpKind::Plane, d_final, d_coarse, 30).stages();
        assert_eq!(stages(0.025, 0.025), SCHEDULE.to_vec(), "at the default: the schedule");
        assert_eq!(stages(0.05, 0.025), SCHEDULE.to_vec(), "wider than the default: the schedule");
        assert_eq!(stages(0.025 / 8.0, 0.025), vec![32.0, 16.0, 8.0, 4.0, 2.0, 1.0]);
        assert_eq!(stages(0.025 / 3.0, 0.025), vec![12.0, 6.0, 3.0, 1.5, 1.0]);
        let s = stages(0.025 / 2.2, 0.025);
        assert_eq!(s.len(), 4, "{s:?}: the step below 1.25 merged into the final stage");
        assert_eq!(s[3], 1.0);
    }
}
