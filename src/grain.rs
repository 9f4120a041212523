//! A cloud's *grain*: how finely its points resolve its surface, measured in a few probe cells.
//!
//! The default correspondence distance is a share of the clouds' size, which spans a few point
//! spacings on an object's scan and on the paper's pairs, but tens of them on a dense scene (a
//! survey of a site, a LiDAR frame), where an answer off by a fraction of that distance fits as
//! well as the right one. The grain says how many: at [`PROBES`] points spread evenly over the
//! cloud, the cell of the given size around each (a voxel grid's cell) holds `m` points whose
//! covariance has eigenvalues `l0 <= l1 <= l2`. On a surface, `sqrt(l0)` is the points' spread
//! across it (noise, and the surface's bend within the cell), and the cell's share of the surface
//! is about `12 sqrt(l1 l2)` (a uniform square's), so `m` points resolve it at a spacing of
//! `sqrt(12 sqrt(l1 l2) / m)`. The grain is the median of each over the cells that hold at least
//! [`MIN_CELL_POINTS`]; a cloud sparse at that scale (fewer than half its cells hold that many)
//! has none.
//!
//! One pass over the points (at most [`MAX_VISITED`] of them, evenly spread, their counts scaled
//! up accordingly), a lookup of each point's cell among the probes' cells.

use crate::refine::even_sample;
use crate::sampling::VoxelKeys;
use nalgebra::Matrix3;

/// Probe points spread evenly over the cloud.
pub const PROBES: usize = 256;

/// Fewest points in a probe's cell for it to count: fewer spread too little to tell a surface.
pub const MIN_CELL_POINTS: usize = 12;

/// Most points the pass visits; a larger cloud is visited at an even stride, its cells' counts
/// multiplied by it.
pub const MAX_VISITED: usize = 2_000_000;

/// How finely a cloud resolves its surface (see the module docs), in the cloud's units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grain {
    /// The spacing its points sample the surface at.
    pub spacing: f64,
    /// Its points' spread across the surface (noise, and its bend within a cell).
    pub spread: f64,
}

impl Grain {
    /// The grain with both lengths multiplied by `factor` (1 / the normalisation's scale: in
    /// normalised units).
    pub fn scaled(self, factor: f64) -> Self {
        Self { spacing: self.spacing * factor, spread: self.spread * factor }
    }
}

/// The grain of `points` measured in cells of side `cell` (their units); `None` when the cloud is
/// sparse at that scale or `cell` is not a positive finite size.
pub fn of(points: &[[f32; 3]], cell: f64) -> Option<Grain> {
    if !(cell.is_finite() && cell > 0.0) || points.is_empty() {
        return None;
    }
    let inv = 1.0 / cell;
    let key_of = |p: &[f32; 3]| p.map(|v| (f64::from(v) * inv).floor() as i64);
    // the probes' distinct cells, each with its first probe as the anchor its sums are taken about
    let mut cells = VoxelKeys::default();
    let mut anchors: Vec<[f64; 3]> = Vec::new();
    for p in even_sample(points, PROBES) {
        cells.entry(key_of(&p)).or_insert_with(|| {
            anchors.push(p.map(f64::from));
            anchors.len() as u32 - 1
        });
    }
    let stride = points.len().div_ceil(MAX_VISITED).max(1);
    let mut moments = vec![Moments::default(); anchors.len()];
    for p in points.iter().step_by(stride) {
        if let Some(&i) = cells.get(&key_of(p)) {
            let a = &anchors[i as usize];
            moments[i as usize].add([f64::from(p[0]) - a[0], f64::from(p[1]) - a[1], f64::from(p[2]) - a[2]]);
        }
    }
    let mut spacings = Vec::with_capacity(moments.len());
    let mut spreads = Vec::with_capacity(moments.len());
    for m in &moments {
        if let Some((spacing, spread)) = m.grain(stride as f64) {
            spacings.push(spacing);
            spreads.push(spread);
        }
    }
    if spacings.len() * 2 < moments.len() {
        return None;
    }
    Some(Grain { spacing: crate::stats::median(&mut spacings)?, spread: crate::stats::median(&mut spreads)? })
}

/// A cell's point count and sums (about its anchor).
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    n: usize,
    sum: [f64; 3],
    /// xx, xy, xz, yy, yz, zz
    outer: [f64; 6],
}

impl Moments {
    fn add(&mut self, d: [f64; 3]) {
        self.n += 1;
        for (sum, v) in self.sum.iter_mut().zip(d) {
            *sum += v;
        }
        let [x, y, z] = d;
        for (o, v) in self.outer.iter_mut().zip([x * x, x * y, x * z, y * y, y * z, z * z]) {
            *o += v;
        }
    }

    /// The cell's spacing and spread (see the module docs), its count multiplied by `stride`;
    /// `None` below [`MIN_CELL_POINTS`] visited points.
    fn grain(&self, stride: f64) -> Option<(f64, f64)> {
        if self.n < MIN_CELL_POINTS {
            return None;
        }
        let n = self.n as f64;
        let c = self.sum.map(|s| s / n);
        let o = self.outer.map(|s| s / n);
        let cov = Matrix3::new(
            o[0] - c[0] * c[0],
            o[1] - c[0] * c[1],
            o[2] - c[0] * c[2],
            o[1] - c[0] * c[1],
            o[3] - c[1] * c[1],
            o[4] - c[1] * c[2],
            o[2] - c[0] * c[2],
            o[4] - c[1] * c[2],
            o[5] - c[2] * c[2],
        );
        // the least spread is across the surface, the other two along it
        let [s2, s1, s0] = crate::checks::spreads_of(&cov);
        Some(((12.0 * s1 * s2 / (n * stride)).sqrt(), s0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `side` x `side` grid of spacing `step` in the plane z = 0.05 (inside the cells of side
    /// 0.1 the tests measure in), lifted by `lift(i)`.
    fn grid(side: usize, step: f32, lift: impl Fn(usize) -> f32) -> Vec<[f32; 3]> {
        (0..side * side).map(|i| [(i % side) as f32 * step, (i / side) as f32 * step, 0.05 + lift(i)]).collect()
    }

    #[test]
    fn a_dense_grid_has_its_spacing_and_no_spread() {
        let g = of(&grid(400, 0.01, |_| 0.0), 0.1).unwrap();
        assert!((g.spacing - 0.01).abs() < 0.001, "{g:?}");
        assert!(g.spread < 1e-6, "{g:?}");
    }

    #[test]
    fn a_noisy_grid_spreads_by_its_noise() {
        // a deterministic spread of +-0.004 (a uniform one's deviation: 0.004 / sqrt(3))
        let lift = |i: usize| ((i.wrapping_mul(2_654_435_761) % 1001) as f32 / 500.0 - 1.0) * 0.004;
        let g = of(&grid(400, 0.01, lift), 0.1).unwrap();
        let sigma = 0.004 / 3f64.sqrt();
        assert!((g.spread - sigma).abs() < 0.2 * sigma, "{g:?}");
        assert!((g.spacing - 0.01).abs() < 0.0015, "{g:?}");
    }

    #[test]
    fn a_cloud_sparse_at_the_cells_scale_has_none() {
        // three points per cell side: nine to a cell, fewer than MIN_CELL_POINTS
        assert!(of(&grid(60, 0.034, |_| 0.0), 0.1).is_none());
        assert!(of(&grid(60, 0.01, |_| 0.0), 0.0).is_none());
        assert!(of(&grid(60, 0.01, |_| 0.0), f64::NAN).is_none());
        assert!(of(&[], 0.1).is_none());
    }

    #[test]
    fn a_cloud_past_the_visited_points_is_measured_at_a_stride() {
        let side = 1_600; // 2.56 million points, visited every second one
        assert!(side * side > MAX_VISITED);
        let g = of(&grid(side, 0.01, |_| 0.0), 0.1).unwrap();
        assert!((g.spacing - 0.01).abs() < 0.001, "{g:?}");
    }
}
