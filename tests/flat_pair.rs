//! Two flat clouds (a plate, a tray's bottom): every normal is the plane's, so point-to-plane ICP
//! cannot move within the plane and the answer kept its start's error there; ICP runs
//! point-to-point on such a pair and recovers a known motion, from the file's vertices or its
//! surface.

use arps::io::{read_point_cloud_with, transform_file, ReadOptions};
use arps::transform::{from_rotation_translation, rotation_error_deg};
use arps::{Options, Registrar};
use nalgebra::{Rotation3, Vector3};

#[test]
#[allow(non_snake_case)]
fn a_flat_part_onto_its_moved_copy_is_recovered() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/formats/tray_bottom_150_ascii.stl");
    let bytes = std::fs::read(path).unwrap();
    let T_target_source = from_rotation_translation(
        &Rotation3::from_euler_angles(2.0, -0.7, 2.9).into_inner(),
        &Vector3::new(0.3, -1.7, 12.5),
    );
    let moved = transform_file(&bytes, "tray.stl", &T_target_source).unwrap();
    let mut reg = Registrar::with_default_model().unwrap();
    for surface_points in [None, Some(5_000)] {
        let read = ReadOptions { surface_points, ..Default::default() };
        let source = read_point_cloud_with(&bytes, "tray.stl", &read).unwrap();
        let target = read_point_cloud_with(&moved, "tray.stl", &read).unwrap();
        let r = reg.register(&source, &target, &Options::default()).unwrap();
        let err = rotation_error_deg(&r.T_target_source, &T_target_source);
        let shift = (r.T_target_source.fixed_view::<3, 1>(0, 3) - T_target_source.fixed_view::<3, 1>(0, 3)).norm();
        assert!(
            err < 0.1 && shift < 0.5,
            "{surface_points:?}: {err} degrees, {shift} off (half-extent {})",
            source.half_extent()
        );
        assert!(r.warnings.iter().any(|w| w.contains("ICP ran point-to-point")), "{:?}", r.warnings);
    }
}
