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
/// weak matching beats none). One pass over the distance matrix finds both directions' nearest
/// (ties to the lower index, as [`nearest_each`]).
///
/// The target descriptors are read four at a time, transposed, so that one source descriptor's
/// distances to them are computed lane by lane in vector registers: each distance with the same
/// operations in the same order as one computed alone, so the same value.
pub fn mutual_matches(source: &[Descriptor], target: &[Descriptor], min_mutual: usize) -> Vec<(u32, u32)> {
    nearest_and_mutual(source, target, min_mutual).1
}

/// Every source descriptor's nearest target descriptor `(source index, target index)`, in source
/// order (as [`nearest_each`]), and [`mutual_matches`] among them, from one pass over the distance
/// matrix.
#[allow(clippy::type_complexity)]
pub fn nearest_and_mutual(
    source: &[Descriptor],
    target: &[Descriptor],
    min_mutual: usize,
) -> (Vec<(u32, u32)>, Vec<(u32, u32)>) {
    if source.is_empty() || target.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let groups = transpose(target);
    let mut row = vec![(0u32, f32::INFINITY); source.len()];
    // each target's nearest source so far, distance and index apart (the update vectorises)
    let mut col_d = vec![f32::INFINITY; groups.len() * GROUP];
    let mut col_i = vec![0u32; groups.len() * GROUP];
    for (i, x) in source.iter().enumerate() {
        // this source's nearest per lane: the lowest index at the lane's least distance
        let mut lane_d = [f32::INFINITY; GROUP];
        let mut lane_j = [0u32; GROUP];
        for (g, group) in groups.iter().enumerate() {
            let d = group_dist2(x, group);
            let base = g * GROUP;
            for w in 0..GROUP {
                let closer = d[w] < lane_d[w];
                lane_d[w] = if closer { d[w] } else { lane_d[w] };
                lane_j[w] = if closer { (base + w) as u32 } else { lane_j[w] };
            }
            let (cd, ci) = (&mut col_d[base..base + GROUP], &mut col_i[base..base + GROUP]);
            for w in 0..GROUP {
                let closer = d[w] < cd[w];
                cd[w] = if closer { d[w] } else { cd[w] };
                ci[w] = if closer { i as u32 } else { ci[w] };
            }
        }
        // the lanes' nearest, by distance, then index: the first nearest in target order
        for w in 0..GROUP {
            let (d, j) = (lane_d[w], lane_j[w]);
            if d < row[i].1 || (d == row[i].1 && d < f32::INFINITY && j < row[i].0) {
                row[i] = (j, d);
            }
        }
    }
    let nearest = row.iter().enumerate().map(|(i, &(j, _))| (i as u32, j)).collect();
    (nearest, keep_mutual(&row, |j| col_i[j as usize], min_mutual))
}

/// The pairs `(i, row[i])` whose target's nearest source (`nearest_source`) is `i` again, or
/// every pair when fewer than `min_mutual` are.
fn keep_mutual(row: &[(u32, f32)], nearest_source: impl Fn(u32) -> u32, min_mutual: usize) -> Vec<(u32, u32)> {
    let mutual: Vec<(u32, u32)> = row
        .iter()
        .enumerate()
        .filter(|&(i, &(j, _))| nearest_source(j) == i as u32)
        .map(|(i, &(j, _))| (i as u32, j))
        .collect();
    if mutual.len() >= min_mutual {
        mutual
    } else {
        row.iter().enumerate().map(|(i, &(j, _))| (i as u32, j)).collect()
    }
}

/// How many target descriptors [`mutual_matches`] compares with a source descriptor at once.
const GROUP: usize = 4;

/// The partial sums of a descriptor distance (one per lane of eight bins; [`dist2`] and
/// [`group_dist2`] add the same ones in the same order).
const LANES: usize = 8;

/// Descriptors `GROUP` at a time, transposed (`[bin][lane]`); the last group padded with
/// infinite descriptors, whose distances are infinite and so never nearest.
fn transpose(descriptors: &[Descriptor]) -> Vec<[[f32; GROUP]; DIM]> {
    descriptors
        .chunks(GROUP)
        .map(|chunk| {
            let mut group = [[f32::INFINITY; GROUP]; DIM];
            for (w, d) in chunk.iter().enumerate() {
                for (k, bin) in group.iter_mut().enumerate() {
                    bin[w] = d[k];
                }
            }
            group
        })
        .collect()
}

/// [`dist2`] of `x` to each descriptor of a transposed group: per lane the same eight partial
/// sums, added in the same order.
#[inline(always)]
fn group_dist2(x: &Descriptor, group: &[[f32; GROUP]; DIM]) -> [f32; GROUP] {
    let mut acc = [[0.0f32; GROUP]; LANES];
    for k in 0..DIM / LANES {
        for (l, a) in acc.iter_mut().enumerate() {
            let xk = x[k * LANES + l];
            let y = &group[k * LANES + l];
            for w in 0..GROUP {
                let e = xk - y[w];
                a[w] += e * e;
            }
        }
    }
    let mut d = [0.0f32; GROUP];
    for a in &acc {
        for w in 0..GROUP {
            d[w] += a[w];
        }
    }
    for k in (DIM / LANES) * LANES..DIM {
        let xk = x[k];
        for w in 0..GROUP {
            let e = xk - group[k][w];
            d[w] += e * e;
        }
    }
    d
}

/// Squared Euclidean distance of two descriptors, in eight independent lanes (so it vectorises).
#[inline(always)]
fn dist2(x: &Descriptor, y: &Descriptor) -> f32 {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition: every pair's [`dist2`] in source-then-target order, the first nearest kept.
    fn reference(source: &[Descriptor], target: &[Descriptor], min_mutual: usize) -> Vec<(u32, u32)> {
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
        keep_mutual(&row, |j| col[j as usize].0, min_mutual)
    }

    /// `n` descriptors with bins drawn from a few values (so that distances tie often).
    fn descriptors(n: usize, seed: u64) -> Vec<Descriptor> {
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (0..n)
            .map(|_| {
                [0.0f32; DIM].map(|_| {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    ((state >> 33) % 4) as f32 * 12.5
                })
            })
            .collect()
    }

    #[test]
    fn the_grouped_pass_matches_the_definition_with_ties_and_ragged_groups() {
        for (n_s, n_t, seed) in [(1, 1, 1), (5, 3, 2), (40, 8, 3), (37, 61, 4), (120, 97, 5), (9, 200, 6)] {
            let (s, t) = (descriptors(n_s, seed), descriptors(n_t, seed + 100));
            for min_mutual in [0, n_s.min(n_t) + 1] {
                assert_eq!(mutual_matches(&s, &t, min_mutual), reference(&s, &t, min_mutual), "{n_s} x {n_t}");
            }
            // every descriptor equal to every other: all ties, the lowest indices win
            let same = vec![[1.0f32; DIM]; n_t];
            assert_eq!(mutual_matches(&s[..1], &same, 0), reference(&s[..1], &same, 0));
        }
    }
}
