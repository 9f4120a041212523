//! RANSAC over descriptor correspondences (Open3D's `RegistrationRANSACBasedOnCorrespondence`,
//! seeded): draw three correspondences, reject the draw with cheap checks before any scoring
//! (rigid motions keep lengths: the three pairwise distances must agree to [`RansacParams::edge_ratio`];
//! the fitted motion must bring the three points within the inlier distance), score the rest by
//! their correspondence inliers, and stop once the best inlier ratio makes a better draw unlikely
//! ([`RansacParams::confidence`]). Keeps the best few *distinct* motions, each refitted to its
//! inliers, ranked by inlier count.

use crate::gmr::kabsch;
use crate::transform::rotation_error_deg;
use nalgebra::Matrix4;
use rand::Rng;

/// Settings of [`ransac`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RansacParams {
    /// Most draws (each draw counts, rejected or scored).
    pub max_iterations: u32,
    /// Stop when a draw of three inliers has been this likely to have happened, given the best
    /// inlier ratio so far (0.999).
    pub confidence: f64,
    /// A correspondence is an inlier when the motion brings its source point within this distance
    /// of its target point.
    pub inlier_distance: f64,
    /// Pairwise distances within a draw must agree to this ratio (0.9).
    pub edge_ratio: f64,
    /// How many distinct hypotheses to return at most.
    pub hypotheses: usize,
    /// Seed of the draws.
    pub seed: u64,
}

/// One rigid motion found by [`ransac`].
#[allow(non_snake_case)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hypothesis {
    /// Maps the source points into the target frame.
    pub T_target_source: Matrix4<f64>,
    /// Correspondences it brings within the inlier distance.
    pub inliers: usize,
}

/// Two hypotheses closer than this in rotation (degrees) and in where they move the source's
/// centre (in inlier distances) are the same basin: only the better one is kept.
const SAME_DEGREES: f64 = 10.0;
const SAME_DISTANCES: f64 = 3.0;

fn f64s(p: &[f32; 3]) -> [f64; 3] {
    p.map(|v| v as f64)
}

fn dist(a: &[f32; 3], b: &[f32; 3]) -> f64 {
    let d = [0, 1, 2].map(|i| a[i] as f64 - b[i] as f64);
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

fn moved(t: &Matrix4<f64>, p: &[f32; 3]) -> [f64; 3] {
    let v = t * nalgebra::Vector4::new(p[0] as f64, p[1] as f64, p[2] as f64, 1.0);
    [v.x, v.y, v.z]
}

/// Correspondences `(source index, target index)` that `t` brings within `d` (`out` cleared first).
fn inliers_into(t: &Matrix4<f64>, s: &[[f32; 3]], tg: &[[f32; 3]], m: &[(u32, u32)], d: f64, out: &mut Vec<usize>) {
    out.clear();
    let d2 = d * d;
    for (k, &(i, j)) in m.iter().enumerate() {
        let p = moved(t, &s[i as usize]);
        let q = tg[j as usize];
        let e = [0, 1, 2].map(|a| p[a] - q[a] as f64);
        if e[0] * e[0] + e[1] * e[1] + e[2] * e[2] < d2 {
            out.push(k);
        }
    }
}

/// Kabsch fit of the correspondences `idx`.
fn fit(s: &[[f32; 3]], tg: &[[f32; 3]], m: &[(u32, u32)], idx: &[usize]) -> Matrix4<f64> {
    let a: Vec<[f64; 3]> = idx.iter().map(|&k| f64s(&s[m[k].0 as usize])).collect();
    let b: Vec<[f64; 3]> = idx.iter().map(|&k| f64s(&tg[m[k].1 as usize])).collect();
    kabsch(&a, &b, None)
}

/// Whether two motions are the same basin ([`SAME_DEGREES`], [`SAME_DISTANCES`] of the inlier
/// distance `d`), judged where they move `center` (the source's matched points' centroid).
pub(crate) fn same_basin(a: &Matrix4<f64>, b: &Matrix4<f64>, center: &[f32; 3], d: f64) -> bool {
    let (p, q) = (moved(a, center), moved(b, center));
    let gap = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
    gap < SAME_DISTANCES * d && rotation_error_deg(a, b) < SAME_DEGREES
}

/// Inserts `h` into `top` (sorted by inliers, best first, at most `cap` long), unless a kept
/// hypothesis in the same basin is at least as good; a worse one in the same basin is replaced.
fn offer(top: &mut Vec<Hypothesis>, h: Hypothesis, center: &[f32; 3], d: f64, cap: usize) {
    let same = |a: &Hypothesis| same_basin(&a.T_target_source, &h.T_target_source, center, d);
    if let Some(k) = top.iter().position(same) {
        if top[k].inliers >= h.inliers {
            return;
        }
        top.remove(k);
    }
    let at = top.partition_point(|x| x.inliers >= h.inliers);
    if at < cap {
        top.insert(at, h);
        top.truncate(cap);
    }
}

/// The best distinct rigid motions taking `source[i]` onto `target[j]` for the correspondences
/// `(i, j)` of `matches`, best first (at most `params.hypotheses`; none for fewer than three
/// correspondences). Deterministic for a seed. Memory is O(matches).
pub fn ransac(
    source: &[[f32; 3]],
    target: &[[f32; 3]],
    matches: &[(u32, u32)],
    params: &RansacParams,
) -> Vec<Hypothesis> {
    let n = matches.len();
    let cap = params.hypotheses;
    if n < 3 || cap == 0 {
        return Vec::new();
    }
    let d = params.inlier_distance;
    let mut center = [0.0f32; 3];
    for &(i, _) in matches {
        for a in 0..3 {
            center[a] += source[i as usize][a] / n as f32;
        }
    }
    let mut rng = crate::sampling::rng(params.seed);
    // keep more candidates than asked while drawing: refitting can merge basins
    let pool = cap * 4;
    let mut top: Vec<Hypothesis> = Vec::with_capacity(pool + 1);
    let mut inl = Vec::with_capacity(n);
    let mut needed = params.max_iterations as u64;
    let mut it = 0u64;
    while it < needed && !crate::cancel::cancelled() {
        it += 1;
        let a = rng.random_range(0..n);
        let b = rng.random_range(0..n);
        let c = rng.random_range(0..n);
        if a == b || b == c || a == c {
            continue;
        }
        let (s, t) =
            ([a, b, c].map(|k| source[matches[k].0 as usize]), [a, b, c].map(|k| target[matches[k].1 as usize]));
        let mut ok = true;
        for (x, y) in [(0, 1), (1, 2), (0, 2)] {
            let (ls, lt) = (dist(&s[x], &s[y]), dist(&t[x], &t[y]));
            // a short edge fixes no rotation; lengths must agree
            if ls.min(lt) < 2.0 * d || ls.min(lt) < params.edge_ratio * ls.max(lt) {
                ok = false;
                break;
            }
        }
        if !ok {
            continue;
        }
        let tr = kabsch(&s.map(|p| f64s(&p)), &t.map(|p| f64s(&p)), None);
        if (0..3).any(|k| {
            let p = moved(&tr, &s[k]);
            let e = [0, 1, 2].map(|i| p[i] - t[k][i] as f64);
            (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() >= d
        }) {
            continue;
        }
        inliers_into(&tr, source, target, matches, d, &mut inl);
        let best = top.first().map_or(0, |h| h.inliers);
        if inl.len() > best {
            let w = inl.len() as f64 / n as f64;
            let p_good = w * w * w;
            if p_good >= 1.0 {
                needed = it;
            } else if p_good > 0.0 {
                let k = ((1.0 - params.confidence).ln() / (1.0 - p_good).ln()).ceil();
                if k.is_finite() && k >= 0.0 {
                    needed = needed.min(k as u64).max(it);
                }
            }
        }
        offer(&mut top, Hypothesis { T_target_source: tr, inliers: inl.len() }, &center, d, pool);
    }
    // refit each to its inliers (twice: the inlier set can grow), then rank again
    let mut out = Vec::with_capacity(pool);
    for h in top {
        let mut h = h;
        for _ in 0..2 {
            inliers_into(&h.T_target_source, source, target, matches, d, &mut inl);
            if inl.len() < 3 {
                break;
            }
            let t = fit(source, target, matches, &inl);
            inliers_into(&t, source, target, matches, d, &mut inl);
            if inl.len() >= h.inliers {
                h = Hypothesis { T_target_source: t, inliers: inl.len() };
            }
        }
        offer(&mut out, h, &center, d, cap);
    }
    out
}
