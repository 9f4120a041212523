//! The translation that most descriptor matches agree on, for a given rotation.
//!
//! With the rotation `R` of a motion right, every right match `(p, q)` gives the motion's
//! translation as `q - R p`, and the wrong ones scatter: the densest cluster of those votes is the
//! translation. It puts back a pose whose rotation is right but whose translation is not (on scans
//! of rooms, a wall matched to the next one; ICP cannot slide that far), from every source point's
//! nearest descriptor, of which a few percent right are enough (`BENCHMARK.md`, "A slid answer put
//! back").

use nalgebra::{Matrix3, Vector3};

/// The densest cluster of the votes `q - R p` over `matches` (`(source index, target index)` into
/// `source` and `target`; a pair with an index out of range is left out): the vote with the most
/// votes within `radius` of it, and the mean of those, with how many they are. `None` without
/// votes, with a `radius` that is not positive, or when no vote is finite. Deterministic (ties to
/// the first vote in `matches`' order); the votes sorted into cells of side `radius`, each vote
/// compared with those of the 125 cells around its own (out to twice `radius`), so O(m log m)
/// for `m` votes spread evenly.
pub fn voted(
    source: &[[f32; 3]],
    target: &[[f32; 3]],
    matches: &[(u32, u32)],
    r: &Matrix3<f64>,
    radius: f64,
) -> Option<(Vector3<f64>, usize)> {
    modes(source, target, matches, r, radius, 1).into_iter().next()
}

/// Up to `count` clusters of the votes of [`voted`], densest first: the first is [`voted`]'s;
/// each next one the densest among the votes farther than twice `radius` from every cluster
/// before it (counting only those votes). A row of alike parts (two identical pipe spools side
/// by side, a facade's bays) gives a cluster per part the source matches.
pub fn modes(
    source: &[[f32; 3]],
    target: &[[f32; 3]],
    matches: &[(u32, u32)],
    r: &Matrix3<f64>,
    radius: f64,
    count: usize,
) -> Vec<(Vector3<f64>, usize)> {
    if radius.is_nan() || radius <= 0.0 {
        return Vec::new();
    }
    let v3 = |p: &[f32; 3]| Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
    let votes: Vec<Vector3<f64>> = matches
        .iter()
        .filter_map(|&(i, j)| Some(v3(target.get(j as usize)?) - r * v3(source.get(i as usize)?)))
        .collect();
    let cell = |v: &Vector3<f64>| -> [i64; 3] { [v.x, v.y, v.z].map(|x| (x / radius).floor() as i64) };
    // the votes sorted by cell, so that a cell's votes are found by a binary search
    let mut by_cell: Vec<([i64; 3], u32)> = votes.iter().enumerate().map(|(k, v)| (cell(v), k as u32)).collect();
    by_cell.sort_unstable();
    // calls `f` with each vote within `within` (at most twice `radius`) of `v`
    let each_near = |v: &Vector3<f64>, within: f64, f: &mut dyn FnMut(usize)| {
        let c = cell(v);
        for dx in -2..=2 {
            for dy in -2..=2 {
                for dz in -2..=2 {
                    let key = [c[0] + dx, c[1] + dy, c[2] + dz];
                    let start = by_cell.partition_point(|e| e.0 < key);
                    for &(_, k) in by_cell[start..].iter().take_while(|e| e.0 == key) {
                        if (votes[k as usize] - v).norm() < within {
                            f(k as usize);
                        }
                    }
                }
            }
        }
    };
    // the votes a cluster found so far has claimed
    let mut claimed = vec![false; votes.len()];
    let mut out = Vec::new();
    while out.len() < count {
        let (mut best, mut best_k) = (0usize, 0usize);
        for (k, v) in votes.iter().enumerate().filter(|(k, _)| !claimed[*k]) {
            let mut n = 0usize;
            each_near(v, radius, &mut |j| n += usize::from(!claimed[j]));
            if n > best {
                (best, best_k) = (n, k);
            }
        }
        if best == 0 {
            // no vote left, or none near even itself: not finite (a rotation with a NaN)
            break;
        }
        let (mut sum, mut n) = (Vector3::zeros(), 0usize);
        each_near(&votes[best_k], radius, &mut |k| {
            if !claimed[k] {
                sum += votes[k];
                n += 1;
            }
        });
        let mean = sum / n as f64;
        each_near(&mean, 2.0 * radius, &mut |k| claimed[k] = true);
        out.push((mean, n));
    }
    out
}
