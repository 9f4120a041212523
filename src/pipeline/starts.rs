//! Stage 4: the candidate starts.
//!
//! Takes the [`Options`], the [`Prepared`] clouds and the network's estimate; gives the stages of
//! the search ([`stages`]: lists of [`Start`] kinds) and, per stage, the transforms ICP starts
//! from ([`Starts::build`], normalised units). A new start kind is added here (and in
//! [`Start`]).

use super::network;
use super::prepare::Prepared;
use crate::icp::IcpKind;
use crate::model::{Model, ModelWorkspace};
use crate::refine::{self, Start};
use crate::register::{Options, Search};
use crate::timing::{Clock, Stopwatch};
use crate::{global, transform, Result};
use nalgebra::{Matrix4, Vector3};

/// The starts as the options name them, with the network off mapped to what they become
/// ([`Start::RotationsNetwork`] left out: the adaptive search's last stage has the blind
/// rotations), without repeats; only the first with ICP off.
pub(crate) fn kinds(options: &Options) -> Vec<Start> {
    let mut kinds: Vec<Start> = Vec::with_capacity(options.starts.len());
    for &start in &options.starts {
        if start == Start::RotationsNetwork && !options.network {
            continue;
        }
        let start = match start {
            Start::Network if !options.network => Start::Initial,
            Start::TurnedInitial if !options.network => Start::Turned,
            Start::GlobalNetwork if !options.network => Start::Global,
            s => s,
        };
        if !kinds.contains(&start) {
            kinds.push(start);
        }
    }
    if options.icp == IcpKind::Off {
        kinds.truncate(1);
    }
    kinds
}

/// One stage of the search ([`super::search`]), in the order [`stages`] gives them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Step {
    /// Starts the options name, refined together.
    Listed(Vec<Start>),
    /// The adaptive search's last stage of blind starts ([`Starts::more`]): refined only while no
    /// stage has reached the stop.
    Blind,
    /// The starts for unsure answers ([`Start::is_for_unsure`]): refined only while the answer is
    /// still unsure.
    Unsure(Vec<Start>),
}

/// The stages of the search: the first start alone, then the others in their order, grouped into
/// runs of local and of global starts; for [`Search::Adaptive`] then the last stage of blind
/// starts, and last, in one stage of their own, the starts for unsure answers
/// ([`Start::is_for_unsure`]) (with the default starts: the network's; the global ones; the
/// other local ones; the blind ones; the network's rotations). [`Search::Exhaustive`] runs the
/// same stages of `kinds`, the starts for unsure answers among them in their order, every one
/// of them: each stage's best is judged as in the adaptive search, so both count the same
/// look-alikes as alternatives. With a `guess` (the caller's `initialTransform`),
/// [`Start::Initial`], when `kinds` has it, joins the first stage: the caller's guess is always
/// refined, whatever stops the search (a global hypothesis can fit a sparse source about as well
/// turned over, and look sure).
pub(crate) fn stages(kinds: &[Start], search: Search, guess: bool) -> Vec<Step> {
    let (unsure, mut kinds): (Vec<Start>, Vec<Start>) = match search {
        Search::Adaptive => kinds.iter().partition(|k| k.is_for_unsure()),
        Search::Exhaustive | Search::Local => (Vec::new(), kinds.to_vec()),
    };
    let mut stages: Vec<Vec<Start>> = kinds.iter().take(1).map(|&k| vec![k]).collect();
    if guess && search == Search::Adaptive && kinds.iter().skip(1).any(|&k| k == Start::Initial) {
        kinds.retain(|&k| k != Start::Initial);
        stages[0].push(Start::Initial);
    }
    for &k in kinds.iter().skip(1) {
        let joins = stages.len() > 1 && stages.last().is_some_and(|l| l[0].is_global() == k.is_global());
        match stages.last_mut() {
            Some(last) if joins => last.push(k),
            _ => stages.push(vec![k]),
        }
    }
    let adaptive = search == Search::Adaptive;
    let blind = (adaptive && !stages.is_empty()).then_some(Step::Blind);
    let unsure = (!unsure.is_empty()).then_some(Step::Unsure(unsure));
    stages.into_iter().map(Step::Listed).chain(blind).chain(unsure).collect()
}

/// Whether the adaptive search's last stage ([`Step::Blind`]) adds the 24 blind rotations to its
/// further global hypotheses: not for an answer nearly sure after the global stage, and not when
/// `kinds` has the network's turns ([`Start::RotationsNetwork`]), which follow for an unsure
/// answer and search every orientation better; so with the network off (where [`kinds`] leaves
/// them out), or starts that leave them out, it does.
pub(crate) fn blind_rotations(kinds: &[Start], nearly_sure: bool) -> bool {
    !nearly_sure && !kinds.contains(&Start::RotationsNetwork)
}

/// Builds the start transforms of each stage; describes and matches the clouds once, when a
/// global start first needs it, and draws the global hypotheses from those matches: the first
/// ones for the global starts, more for the adaptive search's last stage ([`Starts::more`]).
pub(crate) struct Starts<'a> {
    prepared: &'a Prepared,
    /// The network's estimate (the initial transform with the network off).
    t_net_n: Matrix4<f64>,
    seed: u64,
    clock: Option<Clock>,
    matched: Option<global::Matched>,
    hypotheses: Option<Vec<Matrix4<f64>>>,
    /// Whether a pair between sparse and dense is described at the finer scale too
    /// ([`global::Density::Mid`]), when the clouds are first described.
    pub(crate) finer: bool,
    /// Milliseconds spent on the global hypotheses so far.
    pub global_ms: f64,
    /// Milliseconds spent on the network's passes for starts it refines first
    /// ([`Start::GlobalNetwork`], [`Start::RotationsNetwork`]) so far.
    pub network_ms: f64,
}

impl<'a> Starts<'a> {
    /// Starts for `prepared`, with the network's estimate `t_net_n` (normalised units).
    pub(crate) fn new(prepared: &'a Prepared, t_net_n: Matrix4<f64>, seed: u64, clock: Option<Clock>) -> Self {
        Self {
            prepared,
            t_net_n,
            seed,
            clock,
            matched: None,
            hypotheses: None,
            finer: true,
            global_ms: 0.0,
            network_ms: 0.0,
        }
    }

    /// The network's estimate these starts were built from (normalised units).
    pub(crate) fn t_net_n(&self) -> Matrix4<f64> {
        self.t_net_n
    }

    /// The (kind, transform) starts of one stage, in order (turned starts are six each, global
    /// ones one per hypothesis).
    pub(crate) fn build(
        &mut self,
        stage: &[Start],
        model: &Model,
        workspace: &mut ModelWorkspace,
    ) -> Result<Vec<(Start, Matrix4<f64>)>> {
        let p = self.prepared;
        let (t_net_n, t_initial) = (self.t_net_n, p.t_initial);
        // the six turns of `base` through the source's centroid as `base` moves it
        let c = p.src_n.centroid();
        let turns = |base: &Matrix4<f64>| {
            let moved = base.transform_point(&nalgebra::Point3::new(c[0], c[1], c[2]));
            refine::turned(base, [moved.x, moved.y, moved.z], refine::TURN_DEGREES)
        };
        let mut starts: Vec<(Start, Matrix4<f64>)> = Vec::with_capacity(stage.len() * 6);
        for &start in stage {
            match start {
                Start::Network => starts.push((start, t_net_n)),
                Start::Initial => starts.push((start, t_initial)),
                Start::Centroids => starts.push((start, centroid_alignment(p.src_n.centroid(), p.target.centroid()))),
                Start::Rotations => starts.extend(rotations(p).into_iter().map(|t| (start, t))),
                Start::RotationsNetwork => {
                    let turns = rotations(p);
                    starts.extend(self.refined_by_network(start, &turns, model, workspace)?);
                }
                Start::Turned | Start::TurnedInitial => {
                    // t_net_n is the initial transform when the network is off
                    let base = if start == Start::Turned { t_net_n } else { t_initial };
                    starts.extend(turns(&base).map(|t| (start, t)));
                }
                Start::Global | Start::GlobalNetwork => {
                    if self.hypotheses.is_none() {
                        self.hypotheses = Some(self.draw(global::GlobalParams::default().hypotheses));
                    }
                    let hypotheses = self.hypotheses.clone().unwrap_or_default();
                    starts.extend(self.global(start, &hypotheses, model, workspace)?);
                }
            }
        }
        Ok(starts)
    }

    /// The adaptive search's last stage: [`MORE_HYPOTHESES`] global hypotheses drawn from the same
    /// matches, less those within [`SAME_HYPOTHESIS_DEGREES`] and [`SAME_HYPOTHESIS_SHIFT`] of one
    /// a global start already used, as starts of each global kind in `kinds`; then, when
    /// `with_rotations`, the [`Start::Rotations`] starts, unless `kinds` has them already. None
    /// when `kinds` has no global kind, or no global start ran before.
    pub(crate) fn more(
        &mut self,
        kinds: &[Start],
        with_rotations: bool,
        model: &Model,
        workspace: &mut ModelWorkspace,
    ) -> Result<Vec<(Start, Matrix4<f64>)>> {
        let Some(used) = self.hypotheses.clone() else { return Ok(Vec::new()) };
        let same = |a: &Matrix4<f64>, b: &Matrix4<f64>| {
            transform::rotation_error_deg(a, b) < SAME_HYPOTHESIS_DEGREES
                && (transform::translation(a) - transform::translation(b)).norm() < SAME_HYPOTHESIS_SHIFT
        };
        let mut more = self.draw(MORE_HYPOTHESES);
        more.retain(|h| !used.iter().any(|u| same(u, h)));
        let mut starts = Vec::new();
        for &start in kinds.iter().filter(|k| k.is_global()) {
            starts.extend(self.global(start, &more, model, workspace)?);
        }
        if with_rotations && !kinds.contains(&Start::Rotations) {
            starts.extend(rotations(self.prepared).into_iter().map(|t| (Start::Rotations, t)));
        }
        Ok(starts)
    }

    /// `T_target_source` with the translation the global stage's descriptor matches agree on for
    /// its rotation ([`global::Matched::translations`]), when the global stage has run, at least
    /// [`MIN_TRANSLATION_VOTES`] matches agree, and that translation is another one: farther from
    /// `T_target_source`'s than the radius of the matches' clusters (RANSAC's inlier distance).
    #[allow(non_snake_case)]
    pub(crate) fn voted_pose(&self, T_target_source: &Matrix4<f64>) -> Option<Matrix4<f64>> {
        self.voted_poses(T_target_source, 1).into_iter().next().map(|(t, _)| t)
    }

    /// [`Starts::voted_pose`] for each of the `count` translations the matches agree on most
    /// ([`global::Matched::translations`]) that at least [`MIN_TRANSLATION_VOTES`] agree on and
    /// that is another one than `T_target_source`'s, with its rank among them (0: the densest):
    /// with the answer on one of a row of alike parts (two identical pipe spools), the next best
    /// is the other part.
    #[allow(non_snake_case)]
    pub(crate) fn voted_poses(&self, T_target_source: &Matrix4<f64>, count: usize) -> Vec<(Matrix4<f64>, usize)> {
        let Some(matched) = self.matched.as_ref() else { return Vec::new() };
        let r = transform::rotation(T_target_source);
        let own = transform::translation(T_target_source);
        matched
            .translations(&r, count)
            .into_iter()
            .enumerate()
            .filter(|(_, (t, votes))| *votes >= MIN_TRANSLATION_VOTES && (t - own).norm() > matched.inlier_distance())
            .map(|(rank, (t, _))| (transform::from_rotation_translation(&r, &t), rank))
            .collect()
    }

    /// Up to `count` global hypotheses, best first (describing and matching the clouds on first
    /// use; the time goes to `global_ms`).
    fn draw(&mut self, count: usize) -> Vec<Matrix4<f64>> {
        let p = self.prepared;
        let mut w = Stopwatch::start(self.clock);
        let params = global::GlobalParams { seed: self.seed, hypotheses: count, ..Default::default() };
        let matched = self.matched.get_or_insert_with(|| {
            // large clouds: ICP's voxelised copies stand in for their points (normalised units,
            // where the pair's larger half-extent is 1)
            let (voxel, fraction) = (f64::from_bits(p.target.sizes.voxel), params.voxel_fraction);
            let source = global::standin(&p.src_n, &p.icp_src, voxel, 1.0, fraction);
            let target = global::standin(&p.target.cloud, &p.target.icp, voxel, 1.0, fraction);
            global::Matched::onto_at(source, target, &p.target.features, fraction, self.finer)
        });
        let hypotheses = matched.hypotheses(&params).iter().map(|h| h.T_target_source).collect();
        self.global_ms += w.lap();
        hypotheses
    }

    /// The starts of the global kind `start` from `hypotheses`: each as it is
    /// ([`Start::Global`]) or refined by the network first ([`Start::GlobalNetwork`]).
    fn global(
        &mut self,
        start: Start,
        hypotheses: &[Matrix4<f64>],
        model: &Model,
        workspace: &mut ModelWorkspace,
    ) -> Result<Vec<(Start, Matrix4<f64>)>> {
        if start != Start::GlobalNetwork {
            return Ok(hypotheses.iter().map(|&t| (start, t)).collect());
        }
        self.refined_by_network(start, hypotheses, model, workspace)
    }

    /// Each of `transforms` followed by the network's estimate of the motion left after it (the
    /// network-sampled source moved by it against the target; normalised units), as starts of
    /// kind `start`; the time goes to `network_ms`.
    fn refined_by_network(
        &mut self,
        start: Start,
        transforms: &[Matrix4<f64>],
        model: &Model,
        workspace: &mut ModelWorkspace,
    ) -> Result<Vec<(Start, Matrix4<f64>)>> {
        let p = self.prepared;
        let mut w = Stopwatch::start(self.clock);
        let mut starts = Vec::with_capacity(transforms.len());
        for t in transforms {
            let apply = transform::mapping(t);
            let moved: Vec<[f32; 3]> = p.net_src.points.iter().map(|&q| apply(q)).collect();
            starts.push((start, network::estimate(model, workspace, &moved, &p.target.net.points)? * t));
        }
        self.network_ms += w.lap();
        Ok(starts)
    }
}

/// Fewest descriptor matches that must agree on a translation for [`Starts::voted_pose`].
const MIN_TRANSLATION_VOTES: usize = 8;

/// How many global hypotheses the adaptive search's last stage draws from the matches; those
/// the global stage did not use already (up to ten) become its starts (`BENCHMARK.md`, "A last
/// stage for unsure answers", has the sweep).
pub(crate) const MORE_HYPOTHESES: usize = 15;
/// A hypothesis of the last stage closer than this (degrees) and [`SAME_HYPOTHESIS_SHIFT`] to
/// one a global start already used is not refined again.
const SAME_HYPOTHESIS_DEGREES: f64 = 10.0;
/// See [`SAME_HYPOTHESIS_DEGREES`]: translations this close (normalised units).
const SAME_HYPOTHESIS_SHIFT: f64 = 0.1;

/// The [`Start::Rotations`] transforms of the prepared clouds: each of the
/// [`refine::cube_rotations`] about the source's centroid, which moves onto the target's; with a
/// shared up axis ([`Prepared::upright`]), the [`UP_ROTATIONS`] turns about the target's up
/// instead (the cube's other rotations tilt it).
fn rotations(p: &Prepared) -> Vec<Matrix4<f64>> {
    let (cs, ct) = (Vector3::from(p.src_n.centroid()), Vector3::from(p.target.centroid()));
    let place = |r: nalgebra::Matrix3<f64>| transform::from_rotation_translation(&r, &(ct - r * cs));
    match p.upright.map(|u| u.up()) {
        Some(axis) => (0..UP_ROTATIONS)
            .map(|k| {
                let angle = std::f64::consts::TAU * k as f64 / UP_ROTATIONS as f64;
                place(nalgebra::Rotation3::from_axis_angle(&axis, angle).into_inner())
            })
            .collect(),
        None => refine::cube_rotations().into_iter().map(place).collect(),
    }
}

/// With a shared up axis, how many turns about it the rotations are (every 30 degrees: ICP's
/// basin reaches about 20-30 degrees, `refine::TURN_DEGREES`).
const UP_ROTATIONS: usize = 12;

/// The [`Start::Centroids`] transform between two clouds in one frame, given their centroids: no
/// rotation, the translation taking the source's centroid onto the target's.
fn centroid_alignment(cs: [f64; 3], ct: [f64; 3]) -> Matrix4<f64> {
    Matrix4::new_translation(&nalgebra::Vector3::new(ct[0] - cs[0], ct[1] - cs[1], ct[2] - cs[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use Start::*;

    #[test]
    fn adaptive_stages_follow_the_order_of_the_starts() {
        let listed = |l: &[&[Start]]| l.iter().map(|s| Step::Listed(s.to_vec())).collect::<Vec<_>>();
        let with_blind = |l: &[&[Start]]| [listed(l), vec![Step::Blind]].concat();
        let default = [Network, Global, Centroids, Initial, Turned, TurnedInitial, RotationsNetwork];
        assert_eq!(
            stages(&default, Search::Adaptive, false),
            [
                with_blind(&[&[Network], &[Global], &[Centroids, Initial, Turned, TurnedInitial]]),
                vec![Step::Unsure(vec![RotationsNetwork])]
            ]
            .concat()
        );
        assert_eq!(crate::Options::default().starts, default.to_vec());
        assert_eq!(
            stages(&[Network, Centroids, Initial, Global], Search::Adaptive, false),
            with_blind(&[&[Network], &[Centroids, Initial], &[Global]])
        );
        assert_eq!(
            stages(&[Network, Global, Centroids, Turned], Search::Adaptive, false),
            with_blind(&[&[Network], &[Global], &[Centroids, Turned]])
        );
        assert_eq!(
            stages(&[Global, GlobalNetwork, Initial], Search::Adaptive, false),
            with_blind(&[&[Global], &[GlobalNetwork], &[Initial]])
        );
        // the starts for unsure answers come last, in a stage of their own, wherever named
        assert_eq!(
            stages(&[RotationsNetwork, Network, Rotations], Search::Adaptive, false),
            [with_blind(&[&[Network], &[Rotations]]), vec![Step::Unsure(vec![RotationsNetwork])]].concat()
        );
        assert_eq!(stages(&[RotationsNetwork], Search::Adaptive, false), vec![Step::Unsure(vec![RotationsNetwork])]);
        // the exhaustive search: the same stages, every start in them, none for unsure answers alone
        assert_eq!(
            stages(&default, Search::Exhaustive, false),
            listed(&[&[Network], &[Global], &[Centroids, Initial, Turned, TurnedInitial, RotationsNetwork]])
        );
        assert!(stages(&[], Search::Adaptive, false).is_empty());
        // with the caller's guess, it is refined in the first stage
        assert_eq!(
            stages(&default, Search::Adaptive, true),
            [
                with_blind(&[&[Network, Initial], &[Global], &[Centroids, Turned, TurnedInitial]]),
                vec![Step::Unsure(vec![RotationsNetwork])]
            ]
            .concat()
        );
        assert_eq!(stages(&[Initial, Global], Search::Adaptive, true), with_blind(&[&[Initial], &[Global]]));
        assert_eq!(stages(&[Network, Global], Search::Adaptive, true), with_blind(&[&[Network], &[Global]]));
        assert_eq!(
            stages(&default, Search::Exhaustive, true),
            stages(&default, Search::Exhaustive, false),
            "the exhaustive search refines it anyway"
        );
    }

    #[test]
    fn the_last_stage_has_blind_rotations_only_without_the_networks_turns() {
        let options = crate::Options::default();
        assert!(!blind_rotations(&kinds(&options), false));
        let off = crate::Options { network: false, ..crate::Options::default() };
        assert!(blind_rotations(&kinds(&off), false));
        assert!(!blind_rotations(&kinds(&off), true));
        assert!(blind_rotations(&[Network, Global, Turned], false));
    }
}
