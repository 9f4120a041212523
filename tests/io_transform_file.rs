//! `io::transform_file`: a file moved as it is, in its own format. On the real fixtures of every
//! format it moves (PCD ascii, binary and binary_compressed; a CSV with normals; OBJ; binary and
//! ASCII STL) and on made text lists (a survey's named columns far from zero, PTS, CRLF, colours,
//! unnamed normals, a change of unit): the points read back are the transform of the file's own,
//! normals are turned, every other byte is kept, and what cannot be moved is refused with a
//! message.

use arps::io::{can_transform, read_mesh, read_point_cloud, transform_file, transform_las, transform_ply};
mod common;
use common::{apply, format_fixture, tilted_motion};
use nalgebra::{Matrix3, Matrix4, Rotation3, Vector3};

fn rotation(m: &Matrix4<f64>) -> Matrix3<f64> {
    m.fixed_view::<3, 3>(0, 0).into_owned()
}

/// Asserts that the file `moved` reads as the points of `bytes` moved by `m`, to `tol`.
fn assert_points_moved(bytes: &[u8], moved: &[u8], name: &str, m: &Matrix4<f64>, tol: f64) {
    let (before, after) = (read_point_cloud(bytes, name).unwrap(), read_point_cloud(moved, name).unwrap());
    assert_eq!(before.len(), after.len(), "{name}");
    let mut finite = 0;
    for i in 0..before.len() {
        let p = before.point_f64(i);
        if !p.iter().all(|v| v.is_finite()) {
            assert!(after.point_f64(i).iter().all(|v| v.is_nan()), "{name}: a hole stays a hole");
            continue;
        }
        finite += 1;
        let (want, got) = (apply(m, p), after.point_f64(i));
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < tol, "{name}: point {i} axis {k}: {} vs {}", got[k], want[k]);
        }
    }
    assert!(finite > 0, "{name}");
}

/// The text of the header up to and including its `DATA` line.
fn pcd_header(bytes: &[u8]) -> &[u8] {
    let at = bytes.windows(5).position(|w| w == b"DATA ").unwrap();
    let end = at + bytes[at..].iter().position(|&b| b == b'\n').unwrap() + 1;
    &bytes[..end]
}

#[test]
fn pcd_files_move_in_every_encoding() {
    let m = tilted_motion();
    for name in [
        "velodyne_2000_ascii.pcd",
        "velodyne_2000_binary.pcd",
        "cloud_bin_0_binary.pcd",
        "milk_compressed.pcd",
        "table_scene_80x60_compressed.pcd",
    ] {
        let bytes = format_fixture(name);
        let moved = transform_file(&bytes, name, &m).unwrap();
        assert_eq!(pcd_header(&moved), pcd_header(&bytes), "{name}: the header is kept");
        assert_points_moved(&bytes, &moved, name, &m, 1e-4);
    }
    // Binary records: the coordinates (and normals) rewritten, the other fields kept byte for byte.
    let bytes = format_fixture("velodyne_2000_binary.pcd");
    let moved = transform_file(&bytes, "v.pcd", &m).unwrap();
    let body = pcd_header(&bytes).len();
    assert_eq!(moved.len(), bytes.len());
    for i in 0..2000 {
        let at = body + 16 * i + 12;
        assert_eq!(moved[at..at + 4], bytes[at..at + 4], "intensity of point {i}");
    }
    // cloud_bin_0: x y z normal_x normal_y normal_z rgb, all 4-byte: normals turned, colours kept.
    let bytes = format_fixture("cloud_bin_0_binary.pcd");
    let moved = transform_file(&bytes, "c.pcd", &m).unwrap();
    let body = pcd_header(&bytes).len();
    let f = |b: &[u8], at: usize| f32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as f64;
    for i in 0..3903 {
        let at = body + 28 * i;
        let n = Vector3::new(f(&bytes, at + 12), f(&bytes, at + 16), f(&bytes, at + 20));
        let turned = rotation(&m) * n;
        for k in 0..3 {
            assert!((f(&moved, at + 12 + 4 * k) - turned[k]).abs() < 1e-6, "normal {i} axis {k}");
        }
        assert_eq!(moved[at + 24..at + 28], bytes[at + 24..at + 28], "rgb of point {i}");
    }
    // Ascii: the intensity column and the line layout kept, coordinates as precise as the file's.
    let bytes = format_fixture("velodyne_2000_ascii.pcd");
    let moved = transform_file(&bytes, "v.pcd", &m).unwrap();
    let (a, b) = (String::from_utf8(bytes).unwrap(), String::from_utf8(moved).unwrap());
    assert_eq!(a.lines().count(), b.lines().count());
    for (x, y) in a.lines().zip(b.lines()).skip(11) {
        let (x, y): (Vec<&str>, Vec<&str>) = (x.split(' ').collect(), y.split(' ').collect());
        assert_eq!(x.len(), y.len());
        assert_eq!(x[3], y[3], "intensity");
    }
}

#[test]
fn pcd_with_integer_coordinates_is_refused() {
    let pcd = b"VERSION 0.7\nFIELDS x y z\nSIZE 2 2 2\nTYPE I I I\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n";
    let e = transform_file(pcd, "int.pcd", &tilted_motion()).unwrap_err().to_string();
    assert!(e.starts_with("PCD file cannot be moved as it is: field 'x' is an integer"), "{e}");
}

#[test]
fn a_csv_with_named_normals_keeps_its_layout_and_turns_them() {
    // eth_car_1000.csv: "x,y,z,nx,ny,nz", values written "-3.5376 , 0.639553 , -1.37678 , ..."
    let m = tilted_motion();
    let bytes = format_fixture("eth_car_1000.csv");
    let moved = transform_file(&bytes, "car.csv", &m).unwrap();
    assert_points_moved(&bytes, &moved, "car.csv", &m, 1e-5);
    let (a, b) = (String::from_utf8(bytes).unwrap(), String::from_utf8(moved).unwrap());
    assert_eq!(a.lines().next(), b.lines().next(), "the header line is kept");
    for (x, y) in a.lines().zip(b.lines()).skip(1).take(200) {
        let shape = |l: &str| l.chars().filter(|c| !c.is_ascii_digit() && *c != '-' && *c != '.').collect::<String>();
        assert_eq!(shape(x), shape(y), "the separators are kept: {x} / {y}");
        let values = |l: &str| l.split(',').map(|t| t.trim().parse::<f64>().unwrap()).collect::<Vec<_>>();
        let (x, y) = (values(x), values(y));
        let turned = rotation(&m) * Vector3::new(x[3], x[4], x[5]);
        for k in 0..3 {
            assert!((y[3 + k] - turned[k]).abs() < 2e-6, "normal axis {k}");
        }
    }
}

#[test]
fn a_survey_csv_moves_its_named_columns_and_keeps_ids_codes_and_line_endings() {
    // Map-grid coordinates in millimetre steps, a point number first, a code last, CRLF.
    let csv = "PointID,Easting,Northing,Elevation,Code\r\n\
               101,1694289.125,1816495.250,5595.875,TREE\r\n\
               102,1694290.500,1816497.000,5596.125,POLE\r\n\
               103,1694301.750,1816480.375,5594.000,KERB\r\n";
    let m = Matrix4::new_translation(&Vector3::new(-1694000.0, -1816000.0, -5000.0))
        * Rotation3::from_axis_angle(&Vector3::z_axis(), 12f64.to_radians()).to_homogeneous();
    let moved = String::from_utf8(transform_file(csv.as_bytes(), "survey.csv", &m).unwrap()).unwrap();
    let rows: Vec<&str> = moved.split("\r\n").collect();
    assert_eq!(rows.len(), 5, "CRLF kept: {moved:?}");
    assert_eq!(rows[0], "PointID,Easting,Northing,Elevation,Code");
    for (row, (id, code)) in rows[1..4].iter().zip([("101", "TREE"), ("102", "POLE"), ("103", "KERB")]) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!((f[0], f[4]), (id, code), "{row}");
        assert!(f[1..4].iter().all(|v| v.split_once('.').unwrap().1.len() == 3), "three decimals, as the file: {row}");
    }
    let before = read_point_cloud(csv.as_bytes(), "survey.csv").unwrap();
    let after = read_point_cloud(moved.as_bytes(), "survey.csv").unwrap();
    for i in 0..3 {
        let want = apply(&m, before.point_f64(i));
        let got = after.point_f64(i);
        assert!((0..3).all(|k| (got[k] - want[k]).abs() <= 5e-4 + 1e-9), "{got:?} vs {want:?}");
    }
}

#[test]
fn text_lists_keep_colours_turn_unnamed_normals_and_follow_a_change_of_unit() {
    let m = tilted_motion();
    // PTS: a count line, then x y z intensity r g b.
    let pts = "3\n1.5 2.25 -0.5 -1200 255 128 0\n1.0 2.0 3.0 -800 10 20 30\n0.125 0.5 0.75 0 1 2 3\n";
    let moved = String::from_utf8(transform_file(pts.as_bytes(), "scan.pts", &m).unwrap()).unwrap();
    let lines: Vec<&str> = moved.lines().collect();
    assert_eq!(lines[0], "3");
    for (a, b) in pts.lines().zip(&lines).skip(1) {
        let (a, b): (Vec<&str>, Vec<&str>) = (a.split(' ').collect(), b.split(' ').collect());
        assert_eq!(a[3..], b[3..], "intensity and colour kept");
        // up to three decimals, the file's most; its numbers are not padded, so neither are these
        assert!(b[..3].iter().all(|v| v.split_once('.').map_or(0, |(_, f)| f.len()) <= 3), "{b:?}");
    }
    assert_points_moved(pts.as_bytes(), moved.as_bytes(), "scan.pts", &m, 5e-4 + 1e-9);
    // XYZ with unit normals after x, y, z and no header: the normals are turned.
    let xyz = "0.5 0.25 1.0 0.0 0.0 1.0\n1.5 0.75 2.0 0.6 0.8 0.0\n";
    let moved = String::from_utf8(transform_file(xyz.as_bytes(), "n.xyz", &m).unwrap()).unwrap();
    for (a, b) in xyz.lines().zip(moved.lines()) {
        let v = |l: &str| l.split(' ').map(|t| t.parse::<f64>().unwrap()).collect::<Vec<_>>();
        let (a, b) = (v(a), v(b));
        let turned = rotation(&m) * Vector3::new(a[3], a[4], a[5]);
        assert!((0..3).all(|k| (b[3 + k] - turned[k]).abs() < 1e-6), "{b:?}");
    }
    // Colours 0-255 after x, y, z are not normals: kept.
    let rgb = "0.5 0.25 1.0 255 0 0\n1.5 0.75 2.0 0 255 0\n";
    let moved = String::from_utf8(transform_file(rgb.as_bytes(), "c.xyz", &m).unwrap()).unwrap();
    assert!(moved.lines().zip(["255 0 0", "0 255 0"]).all(|(l, c)| l.ends_with(c)), "{moved}");
    // Colours 0-1 in columns a header names (a pure red is a unit vector): kept, in every way
    // of naming them; without names they would be taken for normals.
    for (name, header, sep) in
        [("c.csv", "x,y,z,r,g,b", ","), ("c.txt", "x y z red green blue", " "), ("c.txt", "//X Y Z R G B", " ")]
    {
        let rows = ["0.5 0.25 1.0 1.0 0.0 0.0", "1.5 0.75 2.0 0.0 1.0 0.0", "2.5 0.5 1.5 0.0 0.0 1.0"];
        let file = format!("{header}\n{}\n", rows.map(|r| r.replace(' ', sep)).join("\n"));
        let moved = String::from_utf8(transform_file(file.as_bytes(), name, &m).unwrap()).unwrap();
        for (row, l) in rows.iter().zip(moved.lines().skip(1)) {
            assert!(l.ends_with(&row[12..].replace(' ', sep)), "{header}: {l}");
        }
        assert_points_moved(file.as_bytes(), moved.as_bytes(), name, &m, 5e-3 + 1e-9);
    }
    // Metres onto millimetres: three decimals in metres are whole millimetres.
    let scale = Matrix4::new_scaling(1000.0);
    let moved = String::from_utf8(transform_file(b"1.234 -0.5 2.000\n", "m.xyz", &scale).unwrap()).unwrap();
    assert_eq!(moved, "1234 -500 2000\n");
    // Exponent notation stays exponent notation, with its significant digits.
    let moved = String::from_utf8(transform_file(b"1.5e0 2.0e0 -3.0e-1\n", "e.xyz", &scale).unwrap()).unwrap();
    assert_eq!(moved, "1.5e3 2.0e3 -3.0e2\n");
}

/// The mesh fixture `name` moved by `m` as it is: the same faces, every vertex within `tol` of the
/// file's own moved, as many lines; returns the file and the moved one as text.
fn moved_mesh(name: &str, m: &Matrix4<f64>, tol: f64) -> (String, String) {
    let bytes = format_fixture(name);
    let moved = transform_file(&bytes, name, m).unwrap();
    let (before, after) = (read_mesh(&bytes, name).unwrap(), read_mesh(&moved, name).unwrap());
    assert_eq!(before.triangles, after.triangles);
    for (p, q) in before.vertices.iter().zip(&after.vertices) {
        let want = apply(m, p.map(f64::from));
        assert!((0..3).all(|k| (q[k] as f64 - want[k]).abs() < tol), "{q:?} vs {want:?}");
    }
    let (a, b) = (String::from_utf8(bytes).unwrap(), String::from_utf8(moved).unwrap());
    assert_eq!(a.lines().count(), b.lines().count());
    (a, b)
}

#[test]
fn obj_keeps_faces_and_texture_and_turns_normals() {
    let m = tilted_motion();
    let (a, b) = moved_mesh("fuze.obj", &m, 1e-5);
    let mut normals = 0;
    for (x, y) in a.lines().zip(b.lines()) {
        if x.starts_with("vn ") {
            let v = |l: &str| l.split_whitespace().skip(1).map(|t| t.parse::<f64>().unwrap()).collect::<Vec<_>>();
            let turned = rotation(&m) * Vector3::from_column_slice(&v(x));
            assert!((0..3).all(|k| (v(y)[k] - turned[k]).abs() < 1e-5), "{x} -> {y}");
            normals += 1;
        } else if !x.starts_with("v ") {
            assert_eq!(x, y, "a line other than v / vn is kept");
        }
    }
    assert!(normals > 100);
}

#[test]
fn obj_with_continued_lines_keeps_a_continued_face_and_refuses_a_continued_vertex() {
    let m = tilted_motion();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 \\\n 3\nf 1 3 4\n";
    let moved = String::from_utf8(transform_file(obj.as_bytes(), "a.obj", &m).unwrap()).unwrap();
    let lines: Vec<&str> = moved.lines().collect();
    assert_eq!(lines[4..], ["f 1 2 \\", " 3", "f 1 3 4"]);
    let p = apply(&m, [1.0, 0.0, 0.0]);
    let second: Vec<f64> = lines[1].split_whitespace().skip(1).map(|t| t.parse().unwrap()).collect();
    assert!((0..3).all(|k| (second[k] - p[k]).abs() < 0.05 + 1e-9), "{second:?} vs {p:?}");
    let split = obj.replace("v 1 0 0\n", "v 1 \\\n 0 0\n");
    let err = transform_file(split.as_bytes(), "a.obj", &m).unwrap_err().to_string();
    assert!(err.contains("line 2") && err.contains("continued"), "{err}");
}

#[test]
fn off_keeps_faces_and_colours_turns_normals_and_follows_split_records() {
    let m = tilted_motion();
    // ballA.off (ModelNet's layout): 1,900 vertices, 3,796 faces
    let (a, b) = moved_mesh("ballA.off", &m, 1e-4);
    assert!(a.lines().zip(b.lines()).skip(1902).all(|(x, y)| x == y), "the faces are kept");
    // NOFF with a colour after the normal, a comment, and a vertex split over two lines
    let noff = "NOFF\n# made\n3 1 0\n1.0 0.0 0.0 0.0 0.0 1.0 255\n0.0 1.0\n 0.0 1.0 0.0 0.0 7\n0.0 0.0 1.0 0.6 0.8 0.0 9\n3 0 1 2\n";
    let moved = String::from_utf8(transform_file(noff.as_bytes(), "n.off", &m).unwrap()).unwrap();
    let lines: Vec<&str> = moved.lines().collect();
    assert_eq!((lines[0], lines[1], lines[2], lines[7]), ("NOFF", "# made", "3 1 0", "3 0 1 2"));
    let values = |l: &str| l.split_whitespace().map(|t| t.parse::<f64>().unwrap()).collect::<Vec<_>>();
    let first = values(lines[3]);
    assert_eq!(first[6], 255.0, "the colour kept");
    let (p, n) = (apply(&m, [1.0, 0.0, 0.0]), rotation(&m) * Vector3::new(0.0, 0.0, 1.0));
    assert!((0..3).all(|k| (first[k] - p[k]).abs() < 0.05 + 1e-9 && (first[3 + k] - n[k]).abs() < 1e-6), "{first:?}");
    let split = [values(lines[4]), values(lines[5])].concat();
    let (p, n) = (apply(&m, [0.0, 1.0, 0.0]), rotation(&m) * Vector3::new(1.0, 0.0, 0.0));
    assert!((0..3).all(|k| (split[k] - p[k]).abs() < 0.05 + 1e-9 && (split[3 + k] - n[k]).abs() < 1e-6), "{split:?}");
    assert_eq!(split[6], 7.0);
}

#[test]
fn stl_binary_and_ascii_move_their_corners_and_turn_their_normals() {
    let m = tilted_motion();
    for name in ["cylinder_binary.stl", "angle_block_binary_solid.stl", "tray_bottom_150_ascii.stl"] {
        let bytes = format_fixture(name);
        let moved = transform_file(&bytes, name, &m).unwrap();
        // Corners compared facet by facet: STL repeats them, and two that differ in the last bit
        // of a float may round to one once moved, so the welded meshes may differ.
        let (before, after) = (read_mesh(&bytes, name).unwrap(), read_mesh(&moved, name).unwrap());
        assert_eq!(before.triangles.len(), after.triangles.len(), "{name}");
        let size = before.vertices.iter().flat_map(|p| p.iter()).fold(0f64, |a, &v| a.max((v as f64).abs()));
        for (s, t) in before.triangles.iter().zip(&after.triangles) {
            for c in 0..3 {
                let (p, q) = (before.vertices[s[c] as usize], after.vertices[t[c] as usize]);
                let want = apply(&m, p.map(f64::from));
                let close = (0..3).all(|k| (q[k] as f64 - want[k]).abs() < 1e-6 * size.max(10.0));
                assert!(close, "{name}: {q:?} vs {want:?}");
            }
        }
        if name.contains("binary") {
            assert_eq!(moved.len(), bytes.len());
            assert_eq!(moved[..84], bytes[..84], "{name}: header and count kept");
            let f = |b: &[u8], at: usize| f32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as f64;
            for k in 0..(bytes.len() - 84) / 50 {
                let at = 84 + 50 * k;
                assert_eq!(moved[at + 48..at + 50], bytes[at + 48..at + 50], "attribute bytes");
                let n = rotation(&m) * Vector3::new(f(&bytes, at), f(&bytes, at + 4), f(&bytes, at + 8));
                assert!((0..3).all(|a| (f(&moved, at + 4 * a) - n[a]).abs() < 1e-5), "{name}: facet {k} normal");
            }
        } else {
            let (a, b) = (String::from_utf8(bytes).unwrap(), String::from_utf8(moved).unwrap());
            for (x, y) in a.lines().zip(b.lines()) {
                if !x.contains("vertex") && !x.contains("normal") {
                    assert_eq!(x, y);
                } else {
                    assert_eq!(x.find(|c: char| !c.is_whitespace()), y.find(|c: char| !c.is_whitespace()));
                    assert!(y.split_whitespace().last().unwrap().contains('e'), "exponent form kept: {y}");
                }
            }
        }
    }
}

#[test]
fn the_format_picks_the_mover_and_unmovable_formats_say_so() {
    let m = tilted_motion();
    for name in ["simple.las", "fuze_binary.ply", "fuze_ascii.ply"] {
        let bytes = format_fixture(name);
        let own = if name.ends_with(".las") { transform_las(&bytes, &m) } else { transform_ply(&bytes, &m) };
        assert_eq!(transform_file(&bytes, name, &m).unwrap(), own.unwrap(), "{name}");
        assert!(can_transform(name));
    }
    // Without an extension the content says the format.
    let bytes = format_fixture("velodyne_2000_binary.pcd");
    assert_eq!(transform_file(&bytes, "", &m).unwrap(), transform_file(&bytes, "a.pcd", &m).unwrap());
    // LAZ by the LAS mover too, compressed again (tests/io_las_transform.rs)
    let laz = format_fixture("simple.laz");
    assert_eq!(transform_file(&laz, "simple.laz", &m).unwrap(), transform_las(&laz, &m).unwrap());
    // (E57: tests/io_e57_transform.rs); a name and content that say no format
    let e = transform_file(b"\x00\x01 not a point file", "drawing.dxf", &m).unwrap_err().to_string();
    assert!(e.contains("cannot tell the format"), "{e}");
    for name in
        ["a.PCD", "b.xyz", "c.pts", "d.txt", "e.csv", "f.obj", "g.stl", "h.Ply", "i.las", "j.LAZ", "k.e57", "l.off"]
    {
        assert!(can_transform(name), "{name}");
    }
    assert!(!can_transform("noextension") && !can_transform("x.dxf"));
    // A mirror is not a motion of the file.
    let mirror = Matrix4::new_nonuniform_scaling(&Vector3::new(-1.0, 1.0, 1.0));
    let e = transform_file(&format_fixture("eth_car_1000.csv"), "car.csv", &mirror).unwrap_err().to_string();
    assert!(e.contains("mirrors"), "{e}");
    assert!(!e.contains("transpose"), "{e}");
    // a motion given in the other order (row-major read column-major): the error says so
    let motion = Matrix4::new_translation(&Vector3::new(1.0, 2.0, 3.0));
    let e =
        transform_file(&format_fixture("eth_car_1000.csv"), "car.csv", &motion.transpose()).unwrap_err().to_string();
    assert!(
        e.contains("bottom row") && e.contains("its transpose is rigid, so its 16 numbers may be in the other order"),
        "{e}"
    );
}
