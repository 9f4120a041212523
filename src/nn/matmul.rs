//! Matrix products on row-major `f32` slices, built on `matrixmultiply`.

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
/// (in elements) for each operand. Panics (debug) if a slice is too short for its strides.
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
    if m == 0 || n == 0 {
        return;
    }
    debug_assert!(span(m, k, rsa, csa) <= a.len(), "A too short");
    debug_assert!(span(k, n, rsb, csb) <= b.len(), "B too short");
    debug_assert!(span(m, n, rsc, csc) <= c.len(), "C too short");
    // SAFETY: the spans of all three operands were checked against the slice lengths above
    // (strides are non-negative everywhere in this crate), and `c` is exclusively borrowed.
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

/// Number of elements a `rows x cols` strided view touches (0 if empty).
fn span(rows: usize, cols: usize, rs: isize, cs: isize) -> usize {
    if rows == 0 || cols == 0 {
        return 0;
    }
    ((rows - 1) as isize * rs + (cols - 1) as isize * cs) as usize + 1
}
