//! `arps-train`: trains a DGMR-ARPS network on the CPU, checkpoints and resumes runs, and exports
//! the engine's weights.
//!
//! * `arps-train train --run runs/NAME [...]`: a run (new, or `--resume`d from its checkpoint).
//! * `arps-train export --run runs/NAME --out models/web.safetensors [--f16]`: best weights with
//!   provenance.
//! * `arps-train curves --run runs/NAME --out curve.svg`: validation recall / MRE and the training
//!   loss over wall-clock time.
//! * `arps-train init --run runs/NAME [train flags]`: a new run's configuration and step-0
//!   checkpoint, without training (for `stream` and the PyTorch trainer in `trainer/`).
//! * `arps-train stream --config runs/NAME/config.json [--worker K --workers W] [--val]`: training
//!   batches or validation pairs in the binary layout of `arps::train::run::stream`, on stdout.
//! * `arps-train pack-bank --bank DIR --out bank.arpsbank.gz`: the shape bank in one file.
//! * `arps-train grow --from runs/OLD --run runs/NEW --ffn-dim F`: a run whose network is wider
//!   and computes what the old one did, to train on (`arps::train::run::grow`).
//! * `arps-train slim --from runs/OLD --run runs/NEW`: the run's network without the optimiser's
//!   state, a third of the checkpoint or less, to keep as a line's resume point
//!   (`arps::train::run::slim`).
//!
//! The binary only parses arguments; the work is in `arps::train::run`.

use arps::data::pairs::{check_pose_angle, check_share};
use arps::train::run::session::{self, Export, ResumeChanges, Session, Start};
use arps::train::run::{Curriculum, RunConfig};
use arps::train::{CentroidMode, ConsistencyKind, LossConfig};
use arps::ModelConfig;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[macro_use]
#[path = "../common/out.rs"]
mod out;
mod curves;
mod oracle;
mod stream;

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
    /// Write a new run's configuration (`RUN/config.json`) from the `train` flags, for
    /// `stream` and the PyTorch trainer.
    Init(Box<TrainArgs>),
    /// Write training batches (or validation pairs) in the binary stream layout to stdout.
    Stream(StreamArgs),
    /// Pack a shape-bank directory into one gzipped file (usable wherever a bank path is).
    PackBank(PackBankArgs),
    /// Make a new run from a run's checkpoint with wider feed-forward layers that compute what
    /// the old ones did (new hidden units with zero output weights), to go on training it.
    Grow(GrowArgs),
    /// Make a new run holding only the network to go on from (the moving average, else the
    /// parameters) without Adam's moments: a third of the checkpoint or less; training it
    /// restarts Adam.
    Slim(SlimArgs),
}

#[derive(Args)]
struct SlimArgs {
    /// The run to copy (its checkpoint.safetensors; the run itself is not changed).
    #[arg(long)]
    from: PathBuf,
    /// The new run directory (must not hold a checkpoint).
    #[arg(long)]
    run: PathBuf,
}

#[derive(Args)]
struct GrowArgs {
    /// The run to grow (its checkpoint.safetensors; the run itself is not changed).
    #[arg(long)]
    from: PathBuf,
    /// The new run directory (must not hold a checkpoint).
    #[arg(long)]
    run: PathBuf,
    /// The attention blocks' new feed-forward width (larger than the run's).
    #[arg(long)]
    ffn_dim: usize,
    /// Seed of the new hidden units' input weights.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

#[derive(Args)]
struct StreamArgs {
    /// The run's configuration: a `config.json` from `init`, or a `checkpoint.json`.
    #[arg(long)]
    config: PathBuf,
    /// Validation pairs 0..COUNT of the held-out split instead of training batches.
    #[arg(long)]
    val: bool,
    /// Training: the stream index of the first pair of batch 0 (a resumed run's pairs seen).
    #[arg(long, default_value_t = 0)]
    first_pair: u64,
    /// This generator's number (0-based); it writes batches worker, worker + workers, ...
    #[arg(long, default_value_t = 0)]
    worker: u64,
    /// Generators in all.
    #[arg(long, default_value_t = 1)]
    workers: u64,
    /// Training: batches to write (default: until the reader closes the stream). Validation:
    /// pairs (default: the config's val_pairs).
    #[arg(long)]
    count: Option<u64>,
    /// Threads building the pairs of a batch.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Replace the configuration's bank path (e.g. a packed bank carried to another machine).
    #[arg(long)]
    bank: Option<PathBuf>,
}

#[derive(Args)]
struct PackBankArgs {
    /// Bank directory.
    #[arg(long)]
    bank: PathBuf,
    /// Output file (e.g. bank.arpsbank.gz).
    #[arg(long)]
    out: PathBuf,
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
    /// Pairs per step (default 8). On --resume, replaces the stored value (the pair stream goes
    /// on where it was: a CPU fork of a run trained at a GPU's batch size).
    #[arg(long)]
    batch: Option<usize>,
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
    /// Training pairs only: this share of them is a part of a shape (30-60% of it) against the
    /// whole shape, as a scan onto a model (default 0, the paper's protocol; validation always
    /// uses it). On --resume, replaces the stored value.
    #[arg(long)]
    part_whole: Option<f64>,
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
        Command::Train(a) => session(*a).and_then(|s| session::train(&s)),
        Command::Export(a) => session::export(&Export { run: a.run, out: a.out, f16: a.f16, latest: a.latest }),
        Command::Curves(a) => curves::run(&a.run, &a.out, a.x == "cpu"),
        Command::PartitionOracle(a) => oracle::run(&a.run, a.pairs, &a.kappa, a.points),
        Command::Init(a) => run_config(&a).and_then(|c| session::init(&a.run, &c)),
        Command::Stream(a) => stream::stream(&a),
        Command::PackBank(a) => stream::pack_bank(&a.bank, &a.out),
        Command::Grow(a) => arps::train::run::grow::grow(&a.from, &a.run, a.ffn_dim, a.seed),
        Command::Slim(a) => arps::train::run::slim::slim(&a.from, &a.run),
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
/// Pairs per step of a new run.
const DEFAULT_BATCH: usize = 8;

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

/// `--part-whole`, checked ([`check_share`]).
fn part_whole(a: &TrainArgs) -> Result<Option<f64>, String> {
    a.part_whole.map(|v| check_share(v).map_err(|e| format!("--part-whole {e}"))).transpose()
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

/// The session the arguments ask for.
fn session(a: TrainArgs) -> Result<Session, String> {
    let start = if a.resume {
        if let Some((flag, _, _)) = size_flags(&a).first() {
            return Err(format!("{flag} sets the size of a new run; a resumed run keeps its model's size"));
        }
        Start::Resume(Box::new(ResumeChanges {
            threads: a.threads.max(1),
            val_every_minutes: a.val_every_minutes,
            curriculum: a.curriculum.as_deref().map(Curriculum::parse).transpose()?,
            icp_every: a.icp_every,
            checkpoint_every_minutes: a.checkpoint_every_minutes,
            val_every_steps: a.val_every_steps,
            patience: a.patience,
            network_points: a.network_points,
            pose_angle_deg: pose_angle(&a)?,
            part_whole: part_whole(&a)?,
            ema_decay: ema_decay(&a)?,
            loss: a.loss.is_some().then(|| parse_loss(&a)).transpose()?,
            lr: a.lr,
            batch: a.batch,
        }))
    } else {
        Start::New(Box::new(run_config(&a)?))
    };
    Ok(Session {
        run: a.run,
        start,
        minutes: a.minutes,
        cpu_minutes: a.cpu_minutes,
        steps: a.steps,
        final_val: a.final_val,
        quiet: a.quiet,
    })
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
        batch: a.batch.unwrap_or(DEFAULT_BATCH),
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
        part_whole: part_whole(a)?.unwrap_or(0.0),
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
