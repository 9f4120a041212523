//! What the `arps-train` subcommands do, behind the binary's argument parsing: one training
//! session of a run ([`train()`] of a [`Session`]), the export of a run's weights ([`export`]),
//! a new run's configuration and step-0 checkpoint without training ([`init`], for the data
//! stream and the PyTorch trainer), and reading a run configuration back ([`read_config`]).

use super::{
    checkpoint, data::TrainData, log, process_cpu_seconds, validate, Curriculum, RunConfig, RunState, ValMetrics,
    TRAINER_VERSION,
};
use crate::train::{self, LossConfig, LossParts, TrainState};
use crate::{StoreAs, Weights};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The provenance an exported weights file carries: trainer, run, the best step and its
/// validation, data, losses, optimiser and seed.
pub fn provenance(run: &Path, st: &RunState, bank_counts: (usize, usize, usize, usize)) -> serde_json::Value {
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
            "part_whole": c.part_whole,
            "curriculum": c.curriculum,
            "val_pairs": c.val_pairs,
        },
        "losses": c.loss,
        "optimiser": {"adam_lr": c.lr, "warmup_steps": c.warmup_steps, "clip_norm": c.clip_norm, "batch": c.batch, "plateau_patience": c.plateau_patience, "ema_decay": c.ema_decay},
        "seed": c.seed,
    })
}

/// A log line's `loss` object.
pub fn loss_json(l: &LossParts) -> serde_json::Value {
    let r = |v: f64| (v * 1e6).round() / 1e6;
    json!({
        "total": r(l.total), "sup": r(l.sup), "ctr": r(l.ctr), "ctr_no_shift": r(l.ctr_no_shift), "aff": r(l.aff),
        "reg": r(l.reg), "consistency": r(l.consistency), "consistency_pairs": r(l.consistency_pairs),
        "means": r(l.means), "means_spread": r(l.means_spread), "gamma_entropy": r(l.gamma_entropy), "seg": r(l.seg),
        "steps": l.steps.iter().map(|&s| r(s)).collect::<Vec<_>>(),
    })
}

/// Where a session starts: a new run, or a resumed one with the changes it takes.
#[derive(Clone, Debug)]
pub enum Start {
    /// A new run with this configuration (its directory must not hold a checkpoint yet).
    New(Box<RunConfig>),
    /// Continue the run from its checkpoint, with these changes to its stored configuration.
    Resume(Box<ResumeChanges>),
}

/// Changes a resumed run takes (None keeps the stored value).
#[derive(Clone, Debug, Default)]
pub struct ResumeChanges {
    /// Worker threads (always replaced).
    pub threads: usize,
    /// [`RunConfig::val_every_minutes`].
    pub val_every_minutes: Option<f64>,
    /// [`RunConfig::curriculum`] from the current pair on.
    pub curriculum: Option<Curriculum>,
    /// [`RunConfig::icp_every_validations`].
    pub icp_every: Option<u32>,
    /// [`RunConfig::checkpoint_every_minutes`].
    pub checkpoint_every_minutes: Option<f64>,
    /// [`RunConfig::val_every_steps`] (0 turns the step schedule off).
    pub val_every_steps: Option<u64>,
    /// [`RunConfig::plateau_patience`] (resets the plateau counter).
    pub patience: Option<u32>,
    /// The model's N (a fork that fine-tunes at another N; the weights do not depend on it).
    pub network_points: Option<usize>,
    /// [`RunConfig::pose_angle_deg`].
    pub pose_angle_deg: Option<f64>,
    /// [`RunConfig::part_whole`].
    pub part_whole: Option<f64>,
    /// [`RunConfig::ema_decay`]: `Some(None)` turns the average off.
    pub ema_decay: Option<Option<f32>>,
    /// [`RunConfig::loss`].
    pub loss: Option<LossConfig>,
    /// The current base lr (resets the plateau counter).
    pub lr: Option<f32>,
    /// [`RunConfig::batch`] (a CPU fork of a run trained at a GPU's batch size).
    pub batch: Option<usize>,
}

/// One training session of a run.
#[derive(Clone, Debug)]
pub struct Session {
    /// Run directory (`checkpoint.safetensors`, `best.safetensors`, `log.jsonl`).
    pub run: PathBuf,
    /// New or resumed.
    pub start: Start,
    /// Stop after this many wall-clock minutes of this session.
    pub minutes: Option<f64>,
    /// Stop after this many minutes of process CPU time of this session.
    pub cpu_minutes: Option<f64>,
    /// Stop when the run's step count reaches this (total over all sessions).
    pub steps: Option<u64>,
    /// Validate once more at the end (if the last step was not validated).
    pub final_val: bool,
    /// No progress bar (plain log lines on stderr instead).
    pub quiet: bool,
}

/// Applies `c` to a loaded run state.
fn apply_changes(st: &mut RunState, c: &ResumeChanges) -> Result<(), String> {
    st.config.threads = c.threads.max(1);
    if let Some(v) = c.val_every_minutes {
        st.config.val_every_minutes = v;
    }
    if let Some(v) = &c.curriculum {
        st.config.curriculum = v.clone();
    }
    if let Some(v) = c.icp_every {
        st.config.icp_every_validations = v;
    }
    if let Some(v) = c.checkpoint_every_minutes {
        st.config.checkpoint_every_minutes = v;
    }
    if let Some(v) = c.val_every_steps {
        st.config.val_every_steps = Some(v).filter(|&s| s > 0);
    }
    if let Some(v) = c.patience {
        st.config.plateau_patience = v;
        st.bad_validations = 0;
    }
    if let Some(n) = c.network_points {
        st.set_network_points(n)?;
    }
    if let Some(v) = c.pose_angle_deg {
        st.config.pose_angle_deg = v;
    }
    if let Some(v) = c.part_whole {
        st.config.part_whole = v;
    }
    if let Some(v) = c.ema_decay {
        st.config.ema_decay = v;
    }
    if let Some(l) = &c.loss {
        st.config.loss = l.clone();
    }
    if let Some(lr) = c.lr {
        if !(lr.is_finite() && lr > 0.0) {
            return Err(format!("--lr {lr} must be a positive number"));
        }
        st.lr = lr;
        st.bad_validations = 0;
    }
    if let Some(b) = c.batch {
        st.config.batch = b;
    }
    Ok(())
}

/// Runs one training session: loads or creates the run, builds the validation set, trains until
/// a limit (or a `STOP` file in the run directory), validates, checkpoints and logs on the run's
/// schedule, and leaves a final checkpoint.
pub fn train(a: &Session) -> Result<(), String> {
    std::fs::create_dir_all(&a.run).map_err(|e| format!("{}: {e}", a.run.display()))?;
    let ckpt_path = a.run.join("checkpoint.safetensors");
    let best_path = a.run.join("best.safetensors");
    let (mut st, params, adam, ema) = match &a.start {
        Start::Resume(changes) => {
            let checkpoint::Checkpoint { state: mut st, params: p, adam, ema } = checkpoint::load(&ckpt_path)?;
            apply_changes(&mut st, changes)?;
            (st, p, adam, ema)
        }
        Start::New(cfg) => {
            if ckpt_path.exists() {
                return Err(format!("{} exists: use --resume, or another --run", ckpt_path.display()));
            }
            let cfg = (**cfg).clone();
            let params = train::init_params(&cfg.model, cfg.seed).map_err(|e| e.to_string())?;
            let lr = cfg.lr;
            (RunState::new(cfg), params, train::Adam::new(lr), None)
        }
    };
    // a new run's configuration or a resumed run's changes: only `--batch 0` can give this
    if st.config.batch == 0 {
        return Err("--batch 0: a step needs at least one pair".into());
    }
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
                .collect::<crate::Result<Vec<_>>>()
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
                    .collect::<crate::Result<Vec<_>>>()
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

/// `HH:MM:SS` (UTC) for log lines on stderr.
pub fn chrono_now() -> String {
    let s = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    format!("{:02}:{:02}:{:02}", (s / 3600) % 24, (s / 60) % 60, s % 60)
}

fn git_commit() -> Option<String> {
    let out = std::process::Command::new("git").args(["rev-parse", "HEAD"]).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The `bank_meshes` counts of the last session start in a run log (null when there is none).
fn last_bank_counts(log: &Path) -> serde_json::Value {
    let text = log::read_text(log).unwrap_or_default();
    text.lines()
        .rev()
        .filter(|l| l.contains("\"bank_meshes\""))
        .find_map(|l| serde_json::from_str::<serde_json::Value>(l).ok()?.get("bank_meshes").cloned())
        .unwrap_or(serde_json::Value::Null)
}

/// What [`export`] writes.
#[derive(Clone, Debug)]
pub struct Export {
    /// Run directory.
    pub run: PathBuf,
    /// Output weights file.
    pub out: PathBuf,
    /// Store f16 (the shipped model); else f32.
    pub f16: bool,
    /// The latest checkpoint's parameters (their moving average, if the run keeps one) instead
    /// of the best validation's.
    pub latest: bool,
}

/// Exports a run's best (or latest) weights in the engine's format with provenance, checks that
/// the file loads, and writes it atomically.
pub fn export(a: &Export) -> Result<(), String> {
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

/// Starts a run without training: `run/config.json` and the step-0 checkpoint (the engine's
/// initialisation for the config's seed), which `train --resume` and the PyTorch trainer
/// continue. Refuses a directory that already holds a checkpoint.
pub fn init(run: &Path, cfg: &RunConfig) -> Result<(), String> {
    std::fs::create_dir_all(run).map_err(|e| format!("{}: {e}", run.display()))?;
    let ckpt = run.join("checkpoint.safetensors");
    if ckpt.exists() {
        return Err(format!("{} exists", ckpt.display()));
    }
    let path = write_config(run, cfg)?;
    let params = train::init_params(&cfg.model, cfg.seed).map_err(|e| e.to_string())?;
    let st = RunState::new(cfg.clone());
    checkpoint::save(&ckpt, &st, &params, &train::Adam::new(cfg.lr), None)?;
    eprintln!("arps-train: wrote {} and {}", path.display(), ckpt.display());
    Ok(())
}

/// Writes `run/config.json` (the configuration `stream` and the PyTorch trainer read); returns
/// its path.
pub fn write_config(run: &Path, cfg: &RunConfig) -> Result<PathBuf, String> {
    let json = serde_json::to_string_pretty(cfg).map_err(|e| e.to_string())?;
    let path = run.join("config.json");
    std::fs::write(&path, json + "\n").map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// Reads a run configuration: a [`RunConfig`] or any object with one under `config`.
pub fn read_config(path: &Path) -> Result<RunConfig, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let v = match v.get("config") {
        Some(c) => c.clone(),
        None => v,
    };
    serde_json::from_value(v).map_err(|e| format!("{}: not a run configuration: {e}", path.display()))
}
