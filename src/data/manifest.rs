//! Pair sets on disk: `pairs.tsv` (as in `fixtures/pairs/pairs.tsv`) and the
//! optional `pairs.json` sidecar that generated sets carry.
//!
//! `pairs.tsv` is tab-separated with a header line and the columns
//! `name, source, target, overlap_threshold, note, T_target_source_4x4_rowmajor`; `source` and
//! `target` are paths relative to the manifest's directory, `overlap_threshold` is the distance
//! under which two points count as overlapping (the pair's units), and the last column holds the
//! 16 numbers of the GT `T_target_source` (maps source points into the target frame), row-major,
//! separated by spaces.

use crate::transform;
use nalgebra::Matrix4;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The header line of `pairs.tsv`.
pub const HEADER: &str = "name\tsource\ttarget\toverlap_threshold\tnote\tT_target_source_4x4_rowmajor";

/// One line of a manifest.
#[allow(non_snake_case)]
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Pair name.
    pub name: String,
    /// Source file, as written (relative to the manifest's directory unless absolute).
    pub source: String,
    /// Target file, as written.
    pub target: String,
    /// Overlap distance threshold, the pair's units.
    pub overlap_threshold: f64,
    /// Free text.
    pub note: String,
    /// GT: maps source points into the target frame.
    pub T_target_source: Matrix4<f64>,
}

impl Entry {
    /// The source path resolved against the manifest's directory.
    pub fn source_path(&self, manifest: &Path) -> PathBuf {
        resolve(manifest, &self.source)
    }
    /// The target path resolved against the manifest's directory.
    pub fn target_path(&self, manifest: &Path) -> PathBuf {
        resolve(manifest, &self.target)
    }
}

fn resolve(manifest: &Path, file: &str) -> PathBuf {
    let p = Path::new(file);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        manifest.parent().unwrap_or(Path::new(".")).join(p)
    }
}

/// Parses a manifest's text. Errors name the line.
pub fn parse(text: &str) -> Result<Vec<Entry>, String> {
    let mut out = Vec::new();
    for (ln, line) in text.lines().enumerate() {
        let line = line.trim_end_matches('\r');
        if line.trim().is_empty() || line.starts_with('#') || (ln == 0 && line.starts_with("name\t")) {
            continue;
        }
        let cols: Vec<&str> = line.split('\t').collect();
        if cols.len() != 6 {
            return Err(format!("line {}: {} tab-separated columns, expected 6", ln + 1, cols.len()));
        }
        let overlap_threshold = cols[3]
            .trim()
            .parse::<f64>()
            .map_err(|e| format!("line {}: overlap_threshold {:?}: {e}", ln + 1, cols[3]))?;
        let nums: Vec<f64> = cols[5]
            .split_whitespace()
            .map(|s| s.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("line {}: transform: {e}", ln + 1))?;
        if nums.len() != 16 {
            return Err(format!("line {}: transform has {} numbers, expected 16", ln + 1, nums.len()));
        }
        let t = Matrix4::from_fn(|r, c| nums[r * 4 + c]);
        transform::check_rigid(&t, 1e-3).map_err(|e| format!("line {}: transform: {e}", ln + 1))?;
        out.push(Entry {
            name: cols[0].to_string(),
            source: cols[1].to_string(),
            target: cols[2].to_string(),
            overlap_threshold,
            note: cols[4].to_string(),
            T_target_source: t,
        });
    }
    Ok(out)
}

/// Reads and parses a manifest file.
pub fn read(path: &Path) -> Result<Vec<Entry>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Formats a manifest (header + one line per entry; numbers in shortest round-trip form).
pub fn format(entries: &[Entry]) -> String {
    let mut s = String::from(HEADER);
    s.push('\n');
    for e in entries {
        let t: Vec<String> = (0..16).map(|i| format!("{}", e.T_target_source[(i / 4, i % 4)])).collect();
        let clean = |x: &str| x.replace(['\t', '\n'], " ");
        s.push_str(&format!(
            "{}\t{}\t{}\t{}\t{}\t{}\n",
            clean(&e.name),
            clean(&e.source),
            clean(&e.target),
            e.overlap_threshold,
            clean(&e.note),
            t.join(" ")
        ));
    }
    s
}

/// Per-pair facts a generated set records beyond the manifest (`pairs.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairMeta {
    /// Pair name (the manifest's `name`).
    pub name: String,
    /// Shape name.
    pub shape: String,
    /// Pair seed.
    pub seed: u64,
    /// Crop overlap.
    pub overlap: f64,
    /// Full-shape centroid in the source frame (not pre-centred).
    pub centroid_source: [f64; 3],
    /// Full-shape centroid in the target frame (not pre-centred).
    pub centroid_target: [f64; 3],
}

/// The `pairs.json` sidecar of a generated set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sidecar {
    /// `"normalized"`: coordinates are in the normalised units of each full shape (largest
    /// half-extent 1), so errors need no rescaling.
    pub units: String,
    /// How the set was made (command line, split, seed).
    pub generator: serde_json::Value,
    /// The protocol parameters.
    pub params: super::pairs::PairParams,
    /// One per manifest line, same order.
    pub pairs: Vec<PairMeta>,
}

/// The sidecar next to a manifest (`pairs.json` in the same directory), if there is one.
pub fn read_sidecar(manifest: &Path) -> Option<Result<Sidecar, String>> {
    let p = manifest.with_file_name("pairs.json");
    if !p.exists() {
        return None;
    }
    Some(
        std::fs::read_to_string(&p)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()))
            .map_err(|e| format!("{}: {e}", p.display())),
    )
}
