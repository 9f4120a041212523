//! The registration pipeline: normalise, sample, network, GMR, ICP, de-normalise.

use crate::cloud::{JointNormalization, NonFinite, PointCloud, MIN_POINTS};
use crate::confidence::{self, Evidence};
use crate::icp::{IcpKind, IcpTarget};
use crate::model::{Model, ModelWorkspace};
use crate::refine::{self, Candidate, Refinement, Start};
use crate::timing::{default_clock, Clock, Stopwatch};
use crate::weights::Weights;
use crate::{checks, global, gmr, limits, origin, sampling, transform, Error, Result};
use nalgebra::{Matrix3, Matrix4, Vector3};
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
    /// six each; [`Start::Global`] up to five). Default `[Network, Centroids, Initial, Turned,
    /// TurnedInitial, Global]`, searched as [`Options::search`] says. On 1,000 fresh
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
    pub starts: Vec<Start>,
    /// How the starts are searched. Default [`Search::Adaptive`]: the first start alone, then the
    /// other local starts, then the global ones ([`Start::is_global`]), stopping as soon as the
    /// best answer's [`Registration::confidence`] reaches [`STOP_CONFIDENCE`].
    /// [`Search::Exhaustive`] refines every start.
    pub search: Search,
}

/// How [`Options::starts`] are searched.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Search {
    /// In stages, cheapest first, stopping at a confident answer: the first start; then the other
    /// local starts; then the global starts. The best of everything refined is returned.
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
                Start::Centroids,
                Start::Initial,
                Start::Turned,
                Start::TurnedInitial,
                Start::Global,
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
    /// correspondence distance, under `T_target_source`; in [0, 1].
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
/// Default final ICP distance in normalised units.
const DEFAULT_MAX_CORRESPONDENCE: f64 = 0.025;
/// Ratio of the clouds' sizes (largest half-extents) above which a warning says they may be in
/// different units. A partial scan of an object is smaller than a model of the whole, but not by
/// this much; metres against millimetres is 1000.
const SIZE_RATIO_WARNING: f64 = 10.0;

/// Confidence below which a warning says the alignment may be wrong.
const LOW_CONFIDENCE: f64 = 0.5;

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
        let n_net = options.network_points.unwrap_or(self.model.config.n_points);
        if n_net < self.model.min_points() || n_net > MAX_NETWORK_POINTS {
            return Err(Error::InvalidOption(format!(
                "networkPoints = {n_net} is outside {}..={MAX_NETWORK_POINTS} for this model",
                self.model.min_points()
            )));
        }
        if options.icp_max_iterations > 10_000 {
            return Err(Error::InvalidOption(format!(
                "icpMaxIterations = {} is more than 10000",
                options.icp_max_iterations
            )));
        }
        refine::check_starts(&options.starts)?;
        limits::check_cloud_points("source", source.len())?;
        limits::check_cloud_points("target", target.len())?;
        let source = source.validated("source", MIN_POINTS, options.non_finite)?;
        let target = target.validated("target", MIN_POINTS, options.non_finite)?;
        let spreads_source = checks::not_collinear("source", &source.points, &mut warnings)?;
        let spreads_target = checks::not_collinear("target", &target.points, &mut warnings)?;
        checks::flat_pair(spreads_source, spreads_target, &mut warnings);
        let init = match &options.initial_transform {
            Some(rows) => {
                let m = transform::from_rows(rows);
                if m.iter().any(|v| !v.is_finite()) {
                    return Err(Error::InvalidOption("initialTransform has a non-finite entry".into()));
                }
                transform::check_rigid(&m, 1e-4)
                    .map_err(|e| Error::InvalidOption(format!("initialTransform is not rigid: {e}")))?;
                m
            }
            None => Matrix4::identity(),
        };
        // From here the pipeline works on each cloud's f32 offsets from its f64 origin (the local
        // frames); the caller's initial guess moves into them in f64: `Tr(-o_t) * init * Tr(o_s)`.
        // Its rotation is applied to the source's points, its translation kept in f64 (`shift`),
        // so a guess that moves the source far keeps the source's shape.
        let (origin_source, origin_target) = (source.origin, target.origin);
        let (source, target) = (source.into_local(), target.into_local());
        let init_local = origin::to_local(&init, origin_source, origin_target);
        let rotate_init = transform::from_rotation_translation(&transform::rotation(&init_local), &Vector3::zeros());
        let shift = Matrix4::new_translation(&transform::translation(&init_local));
        let (size_source, size_target) = (source.half_extent(), target.half_extent());
        let size_ratio = size_source.max(size_target) / size_source.min(size_target);
        if size_ratio > SIZE_RATIO_WARNING {
            warnings.push(format!(
                "the clouds differ in size by {size_ratio:.0}x (largest half-extents: source {size_source:.4}, target {size_target:.4}): registration is rigid, so both must be in the same unit (e.g. both metres, not metres and millimetres)"
            ));
        }
        // The network sees the source already turned by the initial guess (its shift only moves
        // the source's centre, which the normalisation removes).
        let source_init = if transform::rotation(&init_local) == Matrix3::identity() {
            source
        } else {
            source.transformed(&rotate_init)
        };
        let norm = JointNormalization::of_pair(&source_init, &target);
        let s = norm.scale;
        // the initial guess (identity with no initialTransform), from the turned source to the target
        let t_initial = norm.normalize_transform(&shift);
        checks::initial_distance(&t_initial)?;
        let src_n = source_init.transformed(&norm.source_to_normalized());
        let tgt_n = target.transformed(&norm.target_to_normalized());

        let d_final = match options.max_correspondence_distance {
            Some(d) if d.is_finite() && d > 0.0 => d / s,
            Some(d) => {
                return Err(Error::InvalidOption(format!("maxCorrespondenceDistance = {d} must be a positive number")))
            }
            None => DEFAULT_MAX_CORRESPONDENCE,
        };
        let voxel = match options.voxel_size {
            // Voxels below a millionth of the clouds' half-extent cannot merge distinct f32 points
            // meaningfully (and would saturate the grid keys): treat them as "no voxelisation".
            Some(v) if v.is_finite() && v >= 0.0 => {
                if v / s < 1e-6 {
                    0.0
                } else {
                    v / s
                }
            }
            Some(v) => return Err(Error::InvalidOption(format!("voxelSize = {v} must be >= 0"))),
            None => d_final * 0.5,
        };
        for (what, c) in [("source", &src_n), ("target", &tgt_n)] {
            if c.len() < n_net {
                warnings.push(format!(
                    "{what} has {} points, fewer than the network's {n_net}: some were used twice",
                    c.len()
                ));
            }
        }
        let net_src = sampling::network_sample(&src_n, n_net, options.seed);
        let net_tgt = sampling::network_sample(&tgt_n, n_net, options.seed ^ sampling::TARGET_SEED_XOR);
        let icp_src = sampling::voxel_downsample(&src_n, voxel as f32);
        let icp_tgt = sampling::voxel_downsample(&tgt_n, voxel as f32);
        let preprocess_ms = watch.lap();

        let (t_net_n, network_ms, gmr_ms) = if options.network {
            progress(Stage::Network);
            let out = self.model.forward(&net_src.points, &net_tgt.points, &mut self.workspace)?;
            let network_ms = watch.lap();
            let j = self.model.config.gaussians;
            let g_src = gmr::gmm_params(&net_src.points, &out.gamma_source, j);
            let g_tgt = gmr::gmm_params(&net_tgt.points, &out.gamma_target, j);
            let t = gmr::solve(&g_src, &g_tgt);
            (t, network_ms, watch.lap())
        } else {
            // identity in user units (relative to the initial guess), in normalised units
            (t_initial, 0.0, 0.0)
        };

        progress(Stage::Refining);
        let with_normals = options.icp == IcpKind::Plane;
        let target_index = IcpTarget::new(&icp_tgt.points, with_normals);
        // the six turns of `base` through the source's centroid as `base` moves it
        let c = src_n.centroid();
        let turns = |base: &Matrix4<f64>| {
            let moved = base.transform_point(&nalgebra::Point3::new(c[0], c[1], c[2]));
            refine::turned(base, [moved.x, moved.y, moved.z], refine::TURN_DEGREES)
        };
        // the starts as the options name them, with the network off mapped to what they become
        let mut kinds: Vec<Start> = Vec::with_capacity(options.starts.len());
        for &start in &options.starts {
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
        // stages of the search: the first start; the other local ones; the global ones
        let stages: Vec<Vec<Start>> = match options.search {
            Search::Exhaustive => vec![kinds.clone()],
            Search::Adaptive => {
                let first = kinds[..1].to_vec();
                let local: Vec<Start> = kinds[1..].iter().copied().filter(|s| !s.is_global()).collect();
                let global: Vec<Start> = kinds[1..].iter().copied().filter(|s| s.is_global()).collect();
                [first, local, global].into_iter().filter(|s| !s.is_empty()).collect()
            }
        };
        let how = Refinement { kind: options.icp, d_final, max_iterations: options.icp_max_iterations };
        let source_index = IcpTarget::new(&icp_src.points, false);
        let judge = |t: &Matrix4<f64>| {
            confidence::evidence(&target_index, &source_index, &icp_src.points, t, d_final, options.icp)
        };
        let mut hypotheses: Option<Vec<Matrix4<f64>>> = None;
        let mut global_ms = 0.0;
        let mut best: Option<(Candidate, Evidence, f64)> = None;
        let mut starts_refined = 0usize;
        for stage in &stages {
            let mut starts: Vec<(Start, Matrix4<f64>)> = Vec::with_capacity(stage.len() * 6);
            for &start in stage {
                match start {
                    Start::Network => starts.push((start, t_net_n)),
                    Start::Initial => starts.push((start, t_initial)),
                    Start::Centroids => starts.push((start, centroid_alignment(&src_n, &tgt_n))),
                    Start::Turned | Start::TurnedInitial => {
                        // t_net_n is the initial transform when the network is off
                        let base = if start == Start::Turned { t_net_n } else { t_initial };
                        starts.extend(turns(&base).map(|t| (start, t)));
                    }
                    Start::Global | Start::GlobalNetwork => {
                        let hyps = hypotheses.get_or_insert_with(|| {
                            let mut w = Stopwatch::start(self.clock);
                            let params = global::GlobalParams { seed: options.seed, ..Default::default() };
                            let h = global::hypotheses(&src_n, &tgt_n, &params);
                            global_ms += w.lap();
                            h.iter().map(|h| h.T_target_source).collect()
                        });
                        if start == Start::Global {
                            starts.extend(hyps.iter().map(|&t| (start, t)));
                        } else {
                            for &h in hyps.iter() {
                                // the network estimates the motion left after the hypothesis
                                let moved: Vec<[f32; 3]> =
                                    net_src.points.iter().map(|&p| transform::apply(&h, p)).collect();
                                let out = self.model.forward(&moved, &net_tgt.points, &mut self.workspace)?;
                                let j = self.model.config.gaussians;
                                let g_src = gmr::gmm_params(&moved, &out.gamma_source, j);
                                let g_tgt = gmr::gmm_params(&net_tgt.points, &out.gamma_target, j);
                                starts.push((start, gmr::solve(&g_src, &g_tgt) * h));
                            }
                        }
                    }
                }
            }
            if options.icp == IcpKind::Off {
                // nothing is refined or compared: the first start is the answer
                starts.truncate(1);
            }
            if starts.is_empty() {
                continue;
            }
            starts_refined += starts.len();
            let Some(c) = refine::refine_best(&target_index, &icp_src.points, &starts, &how) else { continue };
            let better = match &best {
                None => true,
                Some((b, _, _)) => refine::choose(&[*b, c]) == Some(1),
            };
            if better {
                let e = judge(&c.T_target_source);
                best = Some((c, e, confidence::confidence(&e)));
            }
            if options.search == Search::Adaptive && best.as_ref().is_some_and(|b| b.2 >= STOP_CONFIDENCE) {
                break;
            }
        }
        // no start at all (only global ones, and the descriptors matched too little): the first
        // start the options name, unrefined
        let (chosen, evidence, confidence) = match best {
            Some(b) => b,
            None => {
                let t = if options.network { t_net_n } else { t_initial };
                let start = if options.network { Start::Network } else { Start::Initial };
                let e = judge(&t);
                warnings.push("no start could be refined (the global descriptors matched too little): the answer is the network's estimate".into());
                let c = Candidate {
                    start,
                    T_target_source: t,
                    fitness: e.fitness,
                    inlier_rmse: e.rmse_ratio * d_final,
                    iterations: 0,
                    converged: false,
                };
                (c, e, confidence::confidence(&e))
            }
        };
        let Candidate { start, T_target_source: t_n, fitness, inlier_rmse: rmse_n, iterations, converged } = chosen;
        let icp_ms = watch.lap();

        let to_caller =
            |t: &Matrix4<f64>| origin::to_caller(&(norm.denormalize(t) * rotate_init), origin_source, origin_target);
        let T_target_source = to_caller(&t_n);
        let T_target_source_network = to_caller(&t_net_n);
        checks::finite_transform(&T_target_source, "the result")?;
        checks::finite_transform(&T_target_source_network, "the network's estimate")?;
        if confidence < LOW_CONFIDENCE {
            warnings.push(format!(
                "low confidence {confidence:.2}: the alignment may be wrong (fitness {fitness:.2} within {:.3}, reverse overlap {:.2})",
                d_final * s,
                evidence.overlap_reverse
            ));
        }
        Ok(Registration {
            T_target_source,
            T_target_source_network,
            start,
            fitness,
            inlier_rmse: rmse_n * s,
            icp_iterations: iterations,
            icp_converged: converged,
            max_correspondence_distance: d_final * s,
            timings: Timings {
                preprocess_ms,
                network_ms,
                gmr_ms,
                icp_ms: icp_ms - global_ms,
                global_ms,
                total_ms: total.lap(),
            },
            warnings,
            confidence,
            evidence,
            starts_refined,
        })
    }
}

/// The [`Start::Centroids`] transform between two clouds in one frame: no rotation, the
/// translation taking the source's centroid onto the target's.
fn centroid_alignment(source: &PointCloud, target: &PointCloud) -> Matrix4<f64> {
    let (cs, ct) = (source.centroid(), target.centroid());
    Matrix4::new_translation(&nalgebra::Vector3::new(ct[0] - cs[0], ct[1] - cs[1], ct[2] - cs[2]))
}
