//! `arps-train`: trains a DGMR-ARPS network on the CPU, checkpoints and resumes runs, and exports
//! the engine's weights.
//!
//! * `arps-train train --run runs/NAME [...]`: a run (new, or `--resume`d from its checkpoint).
//! * `arps-train export --run runs/NAME --out models/web.safetensors [--f16]`: best weights with
//!   provenance.
//! * `arps-train curves --run runs/NAME --out curve.svg`: validation recall / MRE and the training
//!   loss over wall-clock time.

use arps::data::pairs::check_pose_angle;
use arps::train::run::{
    checkpoint, data::TrainData, log, process_cpu_seconds, validate, Curriculum, RunConfig, RunState, ValMetrics,
    TRAINER_VERSION,
};
use arps::train::{self, CentroidMode, ConsistencyKind, LossConfig, LossParts, TrainState};
use arps::{ModelConfig, StoreAs, Weights};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[macro_use]
#[path = "../common/out.rs"]
mod out;
mod curves;
mod oracle;

#[derive(Parser)]
#[command(name = "arps-train", version, about = "Train, resume and export DGMR-ARPS models on the CPU")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once; boxing buys nothing
enum Command {
    /// Train (a new run, or --resume an existing one).
    Train(Box<TrainArgs>),
    /// Export a run's best weights in the engine's format, with provenance.
    Export(ExportArgs),
    /// GMR accuracy with oracle memberships (the `seg` loss's targets) on a run's validation
    /// pairs: the ceiling of a network that learned the partition.
    PartitionOracle(OracleArgs),
    /// Plot a run's training curves (SVG).
    Curves(CurvesArgs),
}

#[derive(Args)]
struct TrainArgs {
    /// Run directory (checkpoint.safetensors, best.safetensors, log.jsonl).
    #[arg(long)]
    run: PathBuf,
    /// Model preset (new runs): web, tiny or paper.
    #[arg(long, default_value = "web")]
    preset: String,
    /// Continue the run from its checkpoint (its stored configuration is used; --threads,
    /// --minutes and --steps apply).
    #[arg(long)]
    resume: bool,
    /// Train for this many minutes of wall-clock in this session.
    #[arg(long)]
    minutes: Option<f64>,
    /// Train for this many minutes of process CPU time in this session (equal-CPU comparisons on a
    /// shared machine).
    #[arg(long)]
    cpu_minutes: Option<f64>,
    /// Train until the run's step count reaches this (total over all sessions).
    #[arg(long)]
    steps: Option<u64>,
    /// Pairs per step.
    #[arg(long, default_value_t = 8)]
    batch: usize,
    /// Peak learning rate (Adam; default 1e-3). On --resume, replaces the run's current lr
    /// (logged in the session's start line).
    #[arg(long)]
    lr: Option<f32>,
    /// Linear warm-up steps.
    #[arg(long, default_value_t = 100)]
    warmup_steps: u64,
    /// Global gradient-norm clip (0 = off).
    #[arg(long, default_value_t = 1.0)]
    clip: f64,
    /// Halve the lr after this many validations without improvement (default 3; on --resume,
    /// overrides the stored value).
    #[arg(long)]
    patience: Option<u32>,
    /// Points per cloud the network samples (default: the preset's N). On --resume, replaces
    /// the stored N (a fork that fine-tunes at another N; the weights do not depend on it).
    #[arg(long)]
    network_points: Option<usize>,
    /// Per-point feature width C of a new run (default: the preset's; tokens are 2C wide).
    #[arg(long)]
    feature_dim: Option<usize>,
    /// Attention heads of a new run (default: the preset's; 2C must be divisible by it).
    #[arg(long)]
    heads: Option<usize>,
    /// Feed-forward width of a new run's attention blocks (default: the preset's).
    #[arg(long)]
    ffn_dim: Option<usize>,
    /// ARPS layers L of a new run (default: the preset's).
    #[arg(long)]
    layers: Option<usize>,
    /// Smallest lr the plateau schedule goes to.
    #[arg(long, default_value_t = 1e-5)]
    min_lr: f32,
    /// Seed (initialisation and data stream).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Shape bank directory (real meshes, split by shape); default procedural shapes only.
    #[arg(long)]
    bank: Option<PathBuf>,
    /// Fraction of bank shapes held out for validation.
    #[arg(long, default_value_t = 0.15)]
    val_fraction: f64,
    /// Probability that a pair uses a bank shape.
    #[arg(long, default_value_t = 0.3)]
    bank_fraction: f64,
    /// Losses: comma list of name[=weight] from sup, ctr, stp, aff, reg, consistency, means,
    /// seg (unlisted terms are off, except stp which keeps the paper's 1e-8 unless listed). Default
    /// `sup,ctr`. On --resume, replaces the stored losses (a fork of a run with other losses:
    /// copy its directory, then resume the copy with --loss).
    #[arg(long)]
    loss: Option<String>,
    /// Centroid loss on every layer's reference point (every) or the final one only (final).
    #[arg(long, default_value = "every")]
    ctr_mode: String,
    /// Consistency divergence: kl (symmetric KL) or squared.
    #[arg(long, default_value = "kl")]
    consistency_kind: String,
    /// Concentration of the `seg` loss's soft cones.
    #[arg(long, default_value_t = 8.0)]
    seg_kappa: f32,
    /// Consistency correspondence radius (engine-normalised units).
    #[arg(long, default_value_t = 0.05)]
    consistency_radius: f32,
    /// Curriculum: `off`, or `pairs=N,angle=A,trans=T,keep=K,overlap=O,noise=S` (start values,
    /// ramped linearly to the full protocol over N training pairs).
    /// Default `pairs=16000,angle=10,trans=0.1,keep=0.85,overlap=0.9,noise=0.005`. On --resume,
    /// replaces the stored curriculum from the current pair on (logged in the session's start line).
    #[arg(long)]
    curriculum: Option<String>,
    /// Training pairs only: turn each whole shape by Euler angles up to this many degrees before
    /// cropping, so the source is not in the shape's own orientation (default 0, the paper's
    /// protocol; validation always uses it). On --resume, replaces the stored value.
    #[arg(long)]
    pose_angle: Option<f64>,
    /// Keep a moving average of the parameters with this decay per step (e.g. 0.999) and
    /// validate and export it; 0 = off (the default). On --resume, replaces the stored value (an
    /// average that does not exist yet starts at the current parameters).
    #[arg(long)]
    ema: Option<f32>,
    /// Points per cloud of a generated pair (the network samples the model's N of them).
    #[arg(long, default_value_t = 1024)]
    pair_points: usize,
    /// Validation pairs (held-out shapes, full protocol).
    #[arg(long, default_value_t = 200)]
    val_pairs: usize,
    /// Validate every M minutes (default 5; on --resume, overrides the stored value).
    #[arg(long)]
    val_every_minutes: Option<f64>,
    /// Validate every S steps instead (deterministic schedule).
    #[arg(long)]
    val_every_steps: Option<u64>,
    /// Also run network + ICP every K validations (0 = never; default 3; on --resume, overrides).
    #[arg(long)]
    icp_every: Option<u32>,
    /// Checkpoint every M minutes (default 3; on --resume, overrides).
    #[arg(long)]
    checkpoint_every_minutes: Option<f64>,
    /// Checkpoint every S steps instead.
    #[arg(long)]
    checkpoint_every_steps: Option<u64>,
    /// Log line every S steps.
    #[arg(long, default_value_t = 10)]
    log_every: u64,
    /// Validate once more at the end of the session (if the last step was not validated).
    #[arg(long)]
    final_val: bool,
    /// No progress bar (plain log lines on stderr instead).
    #[arg(long)]
    quiet: bool,
}

#[derive(Args)]
struct ExportArgs {
    /// Run directory.
    #[arg(long)]
    run: PathBuf,
    /// Output weights file.
    #[arg(long)]
    out: PathBuf,
    /// Store f16 (the shipped model); default f32.
    #[arg(long)]
    f16: bool,
    /// Export the latest checkpoint's parameters (their moving average, if the run keeps one)
    /// instead of the best validation's.
    #[arg(long)]
    latest: bool,
}

#[derive(Args)]
struct OracleArgs {
    /// Run directory (its data configuration and validation split are used).
    #[arg(long)]
    run: PathBuf,
    /// Validation pairs.
    #[arg(long, default_value_t = 200)]
    pairs: u64,
    /// Partition concentrations to try.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8,16,64")]
    kappa: Vec<f64>,
    /// Points per cloud (default: the run's N).
    #[arg(long)]
    points: Option<usize>,
}

#[derive(Args)]
struct CurvesArgs {
    /// Run directory (or several, comma-separated, drawn on one plot).
    #[arg(long, value_delimiter = ',')]
    run: Vec<PathBuf>,
    /// Output SVG.
    #[arg(long)]
    out: PathBuf,
    /// X axis: wall-clock minutes (wall) or process CPU minutes (cpu; fair on a shared machine).
    #[arg(long, default_value = "wall")]
    x: String,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let r = match cli.command {
        Command::Train(a) => train_cmd(*a),
        Command::Export(a) => export_cmd(a),
        Command::Curves(a) => curves::run(&a.run, &a.out, a.x == "cpu"),
        Command::PartitionOracle(a) => oracle::run(&a.run, a.pairs, &a.kappa, a.points),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("arps-train: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `--loss` when it is not given.
const DEFAULT_LOSS: &str = "sup,ctr";
/// Plateau patience of a new run (validations without improvement before the lr halves).
const DEFAULT_PATIENCE: u32 = 3;
/// `--lr` when it is not given.
const DEFAULT_LR: f32 = 1e-3;

fn parse_loss(a: &TrainArgs) -> Result<LossConfig, String> {
    let mut l = LossConfig { sup: 0.0, ctr: 0.0, aff: 0.0, reg: 0.0, consistency: 0.0, ..LossConfig::default() };
    for item in a.loss.as_deref().unwrap_or(DEFAULT_LOSS).split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (name, w) = match item.split_once('=') {
            Some((n, w)) => {
                (n.trim(), w.trim().parse::<f32>().map_err(|_| format!("loss weight '{w}' is not a number"))?)
            }
            None => (item, if item == "stp" { 1e-8 } else { 1.0 }),
        };
        match name {
            "sup" => l.sup = w,
            "ctr" => l.ctr = w,
            "stp" => l.stp = w,
            "aff" => l.aff = w,
            "reg" => l.reg = w,
            "consistency" | "cons" => l.consistency = w,
            "means" => l.means = w,
            "seg" => l.seg = w,
            other => return Err(format!("unknown loss '{other}' (sup, ctr, stp, aff, reg, consistency, means, seg)")),
        }
    }
    l.ctr_mode = match a.ctr_mode.as_str() {
        "every" => CentroidMode::EveryLayer,
        "final" => CentroidMode::FinalOnly,
        o => return Err(format!("--ctr-mode {o}: expected every or final")),
    };
    l.consistency_kind = match a.consistency_kind.as_str() {
        "kl" => ConsistencyKind::SymmetricKl,
        "squared" => ConsistencyKind::Squared,
        o => return Err(format!("--consistency-kind {o}: expected kl or squared")),
    };
    l.consistency_radius = a.consistency_radius;
    l.seg_kappa = a.seg_kappa;
    Ok(l)
}

/// `--ema`, checked: Some(None) turns the average off, Some(Some(d)) sets its decay.
fn ema_decay(a: &TrainArgs) -> Result<Option<Option<f32>>, String> {
    match a.ema {
        None => Ok(None),
        Some(0.0) => Ok(Some(None)),
        Some(d) if d > 0.0 && d < 1.0 => Ok(Some(Some(d))),
        Some(d) => Err(format!("--ema {d} must be a decay in (0, 1), or 0 for off")),
    }
}

/// `--pose-angle`, checked ([`check_pose_angle`]).
fn pose_angle(a: &TrainArgs) -> Result<Option<f64>, String> {
    a.pose_angle.map(|v| check_pose_angle(v).map_err(|e| format!("--pose-angle {e}"))).transpose()
}

/// `--network-points`, when given, replaces `model`'s N (checked with the rest of the config).
fn set_network_points(model: &mut ModelConfig, a: &TrainArgs) -> Result<(), String> {
    if let Some(n) = a.network_points {
        model.n_points = n;
        model.validate().map_err(|e| format!("--network-points {n}: {e}"))?;
    }
    Ok(())
}

/// Sets one size of a [`ModelConfig`].
type SetSize = fn(&mut ModelConfig, usize);

/// The model-size flags that were given, as `(flag, value, setter)`.
fn size_flags(a: &TrainArgs) -> Vec<(&'static str, usize, SetSize)> {
    let flags: [(&'static str, Option<usize>, SetSize); 4] = [
        ("--feature-dim", a.feature_dim, |m, v| m.feature_dim = v),
        ("--heads", a.heads, |m, v| m.heads = v),
        ("--ffn-dim", a.ffn_dim, |m, v| m.ffn_dim = v),
        ("--layers", a.layers, |m, v| m.layers = v),
    ];
    flags.into_iter().filter_map(|(flag, v, set)| v.map(|v| (flag, v, set))).collect()
}

/// The preset with the model-size flags applied; the label becomes e.g. `web+feature-dim=96`.
fn model_config(a: &TrainArgs) -> Result<ModelConfig, String> {
    let mut model = ModelConfig::preset(&a.preset).map_err(|e| e.to_string())?;
    for (flag, v, set) in size_flags(a) {
        set(&mut model, v);
        model.preset.push_str(&format!("+{}={v}", &flag[2..]));
    }
    model.validate().map_err(|e| format!("model size: {e}"))?;
    Ok(model)
}

fn run_config(a: &TrainArgs) -> Result<RunConfig, String> {
    let mut model = model_config(a)?;
    set_network_points(&mut model, a)?;
    Ok(RunConfig {
        model,
        loss: parse_loss(a)?,
        batch: a.batch.max(1),
        lr: a.lr.unwrap_or(DEFAULT_LR),
        warmup_steps: a.warmup_steps,
        clip_norm: (a.clip > 0.0).then_some(a.clip),
        plateau_patience: a.patience.unwrap_or(DEFAULT_PATIENCE),
        min_lr: a.min_lr,
        seed: a.seed,
        threads: a.threads.max(1),
        bank: a.bank.as_ref().map(|p| p.to_string_lossy().into_owned()),
        val_fraction: a.val_fraction,
        bank_fraction: a.bank_fraction,
        pair_points: a.pair_points,
        pose_angle_deg: pose_angle(a)?.unwrap_or(0.0),
        ema_decay: ema_decay(a)?.flatten(),
        curriculum: match &a.curriculum {
            Some(c) => Curriculum::parse(c)?,
            None => Curriculum::default(),
        },
        val_pairs: a.val_pairs,
        val_every_minutes: a.val_every_minutes.unwrap_or(5.0),
        val_every_steps: a.val_every_steps.filter(|&s| s > 0),
        icp_every_validations: a.icp_every.unwrap_or(3),
        checkpoint_every_minutes: a.checkpoint_every_minutes.unwrap_or(3.0),
        checkpoint_every_steps: a.checkpoint_every_steps.filter(|&s| s > 0),
        log_every_steps: a.log_every.max(1),
    })
}

fn provenance(run: &Path, st: &RunState, bank_counts: (usize, usize, usize, usize)) -> serde_json::Value {
    let c = &st.config;
    json!({
        "trainer": TRAINER_VERSION,
        "run": run.file_name().map(|n| n.to_string_lossy().into_owned()),
        "step": st.best_step,
        "pairs_seen": st.best_pairs_seen,
        "wall_clock_s": (st.best_elapsed * 10.0).round() / 10.0,
        "validation": st.best_val,
        "data": {
            "procedural": true,
            "bank": c.bank,
            "bank_meshes": {"usable": bank_counts.0, "skipped": bank_counts.1, "train": bank_counts.2, "val": bank_counts.3},
            "bank_fraction": c.bank_fraction,
            "val_fraction": c.val_fraction,
            "pair_points": c.pair_points,
            "pose_angle_deg": c.pose_angle_deg,
            "curriculum": c.curriculum,
            "val_pairs": c.val_pairs,
        },
        "losses": c.loss,
        "optimiser": {"adam_lr": c.lr, "warmup_steps": c.warmup_steps, "clip_norm": c.clip_norm, "batch": c.batch, "plateau_patience": c.plateau_patience, "ema_decay": c.ema_decay},
        "seed": c.seed,
    })
}

fn loss_json(l: &LossParts) -> serde_json::Value {
    let r = |v: f64| (v * 1e6).round() / 1e6;
    json!({
        "total": r(l.total), "sup": r(l.sup), "ctr": r(l.ctr), "ctr_no_shift": r(l.ctr_no_shift), "aff": r(l.aff),
        "reg": r(l.reg), "consistency": r(l.consistency), "consistency_pairs": r(l.consistency_pairs),
        "means": r(l.means), "means_spread": r(l.means_spread), "gamma_entropy": r(l.gamma_entropy), "seg": r(l.seg),
        "steps": l.steps.iter().map(|&s| r(s)).collect::<Vec<_>>(),
    })
}

fn train_cmd(a: TrainArgs) -> Result<(), String> {
    std::fs::create_dir_all(&a.run).map_err(|e| format!("{}: {e}", a.run.display()))?;
    let ckpt_path = a.run.join("checkpoint.safetensors");
    let best_path = a.run.join("best.safetensors");
    let (mut st, params, adam, ema) = if a.resume {
        if let Some((flag, _, _)) = size_flags(&a).first() {
            return Err(format!("{flag} sets the size of a new run; a resumed run keeps its model's size"));
        }
        let checkpoint::Checkpoint { state: mut st, params: p, adam, ema } = checkpoint::load(&ckpt_path)?;
        st.config.threads = a.threads.max(1);
        if let Some(v) = a.val_every_minutes {
            st.config.val_every_minutes = v;
        }
        if let Some(c) = &a.curriculum {
            st.config.curriculum = Curriculum::parse(c)?;
        }
        if let Some(v) = a.icp_every {
            st.config.icp_every_validations = v;
        }
        if let Some(v) = a.checkpoint_every_minutes {
            st.config.checkpoint_every_minutes = v;
        }
        if let Some(v) = a.val_every_steps {
            st.config.val_every_steps = Some(v).filter(|&s| s > 0);
        }
        if let Some(v) = a.patience {
            st.config.plateau_patience = v;
            st.bad_validations = 0;
        }
        set_network_points(&mut st.config.model, &a)?;
        if let Some(v) = pose_angle(&a)? {
            st.config.pose_angle_deg = v;
        }
        if let Some(v) = ema_decay(&a)? {
            st.config.ema_decay = v;
        }
        if a.loss.is_some() {
            st.config.loss = parse_loss(&a)?;
        }
        if let Some(lr) = a.lr {
            if !(lr.is_finite() && lr > 0.0) {
                return Err(format!("--lr {lr} must be a positive number"));
            }
            st.lr = lr;
            st.bad_validations = 0;
        }
        (st, p, adam, ema)
    } else {
        if ckpt_path.exists() {
            return Err(format!("{} exists: use --resume, or another --run", ckpt_path.display()));
        }
        let cfg = run_config(&a)?;
        let params = train::init_params(&cfg.model, cfg.seed).map_err(|e| e.to_string())?;
        let lr = cfg.lr;
        (RunState::new(cfg), params, train::Adam::new(lr), None)
    };
    st.sessions += 1;
    let cfg = st.config.clone();
    let threads = cfg.threads;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
    let mut logf = log::JsonlLog::open(&a.run.join("log.jsonl")).map_err(|e| e.to_string())?;
    let tty = std::io::stderr().is_terminal() && !a.quiet;
    let say = |s: &str| {
        if !tty {
            eprintln!("[{}] {s}", chrono_now());
        }
    };

    let data = TrainData::new(&cfg)?;
    let bank_counts = data.bank_counts;
    say(&format!(
        "run {} session {}: step {}, pairs seen {}, model {} ({} parameters), bank {:?} (train {}, val {})",
        a.run.display(),
        st.sessions,
        st.step,
        st.pairs_seen,
        cfg.model.preset,
        cfg.model.parameter_count(),
        cfg.bank,
        bank_counts.2,
        bank_counts.3
    ));
    // the fixed validation set (held-out shapes, full protocol)
    let t0 = Instant::now();
    let val: Vec<validate::ValPair> = {
        use rayon::prelude::*;
        pool.install(|| {
            (0..cfg.val_pairs as u64)
                .into_par_iter()
                .map(|i| data.val_pair(i).map(|p| validate::ValPair::from(&p)))
                .collect::<arps::Result<Vec<_>>>()
        })
        .map_err(|e| format!("validation pairs: {e}"))?
    };
    say(&format!("{} validation pairs in {:.1} s", val.len(), t0.elapsed().as_secs_f64()));
    logf.write(json!({
        "kind": "start", "session": st.sessions, "step": st.step, "pairs_seen": st.pairs_seen, "elapsed": st.elapsed, "lr": st.lr,
        "threads": threads, "config": cfg, "bank_meshes": {"usable": bank_counts.0, "skipped": bank_counts.1, "train": bank_counts.2, "val": bank_counts.3},
    }));

    // an average the checkpoint does not hold yet starts at the current parameters
    let ema = cfg.ema_decay.map(|d| train::Ema::new(d, ema.as_ref().unwrap_or(&params)));
    let mut ts = TrainState {
        config: cfg.model.clone(),
        params,
        adam,
        clip_norm: cfg.clip_norm,
        steps: st.step,
        skipped_steps: st.skipped_steps,
        ema,
    };

    let session = Instant::now();
    let elapsed0 = st.elapsed;
    let cpu0 = st.cpu - process_cpu_seconds();
    let session_cpu0 = st.cpu;
    let deadline = a.minutes.map(|m| m * 60.0);
    let target = a.steps;
    let pb = if tty {
        let (len, unit) = match (target, deadline) {
            (Some(s), _) => (s, "steps"),
            (None, Some(d)) => (d as u64, "s"),
            (None, None) => (0, "steps"),
        };
        let pb = ProgressBar::new(len);
        pb.set_style(
            ProgressStyle::with_template(&format!(
                "{{elapsed_precise}} [{{bar:30}}] {{pos}}/{{len}} {unit} ETA {{eta}} {{msg}}"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        if unit == "steps" {
            pb.set_position(st.step);
        }
        Some((pb, unit == "s"))
    } else {
        None
    };
    let stop_file = a.run.join("STOP");

    let mut last_ckpt = Instant::now();
    let mut window: Vec<LossParts> = Vec::new();
    let (mut w_gn, mut w_clipped, mut w_skipped, mut w_time, mut w_data, mut w_steps) =
        (0.0f64, 0u64, 0u64, 0.0f64, 0.0f64, 0u64);
    let mut last_val: Option<ValMetrics> = st.best_val.clone();
    let mut last_loss = f64::NAN;
    let mut pps = 0.0f64;

    let do_validate = |st: &mut RunState, ts: &TrainState, logf: &mut log::JsonlLog| -> Result<ValMetrics, String> {
        let with_icp = cfg.icp_every_validations > 0 && st.validations.is_multiple_of(cfg.icp_every_validations as u64);
        st.cpu = cpu0 + process_cpu_seconds();
        let v = validate::validate(&pool, &cfg.model, ts.eval_params(), &val, with_icp).map_err(|e| e.to_string())?;
        // with a moving average, the current parameters too (network only), for comparison
        let v_raw = match ts.ema {
            Some(_) => Some(validate::validate(&pool, &cfg.model, &ts.params, &val, false).map_err(|e| e.to_string())?),
            None => None,
        };
        let improved = st.record_validation(&v);
        if improved {
            let w = train::to_weights(ts.eval_params(), &cfg.model, provenance(&a.run, st, bank_counts))
                .map_err(|e| e.to_string())?;
            let bytes = w.to_bytes(StoreAs::F32).map_err(|e| e.to_string())?;
            checkpoint::write_atomic(&best_path, &bytes).map_err(|e| format!("{}: {e}", best_path.display()))?;
        }
        logf.write(json!({
            "kind": "val", "step": st.step, "pairs_seen": st.pairs_seen, "elapsed": st.elapsed, "cpu": st.cpu, "lr": st.lr,
            "val": v, "score": v.score(), "improved": improved, "best_score": st.best_score,
            "val_raw": v_raw, "ema_decay": cfg.ema_decay,
        }));
        Ok(v)
    };

    // baseline validation of a fresh run
    if st.validations == 0 && st.step == 0 {
        let v = do_validate(&mut st, &ts, &mut logf)?;
        say(&format!(
            "val @0: net recall {:.3} MRE {:.1} | +ICP {:?}  ({:.1} s)",
            v.net_recall, v.net_mre, v.icp_recall, v.seconds
        ));
        last_val = Some(v);
    }

    let mut stopped_by_file = false;
    loop {
        if target.is_some_and(|s| st.step >= s)
            || deadline.is_some_and(|d| session.elapsed().as_secs_f64() >= d)
            || a.cpu_minutes.is_some_and(|m| st.cpu - session_cpu0 >= m * 60.0)
        {
            break;
        }
        if stop_file.exists() {
            stopped_by_file = true;
            let _ = std::fs::remove_file(&stop_file);
            break;
        }
        let step_start = Instant::now();
        let first = st.pairs_seen;
        let pairs: Vec<train::Pair> = {
            use rayon::prelude::*;
            pool.install(|| {
                (first..first + cfg.batch as u64)
                    .into_par_iter()
                    .map(|i| data.train_pair(i))
                    .collect::<arps::Result<Vec<_>>>()
            })
            .map_err(|e| format!("training pair: {e}"))?
        };
        let data_s = step_start.elapsed().as_secs_f64();
        ts.adam.lr = st.effective_lr();
        let r = train::train_step(&mut ts, &pairs, &cfg.loss, threads);
        st.step = ts.steps;
        st.skipped_steps = ts.skipped_steps;
        st.adam_t = ts.adam.t;
        st.pairs_seen += cfg.batch as u64;
        st.elapsed = elapsed0 + session.elapsed().as_secs_f64();
        st.cpu = cpu0 + process_cpu_seconds();
        let dt = step_start.elapsed().as_secs_f64();
        if !r.skipped {
            window.push(r.loss.clone());
            w_gn += r.grad_norm;
        }
        w_clipped += r.clipped as u64;
        w_skipped += r.skipped as u64;
        w_time += dt;
        w_data += data_s;
        w_steps += 1;
        if st.step.is_multiple_of(cfg.log_every_steps) {
            let n = window.len().max(1) as f64;
            let m = LossParts::mean(&window);
            pps = (w_steps * cfg.batch as u64) as f64 / w_time.max(1e-9);
            last_loss = m.total;
            logf.write(json!({
                "kind": "step", "step": st.step, "pairs_seen": st.pairs_seen, "elapsed": (st.elapsed * 10.0).round() / 10.0, "cpu": (st.cpu * 10.0).round() / 10.0,
                "lr": ts.adam.lr, "loss": loss_json(&m), "grad_norm": w_gn / n, "clipped": w_clipped, "skipped": w_skipped,
                "skipped_total": st.skipped_steps, "pairs_per_s": (pps * 100.0).round() / 100.0,
                "data_fraction": (w_data / w_time.max(1e-9) * 1000.0).round() / 1000.0,
                "curriculum": data.curriculum.progress(st.pairs_seen),
            }));
            if !tty {
                eprintln!(
                    "[{}] step {} pairs {} loss {:.4} (sup {:.4} ctr {:.4}/{:.4} cons {:.4}) gn {:.3} steps {:?} lr {:.2e} {:.1} pairs/s",
                    chrono_now(),
                    st.step,
                    st.pairs_seen,
                    m.total,
                    m.sup,
                    m.ctr,
                    m.ctr_no_shift,
                    m.consistency,
                    w_gn / n,
                    m.steps.iter().map(|s| (s * 1000.0).round() / 1000.0).collect::<Vec<_>>(),
                    ts.adam.lr,
                    pps
                );
            }
            window.clear();
            (w_gn, w_clipped, w_skipped, w_time, w_data, w_steps) = (0.0, 0, 0, 0.0, 0.0, 0);
        }
        let val_due = match cfg.val_every_steps {
            Some(s) => st.step.is_multiple_of(s),
            None => st.elapsed - st.last_val_elapsed >= cfg.val_every_minutes * 60.0,
        };
        if val_due {
            let v = do_validate(&mut st, &ts, &mut logf)?;
            say(&format!(
                "val @{} ({} pairs, {:.1} min): net recall {:.3} MRE {:.2} MTE {:.3} | +ICP {:?} | best {:.4} @{} | lr {:.2e} ({:.1} s)",
                st.step,
                st.pairs_seen,
                st.elapsed / 60.0,
                v.net_recall,
                v.net_mre,
                v.net_mte,
                v.icp_recall,
                st.best_score.unwrap_or(f64::NAN),
                st.best_step,
                st.lr,
                v.seconds
            ));
            last_val = Some(v);
        }
        let ckpt_due = match cfg.checkpoint_every_steps {
            Some(s) => st.step.is_multiple_of(s),
            None => last_ckpt.elapsed().as_secs_f64() >= cfg.checkpoint_every_minutes * 60.0,
        };
        if ckpt_due {
            checkpoint::save(&ckpt_path, &st, &ts.params, &ts.adam, ts.ema.as_ref().map(|e| &e.params))?;
            logf.write(
                json!({"kind": "checkpoint", "step": st.step, "pairs_seen": st.pairs_seen, "elapsed": st.elapsed}),
            );
            last_ckpt = Instant::now();
        }
        if let Some((pb, by_time)) = &pb {
            if *by_time {
                pb.set_position(session.elapsed().as_secs_f64() as u64);
            } else {
                pb.set_position(st.step);
            }
            let vr = last_val.as_ref().map_or("-".to_string(), |v| format!("{:.3}", v.net_recall));
            pb.set_message(format!("loss {last_loss:.4} | val recall {vr} | {pps:.1} pairs/s | step {}", st.step));
        }
    }
    if a.final_val && st.last_val_step != st.step {
        let v = do_validate(&mut st, &ts, &mut logf)?;
        say(&format!(
            "final val @{}: net recall {:.3} MRE {:.2} | +ICP {:?}",
            st.step, v.net_recall, v.net_mre, v.icp_recall
        ));
    }
    st.cpu = cpu0 + process_cpu_seconds();
    checkpoint::save(&ckpt_path, &st, &ts.params, &ts.adam, ts.ema.as_ref().map(|e| &e.params))?;
    logf.write(json!({"kind": "end", "cpu": st.cpu, "step": st.step, "pairs_seen": st.pairs_seen, "elapsed": st.elapsed, "stopped_by_file": stopped_by_file, "best_score": st.best_score, "best_step": st.best_step}));
    if let Some((pb, _)) = pb {
        pb.finish();
    }
    eprintln!(
        "arps-train: step {}, {} pairs seen, {:.1} min, best score {:?} at step {} -> {}",
        st.step,
        st.pairs_seen,
        st.elapsed / 60.0,
        st.best_score,
        st.best_step,
        ckpt_path.display()
    );
    Ok(())
}

fn chrono_now() -> String {
    let s = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    format!("{:02}:{:02}:{:02}", (s / 3600) % 24, (s / 60) % 60, s % 60)
}

fn git_commit() -> Option<String> {
    let out = std::process::Command::new("git").args(["rev-parse", "HEAD"]).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The `bank_meshes` counts of the last session start in a run log (null when there is none).
fn last_bank_counts(log: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    text.lines()
        .rev()
        .filter(|l| l.contains("\"bank_meshes\""))
        .find_map(|l| serde_json::from_str::<serde_json::Value>(l).ok()?.get("bank_meshes").cloned())
        .unwrap_or(serde_json::Value::Null)
}

fn export_cmd(a: ExportArgs) -> Result<(), String> {
    let best = a.run.join("best.safetensors");
    let ckpt = a.run.join("checkpoint.safetensors");
    let checkpoint::Checkpoint { state: st, params, ema, .. } = checkpoint::load(&ckpt)?;
    let mut w = if a.latest || !best.exists() {
        if !a.latest {
            eprintln!("arps-train: no best.safetensors yet; exporting the latest checkpoint");
        }
        // a run that keeps a moving average validates and exports the average (checkpoints
        // hold one only while the run keeps it)
        let params = ema.as_ref().unwrap_or(&params);
        let mut p = provenance(&a.run, &st, (0, 0, 0, 0));
        // the bank is not loaded here: take its counts from the run's last session start
        p["data"]["bank_meshes"] = last_bank_counts(&a.run.join("log.jsonl"));
        p["step"] = json!(st.step);
        p["pairs_seen"] = json!(st.pairs_seen);
        p["wall_clock_s"] = json!(st.elapsed);
        p["validation"] = serde_json::Value::Null;
        train::to_weights(params, &st.config.model, p).map_err(|e| e.to_string())?
    } else {
        Weights::from_bytes(&std::fs::read(&best).map_err(|e| format!("{}: {e}", best.display()))?)
            .map_err(|e| e.to_string())?
    };
    if let Some(o) = w.provenance.as_object_mut() {
        o.insert("exported_by".into(), json!(TRAINER_VERSION));
        o.insert("git_commit".into(), json!(git_commit()));
        o.insert(
            "run_total".into(),
            json!({"steps": st.step, "pairs_seen": st.pairs_seen, "wall_clock_s": st.elapsed, "sessions": st.sessions}),
        );
        o.insert("stored_as".into(), json!(if a.f16 { "f16" } else { "f32" }));
    }
    let bytes = w.to_bytes(if a.f16 { StoreAs::F16 } else { StoreAs::F32 }).map_err(|e| e.to_string())?;
    Weights::from_bytes(&bytes).map_err(|e| format!("exported file does not load: {e}"))?;
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    }
    checkpoint::write_atomic(&a.out, &bytes).map_err(|e| format!("{}: {e}", a.out.display()))?;
    eprintln!("arps-train: wrote {} ({} bytes)", a.out.display(), bytes.len());
    Ok(())
}
