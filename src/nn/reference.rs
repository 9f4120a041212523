//! Naive reference implementations of the kernels: plain loops, `f64` accumulation, no
//! blocking, whole matrices allocated. For tests and gradient checks only (slow by design).
//!
//! Each function mirrors a fast kernel of [`crate::nn`] and returns a fresh `Vec<f32>`.

use super::{AttentionBlock, LayerNorm, Linear, Mlp, MultiHeadAttention};

/// `C[m,n] = A[m,k] B[k,n]`, row-major.
pub fn matmul(a: &[f32], b: &[f32], m: usize, k: usize, n: usize) -> Vec<f32> {
    let mut c = vec![0.0; m * n];
    gemm(m, k, n, 1.0, a, k as isize, 1, b, n as isize, 1, 0.0, &mut c, n as isize, 1);
    c
}

/// `C[m,n] = A[m,k] B[n,k]^T`, row-major.
pub fn matmul_bt(a: &[f32], b: &[f32], m: usize, k: usize, n: usize) -> Vec<f32> {
    let mut c = vec![0.0; m * n];
    gemm(m, k, n, 1.0, a, k as isize, 1, b, 1, k as isize, 0.0, &mut c, n as isize, 1);
    c
}

/// Strided `C = alpha A B + beta C` (same arguments as [`crate::nn::matmul::gemm`]); `beta == 0`
/// ignores the old `C`.
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
    let at = |i: usize, j: usize, rs: isize, cs: isize| (i as isize * rs + j as isize * cs) as usize;
    for i in 0..m {
        for j in 0..n {
            let mut s = 0.0f64;
            for p in 0..k {
                s += a[at(i, p, rsa, csa)] as f64 * b[at(p, j, rsb, csb)] as f64;
            }
            let cij = &mut c[at(i, j, rsc, csc)];
            let old = if beta == 0.0 { 0.0 } else { beta as f64 * *cij as f64 };
            *cij = (alpha as f64 * s + old) as f32;
        }
    }
}

/// `y = x W^T + b` for `rows` rows.
pub fn linear(l: &Linear, x: &[f32], rows: usize) -> Vec<f32> {
    let mut y = matmul_bt(x, &l.weight, rows, l.in_dim, l.out_dim);
    if let Some(b) = &l.bias {
        for row in y.chunks_exact_mut(l.out_dim) {
            for (v, bi) in row.iter_mut().zip(b) {
                *v += bi;
            }
        }
    }
    y
}

/// The MLP: ReLU after every layer but the last (and after the last if `relu_last`).
pub fn mlp(m: &Mlp, x: &[f32], rows: usize) -> Vec<f32> {
    let mut h = x.to_vec();
    for (i, l) in m.layers.iter().enumerate() {
        h = linear(l, &h, rows);
        if i + 1 < m.layers.len() || m.relu_last {
            h = relu(&h);
        }
    }
    h
}

/// LayerNorm of each row (two-pass mean/variance in `f64`).
pub fn layernorm(ln: &LayerNorm, x: &[f32]) -> Vec<f32> {
    let dim = ln.gamma.len();
    let mut y = Vec::with_capacity(x.len());
    for row in x.chunks_exact(dim) {
        let mean = row.iter().map(|&v| v as f64).sum::<f64>() / dim as f64;
        let var = row.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / dim as f64;
        let inv = 1.0 / (var + ln.eps as f64).sqrt();
        for ((&v, g), b) in row.iter().zip(&ln.gamma).zip(&ln.beta) {
            y.push(((v as f64 - mean) * inv * *g as f64 + *b as f64) as f32);
        }
    }
    y
}

/// Row-wise softmax with `f64` exp (max-subtracted).
pub fn softmax_rows(x: &[f32], cols: usize) -> Vec<f32> {
    let mut y = Vec::with_capacity(x.len());
    for row in x.chunks_exact(cols) {
        let max = row.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
        let e: Vec<f64> = row.iter().map(|&v| (v as f64 - max).exp()).collect();
        let sum: f64 = e.iter().sum();
        y.extend(e.iter().map(|v| (v / sum) as f32));
    }
    y
}

/// `max(x, 0)` (NaN stays NaN).
pub fn relu(x: &[f32]) -> Vec<f32> {
    x.iter().map(|&v| if v < 0.0 { 0.0 } else { v }).collect()
}

/// GELU, tanh approximation `0.5 u (1 + tanh(z))`, in `f64`, evaluated as the equal
/// `u / (1 + e^(-2z))` (the tanh form cancels to 0 in f64 for u below about -6).
pub fn gelu(x: &[f32]) -> Vec<f32> {
    let c = (2.0 / std::f64::consts::PI).sqrt();
    x.iter()
        .map(|&u| {
            let u = u as f64;
            let z = c * (u + 0.044715 * u * u * u);
            (u / (1.0 + (-2.0 * z).exp())) as f32
        })
        .collect()
}

/// Logistic sigmoid in `f64`.
pub fn sigmoid(x: &[f32]) -> Vec<f32> {
    x.iter().map(|&v| (1.0 / (1.0 + (-(v as f64)).exp())) as f32).collect()
}

/// Multi-head attention with each head's full `[nq, nk]` score matrix materialised.
pub fn attention(mha: &MultiHeadAttention, x_q: &[f32], nq: usize, x_kv: &[f32], nk: usize) -> Vec<f32> {
    let d = mha.dim();
    let q = linear(&mha.q, x_q, nq);
    let k = linear(&mha.k, x_kv, nk);
    let v = linear(&mha.v, x_kv, nk);
    let heads = attend(&q, nq, &k, &v, nk, d, mha.heads);
    linear(&mha.o, &heads, nq)
}

/// The attention core on projected `q [nq, d]`, `k, v [nk, d]` (see
/// [`crate::nn::attention::attend`]).
pub fn attend(q: &[f32], nq: usize, k: &[f32], v: &[f32], nk: usize, d: usize, heads: usize) -> Vec<f32> {
    let dk = d / heads;
    let scale = 1.0 / (dk as f64).sqrt();
    let mut out = vec![0.0f32; nq * d];
    for h in 0..heads {
        let off = h * dk;
        let mut s = vec![0.0f32; nq * nk];
        for i in 0..nq {
            for j in 0..nk {
                let dot: f64 = (0..dk).map(|t| q[i * d + off + t] as f64 * k[j * d + off + t] as f64).sum();
                s[i * nk + j] = (dot * scale) as f32;
            }
        }
        let p = softmax_rows(&s, nk);
        for i in 0..nq {
            for t in 0..dk {
                let acc: f64 = (0..nk).map(|j| p[i * nk + j] as f64 * v[j * d + off + t] as f64).sum();
                out[i * d + off + t] = acc as f32;
            }
        }
    }
    out
}

/// The post-norm block `a = LN1(x + MHA(x, kv)); y = LN2(a + FFN(a))`.
pub fn attention_block(b: &AttentionBlock, x: &[f32], nq: usize, kv: &[f32], nk: usize) -> Vec<f32> {
    let att = attention(&b.attn, x, nq, kv, nk);
    let r1: Vec<f32> = att.iter().zip(x).map(|(a, x)| a + x).collect();
    let a = layernorm(&b.norm1, &r1);
    let h = relu(&linear(&b.ffn1, &a, nq));
    let f = linear(&b.ffn2, &h, nq);
    let r2: Vec<f32> = f.iter().zip(&a).map(|(f, a)| f + a).collect();
    layernorm(&b.norm2, &r2)
}
