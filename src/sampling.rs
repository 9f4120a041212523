//! Deterministic downsampling: to the network's N points, and voxel grids for ICP.

use crate::cloud::PointCloud;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// The hash of [`voxel_downsample`]'s grid keys: a multiply-rotate mix per word and a 64-bit
/// finaliser (MurmurHash3's), several times faster than the default SipHash on the millions of
/// lookups of a large cloud. Keys come from the caller's coordinates, so a crafted cloud could make
/// many collide; that costs time only, never a different result.
#[derive(Default)]
pub(crate) struct VoxelKeyHasher(u64);

/// A map from voxel grid keys to slots, hashed by [`VoxelKeyHasher`].
pub(crate) type VoxelKeys = HashMap<[i64; 3], u32, BuildHasherDefault<VoxelKeyHasher>>;

impl Hasher for VoxelKeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        // `[i64; 3]` hashes its 24 bytes in one call: three words
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.write_u64(u64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]));
        }
        for b in words.remainder() {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(23) ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
        h ^= h >> 33;
        h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
        h ^ (h >> 33)
    }
}

/// The crate's seeded random generator (ChaCha8): the same seed gives the same stream on every
/// platform, native and wasm32.
pub fn rng(seed: u64) -> ChaCha8Rng {
    use rand::SeedableRng;
    ChaCha8Rng::seed_from_u64(seed)
}

/// The target cloud's network sample uses `seed ^ TARGET_SEED_XOR` (the source uses `seed`), so the
/// two clouds get independent draws. The trainer uses the same rule, so training inputs match
/// inference inputs.
pub const TARGET_SEED_XOR: u64 = 0x5EED_7A26_E7C0_FFEE;

/// Voxel-grid downsampling: one point per occupied cube of side `voxel` (the centroid of the
/// points in it), in a deterministic order. `voxel <= 0` returns a copy.
///
/// * Voxel keys are `floor(x / voxel)` per axis, computed in `f64` and converted to `i64` with
///   saturation, so huge coordinate ranges (or tiny voxels) cannot overflow; at worst far-apart
///   points beyond `+-9.2e18` voxels share an edge voxel.
/// * Centroids are accumulated in `f64`.
/// * Output order: ascending voxel key `(x, y, z)` lexicographically. It depends only on the
///   input points (not on their order, up to floating-point summation order within a voxel),
///   and keeps neighbouring voxels close in memory.
/// * Points with a NaN or infinite coordinate are dropped (validation normally removed them).
/// * `voxel` not finite or `<= 0`: a copy of the cloud, unchanged.
/// * The grid is laid on the cloud's offsets (relative to its origin), and the result keeps the
///   origin.
pub fn voxel_downsample(cloud: &PointCloud, voxel: f32) -> PointCloud {
    let points = voxel_downsample_points(&cloud.points, voxel);
    PointCloud::with_origin(points, cloud.origin)
}

/// [`voxel_downsample`] of bare points (relative to any origin), without a cloud around them.
pub(crate) fn voxel_downsample_points(points: &[[f32; 3]], voxel: f32) -> Vec<[f32; 3]> {
    // without a cap on the voxels there is always an answer
    grid::<false>(points, &crate::cloud::bounds_of(points), voxel, usize::MAX).unwrap_or_default()
}

/// [`voxel_downsample`] when it gives at most `max` points (the same cloud, bit for bit); `None`
/// as soon as the points met so far occupy more than `max` voxels, without reading the rest (for
/// a search of the voxel size that fits a budget, `crate::global::feature_voxels`).
pub fn voxel_downsample_at_most(cloud: &PointCloud, voxel: f32, max: usize) -> Option<PointCloud> {
    voxel_downsample_at_most_in(cloud, &cloud.bounds(), voxel, max)
}

/// [`voxel_downsample_at_most`] with the cloud's [`PointCloud::bounds`] given, for a caller that
/// tries several voxel sizes on one cloud (the bounds are a pass over every point, where a size
/// that does not fit may stop after a few).
pub(crate) fn voxel_downsample_at_most_in(
    cloud: &PointCloud,
    bounds: &([f32; 3], [f32; 3]),
    voxel: f32,
    max: usize,
) -> Option<PointCloud> {
    grid::<true>(&cloud.points, bounds, voxel, max).map(|points| PointCloud::with_origin(points, cloud.origin))
}

/// [`voxel_downsample`] of `points`, whose bounds ([`PointCloud::bounds`]) are `bounds`, giving
/// up past `max` voxels only when `CAPPED` (the uncapped loop has no check at all).
fn grid<const CAPPED: bool>(
    points: &[[f32; 3]],
    bounds: &([f32; 3], [f32; 3]),
    voxel: f32,
    max: usize,
) -> Option<Vec<[f32; 3]>> {
    if !(voxel.is_finite() && voxel > 0.0) {
        return (points.len() <= max).then(|| points.to_vec());
    }
    let inv = 1.0 / voxel as f64;
    // `as i64` saturates (and a finite f64 floor is never NaN).
    let key_of = |p: &[f32; 3]| p.map(|v| (v as f64 * inv).floor() as i64);
    // One accumulator per occupied voxel, in the order first met; then sorted by key. Only the
    // occupied voxels are sorted (not every point), and each voxel's sum runs in input order.
    // The keys live apart from the sums: the loop reads and writes a voxel's sums at random (the
    // points are in any order), and a 32-byte, 32-aligned accumulator is one cache line where a
    // record with its key straddled two most of the time.
    let mut slots = Slots::new(points.len(), bounds, &key_of);
    let mut keys: Vec<[i64; 3]> = Vec::new();
    let mut sums: Vec<VoxelSum> = Vec::new();
    for p in points.iter().filter(|p| p.iter().all(|v| v.is_finite())) {
        let key = key_of(p);
        let slot = slots.slot(key, || {
            keys.push(key);
            sums.push(VoxelSum::default());
            (sums.len() - 1) as u32
        });
        if CAPPED && sums.len() > max {
            return None;
        }
        let v = &mut sums[slot as usize];
        for (sum, &x) in v.sum.iter_mut().zip(p) {
            *sum += x as f64;
        }
        v.count += 1;
    }
    drop(slots);
    // keys are unique, so the unstable sort is deterministic
    let mut order: Vec<([i64; 3], u32)> = keys.into_iter().zip(0u32..).collect();
    order.sort_unstable_by_key(|v| v.0);
    let out = order
        .iter()
        .map(|&(_, slot)| {
            let VoxelSum { sum: s, count } = sums[slot as usize];
            let n = count as f64;
            [(s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32]
        })
        .collect();
    Some(out)
}

/// One voxel's running sum of its points' coordinates and their count ([`voxel_downsample`]'s
/// grid), aligned so that it never straddles a cache line.
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
struct VoxelSum {
    sum: [f64; 3],
    count: u32,
}

/// Most cells of a dense voxel table ([`Slots`]): 16 MiB of slots.
const DENSE_MAX_CELLS: usize = 1 << 22;

/// A dense table may have at most this many cells per point of the cloud (plus a few thousand),
/// so that its memory follows the cloud's, like the hashed table's.
const DENSE_CELLS_PER_POINT: usize = 4;

/// Where each voxel's accumulator is: a dense table over the box of the cloud's voxel keys when
/// that box is small enough ([`DENSE_MAX_CELLS`], [`DENSE_CELLS_PER_POINT`]; a normalised cloud
/// at ICP's voxel), a direct index instead of a hash per point; else a hash map. Either gives
/// the same slots in the same order, so the same output.
enum Slots {
    Dense { lo: [i64; 3], dims: [usize; 3], slot: Vec<u32> },
    Hashed(VoxelKeys),
}

impl Slots {
    /// Slots for the voxel keys (`key_of`) of a cloud of `points` points within `bounds`: the key
    /// of every point lies in the box of the keys of the bounds, as the key grows with each
    /// coordinate.
    fn new(points: usize, bounds: &([f32; 3], [f32; 3]), key_of: &impl Fn(&[f32; 3]) -> [i64; 3]) -> Self {
        let (lo, hi) = *bounds;
        let (klo, khi) = (key_of(&lo), key_of(&hi));
        let cap = DENSE_MAX_CELLS.min(points.saturating_mul(DENSE_CELLS_PER_POINT).saturating_add(4096));
        let mut dims = [0usize; 3];
        let mut cells = 1usize;
        for a in 0..3 {
            let n = khi[a].checked_sub(klo[a]).and_then(|d| d.checked_add(1)).and_then(|d| usize::try_from(d).ok());
            match n.and_then(|n| Some((n, cells.checked_mul(n)?))) {
                Some((n, c)) if c <= cap && lo[a].is_finite() && hi[a].is_finite() => (dims[a], cells) = (n, c),
                _ => return Slots::Hashed(HashMap::default()),
            }
        }
        Slots::Dense { lo: klo, dims, slot: vec![u32::MAX; cells] }
    }

    /// The slot of `key`, made by `new_slot` on its first use.
    #[inline(always)]
    fn slot(&mut self, key: [i64; 3], new_slot: impl FnOnce() -> u32) -> u32 {
        match self {
            Slots::Dense { lo, dims, slot } => {
                let at = |a: usize| (key[a] - lo[a]) as usize;
                let s = &mut slot[(at(0) * dims[1] + at(1)) * dims[2] + at(2)];
                if *s == u32::MAX {
                    *s = new_slot();
                }
                *s
            }
            Slots::Hashed(map) => *map.entry(key).or_insert_with(new_slot),
        }
    }
}

/// Draws exactly `n` points for the network, deterministically for a seed.
///
/// **Rule** (the same on every platform, native and wasm32):
/// * If the cloud has at least `n` points: `n` distinct indices drawn uniformly **without
///   replacement** by a partial Fisher-Yates shuffle driven by [`rng`]`(seed)`, kept in the
///   order drawn. Step `i` (0-based) draws `j` uniformly in `i..len` (a `u64` range) and swaps
///   positions `i` and `j` of the virtual index array `0..len`. This matches the training
///   protocol's independent uniform resampling of each cloud.
/// * If it has fewer (but at least one): all points in their original order, then
///   `n - len` more drawn uniformly **with replacement** (indices in `0..len`, same generator).
/// * An empty cloud gives an empty cloud (there is nothing to pad with); `n == 0` too.
///
/// No density equalisation is done here (decided, not measured for accuracy): the network was
/// trained on uniform random subsets of uniformly sampled surfaces, so that is what it is fed,
/// and equalising needs a voxel size that is a choice of its own. It does matter for LiDAR:
/// in the small_gicp Velodyne scan, 70% of the 69,792 points lie within 5 m (horizontally) of
/// the sensor, against 17% of the points left by a 0.5 m voxel grid; uniform sampling thus
/// spends most of the network's points on the near-field rings. A caller with such scans can
/// equalise first, `network_sample(&voxel_downsample(c, v), n, seed)`, with `v` small enough to
/// keep well over `n` voxels.
pub fn network_sample(cloud: &PointCloud, n: usize, seed: u64) -> PointCloud {
    let len = cloud.points.len();
    if len == 0 || n == 0 {
        return PointCloud::default();
    }
    let mut r = rng(seed);
    let mut out = Vec::with_capacity(n);
    if len >= n {
        // Sparse partial Fisher-Yates: `moved[k]` holds the index now at virtual position k
        // (absent = k itself). O(n) time and memory whatever `len` is.
        let mut moved: HashMap<u64, u64> = HashMap::with_capacity(n);
        let len = len as u64;
        for i in 0..n as u64 {
            let j = r.random_range(i..len);
            let at_i = moved.get(&i).copied().unwrap_or(i);
            let at_j = moved.get(&j).copied().unwrap_or(j);
            moved.insert(j, at_i);
            out.push(cloud.points[at_j as usize]);
        }
    } else {
        out.extend_from_slice(&cloud.points);
        for _ in len..n {
            let j = r.random_range(0..len as u64);
            out.push(cloud.points[j as usize]);
        }
    }
    PointCloud::with_origin(out, cloud.origin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_grid_merges_and_orders() {
        let c = PointCloud::new(vec![[0.1, 0.1, 0.1], [5.0, 0.0, 0.0], [0.3, 0.3, 0.3], [-0.5, 0.0, 0.0]]);
        let v = voxel_downsample(&c, 1.0);
        assert_eq!(v.points, vec![[-0.5, 0.0, 0.0], [0.2, 0.2, 0.2], [5.0, 0.0, 0.0]]);
        assert_eq!(voxel_downsample(&c, 0.0), c);
        assert_eq!(voxel_downsample(&c, f32::NAN), c);
        assert_eq!(voxel_downsample(&c, -1.0), c);
    }

    #[test]
    fn huge_coordinates_do_not_overflow() {
        let c = PointCloud::new(vec![[3e38, -3e38, 0.0], [1.0, 1.0, 1.0], [3e38, -3e38, 0.0]]);
        let v = voxel_downsample(&c, 1e-30);
        assert_eq!(v.len(), 2);
        assert!(v.points.iter().flatten().all(|x| x.is_finite()));
    }

    #[test]
    fn padding_keeps_all_then_repeats() {
        let c = PointCloud::new((0..10).map(|i| [i as f32, 0.0, 0.0]).collect());
        let s = network_sample(&c, 25, 3);
        assert_eq!(s.len(), 25);
        assert_eq!(&s.points[..10], &c.points[..]);
        assert!(network_sample(&PointCloud::default(), 5, 0).is_empty());
    }
}
