//! Four points stored coordinate by coordinate, and the leaf scans over them: four squared
//! distances at a time, in WebAssembly's 128-bit SIMD where the build has it (`simd128`, on by
//! default in this crate's `.cargo/config.toml`) and in plain Rust elsewhere (which the compiler
//! vectorises natively). Both compute each distance as `dx * dx + dy * dy + dz * dz` in `f32`,
//! in that order, so they give the same answers bit for bit.
//!
//! A padding lane holds NaN coordinates: its distance is NaN, which is below no bound and
//! recorded in no floor.

/// Four points' x, y and z.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Chunk {
    x: [f32; 4],
    y: [f32; 4],
    z: [f32; 4],
}

impl Chunk {
    /// Four padding lanes.
    pub(super) const PADDING: Chunk = Chunk { x: [f32::NAN; 4], y: [f32::NAN; 4], z: [f32::NAN; 4] };

    /// Stores `p` in lane `l`.
    pub(super) fn set(&mut self, l: usize, p: &[f32; 3]) {
        (self.x[l], self.y[l], self.z[l]) = (p[0], p[1], p[2]);
    }

    /// The point in lane `l`.
    #[inline(always)]
    pub(super) fn get(&self, l: usize) -> [f32; 3] {
        [self.x[l], self.y[l], self.z[l]]
    }
}

/// The two least distances recorded in each lane by [`nearest`] (the k-d tree's floors, merged
/// with the rest when a search ends).
#[derive(Clone, Copy)]
pub(super) struct LaneFloors {
    pub(super) least: [f32; 4],
    pub(super) second: [f32; 4],
}

impl LaneFloors {
    /// Nothing recorded.
    pub(super) const NONE: LaneFloors = LaneFloors { least: [f32::INFINITY; 4], second: [f32::INFINITY; 4] };
}

/// The squared distances from `q` to the chunk's four points.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
pub(super) fn distances(c: &Chunk, q: &[f32; 3]) -> [f32; 4] {
    std::array::from_fn(|l| {
        let (dx, dy, dz) = (c.x[l] - q[0], c.y[l] - q[1], c.z[l] - q[2]);
        dx * dx + dy * dy + dz * dz
    })
}

/// [`distances`] in WebAssembly's SIMD (the compiler's own vectors of the plain loop build each
/// lane apart, slower than scalar code).
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
#[inline(always)]
pub(super) fn distances(c: &Chunk, q: &[f32; 3]) -> [f32; 4] {
    use core::arch::wasm32::*;
    let d2 = simd::distances(c, f32x4_splat(q[0]), f32x4_splat(q[1]), f32x4_splat(q[2]));
    simd::lanes(d2)
}

/// Scans `chunks` (positions `first..`) for points strictly nearer to `q` than `bound`: per lane,
/// the least such squared distance (else `bound`) and its position (the earliest among equals;
/// else `u32::MAX`). With `FLOOR`, every distance is recorded in `floors`.
#[cfg(not(all(target_arch = "wasm32", target_feature = "simd128")))]
#[inline(always)]
pub(super) fn nearest<const FLOOR: bool>(
    chunks: &[Chunk],
    first: u32,
    q: &[f32; 3],
    bound: f32,
    floors: &mut LaneFloors,
) -> ([f32; 4], [u32; 4]) {
    let mut least = [bound; 4];
    let mut at = [u32::MAX; 4];
    for (c, p) in chunks.iter().zip((first..).step_by(4)) {
        let d2 = distances(c, q);
        // selects, not branches (unpredictable); lane by lane, which the compiler vectorises
        for (l, &d) in d2.iter().enumerate() {
            let below = d < least[l];
            least[l] = if below { d } else { least[l] };
            at[l] = if below { p + l as u32 } else { at[l] };
        }
        if FLOOR {
            for (l, &d) in d2.iter().enumerate() {
                let below_least = d < floors.least[l];
                let second = if d < floors.second[l] { d } else { floors.second[l] };
                floors.second[l] = if below_least { floors.least[l] } else { second };
                floors.least[l] = if below_least { d } else { floors.least[l] };
            }
        }
    }
    (least, at)
}

/// [`nearest`] in WebAssembly's SIMD: the same arithmetic and selects, four lanes at once.
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
#[inline(always)]
pub(super) fn nearest<const FLOOR: bool>(
    chunks: &[Chunk],
    first: u32,
    q: &[f32; 3],
    bound: f32,
    floors: &mut LaneFloors,
) -> ([f32; 4], [u32; 4]) {
    use core::arch::wasm32::*;
    use simd::load;
    let (qx, qy, qz) = (f32x4_splat(q[0]), f32x4_splat(q[1]), f32x4_splat(q[2]));
    let mut least = f32x4_splat(bound);
    let mut at = u32x4_splat(u32::MAX);
    let mut position = u32x4(first, first + 1, first + 2, first + 3);
    let (mut floor_least, mut floor_second) = (load(&floors.least), load(&floors.second));
    for c in chunks {
        let d2 = simd::distances(c, qx, qy, qz);
        let below = f32x4_lt(d2, least);
        least = v128_bitselect(d2, least, below);
        at = v128_bitselect(position, at, below);
        position = u32x4_add(position, u32x4_splat(4));
        if FLOOR {
            // pmin(a, b) is `if b < a { b } else { a }`: a NaN (padding) `b` leaves `a`
            let below_least = f32x4_lt(d2, floor_least);
            floor_second = v128_bitselect(floor_least, f32x4_pmin(floor_second, d2), below_least);
            floor_least = f32x4_pmin(floor_least, d2);
        }
    }
    if FLOOR {
        (floors.least, floors.second) = (simd::lanes(floor_least), simd::lanes(floor_second));
    }
    (simd::lanes(least), simd::u32_lanes(at))
}

/// The SIMD pieces the scans share.
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
mod simd {
    use super::Chunk;
    use core::arch::wasm32::*;

    /// Four floats as a vector.
    #[inline(always)]
    pub(super) fn load(v: &[f32; 4]) -> v128 {
        f32x4(v[0], v[1], v[2], v[3])
    }

    /// The vector's four floats.
    #[inline(always)]
    pub(super) fn lanes(v: v128) -> [f32; 4] {
        [f32x4_extract_lane::<0>(v), f32x4_extract_lane::<1>(v), f32x4_extract_lane::<2>(v), f32x4_extract_lane::<3>(v)]
    }

    /// The vector's four `u32`s.
    #[inline(always)]
    pub(super) fn u32_lanes(v: v128) -> [u32; 4] {
        [u32x4_extract_lane::<0>(v), u32x4_extract_lane::<1>(v), u32x4_extract_lane::<2>(v), u32x4_extract_lane::<3>(v)]
    }

    /// The squared distances from `(qx, qy, qz)` (each splat) to the chunk's points:
    /// `dx * dx + dy * dy + dz * dz`, as the plain code computes them.
    #[inline(always)]
    pub(super) fn distances(c: &Chunk, qx: v128, qy: v128, qz: v128) -> v128 {
        let dx = f32x4_sub(load(&c.x), qx);
        let dy = f32x4_sub(load(&c.y), qy);
        let dz = f32x4_sub(load(&c.z), qz);
        f32x4_add(f32x4_add(f32x4_mul(dx, dx), f32x4_mul(dy, dy)), f32x4_mul(dz, dz))
    }
}
