//! Every reader on its committed real fixture (fixtures/formats, see LICENSES.md there).

use arps::io::{detect_format, read_mesh, read_point_cloud, read_point_cloud_with, Format, ReadOptions};
use arps::PointCloud;

fn fixture(name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/formats").join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn read(name: &str) -> PointCloud {
    read_point_cloud(&fixture(name), name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-6 * (1.0 + b[i].abs()))
}

fn finite_bounds(c: &PointCloud) -> ([f32; 3], [f32; 3]) {
    PointCloud::new(c.points.iter().copied().filter(|p| p.iter().all(|v| v.is_finite())).collect()).bounds()
}

#[test]
fn pcd_binary_compressed_milk() {
    let c = read("milk_compressed.pcd");
    assert_eq!(c.len(), 13704);
    assert!(close(c.points[0], [-0.131_607_6, -0.209_542_9, 0.772]));
    let (lo, hi) = c.bounds();
    assert!((lo[0] - -0.140_082_9).abs() < 1e-6 && (hi[0] - 0.013_806_67).abs() < 1e-6);
    assert!((lo[2] - 0.714).abs() < 1e-6 && (hi[2] - 0.891).abs() < 1e-6);
}

#[test]
fn pcd_organized_compressed_keeps_nan() {
    let c = read("table_scene_80x60_compressed.pcd");
    assert_eq!(c.len(), 80 * 60);
    let nan = c.points.iter().filter(|p| p.iter().any(|v| v.is_nan())).count();
    assert_eq!(nan, 1577);
    assert!(c.points[0].iter().all(|v| v.is_nan()));
    assert!(close(c.points[178], [-0.36877, -0.43496, 2.0228]));
    let (lo, hi) = finite_bounds(&c);
    assert!((lo[2] - 0.694_84).abs() < 1e-5 && (hi[2] - 2.5687).abs() < 1e-5);
    // Validation drops the "no return" points.
    let v = c.validated("target", 16, arps::NonFinite::Drop).unwrap();
    assert_eq!(v.len(), 4800 - 1577);
}

#[test]
fn pcd_binary_and_ascii_velodyne_agree() {
    let b = read("velodyne_2000_binary.pcd");
    let a = read("velodyne_2000_ascii.pcd");
    assert_eq!(b.len(), 2000);
    assert!(close(b.points[0], [0.003_139_891_7, 2.570_035, -1.524_156_8]));
    assert!(close(b.points[1999], [0.509_285_45, 2.785_830_7, 0.0]));
    assert_eq!(a, b, "ascii (9 significant digits) and binary give the same f32 values");
}

#[test]
fn pcd_binary_with_normals_and_rgb() {
    let c = read("cloud_bin_0_binary.pcd");
    assert_eq!(c.len(), 3903);
    assert!(close(c.points[0], [2.848_907_7, 0.031_390_607, -1.747_166]));
    assert!(close(c.points[3902], [2.832_442_3, 0.349_908_68, -1.441_496_7]));
}

#[test]
fn ply_binary_with_normals_colours_faces() {
    let name = "frag_115_2000_binary.ply";
    let c = read(name);
    assert_eq!(c.len(), 2000);
    assert!(close(c.points[0], [0.847_656_25, 2.679_497_7, 1.597_656_3]));
    assert!(close(c.points[1999], [0.957_031_25, 1.121_093_8, 1.315_260_6]));
    let (lo, hi) = c.bounds();
    assert!(close(lo, [0.839_843_75, 1.004_519_7, 1.308_593_8]) && close(hi, [0.957_031_25, 2.813_548, 1.608_872_4]));
    let m = read_mesh(&fixture(name), name).unwrap();
    assert_eq!(m.vertices, c.points);
    assert_eq!(m.triangles.len(), 3270);
}

#[test]
fn fuze_in_obj_binary_ply_and_ascii_ply() {
    let obj = read_mesh(&fixture("fuze.obj"), "fuze.obj").unwrap();
    let bin = read_mesh(&fixture("fuze_binary.ply"), "fuze_binary.ply").unwrap();
    let asc = read_mesh(&fixture("fuze_ascii.ply"), "fuze_ascii.ply").unwrap();
    for m in [&obj, &bin, &asc] {
        assert_eq!(m.vertices.len(), 502);
        assert_eq!(m.triangles.len(), 1000);
    }
    assert!(close(obj.vertices[0], [0.002_047, -0.002_871, 0.004_031]));
    assert_eq!(obj.vertices, bin.vertices);
    assert_eq!(obj.triangles, bin.triangles);
    assert_eq!(asc.vertices, bin.vertices);
    assert_eq!(asc.triangles, bin.triangles);
    assert!((obj.surface_area() - 0.0447).abs() < 1e-4);
}

#[test]
fn stl_binary_starting_with_solid_and_plain_binary() {
    let bytes = fixture("angle_block_binary_solid.stl");
    assert!(bytes.starts_with(b"solid"));
    assert_eq!(detect_format(&bytes, "no_extension").unwrap(), Format::Stl);
    let m = read_mesh(&bytes, "angle_block.STL").unwrap();
    assert_eq!(m.triangles.len(), 704);
    assert_eq!(m.vertices.len(), 398, "corners merged by position");
    let c = read("cylinder_binary.stl");
    assert_eq!(c.len(), 210);
    let m = read_mesh(&fixture("cylinder_binary.stl"), "cylinder_binary.stl").unwrap();
    assert_eq!(m.triangles.len(), 416);
}

#[test]
fn stl_ascii() {
    let name = "tray_bottom_150_ascii.stl";
    let m = read_mesh(&fixture(name), name).unwrap();
    assert_eq!(m.triangles.len(), 150);
    assert!(close(m.vertices[0], [101.8757, 3.175, -14.31162]));
    assert!(close(m.vertices[1], [101.6, 3.175, -14.2875]));
    assert_eq!(detect_format(&fixture(name), "x").unwrap(), Format::Stl);
}

#[test]
fn off_mesh() {
    let m = read_mesh(&fixture("ballA.off"), "ballA.off").unwrap();
    assert_eq!(m.vertices.len(), 1900);
    assert_eq!(m.triangles.len(), 3796);
    assert!(close(m.vertices[0], [-0.25829, -4.29578, 4.02524]));
    assert_eq!(read("ballA.off").len(), 1900);
}

#[test]
fn csv_with_header_row() {
    let c = read("eth_car_1000.csv");
    assert_eq!(c.len(), 1000);
    assert!(close(c.points[0], [-3.5376, 0.639553, -1.37678]));
    assert!(close(c.points[999], [-4.08528, 2.11434, -1.64961]));
    let (lo, hi) = c.bounds();
    assert!(close([lo[0], hi[0], lo[2]], [-51.5864, 0.015_841_9, -6.32885]) && (hi[2] - 10.9596).abs() < 1e-5);
}

#[test]
fn sniffing_without_extension_matches_extension() {
    for name in [
        "milk_compressed.pcd",
        "velodyne_2000_ascii.pcd",
        "frag_115_2000_binary.ply",
        "fuze_ascii.ply",
        "fuze.obj",
        "cylinder_binary.stl",
        "tray_bottom_150_ascii.stl",
        "ballA.off",
        "eth_car_1000.csv",
    ] {
        let bytes = fixture(name);
        let by_ext = detect_format(&bytes, name).unwrap();
        assert_eq!(detect_format(&bytes, "upload.bin").unwrap(), by_ext, "{name}");
        assert_eq!(read_point_cloud(&bytes, "upload").unwrap(), read(name), "{name}");
    }
}

/// A file saved under another format's extension is read as what its signature says (a PLY file
/// named `.txt`, an E57 file named `.ply`, ...); a file without one goes by its extension.
#[test]
fn a_signature_overrules_the_extension() {
    for (name, format, as_name) in [
        ("fuze_binary.ply", Format::Ply, "scan.txt"),
        ("fuze_ascii.ply", Format::Ply, "scan.pcd"),
        ("simple.laz", Format::Las, "points.xyz"),
        ("velodyne_two_scans.e57", Format::E57, "scan.ply"),
        ("velodyne_2000_ascii.pcd", Format::Pcd, "cloud.ply"),
        ("ballA.off", Format::Off, "ballA.xyz"),
    ] {
        let bytes = fixture(name);
        assert_eq!(detect_format(&bytes, as_name).unwrap(), format, "{name} as {as_name}");
        assert_eq!(read_point_cloud(&bytes, as_name).unwrap(), read(name), "{name} as {as_name}");
    }
    // without a signature the extension rules: an OBJ file named .xyz is taken for rows of numbers
    assert_eq!(detect_format(&fixture("fuze.obj"), "fuze.xyz").unwrap(), Format::Xyz);
}

#[test]
fn extensions_are_case_insensitive() {
    let cases = [
        ("a.PLY", Format::Ply),
        ("a.Pcd", Format::Pcd),
        ("a.XYZ", Format::Xyz),
        ("a.pts", Format::Xyz),
        ("a.TXT", Format::Xyz),
        ("a.csv", Format::Xyz),
        ("dir.v2/a.OBJ", Format::Obj),
        ("a.off", Format::Off),
        ("a.STL", Format::Stl),
    ];
    for (name, f) in cases {
        assert_eq!(detect_format(b"", name).unwrap(), f, "{name}");
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn read_path_uses_the_file_name() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/formats/ballA.off");
    assert_eq!(arps::io::read_path(&p).unwrap().len(), 1900);
    let err = arps::io::read_path(std::path::Path::new("/nonexistent/x.ply")).unwrap_err().to_string();
    assert!(err.contains("/nonexistent/x.ply"), "{err}");
}

/// A mesh read as its surface (`ReadOptions::surface_points`): that many points, drawn by the
/// mesh sampler (the same points as `Mesh::sample_surface` for the seed, other points for another
/// seed); a PLY with faces sampled too, one without and point files read as they are; counts out
/// of range are clear errors.
#[test]
fn a_mesh_read_as_its_sampled_surface() {
    let surface = |name: &str, n: usize, seed: u64| {
        read_point_cloud_with(
            &fixture(name),
            name,
            &ReadOptions { surface_points: Some(n), seed, scan: None, classes: None, min_opacity: None },
        )
    };
    let stl = "angle_block_binary_solid.stl";
    let s = surface(stl, 5000, 0).unwrap();
    assert_eq!(s.len(), 5000);
    let mesh = read_mesh(&fixture(stl), stl).unwrap();
    assert_eq!(s.points, mesh.sample_surface(5000, 0).unwrap().points, "the mesh sampler's points");
    assert_eq!(s.points, surface(stl, 5000, 0).unwrap().points, "deterministic");
    assert_ne!(s.points, surface(stl, 5000, 1).unwrap().points, "another seed, other points");
    assert_eq!(surface("fuze_binary.ply", 3000, 0).unwrap().len(), 3000, "a PLY with faces");
    for points_only in ["velodyne_2000_binary.pcd", "eth_car_1000.csv"] {
        assert_eq!(surface(points_only, 3000, 0).unwrap().points, read(points_only).points, "{points_only}");
    }
    let ply = std::fs::read(format!("{}/fixtures/wasm/source.ply", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let as_surface = read_point_cloud_with(
        &ply,
        "s.ply",
        &ReadOptions { surface_points: Some(3000), seed: 0, scan: None, classes: None, min_opacity: None },
    );
    assert_eq!(as_surface.unwrap().points, read_point_cloud(&ply, "s.ply").unwrap().points, "a PLY without faces");
    let few = surface(stl, 3, 0).unwrap_err().to_string();
    assert!(few.contains("surfacePoints = 3 is fewer than 16"), "{few}");
    // too many: the option says so, on a mesh and on a point file alike (not that the file holds them)
    for file in [stl, "velodyne_2000_binary.pcd"] {
        let many = surface(file, 20_000_000, 0).unwrap_err().to_string();
        assert!(many.contains("surfacePoints = 20000000 is more than the 16000000 points"), "{many}");
    }
}

/// Excel's and Notepad's "CSV UTF-8" start with a byte order mark: read past (the header's first
/// name is `y`, not `\u{feff}y`; a first row without a header is a point), written back in front
/// by `transform_file`; a UTF-16 file is refused by name.
#[test]
fn a_utf8_byte_order_mark_is_read_past_and_utf16_refused() {
    let bom = |text: &str| [&b"\xEF\xBB\xBF"[..], text.as_bytes()].concat();
    let swapped = read_point_cloud(&bom("y,x,z\n2,1,3\n5,4,6\n"), "survey.csv").unwrap();
    assert_eq!(swapped.points, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    let plain = read_point_cloud(&bom("1 2 3\n4 5 6\n"), "scan.xyz").unwrap();
    assert_eq!(plain.points, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    // a PLY or OBJ saved so too
    let ply = bom("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n");
    assert_eq!(read_point_cloud(&ply, "scan.ply").unwrap().point_f64(0), [1.0, 2.0, 3.0]);
    let moved = arps::io::transform_file(
        &bom("y,x,z\n2,1,3\n"),
        "survey.csv",
        &nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(10.0, 0.0, 0.0)),
    )
    .unwrap();
    assert!(moved.starts_with(b"\xEF\xBB\xBFy,x,z\n"), "{}", String::from_utf8_lossy(&moved));
    assert_eq!(read_point_cloud(&moved, "survey.csv").unwrap().point_f64(0), [11.0, 2.0, 3.0]);
    for utf16 in [&b"\xFF\xFEx\0 \0y\0"[..], b"\xFE\xFF\0x\0 \0y"] {
        let e = read_point_cloud(utf16, "survey.csv").unwrap_err().to_string();
        assert!(e.contains("UTF-16") && e.contains("save it as UTF-8"), "{e}");
    }
}
