//! E57 on real files (fixtures/formats, see LICENSES.md there): two scans with poses written by
//! libE57Format read back in the file's frame (map-grid coordinates), and listed by name,
//! spherical coordinates
//! converted and invalid points left out, and hostile files giving errors.

use arps::io::{detect_format, list_scans, read_point_cloud, read_point_cloud_with, Format, ReadOptions, ScanInfo};
use arps::PointCloud;

fn fixture(dir: &str, name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures").join(dir).join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn read(name: &str) -> PointCloud {
    read_point_cloud(&fixture("formats", name), name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Where `make_e57.py` placed the Velodyne scan's points before storing them in two scanner frames.
const SHIFT: [f64; 3] = [512345.5, 4123456.25, 87.0];

#[test]
fn two_scans_with_poses_come_back_in_the_files_frame() {
    let name = "velodyne_two_scans.e57";
    let c = read(name);
    assert_eq!(c.len(), 2000);
    assert!(!c.origin_is_zero(), "map-grid coordinates get an origin near the points: {:?}", c.origin);
    // the points as they were before each scan's inverse pose stored them (the first 2,000 of
    // the Velodyne fixture, shifted onto the map grid); f32 offsets from the origin, to a millimetre
    let ply = read_point_cloud(&fixture("scans", "velodyne-small.ply"), "velodyne-small.ply").unwrap();
    let worst = (0..2000)
        .map(|i| {
            let (p, q) = (c.point_f64(i), ply.point_f64(i));
            (0..3).map(|k| (p[k] - (q[k] + SHIFT[k])).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-3, "{worst}");
    assert_eq!(detect_format(&fixture("formats", name), "upload").unwrap(), Format::E57);
    assert_eq!(read_point_cloud(&fixture("formats", name), "upload").unwrap(), c, "sniffed");
}

#[test]
fn one_scan_of_several_is_read_alone_and_a_scan_beyond_them_is_an_error() {
    let name = "velodyne_two_scans.e57";
    let bytes = fixture("formats", name);
    let all = read(name);
    let one = |k: usize| read_point_cloud_with(&bytes, name, &ReadOptions { scan: Some(k), ..ReadOptions::default() });
    for k in 0..2 {
        // the second scan alone: the Velodyne points 1000-1999, placed by its own pose
        let c = one(k).unwrap();
        assert_eq!(c.len(), 1000);
        let worst = (0..1000)
            .map(|i| (0..3).map(|a| (c.point_f64(i)[a] - all.point_f64(1000 * k + i)[a]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        assert!(worst < 1e-3, "scan {k}: {worst}");
    }
    let e = one(2).unwrap_err().to_string();
    assert!(e.contains("scan = 2, but the E57 file holds 2 scans (0 to 1)"), "{e}");
    // the scans listed, by name and record count, without decoding a point
    let scans = list_scans(&bytes, name).unwrap();
    let named = |k: usize| ScanInfo { name: Some(format!("scan {k}")), records: 1000 };
    assert_eq!(scans, vec![named(1), named(2)]);
    assert!(list_scans(&bytes[..bytes.len() / 2], name).is_err(), "half a file");
    assert_eq!(list_scans(&fixture("scans", "velodyne-small.ply"), "v.ply").unwrap(), vec![], "one cloud");
    // a file of another format holds one cloud: a scan chosen in it is refused, read and moved
    let ply = fixture("scans", "velodyne-small.ply");
    for k in [0, 5] {
        let options = ReadOptions { scan: Some(k), ..ReadOptions::default() };
        let e = read_point_cloud_with(&ply, "v.ply", &options).unwrap_err().to_string();
        assert!(e.contains(&format!("the scan option ({k})")) && e.contains("a PLY file holds one cloud"), "{e}");
        let moved = arps::io::transform_file_with(&ply, "v.ply", &nalgebra::Matrix4::identity(), &options);
        assert_eq!(moved.unwrap_err().to_string(), e);
    }
    let unset = read_point_cloud_with(&ply, "v.ply", &ReadOptions::default());
    assert_eq!(unset.unwrap(), read_point_cloud(&ply, "v.ply").unwrap());
}

#[test]
fn spherical_coordinates_are_converted_and_invalid_points_left_out() {
    // 360 points at range 1, azimuth = elevation = i * 3.14 / 360 (the generator's step, about half a
    // degree); every odd one is marked a direction without a range
    let c = read("tiny_spherical.e57");
    assert_eq!(c.len(), 180);
    for k in 0..180 {
        #[allow(clippy::approx_constant)] // the generator's own 3.14, not pi
        let a = (2 * k) as f64 * 3.14 / 360.0;
        let want = [a.cos() * a.cos(), a.cos() * a.sin(), a.sin()];
        let p = c.point_f64(k);
        assert!((0..3).all(|i| (p[i] - want[i]).abs() < 1e-6), "point {k}: {p:?}, want {want:?}");
    }
}

#[test]
fn hostile_files_give_errors() {
    let e57 = fixture("formats", "velodyne_two_scans.e57");
    let err = |b: &[u8]| read_point_cloud(b, "a.e57").err().map(|e| e.to_string()).expect("an error");
    let m = err(&e57[..e57.len() - 1024]);
    assert!(m.contains("E57") && m.contains("cannot be read"), "{m}");
    let mut b = e57.clone();
    b[0] = b'X';
    assert!(err(&b).contains("signature"), "{}", err(&b));
    // a flipped byte in the point data: the page's checksum says so
    let mut b = e57.clone();
    b[3000] ^= 0x55;
    let m = err(&b);
    assert!(m.to_lowercase().contains("checksum") || m.contains("CRC"), "{m}");
    // every prefix: an error or the points, never a panic
    for end in (0..e57.len()).step_by(131) {
        let _ = read_point_cloud(&e57[..end], "a.e57");
    }
}
