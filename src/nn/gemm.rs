//! A packed, cache-blocked SGEMM (Goto/BLIS loop order) with an `MR x NR` register-tile
//! micro-kernel: explicit `core::arch::wasm32` simd128 on wasm32 (where it beats
//! `matrixmultiply`'s 8x8 simd128 kernel, ~38-41 vs ~29-33 GFLOP/s on 512x128x128-like
//! shapes in Node 20), and a portable scalar kernel with the same blocking everywhere else, so
//! the blocking and packing logic is tested natively (the simd128 kernel itself by running
//! the test suite as wasm32-wasip1 under Node).
//!
//! Packing buffers are thread-local and only grow: no allocation per call after warm-up.

use std::cell::RefCell;

/// Rows of the register tile.
pub const MR: usize = 4;
/// Columns of the register tile.
pub const NR: usize = 8;
/// Depth of a packed block (the `A` micro-panel `MR x KC` and `B` micro-panel `KC x NR` stay
/// in L1).
const KC: usize = 256;
/// Rows of a packed `A` block (`MC x KC` floats = 64 KiB, in L2).
const MC: usize = 64;
/// Columns of a packed `B` block.
const NC: usize = 512;

thread_local! {
    static PACK: RefCell<(Vec<f32>, Vec<f32>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

/// Which micro-kernel [`gemm_blocked_with`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Plain Rust, any target.
    Portable,
    /// `core::arch::wasm32` simd128 (only on wasm32 builds with `+simd128`; elsewhere it
    /// falls back to [`Kernel::Portable`]).
    Simd128,
}

/// The best kernel of this build.
pub const fn native_kernel() -> Kernel {
    if cfg!(all(target_arch = "wasm32", target_feature = "simd128")) {
        Kernel::Simd128
    } else {
        Kernel::Portable
    }
}

/// `C = alpha * A * B + beta * C` with element strides, using [`native_kernel`]
/// (arguments as in [`gemm`](super::matmul::gemm)). `beta == 0` never reads `C`.
#[allow(clippy::too_many_arguments)]
pub fn gemm_blocked(
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
    gemm_blocked_with(native_kernel(), m, k, n, alpha, a, rsa, csa, b, rsb, csb, beta, c, rsc, csc);
}

/// [`gemm_blocked`] with an explicit micro-kernel (for tests and benchmarks).
#[allow(clippy::too_many_arguments)]
pub fn gemm_blocked_with(
    kernel: Kernel,
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
    super::matmul::check_operands(m, k, n, a.len(), rsa, csa, b.len(), rsb, csb, c.len(), rsc, csc);
    if m == 0 || n == 0 {
        return;
    }
    // SAFETY: check_operands asserted that every strided view lies inside its slice, with
    // non-negative strides; `c` is exclusively borrowed and cannot alias `a` or `b`.
    unsafe {
        if k == 0 {
            return scale_c(m, n, beta, c.as_mut_ptr(), rsc, csc);
        }
        PACK.with(|p| {
            let mut p = p.borrow_mut();
            let (ap, bp) = &mut *p;
            blocked(
                kernel,
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
                ap,
                bp,
            );
        });
    }
}

/// `C = beta * C` (`beta == 0` writes zeros without reading).
unsafe fn scale_c(m: usize, n: usize, beta: f32, c: *mut f32, rsc: isize, csc: isize) {
    for i in 0..m {
        for j in 0..n {
            let p = c.offset(i as isize * rsc + j as isize * csc);
            *p = if beta == 0.0 { 0.0 } else { beta * *p };
        }
    }
}

/// Where a micro-kernel reads its operands: element `(i, p)` of the `A` micro-panel is at
/// `a + i * ars + p * acs` (rows past the tile's `mr` are never read: the kernel clamps them);
/// row `p` of the packed `B` micro-panel is the `NR` contiguous floats at `b + p * NR`.
#[derive(Clone, Copy)]
struct Panels {
    a: *const f32,
    ars: isize,
    acs: isize,
    b: *const f32,
}

/// The destination tile: `mr x nr` at `c` with strides `rsc`, `csc`, updated as
/// `C = alpha * AB + beta * C`.
#[derive(Clone, Copy)]
struct Tile {
    c: *mut f32,
    rsc: isize,
    csc: isize,
    mr: usize,
    nr: usize,
    alpha: f32,
    beta: f32,
}

/// Kept out of line so that the hot loops sit in a function entered once per product: V8
/// switches a wasm function to its optimised tier only between calls (no on-stack
/// replacement), so they must not end up inlined into a long-running caller.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
unsafe fn blocked(
    kernel: Kernel,
    m: usize,
    k: usize,
    n: usize,
    alpha: f32,
    a: *const f32,
    rsa: isize,
    csa: isize,
    b: *const f32,
    rsb: isize,
    csb: isize,
    beta: f32,
    c: *mut f32,
    rsc: isize,
    csc: isize,
    ap: &mut Vec<f32>,
    bp: &mut Vec<f32>,
) {
    // A is only ever read by scalar broadcasts, so it is read in place when its rows are
    // contiguous (each step then touches MR cache lines, sequentially), saving a pass over it
    // (the attention probabilities). B is always packed: reading it in place was slower in
    // V8 (cache-set conflicts at power-of-two row strides), and packing it is cheap.
    let direct_a = csa == 1;
    let kc_max = k.min(KC);
    let ap_len = if direct_a { 0 } else { kc_max * round_up(m.min(MC), MR) };
    let bp_len = kc_max * round_up(n.min(NC), NR);
    if ap.len() < ap_len {
        ap.resize(ap_len, 0.0);
    }
    if bp.len() < bp_len {
        bp.resize(bp_len, 0.0);
    }
    for jc in (0..n).step_by(NC) {
        let nc = NC.min(n - jc);
        for pc in (0..k).step_by(KC) {
            let kc = KC.min(k - pc);
            pack_b(kc, nc, b.offset(pc as isize * rsb + jc as isize * csb), rsb, csb, bp);
            let beta_p = if pc == 0 { beta } else { 1.0 };
            for ic in (0..m).step_by(MC) {
                let mc = MC.min(m - ic);
                let a_blk = a.offset(ic as isize * rsa + pc as isize * csa);
                if !direct_a {
                    pack_a(mc, kc, a_blk, rsa, csa, ap);
                }
                for jr in (0..nc).step_by(NR) {
                    let nr = NR.min(nc - jr);
                    let bpanel = bp.as_ptr().add(jr * kc);
                    for ir in (0..mc).step_by(MR) {
                        let (apanel, ars, acs) = if direct_a {
                            (a_blk.offset(ir as isize * rsa), rsa, csa)
                        } else {
                            (ap.as_ptr().add(ir * kc), 1, MR as isize)
                        };
                        let panels = Panels { a: apanel, ars, acs, b: bpanel };
                        let tile = Tile {
                            c: c.offset((ic + ir) as isize * rsc + (jc + jr) as isize * csc),
                            rsc,
                            csc,
                            mr: MR.min(mc - ir),
                            nr,
                            alpha,
                            beta: beta_p,
                        };
                        match kernel {
                            #[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
                            Kernel::Simd128 => simd128::kernel(kc, panels, tile),
                            _ => portable_kernel(kc, panels, tile),
                        }
                    }
                }
            }
        }
    }
}

fn round_up(x: usize, to: usize) -> usize {
    x.div_ceil(to) * to
}

/// Packs `A[0..mc, 0..kc]` as consecutive `MR x kc` micro-panels, each stored `[kc][MR]`
/// (rows past `mc` zero-padded).
unsafe fn pack_a(mc: usize, kc: usize, a: *const f32, rsa: isize, csa: isize, ap: &mut [f32]) {
    let mut out = ap.as_mut_ptr();
    for ir in (0..mc).step_by(MR) {
        let mr = MR.min(mc - ir);
        let a = a.offset(ir as isize * rsa);
        for p in 0..kc {
            let col = a.offset(p as isize * csa);
            for i in 0..MR {
                *out.add(i) = if i < mr { *col.offset(i as isize * rsa) } else { 0.0 };
            }
            out = out.add(MR);
        }
    }
}

/// Packs `B[0..kc, 0..nc]` as consecutive `kc x NR` micro-panels, each stored `[kc][NR]`
/// (columns past `nc` zero-padded).
unsafe fn pack_b(kc: usize, nc: usize, b: *const f32, rsb: isize, csb: isize, bp: &mut [f32]) {
    let mut out = bp.as_mut_ptr();
    for jr in (0..nc).step_by(NR) {
        let nr = NR.min(nc - jr);
        let b = b.offset(jr as isize * csb);
        if nr == NR && csb == 1 {
            for p in 0..kc {
                std::ptr::copy_nonoverlapping(b.offset(p as isize * rsb), out, NR);
                out = out.add(NR);
            }
        } else if nr == NR && rsb == 1 {
            // B^T stored row-major (a Linear weight): walk each source row contiguously.
            for j in 0..NR {
                let col = b.offset(j as isize * csb);
                for p in 0..kc {
                    *out.add(p * NR + j) = *col.add(p);
                }
            }
            out = out.add(kc * NR);
        } else {
            for p in 0..kc {
                let row = b.offset(p as isize * rsb);
                for j in 0..NR {
                    *out.add(j) = if j < nr { *row.offset(j as isize * csb) } else { 0.0 };
                }
                out = out.add(NR);
            }
        }
    }
}

/// Writes an `MR x NR` accumulator tile (only its `mr x nr` corner) to C:
/// `C = alpha * acc + beta * C`, not reading C when `beta == 0`.
#[inline(always)]
unsafe fn store_tile(acc: &[[f32; NR]; MR], t: Tile) {
    for (i, row) in acc.iter().enumerate().take(t.mr) {
        let ci = t.c.offset(i as isize * t.rsc);
        for (j, v) in row.iter().enumerate().take(t.nr) {
            let p = ci.offset(j as isize * t.csc);
            *p = if t.beta == 0.0 { t.alpha * v } else { t.alpha * v + t.beta * *p };
        }
    }
}

/// Portable `MR x NR` micro-kernel.
unsafe fn portable_kernel(kc: usize, p: Panels, t: Tile) {
    let mut acc = [[0.0f32; NR]; MR];
    let rows: [*const f32; MR] = std::array::from_fn(|i| p.a.offset(i.min(t.mr - 1) as isize * p.ars));
    for s in 0..kc {
        let b = std::slice::from_raw_parts(p.b.add(s * NR), NR);
        for (row, ai) in acc.iter_mut().zip(rows) {
            let ai = *ai.offset(s as isize * p.acs);
            for (v, &bj) in row.iter_mut().zip(b) {
                *v += ai * bj;
            }
        }
    }
    store_tile(&acc, t);
}

#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod simd128 {
    use super::{store_tile, Panels, Tile, MR, NR};
    use core::arch::wasm32::*;

    /// `MR x 8` simd128 micro-kernel: `2 MR` accumulators (MR rows x 2 vectors); per step two
    /// vector loads of B, MR broadcast loads of A, `2 MR` multiplies and adds. Packed A is
    /// addressed through one pointer, in-place A (`acs == 1`) through one pointer per row.
    /// Not unrolled: V8 spilled the unrolled versions (4x8 was also the fastest tile there;
    /// 5x8, 6x8 and 8x8 spill).
    #[inline(always)]
    pub(super) unsafe fn kernel(kc: usize, p: Panels, t: Tile) {
        const _: () = assert!(NR == 8);
        if p.ars == 1 && p.acs == MR as isize {
            kernel_impl::<true>(kc, p, t)
        } else {
            kernel_impl::<false>(kc, p, t)
        }
    }

    #[inline(always)]
    unsafe fn kernel_impl<const AP: bool>(kc: usize, p: Panels, t: Tile) {
        debug_assert!(AP || p.acs == 1);
        let z = f32x4_splat(0.0);
        let mut acc = [[z; 2]; MR];
        let last = t.mr as isize - 1;
        // Packed A: one pointer, element (i, s) at a + s * MR + i. In place: row pointers
        // (rows past mr repeat the last valid one; their results are discarded).
        let mut a: [*const f32; MR] =
            core::array::from_fn(|i| if AP { p.a } else { p.a.offset((i as isize).min(last) * p.ars) });
        let mut b = p.b;
        for _ in 0..kc {
            let b0 = v128_load(b as *const v128);
            let b1 = v128_load(b.add(4) as *const v128);
            for (i, row) in acc.iter_mut().enumerate() {
                let x = v128_load32_splat((if AP { a[0].add(i) } else { a[i] }) as *const u32);
                row[0] = f32x4_add(row[0], f32x4_mul(x, b0));
                row[1] = f32x4_add(row[1], f32x4_mul(x, b1));
            }
            for ai in a.iter_mut() {
                *ai = ai.add(if AP { MR } else { 1 });
            }
            b = b.add(NR);
        }

        if t.mr == MR && t.nr == NR && t.csc == 1 {
            let va = f32x4_splat(t.alpha);
            let vb = f32x4_splat(t.beta);
            for (i, [x0, x1]) in acc.into_iter().enumerate() {
                let ci = t.c.offset(i as isize * t.rsc);
                let (mut y0, mut y1) = (f32x4_mul(va, x0), f32x4_mul(va, x1));
                if t.beta != 0.0 {
                    y0 = f32x4_add(y0, f32x4_mul(vb, v128_load(ci as *const v128)));
                    y1 = f32x4_add(y1, f32x4_mul(vb, v128_load(ci.add(4) as *const v128)));
                }
                v128_store(ci as *mut v128, y0);
                v128_store(ci.add(4) as *mut v128, y1);
            }
        } else {
            let mut tile = [[0.0f32; NR]; MR];
            for (row, [x0, x1]) in tile.iter_mut().zip(acc) {
                v128_store(row.as_mut_ptr() as *mut v128, x0);
                v128_store(row.as_mut_ptr().add(4) as *mut v128, x1);
            }
            store_tile(&tile, t);
        }
    }
}
