//! Matrix products on row-major `f32` slices.
//!
//! Natively they run on `matrixmultiply` (runtime-dispatched AVX/FMA kernels); on wasm32 with
//! simd128 on the crate's own packed GEMM with a 4x8 simd128 micro-kernel
//! ([`gemm`](mod@super::gemm)), which is faster there than `matrixmultiply`'s 8x8 one.

/// `C[m,n] = A[m,k] * B[k,n]` (all row-major, contiguous). Overwrites `c`.
pub fn matmul(a: &[f32], b: &[f32], c: &mut [f32], m: usize, k: usize, n: usize) {
    gemm(m, k, n, 1.0, a, k as isize, 1, b, n as isize, 1, 0.0, c, n as isize, 1);
}

/// `C[m,n] = A[m,k] * B[n,k]^T` (B given row-major as `[n, k]`, e.g. a Linear weight).
/// Overwrites `c`.
pub fn matmul_bt(a: &[f32], b: &[f32], c: &mut [f32], m: usize, k: usize, n: usize) {
    gemm(m, k, n, 1.0, a, k as isize, 1, b, 1, k as isize, 0.0, c, n as isize, 1);
}

/// General strided product `C = alpha * A * B + beta * C`, with explicit row and column strides
/// (in elements) for each operand; `beta == 0` never reads `C` (it may hold NaN).
///
/// Panics if a stride is negative or a slice is too short for its strided view (checks are
/// O(1)).
#[allow(clippy::too_many_arguments)]
pub fn gemm(
    m: usize,
    k: usize,
    n: usize,
    alpha: f32,
    a: &[f32],
    rsa: isize,
    csa: isize,
    b: &[f32],
    rsb: isize,
    csb: isize,
    beta: f32,
    c: &mut [f32],
    rsc: isize,
    csc: isize,
) {
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    super::gemm::gemm_blocked(m, k, n, alpha, a, rsa, csa, b, rsb, csb, beta, c, rsc, csc);
    #[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
    gemm_matrixmultiply(m, k, n, alpha, a, rsa, csa, b, rsb, csb, beta, c, rsc, csc);
}

/// [`gemm`] on `matrixmultiply`, on every target (the native default; kept callable for
/// comparisons in wasm).
#[doc(hidden)]
#[allow(clippy::too_many_arguments)]
pub fn gemm_matrixmultiply(
    m: usize,
    k: usize,
    n: usize,
    alpha: f32,
    a: &[f32],
    rsa: isize,
    csa: isize,
    b: &[f32],
    rsb: isize,
    csb: isize,
    beta: f32,
    c: &mut [f32],
    rsc: isize,
    csc: isize,
) {
    check_operands(m, k, n, a.len(), rsa, csa, b.len(), rsb, csb, c.len(), rsc, csc);
    if m == 0 || n == 0 {
        return;
    }
    // SAFETY: check_operands asserted that all three strided views lie inside their slices,
    // with non-negative strides; `c` is exclusively borrowed so cannot alias `a` or `b`.
    unsafe {
        matrixmultiply::sgemm(
            m,
            k,
            n,
            alpha,
            a.as_ptr(),
            rsa,
            csa,
            b.as_ptr(),
            rsb,
            csb,
            beta,
            c.as_mut_ptr(),
            rsc,
            csc,
        );
    }
}

/// Asserts that the strides are non-negative and every view fits in its slice.
#[allow(clippy::too_many_arguments)]
pub(crate) fn check_operands(
    m: usize,
    k: usize,
    n: usize,
    a_len: usize,
    rsa: isize,
    csa: isize,
    b_len: usize,
    rsb: isize,
    csb: isize,
    c_len: usize,
    rsc: isize,
    csc: isize,
) {
    assert!(rsa >= 0 && csa >= 0 && rsb >= 0 && csb >= 0 && rsc >= 0 && csc >= 0, "gemm: negative stride");
    assert!(span(m, k, rsa, csa) <= a_len, "gemm: A too short for [{m}, {k}] with strides ({rsa}, {csa})");
    assert!(span(k, n, rsb, csb) <= b_len, "gemm: B too short for [{k}, {n}] with strides ({rsb}, {csb})");
    assert!(span(m, n, rsc, csc) <= c_len, "gemm: C too short for [{m}, {n}] with strides ({rsc}, {csc})");
}

/// Number of elements a `rows x cols` strided view touches (0 if empty).
fn span(rows: usize, cols: usize, rs: isize, cs: isize) -> usize {
    if rows == 0 || cols == 0 {
        return 0;
    }
    (rows - 1).saturating_mul(rs as usize).saturating_add((cols - 1).saturating_mul(cs as usize)).saturating_add(1)
}
