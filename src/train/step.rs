//! One training step: per-pair forward + backward on thread-local tapes (data-parallel with
//! rayon), gradients summed in pair order (deterministic whatever the thread timing), then
//! clipping, the non-finite check and Adam.

use super::losses::{self, LossConfig, LossParts};
use super::model::{self, Params};
use super::optim::{clip_grad_norm, grad_norm, Adam, Ema};
use super::pair::Pair;
use super::tape::Tape;
use crate::model::ModelConfig;
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::sync::{Arc, Mutex, OnceLock};

thread_local! {
    static TAPE: RefCell<Tape> = RefCell::new(Tape::new());
}

/// Loss parts and parameter gradients of one pair (gradients of the weighted total).
pub fn pair_gradients(config: &ModelConfig, params: &Params, pair: &Pair, loss: &LossConfig) -> (LossParts, Params) {
    TAPE.with(|cell| {
        let mut t = cell.borrow_mut();
        t.reset();
        let fwd = model::forward(&mut t, config, params, &pair.source, &pair.target);
        let (total, parts) = losses::record(&mut t, &fwd, pair, loss);
        t.backward(total);
        let grads = fwd
            .params
            .iter()
            .map(|(name, &id)| {
                let g = t.grad(id).map_or_else(|| vec![0.0; params[name].len()], |g| g.to_vec());
                (name.clone(), g)
            })
            .collect();
        t.reset();
        (parts, grads)
    })
}

type Pools = Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>>;

fn pool(threads: usize) -> Arc<rayon::ThreadPool> {
    static POOLS: OnceLock<Pools> = OnceLock::new();
    let threads = threads.max(1);
    let mut pools = POOLS.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, p)) = pools.iter().find(|(n, _)| *n == threads) {
        return p.clone();
    }
    let p = Arc::new(rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("rayon pool"));
    pools.push((threads, p.clone()));
    p
}

/// Mean loss parts and mean gradients over a batch, computed on `threads` threads. The result
/// does not depend on `threads` or on thread timing (pairs are reduced in order).
pub fn batch_gradients(
    config: &ModelConfig,
    params: &Params,
    pairs: &[Pair],
    loss: &LossConfig,
    threads: usize,
) -> (LossParts, Params) {
    use rayon::prelude::*;
    let per_pair: Vec<(LossParts, Params)> = if threads <= 1 {
        pairs.iter().map(|p| pair_gradients(config, params, p, loss)).collect()
    } else {
        pool(threads).install(|| pairs.par_iter().map(|p| pair_gradients(config, params, p, loss)).collect())
    };
    let inv = 1.0 / pairs.len().max(1) as f32;
    let mut grads: Params = params.keys().map(|k| (k.clone(), vec![0.0f32; params[k].len()])).collect();
    for (_, g) in &per_pair {
        for (name, acc) in grads.iter_mut() {
            for (a, v) in acc.iter_mut().zip(&g[name]) {
                *a += v;
            }
        }
    }
    for g in grads.values_mut().flatten() {
        *g *= inv;
    }
    let parts: Vec<LossParts> = per_pair.into_iter().map(|(p, _)| p).collect();
    (LossParts::mean(&parts), grads)
}

/// Everything a training run updates: the parameters and the optimiser (serialise both for a
/// checkpoint).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TrainState {
    /// Network sizes.
    pub config: ModelConfig,
    /// Parameters.
    pub params: Params,
    /// Optimiser state.
    pub adam: Adam,
    /// Global gradient-norm clip (None = no clipping).
    pub clip_norm: Option<f64>,
    /// Steps taken (including skipped ones).
    pub steps: u64,
    /// Steps skipped because the loss or a gradient was not finite.
    pub skipped_steps: u64,
    /// Moving average of the parameters, updated after every applied step (None = not kept).
    pub ema: Option<Ema>,
}

impl TrainState {
    /// A fresh state (no moving average).
    pub fn new(config: ModelConfig, params: Params, lr: f32, clip_norm: Option<f64>) -> Self {
        Self { config, params, adam: Adam::new(lr), clip_norm, steps: 0, skipped_steps: 0, ema: None }
    }

    /// The parameters to evaluate and export: the moving average when the run keeps one,
    /// otherwise the current parameters.
    pub fn eval_params(&self) -> &Params {
        self.ema.as_ref().map_or(&self.params, |e| &e.params)
    }
}

/// What one step did.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StepReport {
    /// Mean loss parts over the batch (before the update).
    pub loss: LossParts,
    /// Global gradient norm before clipping.
    pub grad_norm: f64,
    /// Whether the gradients were clipped.
    pub clipped: bool,
    /// Whether the update was skipped (non-finite loss or gradient).
    pub skipped: bool,
    /// Wall time of the step in seconds.
    pub seconds: f64,
}

/// One optimisation step on a batch: mean gradients over `pairs` (data-parallel on `threads`),
/// global-norm clipping, an Adam update and the moving average's update — or no update when the loss or gradient norm is
/// not finite (reported as `skipped`).
pub fn train_step(state: &mut TrainState, pairs: &[Pair], loss: &LossConfig, threads: usize) -> StepReport {
    let start = std::time::Instant::now();
    let (parts, mut grads) = batch_gradients(&state.config, &state.params, pairs, loss, threads);
    let norm0 = grad_norm(&grads);
    let skipped = !(parts.is_finite() && norm0.is_finite());
    let mut clipped = false;
    if !skipped {
        if let Some(c) = state.clip_norm {
            clipped = clip_grad_norm(&mut grads, c).1;
        }
        state.adam.update(&mut state.params, &grads);
        if let Some(ema) = &mut state.ema {
            ema.update(&state.params);
        }
    } else {
        state.skipped_steps += 1;
    }
    state.steps += 1;
    StepReport { loss: parts, grad_norm: norm0, clipped, skipped, seconds: start.elapsed().as_secs_f64() }
}
