//! The JSONL run log (`runs/NAME/log.jsonl`): one object per line, `"kind": "start" | "step" |
//! "val" | "checkpoint" | "end"` (the PyTorch trainer may add `"note"` lines, which readers skip),
//! each with `time` (Unix seconds), `elapsed` (training seconds over all sessions), `step` and
//! `pairs_seen`. A finished run's log may be stored gzipped next to
//! where the plain one would be (`log.jsonl.gz`); the readers here take either.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// Appends to a JSONL file.
pub struct JsonlLog {
    file: std::fs::File,
}

impl JsonlLog {
    /// Opens `path` for appending (creating it). A run stored with its log gzipped
    /// (`log.jsonl.gz` and no `log.jsonl`) gets it back as the plain file first, so a resumed
    /// run's log goes on from its history rather than beside it.
    pub fn open(path: &Path) -> std::io::Result<Self> {
        let gz = gz_path(path);
        if !path.exists() && gz.exists() {
            let text = read_text(path)?;
            let tmp = path.with_extension("jsonl.part");
            std::fs::write(&tmp, text)?;
            std::fs::rename(&tmp, path)?;
            std::fs::remove_file(&gz)?;
        }
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

/// `path` with `.gz` appended (`log.jsonl` -> `log.jsonl.gz`).
pub fn gz_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".gz");
    PathBuf::from(s)
}

/// The text of a log: `path` itself, or when it does not exist, `path.gz` decompressed.
pub fn read_text(path: &Path) -> std::io::Result<String> {
    match std::fs::read_to_string(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let gz = gz_path(path);
            let file = std::fs::File::open(&gz).map_err(|_| e)?;
            let mut text = String::new();
            flate2::read::GzDecoder::new(file)
                .read_to_string(&mut text)
                .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", gz.display())))?;
            Ok(text)
        }
        r => r,
    }
}

/// Reads every line of a log that parses as JSON ([`read_text`]: plain or gzipped).
pub fn read(path: &Path) -> std::io::Result<Vec<serde_json::Value>> {
    Ok(read_text(path)?.lines().filter_map(|l| serde_json::from_str(l).ok()).collect())
}
