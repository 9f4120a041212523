//! Checkpoints: one safetensors file holding the parameters (`param/<name>`), Adam's moments
//! (`adam_m/<name>`, `adam_v/<name>`), the parameters' moving average when the run keeps one
//! (`ema/<name>`), all `f32`, and the [`RunState`] as JSON in the metadata key
//! `arps_train_state`. Written atomically (temporary file, fsync, rename), so a crash never leaves
//! a half-written checkpoint.

use super::RunState;
use crate::train::{Adam, Params};
use safetensors::tensor::{Dtype, TensorView};
use safetensors::SafeTensors;
use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

/// Metadata key of the run state.
pub const STATE_KEY: &str = "arps_train_state";

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}

/// Everything a checkpoint holds.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// Where the run is, with its configuration.
    pub state: RunState,
    /// The current parameters.
    pub params: Params,
    /// The optimiser.
    pub adam: Adam,
    /// The parameters' moving average (runs with `ema_decay` set; its decay is the config's).
    pub ema: Option<Params>,
}

/// Serialises a checkpoint.
pub fn to_bytes(state: &RunState, params: &Params, adam: &Adam, ema: Option<&Params>) -> Result<Vec<u8>, String> {
    let mut raw: Vec<(String, Vec<u8>)> = Vec::new();
    let empty = Params::new();
    for (prefix, map) in [("param", params), ("adam_m", &adam.m), ("adam_v", &adam.v), ("ema", ema.unwrap_or(&empty))] {
        for (name, v) in map {
            raw.push((format!("{prefix}/{name}"), v.iter().flat_map(|x| x.to_le_bytes()).collect()));
        }
    }
    let views = raw
        .iter()
        .map(|(n, b)| {
            TensorView::new(Dtype::F32, vec![b.len() / 4], b).map(|v| (n.clone(), v)).map_err(|e| e.to_string())
        })
        .collect::<Result<Vec<_>, String>>()?;
    let mut meta = HashMap::new();
    meta.insert(STATE_KEY.to_string(), serde_json::to_string(state).map_err(|e| e.to_string())?);
    meta.insert(
        "adam".to_string(),
        serde_json::json!({"lr": adam.lr, "beta1": adam.beta1, "beta2": adam.beta2, "eps": adam.eps, "t": adam.t})
            .to_string(),
    );
    safetensors::serialize(views, Some(meta)).map_err(|e| e.to_string())
}

/// Reads a checkpoint.
pub fn from_bytes(bytes: &[u8]) -> Result<Checkpoint, String> {
    let st = SafeTensors::deserialize(bytes).map_err(|e| format!("bad checkpoint: {e}"))?;
    let (_, meta) = SafeTensors::read_metadata(bytes).map_err(|e| format!("bad checkpoint header: {e}"))?;
    let meta = meta.metadata().clone().unwrap_or_default();
    let state: RunState = serde_json::from_str(meta.get(STATE_KEY).ok_or("checkpoint has no run state")?)
        .map_err(|e| format!("checkpoint run state: {e}"))?;
    let a: serde_json::Value = serde_json::from_str(meta.get("adam").ok_or("checkpoint has no Adam metadata")?)
        .map_err(|e| format!("checkpoint Adam metadata: {e}"))?;
    let mut adam = Adam::new(a["lr"].as_f64().unwrap_or(0.0) as f32);
    adam.beta1 = a["beta1"].as_f64().unwrap_or(0.9) as f32;
    adam.beta2 = a["beta2"].as_f64().unwrap_or(0.999) as f32;
    adam.eps = a["eps"].as_f64().unwrap_or(1e-8) as f32;
    adam.t = a["t"].as_u64().unwrap_or(0);
    let mut params = Params::new();
    let mut ema = Params::new();
    for (name, view) in st.tensors() {
        if view.dtype() != Dtype::F32 {
            return Err(format!("checkpoint tensor {name} is not f32"));
        }
        let v: Vec<f32> = view.data().chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        if let Some(n) = name.strip_prefix("param/") {
            params.insert(n.to_string(), v);
        } else if let Some(n) = name.strip_prefix("adam_m/") {
            adam.m.insert(n.to_string(), v);
        } else if let Some(n) = name.strip_prefix("adam_v/") {
            adam.v.insert(n.to_string(), v);
        } else if let Some(n) = name.strip_prefix("ema/") {
            ema.insert(n.to_string(), v);
        }
    }
    let ema = (!ema.is_empty()).then_some(ema);
    Ok(Checkpoint { state, params, adam, ema })
}

/// Saves a checkpoint atomically, plus a human-readable copy of the state next to it
/// (`<path>.json`, informational only; `--resume` reads the safetensors file).
pub fn save(path: &Path, state: &RunState, params: &Params, adam: &Adam, ema: Option<&Params>) -> Result<(), String> {
    let bytes = to_bytes(state, params, adam, ema)?;
    write_atomic(path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let json = serde_json::to_string_pretty(state).map_err(|e| e.to_string())?;
    write_atomic(&path.with_extension("json"), json.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}

/// Loads a checkpoint.
pub fn load(path: &Path) -> Result<Checkpoint, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    from_bytes(&bytes)
}
