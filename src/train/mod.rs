//! The CPU trainer's core: a small reverse-mode autodiff over the crate's own kernels, the
//! DGMR-ARPS forward pass on it (identical to the engine's), the losses, Adam and the
//! data-parallel training step.
//!
//! * [`tape`]: the tape (nodes, backward sweep, buffer pool). [`ops`]: the differentiable ops.
//! * [`model`]: [`model::forward`] records a pair's forward pass, parameters by
//!   [`crate::ModelConfig::tensor_specs`] name ([`Params`]).
//! * [`losses`]: [`LossConfig`] switches and [`losses::record`].
//! * [`optim`]: [`Adam`], gradient clipping. [`step`]: [`train_step`] on a batch of [`Pair`]s.
//! * [`export`]: [`to_weights`] gives the engine's [`crate::Weights`].
//! * [`synthetic`]: tiny procedural pairs for tests and benchmarks.
//!
//! A checkpoint is [`TrainState`] (parameters + Adam moments, all plain maps by tensor name).
//!
//! Typical use:
//! ```no_run
//! use arps::train::{self, LossConfig, TrainState};
//! let config = arps::ModelConfig::web();
//! let mut state = TrainState::new(config.clone(), train::init_params(&config, 0)?, 1e-3, Some(1.0));
//! let pairs: Vec<train::Pair> = train::synthetic::pairs(8, config.n_points, 0); // the data pipeline's pairs
//! let report = train::train_step(&mut state, &pairs, &LossConfig::default(), 2);
//! println!("loss {:.4}, |g| {:.3}, skipped {}", report.loss.total, report.grad_norm, report.skipped);
//! let weights = train::to_weights(&state.params, &config, serde_json::json!({"steps": state.steps}))?;
//! # Ok::<(), arps::Error>(())
//! ```
//!
//! Numerics: everything is `f32` with the engine's kernels ([`crate::nn::matmul::gemm`] for every
//! product, forward and backward), except the trainer's softmax (a polynomial `exp`, see
//! [`simd`]) and the GMM + Procrustes solve, which runs in `f64` from the memberships to `T`
//! (one fused op, [`ops::gmr()`]). The forward pass matches the engine's memberships, steps,
//! shifts and transforms to 1e-4 (tests/train_model.rs).
//!
//! Speed (web config, N = 512, batch 8, 2 threads): 0.21-0.23 CPU-seconds per pair, i.e.
//! ~9 pairs/s on two otherwise idle cores; ~85 % of the time is sgemm (matrixmultiply,
//! including ~20 % packing), the rest softmax, LayerNorm and bookkeeping
//! (`cargo test --release --features train --test train_bench -- --ignored --nocapture`).

pub mod export;
pub mod losses;
pub mod model;
pub mod ops;
pub mod optim;
pub mod pair;
pub mod partition;
pub mod run;
pub mod simd;
pub mod step;
pub mod synthetic;
pub mod tape;

pub use export::{init_params, to_weights};
pub use losses::{CentroidMode, LossConfig, LossParts};
pub use model::{forward, Forward, Params};
pub use ops::ConsistencyKind;
pub use optim::{Adam, Ema};
pub use pair::Pair;
pub use step::{batch_gradients, pair_gradients, train_step, StepReport, TrainState};
pub use tape::{Id, Tape};
