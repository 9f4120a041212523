//! `io::transform_file` keeps the moved positions' precision: a `float` PLY moved onto a map grid
//! gets `double` positions; a `float` PCD or STL that cannot hold them is refused; a text file
//! written with few decimals (or C's `%g`) gets the digits its moved values need; and a matrix
//! within the rigid tolerance maps the points where it puts them, not about a snapped rotation.

use arps::io::{read_point_cloud, transform_file};
mod common;
use common::apply;
use nalgebra::{Matrix4, Rotation3, Vector3};

/// A local scan placed on a map grid: turned 30 degrees about z, then moved 5.4e6 away.
fn onto_map() -> Matrix4<f64> {
    Matrix4::new_translation(&Vector3::new(512_345.25, 5_412_345.5, 250.0))
        * Rotation3::from_axis_angle(&Vector3::z_axis(), 30f64.to_radians()).to_homogeneous()
}

/// Eight points of a 2 x 1.5 x 1 box near zero (local scanner coordinates).
fn box_points() -> Vec<[f64; 3]> {
    (0..8).map(|k| [(k & 1) as f64 * 2.0 - 1.0, ((k >> 1) & 1) as f64 * 1.5 - 0.75, ((k >> 2) & 1) as f64]).collect()
}

/// Asserts that `moved` reads (as `name`) as `points` moved by `m`, to `tol`.
fn assert_moved(moved: &[u8], name: &str, points: &[[f64; 3]], m: &Matrix4<f64>, tol: f64) {
    let after = read_point_cloud(moved, name).unwrap();
    assert_eq!(after.len(), points.len(), "{name}");
    for (i, p) in points.iter().enumerate() {
        let (want, got) = (apply(m, *p), after.point_f64(i));
        assert!((0..3).all(|k| (got[k] - want[k]).abs() <= tol), "{name} point {i}: {got:?} vs {want:?}");
    }
}

fn binary_ply(points: &[[f64; 3]]) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment local scan\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nend_header\n",
        points.len()
    );
    let mut bytes = header.into_bytes();
    for (i, p) in points.iter().enumerate() {
        p.iter().for_each(|v| bytes.extend_from_slice(&(*v as f32).to_le_bytes()));
        bytes.push(10 * i as u8);
    }
    bytes
}

#[test]
fn a_float_ply_moved_onto_a_map_grid_gets_double_positions_and_keeps_the_rest() {
    let (points, m) = (box_points(), onto_map());
    let moved = transform_file(&binary_ply(&points), "scan.ply", &m).unwrap();
    let text = String::from_utf8_lossy(&moved[..200]).to_string();
    assert!(text.contains("property double x\nproperty double y\nproperty double z\nproperty uchar red\n"), "{text}");
    assert!(text.contains("comment local scan\n"), "{text}");
    assert_moved(&moved, "scan.ply", &points, &m, 1e-6);
    // each record: three doubles and the colour byte, as it was
    let body = &moved[moved.windows(11).position(|w| w == b"end_header\n").unwrap() + 11..];
    assert_eq!(body.len(), 8 * 25);
    assert!(body.chunks(25).enumerate().all(|(i, r)| r[24] == 10 * i as u8));
    // ASCII: the header's types and the values' digits alike
    let ascii: String = format!(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float32 x\nproperty float32 y\nproperty float32 z\nend_header\n{}",
        points.iter().map(|p| format!("{} {} {}\n", p[0], p[1], p[2])).collect::<String>()
    );
    let moved = transform_file(ascii.as_bytes(), "scan.ply", &m).unwrap();
    assert!(String::from_utf8_lossy(&moved).contains("property float64 x\n"));
    assert_moved(&moved, "scan.ply", &points, &m, 1e-6);
    // moved near zero, float holds it: the file stays float, byte for byte in size
    let near = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.5).to_homogeneous();
    let bytes = binary_ply(&points);
    let moved = transform_file(&bytes, "scan.ply", &near).unwrap();
    assert_eq!(moved.len(), bytes.len());
    assert_moved(&moved, "scan.ply", &points, &near, 1e-6);
}

#[test]
fn a_float_ply_scaled_onto_plant_millimetres_keeps_its_own_precision() {
    // a 2 m scan in metres, scaled by 1000 onto a plant model in millimetres 2.4e6 from zero:
    // float would hold it to 0.25 mm there (1/8000 of its size, within the engine's warning rule),
    // 500 times more coarsely than the file held it
    let (points, scaled) = (box_points(), Matrix4::new_translation(&Vector3::new(2_432_342.0, 1_187_386.0, 1_500.0)));
    let m = scaled * Matrix4::new_scaling(1000.0);
    let moved = transform_file(&binary_ply(&points), "scan.ply", &m).unwrap();
    assert!(String::from_utf8_lossy(&moved[..200]).contains(
        "property double x
"
    ));
    assert_moved(&moved, "scan.ply", &points, &m, 1e-6);
    // the same scan moved 10 m from zero in its own metres: float holds it about as finely as the
    // file did (1e-6 m), and the file stays float
    let ten = Matrix4::new_translation(&Vector3::new(10.0, -4.0, 1.0));
    let bytes = binary_ply(&points);
    let moved = transform_file(&bytes, "scan.ply", &ten).unwrap();
    assert_eq!(moved.len(), bytes.len());
    assert_moved(&moved, "scan.ply", &points, &ten, 2e-6);
}

#[test]
fn a_float_pcd_moved_onto_a_map_grid_gets_double_coordinates_and_a_float_stl_is_refused() {
    let points = box_points();
    let head = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 8\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 8\nDATA binary\n";
    let mut pcd = head.as_bytes().to_vec();
    points.iter().flatten().for_each(|v| pcd.extend_from_slice(&(*v as f32).to_le_bytes()));
    pcd.extend_from_slice(b"trailing bytes");
    let moved = transform_file(&pcd, "scan.pcd", &onto_map()).unwrap();
    assert_eq!(String::from_utf8_lossy(&moved[..head.len()]), head.replace("SIZE 4 4 4", "SIZE 8 8 8"));
    assert_eq!(moved.len(), pcd.len() + 8 * 12, "12 bytes more per point");
    assert!(moved.ends_with(b"trailing bytes"));
    assert_moved(&moved, "scan.pcd", &points, &onto_map(), 1e-6);
    // moved 10 m from zero, float holds it as finely as the file did: the file stays float
    let ten = Matrix4::new_translation(&Vector3::new(10.0, -4.0, 1.0));
    assert_eq!(transform_file(&pcd, "scan.pcd", &ten).unwrap().len(), pcd.len());
    // the real files: every other field kept (colour, normals turned), holes kept, compressed again
    for name in
        ["cloud_bin_0_binary.pcd", "milk_compressed.pcd", "table_scene_80x60_compressed.pcd", "velodyne_2000_ascii.pcd"]
    {
        let bytes = std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/formats").join(name))
            .unwrap();
        let before = read_point_cloud(&bytes, name).unwrap();
        let moved = transform_file(&bytes, name, &onto_map()).unwrap();
        assert!(String::from_utf8_lossy(&moved[..400]).contains("SIZE 8 8 8"), "{name}");
        let after = read_point_cloud(&moved, name).unwrap();
        assert_eq!(after.len(), before.len());
        for i in 0..before.len() {
            let (p, q) = (before.point_f64(i), after.point_f64(i));
            if !p.iter().all(|v| v.is_finite()) {
                assert!(q.iter().all(|v| v.is_nan()), "{name}: a hole stays a hole");
                continue;
            }
            let want = apply(&onto_map(), p);
            // (the ascii file's values as it wrote them: to its own decimals)
            let tol = if name.contains("ascii") { 1e-3 } else { 1e-6 };
            assert!((0..3).all(|k| (q[k] - want[k]).abs() < tol), "{name} point {i}: {q:?} vs {want:?}");
        }
        if name == "cloud_bin_0_binary.pcd" {
            // x y z normal_x normal_y normal_z rgb, 28 bytes a record, then 40: the colours
            // kept, the normals turned
            let (old, new) = (bytes.len() - 3903 * 28, moved.len() - 3903 * 40);
            let turn = onto_map().fixed_view::<3, 3>(0, 0).into_owned();
            let f = |b: &[u8], at: usize| f32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as f64;
            for i in 0..3903 {
                let (r, w) = (old + 28 * i, new + 40 * i);
                assert_eq!(bytes[r + 24..r + 28], moved[w + 36..w + 40], "point {i}'s colour");
                let n = turn * Vector3::new(f(&bytes, r + 12), f(&bytes, r + 16), f(&bytes, r + 20));
                assert!((0..3).all(|k| (f(&moved, w + 24 + 4 * k) - n[k]).abs() < 1e-6), "point {i}'s normal");
            }
        }
    }
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&1u32.to_le_bytes());
    for v in [[0.0, 0.0, 1.0], points[0], points[1], points[2]] {
        v.iter().for_each(|x| stl.extend_from_slice(&(*x as f32).to_le_bytes()));
    }
    stl.extend_from_slice(&[0, 0]);
    let e = transform_file(&stl, "part.stl", &onto_map()).unwrap_err().to_string();
    assert!(e.starts_with("binary STL file cannot be moved as it is: the transform moves its points up to"), "{e}");
}

#[test]
fn text_written_with_few_digits_gets_those_its_moved_values_need() {
    // a CAD cube in one decimal: turned, its corners leave that grid
    let cube = "OFF\n8 0 0\n0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n1.0 1.0 0.0\n0.0 0.0 1.0\n1.0 0.0 1.0\n0.0 1.0 1.0\n1.0 1.0 1.0\n";
    let m = Rotation3::from_euler_angles(0.4, -0.7, 1.1).to_homogeneous();
    let moved = transform_file(cube.as_bytes(), "cube.off", &m).unwrap();
    let corners: Vec<[f64; 3]> =
        (0..8).map(|k| [(k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64]).collect();
    // to 0.001 of the diagonal (half a step of three decimals), where one decimal was 0.05 off
    assert_moved(&moved, "cube.off", &corners, &m, 5e-4 + 1e-12);
    // C's %g with six significant digits, moved onto the map grid: 1 m steps there, so more digits
    let g = "0.5 0.25 1\n-1.5 0.75 2.5e-05\n1.25 -0.5 0.125\n";
    let points = [[0.5, 0.25, 1.0], [-1.5, 0.75, 2.5e-5], [1.25, -0.5, 0.125]];
    let moved = transform_file(g.as_bytes(), "scan.xyz", &onto_map()).unwrap();
    let diagonal = (2.75f64.powi(2) + 1.25f64.powi(2) + 1.0f64.powi(2)).sqrt();
    assert_moved(&moved, "scan.xyz", &points, &onto_map(), diagonal * 1e-3);
    // exponent form (`%.3e`), moved to 1.2e6: the last significant digit reaches the step (0.1% of
    // the diagonal) there, so each value is within half a step
    let e = "1.000e+00 2.000e+00 5.000e-01\n-3.000e+00 1.500e+00 2.500e+00\n4.000e+00 -2.500e+00 1.000e-01\n";
    let points = [[1.0, 2.0, 0.5], [-3.0, 1.5, 2.5], [4.0, -2.5, 0.1]];
    let far = Matrix4::new_translation(&Vector3::new(1.2e6, 0.0, 0.0));
    let moved = transform_file(e.as_bytes(), "scan.xyz", &far).unwrap();
    let diagonal = (7.0f64.powi(2) + 4.5f64.powi(2) + 2.4f64.powi(2)).sqrt();
    assert_moved(&moved, "scan.xyz", &points, &far, diagonal * 1e-3 / 2.0 + 1e-9);
}

#[test]
fn a_nearly_rigid_matrix_maps_points_where_it_puts_them() {
    // the map grid's scale factor (0.9996) and a rotation written with four decimals: within the
    // rigid tolerance, and applied as given, not snapped about the frame's origin 5.4e6 away
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 20f64.to_radians()).into_inner();
    let rounded = r.map(|v| (v * 1e4).round() / 1e4);
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&(rounded * 0.9996));
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::new(-2000.0, 1500.0, 3.0));
    let survey = "Easting,Northing,Elevation\n512345.125,5412345.250,250.500\n512355.750,5412340.125,251.250\n512350.000,5412352.500,249.750\n";
    let points = [[512345.125, 5412345.25, 250.5], [512355.75, 5412340.125, 251.25], [512350.0, 5412352.5, 249.75]];
    let moved = transform_file(survey.as_bytes(), "survey.csv", &m).unwrap();
    assert_moved(&moved, "survey.csv", &points, &m, 5e-4 + 1e-9);
}

#[test]
fn one_point_a_file_already_on_the_grid_and_double_axes_are_judged_as_they_are() {
    // one point moved onto the map grid: float cannot hold it as the file did (0.1 there)
    let one = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0.1 0.2 0.3\n";
    let m = onto_map();
    let moved = transform_file(one.as_bytes(), "one.ply", &m).unwrap();
    assert!(String::from_utf8_lossy(&moved).contains("property double y\n"));
    assert_moved(&moved, "one.ply", &[[0.1, 0.2, 0.3]], &m, 1e-6);
    // a float PCD already on the grid, moved by a metre: float holds it as the file did
    let on_grid: Vec<[f64; 3]> = box_points().iter().map(|p| apply(&m, *p)).collect();
    let header = |sizes: &str, types: &str| {
        format!(
            "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE {sizes}\nTYPE {types}\nCOUNT 1 1 1\nWIDTH 8\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 8\nDATA binary\n"
        )
        .into_bytes()
    };
    let mut pcd = header("4 4 4", "F F F");
    on_grid.iter().flatten().for_each(|v| pcd.extend_from_slice(&(*v as f32).to_le_bytes()));
    let step = Matrix4::new_translation(&Vector3::new(1.0, 0.0, 0.0));
    let moved = transform_file(&pcd, "grid.pcd", &step).unwrap();
    assert_eq!(moved.len(), pcd.len());
    // x a double, y and z floats near zero: moved far along x only, it fits
    let mut mixed = header("8 4 4", "F F F");
    for p in box_points() {
        mixed.extend_from_slice(&p[0].to_le_bytes());
        mixed.extend_from_slice(&(p[1] as f32).to_le_bytes());
        mixed.extend_from_slice(&(p[2] as f32).to_le_bytes());
    }
    let along_x = Matrix4::new_translation(&Vector3::new(5e6, 0.0, 0.0));
    let moved = transform_file(&mixed, "mixed.pcd", &along_x).unwrap();
    assert_moved(&moved, "mixed.pcd", &box_points(), &along_x, 1e-6);
}

#[test]
fn a_ply_widens_its_vertex_positions_by_index_whatever_their_lines_hold() {
    // a property line with an extra word, a comment naming a property, another element with x
    let points = box_points();
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\ncomment property float x\nelement camera 1\nproperty float x\nelement vertex {}\nproperty float x extra\nproperty float y\nproperty float z\nend_header\n",
        points.len()
    )
    .into_bytes();
    bytes.extend_from_slice(&7.5f32.to_le_bytes());
    points.iter().flatten().for_each(|v| bytes.extend_from_slice(&(*v as f32).to_le_bytes()));
    let m = onto_map();
    let moved = transform_file(&bytes, "scan.ply", &m).unwrap();
    let text = String::from_utf8_lossy(&moved[..260]).to_string();
    assert!(
        text.contains("comment property float x\nelement camera 1\nproperty float x\nelement vertex 8\nproperty double x extra\nproperty double y\nproperty double z\n"),
        "{text}"
    );
    assert_moved(&moved, "scan.ply", &points, &m, 1e-6);
}

#[test]
fn an_e57_file_refuses_a_matrix_its_rigid_poses_would_apply_elsewhere() {
    let e57 = common::format_fixture("velodyne_two_scans.e57");
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), 20f64.to_radians()).into_inner();
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r.map(|v| (v * 1e4).round() / 1e4));
    let e = transform_file(&e57, "two.e57", &m).unwrap_err().to_string();
    assert!(
        e.contains("an E57 file's poses are rigid: this matrix is") && e.contains("save the points instead"),
        "{e}"
    );
    // the exact rotation is stored as a pose
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    assert!(transform_file(&e57, "two.e57", &m).is_ok());
}
