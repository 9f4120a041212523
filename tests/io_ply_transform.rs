//! `io::transform_ply`: a PLY file moved as it is. On real files (a binary fragment with normals,
//! colours and faces; an ASCII mesh with colours and textured faces) and on made ones (big-endian
//! doubles, an element before the vertices, blank lines): the positions are the transform of the
//! file's own, in the file's types; normals are turned and stay unit; every other byte (colours,
//! faces, comments, the header) is kept; hostile files and transforms are refused with a message.

use arps::io::{read_mesh, read_point_cloud, transform_ply};
mod common;
use common::{apply, format_fixture, tilted_motion};
use nalgebra::{Matrix4, Vector3};

fn header_len(bytes: &[u8]) -> usize {
    let at = bytes.windows(11).position(|w| w == b"end_header\n").unwrap();
    at + 11
}

fn f32_at(b: &[u8], off: usize) -> f32 {
    f32::from_le_bytes(b[off..off + 4].try_into().unwrap())
}

#[test]
fn a_binary_fragment_keeps_its_colours_and_faces_and_turns_its_normals() {
    // frag_115_2000_binary.ply: 2,000 vertices of x y z nx ny nz (float) red green blue (uchar),
    // then 3,270 faces
    let bytes = format_fixture("frag_115_2000_binary.ply");
    let m = tilted_motion();
    let moved = transform_ply(&bytes, &m).unwrap();
    assert_eq!(moved.len(), bytes.len());
    let body = header_len(&bytes);
    assert_eq!(moved[..body], bytes[..body], "the header is kept");
    let stride = 6 * 4 + 3;
    let vertices = body + 2000 * stride;
    assert_eq!(moved[vertices..], bytes[vertices..], "the faces are kept, byte for byte");
    let r = m.fixed_view::<3, 3>(0, 0).into_owned();
    for i in 0..2000 {
        let (a, b) = (&bytes[body + i * stride..], &moved[body + i * stride..]);
        let p = [0, 1, 2].map(|k| f32_at(a, 4 * k) as f64);
        let want = apply(&m, p);
        for (k, want) in want.into_iter().enumerate() {
            assert!((f32_at(b, 4 * k) as f64 - want).abs() < 1e-5, "vertex {i} axis {k}");
        }
        let n = Vector3::from([3, 4, 5].map(|k| f32_at(a, 4 * k) as f64));
        let turned = r * n;
        for k in 0..3 {
            assert!((f32_at(b, 4 * (k + 3)) as f64 - turned[k]).abs() < 1e-6, "normal {i} axis {k}");
        }
        assert_eq!(a[24..27], b[24..27], "vertex {i}'s colour");
    }
    // the reader sees the moved mesh
    let (before, after) = (read_mesh(&bytes, "f.ply").unwrap(), read_mesh(&moved, "f.ply").unwrap());
    assert_eq!(before.triangles, after.triangles);
}

#[test]
fn an_ascii_mesh_keeps_every_other_value_and_line() {
    // fuze_ascii.ply: 502 vertices x y z (float) red green blue alpha, 1,000 textured faces
    let bytes = format_fixture("fuze_ascii.ply");
    let m = tilted_motion();
    let moved = transform_ply(&bytes, &m).unwrap();
    let (a, b) = (String::from_utf8(bytes.clone()).unwrap(), String::from_utf8(moved.clone()).unwrap());
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    assert_eq!(la.len(), lb.len(), "one line for one line");
    let first = la.iter().position(|l| *l == "end_header").unwrap() + 1;
    assert_eq!(la[..first], lb[..first], "the header");
    assert_eq!(la[first + 502..], lb[first + 502..], "the faces");
    for i in 0..502 {
        let (ta, tb): (Vec<&str>, Vec<&str>) =
            (la[first + i].split_whitespace().collect(), lb[first + i].split_whitespace().collect());
        assert_eq!(ta[3..], tb[3..], "vertex {i}'s colour");
        let p = [0, 1, 2].map(|k| ta[k].parse::<f64>().unwrap());
        let want = apply(&m, p);
        for k in 0..3 {
            let got: f32 = tb[k].parse().unwrap();
            assert_eq!(got, want[k] as f32, "vertex {i} axis {k}: written as the float it is");
        }
    }
    let (before, after) = (read_point_cloud(&bytes, "a.ply").unwrap(), read_point_cloud(&moved, "a.ply").unwrap());
    assert_eq!(before.len(), after.len());
}

/// A big-endian PLY of `double` x y z and float normals, with an element before the vertices
/// (of a list property) and one after.
fn made_big_endian(points: &[[f64; 3]], normals: &[[f32; 3]]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_big_endian 1.0\ncomment made by the test\nelement camera 2\nproperty list uchar float view\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty ushort intensity\nelement note 1\nproperty int tag\nend_header\n",
        points.len()
    )
    .into_bytes();
    for k in 0..2u8 {
        out.push(k + 1);
        for j in 0..=k {
            out.extend_from_slice(&(j as f32 + 0.5).to_be_bytes());
        }
    }
    for (i, (p, n)) in points.iter().zip(normals).enumerate() {
        for v in p {
            out.extend_from_slice(&v.to_be_bytes());
        }
        for v in n {
            out.extend_from_slice(&v.to_be_bytes());
        }
        out.extend_from_slice(&(i as u16 * 7).to_be_bytes());
    }
    out.extend_from_slice(&1234i32.to_be_bytes());
    out
}

#[test]
fn big_endian_doubles_far_from_zero_keep_every_digit() {
    let points: Vec<[f64; 3]> = (0..40)
        .map(|i| [1_694_289.125 + i as f64 * 0.37, 1_816_495.5 - i as f64 * 0.11, 5595.25 + (i % 7) as f64])
        .collect();
    let normals: Vec<[f32; 3]> = (0..40).map(|i| if i % 2 == 0 { [0.0, 0.0, 1.0] } else { [0.6, 0.0, 0.8] }).collect();
    let bytes = made_big_endian(&points, &normals);
    let m = tilted_motion();
    let moved = transform_ply(&bytes, &m).unwrap();
    assert_eq!(moved.len(), bytes.len());
    let cloud = read_point_cloud(&moved, "far.ply").unwrap();
    for (i, p) in points.iter().enumerate() {
        let (want, got) = (apply(&m, *p), cloud.point_f64(i));
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-6, "point {i} axis {k}: {} vs {}", got[k], want[k]);
        }
    }
    // the element before the vertices, each vertex's intensity and the element after: as they were
    let body = header_len(&bytes);
    let camera = 1 + 4 + 1 + 8;
    assert_eq!(moved[body..body + camera], bytes[body..body + camera]);
    let stride = 24 + 12 + 2;
    for i in 0..40 {
        let at = body + camera + i * stride;
        assert_eq!(moved[at + 36..at + 38], bytes[at + 36..at + 38], "intensity {i}");
        let n = [0, 1, 2].map(|k| f32::from_be_bytes(moved[at + 24 + 4 * k..at + 28 + 4 * k].try_into().unwrap()));
        let len = n.iter().map(|v| v * v).sum::<f32>().sqrt();
        assert!((len - 1.0).abs() < 1e-6, "normal {i} stays unit: {len}");
    }
    assert_eq!(moved[moved.len() - 4..], 1234i32.to_be_bytes());
}

#[test]
fn a_uniform_scale_moves_positions_and_leaves_normals_unit() {
    // a source in metres saved into a target in millimetres: T times 1000
    let points = vec![[1.0, 2.0, 3.0], [-0.5, 0.25, 4.0]];
    let bytes = made_big_endian(&points, &[[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]);
    let m = tilted_motion() * Matrix4::new_scaling(1000.0);
    let moved = transform_ply(&bytes, &m).unwrap();
    let cloud = read_point_cloud(&moved, "mm.ply").unwrap();
    let want = apply(&m, points[1]);
    // read back as f32 offsets from an origin, points thousands apart: to 1e-3
    assert!((0..3).all(|k| (cloud.point_f64(1)[k] - want[k]).abs() < 1e-3));
    let body = header_len(&bytes) + 14;
    let n = [0, 1, 2].map(|k| f32::from_be_bytes(moved[body + 24 + 4 * k..body + 28 + 4 * k].try_into().unwrap()));
    let turned = m.fixed_view::<3, 3>(0, 0) / 1000.0 * Vector3::new(0.0, 1.0, 0.0);
    assert!((0..3).all(|k| (n[k] as f64 - turned[k]).abs() < 1e-6), "{n:?} vs {turned:?}");
}

#[test]
fn blank_lines_and_crlf_in_an_ascii_file_are_kept() {
    let bytes = b"ply\r\nformat ascii 1.0\r\nelement vertex 2\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\nproperty uchar red\r\nend_header\r\n1 2 3 200\r\n\r\n4   5 6 10\r\n";
    let m = Matrix4::new_translation(&Vector3::new(0.5, 0.0, -1.0));
    let moved = String::from_utf8(transform_ply(bytes, &m).unwrap()).unwrap();
    assert!(moved.ends_with("end_header\r\n1.5 2 2 200\r\n\r\n4.5 5 5 10\r\n"), "{moved:?}");
}

#[test]
fn hostile_files_and_transforms_are_refused_with_a_message() {
    let m = tilted_motion();
    let good = format_fixture("frag_115_2000_binary.ply");
    let refused = |bytes: &[u8], m: &Matrix4<f64>| transform_ply(bytes, m).unwrap_err().to_string();
    assert!(refused(
        b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
        &m
    )
    .contains("no 'vertex' element"));
    assert!(refused(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty int x\nproperty int y\nproperty int z\nend_header\n1 2 3\n",
        &m
    )
    .starts_with("PLY file cannot be moved as it is: vertex property 'x' is an integer"));
    assert!(refused(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty list uchar int ids\nend_header\n1 2 3 0\n",
        &m
    )
    .starts_with("PLY file cannot be moved as it is: element 'vertex' has a list property ('ids')"));
    assert!(refused(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 5\n", &m)
        .contains("a vertex needs 3 values"));
    assert!(refused(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n", &m)
        .contains("ends after 1 of the 2"));
    assert!(refused(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 two 3\n", &m)
        .contains("line 8"));
    assert!(refused(b"not a ply", &m).contains("PLY"));
    let mut sheared = m;
    sheared[(0, 1)] += 0.3;
    assert!(refused(&good, &sheared).contains("not rigid"));
    assert!(refused(&good, &Matrix4::new_nonuniform_scaling(&Vector3::new(1.0, 1.0, -1.0))).contains("mirrors"));
    assert!(refused(&good, &Matrix4::new_nonuniform_scaling(&Vector3::new(1.0, 2.0, 1.0))).contains("not rigid"));
    let mut nan = m;
    nan[(1, 3)] = f64::NAN;
    assert!(refused(&good, &nan).contains("non-finite"));
    let mut projective = m;
    projective[(3, 0)] = 0.1;
    assert!(refused(&good, &projective).contains("bottom row"));
    // every prefix of a binary file: moved in full (a prefix that still holds every vertex) or
    // refused, never a panic
    let body = header_len(&good);
    let vertices_end = body + 2000 * 27;
    for cut in (0..good.len()).step_by(97).chain([vertices_end - 1, vertices_end]) {
        match transform_ply(&good[..cut], &m) {
            Ok(out) => assert!(cut >= vertices_end && out.len() == cut, "cut at {cut}"),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
    }
}

/// A 3D Gaussian Splatting file of `n` splats (the reference layout: position, zero normal,
/// colour, 45 colour coefficients, opacity, log-extents, quaternion), binary or ASCII.
fn splat_file(n: usize, ascii: bool) -> (Vec<u8>, Vec<Vec<f32>>) {
    let mut names: Vec<String> =
        ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"].map(String::from).to_vec();
    names.extend((0..45).map(|k| format!("f_rest_{k}")));
    names.extend(["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"].map(String::from));
    let format = if ascii { "ascii" } else { "binary_little_endian" };
    let mut out = format!("ply\nformat {format} 1.0\nelement vertex {n}\n").into_bytes();
    for name in &names {
        out.extend(format!("property float {name}\n").bytes());
    }
    out.extend(b"end_header\n");
    let records: Vec<Vec<f32>> = (0..n)
        .map(|i| {
            (0..names.len()).map(|k| ((i * 62 + k) as f32 * 0.618).sin() * if k < 3 { 2.0 } else { 1.0 }).collect()
        })
        .collect();
    for r in &records {
        if ascii {
            let line: Vec<String> = r.iter().map(|v| v.to_string()).collect();
            out.extend(line.join(" ").bytes());
            out.push(b'\n');
        } else {
            r.iter().for_each(|v| out.extend(v.to_le_bytes()));
        }
    }
    (out, records)
}

/// The values of a moved splat file, read back (every property float).
fn splat_values(bytes: &[u8], n: usize, ascii: bool) -> Vec<Vec<f32>> {
    let body = &bytes[header_len(bytes)..];
    if ascii {
        let text = std::str::from_utf8(body).unwrap();
        return text.lines().take(n).map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect()).collect();
    }
    body.chunks_exact(62 * 4).take(n).map(|r| (0..62).map(|k| f32_at(r, 4 * k)).collect()).collect()
}

#[test]
fn gaussian_splats_turn_and_scale_with_the_scene() {
    use nalgebra::{Quaternion, UnitQuaternion};
    // turned, moved and scaled by 2.5 (a scene of unknown scale onto another)
    let rigid = arps::transform::from_rotation_translation(
        nalgebra::Rotation3::from_euler_angles(0.4, -1.2, 2.9).matrix(),
        &nalgebra::Vector3::new(1.0, -2.0, 0.5),
    );
    let mut m = rigid;
    m.fixed_view_mut::<3, 3>(0, 0).scale_mut(2.5);
    let r = rigid.fixed_view::<3, 3>(0, 0).into_owned();
    for ascii in [false, true] {
        let (file, before) = splat_file(4, ascii);
        let moved = arps::io::transform_ply(&file, &m).unwrap();
        let after = splat_values(&moved, 4, ascii);
        for (b, a) in before.iter().zip(&after) {
            let f = |v: &[f32], k: usize| v[k] as f64;
            // the centre moved
            let p = m.transform_point(&nalgebra::Point3::new(f(b, 0), f(b, 1), f(b, 2)));
            assert!((0..3).all(|k| (f(a, k) - p[k]).abs() < 1e-5), "{a:?}");
            // colour of the constant band and opacity as they were
            assert_eq!((&a[6..9], a[54]), (&b[6..9], b[54]));
            // the extents 2.5 times larger (logarithms)
            assert!((55..58).all(|k| (f(a, k) - f(b, k) - 2.5f64.ln()).abs() < 1e-5), "{a:?}");
            // the axes turned: the new quaternion's rotation is R times the old one's
            let axes = |v: &[f32]| {
                let q = Quaternion::new(f(v, 58), f(v, 59), f(v, 60), f(v, 61));
                *UnitQuaternion::from_quaternion(q).to_rotation_matrix().matrix()
            };
            assert!((axes(a) - r * axes(b)).abs().max() < 1e-5, "{a:?}");
            // the view-dependent colour turned: its coefficients changed, their energy per band kept
            let energy = |v: &[f32], c: usize, band: std::ops::Range<usize>| {
                band.map(|k| f(v, 9 + 15 * c + k).powi(2)).sum::<f64>()
            };
            for c in 0..3 {
                for band in [0..3, 3..8, 8..15] {
                    let (e_a, e_b) = (energy(a, c, band.clone()), energy(b, c, band));
                    assert!((e_a - e_b).abs() < 1e-4 * e_b.max(1.0), "{e_a} vs {e_b}");
                }
            }
            assert_ne!(&a[9..54], &b[9..54]);
        }
    }
}

#[test]
fn splats_are_read_by_their_opacity() {
    use arps::io::{read_point_cloud_with, ReadOptions};
    let (file, records) = splat_file(40, false);
    // `{ minOpacity: 0.5 }`: the splats whose opacity logit is 0 or more
    let options: ReadOptions = serde_json::from_str(r#"{ "minOpacity": 0.5 }"#).unwrap();
    let opaque: Vec<&Vec<f32>> = records.iter().filter(|r| r[54] >= 0.0).collect();
    assert!(!opaque.is_empty() && opaque.len() < records.len());
    let cloud = read_point_cloud_with(&file, "scene.ply", &options).unwrap();
    assert_eq!(cloud.len(), opaque.len());
    for (i, r) in opaque.iter().enumerate() {
        let p = cloud.point_f64(i);
        assert!((0..3).all(|k| (p[k] - r[k] as f64).abs() < 1e-6), "{p:?} {r:?}");
    }
    // the same in an ASCII file
    let (ascii, _) = splat_file(40, true);
    assert_eq!(read_point_cloud_with(&ascii, "scene.ply", &options).unwrap().len(), opaque.len());
    // refused: none that opaque (the most opaque named), out of [0, 1], with surfacePoints, a PLY
    // without opacity, another format
    let with = |min: f64| ReadOptions { min_opacity: Some(min), ..ReadOptions::default() };
    let e = read_point_cloud_with(&file, "scene.ply", &with(0.9999)).unwrap_err().to_string();
    assert!(e.contains("no splat of the file is that opaque (the most opaque: 0.7"), "{e}");
    let e = read_point_cloud_with(&file, "scene.ply", &with(1.5)).unwrap_err().to_string();
    assert!(e.contains("minOpacity = 1.5 must be a number in [0, 1]"), "{e}");
    let sampled = ReadOptions { surface_points: Some(100), ..with(0.5) };
    let e = read_point_cloud_with(&file, "scene.ply", &sampled).unwrap_err().to_string();
    assert!(e.contains("give one of them"), "{e}");
    let e = read_point_cloud_with(&format_fixture("frag_115_2000_binary.ply"), "f.ply", &with(0.5)).unwrap_err();
    assert!(e.to_string().contains("no vertex 'opacity' property"), "{e}");
    let e = read_point_cloud_with(b"1 2 3\n4 5 6\n", "p.xyz", &with(0.5)).unwrap_err().to_string();
    assert!(e.contains("but this is a XYZ file"), "{e}");
    // moving the file moves every splat, whatever the option
    let moved =
        arps::transform::from_rotation_translation(&nalgebra::Matrix3::identity(), &Vector3::new(1.0, 0.0, 0.0));
    let out = arps::io::transform_file_with(&file, "scene.ply", &moved, &with(0.5)).unwrap();
    assert_eq!(splat_values(&out, 40, false).len(), 40);
}
