//! `parsePointCloud` on real files of every format (fixtures/formats/, see its LICENSES.md; LAS
//! and LAZ too, decompressed in wasm),
//! through the JS-facing binding in Node: point counts and values as the native reader tests
//! check them, format by extension and by sniffing, NaN kept for organised PCD, and registration
//! of a parsed real scan against a known motion of itself.
#![cfg(target_arch = "wasm32")]

mod wasm_common;

use arps::transform::{euler_xyz, from_rotation_translation, rotation_error_deg, translation_error};
use arps::wasm::{parse_point_cloud, Registrar};
use nalgebra::Vector3;
use wasm_bindgen_test::wasm_bindgen_test;
use wasm_common::*;

macro_rules! fixture {
    ($name:literal) => {
        ($name, include_bytes!(concat!("../fixtures/formats/", $name)) as &[u8])
    };
    ($name:literal, $n:expr, $first:expr) => {
        ($name, include_bytes!(concat!("../fixtures/formats/", $name)) as &[u8], $n, $first)
    };
}

const NONE: [f32; 3] = [f32::NAN; 3];

/// (file, bytes, points the reader returns, first point or NaN when not checked).
const FILES: &[(&str, &[u8], usize, [f32; 3])] = &[
    fixture!("milk_compressed.pcd", 13704, [-0.131_607_6, -0.209_542_9, 0.772]),
    fixture!("velodyne_2000_binary.pcd", 2000, [0.003_139_891_7, 2.570_035, -1.524_156_8]),
    fixture!("velodyne_2000_ascii.pcd", 2000, [0.003_139_891_7, 2.570_035, -1.524_156_8]),
    fixture!("cloud_bin_0_binary.pcd", 3903, [2.848_907_7, 0.031_390_607, -1.747_166]),
    fixture!("frag_115_2000_binary.ply", 2000, [0.847_656_25, 2.679_497_7, 1.597_656_3]),
    fixture!("eth_car_1000.csv", 1000, NONE),
    fixture!("ballA.off", 1900, NONE),
    fixture!("fuze_binary.ply", 502, NONE),
    fixture!("fuze_ascii.ply", 502, NONE),
    fixture!("fuze.obj", 502, NONE),
    fixture!("simple.las", 1065, [637_012.24, 849_028.3, 431.66]),
    fixture!("simple.laz", 1065, [637_012.24, 849_028.3, 431.66]),
    fixture!("1_4_w_evlr.laz", 1000, [1_694_510.4, 1_816_498.0, 5_598.36]),
    fixture!("tiny_spherical.e57", 180, [1.0, 0.0, 0.0]),
];

fn close(a: &[f32], b: [f32; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-5 * (1.0 + y.abs()))
}

#[wasm_bindgen_test]
fn every_format_by_extension_and_by_sniffing() {
    for &(name, bytes, n, first) in FILES {
        let xyz = parse_point_cloud(bytes, name, None).map_err(message).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(xyz.len(), 3 * n, "{name}: point count");
        if !first[0].is_nan() {
            assert!(close(&xyz[..3], first), "{name}: first point {:?}", &xyz[..3]);
        }
        // No extension: the content decides (CSV has no magic; skip it).
        if !name.ends_with(".csv") {
            let sniffed = parse_point_cloud(bytes, "upload", None).map_err(message);
            assert_eq!(sniffed.as_deref().ok(), Some(&xyz[..]), "{name}: sniffed without an extension");
        }
    }
}

#[wasm_bindgen_test]
fn ascii_and_binary_agree_and_meshes_give_vertices() {
    let bin = parse_point_cloud(FILES[1].1, FILES[1].0, None).map_err(message).unwrap();
    let asc = parse_point_cloud(FILES[2].1, FILES[2].0, None).map_err(message).unwrap();
    assert_eq!(bin, asc, "velodyne ascii and binary PCD");
    let ply = parse_point_cloud(FILES[7].1, FILES[7].0, None).map_err(message).unwrap();
    let obj = parse_point_cloud(FILES[9].1, FILES[9].0, None).map_err(message).unwrap();
    assert_eq!(ply, obj, "fuze PLY and OBJ vertices");
    for (name, bytes) in [
        fixture!("angle_block_binary_solid.stl"),
        fixture!("cylinder_binary.stl"),
        fixture!("tray_bottom_150_ascii.stl"),
        fixture!("fuze_trimesh.glb"),
        fixture!("fuze_quantized.glb"),
    ] {
        let xyz = parse_point_cloud(bytes, name, None).map_err(message).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(xyz.len() >= 9 && xyz.len().is_multiple_of(3), "{name}: {} values", xyz.len());
    }
}

#[wasm_bindgen_test]
fn organised_pcd_keeps_nan_and_drop_option_registers_it() {
    let (name, bytes) = fixture!("table_scene_80x60_compressed.pcd");
    let xyz = parse_point_cloud(bytes, name, None).map_err(message).unwrap();
    assert_eq!(xyz.len(), 3 * 80 * 60);
    let nan = xyz.chunks(3).filter(|p| p.iter().any(|v| v.is_nan())).count();
    assert_eq!(nan, 1577, "no-return points stay NaN in the Float32Array");
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let e = r.register(&xyz, &xyz, None, None, None, None).err().map(message).expect("NaN rejected by default");
    assert!(e.contains("non-finite"), "{e}");
    let res =
        r.register(&xyz, &xyz, Some(options(r#"{"nonFinite": "drop"}"#)), None, None, None).map_err(message).unwrap();
    let m = matrix(&res, "T_target_source");
    assert!(rotation_error_deg(&m, &nalgebra::Matrix4::identity()) < 0.5, "a cloud onto itself: {m}");
}

#[wasm_bindgen_test]
fn real_scan_recovers_a_known_motion() {
    let bytes = include_bytes!("../fixtures/scans/velodyne-small.ply");
    let src = parse_point_cloud(bytes, "velodyne-small.ply", None).map_err(message).unwrap();
    let gt = from_rotation_translation(&euler_xyz(0.08, -0.12, 0.18), &Vector3::new(0.4, -0.3, 0.1));
    let tgt: Vec<f32> = src.chunks(3).flat_map(|p| arps::transform::apply(&gt, [p[0], p[1], p[2]])).collect();
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let res = r.register(&src, &tgt, None, None, None, None).map_err(message).unwrap();
    let m = matrix(&res, "T_target_source");
    let (rot, tr) = (rotation_error_deg(&m, &gt), translation_error(&m, &gt));
    assert!(rot < 1.0 && tr < 0.05, "rotation error {rot:.3} deg, translation error {tr:.4}");
}

/// `readPointCloud` keeps large coordinates: a PLY of doubles far from zero comes back as `f32`
/// offsets from an origin near the points, equal to the file's values to well under a
/// millimetre, where `parsePointCloud`'s `f32` coordinates are rounded to 0.25-0.5.
#[wasm_bindgen_test]
fn read_point_cloud_keeps_large_coordinates() {
    let far = [512_345.25, 4_123_456.5, 87.125];
    let mut body = Vec::new();
    let mut expected = Vec::new();
    for i in 0..200 {
        let t = i as f64 * 0.05;
        let p = [far[0] + t.cos(), far[1] + t.sin(), far[2] + 0.01 * i as f64];
        for v in p {
            body.extend_from_slice(&v.to_le_bytes());
            expected.push(v);
        }
    }
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 200\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
    let bytes = [header.as_bytes(), &body].concat();
    let cloud = arps::wasm::read_point_cloud(&bytes, "far.ply", None).map_err(message).unwrap();
    let get = |k: &str| js_sys::Reflect::get(&cloud, &k.into()).unwrap();
    let points = js_sys::Float32Array::from(get("points")).to_vec();
    let origin: Vec<f64> = js_sys::Array::from(&get("origin")).iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(points.len(), expected.len());
    assert!((origin[1] - far[1]).abs() < 10.0, "origin {origin:?} near the points");
    let worst =
        expected.iter().enumerate().map(|(i, v)| (origin[i % 3] + points[i] as f64 - v).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-6, "read back to {worst}");
    let rounded = parse_point_cloud(&bytes, "far.ply", None).map_err(message).unwrap();
    assert!((rounded[1] as f64 - expected[1]).abs() < 0.5);
}

/// `options.surfacePoints` reads a mesh as that many points over its surface (the core's
/// sampler: the same points as `read_point_cloud_with`); a misspelled or out-of-range option
/// throws a clear error.
#[wasm_bindgen_test]
fn a_mesh_read_as_its_surface() {
    let (name, bytes) = fixture!("angle_block_binary_solid.stl");
    let xyz = parse_point_cloud(bytes, name, Some(options(r#"{"surfacePoints": 1000, "seed": 3}"#))).map_err(message);
    let core = arps::io::read_point_cloud_with(
        bytes,
        name,
        &arps::io::ReadOptions { surface_points: Some(1000), seed: 3, scan: None, classes: None, min_opacity: None },
    );
    assert_eq!(xyz.unwrap(), core.unwrap().to_xyz());
    let e = parse_point_cloud(bytes, name, Some(options(r#"{"surfacePoint": 1000}"#))).err().map(message);
    assert!(e.as_deref().is_some_and(|e| e.contains("invalid read options: unknown field `surfacePoint`")), "{e:?}");
    let e = parse_point_cloud(bytes, name, Some(options(r#"{"surfacePoints": 3}"#))).err().map(message);
    assert!(e.as_deref().is_some_and(|e| e.contains("surfacePoints = 3 is fewer than 16")), "{e:?}");
}

/// A georeferenced LAZ survey (LAS 1.4, layered chunks, decompressed in wasm) through
/// `readPointCloud`: map-grid coordinates (1.7e6) as laspy reads them, to a millimetre.
#[wasm_bindgen_test]
fn read_point_cloud_keeps_a_laz_surveys_coordinates() {
    let (name, bytes) = fixture!("1_4_w_evlr.laz");
    let cloud = arps::wasm::read_point_cloud(bytes, name, None).map_err(message).unwrap();
    let get = |k: &str| js_sys::Reflect::get(&cloud, &k.into()).unwrap();
    let points = js_sys::Float32Array::from(get("points")).to_vec();
    let origin: Vec<f64> = js_sys::Array::from(&get("origin")).iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(points.len(), 3 * 1000);
    let at = |i: usize| [0, 1, 2].map(|k| origin[k] + points[3 * i + k] as f64);
    for (i, laspy) in [
        (0, [1_694_510.386_934_684_1, 1_816_497.966_263_977, 5_598.359_612_814_967_5]),
        (999, [1_694_291.636_332_655_8, 1_816_493.066_230_584_6, 5_597.089_652_537_912]),
    ] {
        let p = at(i);
        assert!((0..3).all(|k| (p[k] - laspy[k]).abs() < 1e-3), "point {i}: {p:?}, laspy {laspy:?}");
    }
}

/// `options.scan` reads one scan of an E57 file (placed by its pose); one beyond the file's scans,
/// or a negative index, throws a clear error.
#[wasm_bindgen_test]
fn one_scan_of_an_e57_file() {
    let (name, bytes) = fixture!("velodyne_two_scans.e57");
    let all = parse_point_cloud(bytes, name, None).map_err(message).unwrap();
    let second = parse_point_cloud(bytes, name, Some(options(r#"{"scan": 1}"#))).map_err(message).unwrap();
    assert_eq!((all.len(), second.len()), (6000, 3000));
    // the file's last 1,000 points (f32 on the map grid: 0.25-0.5 apart near 4e6)
    let worst = second.iter().zip(&all[3000..]).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    assert!(worst <= 0.5, "the second scan is the file's last 1,000 points: {worst}");
    let e = parse_point_cloud(bytes, name, Some(options(r#"{"scan": 2}"#))).err().map(message);
    assert!(e.as_deref().is_some_and(|e| e.contains("scan = 2, but the E57 file holds 2 scans")), "{e:?}");
    let e = parse_point_cloud(bytes, name, Some(options(r#"{"scan": -1}"#))).err().map(message);
    assert!(e.as_deref().is_some_and(|e| e.contains("invalid read options")), "{e:?}");
}
