//! FLOP counts of the layers and a matmul throughput probe, for reporting the network's
//! achieved GFLOP/s next to the machine's matmul peak (`arps bench`).
//!
//! Counts are multiply-adds x 2 of the matrix products only (bias, softmax, norms and
//! activations are O(rows x width) and left out).

use super::matmul::gemm;
use super::Mlp;

/// FLOPs of a [`Linear`](super::Linear) on `rows` rows: `2 * rows * in * out`.
pub fn flops_linear(rows: usize, in_dim: usize, out_dim: usize) -> u64 {
    2 * rows as u64 * in_dim as u64 * out_dim as u64
}

/// FLOPs of an [`Mlp`] on `rows` rows.
pub fn flops_mlp(mlp: &Mlp, rows: usize) -> u64 {
    mlp.layers.iter().map(|l| flops_linear(rows, l.in_dim, l.out_dim)).sum()
}

/// FLOPs of [`MultiHeadAttention::forward`](super::MultiHeadAttention::forward): the four
/// `d x d` projections plus `Q K^T` and `P V` (`2 nq nk d` each, whatever the head count).
pub fn flops_attention(nq: usize, nk: usize, d: usize, _heads: usize) -> u64 {
    2 * flops_linear(nq, d, d) + 2 * flops_linear(nk, d, d) + 4 * nq as u64 * nk as u64 * d as u64
}

/// FLOPs of [`AttentionBlock::forward`](super::AttentionBlock::forward): attention plus the
/// FFN `d -> ffn -> d` on the `nq` queries.
pub fn flops_attention_block(nq: usize, nk: usize, d: usize, heads: usize, ffn: usize) -> u64 {
    flops_attention(nq, nk, d, heads) + flops_linear(nq, d, ffn) + flops_linear(nq, ffn, d)
}

/// Median GFLOP/s of the crate's [`gemm`] on `[m, k] x [k, n]` (row-major, contiguous), over
/// `reps` timed runs after a warm-up of at least 30 ms. `clock` returns milliseconds (e.g.
/// [`crate::timing::default_clock`] natively, `performance.now` in wasm). Each timed run repeats
/// the product until it lasts at least ~2 ms, so coarse clocks still give usable figures.
///
/// In a browser or Node, call it once before the call you report: V8 first runs wasm in its
/// baseline compiler and optimises in the background, and on a busy machine the first call can
/// read ~4x low (measured 8-10 instead of ~40 GFLOP/s at n = 128 here).
pub fn bench_gemm_gflops(m: usize, k: usize, n: usize, reps: usize, clock: fn() -> f64) -> f64 {
    let a: Vec<f32> = (0..m * k).map(|i| ((i * 7 % 13) as f32 - 6.0) * 0.1).collect();
    let b: Vec<f32> = (0..k * n).map(|i| ((i * 5 % 11) as f32 - 5.0) * 0.1).collect();
    let mut c = vec![0.0f32; m * n];
    let mut run = || gemm(m, k, n, 1.0, &a, k as isize, 1, &b, n as isize, 1, 0.0, &mut c, n as isize, 1);
    // Warm up for at least 3 calls and 30 ms (packing buffers, caches, and a JIT's tier-up:
    // V8 keeps a wasm function in its baseline compiler for its first calls), and size the
    // inner loop from it. The call cap keeps a clock that does not advance from hanging here.
    let t0 = clock();
    let mut calls = 0usize;
    while calls < 3 || (clock() - t0 < 30.0 && calls < 10_000) {
        run();
        calls += 1;
    }
    let once = ((clock() - t0) / calls as f64).max(1e-4);
    let inner = ((2.0 / once).ceil() as usize).clamp(1, 10_000);
    let mut times: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let t0 = clock();
            for _ in 0..inner {
                run();
            }
            (clock() - t0) / inner as f64
        })
        .collect();
    std::hint::black_box(&c);
    times.sort_by(f64::total_cmp);
    let ms = times[times.len() / 2];
    if ms <= 0.0 {
        return 0.0;
    }
    flops_linear(m, k, n) as f64 / (ms * 1e6)
}

/// Median GFLOP/s of a square `n x n x n` product (see [`bench_gemm_gflops`]): the matmul
/// peak to quote next to the network's achieved rate.
pub fn bench_matmul_gflops(n: usize, reps: usize, clock: fn() -> f64) -> f64 {
    bench_gemm_gflops(n, n, n, reps, clock)
}
