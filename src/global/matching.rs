//! Correspondences between two clouds' descriptors: nearest neighbours in descriptor space,
//! kept when they are mutual (A's nearest is B and B's nearest is A), which removes most wrong
//! matches cheaply.
//!
//! Brute force: the clouds given here are voxelised to at most
//! [`super::MAX_FEATURE_POINTS`] points, so `n_s * n_t * 33` multiply-adds bound the cost, and a
//! k-d tree in 33 dimensions would prune little.

use super::fpfh::{Descriptor, DIM};

/// For each descriptor of `a`, the index of its nearest descriptor in `b` (squared Euclidean
/// distance; ties to the lower index). Empty `b`: an empty list.
pub fn nearest_each(a: &[Descriptor], b: &[Descriptor]) -> Vec<u32> {
    if b.is_empty() {
        return Vec::new();
    }
    a.iter()
        .map(|x| {
            let mut best = (0u32, f32::INFINITY);
            for (j, y) in b.iter().enumerate() {
                let mut d = 0.0f32;
                for k in 0..DIM {
                    let e = x[k] - y[k];
                    d += e * e;
                }
                if d < best.1 {
                    best = (j as u32, d);
                }
            }
            best.0
        })
        .collect()
}

/// Mutual nearest neighbours `(source index, target index)`, in source order. When fewer than
/// `min_mutual` pairs are mutual, every source point's nearest target is returned instead (a
/// weak matching beats none).
pub fn mutual_matches(source: &[Descriptor], target: &[Descriptor], min_mutual: usize) -> Vec<(u32, u32)> {
    let st = nearest_each(source, target);
    let ts = nearest_each(target, source);
    let mutual: Vec<(u32, u32)> =
        st.iter().enumerate().filter(|&(i, &j)| ts[j as usize] == i as u32).map(|(i, &j)| (i as u32, j)).collect();
    if mutual.len() >= min_mutual {
        mutual
    } else {
        st.iter().enumerate().map(|(i, &j)| (i as u32, j)).collect()
    }
}
