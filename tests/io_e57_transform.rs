//! `io::transform_file` on E57 files: the poses of the scans composed with the motion in the
//! XML, the points kept byte for byte. On the fixtures (two scans with poses on the map grid;
//! spherical coordinates): every scan reads back moved, alone and together, the file's binary
//! sections are the same bytes, the new XML is valid to the e57 crate (CRCs included); a change
//! of unit is refused. One scan alone (`transform_file_with` and `ReadOptions::scan`) is a file of
//! its own: that scan moved, its images' bytes kept, the others left out.

use arps::io::{read_point_cloud, read_point_cloud_with, transform_file, transform_file_with, ReadOptions};
mod common;
use common::format_fixture;
use nalgebra::{Matrix4, Rotation3, Vector3};

/// 30 degrees about a tilted axis, then a shift of the size of a map grid's.
fn motion() -> Matrix4<f64> {
    let r = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::new(0.2, 0.1, 1.0)), 30f64.to_radians());
    Matrix4::new_translation(&Vector3::new(-512000.0, -4123000.0, 10.0)) * r.to_homogeneous()
}

fn assert_moved(bytes: &[u8], moved: &[u8], options: &ReadOptions, m: &Matrix4<f64>) {
    assert_moved_as(bytes, options, moved, options, m);
}

/// The cloud `bytes` reads as with `options` is, moved by `m`, the one `moved` reads as with
/// `moved_options`.
fn assert_moved_as(bytes: &[u8], options: &ReadOptions, moved: &[u8], moved_options: &ReadOptions, m: &Matrix4<f64>) {
    let before = read_point_cloud_with(bytes, "a.e57", options).unwrap();
    let after = read_point_cloud_with(moved, "a.e57", moved_options).unwrap();
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

fn scan(k: usize) -> ReadOptions {
    ReadOptions { scan: Some(k), ..ReadOptions::default() }
}

#[test]
fn one_scan_alone_is_a_file_of_its_own() {
    let m = motion();
    let bytes = format_fixture("velodyne_two_scans.e57");
    let all = arps::io::list_scans(&bytes, "two.e57").unwrap();
    for (k, info) in all.iter().enumerate() {
        let moved = transform_file_with(&bytes, "two.e57", &m, &scan(k)).unwrap();
        assert_eq!(arps::io::list_scans(&moved, "two.e57").unwrap(), vec![info.clone()]);
        assert_moved_as(&bytes, &scan(k), &moved, &ReadOptions::default(), &m);
        assert!(moved.len() < bytes.len() && moved.len().is_multiple_of(1024), "{} bytes", moved.len());
    }
    // a file of one scan (spherical coordinates), that scan
    let tiny = format_fixture("tiny_spherical.e57");
    let moved = transform_file_with(&tiny, "tiny.e57", &m, &scan(0)).unwrap();
    assert_moved_as(&tiny, &ReadOptions::default(), &moved, &ReadOptions::default(), &m);
    // a scan beyond the file's; the option is for E57 files (a file of one cloud refuses it)
    let e = transform_file_with(&bytes, "two.e57", &m, &scan(2)).unwrap_err().to_string();
    assert!(e.contains("scan = 2, but the E57 file holds 2 scans (0 to 1)"), "{e}");
    // (a float PCD moved near zero: moved onto the map grid, float would round it, refused)
    let (pcd, near) = (common::format_fixture("cloud_bin_0_binary.pcd"), common::tilted_motion());
    let e = transform_file_with(&pcd, "a.pcd", &near, &scan(3)).unwrap_err().to_string();
    assert!(e.contains("the scan option (3) chooses among an E57 file's scans; a PCD file holds one cloud"), "{e}");
    assert!(
        transform_file_with(&pcd, "a.pcd", &near, &ReadOptions::default()).unwrap()
            == transform_file(&pcd, "a.pcd", &near).unwrap()
    );
}

/// An E57 file written by the e57 crate: two scans of `n` points each (x, y, z as doubles), each
/// with a pinhole image (PNG bytes standing in, with a mask) associated with it, and a third
/// image of no scan.
fn scans_with_images(n: usize) -> Vec<u8> {
    use e57::{E57Writer, ImageFormat, PinholeImageProperties, Record, RecordValue};
    let mut file = std::io::Cursor::new(Vec::new());
    let mut writer = E57Writer::new(&mut file, "{file}").unwrap();
    for (k, guid) in ["{scan-a}", "{scan-b}"].into_iter().enumerate() {
        let prototype = vec![Record::CARTESIAN_X_F64, Record::CARTESIAN_Y_F64, Record::CARTESIAN_Z_F64];
        let mut pc = writer.add_pointcloud(guid, prototype).unwrap();
        for i in 0..n {
            let t = i as f64 * 0.01 + k as f64;
            pc.add_point(vec![
                RecordValue::Double(t.sin()),
                RecordValue::Double(t.cos() * 2.0),
                RecordValue::Double(t * 0.1),
            ])
            .unwrap();
        }
        pc.finalize().unwrap();
    }
    for (guid, scan) in [("{image-a}", Some("{scan-a}")), ("{image-b}", Some("{scan-b}")), ("{image-c}", None)] {
        let mut image = writer.add_image(guid).unwrap();
        if let Some(scan) = scan {
            image.set_pointcloud_guid(scan);
        }
        let pixels: Vec<u8> = (0..3000u32).map(|i| (i * 7 + guid.len() as u32) as u8).collect();
        let mask: Vec<u8> = (0..1500u32).map(|i| (i * 3) as u8).collect();
        let properties = PinholeImageProperties {
            width: 10,
            height: 10,
            focal_length: 0.01,
            pixel_width: 0.001,
            pixel_height: 0.001,
            principal_x: 5.0,
            principal_y: 5.0,
        };
        image.add_pinhole(ImageFormat::Png, &mut pixels.as_slice(), properties, Some(&mut mask.as_slice())).unwrap();
        image.finalize().unwrap();
    }
    writer.finalize().unwrap();
    drop(writer);
    file.into_inner()
}

/// An image of an E57 file: its guid, scan, pose and its blobs' bytes (image, mask).
type ImageParts = (Option<String>, Option<String>, Option<e57::Transform>, Vec<Vec<u8>>);

/// Each image of an E57 file.
fn images(bytes: &[u8]) -> Vec<ImageParts> {
    let mut reader = e57::E57Reader::new(std::io::Cursor::new(bytes)).unwrap();
    let mut out = Vec::new();
    for image in reader.images() {
        let Some(e57::Projection::Pinhole(p)) = &image.projection else { panic!("a pinhole image") };
        let mut blobs = Vec::new();
        for blob in [Some(&p.blob.data), p.mask.as_ref()].into_iter().flatten() {
            let mut data = Vec::new();
            reader.blob(blob, &mut data).unwrap();
            blobs.push(data);
        }
        out.push((image.guid.clone(), image.pointcloud_guid.clone(), image.transform.clone(), blobs));
    }
    out
}

#[test]
fn one_scan_alone_keeps_its_images() {
    // scans large enough to span several pages, with images between and after them
    let m = motion();
    let bytes = scans_with_images(2000);
    let before = images(&bytes);
    assert_eq!(before.len(), 3);
    for (k, own) in before.iter().enumerate().take(2) {
        let moved = transform_file_with(&bytes, "a.e57", &m, &scan(k)).unwrap();
        assert_moved_as(&bytes, &scan(k), &moved, &ReadOptions::default(), &m);
        let after = images(&moved);
        // the scan's own image alone, its bytes and mask as they were, its pose moved
        assert_eq!(after.len(), 1, "scan {k}");
        let (guid, pc, pose, blobs) = &after[0];
        assert_eq!((guid, pc, blobs), (&own.0, &own.1, &own.3), "scan {k}");
        let t = pose.as_ref().expect("a pose").translation.clone();
        assert!((t.x - m[(0, 3)]).abs() < 1e-6 && (t.y - m[(1, 3)]).abs() < 1e-6 && (t.z - m[(2, 3)]).abs() < 1e-6);
        assert!(moved.len() < bytes.len());
    }
}
