//! Growing a run's network without changing what it computes: a wider feed-forward layer in
//! every attention block (`ffn_dim`), so a trained line gains capacity and goes on training
//! instead of starting a larger network from scratch.
//!
//! Each block's feed-forward layer is `ffn2(relu(ffn1(x)))`. The grown `ffn1` keeps its trained
//! rows and gains new hidden units drawn as a new run's would be ([`crate::Weights::random`] of the
//! grown configuration); the grown `ffn2` keeps its trained columns and gets zero columns for
//! the new units, so they add nothing to the block's output until training moves them: the
//! grown network's forward pass is the original's (up to the order of float additions).
//!
//! The optimiser goes on too. Adam's moments of the trained entries are kept; a new entry gets
//! a first moment of 0 and, as its second moment, the mean second moment of its tensor's trained
//! entries, so its first steps are about as large as its neighbours' (with a second moment of 0
//! they would be several times the learning rate). The moving average, when the run keeps one,
//! grows like the parameters. The best validation is forgotten (it was the smaller network's),
//! as when a run changes its network points.

use super::checkpoint::Checkpoint;
use crate::train::model::check_params;
use crate::train::Params;
use std::path::Path;

/// How one tensor grows from `old` to `new` hidden units (`d`: the blocks' token width).
#[derive(Clone, Copy)]
enum Growth {
    /// `ffn1.weight` `[ffn, d]` and `ffn1.bias` `[ffn]`: rows appended.
    Rows { per_row: usize },
    /// `ffn2.weight` `[d, ffn]`: each of the `d` rows gets `new - old` entries.
    Columns { rows: usize },
    /// Every other tensor.
    Same,
}

fn growth(name: &str, d: usize) -> Growth {
    if name.ends_with(".ffn1.weight") {
        Growth::Rows { per_row: d }
    } else if name.ends_with(".ffn1.bias") {
        Growth::Rows { per_row: 1 }
    } else if name.ends_with(".ffn2.weight") {
        Growth::Columns { rows: d }
    } else {
        Growth::Same
    }
}

/// `v` grown from `old` to `new` hidden units; the new entries of appended rows come from
/// `fresh` (the grown tensor of a new run), or are `fill` where `fresh` is `None`; new columns
/// are always `fill`.
fn grow_tensor(v: &[f32], g: Growth, old: usize, new: usize, fresh: Option<&[f32]>, fill: f32) -> Vec<f32> {
    match g {
        Growth::Same => v.to_vec(),
        Growth::Rows { per_row } => {
            let mut out = v.to_vec();
            match fresh {
                Some(f) => out.extend_from_slice(&f[old * per_row..new * per_row]),
                None => out.resize(new * per_row, fill),
            }
            out
        }
        Growth::Columns { rows } => {
            let mut out = Vec::with_capacity(rows * new);
            for r in 0..rows {
                out.extend_from_slice(&v[r * old..(r + 1) * old]);
                out.resize((r + 1) * new, fill);
            }
            out
        }
    }
}

/// The checkpoint `from` with every attention block's feed-forward width grown to `ffn_dim`
/// (see the module docs); `seed` draws the new hidden units' input weights.
pub fn grow_ffn(from: &Checkpoint, ffn_dim: usize, seed: u64) -> Result<Checkpoint, String> {
    let old_model = &from.state.config.model;
    let old = old_model.ffn_dim;
    if ffn_dim <= old {
        return Err(format!("--ffn-dim {ffn_dim} must be larger than the run's feed-forward width {old}"));
    }
    let mut model = old_model.clone();
    model.ffn_dim = ffn_dim;
    model.validate().map_err(|e| format!("--ffn-dim {ffn_dim}: {e}"))?;
    check_params(old_model, &from.params).map_err(|e| format!("the run's parameters: {e}"))?;
    let d = 2 * model.feature_dim;
    let fresh = crate::Weights::random(&model, seed).map_err(|e| e.to_string())?.tensors;
    let grow_params = |p: &Params| -> Result<Params, String> {
        let mut out = Params::new();
        for (name, v) in p {
            let g = growth(name, d);
            out.insert(name.clone(), grow_tensor(v, g, old, ffn_dim, fresh.get(name).map(Vec::as_slice), 0.0));
        }
        check_params(&model, &out).map_err(|e| format!("the grown parameters: {e}"))?;
        Ok(out)
    };
    let params = grow_params(&from.params)?;
    let ema = from.ema.as_ref().map(grow_params).transpose()?;
    let mut adam = from.adam.clone();
    for (name, m) in adam.m.iter_mut() {
        *m = grow_tensor(m, growth(name, d), old, ffn_dim, None, 0.0);
    }
    for (name, v) in adam.v.iter_mut() {
        let mean = if v.is_empty() { 0.0 } else { v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64 };
        *v = grow_tensor(v, growth(name, d), old, ffn_dim, None, mean as f32);
    }
    let mut state = from.state.clone();
    state.config.model = model;
    state.best_score = None;
    state.best_val = None;
    state.bad_validations = 0;
    Ok(Checkpoint { state, params, adam, ema })
}

/// Grows the run in `from` (its `checkpoint.safetensors`) into a new run directory `run`
/// ([`grow_ffn`]; written by [`super::fork::write`], with a note saying what grew). Refuses to
/// overwrite a run.
pub fn grow(from: &Path, run: &Path, ffn_dim: usize, seed: u64) -> Result<(), String> {
    let old = super::fork::load_source(from, run)?;
    let new = grow_ffn(&old, ffn_dim, seed)?;
    let count = |p: &Params| p.values().map(Vec::len).sum::<usize>();
    let (before, after) = (count(&old.params), count(&new.params));
    let old_ffn = old.state.config.model.ffn_dim;
    let note = format!(
        "grown from {}: ffn_dim {old_ffn} -> {ffn_dim} (seed {seed}), {before} -> {after} parameters; best validation forgotten",
        from.display()
    );
    super::fork::write(from, run, &new, note)?;
    eprintln!(
        "arps-train: grew {} (step {}, ffn_dim {old_ffn}) into {}: ffn_dim {ffn_dim}, {before} -> {after} parameters",
        from.display(),
        new.state.step,
        run.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_columns_grow_in_place() {
        // ffn1.weight of 2 units x d = 3 inputs, grown to 3 units
        let w1 = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let fresh = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 7.0, 8.0, 9.0];
        assert_eq!(
            grow_tensor(&w1, Growth::Rows { per_row: 3 }, 2, 3, Some(&fresh), 0.0),
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
        );
        // ffn2.weight of d = 2 outputs x 2 units, grown to 3 units: a zero column
        let w2 = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(grow_tensor(&w2, Growth::Columns { rows: 2 }, 2, 3, None, 0.0), [1.0, 2.0, 0.0, 3.0, 4.0, 0.0]);
        assert_eq!(grow_tensor(&[1.0, 2.0], Growth::Rows { per_row: 1 }, 2, 4, None, 0.5), [1.0, 2.0, 0.5, 0.5]);
        assert_eq!(grow_tensor(&w2, Growth::Same, 2, 3, None, 0.0), w2);
    }
}
