// Shared by the `read_point_cloud` and `read_e57` fuzz targets and `tests/io_fuzz_regressions.rs`
// (which replays their inputs), through `include!`, so all check the round trip the same way.

/// True when `b` holds the same points as `a` in the caller's frame: bit for bit when both
/// origins are zero (the usual case: written as `float`, read back as such), else within `f32`
/// rounding of the offsets (the re-read cloud picks its origin from what it reads).
fn same_points(a: &arps::PointCloud, b: &arps::PointCloud) -> bool {
    if a.len() != b.len() {
        return false;
    }
    if a.origin_is_zero() && b.origin_is_zero() {
        return a.points.iter().zip(&b.points).all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits));
    }
    let far = a.origin.iter().chain(&b.origin).fold(0.0f64, |m, v| m.max(v.abs()));
    let tol = 1e-6 * (a.half_extent().max(b.half_extent()) + 1e-30) + 1e-12 * far;
    (0..a.len()).all(|i| {
        let (p, q) = (a.point_f64(i), b.point_f64(i));
        (0..3).all(|k| if p[k].is_finite() { (p[k] - q[k]).abs() <= tol } else { p[k].is_nan() == q[k].is_nan() })
    })
}

/// Whatever was read writes as PLY and reads back with the same points ([`same_points`]).
fn reads_back(cloud: &arps::PointCloud) -> bool {
    let back = arps::io::read_point_cloud(&arps::io::write_ply_binary(cloud), "b.ply").expect("own PLY reads back");
    same_points(cloud, &back)
}
