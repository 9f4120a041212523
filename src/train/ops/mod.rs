//! Differentiable ops on the [`Tape`](super::tape::Tape), one concern per file.
//!
//! Each op is a function that computes the forward value with the crate's own kernels
//! ([`crate::nn`]), records the node, and registers a backward (a private struct implementing
//! [`Op`](super::tape::Op)). Shapes are checked with `assert!` at record time.

pub mod alignment;
pub mod attention;
pub mod concat;
pub mod elementwise;
pub mod gmm;
pub mod gmr;
pub mod layernorm;
pub mod linear;
pub mod loss;
pub mod procrustes;
pub mod reduce;
pub mod rigid;
pub mod softmax;

pub use alignment::means_alignment;
pub use attention::attention;
pub use concat::{concat_colmax, concat_cols};
pub use elementwise::{add, mul_scalar, relu, scale, sigmoid, sub, sub_row};
pub use gmm::gmm_params;
pub use gmr::gmr;
pub use layernorm::layer_norm;
pub use linear::linear;
pub use loss::{chamfer_sq, membership_consistency, membership_kl, sq_err, ConsistencyKind};
pub use procrustes::procrustes;
pub use reduce::{mean_all, reshape, weighted_sum, weighted_total};
pub use rigid::{matmul, rigid_inverse, transform_points};
pub use softmax::softmax_rows;
