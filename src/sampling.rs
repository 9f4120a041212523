//! Deterministic downsampling: to the network's N points, and voxel grids for ICP.

use crate::cloud::PointCloud;
use rand_chacha::ChaCha8Rng;

/// The crate's seeded random generator (ChaCha8): the same seed gives the same stream on every
/// platform, native and wasm32.
pub fn rng(seed: u64) -> ChaCha8Rng {
    use rand::SeedableRng;
    ChaCha8Rng::seed_from_u64(seed)
}

/// Voxel-grid downsampling: one point per occupied cube of side `voxel` (the centroid of the
/// points in it), in a deterministic order. `voxel <= 0` returns a copy.
pub fn voxel_downsample(cloud: &PointCloud, voxel: f32) -> PointCloud {
    let _ = (cloud, voxel);
    todo!("helper: sampling")
}

/// Draws exactly `n` points for the network, deterministically for a seed (rule documented here
/// by the implementation).
pub fn network_sample(cloud: &PointCloud, n: usize, seed: u64) -> PointCloud {
    let _ = (cloud, n, seed);
    todo!("helper: sampling")
}
