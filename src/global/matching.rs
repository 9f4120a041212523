//! Correspondences between two clouds' descriptors: nearest neighbours in descriptor space,
//! kept when they are mutual (A's nearest is B and B's nearest is A), which removes most wrong
//! matches cheaply.
//!
//! Brute force: the clouds given here are voxelised to at most [`super::MAX_FEATURE_POINTS`]
//! points ([`super::DENSE_FEATURE_POINTS`] on dense scans), so `n_s * n_t * 33` multiply-adds
//! bound the cost, and a k-d tree in 33 dimensions would prune little.

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
                let d = dist2(x, y);
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
/// weak matching beats none). One pass over the distance matrix finds both directions' nearest.
pub fn mutual_matches(source: &[Descriptor], target: &[Descriptor], min_mutual: usize) -> Vec<(u32, u32)> {
    if source.is_empty() || target.is_empty() {
        return Vec::new();
    }
    let mut row = vec![(0u32, f32::INFINITY); source.len()];
    let mut col = vec![(0u32, f32::INFINITY); target.len()];
    for (i, x) in source.iter().enumerate() {
        for (j, y) in target.iter().enumerate() {
            let d = dist2(x, y);
            if d < row[i].1 {
                row[i] = (j as u32, d);
            }
            if d < col[j].1 {
                col[j] = (i as u32, d);
            }
        }
    }
    let mutual: Vec<(u32, u32)> = row
        .iter()
        .enumerate()
        .filter(|&(i, &(j, _))| col[j as usize].0 == i as u32)
        .map(|(i, &(j, _))| (i as u32, j))
        .collect();
    if mutual.len() >= min_mutual {
        mutual
    } else {
        row.iter().enumerate().map(|(i, &(j, _))| (i as u32, j)).collect()
    }
}

/// Squared Euclidean distance of two descriptors, in eight independent lanes (so it vectorises).
#[inline(always)]
fn dist2(x: &Descriptor, y: &Descriptor) -> f32 {
    const LANES: usize = 8;
    let mut acc = [0.0f32; LANES];
    for k in 0..DIM / LANES {
        for l in 0..LANES {
            let e = x[k * LANES + l] - y[k * LANES + l];
            acc[l] += e * e;
        }
    }
    let mut d = acc.iter().sum::<f32>();
    for k in (DIM / LANES) * LANES..DIM {
        let e = x[k] - y[k];
        d += e * e;
    }
    d
}
