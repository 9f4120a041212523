//! `arps eval`: runs every pair of a manifest (`pairs.tsv`, the format of
//! `fixtures/pairs/pairs.tsv`) through seven methods side by side and prints the paper's
//! table (docs/design.md §9): MRE, MTE, Recall, RRE, RTE and ms/pair.
//!
//! Methods (all use the pipeline's refinement: point-to-plane ICP, coarse to fine, defaults of
//! [`Options`] unless said):
//! * `network`: the network + GMR estimate, ICP off;
//! * `network + ICP`: ICP from the network estimate only (`starts: [network]`);
//! * `network + multi-start ICP`: the pipeline default (ICP from each of [`Options::starts`],
//!   the best by fitness); the table's footer counts which start won;
//! * `multi-start ICP, no network`: the same without the network (`starts: [centroids, initial,
//!   turned]`, the turns taken about the identity);
//! * `ICP from identity`: the network skipped (`Options::network = false`, `starts: [initial]`);
//! * `ICP from centroids`: the network skipped, ICP started at the translation that aligns the
//!   two clouds' centroids (`starts: [initial]`);
//! * `untrained network + ICP`: random weights (`Weights::random(&ModelConfig::web(), 0)`),
//!   `starts: [network]`;
//! * `FPFH + RANSAC + ICP`: global hypotheses only (`network: false`, `starts: [global]`);
//! * `FPFH + RANSAC + network + ICP`: each hypothesis refined by the network, then ICP
//!   (`starts: [globalNetwork]`);
//! * `exhaustive multi-start ICP`: the multi-start method's starts, every one refined
//!   (`search: exhaustive`) instead of the adaptive search.
//!
//! Confidence: for every method, the share of wrong answers (missed recall) whose
//! `confidence` is below 0.5 and the share of right answers whose is; the JSON carries each
//! answer's confidence and evidence.
//!
//! Alternatives: for every method whose answers came with other poses that fit about as well
//! (`Registration::alternatives`), the share of pairs whose answer *or* one of those poses is
//! right (what an application that offers the alternatives to its user can reach), and how many
//! wrong answers came with the right pose among their alternatives; the JSON carries each
//! alternative's errors and fitness.
//!
//! Failures that fit as well as the truth: for every pair the truth is refined too (ICP started
//! at the ground truth, same settings), and a failed estimate whose fitness is at least that
//! fitness − [`AMBIGUITY_MARGIN`] is counted in the `fit>=GT` column. Such failures are
//! geometric ambiguities (a cone turned about its axis, a box flipped): no method that
//! scores poses by how well the clouds overlap can tell them from the truth.
//!
//! Units: errors are in normalised units. Generated sets (`arps make-pairs`, whose `pairs.json`
//! says `"units": "normalized"`) already are; for anything else (real scans) TE is divided by the
//! pair's shared scale (the largest bounding-box half-extent of the two clouds, as
//! [`arps::cloud::JointNormalization`] picks it), so the 0.2 threshold means 20% of that.

use arps::cloud::JointNormalization;
use arps::confidence::Evidence;
use arps::data::manifest;
use arps::data::metrics::{ambiguous_miss, pair_error, recall_svg, recalled, summarize, PairError, Summary};
use arps::transform::{euler_xyz, from_rotation_translation, rigid_inverse, to_rows};
use arps::{io, ModelConfig, Options, Outliers, PointCloud, Registrar, Search, Start, Support, Timings, Weights};
use clap::{Args, ValueEnum};
use nalgebra::{Matrix4, Vector3};
use rand::Rng;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TeScale {
    /// Normalised pair sets (pairs.json says so) as they are; anything else divided by the pair's shared scale.
    Auto,
    /// Never rescale TE.
    One,
    /// Always divide TE by the pair's shared scale.
    Pair,
}

#[derive(Args)]
pub struct EvalArgs {
    /// The manifest (pairs.tsv): name, source, target, overlap_threshold, note, T_target_source (row-major).
    manifest: PathBuf,
    /// Weights file for the trained network (default: the embedded model).
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Only the first N pairs.
    #[arg(long)]
    limit: Option<usize>,
    /// Move each source by a random pose (Euler angles in [-45, 45] deg about its bounding-box
    /// centre, or in [-A, A] with `--perturb-angle A`; translation up to 0.5 normalised units) from
    /// this seed, and compose the GT accordingly.
    #[arg(long)]
    perturb: Option<u64>,
    /// With `--perturb`: the largest Euler angle of the random pose, degrees, in (0, 180] (180:
    /// any orientation, the scans as they would arrive in unrelated frames).
    #[arg(long, default_value_t = 45.0, requires = "perturb")]
    perturb_angle: f64,
    /// Write recall-vs-threshold curves (rotation 0-30 deg, translation 0-0.4) to this SVG.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Print one JSON object (summaries and per-pair errors) instead of the table.
    #[arg(long)]
    json: bool,
    /// Recall rotation threshold, degrees (strict).
    #[arg(long, default_value_t = 15.0)]
    rot_threshold: f64,
    /// Recall translation threshold, normalised units (strict).
    #[arg(long, default_value_t = 0.2)]
    trans_threshold: f64,
    /// How TE is scaled.
    #[arg(long, value_enum, default_value_t = TeScale::Auto)]
    te_scale: TeScale,
    /// The starts of `network + multi-start ICP`, comma-separated (network, centroids, initial,
    /// turned, turnedInitial, global, globalNetwork, rotations, rotationsNetwork) [default: the engine's `Options::starts`].
    #[arg(long, value_delimiter = ',')]
    starts: Option<Vec<Start>>,
    /// The direction that is up in both clouds of every pair, x,y,z (`Options::up`), for every
    /// method but the ground truth's refinement.
    #[arg(long, value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    up: Option<Vec<f64>>,
    /// The share of each pair's source that lies on its target once aligned (`Options::source_overlap`;
    /// 1 for pairs whose source is a part of the target, `make-pairs --target-keep 1`), for every
    /// method but the ground truth's refinement.
    #[arg(long, value_name = "SHARE")]
    source_overlap: Option<f64>,
    /// Keep the points that lie far out from the rest of their cloud (`Options::outliers` set to
    /// keep), for every method and the ground truth's refinement; by default they are left out.
    #[arg(long)]
    keep_outliers: bool,
    /// Keep support planes (`Options::support_plane` set to keep), for every method and the
    /// ground truth's refinement; by default they are left out.
    #[arg(long)]
    keep_support: bool,
    /// Run only these methods, comma-separated [default: all ten].
    #[arg(long, value_enum, value_delimiter = ',')]
    methods: Option<Vec<Method>>,
}

/// A failed estimate whose fitness is within this of the refined truth's counts as ambiguous.
const AMBIGUITY_MARGIN: f64 = 0.01;

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// `network`: the network + GMR estimate, ICP off.
    Network,
    /// `network + ICP`: ICP from the network's estimate only.
    NetworkIcp,
    /// `network + multi-start ICP`: the pipeline default (or `--starts`).
    MultiStart,
    /// `multi-start ICP, no network`.
    MultiStartNoNetwork,
    /// `ICP from identity`.
    IcpIdentity,
    /// `ICP from centroids`.
    IcpCentroids,
    /// `untrained network + ICP`.
    UntrainedIcp,
    /// `FPFH + RANSAC + ICP`.
    Global,
    /// `FPFH + RANSAC + network + ICP`.
    GlobalNetwork,
    /// `exhaustive multi-start ICP`.
    Exhaustive,
}

const METHODS: [Method; 10] = [
    Method::Network,
    Method::NetworkIcp,
    Method::MultiStart,
    Method::MultiStartNoNetwork,
    Method::IcpIdentity,
    Method::IcpCentroids,
    Method::UntrainedIcp,
    Method::Global,
    Method::GlobalNetwork,
    Method::Exhaustive,
];

impl Method {
    /// The method's row name in the table and the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Method::Network => "network",
            Method::NetworkIcp => "network + ICP",
            Method::MultiStart => "network + multi-start ICP",
            Method::MultiStartNoNetwork => "multi-start ICP, no network",
            Method::IcpIdentity => "ICP from identity",
            Method::IcpCentroids => "ICP from centroids",
            Method::UntrainedIcp => "untrained network + ICP",
            Method::Global => "FPFH + RANSAC + ICP",
            Method::GlobalNetwork => "FPFH + RANSAC + network + ICP",
            Method::Exhaustive => "exhaustive multi-start ICP",
        }
    }
    /// True for the methods that refine several starts.
    fn multi_start(self) -> bool {
        matches!(self, Method::MultiStart | Method::MultiStartNoNetwork | Method::Exhaustive)
    }
    /// The one place that says how each method calls the pipeline; `starts` are the multi-start
    /// method's.
    fn options(self, source: &PointCloud, target: &PointCloud, starts: &[Start]) -> Options {
        let base = Options::default();
        let single = |start| Options { starts: vec![start], ..Options::default() };
        match self {
            Method::Network => Options { icp: arps::IcpKind::Off, ..single(Start::Network) },
            Method::NetworkIcp | Method::UntrainedIcp => single(Start::Network),
            Method::MultiStart => Options { starts: starts.to_vec(), ..base },
            Method::Exhaustive => Options { starts: starts.to_vec(), search: Search::Exhaustive, ..base },
            Method::Global => Options { network: false, search: Search::Exhaustive, ..single(Start::Global) },
            Method::GlobalNetwork => Options { search: Search::Exhaustive, ..single(Start::GlobalNetwork) },
            Method::MultiStartNoNetwork => {
                Options { network: false, starts: vec![Start::Centroids, Start::Initial, Start::Turned], ..base }
            }
            Method::IcpIdentity => Options { network: false, ..single(Start::Initial) },
            Method::IcpCentroids => {
                let (cs, ct) = (source.centroid(), target.centroid());
                let t = Vector3::new(ct[0] - cs[0], ct[1] - cs[1], ct[2] - cs[2]);
                Options {
                    network: false,
                    initial_transform: Some(to_rows(&Matrix4::new_translation(&t))),
                    ..single(Start::Initial)
                }
            }
        }
    }
}

/// A random pose about `center`: Euler angles U[-`max_deg`, `max_deg`] each (R = Rx Ry Rz),
/// translation `a * u * scale`, u uniform on S², a ~ U[0, 0.5].
fn perturbation(seed: u64, index: u64, center: [f64; 3], scale: f64, max_deg: f64) -> Matrix4<f64> {
    let mut rng = arps::sampling::rng(arps::data::mix(seed, index));
    let a = max_deg.to_radians();
    let mut ang = || (rng.random::<f64>() * 2.0 - 1.0) * a;
    let r = euler_xyz(ang(), ang(), ang());
    let u = arps::data::pairs::unit_vector(&mut rng);
    let t = u * (rng.random::<f64>() * 0.5 * scale);
    let c = Vector3::from(center);
    // x -> R (x - c) + c + t
    from_rotation_translation(&r, &(c - r * c + t))
}

struct PairResult {
    name: String,
    scale: f64,
    errors: Vec<PairError>,
    ms: Vec<f64>,
    failed: Vec<Option<String>>,
    /// The start each method's answer came from (`None` when it failed).
    start: Vec<Option<Start>>,
    /// Each method's fitness at the final ICP distance (`None` when it failed).
    fitness: Vec<Option<f64>>,
    /// The fitness of the truth, refined by ICP from the ground-truth pose.
    gt_fitness: f64,
    /// The error of that refined truth: where ICP from a perfect start ends.
    gt_refined: PairError,
    /// Each method's confidence and its evidence (`None` when it failed).
    confidence: Vec<Option<(f64, Evidence)>>,
    /// Each method's stage timings and starts refined (`None` when it failed).
    work: Vec<Option<(Timings, usize)>>,
    /// Each method's answer, `T_target_source` (`None` when it failed).
    answer: Vec<Option<Matrix4<f64>>>,
    /// Each method's alternative poses: their errors and fitness (empty when it failed).
    alternatives: Vec<Vec<(PairError, f64)>>,
}

impl PairResult {
    /// Method `i` failed the recall thresholds with a fit at least as good as the truth's.
    fn ambiguous(&self, i: usize, rot_thr: f64, trans_thr: f64) -> bool {
        ambiguous_miss(
            recalled(&self.errors[i], rot_thr, trans_thr),
            self.fitness[i],
            self.gt_fitness,
            AMBIGUITY_MARGIN,
        )
    }

    /// Method `i`'s answer or one of its alternatives is right.
    fn right_among_alternatives(&self, i: usize, rot_thr: f64, trans_thr: f64) -> bool {
        recalled(&self.errors[i], rot_thr, trans_thr)
            || self.alternatives[i].iter().any(|(e, _)| recalled(e, rot_thr, trans_thr))
    }
}

/// One row of the table.
struct MethodSummary {
    name: String,
    errors: Vec<PairError>,
    summary: Summary,
    /// Pairs where the pipeline returned an error.
    failed: usize,
    /// Pairs missed with a fit at least as good as the truth's ([`PairResult::ambiguous`]).
    ambiguous: usize,
    /// Share of the missed pairs whose confidence is below 0.5 (`NaN` when none was missed).
    wrong_doubted: f64,
    /// Share of the recalled pairs whose confidence is below 0.5 (`NaN` when none was recalled).
    right_doubted: f64,
    /// Pairs whose answer came with alternatives.
    with_alternatives: usize,
    /// Share of the pairs whose answer or one of its alternatives is right.
    recall_with_alternatives: f64,
    /// Missed pairs with the right pose among the answer's alternatives.
    wrong_right_alternative: usize,
}

pub fn run(a: EvalArgs) -> Result<(), String> {
    if !(a.perturb_angle > 0.0 && a.perturb_angle <= 180.0) {
        return Err(format!("--perturb-angle must be in (0, 180] degrees, got {}", a.perturb_angle));
    }
    let entries = manifest::read(&a.manifest)?;
    let entries: Vec<_> = entries.into_iter().take(a.limit.unwrap_or(usize::MAX)).collect();
    if entries.is_empty() {
        return Err(format!("{}: no pairs", a.manifest.display()));
    }
    let normalized_set = match manifest::read_sidecar(&a.manifest) {
        Some(Ok(s)) => s.units == "normalized",
        Some(Err(e)) => return Err(e),
        None => false,
    };
    let divide = match a.te_scale {
        TeScale::Auto => !normalized_set,
        TeScale::One => false,
        TeScale::Pair => true,
    };
    // the selected methods, in table order
    let methods: Vec<Method> = match &a.methods {
        Some(list) => METHODS.into_iter().filter(|m| list.contains(m)).collect(),
        None => METHODS.to_vec(),
    };
    let starts = a.starts.clone().unwrap_or_else(|| Options::default().starts);
    let up = a.up.as_deref().map(super::up_axis).transpose()?;
    arps::refine::check_starts(&starts).map_err(|e| format!("--starts: {e}"))?;
    let mut trained = super::load_registrar(a.weights.as_deref())?;
    let untrained_weights = Weights::random(&ModelConfig::web(), 0).map_err(|e| e.to_string())?;
    let mut untrained = Registrar::new(&untrained_weights).map_err(|e| e.to_string())?;

    let outliers = if a.keep_outliers { Outliers::Keep } else { Outliers::Drop };
    let support_plane = if a.keep_support { Support::Keep } else { Support::Drop };
    let mut results = Vec::new();
    for (k, e) in entries.iter().enumerate() {
        let read = |p: PathBuf| io::read_path(&p).map_err(|err| format!("{}: {err}", p.display()));
        let mut source = read(e.source_path(&a.manifest))?;
        let target = read(e.target_path(&a.manifest))?;
        let mut gt = e.T_target_source;
        if let Some(seed) = a.perturb {
            let n = JointNormalization::of_pair(&source, &target);
            let p = perturbation(seed, k as u64, n.source_center, n.scale, a.perturb_angle);
            source = source.transformed(&p);
            gt *= rigid_inverse(&p);
        }
        let scale = if divide { JointNormalization::of_pair(&source, &target).scale } else { 1.0 };
        // manifests store the truth to a few digits: project its rotation back onto SO(3)
        let r_gt = arps::gmr::nearest_rotation(&arps::transform::rotation(&gt));
        let gt_rigid = from_rotation_translation(&r_gt, &arps::transform::translation(&gt));
        let truth = Options {
            network: false,
            initial_transform: Some(to_rows(&gt_rigid)),
            starts: vec![Start::Initial],
            outliers,
            support_plane,
            ..Options::default()
        };
        let refined_truth = trained
            .register(&source, &target, &truth)
            .map_err(|err| format!("{}: refining the ground truth: {err}", e.name))?;
        let gt_fitness = refined_truth.fitness;
        let gt_refined = pair_error(&refined_truth.T_target_source, &gt, scale);
        let mut r = PairResult {
            name: e.name.clone(),
            scale,
            errors: Vec::new(),
            ms: Vec::new(),
            failed: Vec::new(),
            start: Vec::new(),
            fitness: Vec::new(),
            gt_fitness,
            gt_refined,
            confidence: Vec::new(),
            work: Vec::new(),
            answer: Vec::new(),
            alternatives: Vec::new(),
        };
        for &m in &methods {
            let options = Options {
                up,
                outliers,
                support_plane,
                source_overlap: a.source_overlap,
                ..m.options(&source, &target, &starts)
            };
            let reg = if m == Method::UntrainedIcp { &mut untrained } else { &mut trained };
            // each method pays for preparing the target, as a call on its own would
            reg.forget_target();
            let t0 = Instant::now();
            let out = reg.register(&source, &target, &options);
            r.ms.push(t0.elapsed().as_secs_f64() * 1e3);
            // a failed registration counts as the identity (no estimate), and is reported
            let others = out.as_ref().map_or(Vec::new(), |x| {
                x.alternatives.iter().map(|o| (pair_error(&o.T_target_source, &gt, scale), o.fitness)).collect()
            });
            r.alternatives.push(others);
            let (pred, fail, start, fitness, conf, work) = match out {
                Ok(x) => (
                    x.T_target_source,
                    None,
                    Some(x.start),
                    Some(x.fitness),
                    Some((x.confidence, x.evidence)),
                    Some((x.timings, x.starts_refined)),
                ),
                Err(err) => (Matrix4::identity(), Some(err.to_string()), None, None, None, None),
            };
            r.confidence.push(conf);
            r.work.push(work);
            r.errors.push(pair_error(&pred, &gt, scale));
            r.answer.push(fail.is_none().then_some(pred));
            r.failed.push(fail);
            r.start.push(start);
            r.fitness.push(fitness);
        }
        if !a.json {
            eprint!("\r{} / {} pairs", k + 1, entries.len());
        }
        results.push(r);
    }
    if !a.json {
        eprintln!();
    }

    let per_method: Vec<MethodSummary> = methods
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let errors: Vec<PairError> = results.iter().map(|r| r.errors[i]).collect();
            let ms: Vec<f64> = results.iter().map(|r| r.ms[i]).collect();
            MethodSummary {
                name: m.name().to_string(),
                summary: summarize(&errors, &ms, a.rot_threshold, a.trans_threshold),
                errors,
                failed: results.iter().filter(|r| r.failed[i].is_some()).count(),
                ambiguous: results.iter().filter(|r| r.ambiguous(i, a.rot_threshold, a.trans_threshold)).count(),
                wrong_doubted: doubted(&results, i, false, a.rot_threshold, a.trans_threshold),
                right_doubted: doubted(&results, i, true, a.rot_threshold, a.trans_threshold),
                with_alternatives: results.iter().filter(|r| !r.alternatives[i].is_empty()).count(),
                recall_with_alternatives: results
                    .iter()
                    .filter(|r| r.right_among_alternatives(i, a.rot_threshold, a.trans_threshold))
                    .count() as f64
                    / results.len() as f64,
                wrong_right_alternative: results
                    .iter()
                    .filter(|r| {
                        !recalled(&r.errors[i], a.rot_threshold, a.trans_threshold)
                            && r.right_among_alternatives(i, a.rot_threshold, a.trans_threshold)
                    })
                    .count(),
            }
        })
        .collect();

    // ICP from the truth: the most ICP from any one start (a perfect network's) could recall
    let truth_recall = results.iter().filter(|r| recalled(&r.gt_refined, a.rot_threshold, a.trans_threshold)).count()
        as f64
        / results.len().max(1) as f64;
    let units = if divide {
        "TE divided by each pair's shared scale (largest bounding-box half-extent of the two clouds)"
    } else {
        "normalised shape units (largest half-extent 1), TE not rescaled"
    };
    let weights_desc = match &a.weights {
        Some(p) => p.display().to_string(),
        None => "embedded default model".into(),
    };
    if let Some(path) = &a.svg {
        let curves: Vec<(String, Vec<PairError>)> =
            per_method.iter().map(|m| (m.name.clone(), m.errors.clone())).collect();
        let title = format!(
            "{} ({} pairs{})",
            a.manifest.display(),
            results.len(),
            a.perturb
                .map(|s| format!(", perturbed, seed {s}, angles up to {} deg", a.perturb_angle))
                .unwrap_or_default()
        );
        let svg = recall_svg(&curves, a.rot_threshold, a.trans_threshold, 30.0, 0.4, &title);
        std::fs::write(path, svg).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if a.json {
        let out = serde_json::json!({
            "manifest": a.manifest.display().to_string(),
            "pairs": results.len(),
            "weights": weights_desc,
            "weights_provenance": trained.provenance(),
            "starts": starts.iter().map(|s| s.name()).collect::<Vec<_>>(),
            "perturb": a.perturb,
            "perturb_angle_deg": a.perturb.map(|_| a.perturb_angle),
            "units": units,
            "rot_threshold_deg": a.rot_threshold,
            "trans_threshold": a.trans_threshold,
            "ambiguity_margin": AMBIGUITY_MARGIN,
            "truth_refined_recall": truth_recall,
            "methods": per_method.iter().map(|m| serde_json::json!({
                "name": m.name, "summary": m.summary, "failed": m.failed, "fit_ge_gt": m.ambiguous,
                "wrong_below_half": m.wrong_doubted, "right_below_half": m.right_doubted,
                "with_alternatives": m.with_alternatives,
                "recall_with_alternatives": m.recall_with_alternatives,
                "wrong_right_alternative": m.wrong_right_alternative,
            })).collect::<Vec<_>>(),
            "per_pair": results.iter().map(|r| serde_json::json!({
                "name": r.name,
                "te_scale": r.scale,
                "gt_fitness": r.gt_fitness,
                "gt_refined": { "rot_deg": r.gt_refined.rot_deg, "trans": r.gt_refined.trans },
                "results": methods.iter().enumerate().map(|(i, m)| serde_json::json!({
                    "method": m.name(),
                    "rot_deg": r.errors[i].rot_deg,
                    "trans": r.errors[i].trans,
                    "ms": r.ms[i],
                    "start": r.start[i],
                    "fitness": r.fitness[i],
                    "confidence": r.confidence[i].map(|c| c.0),
                    "evidence": r.confidence[i].map(|c| c.1),
                    "timings": r.work[i].map(|w| w.0),
                    "starts_refined": r.work[i].map(|w| w.1),
                    "T_target_source": r.answer[i].map(|t| to_rows(&t)),
                    "alternatives": r.alternatives[i].iter().map(|(e, f)| serde_json::json!({
                        "rot_deg": e.rot_deg, "trans": e.trans, "fitness": f,
                    })).collect::<Vec<_>>(),
                    "error": r.failed[i],
                })).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        });
        out!("{out}");
        return Ok(());
    }
    out!(
        "arps eval: {} pairs from {}{}",
        results.len(),
        a.manifest.display(),
        a.perturb
            .map(|s| format!(", sources perturbed (seed {s}, angles up to {} deg)", a.perturb_angle))
            .unwrap_or_default()
    );
    out!("  weights: {weights_desc}; untrained: random web weights, seed 0");
    let names: Vec<&str> = starts.iter().map(|s| s.name()).collect();
    out!("  network + multi-start ICP starts: {}", names.join(", "));
    out!("  errors: {units}");
    out!(
        "  recall: RE < {} deg and TE < {} (strict); RRE/RTE over recalled pairs; ICP: point-to-plane, coarse to fine",
        a.rot_threshold,
        a.trans_threshold
    );
    out!(
        "  fit>=GT: pairs missed with a fitness within {AMBIGUITY_MARGIN} of the truth's (refined by ICP from the ground truth): ambiguous geometry"
    );
    out!(
        "{:<28} {:>9} {:>8} {:>7} {:>9} {:>8} {:>9} {:>6} {:>8}",
        "method",
        "MRE(deg)",
        "MTE",
        "Recall",
        "RRE(deg)",
        "RTE",
        "ms/pair",
        "failed",
        "fit>=GT"
    );
    // RRE/RTE are undefined (NaN) when nothing is recalled: print "-"
    let num = |v: f64, prec: usize| {
        if v.is_nan() {
            "-".to_string()
        } else {
            format!("{v:.prec$}")
        }
    };
    for m in &per_method {
        let s = &m.summary;
        out!(
            "{:<28} {:>9} {:>8} {:>7.4} {:>9} {:>8} {:>9.1} {:>6} {:>8}",
            m.name,
            num(s.mre, 3),
            num(s.mte, 4),
            s.recall,
            num(s.rre, 3),
            num(s.rte, 4),
            s.ms_per_pair,
            m.failed,
            m.ambiguous
        );
    }
    out!(
        "  ICP from the ground truth (the refinement of a perfect start, the most any one start can give): recall {truth_recall:.4}"
    );
    // (a share of no answers, NaN: "no wrong answers")
    let share = |v: f64, what: &str| {
        if v.is_nan() {
            format!("no {what} answers")
        } else {
            format!("{v:.3} of {what} answers")
        }
    };
    for m in &per_method {
        out!(
            "  {}: confidence < 0.5 on {}, {}",
            m.name,
            share(m.wrong_doubted, "wrong"),
            share(m.right_doubted, "right")
        );
    }
    for m in per_method.iter().filter(|m| m.with_alternatives > 0) {
        out!(
            "  {}: alternatives on {} pairs; the answer or an alternative right on {:.4} of pairs ({} wrong answers had the right pose among their alternatives)",
            m.name,
            m.with_alternatives,
            m.recall_with_alternatives,
            m.wrong_right_alternative
        );
    }
    let wins = |i: usize, start: Start| results.iter().filter(|r| r.start[i] == Some(start)).count();
    for (i, m) in methods.iter().enumerate().filter(|(_, m)| m.multi_start()) {
        let counts: Vec<String> = Start::ALL
            .into_iter()
            .map(|s| (s, wins(i, s)))
            .filter(|&(_, n)| n > 0)
            .map(|(s, n)| format!("{} {n}", s.name()))
            .collect();
        out!("  {}: chosen start {}", m.name(), counts.join(", "));
    }
    for (i, m) in methods.iter().enumerate() {
        let work: Vec<(Timings, usize)> = results.iter().filter_map(|r| r.work[i]).collect();
        if work.is_empty() {
            continue;
        }
        let median =
            |f: &dyn Fn(&(Timings, usize)) -> f64| crate::bench::median(&mut work.iter().map(f).collect::<Vec<_>>());
        out!(
            "  {}: median ms network {}, ICP and confidence {}, global hypotheses {}; starts refined {}",
            m.name(),
            num(median(&|w| w.0.network_ms + w.0.gmr_ms), 1),
            num(median(&|w| w.0.icp_ms), 1),
            num(median(&|w| w.0.global_ms), 1),
            median(&|w| w.1 as f64)
        );
    }
    for r in &results {
        for (i, f) in r.failed.iter().enumerate() {
            if let Some(f) = f {
                out!("  failed: {} with {}: {f}", r.name, methods[i].name());
            }
        }
    }
    if let Some(p) = &a.svg {
        out!("  curves: {}", p.display());
    }
    Ok(())
}

/// Among the pairs method `i` answered right (`right`) or wrong, the share whose confidence is
/// below 0.5 (a failed call counts as wrong with confidence 0); `NaN` when there are none.
fn doubted(results: &[PairResult], i: usize, right: bool, rot_thr: f64, trans_thr: f64) -> f64 {
    let group: Vec<&PairResult> =
        results.iter().filter(|r| recalled(&r.errors[i], rot_thr, trans_thr) == right).collect();
    if group.is_empty() {
        return f64::NAN;
    }
    let low = group.iter().filter(|r| r.confidence[i].map_or(0.0, |c| c.0) < 0.5).count();
    low as f64 / group.len() as f64
}
