//! `arps-train init`, `stream` and `pack-bank`: thin wrappers over [`arps::train::run::stream`]
//! and [`arps::train::run::bank_pack`].

use super::StreamArgs;
use arps::train::run::{bank_pack, data::TrainData, stream as s, RunConfig};
use std::path::Path;

/// Starts a run without training: `run/config.json` and the step-0 checkpoint (the engine's
/// initialisation for the config's seed), which `train --resume` and the PyTorch trainer
/// continue. Refuses a directory that already holds a checkpoint.
pub fn init(run: &Path, cfg: &RunConfig) -> Result<(), String> {
    std::fs::create_dir_all(run).map_err(|e| format!("{}: {e}", run.display()))?;
    let ckpt = run.join("checkpoint.safetensors");
    if ckpt.exists() {
        return Err(format!("{} exists", ckpt.display()));
    }
    let json = serde_json::to_string_pretty(cfg).map_err(|e| e.to_string())?;
    let path = run.join("config.json");
    std::fs::write(&path, json + "\n").map_err(|e| format!("{}: {e}", path.display()))?;
    let params = arps::train::init_params(&cfg.model, cfg.seed).map_err(|e| e.to_string())?;
    let st = arps::train::run::RunState::new(cfg.clone());
    arps::train::run::checkpoint::save(&ckpt, &st, &params, &arps::train::Adam::new(cfg.lr), None)?;
    eprintln!("arps-train: wrote {} and {}", path.display(), ckpt.display());
    Ok(())
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

pub fn stream(a: &StreamArgs) -> Result<(), String> {
    let mut cfg = read_config(&a.config)?;
    if let Some(b) = &a.bank {
        cfg.bank = Some(b.to_string_lossy().into_owned());
    }
    let data = TrainData::new(&cfg)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(a.threads.max(1)).build().map_err(|e| e.to_string())?;
    let spec = s::StreamSpec {
        val: a.val,
        first_pair: a.first_pair,
        worker: a.worker,
        workers: a.workers,
        count: if a.val { Some(a.count.unwrap_or(cfg.val_pairs as u64)) } else { a.count },
    };
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::with_capacity(1 << 20, stdout.lock());
    s::write_stream(&mut out, &pool, &data, &cfg, &spec)
}

pub fn pack_bank(dir: &Path, out: &Path) -> Result<(), String> {
    let bank = arps::data::bank::load_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut bytes = Vec::new();
    bank_pack::write(&bank, &mut bytes).map_err(|e| e.to_string())?;
    arps::train::run::checkpoint::write_atomic(out, &bytes).map_err(|e| format!("{}: {e}", out.display()))?;
    eprintln!(
        "arps-train: packed {} meshes ({} skipped) into {} ({} bytes)",
        bank.meshes.len(),
        bank.skipped.len(),
        out.display(),
        bytes.len()
    );
    Ok(())
}
