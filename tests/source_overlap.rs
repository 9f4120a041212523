//! `sourceOverlap`: the share of the source the caller knows lies on the target. A view of one
//! part registered onto the model of another fits only in part, however it is turned: with
//! `sourceOverlap: 1` that answer is not taken as sure, and says why; a view onto its own model
//! is answered as without the option.
#![allow(non_snake_case)]

use arps::io::{read_point_cloud_with, ReadOptions};
use arps::transform::{from_rotation_translation, rigid_inverse, rotation_error_deg};
use arps::{Options, PointCloud, Registrar};
use nalgebra::{Rotation3, Vector3};

/// A model from the fixtures read as `n` points over its surface, centred and scaled to a largest
/// half-extent of 1.
fn model(file: &str, n: usize, seed: u64) -> PointCloud {
    let bytes = std::fs::read(format!("{}/fixtures/formats/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let cloud =
        read_point_cloud_with(&bytes, file, &ReadOptions { surface_points: Some(n), seed, ..Default::default() })
            .unwrap();
    let (lo, hi) = cloud.bounds();
    let c: Vec<f32> = (0..3).map(|a| (lo[a] + hi[a]) / 2.0).collect();
    let h = cloud.half_extent() as f32;
    PointCloud::new(cloud.points.iter().map(|p| [0, 1, 2].map(|a| (p[a] - c[a]) / h)).collect())
}

/// The half of `cloud` seen from `view`, moved out of the target's frame by `T_target_source`.
fn view(cloud: &PointCloud, view: Vector3<f64>, T_target_source: &nalgebra::Matrix4<f64>) -> PointCloud {
    let seen =
        cloud.points.iter().copied().filter(|p| Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64).dot(&view) > 0.0);
    PointCloud::new(seen.collect()).transformed(&rigid_inverse(T_target_source))
}

#[test]
fn a_view_of_another_part_falls_short_of_the_declared_overlap() {
    let T_target_source = from_rotation_translation(
        &Rotation3::from_euler_angles(0.5, -0.3, 1.9).into_inner(),
        &Vector3::new(0.2, -0.4, 0.3),
    );
    let part = view(
        &model("angle_block_binary_solid.stl", 6_000, 2),
        Vector3::new(0.4, 1.0, 0.7).normalize(),
        &T_target_source,
    );
    let own = model("angle_block_binary_solid.stl", 20_000, 1);
    let other = model("fuze.obj", 20_000, 1);
    let declared = Options { source_overlap: Some(1.0), ..Options::default() };
    let mut reg = Registrar::with_default_model().unwrap();

    // onto its own model: right, and the same answer as without the option
    let plain = reg.register(&part, &own, &Options::default()).unwrap();
    let r = reg.register(&part, &own, &declared).unwrap();
    assert!(rotation_error_deg(&r.T_target_source, &T_target_source) < 2.0, "{}", r.T_target_source);
    assert!(r.confidence > 0.9, "{} {:?}", r.confidence, r.warnings);
    assert!(!r.warnings.iter().any(|w| w.contains("sourceOverlap")), "{:?}", r.warnings);
    assert_eq!(r.T_target_source, plain.T_target_source);
    assert_eq!(r.confidence, plain.confidence);

    // onto another part's model: it fits only in part, and the answer says so
    let r = reg.register(&part, &other, &declared).unwrap();
    assert!(r.evidence.fitness_loose < 0.85, "{:?}", r.evidence);
    assert!(r.confidence <= 0.25, "{} {:?}", r.confidence, r.warnings);
    assert!(
        r.warnings.iter().any(|w| w.contains("of the source lies within") && w.contains("sourceOverlap says 100%")),
        "{:?}",
        r.warnings
    );
    // without the option nothing is said about the share
    let r = reg.register(&part, &other, &Options::default()).unwrap();
    assert!(!r.warnings.iter().any(|w| w.contains("sourceOverlap")), "{:?}", r.warnings);
}

#[test]
fn source_overlap_outside_zero_to_one_is_an_error() {
    let part = model("angle_block_binary_solid.stl", 2_000, 1);
    let mut reg = Registrar::with_default_model().unwrap();
    for share in [0.0, -0.5, 1.5, f64::NAN, f64::INFINITY] {
        let err =
            reg.register(&part, &part, &Options { source_overlap: Some(share), ..Options::default() }).unwrap_err();
        assert!(err.to_string().contains("sourceOverlap"), "{share}: {err}");
    }
    // and the registrar is usable after the errors
    assert!(reg.register(&part, &part, &Options { source_overlap: Some(0.8), ..Options::default() }).is_ok());
}
