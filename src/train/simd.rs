//! Hot element-wise kernels of the trainer, written in 8-lane form so LLVM vectorises them, and
//! compiled twice: for the baseline target and with AVX2 + FMA, picked at run time.
//!
//! The softmax uses a polynomial `exp` (Cephes `expf`: Cody-Waite range reduction, degree-6
//! polynomial, relative error about 2e-7) instead of libm's, which costs ~4 ns per call and was
//! two thirds of the attention forward pass at N = 512. Results differ from the engine's
//! [`crate::nn::softmax_rows_inplace`] by a few units in the last place.

const LANES: usize = 8;

#[inline(always)]
fn madd<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `exp(x)` for `x` in about `[-87.3, 88.3]` (clamped outside).
#[inline(always)]
fn exp1<const FMA: bool>(x: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    const C1: f32 = 0.693_359_4;
    const C2: f32 = -2.121_944_4e-4;
    const MAGIC: f32 = 12_582_912.0; // 1.5 * 2^23: adding it rounds to an integer
    let x = x.clamp(-87.3, 88.3);
    let t = madd::<FMA>(x, LOG2E, MAGIC);
    let n = t - MAGIC;
    let ni = t.to_bits().wrapping_sub(MAGIC.to_bits()) as i32;
    let r = madd::<FMA>(n, -C2, madd::<FMA>(n, -C1, x));
    let mut p = 1.987_569_1e-4f32;
    p = madd::<FMA>(p, r, 1.398_199_9e-3);
    p = madd::<FMA>(p, r, 8.333_452e-3);
    p = madd::<FMA>(p, r, 4.166_579_6e-2);
    p = madd::<FMA>(p, r, 1.666_666_5e-1);
    p = madd::<FMA>(p, r, 0.5);
    let y = madd::<FMA>(p * r, r, r) + 1.0;
    y * f32::from_bits(((ni + 127) as u32) << 23)
}

#[inline(always)]
fn softmax_rows_body<const FMA: bool>(x: &mut [f32], cols: usize) {
    for row in x.chunks_exact_mut(cols) {
        let mut m = [f32::NEG_INFINITY; LANES];
        let mut chunks = row.chunks_exact(LANES);
        for c in &mut chunks {
            for k in 0..LANES {
                m[k] = m[k].max(c[k]);
            }
        }
        let mut max = m.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        for &v in chunks.remainder() {
            max = max.max(v);
        }
        let mut s = [0.0f32; LANES];
        let mut chunks = row.chunks_exact_mut(LANES);
        for c in &mut chunks {
            for k in 0..LANES {
                let e = exp1::<FMA>(c[k] - max);
                c[k] = e;
                s[k] += e;
            }
        }
        let mut sum: f32 = s.iter().sum();
        for v in chunks.into_remainder() {
            let e = exp1::<FMA>(*v - max);
            *v = e;
            sum += e;
        }
        let inv = 1.0 / sum;
        for v in row.iter_mut() {
            *v *= inv;
        }
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
    use std::arch::x86_64::*;

    /// Eight `exp`s, the same polynomial as [`super::exp1`].
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn exp8(x: __m256) -> __m256 {
        const MAGIC: f32 = 12_582_912.0;
        let x = _mm256_min_ps(_mm256_max_ps(x, _mm256_set1_ps(-87.3)), _mm256_set1_ps(88.3));
        let t = _mm256_fmadd_ps(x, _mm256_set1_ps(std::f32::consts::LOG2_E), _mm256_set1_ps(MAGIC));
        let n = _mm256_sub_ps(t, _mm256_set1_ps(MAGIC));
        let ni = _mm256_sub_epi32(_mm256_castps_si256(t), _mm256_set1_epi32(MAGIC.to_bits() as i32));
        let r = _mm256_fnmadd_ps(n, _mm256_set1_ps(0.693_359_4), x);
        let r = _mm256_fnmadd_ps(n, _mm256_set1_ps(-2.121_944_4e-4), r);
        let mut p = _mm256_set1_ps(1.987_569_1e-4);
        p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.398_199_9e-3));
        p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(8.333_452e-3));
        p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(4.166_579_6e-2));
        p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.666_666_5e-1));
        p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(0.5));
        let y = _mm256_add_ps(_mm256_fmadd_ps(_mm256_mul_ps(p, r), r, r), _mm256_set1_ps(1.0));
        let scale = _mm256_castsi256_ps(_mm256_slli_epi32::<23>(_mm256_add_epi32(ni, _mm256_set1_epi32(127))));
        _mm256_mul_ps(y, scale)
    }

    #[inline]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn hsum(v: __m256) -> f32 {
        let s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let s = _mm_add_ps(s, _mm_movehl_ps(s, s));
        let s = _mm_add_ss(s, _mm_shuffle_ps::<1>(s, s));
        _mm_cvtss_f32(s)
    }

    #[inline]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn hmax(v: __m256) -> f32 {
        let s = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
        let s = _mm_max_ps(s, _mm_movehl_ps(s, s));
        let s = _mm_max_ss(s, _mm_shuffle_ps::<1>(s, s));
        _mm_cvtss_f32(s)
    }

    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn softmax_rows(x: &mut [f32], cols: usize) {
        let main = cols / 8 * 8;
        for row in x.chunks_exact_mut(cols) {
            let ptr = row.as_mut_ptr();
            let mut max = f32::NEG_INFINITY;
            if main > 0 {
                let mut m = _mm256_set1_ps(f32::NEG_INFINITY);
                for k in (0..main).step_by(8) {
                    m = _mm256_max_ps(m, _mm256_loadu_ps(ptr.add(k)));
                }
                max = hmax(m);
            }
            for &v in &row[main..] {
                max = max.max(v);
            }
            let mut sum = 0.0f32;
            if main > 0 {
                let vmax = _mm256_set1_ps(max);
                let mut s = _mm256_setzero_ps();
                for k in (0..main).step_by(8) {
                    let e = exp8(_mm256_sub_ps(_mm256_loadu_ps(ptr.add(k)), vmax));
                    _mm256_storeu_ps(ptr.add(k), e);
                    s = _mm256_add_ps(s, e);
                }
                sum = hsum(s);
            }
            for v in &mut row[main..] {
                let e = super::exp1::<true>(*v - max);
                *v = e;
                sum += e;
            }
            let inv = 1.0 / sum;
            if main > 0 {
                let vinv = _mm256_set1_ps(inv);
                for k in (0..main).step_by(8) {
                    _mm256_storeu_ps(ptr.add(k), _mm256_mul_ps(_mm256_loadu_ps(ptr.add(k)), vinv));
                }
            }
            for v in &mut row[main..] {
                *v *= inv;
            }
        }
    }
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

/// Row-wise softmax in place (max-subtracted, polynomial `exp`).
pub fn softmax_rows(x: &mut [f32], cols: usize) {
    if cols == 0 {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if has_avx2_fma() {
        // SAFETY: the CPU supports AVX2 and FMA (checked at run time).
        return unsafe { avx2::softmax_rows(x, cols) };
    }
    softmax_rows_body::<false>(x, cols)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_is_accurate() {
        let mut worst = 0.0f64;
        let mut x = -87.0f32;
        while x < 88.0 {
            for v in [exp1::<false>(x), exp1::<true>(x)] {
                let e = (x as f64).exp();
                worst = worst.max(((v as f64) - e).abs() / e);
            }
            x += 0.0137;
        }
        assert!(worst < 5e-7, "{worst}");
    }

    #[test]
    fn softmax_matches_engine() {
        for cols in [1, 5, 8, 16, 37, 512] {
            let mut a: Vec<f32> = (0..3 * cols).map(|i| ((i * 7919) % 1000) as f32 / 50.0 - 10.0).collect();
            let mut b = a.clone();
            softmax_rows(&mut a, cols);
            crate::nn::softmax_rows_inplace(&mut b, cols);
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() <= 1e-6 * y.max(1e-3), "{cols} columns: {x} vs {y}");
            }
        }
    }
}
