//! `io::transform_file` on E57 files: the poses of the scans composed with the motion in the
//! XML, the points kept byte for byte. On the fixtures (two scans with poses on the map grid;
//! spherical coordinates): every scan reads back moved, alone and together, the file's binary
//! sections are the same bytes, the new XML is valid to the e57 crate (CRCs included); a change
//! of unit is refused.

use arps::io::{read_point_cloud, read_point_cloud_with, transform_file, ReadOptions};
mod common;
use common::format_fixture;
use nalgebra::{Matrix4, Rotation3, Vector3};

/// 30 degrees about a tilted axis, then a shift of the size of a map grid's.
fn motion() -> Matrix4<f64> {
    let r = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::new(0.2, 0.1, 1.0)), 30f64.to_radians());
    Matrix4::new_translation(&Vector3::new(-512000.0, -4123000.0, 10.0)) * r.to_homogeneous()
}

fn assert_moved(bytes: &[u8], moved: &[u8], options: &ReadOptions, m: &Matrix4<f64>) {
    let before = read_point_cloud_with(bytes, "a.e57", options).unwrap();
    let after = read_point_cloud_with(moved, "a.e57", options).unwrap();
    assert_eq!(before.len(), after.len());
    let mut worst = 0f64;
    for i in 0..before.len() {
        let want = m.transform_point(&nalgebra::Point3::from(before.point_f64(i)));
        let got = after.point_f64(i);
        worst = (0..3).map(|k| (got[k] - want[k]).abs()).fold(worst, f64::max);
    }
    // f32 offsets beside each cloud's origin, on both sides
    assert!(worst < 1e-3, "{options:?}: up to {worst} from the points moved in f64");
}

#[test]
fn scans_move_by_their_poses_and_their_points_stay_as_stored() {
    let m = motion();
    for name in ["velodyne_two_scans.e57", "tiny_spherical.e57"] {
        let bytes = format_fixture(name);
        let moved = transform_file(&bytes, name, &m).unwrap();
        assert_moved(&bytes, &moved, &ReadOptions::default(), &m);
        // the pages after the first (the points' binary sections, the old XML) are the same bytes
        assert_eq!(moved[1024..bytes.len()], bytes[1024..], "{name}");
        assert_eq!(moved.len() % 1024, 0);
        // moved back: the points where they were
        let back = transform_file(&moved, name, &m.try_inverse().unwrap()).unwrap();
        assert_moved(&bytes, &back, &ReadOptions::default(), &Matrix4::identity());
    }
    let bytes = format_fixture("velodyne_two_scans.e57");
    let moved = transform_file(&bytes, "two.e57", &m).unwrap();
    for k in 0..2 {
        assert_moved(&bytes, &moved, &ReadOptions { scan: Some(k), ..ReadOptions::default() }, &m);
    }
    assert_eq!(arps::io::list_scans(&moved, "two.e57").unwrap(), arps::io::list_scans(&bytes, "two.e57").unwrap());
    assert!(read_point_cloud(&moved, "two.e57").is_ok());
}

#[test]
fn a_change_of_unit_and_broken_files_are_refused() {
    let bytes = format_fixture("velodyne_two_scans.e57");
    let e = transform_file(&bytes, "two.e57", &(motion() * Matrix4::new_scaling(1000.0))).unwrap_err().to_string();
    assert!(e.contains("poses are rigid") && e.contains("x1000"), "{e}");
    let e = transform_file(&bytes[..bytes.len() - 1024], "two.e57", &motion()).unwrap_err().to_string();
    assert!(e.contains("E57"), "{e}");
    assert!(arps::io::can_transform("scan.E57"));
}
