//! Normal estimation (for point-to-plane ICP).

/// Estimates a unit normal per point from its `k` nearest neighbours (PCA: the eigenvector of
/// the smallest eigenvalue of the neighbourhood covariance). Orientation is arbitrary (point-to-
/// plane ICP does not need it). Degenerate neighbourhoods get a defined normal, never NaN.
pub fn estimate_normals(points: &[[f32; 3]], k: usize) -> Vec<[f32; 3]> {
    let _ = (points, k);
    todo!("helper: normals")
}
