//! Linear layers on int8 weights, computed in integers.
//!
//! A weight stored as int8 with one scale per row (`weights::int8`) is kept as 16-bit integers.
//! Each input row is quantised to 16-bit integers with its own scale (its largest magnitude maps
//! to [`QuantWeight::input_max`]), the products are summed exactly in 32-bit integers, and each
//! sum is scaled back once: `y[r][o] = sum_k qx[r][k] qw[o][k] * (sx[r] sw[o]) + b[o]`. Against the
//! same weights in `f32`, each input is off by at most half a step (`1 / 65534` of its row's
//! largest magnitude for layers of up to 512 inputs; wider ones take fewer steps, so that no sum
//! can overflow). On wasm32 a `simd128` kernel does 8 multiply-adds per instruction
//! (`i32x4.dot_i16x8_s`), about twice what the `f32` kernel does without fused multiply-add.
//!
//! Integer sums do not depend on their order, and the scaling is the same scalar arithmetic
//! everywhere, so every target computes the same bits.

use std::cell::RefCell;

/// Outputs per tile of the kernel: a weight's rows are padded with zeros to a multiple of this.
const TILE_OUT: usize = 4;
/// Inputs per step of the kernel: rows are padded with zeros to a multiple of this (the AVX2
/// kernel's step; the others take two steps of 8).
const PAD: usize = 16;
/// Inputs per step of the 128-bit kernels.
const STEP: usize = 8;

thread_local! {
    /// The quantised input rows and their scales (grown, never shrunk).
    static INPUT: RefCell<(Vec<i16>, Vec<f32>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

/// A `[out, in]` weight as 16-bit integers with one `f32` scale per output (row).
#[derive(Clone, Debug, PartialEq)]
pub struct QuantWeight {
    /// `[out_pad, in_pad]` row-major, zero-padded (`out_pad`, `in_pad` multiples of 4 and 16).
    q: Vec<i16>,
    /// One scale per output row.
    scale: Vec<f32>,
    in_dim: usize,
    in_pad: usize,
    out_dim: usize,
    out_pad: usize,
}

impl QuantWeight {
    /// From int8 values `q` (`[out_dim, in_dim]` row-major) and one scale per row; `None` if the
    /// lengths disagree.
    pub fn new(q: &[i8], scale: &[f32], out_dim: usize, in_dim: usize) -> Option<Self> {
        if q.len() != out_dim * in_dim || scale.len() != out_dim {
            return None;
        }
        let in_pad = in_dim.div_ceil(PAD) * PAD;
        let out_pad = out_dim.div_ceil(TILE_OUT) * TILE_OUT;
        let mut padded = vec![0i16; out_pad * in_pad];
        for (dst, src) in padded.chunks_exact_mut(in_pad.max(1)).zip(q.chunks_exact(in_dim.max(1))) {
            for (d, &s) in dst.iter_mut().zip(src) {
                *d = s as i16;
            }
        }
        Some(Self { q: padded, scale: scale.to_vec(), in_dim, in_pad, out_dim, out_pad })
    }

    /// The integer an input row's largest magnitude becomes: as large as 16 bits allow while no
    /// sum of `in_dim` products with weights of magnitude up to 128 can leave 32 bits.
    pub fn input_max(&self) -> f32 {
        let bound = (i32::MAX as usize) / (self.in_pad.max(1) * 128);
        bound.min(i16::MAX as usize) as f32
    }

    /// `y = x W^T + b` for `rows` rows of `x` (`[rows, in_dim]`), written `[rows, out_dim]`, or
    /// transposed (`[out_dim, rows]`) with `transposed`. Returns `false`, writing nothing, when an
    /// input is not finite or a row is too small to scale (its largest magnitude below about
    /// 1e-34); the caller then computes in `f32`, which carries a NaN on.
    pub fn forward(&self, x: &[f32], rows: usize, y: &mut [f32], bias: Option<&[f32]>, transposed: bool) -> bool {
        self.run(x, rows, Output { y, rows, out_dim: self.out_dim, transposed, bias }, kernel)
    }

    /// [`QuantWeight::forward`] through the plain-Rust kernel (for tests: every target's kernel
    /// must give its bits).
    #[doc(hidden)]
    pub fn forward_portable(&self, x: &[f32], rows: usize, y: &mut [f32], bias: Option<&[f32]>) -> bool {
        let out = Output { y, rows, out_dim: self.out_dim, transposed: false, bias };
        self.run(x, rows, out, |w, xq, xs, rows, mut out| portable_kernel(w, xq, xs, rows, &mut out))
    }

    /// Quantises the rows of `x` into the thread's buffers ([`quantize_rows`]) and runs `kernel` on
    /// them; `false`, writing nothing, when they cannot be quantised.
    fn run(
        &self,
        x: &[f32],
        rows: usize,
        out: Output,
        kernel: impl FnOnce(&Self, &[i16], &[f32], usize, Output),
    ) -> bool {
        debug_assert_eq!(x.len(), rows * self.in_dim);
        debug_assert_eq!(out.y.len(), rows * self.out_dim);
        INPUT.with(|cell| {
            let (xq, xs) = &mut *cell.borrow_mut();
            if !quantize_rows(x, rows, self.in_dim, self.in_pad, self.input_max(), xq, xs) {
                return false;
            }
            kernel(self, xq, xs, rows, out);
            true
        })
    }
}

/// Quantises each row of `x` (`[rows, k]`) into `xq` (`[rows, k_pad]`, zero-padded) with its scale
/// in `xs` (`largest magnitude / qmax`; 0 for a row of zeros). `false` if an input is not finite
/// or a row's largest magnitude so small that its scale overflows.
fn quantize_rows(
    x: &[f32],
    rows: usize,
    k: usize,
    k_pad: usize,
    qmax: f32,
    xq: &mut Vec<i16>,
    xs: &mut Vec<f32>,
) -> bool {
    xq.clear();
    xq.resize(rows * k_pad, 0);
    xs.clear();
    for (src, dst) in x.chunks_exact(k.max(1)).take(rows).zip(xq.chunks_exact_mut(k_pad.max(1))) {
        // the largest magnitude by its bits (ordered as the values are; infinities and NaNs
        // above every finite value), so that the loop vectorises
        let bits = src.iter().fold(0u32, |m, v| m.max(v.to_bits() & 0x7fff_ffff));
        if bits >= f32::INFINITY.to_bits() {
            return false;
        }
        let max = f32::from_bits(bits);
        if max == 0.0 {
            xs.push(0.0);
            continue;
        }
        let inv = qmax / max;
        if !inv.is_finite() {
            // a row below about 1e-34 (subnormal): its scale would overflow
            return false;
        }
        for (d, &v) in dst.iter_mut().zip(src) {
            // |v * inv| <= qmax < 2^22: adding 1.5 * 2^23 rounds it to the nearest integer (ties
            // to even), which the low mantissa bits then hold, offset by 2^22
            let t = v * inv + ROUNDING;
            *d = (t.to_bits() as i32 - ROUNDING.to_bits() as i32) as i16;
        }
        xs.push(max / qmax);
    }
    if k == 0 {
        xs.resize(rows, 0.0);
    }
    true
}

/// `1.5 * 2^23`: see [`quantize_rows`].
const ROUNDING: f32 = 12_582_912.0;

/// Where the kernel writes.
struct Output<'a> {
    y: &'a mut [f32],
    rows: usize,
    out_dim: usize,
    transposed: bool,
    bias: Option<&'a [f32]>,
}

impl Output<'_> {
    /// Writes the integer sums `acc` of row `r`, outputs `o..o + 4` (those below `out_dim`).
    #[inline(always)]
    fn put(&mut self, w: &QuantWeight, r: usize, o: usize, acc: [i32; TILE_OUT], sx: f32) {
        for (j, &a) in acc.iter().enumerate() {
            let oj = o + j;
            if oj >= self.out_dim {
                break;
            }
            let mut v = a as f32 * (sx * w.scale[oj]);
            if let Some(b) = self.bias {
                v += b[oj];
            }
            let at = if self.transposed { oj * self.rows + r } else { r * self.out_dim + oj };
            self.y[at] = v;
        }
    }
}

/// The integer products of every row with every output, written through `out`.
fn kernel(w: &QuantWeight, xq: &[i16], xs: &[f32], rows: usize, mut out: Output) {
    #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
    {
        simd128::kernel(w, xq, xs, rows, &mut out);
    }
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2.
            unsafe { avx2::kernel(w, xq, xs, rows, &mut out) }
        } else {
            sse2::kernel(w, xq, xs, rows, &mut out);
        }
    }
    #[cfg(not(any(all(target_arch = "wasm32", target_feature = "simd128"), target_arch = "x86_64")))]
    {
        portable_kernel(w, xq, xs, rows, &mut out);
    }
}

/// Plain Rust, for targets without a kernel of their own (and the tests' reference).
fn portable_kernel(w: &QuantWeight, xq: &[i16], xs: &[f32], rows: usize, out: &mut Output) {
    let kp = w.in_pad;
    for r in 0..rows {
        let x = &xq[r * kp..(r + 1) * kp];
        for o in (0..w.out_pad).step_by(TILE_OUT) {
            let mut acc = [0i32; TILE_OUT];
            for (j, a) in acc.iter_mut().enumerate() {
                let wr = &w.q[(o + j) * kp..(o + j + 1) * kp];
                *a = x.iter().zip(wr).map(|(&p, &q)| p as i32 * q as i32).sum();
            }
            out.put(w, r, o, acc, xs[r]);
        }
    }
}

/// Walks the output in tiles of two rows (a lone last row read twice, its copy not written) by
/// four outputs: `tile(r, two, x0, x1, o, wp)` gets the tile's first row `r`, whether it has a
/// second, pointers to the two rows' quantised inputs and to the first of its four weight rows.
#[allow(dead_code)] // unused where only the portable kernel runs
#[inline(always)]
fn tiles(
    w: &QuantWeight,
    xq: &[i16],
    rows: usize,
    mut tile: impl FnMut(usize, bool, *const i16, *const i16, usize, *const i16),
) {
    let kp = w.in_pad;
    let mut r = 0;
    while r < rows {
        let two = r + 1 < rows;
        let x0 = xq[r * kp..(r + 1) * kp].as_ptr();
        let x1 = if two { xq[(r + 1) * kp..(r + 2) * kp].as_ptr() } else { x0 };
        for o in (0..w.out_pad).step_by(TILE_OUT) {
            tile(r, two, x0, x1, o, w.q[o * kp..(o + TILE_OUT) * kp].as_ptr());
        }
        r += 2;
    }
}

#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod simd128 {
    use super::{Output, QuantWeight, STEP, TILE_OUT};
    use core::arch::wasm32::*;

    /// The sums of four `i32x4` vectors, one per lane: `[sum a, sum b, sum c, sum d]`.
    #[inline(always)]
    fn sum4(a: v128, b: v128, c: v128, d: v128) -> v128 {
        let ab = i32x4_add(i32x4_shuffle::<0, 4, 2, 6>(a, b), i32x4_shuffle::<1, 5, 3, 7>(a, b));
        let cd = i32x4_add(i32x4_shuffle::<0, 4, 2, 6>(c, d), i32x4_shuffle::<1, 5, 3, 7>(c, d));
        i32x4_add(i32x4_shuffle::<0, 1, 4, 5>(ab, cd), i32x4_shuffle::<2, 3, 6, 7>(ab, cd))
    }

    /// [`Output::put`] of the sums `s` (one per lane), in four lanes at once where the four
    /// outputs are contiguous: the same operations lane by lane, so the same bits.
    #[inline(always)]
    fn put4(out: &mut Output, w: &QuantWeight, r: usize, o: usize, s: v128, sx: f32) {
        if out.transposed || o + TILE_OUT > out.out_dim {
            let lanes = [
                i32x4_extract_lane::<0>(s),
                i32x4_extract_lane::<1>(s),
                i32x4_extract_lane::<2>(s),
                i32x4_extract_lane::<3>(s),
            ];
            out.put(w, r, o, lanes, sx);
            return;
        }
        let scale = &w.scale[o..o + TILE_OUT];
        let at = r * out.out_dim + o;
        let y = &mut out.y[at..at + TILE_OUT];
        // SAFETY: the loads and the store cover four in-bounds values each (checked just above)
        unsafe {
            let mut v =
                f32x4_mul(f32x4_convert_i32x4(s), f32x4_mul(f32x4_splat(sx), v128_load(scale.as_ptr() as *const v128)));
            if let Some(b) = out.bias {
                v = f32x4_add(v, v128_load(b[o..o + TILE_OUT].as_ptr() as *const v128));
            }
            v128_store(y.as_mut_ptr() as *mut v128, v);
        }
    }

    /// Two rows by four outputs per tile (eight `i32x4` accumulators: V8 keeps them in registers),
    /// eight inputs per step: two row loads, four weight loads, eight `dot_i16x8` and eight adds.
    pub(super) fn kernel(w: &QuantWeight, xq: &[i16], xs: &[f32], rows: usize, out: &mut Output) {
        let kp = w.in_pad;
        super::tiles(w, xq, rows, |r, two, x0, x1, o, wp| {
            let mut a = [[i32x4_splat(0); TILE_OUT]; 2];
            // SAFETY: every row of `xq` and `w.q` holds `kp` values (a multiple of STEP), and the
            // tile's four weight rows lie inside `w.q` (`out_pad` is a multiple of 4).
            unsafe {
                for s in (0..kp).step_by(STEP) {
                    let (u0, u1) = (v128_load(x0.add(s) as *const v128), v128_load(x1.add(s) as *const v128));
                    let [a0, a1] = &mut a;
                    for (j, (p0, p1)) in a0.iter_mut().zip(a1.iter_mut()).enumerate() {
                        let v = v128_load(wp.add(j * kp + s) as *const v128);
                        *p0 = i32x4_add(*p0, i32x4_dot_i16x8(u0, v));
                        *p1 = i32x4_add(*p1, i32x4_dot_i16x8(u1, v));
                    }
                }
            }
            put4(out, w, r, o, sum4(a[0][0], a[0][1], a[0][2], a[0][3]), xs[r]);
            if two {
                put4(out, w, r + 1, o, sum4(a[1][0], a[1][1], a[1][2], a[1][3]), xs[r + 1]);
            }
        });
    }
}

/// The simd128 kernel's twin on x86-64, whose baseline SSE2 has the same instruction
/// (`pmaddwd`).
#[cfg(target_arch = "x86_64")]
mod sse2 {
    use super::{Output, QuantWeight, STEP, TILE_OUT};
    use core::arch::x86_64::*;

    /// The sums of four `i32x4` vectors, one per lane.
    #[inline(always)]
    pub(super) unsafe fn sum4(a: __m128i, b: __m128i, c: __m128i, d: __m128i) -> [i32; 4] {
        let ab = _mm_add_epi32(_mm_unpacklo_epi32(a, b), _mm_unpackhi_epi32(a, b));
        let cd = _mm_add_epi32(_mm_unpacklo_epi32(c, d), _mm_unpackhi_epi32(c, d));
        let s = _mm_add_epi32(_mm_unpacklo_epi64(ab, cd), _mm_unpackhi_epi64(ab, cd));
        let mut out = [0i32; 4];
        _mm_storeu_si128(out.as_mut_ptr() as *mut __m128i, s);
        out
    }

    /// Two rows by four outputs per tile, as on wasm32.
    pub(super) fn kernel(w: &QuantWeight, xq: &[i16], xs: &[f32], rows: usize, out: &mut Output) {
        let kp = w.in_pad;
        super::tiles(w, xq, rows, |r, two, x0, x1, o, wp| {
            // SAFETY: SSE2 is part of x86-64; the loads stay inside the rows (as on wasm32).
            let (s0, s1) = unsafe {
                let mut a = [[_mm_setzero_si128(); TILE_OUT]; 2];
                for s in (0..kp).step_by(STEP) {
                    let u0 = _mm_loadu_si128(x0.add(s) as *const __m128i);
                    let u1 = _mm_loadu_si128(x1.add(s) as *const __m128i);
                    let [a0, a1] = &mut a;
                    for (j, (p0, p1)) in a0.iter_mut().zip(a1.iter_mut()).enumerate() {
                        let v = _mm_loadu_si128(wp.add(j * kp + s) as *const __m128i);
                        *p0 = _mm_add_epi32(*p0, _mm_madd_epi16(u0, v));
                        *p1 = _mm_add_epi32(*p1, _mm_madd_epi16(u1, v));
                    }
                }
                (sum4(a[0][0], a[0][1], a[0][2], a[0][3]), sum4(a[1][0], a[1][1], a[1][2], a[1][3]))
            };
            out.put(w, r, o, s0, xs[r]);
            if two {
                out.put(w, r + 1, o, s1, xs[r + 1]);
            }
        });
    }
}

/// Sixteen inputs per step (`vpmaddwd` on 256 bits), where the CPU has AVX2.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{Output, QuantWeight, PAD, TILE_OUT};
    use core::arch::x86_64::*;

    /// Two rows by four outputs per tile, as the other kernels.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn kernel(w: &QuantWeight, xq: &[i16], xs: &[f32], rows: usize, out: &mut Output) {
        let kp = w.in_pad;
        super::tiles(w, xq, rows, |r, two, x0, x1, o, wp| {
            let mut a = [[_mm256_setzero_si256(); TILE_OUT]; 2];
            for s in (0..kp).step_by(PAD) {
                let u0 = _mm256_loadu_si256(x0.add(s) as *const __m256i);
                let u1 = _mm256_loadu_si256(x1.add(s) as *const __m256i);
                let [a0, a1] = &mut a;
                for (j, (p0, p1)) in a0.iter_mut().zip(a1.iter_mut()).enumerate() {
                    let v = _mm256_loadu_si256(wp.add(j * kp + s) as *const __m256i);
                    *p0 = _mm256_add_epi32(*p0, _mm256_madd_epi16(u0, v));
                    *p1 = _mm256_add_epi32(*p1, _mm256_madd_epi16(u1, v));
                }
            }
            let half = |v: __m256i| _mm_add_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256::<1>(v));
            out.put(w, r, o, super::sse2::sum4(half(a[0][0]), half(a[0][1]), half(a[0][2]), half(a[0][3])), xs[r]);
            if two {
                let s1 = super::sse2::sum4(half(a[1][0]), half(a[1][1]), half(a[1][2]), half(a[1][3]));
                out.put(w, r + 1, o, s1, xs[r + 1]);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn weight(out: usize, k: usize, seed: u32) -> (Vec<i8>, Vec<f32>) {
        let q = (0..out * k).map(|i| ((i as u32).wrapping_mul(2_654_435_761).wrapping_add(seed) >> 24) as i8).collect();
        let s = (0..out).map(|o| 0.01 + 0.001 * o as f32).collect();
        (q, s)
    }

    /// The integer layer against the same weights in `f64`, for shapes off the tile sizes.
    #[test]
    fn matches_the_dequantised_weights() {
        for (rows, k, out) in [(1, 3, 1), (5, 13, 6), (2, 8, 4), (7, 130, 9), (128, 128, 128), (3, 256, 64)] {
            let (q, s) = weight(out, k, 7);
            let w = QuantWeight::new(&q, &s, out, k).unwrap();
            let x: Vec<f32> = (0..rows * k).map(|i| ((i * 37 % 101) as f32 - 50.0) / 17.0).collect();
            let b: Vec<f32> = (0..out).map(|o| o as f32 * 0.5).collect();
            let mut y = vec![f32::NAN; rows * out];
            let mut yt = vec![f32::NAN; rows * out];
            assert!(w.forward(&x, rows, &mut y, Some(&b), false));
            assert!(w.forward(&x, rows, &mut yt, Some(&b), true));
            for r in 0..rows {
                let xr = &x[r * k..(r + 1) * k];
                let big = xr.iter().fold(0.0f64, |m, v| m.max(v.abs() as f64));
                for o in 0..out {
                    let exact: f64 =
                        (0..k).map(|c| xr[c] as f64 * q[o * k + c] as f64 * s[o] as f64).sum::<f64>() + b[o] as f64;
                    // each input off by at most half a step of big / 32767
                    let bound: f64 =
                        (0..k).map(|c| (q[o * k + c] as f64 * s[o] as f64).abs()).sum::<f64>() * big / 65534.0;
                    let got = y[r * out + o] as f64;
                    assert!(
                        (got - exact).abs() <= bound + 1e-5 * exact.abs().max(1.0),
                        "{rows}x{k}x{out} r{r} o{o}: {got} vs {exact}"
                    );
                    assert_eq!(yt[o * rows + r].to_bits(), y[r * out + o].to_bits());
                }
            }
        }
    }

    /// This target's kernel gives the portable kernel's bits.
    #[test]
    fn the_kernel_matches_the_portable_one() {
        for (rows, k, out) in [(1, 3, 1), (5, 13, 6), (7, 130, 9), (64, 256, 128)] {
            let (q, s) = weight(out, k, 3);
            let w = QuantWeight::new(&q, &s, out, k).unwrap();
            let x: Vec<f32> = (0..rows * k).map(|i| ((i * 53 % 97) as f32 - 48.0) / 7.0).collect();
            let b: Vec<f32> = (0..out).map(|o| o as f32 * 0.25).collect();
            let (mut a, mut c) = (vec![0.0f32; rows * out], vec![0.0f32; rows * out]);
            assert!(w.forward(&x, rows, &mut a, Some(&b), false));
            assert!(w.forward_portable(&x, rows, &mut c, Some(&b)));
            assert!(a.iter().zip(&c).all(|(u, v)| u.to_bits() == v.to_bits()), "{rows}x{k}x{out}");
        }
    }

    /// The SSE2 kernel, which machines with AVX2 never dispatch to, gives the portable kernel's
    /// bits too.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_sse2_kernel_matches_the_portable_one() {
        for (rows, k, out) in [(1, 3, 1), (5, 13, 6), (7, 130, 9), (64, 256, 128)] {
            let (q, s) = weight(out, k, 5);
            let w = QuantWeight::new(&q, &s, out, k).unwrap();
            let x: Vec<f32> = (0..rows * k).map(|i| ((i * 29 % 89) as f32 - 44.0) / 5.0).collect();
            let (mut xq, mut xs) = (Vec::new(), Vec::new());
            assert!(quantize_rows(&x, rows, k, w.in_pad, w.input_max(), &mut xq, &mut xs));
            let (mut a, mut c) = (vec![0.0f32; rows * out], vec![0.0f32; rows * out]);
            sse2::kernel(
                &w,
                &xq,
                &xs,
                rows,
                &mut Output { y: &mut a, rows, out_dim: out, transposed: false, bias: None },
            );
            assert!(w.forward_portable(&x, rows, &mut c, None));
            assert!(a.iter().zip(&c).all(|(u, v)| u.to_bits() == v.to_bits()), "{rows}x{k}x{out}");
        }
    }

    #[test]
    fn non_finite_inputs_are_left_to_the_caller() {
        let (q, s) = weight(4, 8, 1);
        let w = QuantWeight::new(&q, &s, 4, 8).unwrap();
        let mut x = vec![1.0f32; 16];
        x[11] = f32::NAN;
        let mut y = vec![0.0; 8];
        assert!(!w.forward(&x, 2, &mut y, None, false));
        assert!(y.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn rows_too_small_to_scale_are_left_to_the_caller() {
        let (q, s) = weight(4, 8, 1);
        let w = QuantWeight::new(&q, &s, 4, 8).unwrap();
        let mut x = vec![0.0f32; 16];
        x[3] = 1e-40;
        let mut y = vec![0.0; 8];
        assert!(!w.forward(&x, 2, &mut y, None, false));
        x[3] = 1e-30;
        assert!(w.forward(&x, 2, &mut y, None, false));
        assert!(y.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn zero_rows_give_the_bias() {
        let (q, s) = weight(3, 5, 2);
        let w = QuantWeight::new(&q, &s, 3, 5).unwrap();
        let mut y = vec![f32::NAN; 6];
        assert!(w.forward(&[0.0; 10], 2, &mut y, Some(&[1.0, 2.0, 3.0]), false));
        assert_eq!(y, [1.0, 2.0, 3.0, 1.0, 2.0, 3.0]);
    }

    #[test]
    fn no_sum_can_overflow() {
        for k in [8, 256, 512, 1024, 4096] {
            let q = vec![-128i8; k];
            let w = QuantWeight::new(&q, &[1.0], 1, k).unwrap();
            assert!(w.input_max() * 128.0 * w.in_pad as f32 <= i32::MAX as f32, "{k}");
            let x = vec![-3.0f32; k];
            let mut y = [0.0f32];
            assert!(w.forward(&x, 1, &mut y, None, false));
            assert!((y[0] - 3.0 * 128.0 * k as f32).abs() <= 1e-3 * y[0]);
        }
    }
}
