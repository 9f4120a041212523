//! Neural-network kernels for inference (and, through the trainer's tape, for training).
//!
//! Layout: activations are row-major `[rows, dim]` `f32` slices; a [`Linear`] weight is
//! `[out, in]` row-major (the PyTorch layout), so `y = x W^T + b`.
//! Kernels write into caller-provided buffers; [`Workspace`] holds the scratch a forward
//! pass reuses across calls, so the hot path makes no large allocations after the first call.
//!
//! [`reference`](mod@reference) has naive versions of every kernel (for tests and gradient checks).

pub mod activation;
pub mod attention;
pub mod bench;
pub mod fastmath;
pub mod gemm;
pub mod linear;
pub mod matmul;
pub mod norm;
pub mod qlinear;
#[doc(hidden)]
pub mod reference;
pub mod softmax;
pub mod workspace;

pub use activation::{gelu_inplace, relu_inplace, sigmoid, sigmoid_inplace};
pub use attention::{AttentionBlock, MultiHeadAttention};
pub use bench::{
    bench_gemm_gflops, bench_matmul_gflops, flops_attention, flops_attention_block, flops_linear, flops_mlp,
};
pub use fastmath::exp_fast;
pub use linear::{Linear, Mlp};
pub use matmul::{gemm, matmul, matmul_bt};
pub use norm::LayerNorm;
pub use qlinear::QuantWeight;
pub use softmax::softmax_rows_inplace;
pub use workspace::Workspace;
