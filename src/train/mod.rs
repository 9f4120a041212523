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

pub mod export;
pub mod losses;
pub mod model;
pub mod ops;
pub mod optim;
pub mod pair;
pub mod run;
pub mod simd;
pub mod step;
pub mod synthetic;
pub mod tape;

pub use export::{init_params, to_weights};
pub use losses::{CentroidMode, LossConfig, LossParts};
pub use model::{forward, Forward, Params};
pub use ops::ConsistencyKind;
pub use optim::Adam;
pub use pair::Pair;
pub use step::{batch_gradients, pair_gradients, train_step, StepReport, TrainState};
pub use tape::{Id, Tape};
