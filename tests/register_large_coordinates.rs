//! Map-grid coordinates (5e6, as UTM gives) keep their shape: readers keep doubles, clouds carry
//! an f64 origin, and the registration at 5e6 equals the one at the origin, in the caller's frame.

use arps::io::{read_point_cloud, write_ply_binary};
use arps::transform::{from_rows, rotation_error_deg, translation_error};
use arps::{Options, PointCloud, Registrar};
use nalgebra::{Matrix4, Vector3};

/// A UTM-like offset, with digits below the f32 resolution at this magnitude (0.5 m).
const FAR: [f64; 3] = [5_012_345.678_9, 4_204_321.123_4, 312.5];

/// The largest distance, over `cloud`'s points (caller's frame, f64), between where `a` and `b`
/// put them. (Comparing translations would not do: at 5e6 from zero, a rotation difference of
/// 1e-8 rad, f32 rounding on a 2-unit cloud, moves the translation by 0.05.)
fn gap(a: &Matrix4<f64>, b: &Matrix4<f64>, cloud: &PointCloud) -> f64 {
    (0..cloud.len())
        .map(|i| {
            let p = nalgebra::Point3::from(cloud.point_f64(i));
            (a.transform_point(&p) - b.transform_point(&p)).norm()
        })
        .fold(0.0, f64::max)
}

fn fixture(name: &str) -> PointCloud {
    let path = format!("{}/fixtures/wasm/{name}", env!("CARGO_MANIFEST_DIR"));
    read_point_cloud(&std::fs::read(&path).unwrap(), name).unwrap()
}

/// The cloud moved by `offset`, as a binary little-endian PLY with `double` properties.
fn double_ply(cloud: &PointCloud, offset: [f64; 3]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nend_header\n",
        cloud.len()
    )
    .into_bytes();
    for i in 0..cloud.len() {
        let p = cloud.point_f64(i);
        for a in 0..3 {
            out.extend_from_slice(&(p[a] + offset[a]).to_le_bytes());
        }
    }
    out
}

#[test]
fn double_ply_far_from_zero_keeps_its_shape() {
    let source = fixture("source.ply");
    let far = read_point_cloud(&double_ply(&source, FAR), "far.ply").unwrap();
    assert!(far.origin.iter().zip(FAR).all(|(o, f)| (o - f).abs() < 10.0), "origin {:?}", far.origin);
    for i in 0..source.len() {
        let (p, q) = (source.point_f64(i), far.point_f64(i));
        for a in 0..3 {
            // f32 offsets from a nearby origin: about 1e-7 of the cloud's size, not 0.5 m
            assert!((q[a] - FAR[a] - p[a]).abs() < 1e-6, "point {i} axis {a}: {} vs {}", q[a] - FAR[a], p[a]);
        }
    }
    // and it writes back as doubles, losing nothing more
    let back = read_point_cloud(&write_ply_binary(&far), "back.ply").unwrap();
    for i in (0..far.len()).step_by(97) {
        let (p, q) = (far.point_f64(i), back.point_f64(i));
        assert!((0..3).all(|a| (p[a] - q[a]).abs() < 1e-6), "{p:?} vs {q:?}");
    }
}

#[test]
fn registration_at_map_grid_coordinates_equals_the_one_at_the_origin() {
    let (source, target) = (fixture("source.ply"), fixture("target.ply"));
    let mut registrar = Registrar::with_default_model().unwrap();
    let near = registrar.register(&source, &target, &Options::default()).unwrap();

    let far_source = read_point_cloud(&double_ply(&source, FAR), "s.ply").unwrap();
    let far_target = read_point_cloud(&double_ply(&target, FAR), "t.ply").unwrap();
    let far = registrar.register(&far_source, &far_target, &Options::default()).unwrap();
    // the same motion, seen in the shifted frame: Tr(FAR) * T * Tr(-FAR)
    let shift = Matrix4::new_translation(&Vector3::from(FAR));
    let expected = shift * near.T_target_source * Matrix4::new_translation(&-Vector3::from(FAR));
    let (re, g) =
        (rotation_error_deg(&far.T_target_source, &expected), gap(&far.T_target_source, &expected, &far_source));
    assert!(re < 1e-3 && g < 1e-4, "{re} deg, points {g} apart (the fixture is about 2 units across)");
    assert!((far.fitness - near.fitness).abs() < 0.01, "fitness {} vs {}", far.fitness, near.fitness);
    assert!(far.warnings.len() == near.warnings.len(), "{:?} vs {:?}", far.warnings, near.warnings);
}

#[test]
fn initial_transform_is_taken_in_the_callers_frame() {
    let (source, target) = (fixture("source.ply"), fixture("target.ply"));
    let mut registrar = Registrar::with_default_model().unwrap();
    let rows = |m: &Matrix4<f64>| std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]));
    let truth_path = format!("{}/fixtures/wasm/pair.json", env!("CARGO_MANIFEST_DIR"));
    let pair: serde_json::Value = serde_json::from_slice(&std::fs::read(truth_path).unwrap()).unwrap();
    let truth_rows: [[f64; 4]; 4] = serde_json::from_value(pair["T_target_source"].clone()).unwrap();
    let truth = from_rows(&truth_rows);
    // ICP only, from the true transform: stays there, both near zero and at 5e6
    let opts = |m: &Matrix4<f64>| Options { network: false, initial_transform: Some(rows(m)), ..Options::default() };
    let near = registrar.register(&source, &target, &opts(&truth)).unwrap();
    let shift = Matrix4::new_translation(&Vector3::from(FAR));
    let truth_far = shift * truth * Matrix4::new_translation(&-Vector3::from(FAR));
    let far_source = read_point_cloud(&double_ply(&source, FAR), "s.ply").unwrap();
    let far_target = read_point_cloud(&double_ply(&target, FAR), "t.ply").unwrap();
    let far = registrar.register(&far_source, &far_target, &opts(&truth_far)).unwrap();
    let expected = shift * near.T_target_source * Matrix4::new_translation(&-Vector3::from(FAR));
    let (re, g) =
        (rotation_error_deg(&far.T_target_source, &expected), gap(&far.T_target_source, &expected, &far_source));
    assert!(re < 1e-3 && g < 1e-4, "{re} deg, points {g} apart");
    assert!(translation_error(&near.T_target_source, &truth) < 0.05);
    assert!(rotation_error_deg(&near.T_target_source, &truth) < 1.0);
}

#[test]
fn packed_f64_buffers_choose_an_origin_only_when_far() {
    let near = PointCloud::from_xyz_f64(&[0.0, 0.0, 0.0, 1.0, 2.0, 3.0]).unwrap();
    assert_eq!(near.origin, [0.0; 3]);
    assert_eq!(near.points, vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]);
    let far = PointCloud::from_xyz_f64(&[5e6, 4e6, 10.0, 5e6 + 1.25, 4e6 - 0.5, 10.0, f64::NAN, 0.0, 0.0]).unwrap();
    assert_eq!(far.origin, [5e6 + 0.625, 4e6 - 0.25, 10.0]);
    assert_eq!(far.points[0], [-0.625, 0.25, 0.0]);
    assert!(far.points[2][0].is_nan());
    assert_eq!(far.to_xyz_f64()[3..6], [5e6 + 1.25, 4e6 - 0.5, 10.0]);
    assert!(PointCloud::from_xyz_f64(&[1.0; 4]).is_err());
}

#[test]
fn clouds_in_different_frames_register_too() {
    // the source in map-grid coordinates, the target near zero: the network's start does not
    // depend on where the clouds sit, so the answer is the near one, moved by the source's offset
    let (source, target) = (fixture("source.ply"), fixture("target.ply"));
    let mut registrar = Registrar::with_default_model().unwrap();
    let near = registrar.register(&source, &target, &Options::default()).unwrap();
    let far_source = read_point_cloud(&double_ply(&source, FAR), "s.ply").unwrap();
    let far = registrar.register(&far_source, &target, &Options::default()).unwrap();
    let expected = near.T_target_source * Matrix4::new_translation(&-Vector3::from(FAR));
    let (re, g) =
        (rotation_error_deg(&far.T_target_source, &expected), gap(&far.T_target_source, &expected, &far_source));
    assert!(re < 1e-3 && g < 1e-4, "{re} deg, points {g} apart");
}
