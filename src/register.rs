//! The registration API: [`Options`], [`Registrar`] and its [`Registration`]. The pipeline's
//! stages (options, preparation, network, starts, search, result) are in `crate::pipeline`.

use crate::cloud::{NonFinite, PointCloud};
use crate::confidence::Evidence;
use crate::icp::{IcpKind, IcpLoss};
use crate::model::{Model, ModelWorkspace};
use crate::outliers::Outliers;
use crate::pipeline::starts::{self, Starts};
use crate::pipeline::target::PreparedTarget;
use crate::pipeline::{network, options, prepare, result, search};
use crate::refine::Start;
use crate::support::Support;
use crate::timing::{default_clock, Clock, Stopwatch};
use crate::warning::WarningCode;
use crate::weights::Weights;
use crate::Result;
use nalgebra::Matrix4;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Options of a registration (`Registrar::register` in Rust, `Registrar.register` in JS). Every
/// field has a default, given in its docs. In JS and JSON the fields are camelCase
/// (`networkPoints`, `icpMaxIterations`, ...; the conventions are in the `arps::contract` module
/// docs and `js/README.md`); every field may be left out (or be `null` in JS), which takes its
/// default; unknown fields, wrong types and out-of-range values are errors naming the field.
#[allow(non_snake_case)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegisterOptions", optional_fields = nullable))]
pub struct Options {
    /// Points per cloud fed to the network (each cloud is resampled to exactly this many; a
    /// cloud with fewer points has some used twice, with a warning). Default: the model's N
    /// (`ModelConfig.nPoints`, 128 for the default model). Range: the model's minimum
    /// (`max(topH, 16)`) up to 4096 (`MAX_NETWORK_POINTS`; attention cost grows with its square).
    pub network_points: Option<usize>,
    /// Seed of every random choice (the network's point sampling, the global starts' RANSAC).
    /// Default 0. The same inputs and seed give the same output, bit for bit, on a given build.
    /// A non-negative integer (in JS a `bigint` from 2^53 on: a number that large may have been rounded).
    #[cfg_attr(feature = "ts", ts(type = "number | bigint", optional = nullable))]
    pub seed: u64,
    /// Refinement after the network: `"plane"` (point-to-plane ICP, target normals; the
    /// default), `"point"` (point-to-point ICP) or `"off"` (the network + GMR estimate is the
    /// answer). When both clouds are flat, `"plane"` runs point-to-point: every normal is the
    /// plane's, and a point-to-plane fit could not move within it.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub icp: IcpKind,
    /// Run the network. Default `true`. With `false` the coarse estimate is `initialTransform`
    /// (the identity if unset) and only ICP runs: the classical baseline, or a refinement when a
    /// good initial guess is known.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub network: bool,
    /// ICP's final maximum correspondence distance, in the clouds' units. Default: 2.5% of the
    /// clouds' shared half-extent (of the points kept: far outliers and a dropped support plane
    /// left out), or six point spacings of the sparser cloud where that is less
    /// (a dense scene: a LiDAR frame, a drone survey, an object scan of millions of points), at
    /// least three times its noise and a quarter of the 2.5% (Rust: `arps::grain`); the result's
    /// `maxCorrespondenceDistance` says which. ICP runs coarse to fine at 4x, 2x and 1x this
    /// distance; `fitness` and `inlierRmse` are measured at 1x (the confidence's evidence at the
    /// 2.5%, or at a smaller distance you give). Must be > 0, and at most the clouds' shared
    /// half-extent (beyond it every point pairs with one, whatever the pose).
    pub max_correspondence_distance: Option<f64>,
    /// Iteration cap of each of the three ICP stages. Default 30; at least 1, at most 10000
    /// (`icp: "off"` leaves ICP out). The answer's
    /// final stage, when it has not converged within the cap, runs on for up to three more
    /// rounds of as many while it still moves (a slow fit is not judged where the cap cut it;
    /// `icpConverged` says whether it converged).
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub icp_max_iterations: u32,
    /// How ICP weighs its pairs: `"robust"` (the default: each pair weighed by Tukey's biweight
    /// of its residual, so that a surface that changed between the scans, such as eroded cliffs,
    /// a new building, a dug pit, moved furniture or a bent part, no longer pulls the answer; in
    /// every stage of the refinement of `initialTransform`, which the wide stages would
    /// otherwise pull off a right guess, and in one more refinement of the search's answer, at
    /// the scale of the pairs' spread and by a graduated descent of fixed scales from half the
    /// distance down, from the answer and from `initialTransform`, so that a change within the
    /// distance, which pulled least squares far enough to spread every residual, is left out
    /// too; that pose replaces the least-squares answer only where clearly more of the source
    /// lies on the target's surfaces, so where nothing changed the answer is least squares' but
    /// for a few pairs in a hundred) or
    /// `"squared"` (every pair within the distance alike, throughout). A change over half the
    /// overlap is the scene to any robust weighting, and without a guess near the truth one that
    /// tilted the fit by about its own height is not told from the rest.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub icp_loss: IcpLoss,
    /// Voxel size of the clouds ICP works on, in the clouds' units. Default: half the final max
    /// correspondence distance, or of the default distance when `maxCorrespondenceDistance` is
    /// wider (the voxels the answer's evidence is measured on). `0` uses the full clouds, as does
    /// a size below a millionth of the clouds' shared half-extent. Must be >= 0, and at most the
    /// clouds' shared half-extent.
    pub voxel_size: Option<f64>,
    /// An initial guess of `T_target_source` (rigid, the clouds' units); the network then
    /// estimates the remaining motion from there, the adaptive search refines the guess itself
    /// (the `"initial"` start, when `starts` has it) with the first start, and of two answers that
    /// fit about as well, the one nearer the guess's rotation wins (see `starts`). An answer that
    /// turns more than 60 degrees away from the guess (`GUESS_TURN_DEG`) contradicts it: its
    /// confidence is at most 0.25, with a warning (the guess was off, or the answer is a
    /// look-alike: 30-100 probe points on a vertebra, turned over, fit 0.89-0.97 of them). An
    /// answer that puts the
    /// source farther than half its size from where the guess puts it comes with a warning (a
    /// look-alike elsewhere, when the guess placed it). Along a motion the fit leaves free
    /// (`evidence.constraint`: a jar's turn about its axis between two turntable views) the answer
    /// follows the guess, with a warning, since the clouds cannot place it there; so it does along
    /// a motion the fit barely holds (`evidence.slide`: a nearly round teapot) when the answer
    /// turned more than 10 degrees from the guess (a guess off along such a motion is then off as
    /// much, at a confidence of 0.25 or less). Default:
    /// the identity. Either 16
    /// numbers in **column-major** order (a previous result's `T_target_source`, a three.js
    /// `Matrix4.elements`; in JS also a `Float32Array` or `Float64Array`), or four **row-major**
    /// rows `[[r00, r01, r02, tx], [r10, r11, r12, ty], [r20, r21, r22, tz], [0, 0, 0, 1]]`. A
    /// non-rigid or non-finite matrix is an error; with `sourceScale`, its 3x3 part is a rotation
    /// times that factor, as the result's is. (In Rust: four row-major rows.)
    #[serde(with = "crate::contract::initial_transform")]
    #[cfg_attr(feature = "ts", ts(type = "ArrayLike<number> | number[][] | null", optional = nullable))]
    pub initial_transform: Option<[[f64; 4]; 4]>,
    /// What to do with points that have a NaN or infinite coordinate, or one beyond 1e18 from the
    /// cloud's origin (where the engine's `f32` distances overflow: a sensor's `f32::MAX` for "no
    /// return"): `"error"` (an error naming the first bad point; the default) or `"drop"` (ignore
    /// them, e.g. PCD "no return" points).
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub non_finite: NonFinite,
    /// What to do with points that lie far out from the rest of their cloud (stray returns,
    /// reflections: outside the box of the points whose few nearest neighbours are close, and
    /// with no others around them): `"drop"` (leave them out, with a warning that counts them;
    /// the default) or `"keep"`. A few such points would otherwise inflate the bounding box that
    /// the clouds are normalised by. A cloud without them is used exactly as given either way.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub outliers: Outliers,
    /// What to do with a support plane, the table or floor under a scanned object: `"drop"` (leave
    /// it out of each cloud that stands on one, with a warning that counts its points; the default)
    /// or `"keep"`. A support plane holds a tenth or more of its cloud, has nearly all the rest of
    /// the cloud on one side, reaches out beyond what stands on it on at least three sides (with at
    /// least 30% of its points outside the footprint of the rest), and is one layer (a sheet's two
    /// faces are not a table; nor is a plane with the object's own bottom face sampled just above
    /// it, which no capture of an object on a table sees). At least a tenth of the cloud stands off
    /// it, or a hundredth when the other cloud stands on a support plane: a view that is nearly all
    /// table around a small object loses its table when the other view does, and both are left out.
    /// Left in a scan registered onto a model of the object, it sets the clouds' scale and the
    /// object's flat faces are drawn onto it; between two scans it pulls the answer towards the
    /// table's motion, which differs from the object's when the object was tipped or turned over
    /// between them. Keep it for two scans of an object that stood still on its table, where the
    /// shared table helps.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub support_plane: Support,
    /// The direction that is up in both clouds' frames, when both were captured level: scans
    /// from a phone or a terrestrial scanner (gravity-aligned), survey data, a CAD model in its
    /// upright pose (`[0, 0, 1]` for z-up data, `[0, 1, 0]` for three.js's y-up). The answer then
    /// only turns the source about this axis, within [`UP_TOLERANCE_DEG`] of tilt for scans
    /// levelled a little differently: every start is levelled first (its tilt off `up` taken
    /// out, ICP then finds the small tilt between the scans; with `icp: "off"` the answer is
    /// the levelled start, so leave `up` out to judge a pose as given), answers tilted further are
    /// rejected, and look-alikes tilted further do not count as alternatives; the answer turned
    /// a quarter and a half turn about up, each placed where the global descriptors' matches
    /// agree, is refined too (a box-like room captured from another spot fits its turns about as
    /// well), and counts as an alternative or replaces the answer when it fits about as well or
    /// clearly better. When a rejected,
    /// tilted answer fits clearly better than the upright one, `up` probably does not hold: a
    /// warning says so and the confidence is at most 0.25. It is the same direction in both
    /// clouds' frames, whatever `initialTransform` says. Default: none (any rotation). Three
    /// finite numbers, not all zero (any length).
    #[serde(with = "crate::contract::up")]
    #[cfg_attr(feature = "ts", ts(as = "Option<[f64; 3]>", optional = nullable))]
    pub up: Option<[f64; 3]>,
    /// The share of the source that lies on the target once aligned, when the caller knows it:
    /// `1` for a scan of an object onto a complete model of it (a CAD part read as its surface),
    /// or a frame onto a map that covers everything the frame sees; less where the source also
    /// holds what the target lacks (clutter around the part, people in the frame, what lies beyond
    /// the map's edge). Default: none (unknown, as between two partial views, which may overlap by
    /// any share). With it, an answer under which clearly less of the source lies near the target
    /// (its share within twice the distance the answer is judged at, `evidence.fitnessLoose`,
    /// below `sourceOverlap - 0.15`) is not taken as sure: the adaptive search goes on as for an
    /// unsure answer, and when the answer still falls short its confidence is at most 0.25, with a
    /// warning that gives the share (the wrong model, a mirror-image export, a scale or unit
    /// error, points the target lacks left in the source, or a pose the search did not find).
    /// With it, the source's mirror images are also refined from the answer: when one fits
    /// clearly better, the confidence is at most 0.25, with a warning (a mirrored part, an export
    /// with one axis flipped). A number in (0, 1].
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub source_overlap: Option<f64>,
    /// The factor that takes the source's coordinates into the target's unit, when they differ:
    /// `1000` for a scan in metres onto a model in millimetres, `0.001` the other way, `0.0254`
    /// for inches onto metres. The source's points are multiplied by it before anything else;
    /// every distance (`maxCorrespondenceDistance`, `voxelSize`, the result's `inlierRmse`) is then
    /// in the target's unit. `T_target_source` (the result's, its alternatives' and
    /// `initialTransform`) still maps the source's points **as given** into the target frame: its
    /// 3x3 part is the rotation times this factor, so three.js's `matrix.fromArray` places the
    /// source object and `transformFile` moves the source's file as they are. Default: none (the
    /// same unit, a factor of 1). A finite number > 0.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub source_scale: Option<f64>,
    /// The transforms ICP starts from, in order of preference. Each is refined coarse to fine
    /// against the same prepared target and the best is returned (the result's `start` says
    /// which): the highest `fitness`, ties going to the lower `inlierRmse`, then to the earlier
    /// start; but of two answers whose fitness is within 10% and whose turns away from
    /// `initialTransform` (the identity if unset) differ by more than 60 degrees, the one that
    /// turns less (a near-symmetric shape's half turn fits about as well as the truth; the
    /// smaller motion is the likelier). Starts that meet during refinement are refined once, as
    /// the earlier; on large clouds the starts are compared on 2048 of the source points and only
    /// the winner is refined on 8192 of them. Which starts are refined at all depends on
    /// `search`. Default `["network", "global", "centroids", "initial", "turned",
    /// "turnedInitial", "rotationsNetwork"]`; each extra start costs one ICP run on at most 2048
    /// points (`"turned"` and `"turnedInitial"` are six each, `"global"` and `"globalNetwork"` up
    /// to five each, plus the descriptor matching, `"rotations"` 24, `"rotationsNetwork"` 24 and
    /// as many network passes), so `["network"]` is the fastest, and the least sure: when the
    /// network turns the source wrong (a half turn), no other start corrects it, and the
    /// confidence may not tell (two vehicle LiDAR sweeps at a 20-degree turn came back turned over
    /// at 0.98). Must be non-empty, without repeats.
    /// - `"network"`: the network + GMR estimate (with `network: false`, the initial transform,
    ///   reported as `"initial"`);
    /// - `"centroids"`: `initialTransform`'s rotation (none if unset) with the translation that
    ///   moves the source's centroid onto the target's;
    /// - `"initial"`: `initialTransform` itself (the identity if unset);
    /// - `"turned"`: six starts, the network estimate (the initial transform with
    ///   `network: false`) turned 45 degrees both ways about each axis through the source's
    ///   centroid, for estimates that landed outside ICP's basin;
    /// - `"turnedInitial"`: six starts, `initialTransform` (the identity if unset) turned the same
    ///   way, for pairs where the network's estimate is far off (with `network: false`, the same
    ///   starts as `"turned"`, reported as `"turned"`);
    /// - `"global"`: up to five hypotheses from global registration (FPFH descriptors, mutual
    ///   matches, a seeded RANSAC), for motions of any size, e.g. scans in unrelated frames; none
    ///   when the descriptors match too little;
    /// - `"globalNetwork"`: the `"global"` hypotheses, each refined by the network first (with
    ///   `network: false`, the same starts as `"global"`, reported as `"global"`);
    /// - `"rotations"`: 24 starts, the source's centroid moved onto the target's and turned by
    ///   each rotation of a cube onto itself (after `initialTransform`'s rotation): a blind
    ///   search over every orientation, for shapes whose descriptors match poorly (repetitive,
    ///   smooth or symmetric ones). Not in the default list; the adaptive search adds them to its
    ///   last stage (see `search`);
    /// - `"rotationsNetwork"`: the `"rotations"` turns, each refined by the network first (it
    ///   estimates the motion left after the turn; every orientation is within about 63 degrees
    ///   of one of them): a search over every orientation that, unlike the blind one, lands near
    ///   the truth where ICP alone would not. The adaptive search refines them only for an answer
    ///   still unsure (confidence below 0.5) after every other stage (see `search`). It needs the
    ///   network: with `network: false` it is left out, and naming it alone is an error.
    ///
    /// The refined answer is then probed for poses that fit about as well (the `confidence`'s
    /// turns, `evidence.ambiguity`); when one fits better (typically the answer flipped about an
    /// axis of an elongated shape), it is refined like one more start, reported under the start
    /// it came from, and kept if it fits best. While the answer's confidence is below 0.95, a
    /// stage's best that does not replace it is probed too, since its flip may. When either cloud
    /// has many points (see `search`), the stages before the global one are probed only once it
    /// has run: the better of their answer and its answer first.
    ///
    /// With `icp: "off"` nothing is refined or compared: the first start is the answer.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub starts: Vec<Start>,
    /// How `starts` are searched. Default `"adaptive"`: in stages, stopping as soon as the best
    /// answer's `confidence` reaches 0.95 (`STOP_CONFIDENCE`): the first start alone (with
    /// `initialTransform` given, and `"initial"` in `starts`, with that start); then the
    /// others in order, each run of local starts or of global ones (`"global"`,
    /// `"globalNetwork"`) one stage (with the default starts: the global ones, then the other
    /// local ones). When every stage has run without reaching 0.95 and `starts` has a global
    /// kind, a last stage refines up to ten more global hypotheses (the next best of a second,
    /// larger RANSAC draw on the same descriptor matches) and the 24 `"rotations"` starts
    /// (unless `starts` names them), of which the 12 that fit best after a short ICP run each
    /// are refined; so only the pairs no stage settled pay for them. Its starts are blind, so its
    /// best replaces the answer only when it fits more than 10% better. An answer whose
    /// confidence reaches 0.85 once the global stage has run (`NEARLY_SURE_CONFIDENCE`), or 0.5
    /// when the global stage's best hypothesis, refined, is that same pose (`AGREED_CONFIDENCE`),
    /// skips the stages left, and its last stage refines only the 3 best of those further
    /// hypotheses. Then, when `starts` has `"rotationsNetwork"` and the answer's confidence is
    /// still below 0.5 (`UNSURE_CONFIDENCE`), those starts are refined, as one more stage whose
    /// best replaces the answer only when it fits more than 15% better (it searches every
    /// orientation, where a look-alike can fit a few percent better than the truth); so only the
    /// answers the engine would otherwise flag as unsure pay for their network passes. Once a
    /// global stage has run, the answer's rotation with the translation the descriptor matches
    /// agree on for it is refined as one more start when that translation is another one, and
    /// replaces the answer when it fits more than 10% better (an answer slid along a wall, its
    /// rotation right); so is, at the final distance only, the answer's rotation at the next
    /// translation they agree on, when it already fits half as well as the answer (the other of
    /// two alike parts side by side, such as identical pipe spools: an alternative when it fits
    /// about as well). Then, when most of the source lies on thin walls (another face parallel
    /// to its own within ten final distances), the answer moved onto those other faces is
    /// refined at the final distance, and replaces it when it fits better, its points no farther
    /// (a one-view scan of sheet metal settled on the inner faces); one that fits alike comes
    /// with a warning, as a flat sheet's two faces cannot be told apart. `"exhaustive"` refines every start, in the same stages (the starts for
    /// unsure answers in their place in `starts`), each stage's best judged as above, without
    /// the stops and without those last stages. The result's `startsRefined` says how many were
    /// refined.
    #[cfg_attr(feature = "ts", ts(optional = nullable))]
    pub search: Search,
}

/// How the options' `starts` are searched (see `search`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationSearch"))]
pub enum Search {
    /// In stages, stopping at a confident answer: the first start; then the others in order, each
    /// run of local or of global starts a stage (of the global hypotheses, the best after a short
    /// ICP run and those whose short run comes near the answer's so far); then, while the answer
    /// is still below the stop (0.95), more global hypotheses (and blind rotations, unless the
    /// starts name [`Start::RotationsNetwork`], which search every orientation better); an answer
    /// at 0.85 or more once the global stage has run ([`NEARLY_SURE_CONFIDENCE`]), or at 0.5 or
    /// more when the global stage found it again ([`AGREED_CONFIDENCE`]), skips the stages left
    /// and gets only a few more global hypotheses, those whose short run comes near its fit; an
    /// answer still below [`UNSURE_CONFIDENCE`] (0.5) then gets the starts for unsure answers
    /// ([`Start::RotationsNetwork`]) when the starts name them. When either cloud has many points
    /// (at least 3,000, [`GLOBAL_BEFORE_STOP_POINTS`]: scans, or a scan onto a model) it does not
    /// stop before the global stage. Once the global stage has run, the answer's rotation with the
    /// translation the descriptor matches agree on for it ([`crate::global::translation`]) is one
    /// more start, which replaces the answer when it fits clearly better.
    /// The best of everything refined is returned. Easy pairs cost one start; hard ones get every
    /// start and more.
    #[default]
    Adaptive,
    /// Every start is refined and the best returned (slower, never stops early): the adaptive
    /// search's stages of the starts, each stage's best judged by the probes as there (so both
    /// count the same look-alikes as alternatives), all of them run, without its last stages.
    Exhaustive,
    /// Every start is refined and the best returned, and nothing moves it after: a pose the
    /// confidence's probes find that fits better (the answer turned over, say) is refined and
    /// offered among the alternatives, with a warning, instead of replacing the answer (the
    /// answer is then at most 0.5 sure); no stages after the starts'. Its ICP stages start at
    /// [`crate::refine::SCHEDULE`]'s multiples of the final distance even when that is tighter
    /// than the default (the other searches start from the default distance), so that a start
    /// moves only as far as the caller's distance reaches: a survey swath hanging past the
    /// reference's edge is not pulled onto it. With `starts: ["initial"]` and
    /// `initialTransform`, a refinement of the caller's guess alone: a tracking or survey pose
    /// that a look-alike with more overlap would otherwise replace (a room's quarter turn,
    /// stations stacked along a tunnel, a swath one sand wave on).
    Local,
}

/// [`Search::Adaptive`] stops once the best answer's confidence reaches this: high enough that a
/// confidently wrong answer of the first start rarely ends the search (`BENCHMARK.md` has the
/// measurements behind the value).
pub const STOP_CONFIDENCE: f64 = 0.95;

/// [`Search::Adaptive`] refines the starts for unsure answers ([`Start::is_for_unsure`]:
/// `"rotationsNetwork"`) only while the answer's confidence after every other stage is below
/// this, the confidence's own line between right and wrong (`BENCHMARK.md`, "The network from
/// every orientation, for unsure answers").
pub const UNSURE_CONFIDENCE: f64 = 0.5;

/// When the best answer's confidence reaches this once a global stage (`"global"`,
/// `"globalNetwork"`) has run, [`Search::Adaptive`] skips the stages left and the blind rotations:
/// the answer has been weighed against independent hypotheses from the descriptors, and only a
/// few more of those are refined in its last stage. Right answers on clouds that share no
/// samples (every real scan pair) mostly score between this and [`STOP_CONFIDENCE`]
/// (`BENCHMARK.md`, "Nearly sure after the global stage").
pub const NEARLY_SURE_CONFIDENCE: f64 = 0.85;

/// When the global stage of [`Search::Adaptive`] finds the answer again (its best hypothesis,
/// refined, is the same pose as the network's or an earlier stage's answer) and that answer's
/// confidence is at least this (not flagged), it counts as nearly sure
/// ([`NEARLY_SURE_CONFIDENCE`]): two independent estimates agree, and the stages left would
/// mostly only find its look-alikes (`BENCHMARK.md`, "Agreement with the global stage").
pub const AGREED_CONFIDENCE: f64 = 0.5;

/// With [`Options::up`], the most an answer may tilt the source's up away from the target's,
/// degrees: enough for scans levelled a little differently (a phone's gravity estimate, a tripod
/// off level), small against the half turns about a horizontal axis that it rules out.
pub const UP_TOLERANCE_DEG: f64 = 10.0;

/// With [`Options::initial_transform`], an answer that turns more than this many degrees away
/// from it contradicts the guess (the guess was off, or the answer is a look-alike that fits a
/// sparse or partial source about as well): its confidence is at most 0.25, with a warning. ICP's
/// basin reaches 20-30 degrees and the `turnedInitial` starts 45 about the guess; a guess that
/// close is what a caller gives one for.
pub const GUESS_TURN_DEG: f64 = 60.0;

/// When either cloud has at least this many points, [`Search::Adaptive`] does not stop before
/// its global stage has run, however sure an earlier answer is: the confidence is calibrated on
/// sparse, noisy samples (1,024 points per cloud) and is measured to be too sure of wrong answers
/// on denser, cleaner clouds, and of a small scan placed on the wrong part of a large model,
/// where the global descriptors are also the more informative (`BENCHMARK.md`, "Dense scans"
/// and "A scan onto a model").
pub const GLOBAL_BEFORE_STOP_POINTS: usize = 3_000;

impl Default for Options {
    fn default() -> Self {
        Self {
            network_points: None,
            seed: 0,
            icp: IcpKind::Plane,
            network: true,
            max_correspondence_distance: None,
            icp_max_iterations: 30,
            icp_loss: IcpLoss::Robust,
            voxel_size: None,
            initial_transform: None,
            non_finite: NonFinite::Error,
            outliers: Outliers::Drop,
            support_plane: Support::Drop,
            up: None,
            source_overlap: None,
            source_scale: None,
            starts: vec![
                Start::Network,
                Start::Global,
                Start::Centroids,
                Start::Initial,
                Start::Turned,
                Start::TurnedInitial,
                Start::RotationsNetwork,
            ],
            search: Search::Adaptive,
        }
    }
}

/// A stage of a registration, reported as it starts (to `Registrar::register_with_progress`'s
/// callback in Rust, to `onProgress` in JS, as `"preparing"`, `"network"`, `"refining"`); stages
/// that do not run are skipped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationStage"))]
pub enum Stage {
    /// Validation, normalisation, downsampling.
    Preparing,
    /// The network forward pass and the GMR solve (skipped with `network: false`).
    Network,
    /// ICP refinement of the starts (and the global starts' descriptors and RANSAC), and the
    /// quality figures (reported even with ICP off, for the figures).
    Refining,
}

/// Milliseconds spent in each stage of one registration (0 where no clock is available; in JS
/// measured with `performance.now()`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationTimings"))]
pub struct Timings {
    /// Validation, normalisation, network sampling and ICP voxel downsampling.
    pub preprocess_ms: f64,
    /// The network's forward passes: its estimate's, and those (with their GMR solves) of the
    /// starts it refines first, `"globalNetwork"` and `"rotationsNetwork"` (0 with
    /// `network: false`).
    pub network_ms: f64,
    /// GMM parameters and the weighted Procrustes solve.
    pub gmr_ms: f64,
    /// ICP from every start (normals, kd-tree, iterations) and the quality figures.
    pub icp_ms: f64,
    /// Global hypotheses (descriptors, matching, RANSAC); 0 when no global start ran.
    pub global_ms: f64,
    /// The whole registration inside the engine.
    pub total_ms: f64,
}

/// The result of one registration. In JS (`Registrar.register`) and JSON (`arps register
/// --json`) it is a plain object with these fields in camelCase, the transforms as 16
/// column-major numbers (the conventions are in the `arps::contract` module docs and
/// `js/README.md`); safe to `postMessage`, `structuredClone` or `JSON.stringify`.
#[allow(non_snake_case)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationResult"))]
pub struct Registration {
    /// The answer, `T_target_source`: the rigid transform that maps source points into the
    /// target frame (`p_target = R p_source + t`), in the clouds' units, after ICP (with the
    /// options' `sourceScale` `s`, `p_target = s R p_source + t`: the source as given). In JS and
    /// JSON 16 numbers in **column-major** order (element (row r, col c) at index `c * 4 + r`),
    /// ready for three.js: `sourceObject.matrix.fromArray(result.T_target_source)`.
    #[serde(rename = "T_target_source", with = "crate::contract::column_major")]
    #[cfg_attr(feature = "ts", ts(type = "number[]"))]
    pub T_target_source: Matrix4<f64>,
    /// The coarse estimate before ICP (network + GMR, or `initialTransform` with
    /// `network: false`); same frames and layout as `T_target_source`.
    #[serde(rename = "T_target_source_network", with = "crate::contract::column_major")]
    #[cfg_attr(feature = "ts", ts(type = "number[]"))]
    pub T_target_source_network: Matrix4<f64>,
    /// The start (one of the options' `starts`) whose refinement is `T_target_source`.
    pub start: Start,
    /// Fraction of (voxelised) source points that have a target point within
    /// `maxCorrespondenceDistance` under `T_target_source`, in [0, 1]. Right answers on partial,
    /// independently sampled scans often score only 0.15-0.3: judge the result by `confidence`.
    /// Measured on at most 8192 source points, evenly spread.
    pub fitness: f64,
    /// RMS distance of those inlier pairs, in the clouds' units (0 when there are none).
    pub inlier_rmse: f64,
    /// ICP iterations over all stages of the chosen start's refinement (0 with `icp: "off"`).
    pub icp_iterations: u32,
    /// True when the chosen start's last ICP stage met its convergence criteria (false with
    /// `icp: "off"`).
    pub icp_converged: bool,
    /// The final max correspondence distance used, in the clouds' units (the default resolved).
    pub max_correspondence_distance: f64,
    /// Time per stage, in milliseconds.
    pub timings: Timings,
    /// Things to know about this result (input resampled, low confidence, ...), as sentences
    /// for people. One starting with `"low confidence"` comes with every result whose
    /// `confidence` is below 0.5. Test for a kind of warning with `warning_codes`, not by
    /// matching these sentences: they name figures, and may be reworded.
    pub warnings: Vec<String>,
    /// The kind of each warning, in the same order as `warnings` (`warning_codes[i]` is the
    /// kind of `warnings[i]`): what code tests for (`warningCodes.includes("sizeMismatch")`).
    /// Every result whose `confidence` is below 0.5 holds [`WarningCode::LowConfidence`].
    pub warning_codes: Vec<WarningCode>,
    /// An estimate of the probability that `T_target_source` is right (within the evaluation's
    /// recall thresholds), in [0, 1]: a logistic model over `evidence`, calibrated on validation
    /// pairs (`arps::confidence`). Read it as "likely right" near 1, "likely wrong" near 0; below
    /// 0.5 `warnings` says the alignment may be wrong. It judges the fit and whether the fit is
    /// unique: on a symmetric or featureless shape where other poses fit about as well
    /// (`evidence.alternatives`, `evidence.ambiguity`, `evidence.slide`) it is low even when the
    /// answer happens to be right, since nothing in the clouds tells the poses apart.
    pub confidence: f64,
    /// The figures `confidence` is computed from, measured under `T_target_source`.
    pub evidence: Evidence,
    /// How many distinct starts were refined (after merging those that met), counting the
    /// probe poses refined as starts (see the options' `starts`); see the options' `search`.
    pub starts_refined: usize,
    /// Other poses that fit about as well as `T_target_source` (at least 0.9 of its fitness when
    /// found, by the confidence's probes or by the search, more than 15 degrees from it and from
    /// each other, or as turned but placing the source more than 0.2 of the clouds' half-extent
    /// away: a facade's next window bay), each refined like the answer, the best fitting first;
    /// empty when the fit is unique. One may fit a little better than the answer, which the search
    /// chose among near ties by its turn; one that leaves less than half as much of the source off
    /// the target becomes the answer. On a symmetric shape the right pose is often one of these
    /// rather than the answer, and nothing in the clouds tells them apart: an application can offer
    /// them to its user. `evidence.alternatives` counts those of the probes or of the search,
    /// whichever found more (the confidence's input), so this list can be longer; a refinement that
    /// brings a pose back onto the answer or onto another drops it, so it can also be shorter.
    #[serde(default)]
    pub alternatives: Vec<Alternative>,
    /// The motions the fit leaves free, weakest held first; empty when the fit pins every motion.
    /// Along each, the surfaces keep the source on the target (a surface of revolution turned about
    /// its axis, a straight pipe, tunnel or extrusion slid along itself, a plane slid or turned in
    /// itself), or nearly (small features repeated along it: holes on a bolt circle, a gear's
    /// teeth), so only where the clouds' edges fall, or those features, holds the answer there, and
    /// it may be off along it: what the warning `"freeMotion"` names in words, as numbers an
    /// application can draw or constrain (with a guess, `initialTransform`, the answer follows the
    /// guess along them: `"heldByGuess"`).
    #[serde(default)]
    pub free_motions: Vec<FreeMotion>,
}

/// A motion the fit leaves free (one of the result's `freeMotions`): a turn about an axis or a
/// slide along a direction, in the target's frame and units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationFreeMotion"))]
pub struct FreeMotion {
    /// A turn about an axis, or a slide.
    pub kind: FreeMotionKind,
    /// The turn's axis or the slide's direction: a unit vector in the target's frame (either
    /// sign: the motion is free both ways).
    pub direction: [f64; 3],
    /// For a turn, the point of its axis nearest the fitted points' centroid; for a slide, that
    /// centroid (where to draw it); in the target's frame (with its origin: map-grid coordinates
    /// as given).
    pub through: [f64; 3],
}

/// What a [`FreeMotion`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS))]
pub enum FreeMotionKind {
    /// A turn about the axis along `direction` through `through`.
    Turn,
    /// A slide along `direction`.
    Slide,
}

/// Another pose that fits about as well as the answer (one of the result's `alternatives`):
/// frames, units and layout as the answer's.
#[allow(non_snake_case)]
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationAlternative"))]
pub struct Alternative {
    /// The pose, `T_target_source`, in the clouds' units; in JS and JSON 16 numbers in
    /// column-major order, like the answer's.
    #[serde(rename = "T_target_source", with = "crate::contract::column_major")]
    #[cfg_attr(feature = "ts", ts(type = "number[]"))]
    pub T_target_source: Matrix4<f64>,
    /// Its fitness, measured like the answer's `fitness`.
    pub fitness: f64,
    /// Its inlier RMSE, measured like the answer's `inlierRmse`, in the clouds' units.
    pub inlier_rmse: f64,
}

/// Holds a loaded model and reusable buffers; registers pairs of clouds.
///
/// It keeps the last target it prepared (normalised, voxelised, with its k-d tree and the normals
/// and descriptors found so far): a registration onto the same target (the same points and
/// origin) reuses it when the target is at least as large as the source (largest bounding-box
/// half-extent, each in its own frame: the normalisation's scale is then the target's), redoing
/// only what other options change, with the same result; so many close-ups or local captures
/// registered onto one model or map prepare it once. It holds the normalised target (12 bytes a
/// point) and ICP's voxelised copy with its k-d tree and normals until the next registration onto
/// another target, or [`Registrar::forget_target`].
///
/// A registration runs on the calling thread; the engine starts no threads of its own. A
/// `Registrar` is `Send` and `Sync`: a batch job can give each thread its own (each holds its own
/// copy of the model's weights), or move one between threads; [`Registrar::register`]
/// takes `&mut self`, so threads that share one take turns (a `Mutex`). The same input and
/// options give the same result on any thread.
pub struct Registrar {
    model: Model,
    weights_provenance: serde_json::Value,
    workspace: ModelWorkspace,
    clock: Option<Clock>,
    /// The last target prepared ([`crate::pipeline::target`]).
    target: Option<Box<PreparedTarget>>,
}

// what the docs promise a batch job: a registrar moves to and is shared between threads
const _: fn() = || {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Registrar>();
};

/// Most points per cloud the network may be given: attention costs grow with its square
/// (4096 points take seconds in WebAssembly; the shipped model was trained on 256, then 128).
pub const MAX_NETWORK_POINTS: usize = 4096;

impl Registrar {
    /// A registrar for given weights.
    pub fn new(weights: &Weights) -> Result<Self> {
        Ok(Self {
            model: Model::from_weights(weights)?,
            weights_provenance: weights.provenance.clone(),
            workspace: ModelWorkspace::default(),
            clock: default_clock(),
            target: None,
        })
    }

    /// A registrar on the embedded default model ([`crate::weights::DEFAULT_MODEL`]; feature
    /// `embed-model`, on by default).
    #[cfg(feature = "embed-model")]
    pub fn with_default_model() -> Result<Self> {
        Self::from_bytes(crate::weights::DEFAULT_MODEL)
    }

    /// A registrar from weights-file bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        Self::new(&Weights::from_bytes(bytes)?)
    }

    /// Replaces the clock used for [`Timings`] (the wasm binding passes `performance.now`).
    pub fn set_clock(&mut self, clock: Option<Clock>) {
        self.clock = clock;
    }

    /// Drops the target kept from the last registration (see [`Registrar`]), giving its memory
    /// back; the next registration prepares its target anew.
    pub fn forget_target(&mut self) {
        self.target = None;
    }

    /// The network.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// How the loaded weights were made.
    pub fn provenance(&self) -> &serde_json::Value {
        &self.weights_provenance
    }

    /// Registers `source` onto `target`: returns `T_target_source` and quality figures.
    /// The clouds may be in any unit (the same for both) and any size >= 16 points.
    #[allow(non_snake_case)]
    pub fn register(&mut self, source: &PointCloud, target: &PointCloud, options: &Options) -> Result<Registration> {
        self.register_with_progress(source, target, options, &mut |_| {})
    }

    /// [`Registrar::register`], calling `progress` as each stage starts (for progress bars and
    /// worker messages). The calls come in [`Stage`] order; stages that do not run are skipped.
    #[allow(non_snake_case)]
    pub fn register_with_progress(
        &mut self,
        source: &PointCloud,
        target: &PointCloud,
        options: &Options,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<Registration> {
        self.register_cow(Cow::Borrowed(source), Cow::Borrowed(target), options, progress)
    }

    /// [`Registrar::register_with_progress`] that stops early and returns [`crate::Error::Cancelled`]
    /// once `cancel` is cancelled (from another thread: a deadline, a client that went away; see
    /// [`crate::cancel`]); at once when it already is. The registrar stays usable, and a call
    /// that is not cancelled gives the same answer as [`Registrar::register`].
    pub fn register_cancellable(
        &mut self,
        source: &PointCloud,
        target: &PointCloud,
        options: &Options,
        progress: &mut dyn FnMut(Stage),
        cancel: &crate::Cancel,
    ) -> Result<Registration> {
        if cancel.is_cancelled() {
            return Err(crate::Error::Cancelled);
        }
        let result = crate::cancel::during(cancel, || {
            self.register_cow(Cow::Borrowed(source), Cow::Borrowed(target), options, progress)
        });
        if cancel.is_cancelled() {
            // what a stopped search found is not an answer; the target it prepared stays valid
            return Err(crate::Error::Cancelled);
        }
        result
    }

    /// [`Registrar::register_with_progress`] on clouds the caller hands over: their points become
    /// the validated clouds without a copy (the wasm binding's, which it made for the call).
    #[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
    pub(crate) fn register_owned_with_progress(
        &mut self,
        source: PointCloud,
        target: PointCloud,
        options: &Options,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<Registration> {
        self.register_cow(Cow::Owned(source), Cow::Owned(target), options, progress)
    }

    /// The registration itself, on the caller's clouds or on clouds handed over.
    fn register_cow(
        &mut self,
        source: Cow<'_, PointCloud>,
        target: Cow<'_, PointCloud>,
        options: &Options,
        progress: &mut dyn FnMut(Stage),
    ) -> Result<Registration> {
        progress(Stage::Preparing);
        let mut watch = Stopwatch::start(self.clock);
        let mut total = Stopwatch::start(self.clock);
        let mut warnings = Vec::new();
        let resolved = options::resolve(options, &self.model)?;
        // the target kept from the last call is reused when it is this one (and dropped first
        // otherwise, before this one is prepared)
        let kept = self.target.take();
        let prepared = prepare::prepare(source, target, options, &resolved, kept, &mut warnings)?;
        let preprocess_ms = watch.lap();

        let (t_net_n, network_ms, gmr_ms) = if options.network {
            progress(Stage::Network);
            let (src, tgt) = (&prepared.net_src.points, &prepared.target.net.points);
            let out = self.model.forward(src, tgt, &mut self.workspace)?;
            let network_ms = watch.lap();
            let t = network::solve(&self.model, src, tgt, &out);
            (t, network_ms, watch.lap())
        } else {
            // identity in user units (relative to the initial guess), in normalised units
            (prepared.t_initial, 0.0, 0.0)
        };

        progress(Stage::Refining);
        let stages = starts::stages(&starts::kinds(options), options.search, options.initial_transform.is_some());
        let mut builder = Starts::new(&prepared, t_net_n, options.seed, self.clock);
        let chosen =
            search::search(&prepared, &stages, &mut builder, options, &self.model, &mut self.workspace, &mut warnings)?;
        let (global_ms, starts_network_ms) = (builder.global_ms, builder.network_ms);
        let icp_ms = watch.lap() - global_ms - starts_network_ms;
        let network_ms = network_ms + starts_network_ms;

        let timings = Timings { preprocess_ms, network_ms, gmr_ms, icp_ms, global_ms, total_ms: total.lap() };
        let registration = result::finish(&prepared, &t_net_n, chosen, warnings, timings);
        self.target = Some(prepared.target);
        registration
    }
}
