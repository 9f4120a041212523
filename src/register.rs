//! The registration API: [`Options`], [`Registrar`] and its [`Registration`]. The pipeline's
//! stages (options, preparation, network, starts, search, result) are in `crate::pipeline`.

use crate::cloud::{NonFinite, PointCloud};
use crate::confidence::Evidence;
use crate::icp::IcpKind;
use crate::model::{Model, ModelWorkspace};
use crate::pipeline::starts::{self, Starts};
use crate::pipeline::{network, options, prepare, result, search};
use crate::refine::Start;
use crate::timing::{default_clock, Clock, Stopwatch};
use crate::weights::Weights;
use crate::Result;
use nalgebra::Matrix4;
use serde::{Deserialize, Serialize};

/// Options of [`Registrar::register`]. Every field has a documented default
/// ([`Options::default`]); the JS options object mirrors it field by field (camelCase).
#[allow(non_snake_case)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase", default, deny_unknown_fields)]
pub struct Options {
    /// Points per cloud fed to the network, at most [`MAX_NETWORK_POINTS`]. Default `None`: the
    /// model's N (128 for the embedded model, which was fine-tuned at 128; the `web` preset's
    /// runs start at 256).
    pub network_points: Option<usize>,
    /// Seed of every random choice (network sampling). Default 0. Same inputs + same seed = same
    /// output, bit for bit, on a given build.
    pub seed: u64,
    /// Refinement after the network. Default [`IcpKind::Plane`] (point-to-plane).
    pub icp: IcpKind,
    /// Run the network. Default `true`. With `false` the coarse estimate is the initial transform
    /// (identity unless [`Options::initial_transform`] is set) and only ICP runs: the classical
    /// baseline, or a refinement when a good initial guess is known.
    pub network: bool,
    /// ICP's final max correspondence distance, in the **user's units**. Default `None`: 0.025
    /// normalised units (2.5% of the clouds' shared half-extent). ICP runs coarse to fine at
    /// 4x, 2x and 1x this distance; `fitness` and `inlier_rmse` are measured at 1x.
    pub max_correspondence_distance: Option<f64>,
    /// Iteration cap of each ICP stage. Default 30.
    pub icp_max_iterations: u32,
    /// Voxel size for the ICP clouds, in the user's units. Default `None`: half the final max
    /// correspondence distance. `Some(0.0)` uses the full clouds.
    pub voxel_size: Option<f64>,
    /// An initial guess of `T_target_source` (4x4, user units). The network then estimates the
    /// remaining motion from there. Default `None` (identity).
    pub initial_transform: Option<[[f64; 4]; 4]>,
    /// What to do with NaN/Inf points. Default [`NonFinite::Error`].
    pub non_finite: NonFinite,
    /// The transforms ICP starts from ([`Start`]), in order of preference. Each is refined coarse
    /// to fine against the same prepared target ([`refine::refine_best`]; starts that meet on the
    /// way are merged into the earlier one) and the best is returned ([`Registration::start`] says
    /// which): the highest fitness at the final distance, ties going to the lower inlier RMSE, then
    /// to the earlier start ([`refine::choose`]). Each extra start costs one ICP run on at most
    /// [`refine::SCREEN_POINTS`] source points ([`Start::Turned`] and [`Start::TurnedInitial`] are
    /// six each; [`Start::Global`] up to five). Default `[Network, Global, Centroids, Initial,
    /// Turned, TurnedInitial]`, searched as [`Options::search`] says (the global hypotheses before
    /// the local starts: on 500 paper-protocol and 300 any-pose validation pairs the same recall
    /// but one any-pose miss, for 0.55 times the any-pose median time; `BENCHMARK.md`). On 1,000 fresh
    /// validation pairs (`arps eval`, `make-pairs --seed 1`, the model shipped before session 7)
    /// `TurnedInitial` raised recall from 0.936 to 0.947 (11 pairs gained, none lost) and cut MRE
    /// from 4.3 to 3.9 degrees, for about 1.8 times the ICP time; on session 3's model,
    /// `[Network, Centroids, Initial]` recalled 0.880 / 5.6 and `[Network]` alone 0.820 / 7.6
    /// (`BENCHMARK.md`, `models/MODEL.md`). Must be non-empty and without repeats.
    ///
    /// With `network: false`, a `Network` start is the initial transform (reported as `Initial`),
    /// and `Turned` and `TurnedInitial` both turn the initial transform (reported as `Turned`).
    /// With `icp: Off` nothing is refined or compared: the first start is the answer (choosing
    /// among unrefined starts by fitness measured worse than taking the network's).
    ///
    /// [`refine::refine_best`]: crate::refine::refine_best
    /// [`refine::choose`]: crate::refine::choose
    /// [`refine::SCREEN_POINTS`]: crate::refine::SCREEN_POINTS
    pub starts: Vec<Start>,
    /// How the starts are searched. Default [`Search::Adaptive`]: the first start alone, then the
    /// others in the order of [`Options::starts`], each run of local starts and each run of global
    /// ones ([`Start::is_global`]) a stage (with the default starts: the global ones, then the
    /// other local ones), stopping as soon as the best answer's [`Registration::confidence`]
    /// reaches [`STOP_CONFIDENCE`].
    /// [`Search::Exhaustive`] refines every start.
    pub search: Search,
}

/// How [`Options::starts`] are searched.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Search {
    /// In stages, stopping at a confident answer: the first start; then the others in order, each
    /// run of local or of global starts a stage. The best of everything refined is returned.
    #[default]
    Adaptive,
    /// Every start is refined and the best returned.
    Exhaustive,
}

/// [`Search::Adaptive`] stops once the best answer's confidence reaches this.
pub const STOP_CONFIDENCE: f64 = 0.9;

impl Default for Options {
    fn default() -> Self {
        Self {
            network_points: None,
            seed: 0,
            icp: IcpKind::Plane,
            network: true,
            max_correspondence_distance: None,
            icp_max_iterations: 30,
            voxel_size: None,
            initial_transform: None,
            non_finite: NonFinite::Error,
            starts: vec![
                Start::Network,
                Start::Global,
                Start::Centroids,
                Start::Initial,
                Start::Turned,
                Start::TurnedInitial,
            ],
            search: Search::Adaptive,
        }
    }
}

/// A stage of [`Registrar::register_with_progress`], reported as it starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Stage {
    /// Validation, normalisation, downsampling.
    Preparing,
    /// The network forward pass and the GMR solve.
    Network,
    /// ICP refinement and the quality figures (reported even with ICP off, for the figures).
    Refining,
}

/// Milliseconds spent in each stage of one registration (0 where no clock is available).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Timings {
    /// Validation, normalisation and downsampling (network points and ICP voxels).
    pub preprocess_ms: f64,
    /// The network forward pass.
    pub network_ms: f64,
    /// GMM parameters and the weighted Procrustes solve.
    pub gmr_ms: f64,
    /// ICP refinement of every start (normals, kd-tree, iterations) and the quality figures.
    pub icp_ms: f64,
    /// Global hypotheses (descriptors, matching, RANSAC); 0 when no global start ran.
    pub global_ms: f64,
    /// Everything.
    pub total_ms: f64,
}

/// The result of one registration.
#[allow(non_snake_case)]
#[derive(Clone, Debug, PartialEq)]
pub struct Registration {
    /// The answer: maps source points into the target frame (user units), after ICP.
    pub T_target_source: Matrix4<f64>,
    /// The network + GMR estimate, before ICP (user units); the initial transform with `network: false`.
    pub T_target_source_network: Matrix4<f64>,
    /// The start whose refinement is `T_target_source` (one of [`Options::starts`]).
    pub start: Start,
    /// Fraction of (voxelised) source points with a target point within the final max
    /// correspondence distance, under `T_target_source`; in [0, 1]. Measured on at most
    /// [`crate::refine::REFINE_POINTS`] of them, evenly spread.
    pub fitness: f64,
    /// RMS distance of those inlier pairs, user units (0 if there are none).
    pub inlier_rmse: f64,
    /// ICP iterations over all stages of the chosen start's refinement (0 with ICP off).
    pub icp_iterations: u32,
    /// True when the chosen start's last ICP stage met its convergence criteria (false with ICP off).
    pub icp_converged: bool,
    /// The final max correspondence distance used, user units.
    pub max_correspondence_distance: f64,
    /// Time per stage.
    pub timings: Timings,
    /// Things the caller should know (input padded, low confidence, ...).
    pub warnings: Vec<String>,
    /// The estimated probability that `T_target_source` is right, in [0, 1]
    /// ([`crate::confidence::confidence`]); below 0.5 a warning says so.
    pub confidence: f64,
    /// What the confidence is computed from.
    pub evidence: Evidence,
    /// How many distinct starts were refined (after merging).
    pub starts_refined: usize,
}

/// Holds a loaded model and reusable buffers; registers pairs of clouds.
pub struct Registrar {
    model: Model,
    weights_provenance: serde_json::Value,
    workspace: ModelWorkspace,
    clock: Option<Clock>,
}

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
        })
    }

    /// A registrar on the embedded default model ([`crate::weights::DEFAULT_MODEL`]).
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
        progress(Stage::Preparing);
        let mut watch = Stopwatch::start(self.clock);
        let mut total = Stopwatch::start(self.clock);
        let mut warnings = Vec::new();
        let resolved = options::resolve(options, &self.model)?;
        let prepared = prepare::prepare(source, target, options, &resolved, &mut warnings)?;
        let preprocess_ms = watch.lap();

        let (t_net_n, network_ms, gmr_ms) = if options.network {
            progress(Stage::Network);
            let (src, tgt) = (&prepared.net_src.points, &prepared.net_tgt.points);
            let out = self.model.forward(src, tgt, &mut self.workspace)?;
            let network_ms = watch.lap();
            let t = network::solve(&self.model, src, tgt, &out);
            (t, network_ms, watch.lap())
        } else {
            // identity in user units (relative to the initial guess), in normalised units
            (prepared.t_initial, 0.0, 0.0)
        };

        progress(Stage::Refining);
        let stages = starts::stages(&starts::kinds(options), options.search);
        let mut builder = Starts::new(&prepared, t_net_n, options.seed, self.clock);
        let chosen =
            search::search(&prepared, &stages, &mut builder, options, &self.model, &mut self.workspace, &mut warnings)?;
        let global_ms = builder.global_ms;
        let icp_ms = watch.lap();

        let timings =
            Timings { preprocess_ms, network_ms, gmr_ms, icp_ms: icp_ms - global_ms, global_ms, total_ms: total.lap() };
        result::finish(&prepared, &t_net_n, chosen, warnings, timings)
    }
}
