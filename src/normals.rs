//! Normal estimation (for point-to-plane ICP).

use crate::spatial::neighbourhood::NEIGHBOURS;
use crate::spatial::KdIndex;
use nalgebra::{Matrix3, SymmetricEigen};

/// The normal given to points whose neighbourhood defines no plane (fewer than 3 points, all
/// neighbours at one spot, or a numerical failure).
pub const DEFAULT_NORMAL: [f32; 3] = [0.0, 0.0, 1.0];

/// Estimates a unit normal per point from its `k` nearest neighbours (PCA: the eigenvector of
/// the smallest eigenvalue of the neighbourhood covariance). Orientation is arbitrary (point-to-
/// plane ICP does not need it). Degenerate neighbourhoods get a defined normal, never NaN.
///
/// The neighbourhood includes the point itself; `k` is raised to 3 and capped at the cloud
/// size. The covariance is accumulated in `f64` about the neighbourhood mean and solved with
/// nalgebra's symmetric eigen-decomposition. Neighbourhoods with zero spread, and clouds of
/// fewer than 3 points, get [`DEFAULT_NORMAL`]. A collinear neighbourhood gets some unit vector
/// perpendicular to its line.
pub fn estimate_normals(points: &[[f32; 3]], k: usize) -> Vec<[f32; 3]> {
    if points.len() < 3 {
        return vec![DEFAULT_NORMAL; points.len()];
    }
    let index = KdIndex::new(points);
    let k = k.clamp(3, points.len());
    let mut nbrs = Vec::with_capacity(k + 1);
    points
        .iter()
        .map(|q| {
            index.knn_into(q, k, &mut nbrs);
            normal_of(points, nbrs.iter().map(|e| e.0))
        })
        .collect()
}

/// The normal [`estimate_normals`] gives point `j` of `points`, alone: from its `k` nearest
/// neighbours in `index` (which must index `points`), `k` raised to 3 and capped at the cloud
/// size; [`DEFAULT_NORMAL`] for clouds of fewer than 3 points. With `k` one more than
/// [`NEIGHBOURS`], the index's kept neighbours of `j` ([`KdIndex::neighbours`]) are those
/// points, found once for the normal and the searches hinted with `j`.
pub fn normal_at(points: &[[f32; 3]], index: &KdIndex, j: usize, k: usize) -> [f32; 3] {
    if points.len() < 3 {
        return DEFAULT_NORMAL;
    }
    let k = k.clamp(3, points.len());
    if k == NEIGHBOURS + 1 {
        if let Some(others) = index.neighbours(j) {
            return normal_of(points, std::iter::once(j).chain(others));
        }
    }
    let mut nbrs = Vec::with_capacity(k + 1);
    index.knn_into(&points[j], k, &mut nbrs);
    normal_of(points, nbrs.iter().map(|e| e.0))
}

/// The PCA normal of the points `idx` of `points`.
pub fn normal_of(points: &[[f32; 3]], idx: impl Iterator<Item = usize> + Clone) -> [f32; 3] {
    let count = idx.clone().count();
    if count < 3 {
        return DEFAULT_NORMAL;
    }
    let n = count as f64;
    let mut mean = [0.0f64; 3];
    for i in idx.clone() {
        for a in 0..3 {
            mean[a] += points[i][a] as f64;
        }
    }
    mean = mean.map(|m| m / n);
    let mut c = Matrix3::<f64>::zeros();
    for i in idx {
        let d = [0, 1, 2].map(|a| points[i][a] as f64 - mean[a]);
        for r in 0..3 {
            for s in r..3 {
                c[(r, s)] += d[r] * d[s];
            }
        }
    }
    for r in 0..3 {
        for s in 0..r {
            c[(r, s)] = c[(s, r)];
        }
    }
    let scale = c.abs().max();
    if !(scale > 0.0 && scale.is_finite()) {
        return DEFAULT_NORMAL;
    }
    let eig = SymmetricEigen::new(c / scale);
    let (mut best, mut best_val) = (0, f64::INFINITY);
    for (j, &v) in eig.eigenvalues.iter().enumerate() {
        if v < best_val {
            best = j;
            best_val = v;
        }
    }
    let v = eig.eigenvectors.column(best);
    let norm = v.norm();
    if !(norm > 0.0 && norm.is_finite()) {
        return DEFAULT_NORMAL;
    }
    let out = [(v[0] / norm) as f32, (v[1] / norm) as f32, (v[2] / norm) as f32];
    if out.iter().all(|x| x.is_finite()) {
        out
    } else {
        DEFAULT_NORMAL
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_neighbourhoods_get_default() {
        assert_eq!(estimate_normals(&[[1.0, 2.0, 3.0]; 2], 10), vec![DEFAULT_NORMAL; 2]);
        assert_eq!(estimate_normals(&[[1.0, 2.0, 3.0]; 30], 10), vec![DEFAULT_NORMAL; 30]);
        assert!(estimate_normals(&[], 10).is_empty());
        let line: Vec<[f32; 3]> = (0..30).map(|i| [i as f32, 0.0, 0.0]).collect();
        for n in estimate_normals(&line, 5) {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-5 && n[0].abs() < 1e-5, "{n:?}");
        }
    }
}
