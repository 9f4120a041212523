//! A fast, vectorisable `exp` and the slice kernels built on it.
//!
//! [`exp_fast`] is branch-free scalar code (Cody-Waite range reduction, a degree-5 minimax
//! polynomial, bit casts, selects) so that LLVM auto-vectorises the loops that call it (SSE2,
//! or AVX2 + FMA where the caller dispatches to it, natively); on `wasm32` with simd128 the slice
//! kernels use an explicit simd128 copy computing the same bits.
//! Accuracy: relative error below 2.5e-7 (about 2 ulp) for inputs in [-87.3, 88] (checked
//! against `f64::exp` in the tests), up to 7e-5 in the last (88.38, 88.72] before overflow; results
//! below `f32::MIN_POSITIVE` (inputs below about -87.3) flush to 0 and inputs above
//! `ln(f32::MAX)` give `+inf`. NaN propagates.

/// Largest input whose `exp` is finite in `f32`.
const HI: f32 = 88.722_83;
/// Inputs below this give 0 (their `exp` is subnormal).
const LO: f32 = -87.336_54;
const LOG2E: f32 = std::f32::consts::LOG2_E;
/// Cody-Waite split of ln 2: `LN2_HI` has few mantissa bits so `n * LN2_HI` is exact.
const LN2_HI: f32 = 0.693_359_4;
const LN2_LO: f32 = -2.121_944_4e-4;
/// `1.5 * 2^23`: adding it rounds to the nearest integer, left in the low mantissa bits.
const ROUND: f32 = 12_582_912.0;
/// Coefficients of `e^r = 1 + r + r^2 (C2 + C3 r + C4 r^2 + C5 r^3)`.
const C2: f32 = 0.499_992_3;
const C3: f32 = 0.166_671_14;
const C4: f32 = 0.041_890_115;
const C5: f32 = 0.008_312_525;

/// `e^x` in `f32` without branches (see the module docs for accuracy).
#[inline(always)]
pub fn exp_fast(x: f32) -> f32 {
    exp_impl::<false>(x)
}

/// `a * b + c`, fused when `FMA` (only instantiate with `FMA = true` in code compiled with the
/// `fma` target feature, else `mul_add` is a slow library call).
#[inline(always)]
pub(crate) fn madd<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// [`exp_fast`], with fused multiply-adds when `FMA` (see [`madd`]).
#[inline(always)]
pub(crate) fn exp_impl<const FMA: bool>(x: f32) -> f32 {
    // Clamp into the range where 2^n is a normal float; the true results are restored below.
    // Comparisons (not f32::max/min) so that NaN passes through untouched.
    let xc = if x < LO { LO } else { x };
    let xc = if xc > HI { HI } else { xc };
    // n = round(x / ln 2), r = x - n ln 2 in [-ln2/2, ln2/2]; n is capped at 127 so that 2^n is
    // finite (then r <= 0.7 in the top (88.38, 88.72], where the polynomial's error grows to 7e-5).
    let t = madd::<FMA>(xc, LOG2E, ROUND);
    let t = if t > ROUND + 127.0 { ROUND + 127.0 } else { t };
    let n = t - ROUND;
    let r = madd::<FMA>(-n, LN2_LO, madd::<FMA>(-n, LN2_HI, xc));
    // e^r = 1 + r + r^2 P(r), P of degree 3: relative minimax fit on [-ln2/2, ln2/2]
    // (Remez; 1.06e-7 with these f32 coefficients, before rounding of the evaluation).
    let mut p = C5;
    p = madd::<FMA>(p, r, C4);
    p = madd::<FMA>(p, r, C3);
    p = madd::<FMA>(p, r, C2);
    let er = madd::<FMA>(p, r * r, r) + 1.0;
    // 2^n from the rounded integer in t's low mantissa bits: n + 127 into the exponent field.
    let ni = t.to_bits().wrapping_sub(ROUND.to_bits()) as i32;
    let scale = f32::from_bits((ni.wrapping_add(127) << 23) as u32);
    let y = er * scale;
    let y = if x < LO { 0.0 } else { y };
    if x > HI {
        f32::INFINITY
    } else {
        y
    }
}

/// `x = e^x` elementwise, in place.
pub fn exp_inplace(x: &mut [f32]) {
    map_exp_inplace(x, |v| v, |e, _| e);
}

/// `x = post(e^(pre(x)), x)` elementwise in place, with the vectorised exp: the building block
/// of the exp-based activations. `pre` and `post` must be plain arithmetic so that the loop
/// vectorises (`post` also receives the original `x`).
#[inline(always)]
pub(crate) fn map_exp_inplace(x: &mut [f32], pre: impl Fn(f32) -> f32 + Copy, post: impl Fn(f32, f32) -> f32 + Copy) {
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    {
        simd128::map_exp_inplace(x, pre, post)
    }
    #[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
    for v in x {
        *v = post(exp_fast(pre(*v)), *v);
    }
}

/// `x = e^(x - shift)` elementwise in place; returns the sum of the results (lane-wise partial
/// sums, so the order differs from a sequential sum by rounding only).
#[inline(always)]
pub fn exp_shifted_sum_inplace(x: &mut [f32], shift: f32) -> f32 {
    exp_shifted_sum_impl::<false>(x, shift)
}

/// [`exp_shifted_sum_inplace`] with fused multiply-adds when `FMA`.
#[inline(always)]
pub(crate) fn exp_shifted_sum_impl<const FMA: bool>(x: &mut [f32], shift: f32) -> f32 {
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    {
        simd128::exp_shifted_sum(x, shift)
    }
    #[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
    {
        exp_shifted_sum_lanes::<FMA>(x, shift)
    }
}

#[allow(dead_code)] // unused on wasm32 + simd128
#[inline(always)]
fn exp_shifted_sum_lanes<const FMA: bool>(x: &mut [f32], shift: f32) -> f32 {
    const L: usize = 16;
    let mut acc = [0.0f32; L];
    let mut chunks = x.chunks_exact_mut(L);
    for c in &mut chunks {
        for (v, a) in c.iter_mut().zip(acc.iter_mut()) {
            let e = exp_impl::<FMA>(*v - shift);
            *v = e;
            *a += e;
        }
    }
    let mut tail = 0.0f32;
    for v in chunks.into_remainder() {
        let e = exp_impl::<FMA>(*v - shift);
        *v = e;
        tail += e;
    }
    sum_lanes(&acc) + tail
}

/// Largest element (`-inf` for an empty slice); NaN elements are ignored, as by `f32::max`.
#[inline(always)]
pub fn max_of(x: &[f32]) -> f32 {
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    {
        simd128::max_of(x)
    }
    #[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
    {
        max_of_lanes(x)
    }
}

#[allow(dead_code)] // unused on wasm32 + simd128
#[inline(always)]
fn max_of_lanes(x: &[f32]) -> f32 {
    const L: usize = 16;
    let mut acc = [f32::NEG_INFINITY; L];
    let mut chunks = x.chunks_exact(L);
    for c in &mut chunks {
        for (v, a) in c.iter().zip(acc.iter_mut()) {
            *a = if *v > *a { *v } else { *a };
        }
    }
    let mut m = chunks.remainder().iter().copied().fold(f32::NEG_INFINITY, max_skip_nan);
    for a in acc {
        m = max_skip_nan(m, a);
    }
    m
}

/// `max(m, v)` ignoring a NaN `v` (`m` is never NaN here); unlike `f32::max`, no libm call
/// on wasm.
#[inline(always)]
fn max_skip_nan(m: f32, v: f32) -> f32 {
    if v > m {
        v
    } else {
        m
    }
}

/// Sum with lane-wise partial sums (vectorisable).
#[inline]
pub fn sum_of(x: &[f32]) -> f32 {
    const L: usize = 16;
    let mut acc = [0.0f32; L];
    let mut chunks = x.chunks_exact(L);
    for c in &mut chunks {
        for (v, a) in c.iter().zip(acc.iter_mut()) {
            *a += *v;
        }
    }
    sum_lanes(&acc) + chunks.remainder().iter().sum::<f32>()
}

/// Pairwise sum of a small array of lanes.
#[inline(always)]
fn sum_lanes<const L: usize>(acc: &[f32; L]) -> f32 {
    let mut w = *acc;
    let mut n = L;
    while n > 1 {
        n /= 2;
        for i in 0..n {
            w[i] += w[i + n];
        }
    }
    w[0]
}

/// Explicit simd128 versions: V8 compiles LLVM's auto-vectorised 16-lane loops poorly
/// (constants rematerialised, spills), so on wasm the loops are written one `v128` at a time.
/// `exp` here is bit-identical to the scalar [`exp_fast`] (same operations, same order).
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod simd128 {
    use super::{exp_fast, max_skip_nan, C2, C3, C4, C5, HI, LN2_HI, LN2_LO, LO, LOG2E, ROUND};
    use core::arch::wasm32::*;

    /// The constants of [`exp_v`], splatted once per call. V8 materialises every
    /// `v128.const` inside a loop (several instructions each, ~14 of them per exp) instead of
    /// hoisting it; splats of opaque values stay in locals (registers or one stack reload).
    pub struct Consts([v128; 13]);

    impl Consts {
        #[inline(always)]
        pub fn new() -> Self {
            let c = core::hint::black_box([
                LO,
                HI,
                LOG2E,
                ROUND,
                ROUND + 127.0,
                LN2_HI,
                LN2_LO,
                C5,
                C4,
                C3,
                C2,
                1.0,
                f32::INFINITY,
            ]);
            Consts(c.map(|v| f32x4_splat(v)))
        }
    }

    /// [`exp_fast`] on four lanes.
    #[inline(always)]
    pub fn exp_v(x: v128, k: &Consts) -> v128 {
        let [lo, hi, log2e, round, round127, ln2_hi, ln2_lo, c5, c4, c3, c2, one, inf] = k.0;
        let xc = f32x4_pmax(x, lo); // x < LO ? LO : x (NaN stays)
        let xc = f32x4_pmin(xc, hi); // HI < xc ? HI : xc
        let t = f32x4_add(f32x4_mul(xc, log2e), round);
        let t = f32x4_pmin(t, round127);
        let n = f32x4_sub(t, round);
        let r = f32x4_sub(f32x4_sub(xc, f32x4_mul(n, ln2_hi)), f32x4_mul(n, ln2_lo));
        let mut p = c5;
        p = f32x4_add(f32x4_mul(p, r), c4);
        p = f32x4_add(f32x4_mul(p, r), c3);
        p = f32x4_add(f32x4_mul(p, r), c2);
        let er = f32x4_add(f32x4_add(f32x4_mul(p, f32x4_mul(r, r)), r), one);
        // 2^n: ((bits(t) - bits(ROUND)) + 127) << 23 == (bits(t) << 23) + bits(1.0) (mod 2^32).
        let scale = i32x4_add(i32x4_shl(t, 23), one);
        let y = f32x4_mul(er, scale);
        let y = v128_andnot(y, f32x4_lt(x, lo));
        v128_bitselect(inf, y, f32x4_gt(x, hi))
    }

    #[inline(always)]
    pub fn exp_shifted_sum(x: &mut [f32], shift: f32) -> f32 {
        let k = Consts::new();
        let vs = f32x4_splat(shift);
        let mut acc = f32x4_splat(0.0);
        let mut chunks = x.chunks_exact_mut(4);
        for c in &mut chunks {
            // SAFETY: c has exactly 4 elements; v128 loads/stores need no alignment.
            unsafe {
                let p = c.as_mut_ptr() as *mut v128;
                let e = exp_v(f32x4_sub(v128_load(p), vs), &k);
                v128_store(p, e);
                acc = f32x4_add(acc, e);
            }
        }
        let mut tail = 0.0f32;
        for v in chunks.into_remainder() {
            let e = exp_fast(*v - shift);
            *v = e;
            tail += e;
        }
        let h = f32x4_add(acc, i32x4_shuffle::<2, 3, 0, 1>(acc, acc));
        f32x4_extract_lane::<0>(h) + f32x4_extract_lane::<1>(h) + tail
    }

    #[inline(always)]
    pub fn max_of(x: &[f32]) -> f32 {
        // Four independent accumulators: one chain would be bound by the max latency.
        let mut acc = [f32x4_splat(f32::NEG_INFINITY); 4];
        let mut chunks = x.chunks_exact(16);
        for c in &mut chunks {
            for (j, a) in acc.iter_mut().enumerate() {
                // SAFETY: c has 16 elements, so 4 * j + 4 <= 16.
                let v = unsafe { v128_load(c.as_ptr().add(4 * j) as *const v128) };
                *a = f32x4_pmax(*a, v); // a < v ? v : a: NaN in v is skipped
            }
        }
        let acc = f32x4_pmax(f32x4_pmax(acc[0], acc[1]), f32x4_pmax(acc[2], acc[3]));
        let mut m = chunks.remainder().iter().copied().fold(f32::NEG_INFINITY, max_skip_nan);
        for l in [
            f32x4_extract_lane::<0>(acc),
            f32x4_extract_lane::<1>(acc),
            f32x4_extract_lane::<2>(acc),
            f32x4_extract_lane::<3>(acc),
        ] {
            m = max_skip_nan(m, l);
        }
        m
    }

    /// See [`super::map_exp_inplace`]; `pre`/`post` are applied lane by lane (LLVM turns the
    /// scalar closures back into vector ops).
    #[inline(always)]
    pub fn map_exp_inplace(x: &mut [f32], pre: impl Fn(f32) -> f32 + Copy, post: impl Fn(f32, f32) -> f32 + Copy) {
        let k = Consts::new();
        let mut chunks = x.chunks_exact_mut(4);
        for c in &mut chunks {
            let u = [c[0], c[1], c[2], c[3]];
            let z = f32x4(pre(u[0]), pre(u[1]), pre(u[2]), pre(u[3]));
            let e = exp_v(z, &k);
            c[0] = post(f32x4_extract_lane::<0>(e), u[0]);
            c[1] = post(f32x4_extract_lane::<1>(e), u[1]);
            c[2] = post(f32x4_extract_lane::<2>(e), u[2]);
            c[3] = post(f32x4_extract_lane::<3>(e), u[3]);
        }
        for v in chunks.into_remainder() {
            *v = post(exp_fast(pre(*v)), *v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_matches_std_in_softmax_range() {
        let mut worst = 0.0f64;
        let n = 2_000_000;
        for i in 0..=n {
            let x = -87.0 + 87.0 * 1.01 * i as f32 / n as f32; // [-87, ~0.87]
            let e = exp_fast(x) as f64;
            let r = (x as f64).exp();
            worst = worst.max(((e - r) / r).abs());
        }
        assert!(worst < 2.5e-7, "worst relative error {worst}");
    }

    #[test]
    fn exp_full_range_and_specials() {
        for i in 0..=200_000 {
            let x = -87.3 + 176.0 * i as f32 / 200_000.0;
            let e = exp_fast(x) as f64;
            let r = (x as f64).exp();
            let tol = if x > 88.0 { 1e-4 } else { 2.5e-7 };
            if r < f32::MAX as f64 {
                assert!(((e - r) / r).abs() < tol, "x = {x}: {e} vs {r}");
            }
        }
        assert_eq!(exp_fast(0.0), 1.0);
        assert_eq!(exp_fast(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp_fast(-100.0), 0.0);
        assert_eq!(exp_fast(f32::INFINITY), f32::INFINITY);
        assert_eq!(exp_fast(89.0), f32::INFINITY);
        assert!(exp_fast(88.5).is_finite());
        assert!(exp_fast(f32::NAN).is_nan());
    }

    #[test]
    fn reductions() {
        let x: Vec<f32> = (0..37).map(|i| ((i * 7919) % 101) as f32 - 50.0).collect();
        assert_eq!(max_of(&x), 50.0);
        assert_eq!(max_of(&[]), f32::NEG_INFINITY);
        assert_eq!(sum_of(&x), x.iter().sum::<f32>());
        let mut y = x.clone();
        let s = exp_shifted_sum_inplace(&mut y, 50.0);
        let r: f64 = x.iter().map(|v| ((*v - 50.0) as f64).exp()).sum();
        assert!(((s as f64 - r) / r).abs() < 1e-6);
    }
}
