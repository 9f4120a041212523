//! Pointwise activations.

use super::fastmath::{exp_fast, map_exp_inplace};

/// `x = max(x, 0)` in place (NaN stays NaN).
///
/// Written as a compare-select rather than `f32::max`, whose NaN rule has no wasm simd128
/// instruction: LLVM turns `f32::max` into a scalar `fmaxf` call per element there.
pub fn relu_inplace(x: &mut [f32]) {
    for v in x {
        *v = if *v < 0.0 { 0.0 } else { *v };
    }
}

/// GELU (tanh approximation) in place: `0.5 u (1 + tanh(z))`, `z = sqrt(2/pi) (u + 0.044715 u^3)`,
/// computed as the equal `u / (1 + e^(-2z))` with the fast vectorised exp.
pub fn gelu_inplace(x: &mut [f32]) {
    map_exp_inplace(x, gelu_arg, |e, u| u / (1.0 + e));
}

/// `-2z` of [`gelu`].
#[inline(always)]
fn gelu_arg(u: f32) -> f32 {
    const C2: f32 = -2.0 * 0.797_884_6; // -2 sqrt(2/pi)
    C2 * (u + 0.044715 * u * u * u)
}

/// GELU (tanh approximation) of one value; see [`gelu_inplace`].
#[inline(always)]
pub fn gelu(u: f32) -> f32 {
    u / (1.0 + exp_fast(gelu_arg(u)))
}

/// The logistic sigmoid `1 / (1 + e^-x)`.
pub fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + exp_fast(-x))
}

/// The logistic sigmoid in place (vectorised).
pub fn sigmoid_inplace(x: &mut [f32]) {
    map_exp_inplace(x, |v| -v, |e, _| 1.0 / (1.0 + e));
}
