//! `arps-train stream` and `pack-bank`: thin wrappers over [`arps::train::run::stream`] and
//! [`arps::train::run::bank_pack`].

use super::StreamArgs;
use arps::train::run::{bank_pack, data::TrainData, session, stream as s};
use std::path::Path;

pub fn stream(a: &StreamArgs) -> Result<(), String> {
    let mut cfg = session::read_config(&a.config)?;
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
