//! Reusable scratch buffers.

/// Grows `v` to `len` (never shrinks its capacity) and returns the first `len` elements.
/// Contents are unspecified: callers overwrite them.
pub fn take(v: &mut Vec<f32>, len: usize) -> &mut [f32] {
    if v.len() < len {
        v.resize(len, 0.0);
    }
    &mut v[..len]
}

/// Scratch for one attention block's forward pass; kept by the model between calls.
#[derive(Default, Debug, Clone)]
pub struct Workspace {
    /// Queries `[nq, d]`.
    pub q: Vec<f32>,
    /// Keys, transposed: `[d, nk]`.
    pub k: Vec<f32>,
    /// Values `[nk, d]`.
    pub v: Vec<f32>,
    /// Attention scores / unnormalised probabilities of one head for one block of queries,
    /// `[min(nq, QUERY_BLOCK), nk]` (see [`super::attention::QUERY_BLOCK`]).
    pub scores: Vec<f32>,
    /// Concatenated head outputs `[nq, d]`.
    pub heads: Vec<f32>,
    /// Block-level temporary `[nq, d]`.
    pub tmp: Vec<f32>,
    /// FFN hidden activations `[nq, ffn]`.
    pub hidden: Vec<f32>,
}
