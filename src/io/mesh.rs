//! Mesh area and area-weighted uniform surface sampling.

use super::Mesh;
use crate::cloud::PointCloud;
use crate::{Error, Result};
use rand::Rng;

/// The corners of triangle `t` of `vertices`, or `None` when an index is out of range.
fn corners(vertices: &[[f64; 3]], t: &[u32; 3]) -> Option<[[f64; 3]; 3]> {
    let mut c = [[0.0f64; 3]; 3];
    for (k, &i) in t.iter().enumerate() {
        c[k] = *vertices.get(i as usize)?;
    }
    Some(c)
}

fn area_of(c: &[[f64; 3]; 3]) -> f64 {
    let e1 = [0, 1, 2].map(|a| c[1][a] - c[0][a]);
    let e2 = [0, 1, 2].map(|a| c[2][a] - c[0][a]);
    let x = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    0.5 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
}

/// A running sum of areas with a guide table: `first_above(u)` is the first index whose sum
/// exceeds `u` (`partition_point(|c| c <= u)`, the same answer), found in the few entries of
/// `u`'s bucket instead of a binary search over the whole table, whose scattered reads cost
/// most of a large mesh's sampling.
struct AreaTable {
    /// Non-decreasing, its last entry the total area.
    cumulative: Vec<f64>,
    /// `guide[b]`: how many sums are at most the `b`-th of `buckets` equal steps of `total`.
    guide: Vec<usize>,
}

impl AreaTable {
    /// `cumulative` non-decreasing; about `draws` lookups to come.
    fn new(cumulative: Vec<f64>, draws: usize) -> Self {
        let total = cumulative.last().copied().unwrap_or(0.0);
        let buckets = draws.min(cumulative.len()).max(1);
        let mut guide = Vec::with_capacity(buckets + 1);
        let mut k = 0;
        for b in 0..=buckets {
            let edge = total * (b as f64 / buckets as f64);
            while k < cumulative.len() && cumulative[k] <= edge {
                k += 1;
            }
            guide.push(k);
        }
        Self { cumulative, guide }
    }

    fn first_above(&self, u: f64) -> usize {
        let buckets = self.guide.len() - 1;
        let total = self.cumulative.last().copied().unwrap_or(0.0);
        let b = ((u / total * buckets as f64) as usize).min(buckets - 1);
        // one bucket of slack each side covers the rounding of `b` and of the edges: every sum
        // before `lo` is at most `u`, every sum from `hi` on exceeds it
        let lo = self.guide[b.saturating_sub(1)];
        let hi = self.guide[(b + 2).min(buckets)];
        lo + self.cumulative[lo..hi].partition_point(|&c| c <= u)
    }
}

/// Draws `n` points uniformly over the surface of the triangles `triangles` of `vertices`: a
/// triangle is chosen with probability proportional to its area (a cumulative area table,
/// searched through a guide table), then a point uniformly inside it (`A + s(1-r2)(B-A) + s r2 (C-A)` with
/// `s = sqrt(r1)`), all in `f64`. The same seed gives the same points on every platform.
///
/// Fails when a triangle has an out-of-range vertex index, or when no triangle has a positive,
/// finite area.
pub(crate) fn sample_triangles(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    n: usize,
    seed: u64,
) -> Result<Vec<[f64; 3]>> {
    // the triangles of positive area (their indices, 4 bytes each, not their corners: a 1 GiB STL
    // holds 21 million) and the running sum of their areas
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut chosen: Vec<u32> = Vec::with_capacity(triangles.len());
    let mut total = 0.0f64;
    for (ti, t) in triangles.iter().enumerate() {
        let c = corners(vertices, t).ok_or_else(|| {
            Error::InvalidCloud(format!(
                "mesh triangle {ti} has a vertex index out of range ({t:?}, {} vertices)",
                vertices.len()
            ))
        })?;
        let a = area_of(&c);
        if a > 0.0 && a.is_finite() && (total + a).is_finite() {
            total += a;
            cumulative.push(total);
            chosen.push(ti as u32);
        }
    }
    if chosen.is_empty() {
        return Err(Error::InvalidCloud(format!(
            "cannot sample the mesh surface: none of its {} triangles has a positive, finite area",
            triangles.len()
        )));
    }
    let table = AreaTable::new(cumulative, n);
    let mut rng = crate::sampling::rng(seed);
    let mut points = Vec::with_capacity(n.min(1 << 20));
    for _ in 0..n {
        let u = rng.random::<f64>() * total;
        let k = table.first_above(u).min(chosen.len() - 1);
        // checked above: every index is in range
        let Some([a, b, c]) = corners(vertices, &triangles[chosen[k] as usize]) else { continue };
        let s = rng.random::<f64>().sqrt();
        let r2 = rng.random::<f64>();
        let (wb, wc) = (s * (1.0 - r2), s * r2);
        points.push([0, 1, 2].map(|i| a[i] + wb * (b[i] - a[i]) + wc * (c[i] - a[i])));
    }
    Ok(points)
}

impl Mesh {
    /// Total surface area (in `f64`). Triangles with an out-of-range index or a non-finite
    /// area (NaN / infinite vertices) contribute nothing.
    pub fn surface_area(&self) -> f64 {
        let vertices: Vec<[f64; 3]> = self.vertices.iter().map(|v| v.map(|x| x as f64)).collect();
        self.triangles
            .iter()
            .filter_map(|t| corners(&vertices, t))
            .map(|c| area_of(&c))
            .filter(|a| a.is_finite())
            .fold(0.0, |s, a| s + a)
    }

    /// Draws `n` points uniformly over the surface: a triangle is chosen with probability
    /// proportional to its area (a search in a cumulative area table), then a point
    /// uniformly inside it (`A + s(1-r2)(B-A) + s r2 (C-A)` with `s = sqrt(r1)`), in `f64`. The
    /// same seed gives the same points on every platform.
    ///
    /// Fails when a triangle has an out-of-range vertex index, or when no triangle has a
    /// positive, finite area.
    pub fn sample_surface(&self, n: usize, seed: u64) -> Result<PointCloud> {
        let vertices: Vec<[f64; 3]> = self.vertices.iter().map(|v| v.map(|x| x as f64)).collect();
        let points = sample_triangles(&vertices, &self.triangles, n, seed)?;
        Ok(PointCloud::new(points.into_iter().map(|p| p.map(|x| x as f32)).collect()))
    }
}

#[cfg(test)]
mod tests {
    use super::AreaTable;
    use rand::{Rng, SeedableRng};

    /// The guided search answers exactly as a binary search over the whole table, on tables with
    /// repeated sums and lookups at, between and beyond the sums.
    #[test]
    fn area_table_matches_binary_search() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for (len, draws) in [(1, 10), (7, 3), (1000, 64), (5000, 4096), (300, 10_000)] {
            let mut total = 0.0;
            let cumulative: Vec<f64> = (0..len)
                .map(|i| {
                    // some zero-width steps (repeated sums) and widths over six decades
                    if i % 11 != 3 {
                        total += 10f64.powf(rng.random::<f64>() * 6.0 - 3.0);
                    }
                    total
                })
                .collect();
            let table = AreaTable::new(cumulative.clone(), draws);
            let mut probes: Vec<f64> = (0..20_000).map(|_| rng.random::<f64>() * total).collect();
            probes.extend(cumulative.iter().copied());
            probes.extend([0.0, total, total * (1.0 - 1e-16), -1.0, total * 2.0]);
            for u in probes {
                assert_eq!(table.first_above(u), cumulative.partition_point(|&c| c <= u), "u = {u}");
            }
        }
    }
}
