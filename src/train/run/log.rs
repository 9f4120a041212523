//! The JSONL run log (`runs/NAME/log.jsonl`): one object per line, `"kind": "start" | "step" |
//! "val" | "checkpoint" | "end"`, each with `time` (Unix seconds), `elapsed` (training seconds over
//! all sessions), `step` and `pairs_seen`.

use std::io::Write;
use std::path::Path;

/// Appends to a JSONL file.
pub struct JsonlLog {
    file: std::fs::File,
}

impl JsonlLog {
    /// Opens `path` for appending (creating it).
    pub fn open(path: &Path) -> std::io::Result<Self> {
        Ok(Self { file: std::fs::OpenOptions::new().create(true).append(true).open(path)? })
    }

    /// Writes one line (adds `time`).
    pub fn write(&mut self, mut value: serde_json::Value) {
        if let Some(o) = value.as_object_mut() {
            let now = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_secs_f64())
                .unwrap_or(0.0);
            o.insert("time".into(), serde_json::json!((now * 1000.0).round() / 1000.0));
        }
        let _ = writeln!(self.file, "{value}");
        let _ = self.file.flush();
    }
}

/// Reads every line of a log that parses as JSON.
pub fn read(path: &Path) -> std::io::Result<Vec<serde_json::Value>> {
    Ok(std::fs::read_to_string(path)?.lines().filter_map(|l| serde_json::from_str(l).ok()).collect())
}
