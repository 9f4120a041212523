//! A training run on disk (the `arps-train` binary's library side): run configuration and state,
//! the curriculum, training pairs in the engine's frames, checkpoints, validation with the engine
//! and the JSONL log.
//!
//! * [`RunConfig`]: everything that defines a run (model, losses, data, optimiser, schedule).
//! * [`RunState`]: where a run is (step, pairs seen = the data cursor, lr, best score, ...).
//! * [`curriculum`]: [`Curriculum`] ramps the pair protocol from easy to the paper's.
//! * [`data`]: [`data::TrainData`] turns stream index `i` into a [`crate::train::Pair`] exactly as
//!   the engine sees it at inference.
//! * [`checkpoint`]: atomic checkpoints (parameters + Adam moments + state in one safetensors).
//! * [`validate`]: the fixed validation set and its metrics, computed with the engine.
//! * [`log`]: JSONL lines.
//! * [`bank_pack`]: the shape bank packed into one gzipped file.
//! * [`stream`]: the binary training-data stream another trainer reads.
//! * [`grow`]: a run's network made wider without changing what it computes, to train on.
//! * [`slim`]: a run's checkpoint without the optimiser's state, to keep as a line's resume point.
//! * [`fork`]: writing a new run made from another run's checkpoint (`grow`, `slim`).
//! * [`session`]: [`session::train`] runs one training session, [`session::export`] exports
//!   weights, [`session::init`] starts a run without training.

pub mod bank_pack;
pub mod checkpoint;
pub mod curriculum;
pub mod data;
pub mod fork;
pub mod grow;
pub mod log;
pub mod session;
pub mod slim;
pub mod stream;
pub mod validate;

pub use curriculum::Curriculum;

use crate::model::ModelConfig;
use crate::train::LossConfig;
use serde::{Deserialize, Serialize};

/// Version string of the trainer (written into checkpoints and exported provenance).
pub const TRAINER_VERSION: &str = concat!("arps-train ", env!("CARGO_PKG_VERSION"));

/// Everything that defines a run. Stored in every checkpoint; `--resume` uses the stored one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunConfig {
    /// Network sizes.
    pub model: ModelConfig,
    /// Loss switches.
    pub loss: LossConfig,
    /// Pairs per step.
    pub batch: usize,
    /// Peak learning rate.
    pub lr: f32,
    /// Linear warm-up from `lr / warmup_steps` to `lr` over this many steps.
    pub warmup_steps: u64,
    /// Global gradient-norm clip (None = off).
    pub clip_norm: Option<f64>,
    /// Halve the lr after this many validations without improvement.
    pub plateau_patience: u32,
    /// Lower bound of the lr.
    pub min_lr: f32,
    /// Seed of the parameter initialisation and of the training stream.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// Shape bank directory (None = procedural shapes only).
    pub bank: Option<String>,
    /// Fraction of bank shapes held out for validation (by a hash of the name).
    pub val_fraction: f64,
    /// Probability that a pair uses a bank shape.
    pub bank_fraction: f64,
    /// Points per cloud of a generated pair (the network then samples `model.n_points`).
    pub pair_points: usize,
    /// The curriculum (training pairs only; validation always uses the full protocol).
    pub curriculum: Curriculum,
    /// Training pairs only: the whole shape is first turned by Euler angles up to this many
    /// degrees ([`crate::data::PairParams::pose_angle_deg`]; 0, the default, is the paper's
    /// protocol, in which the source keeps the shape's own orientation).
    #[serde(default)]
    pub pose_angle_deg: f64,
    /// Training pairs only: this share of them (chosen by a hash of the stream index) is a part
    /// of a shape against the whole of it, as when a scan is registered onto a model: the
    /// source's crop keeps a fraction in [`data::PART_KEEP`] of the shape, the target all of it
    /// ([`crate::data::PairParams::target_keep_ratio`]). 0, the default, is the paper's protocol.
    #[serde(default)]
    pub part_whole: f64,
    /// Keep a moving average of the parameters with this decay per step (None = off). When set,
    /// validation, `best.safetensors` and `export --latest` use the average; the current
    /// parameters are also validated and logged (`val_raw`).
    #[serde(default)]
    pub ema_decay: Option<f32>,
    /// Validation pairs (indices 0.. of the validation split: the same pairs as
    /// `arps make-pairs --split val --seed 0`).
    pub val_pairs: usize,
    /// Validate every this many minutes of wall-clock (ignored when `val_every_steps` is set).
    pub val_every_minutes: f64,
    /// Validate every this many steps (deterministic schedule; overrides the minutes).
    pub val_every_steps: Option<u64>,
    /// Also run network + ICP every this many validations (0 = never).
    pub icp_every_validations: u32,
    /// Checkpoint every this many minutes.
    pub checkpoint_every_minutes: f64,
    /// Checkpoint every this many steps (overrides the minutes).
    pub checkpoint_every_steps: Option<u64>,
    /// Write a step line to the log every this many steps.
    pub log_every_steps: u64,
}

/// Validation figures (network only, and optionally network + ICP).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ValMetrics {
    /// Pairs.
    pub pairs: usize,
    /// Network-only recall (RE < 15 deg and TE < 0.2).
    pub net_recall: f64,
    /// Network-only mean rotation error, degrees.
    pub net_mre: f64,
    /// Network-only mean translation error.
    pub net_mte: f64,
    /// Network + point-to-plane ICP recall (when computed).
    pub icp_recall: Option<f64>,
    /// Network + ICP MRE (when computed).
    pub icp_mre: Option<f64>,
    /// Mean step size per layer of the engine's forward pass over the validation pairs.
    pub steps: Vec<f64>,
    /// Seconds the validation took.
    pub seconds: f64,
}

impl ValMetrics {
    /// The score the plateau schedule and `best.safetensors` use: network recall minus 0.002 per
    /// degree of network MRE (recall moves in steps of 1/pairs; the MRE term breaks ties and
    /// shows progress while recall is still flat).
    pub fn score(&self) -> f64 {
        self.net_recall - 0.002 * self.net_mre
    }
}

/// Where a run is. With the parameters and Adam moments this is a complete checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    /// Trainer version that wrote it.
    pub trainer: String,
    /// The run's configuration.
    pub config: RunConfig,
    /// Steps taken (including skipped ones).
    pub step: u64,
    /// Steps skipped (non-finite loss or gradient).
    pub skipped_steps: u64,
    /// Training pairs consumed: the data cursor (pair `i` of the stream is index `i`).
    pub pairs_seen: u64,
    /// Current base learning rate (after plateau halvings; warm-up is applied on top).
    pub lr: f32,
    /// Adam's update count.
    pub adam_t: u64,
    /// Best validation score so far.
    pub best_score: Option<f64>,
    /// Step of the best validation.
    pub best_step: u64,
    /// Pairs seen at the best validation.
    pub best_pairs_seen: u64,
    /// Wall-clock seconds at the best validation.
    pub best_elapsed: f64,
    /// The best validation's metrics.
    pub best_val: Option<ValMetrics>,
    /// Validations since the last improvement.
    pub bad_validations: u32,
    /// Validations run.
    pub validations: u64,
    /// Training wall-clock seconds over all sessions.
    pub elapsed: f64,
    /// `elapsed` at the last validation.
    pub last_val_elapsed: f64,
    /// Step of the last validation.
    pub last_val_step: u64,
    /// Number of sessions (starts + resumes).
    pub sessions: u32,
    /// Process CPU seconds (user + system) over all sessions: the fair clock on a shared machine.
    #[serde(default)]
    pub cpu: f64,
}

/// CPU seconds (user + system) this process has used so far (Linux `/proc/self/stat`; 0 elsewhere).
pub fn process_cpu_seconds() -> f64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/stat") else { return 0.0 };
    // fields after the command name (which is in parentheses and may contain spaces)
    let Some(rest) = s.rfind(')').map(|i| &s[i + 1..]) else { return 0.0 };
    let f: Vec<&str> = rest.split_whitespace().collect();
    // rest starts at field 3 (state); utime is field 14, stime field 15 (1-based)
    let ticks = |i: usize| f.get(i - 3).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(14) + ticks(15)) / 100.0
}

impl RunState {
    /// A fresh run.
    pub fn new(config: RunConfig) -> Self {
        Self {
            trainer: TRAINER_VERSION.to_string(),
            lr: config.lr,
            config,
            step: 0,
            skipped_steps: 0,
            pairs_seen: 0,
            adam_t: 0,
            best_score: None,
            best_step: 0,
            best_pairs_seen: 0,
            best_elapsed: 0.0,
            best_val: None,
            bad_validations: 0,
            validations: 0,
            elapsed: 0.0,
            last_val_elapsed: 0.0,
            last_val_step: 0,
            sessions: 0,
            cpu: 0.0,
        }
    }

    /// The learning rate of the next step: the base lr with linear warm-up.
    pub fn effective_lr(&self) -> f32 {
        let w = self.config.warmup_steps;
        if w == 0 || self.step >= w {
            self.lr
        } else {
            self.lr * (self.step + 1) as f32 / w as f32
        }
    }

    /// Forks the run to another network N: the best validation so far was measured at the old N,
    /// so it is forgotten (the plateau rule and the best weights then compare like with like).
    pub fn set_network_points(&mut self, n: usize) -> Result<(), String> {
        if n == self.config.model.n_points {
            return Ok(());
        }
        let old = self.config.model.n_points;
        self.config.model.n_points = n;
        if let Err(e) = self.config.model.validate() {
            self.config.model.n_points = old;
            return Err(format!("--network-points {n}: {e}"));
        }
        self.best_score = None;
        self.best_val = None;
        self.bad_validations = 0;
        Ok(())
    }

    /// Records a validation: updates the best score (returns true when it improved) and the
    /// plateau counter, halving the lr after `plateau_patience` validations without improvement.
    pub fn record_validation(&mut self, v: &ValMetrics) -> bool {
        self.validations += 1;
        self.last_val_elapsed = self.elapsed;
        self.last_val_step = self.step;
        let s = v.score();
        let improved = self.best_score.is_none_or(|b| s > b);
        if improved {
            self.best_score = Some(s);
            self.best_step = self.step;
            self.best_pairs_seen = self.pairs_seen;
            self.best_elapsed = self.elapsed;
            self.best_val = Some(v.clone());
            self.bad_validations = 0;
        } else {
            self.bad_validations += 1;
            if self.bad_validations >= self.config.plateau_patience.max(1) {
                self.lr = (self.lr * 0.5).max(self.config.min_lr);
                self.bad_validations = 0;
            }
        }
        improved
    }
}
