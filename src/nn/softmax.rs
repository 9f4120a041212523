//! Row-wise softmax.

use super::fastmath::{exp_shifted_sum_impl, max_of};

/// Softmax over each row of a row-major `[rows, cols]` buffer, in place (max-subtracted, with
/// the fast vectorised [`exp_fast`](super::fastmath::exp_fast): relative error ~3e-7 per element).
///
/// Rows whose maximum is not finite still give a distribution (finite, summing to 1): a row
/// of all `-inf` becomes uniform, and a row containing `+inf` spreads the mass uniformly over
/// its `+inf` entries. NaN entries are ignored when finding the maximum and give NaN outputs.
///
/// Natively on x86-64 CPUs with AVX2 and FMA a copy compiled for them is picked at run time.
pub fn softmax_rows_inplace(x: &mut [f32], cols: usize) {
    dispatch(x, cols, None);
}

/// The unnormalised softmax: each row becomes `e^(x - max)` in place and `inv_sum[i]` receives
/// the factor `1 / sum` that would normalise row `i` (so `x[i, :] * inv_sum[i]` is
/// [`softmax_rows_inplace`]). Lets attention scale its `[nq, dk]` output instead of the
/// `[nq, nk]` probabilities. Non-finite rows are normalised here already (factor 1).
pub fn softmax_rows_unnormalized(x: &mut [f32], cols: usize, inv_sum: &mut [f32]) {
    assert!(cols == 0 || inv_sum.len() >= x.len() / cols, "softmax: inv_sum too short");
    dispatch(x, cols, Some(inv_sum));
}

fn dispatch(x: &mut [f32], cols: usize, inv_sum: Option<&mut [f32]>) {
    if cols == 0 {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports AVX2 and FMA (checked just above; std caches the checks).
        return unsafe { rows_avx2(x, cols, inv_sum) };
    }
    rows::<false>(x, cols, inv_sum);
}

#[inline(always)]
fn rows<const FMA: bool>(x: &mut [f32], cols: usize, inv_sum: Option<&mut [f32]>) {
    match inv_sum {
        None => {
            for row in x.chunks_exact_mut(cols) {
                let inv = row_impl::<FMA>(row);
                for v in row.iter_mut() {
                    *v *= inv;
                }
            }
        }
        Some(inv_sum) => {
            for (row, s) in x.chunks_exact_mut(cols).zip(inv_sum) {
                *s = row_impl::<FMA>(row);
            }
        }
    }
}

/// The same code compiled for AVX2 + FMA (8-wide vectors, fused polynomial), picked at run
/// time natively.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rows_avx2(x: &mut [f32], cols: usize, inv_sum: Option<&mut [f32]>) {
    rows::<true>(x, cols, inv_sum);
}

/// Softmax of one row, in place (see [`softmax_rows_inplace`]; portable code, no dispatch).
pub fn softmax_row(row: &mut [f32]) {
    let inv = row_impl::<false>(row);
    for v in row.iter_mut() {
        *v *= inv;
    }
}

/// `row = e^(row - max)`; returns `1 / sum` (or normalises a non-finite row and returns 1).
#[inline(always)]
fn row_impl<const FMA: bool>(row: &mut [f32]) -> f32 {
    let max = max_of(row);
    if !max.is_finite() {
        nonfinite_row(row, max);
        return 1.0;
    }
    1.0 / exp_shifted_sum_impl::<FMA>(row, max)
}

#[cold]
fn nonfinite_row(row: &mut [f32], max: f32) {
    // max is -inf (all entries -inf or NaN) or +inf.
    let hits = |v: f32| if max == f32::NEG_INFINITY { !v.is_nan() } else { v == f32::INFINITY };
    let count = row.iter().filter(|v| hits(**v)).count();
    let p = 1.0 / count.max(1) as f32;
    for v in row.iter_mut() {
        *v = if v.is_nan() {
            f32::NAN
        } else if hits(*v) {
            p
        } else {
            0.0
        };
    }
}
