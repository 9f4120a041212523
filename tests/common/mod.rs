//! Shared test helpers: deterministic synthetic surfaces and transform checks.
#![allow(dead_code)]

use arps::transform::{euler_xyz, from_rotation_translation};
use arps::PointCloud;
use nalgebra::{Matrix4, Vector3};

pub mod box_grid;
#[cfg(not(target_arch = "wasm32"))]
pub mod scratch;
#[cfg(not(target_arch = "wasm32"))]
#[allow(unused_imports)] // not every test crate writes files
pub use scratch::scratch;

/// `n` points on a bumpy, asymmetric closed surface (about 2 units across), from a low-discrepancy
/// sequence: deterministic, no RNG.
pub fn bumpy_surface(n: usize, phase: f64) -> PointCloud {
    let mut pts = Vec::with_capacity(n);
    for i in 0..n as u64 {
        let a = (0.5 + (i as f64 + phase * 1000.0) * 0.754_877_666_246_692_7) % 1.0;
        let b = (0.5 + (i as f64 + phase * 1000.0) * 0.569_840_290_998_053_3) % 1.0;
        let u = a * std::f64::consts::TAU;
        let v = (2.0 * b - 1.0).acos();
        let r = 0.8 + 0.12 * (3.0 * u).sin() * (2.0 * v).cos() + 0.08 * (5.0 * v).sin();
        let p = [r * v.sin() * u.cos() * 1.2, r * v.sin() * u.sin() * 0.8, r * v.cos() + 0.2 * (u).cos()];
        pts.push(p.map(|x| x as f32));
    }
    PointCloud::new(pts)
}

/// `R = Rx Ry Rz` from degrees, plus a translation.
pub fn motion(deg: [f64; 3], t: [f64; 3]) -> Matrix4<f64> {
    let r = deg.map(f64::to_radians);
    from_rotation_translation(&euler_xyz(r[0], r[1], r[2]), &Vector3::from(t))
}

/// Rotation (degrees) and translation errors of `t` against the ground truth `gt`.
pub fn errors(t: &Matrix4<f64>, gt: &Matrix4<f64>) -> (f64, f64) {
    (arps::transform::rotation_error_deg(t, gt), arps::transform::translation_error(t, gt))
}

/// Keeps the points whose dot product with `dir` (about the centroid) is above the given quantile:
/// a half-space crop, as in the training protocol.
pub fn crop(cloud: &PointCloud, dir: [f32; 3], keep: f64) -> PointCloud {
    let c = cloud.centroid();
    let mut d: Vec<(f32, [f32; 3])> = cloud
        .points
        .iter()
        .map(|p| {
            (
                ((p[0] as f64 - c[0]) * dir[0] as f64
                    + (p[1] as f64 - c[1]) * dir[1] as f64
                    + (p[2] as f64 - c[2]) * dir[2] as f64) as f32,
                *p,
            )
        })
        .collect();
    d.sort_by(|a, b| b.0.total_cmp(&a.0));
    let k = (cloud.len() as f64 * keep) as usize;
    PointCloud::new(d[..k].iter().map(|x| x.1).collect())
}

/// A committed fixture pair (`fixtures/pairs`, paper protocol, normalised units) and its ground truth.
pub fn fixture_pair(index: usize) -> (PointCloud, PointCloud, Matrix4<f64>) {
    fixture_pair_in("fixtures/pairs", index)
}

/// Pair `index` of the committed fixture set in `dir` (relative to the crate root: `fixtures/pairs`,
/// `fixtures/any`) and its ground truth.
pub fn fixture_pair_in(dir: &str, index: usize) -> (PointCloud, PointCloud, Matrix4<f64>) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let text = std::fs::read_to_string(dir.join("pairs.tsv")).unwrap();
    // name, source, target, overlap_threshold, note, 16 numbers (row-major)
    let line = text.lines().nth(1 + index).unwrap();
    let fields: Vec<&str> = line.split('\t').collect();
    let read = |name: &str| arps::io::read_point_cloud(&std::fs::read(dir.join(name)).unwrap(), name).unwrap();
    let v: Vec<f64> = fields[5].split_whitespace().map(|x| x.parse().unwrap()).collect();
    (read(fields[1]), read(fields[2]), Matrix4::from_row_slice(&v))
}

/// Checks a `"drop"` / `"keep"` option of `Options` read from JSON under `key`: `"keep"` reads as
/// `keep`, the default is `drop`, and another value is an error that names the variants.
pub fn drop_or_keep_from_json<T: PartialEq + std::fmt::Debug>(
    key: &str,
    field: impl Fn(&arps::Options) -> T,
    drop: T,
    keep: T,
) {
    let o: arps::Options = serde_json::from_str(&format!(r#"{{"{key}": "keep"}}"#)).unwrap();
    assert_eq!(field(&o), keep);
    assert_eq!(field(&arps::Options::default()), drop);
    let e = serde_json::from_str::<arps::Options>(&format!(r#"{{"{key}": "remove"}}"#)).unwrap_err().to_string();
    assert!(e.contains("unknown variant `remove`") && e.contains("drop") && e.contains("keep"), "{e}");
}

/// The bytes of `fixtures/formats/NAME` (one real file per format).
pub fn format_fixture(name: &str) -> Vec<u8> {
    std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/formats").join(name)).unwrap()
}

/// 50 degrees about a tilted axis, then a shift: what the file movers' tests move files by.
pub fn tilted_motion() -> Matrix4<f64> {
    let axis = nalgebra::Unit::new_normalize(Vector3::new(0.3, -1.0, 0.4));
    Matrix4::new_translation(&Vector3::new(2.5, -1.25, 0.75))
        * nalgebra::Rotation3::from_axis_angle(&axis, 50f64.to_radians()).to_homogeneous()
}

/// `m` applied to the point `p`, in f64.
pub fn apply(m: &Matrix4<f64>, p: [f64; 3]) -> [f64; 3] {
    let q = m.transform_point(&nalgebra::Point3::from(p));
    [q.x, q.y, q.z]
}
