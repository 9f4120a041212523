//! A new run made from another run's checkpoint (a wider network, [`super::grow`]; a smaller
//! checkpoint, [`super::slim`]): its configuration, the old run's log so far with a `note` line
//! saying what changed, and the new checkpoint. An existing run is never overwritten.

use super::checkpoint::{self, Checkpoint};
use super::log;
use std::path::Path;

/// Loads `from`'s checkpoint (`checkpoint.safetensors`), after checking that `run` holds none.
pub fn load_source(from: &Path, run: &Path) -> Result<Checkpoint, String> {
    let ckpt = run.join("checkpoint.safetensors");
    if ckpt.exists() {
        return Err(format!("{} exists", ckpt.display()));
    }
    checkpoint::load(&from.join("checkpoint.safetensors"))
}

/// Writes `new` as the run in `run`: `config.json`, `from`'s log (`log.jsonl`, when it has one)
/// followed by a `note` line, and `checkpoint.safetensors`.
pub fn write(from: &Path, run: &Path, new: &Checkpoint, note: String) -> Result<(), String> {
    std::fs::create_dir_all(run).map_err(|e| format!("{}: {e}", run.display()))?;
    super::session::write_config(run, &new.state.config)?;
    let log_path = run.join("log.jsonl");
    let history = match log::read_text(&from.join("log.jsonl")) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(format!("{}: {e}", from.join("log.jsonl").display())),
    };
    std::fs::write(&log_path, history).map_err(|e| format!("{}: {e}", log_path.display()))?;
    let st = &new.state;
    log::JsonlLog::open(&log_path).map_err(|e| format!("{}: {e}", log_path.display()))?.write(serde_json::json!({
        "kind": "note", "step": st.step, "pairs_seen": st.pairs_seen, "elapsed": st.elapsed, "note": note,
    }));
    checkpoint::save(&run.join("checkpoint.safetensors"), st, &new.params, &new.adam, new.ema.as_ref())
}
