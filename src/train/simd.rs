//! Hot element-wise kernels of the trainer, written in 8-lane form so LLVM vectorises them, and
//! compiled twice: for the baseline target and with AVX2 + FMA, picked at run time.
//!
//! The forward softmax is the engine's own ([`crate::nn::softmax_rows_inplace`]: polynomial `exp`,
//! AVX2 picked at run time), so training and inference share one implementation.

const LANES: usize = 8;

#[inline(always)]
fn madd<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

#[inline(always)]
fn dot_body<const FMA: bool>(a: &[f32], b: &[f32]) -> f32 {
    let mut s = [0.0f32; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..LANES {
            s[k] = madd::<FMA>(x[k], y[k], s[k]);
        }
    }
    let mut sum: f32 = s.iter().sum();
    for (x, y) in ra.iter().zip(rb) {
        sum += x * y;
    }
    sum
}

/// Softmax backward in place: each row of `d` (holding `dL/dy`) becomes
/// `scale * y * (d - <d, y>)`, with `y` the softmax output.
#[inline(always)]
fn softmax_backward_body<const FMA: bool>(d: &mut [f32], y: &[f32], cols: usize, scale: f32) {
    for (dr, yr) in d.chunks_exact_mut(cols).zip(y.chunks_exact(cols)) {
        let dot = dot_body::<FMA>(dr, yr);
        for (x, p) in dr.iter_mut().zip(yr) {
            *x = scale * p * (*x - dot);
        }
    }
}

#[inline(always)]
fn sum_body(a: &[f32]) -> f32 {
    let mut s = [0.0f32; LANES];
    let c = a.chunks_exact(LANES);
    let r = c.remainder();
    for x in c {
        for k in 0..LANES {
            s[k] += x[k];
        }
    }
    s.iter().sum::<f32>() + r.iter().sum::<f32>()
}

/// LayerNorm forward of all rows: writes `y` and per-row `(mean, 1/sqrt(var + eps))` to `stats`.
#[inline(always)]
fn layer_norm_body<const FMA: bool>(
    x: &[f32],
    gamma: &[f32],
    beta: &[f32],
    eps: f32,
    y: &mut [f32],
    stats: &mut [f32],
) {
    let dim = gamma.len();
    for ((yr, xr), st) in y.chunks_exact_mut(dim).zip(x.chunks_exact(dim)).zip(stats.chunks_exact_mut(2)) {
        let mean = sum_body(xr) / dim as f32;
        let mut s = [0.0f32; LANES];
        let c = xr.chunks_exact(LANES);
        let mut var = c.remainder().iter().map(|v| (v - mean) * (v - mean)).sum::<f32>();
        for v in c {
            for k in 0..LANES {
                let d = v[k] - mean;
                s[k] = madd::<FMA>(d, d, s[k]);
            }
        }
        var = (var + s.iter().sum::<f32>()) / dim as f32;
        let inv = 1.0 / (var + eps).sqrt();
        for (((y, x), g), b) in yr.iter_mut().zip(xr).zip(gamma).zip(beta) {
            *y = madd::<FMA>((*x - mean) * inv, *g, *b);
        }
        st[0] = mean;
        st[1] = inv;
    }
}

/// LayerNorm backward of all rows. `dx` (if given), `dgamma`, `dbeta` are accumulated into;
/// `scratch` holds `2 * dim` values.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn layer_norm_backward_body<const FMA: bool>(
    g: &[f32],
    x: &[f32],
    gamma: &[f32],
    stats: &[f32],
    mut dx: Option<&mut [f32]>,
    dgamma: &mut [f32],
    dbeta: &mut [f32],
    scratch: &mut [f32],
) {
    let dim = gamma.len();
    let (xhat, dxhat) = scratch.split_at_mut(dim);
    for (r, (gr, xr)) in g.chunks_exact(dim).zip(x.chunks_exact(dim)).enumerate() {
        let (mean, inv) = (stats[2 * r], stats[2 * r + 1]);
        for k in 0..dim {
            xhat[k] = (xr[k] - mean) * inv;
            dxhat[k] = gr[k] * gamma[k];
            dgamma[k] = madd::<FMA>(gr[k], xhat[k], dgamma[k]);
            dbeta[k] += gr[k];
        }
        if let Some(dx) = dx.as_deref_mut() {
            let m1 = sum_body(dxhat) / dim as f32;
            let m2 = dot_body::<FMA>(dxhat, xhat) / dim as f32;
            for ((d, a), b) in dx[r * dim..(r + 1) * dim].iter_mut().zip(dxhat.iter()).zip(xhat.iter()) {
                *d = madd::<FMA>(inv, *a - m1 - b * m2, *d);
            }
        }
    }
}

#[inline(always)]
fn relu_backward_body(d: &mut [f32], g: &[f32], y: &[f32]) {
    for ((d, g), y) in d.iter_mut().zip(g).zip(y) {
        *d += if *y > 0.0 { *g } else { 0.0 };
    }
}

#[cfg(target_arch = "x86_64")]
fn has_avx2_fma() -> bool {
    use std::sync::OnceLock;
    static HAS: OnceLock<bool> = OnceLock::new();
    *HAS.get_or_init(|| std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma"))
}

#[cfg(target_arch = "x86_64")]
mod avx2 {

    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn relu_backward(d: &mut [f32], g: &[f32], y: &[f32]) {
        super::relu_backward_body(d, g, y)
    }
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn dot(a: &[f32], b: &[f32]) -> f32 {
        super::dot_body::<true>(a, b)
    }
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn layer_norm(
        x: &[f32],
        gamma: &[f32],
        beta: &[f32],
        eps: f32,
        y: &mut [f32],
        stats: &mut [f32],
    ) {
        super::layer_norm_body::<true>(x, gamma, beta, eps, y, stats)
    }
    #[target_feature(enable = "avx2,fma")]
    #[allow(clippy::too_many_arguments)]
    pub(super) unsafe fn layer_norm_backward(
        g: &[f32],
        x: &[f32],
        gamma: &[f32],
        stats: &[f32],
        dx: Option<&mut [f32]>,
        dgamma: &mut [f32],
        dbeta: &mut [f32],
        scratch: &mut [f32],
    ) {
        super::layer_norm_backward_body::<true>(g, x, gamma, stats, dx, dgamma, dbeta, scratch)
    }
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn softmax_backward(d: &mut [f32], y: &[f32], cols: usize, scale: f32) {
        super::softmax_backward_body::<true>(d, y, cols, scale)
    }
}

/// ReLU backward: `d += g` where the output `y > 0`.
pub fn relu_backward(d: &mut [f32], g: &[f32], y: &[f32]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time).
        return unsafe { avx2::relu_backward(d, g, y) };
    }
    relu_backward_body(d, g, y)
}

/// `sum a_i b_i` (8 partial sums).
pub fn dot(a: &[f32], b: &[f32]) -> f32 {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time).
        return unsafe { avx2::dot(a, b) };
    }
    dot_body::<false>(a, b)
}

/// Softmax backward in place: rows of `d` (`dL/dy`) become `scale * y * (d - <d, y>)`.
pub fn softmax_backward(d: &mut [f32], y: &[f32], cols: usize, scale: f32) {
    if cols == 0 {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time).
        return unsafe { avx2::softmax_backward(d, y, cols, scale) };
    }
    softmax_backward_body::<false>(d, y, cols, scale)
}

/// LayerNorm over rows of width `gamma.len()`: `y = (x - mean) / sqrt(var + eps) * gamma + beta`;
/// `stats` receives `(mean, 1/sqrt(var + eps))` per row.
pub fn layer_norm(x: &[f32], gamma: &[f32], beta: &[f32], eps: f32, y: &mut [f32], stats: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time).
        return unsafe { avx2::layer_norm(x, gamma, beta, eps, y, stats) };
    }
    layer_norm_body::<false>(x, gamma, beta, eps, y, stats)
}

/// LayerNorm backward (see [`layer_norm`]); accumulates into `dx` (if given), `dgamma`, `dbeta`.
/// `scratch` must hold `2 * gamma.len()` values.
#[allow(clippy::too_many_arguments)]
pub fn layer_norm_backward(
    g: &[f32],
    x: &[f32],
    gamma: &[f32],
    stats: &[f32],
    dx: Option<&mut [f32]>,
    dgamma: &mut [f32],
    dbeta: &mut [f32],
    scratch: &mut [f32],
) {
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time).
        return unsafe { avx2::layer_norm_backward(g, x, gamma, stats, dx, dgamma, dbeta, scratch) };
    }
    layer_norm_backward_body::<false>(g, x, gamma, stats, dx, dgamma, dbeta, scratch)
}
