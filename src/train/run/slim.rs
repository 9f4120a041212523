//! A run's checkpoint at a third of its size or less, to keep in the repository as a line's
//! resume point: only the network to go on from, without the optimiser's state.
//!
//! A full checkpoint holds four copies of the parameters' size: the parameters, Adam's two
//! moments and the moving average. The slim run keeps one: the moving average where the run keeps
//! one (the network that was validated and is exported), else the parameters. Training it resumes
//! from those parameters with Adam started afresh (zero moments, `t = 0`, so the first updates are
//! bias-corrected as at a run's start; the learning rate is kept) and the moving average, if the
//! run keeps one, started from the parameters, as both trainers do for a checkpoint without one.
//! So the resume is not bit-exact with the full run's, but exported weights are the same: `export
//! --latest` of the slim run writes what `export --latest` of the full run writes. The step,
//! data cursor, learning rate and best validation are kept.

use super::checkpoint::Checkpoint;
use crate::train::{Adam, Params};
use std::path::Path;

/// The slim form of `from` (see the module docs).
pub fn slim_checkpoint(from: &Checkpoint) -> Checkpoint {
    let params: Params = from.ema.clone().unwrap_or_else(|| from.params.clone());
    let mut adam = Adam::new(from.adam.lr);
    (adam.beta1, adam.beta2, adam.eps) = (from.adam.beta1, from.adam.beta2, from.adam.eps);
    Checkpoint { state: from.state.clone(), params, adam, ema: None }
}

/// Writes the slim form of the run in `from` as a new run directory `run` (written by
/// [`super::fork::write`], with a note). Refuses to overwrite a run.
pub fn slim(from: &Path, run: &Path) -> Result<(), String> {
    let old = super::fork::load_source(from, run)?;
    let new = slim_checkpoint(&old);
    let kept = if old.ema.is_some() { "the moving average" } else { "the parameters" };
    let note = format!("slim copy of {}: {kept} as the parameters; Adam restarts (no moments)", from.display());
    super::fork::write(from, run, &new, note)?;
    let size = std::fs::metadata(run.join("checkpoint.safetensors")).map(|m| m.len()).unwrap_or(0);
    eprintln!("arps-train: wrote {} (step {}, {kept} as the parameters, {size} bytes)", run.display(), new.state.step);
    Ok(())
}
