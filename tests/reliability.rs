//! Issue 14 (reliability), the Rust side: every defect in the catalogue has a test here (or in
//! `weights.rs`, `io_memory.rs`, `register_large_coordinates.rs`) that failed before its fix.
//! Bad input gets a clear error, and the registrar stays usable after it.

mod common;

use arps::io::read_point_cloud;
use arps::limits::MAX_POINTS_PER_CLOUD;
use arps::{Error, ModelConfig, Options, PointCloud, Registrar, Weights};
use common::{bumpy_surface, motion};

fn registrar() -> Registrar {
    Registrar::new(&Weights::random(&ModelConfig::web(), 0).unwrap()).unwrap()
}

/// A registration that works, to show the registrar is still usable after a failed call.
fn still_works(reg: &mut Registrar) {
    let source = bumpy_surface(1500, 0.0);
    let target = bumpy_surface(1500, 0.3).transformed(&motion([5.0, -3.0, 4.0], [0.05, 0.0, -0.02]));
    let r = reg.register(&source, &target, &Options::default()).unwrap();
    assert!(r.fitness > 0.5 && r.T_target_source.iter().all(|v| v.is_finite()), "fitness {}", r.fitness);
}

/// Defect 2: no up-front size check; 20M points per cloud trapped the wasm registrar for good.
#[test]
fn clouds_over_the_point_budget_are_refused_up_front() {
    let mut reg = registrar();
    let huge = PointCloud::new(vec![[0.0, 0.0, 0.0]; MAX_POINTS_PER_CLOUD + 1]);
    let small = bumpy_surface(500, 0.0);
    for (s, t, what) in [(&huge, &small, "source"), (&small, &huge, "target")] {
        let e = reg.register(s, t, &Options::default()).unwrap_err();
        assert!(matches!(e, Error::TooLarge(_)), "{e}");
        let e = e.to_string();
        assert!(e.contains(&format!("{what} has {} points", MAX_POINTS_PER_CLOUD + 1)), "{e}");
        assert!(
            e.contains(&format!("{MAX_POINTS_PER_CLOUD}")) && e.contains("downsample") && e.contains("voxel"),
            "{e}"
        );
    }
    still_works(&mut reg);
}

/// A cloud under the input budget may still keep too many points for ICP (`voxelSize: 0` keeps
/// them all): refused before ICP builds its k-d tree and normals on them, with what to change.
#[test]
fn icp_on_too_many_points_is_refused_before_it_is_built() {
    let mut reg = registrar();
    use arps::limits::{ICP_BYTES_PER_POINT, INPUT_BYTES_PER_POINT, MAX_CALL_BYTES};
    // just over what fits with voxelSize 0 (8,388,608 points)
    let n = (MAX_CALL_BYTES / 2 / (INPUT_BYTES_PER_POINT + ICP_BYTES_PER_POINT)) as usize + 1000;
    assert!(n < MAX_POINTS_PER_CLOUD && n > arps::limits::max_icp_points(n));
    // a square of n points, 1/4096 apart
    let side = (n as f64).sqrt().ceil() as usize;
    let points: Vec<[f32; 3]> =
        (0..n).map(|i| [(i % side) as f32 / 4096.0, (i / side) as f32 / 4096.0, ((i % 7) as f32) * 1e-4]).collect();
    let big = PointCloud::new(points);
    let small = bumpy_surface(500, 0.0);
    let full = Options { voxel_size: Some(0.0), ..Options::default() };
    let e = reg.register(&big, &small, &full).unwrap_err();
    assert!(matches!(e, Error::TooLarge(_)), "{e}");
    let e = e.to_string();
    assert!(e.contains(&format!("source keeps {n} of its {n} points for ICP at voxelSize 0")), "{e}");
    assert!(e.contains("larger voxelSize") && e.contains(&arps::limits::max_icp_points(n).to_string()), "{e}");
    still_works(&mut reg);
}

/// Defect 6: an initial transform with translation 1e39 returned an all-NaN matrix.
#[test]
fn out_of_range_initial_transforms_are_errors_not_nan() {
    let mut reg = registrar();
    let source = bumpy_surface(1000, 0.0);
    let target = bumpy_surface(1000, 0.2);
    for t in [1e39, 1e14, f64::INFINITY, f64::NAN] {
        let mut rows = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
        rows[0][3] = t;
        let o = Options { initial_transform: Some(rows), ..Options::default() };
        match reg.register(&source, &target, &o) {
            Err(e) => assert!(matches!(e, Error::InvalidOption(_)), "{t}: {e}"),
            Ok(r) => panic!("{t}: expected an error, got {}", r.T_target_source),
        }
    }
    // a far but meaningful guess still works, and its answer is finite
    let mut rows = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
    rows[1][3] = 1e6;
    let r = reg.register(&source, &target, &Options { initial_transform: Some(rows), ..Options::default() }).unwrap();
    assert!(r.T_target_source.iter().all(|v| v.is_finite()));
    still_works(&mut reg);
}

/// Defect 7: collinear clouds got an arbitrary turn about the line with fitness 1.0, no warning.
#[test]
fn collinear_clouds_are_refused_and_thin_ones_warned_about() {
    let mut reg = registrar();
    let line = |n: usize, shift: f32| {
        PointCloud::new((0..n).map(|i| [i as f32 * 0.01 + shift, i as f32 * 0.02, -(i as f32) * 0.005]).collect())
    };
    let cloud = bumpy_surface(800, 0.0);
    for (s, t, what) in [(line(400, 0.0), cloud.clone(), "source"), (cloud.clone(), line(400, 0.1), "target")] {
        let e = reg.register(&s, &t, &Options::default()).unwrap_err().to_string();
        assert!(e.contains(&format!("{what} is collinear")), "{e}");
    }
    let e = reg.register(&line(300, 0.0), &line(300, 0.3), &Options::default()).unwrap_err().to_string();
    assert!(e.contains("collinear"), "{e}");
    // a thin rod (1/200 as wide as long): it runs, and says the roll about its axis is weak
    let rod = |phase: f32| {
        PointCloud::new(
            (0..2000)
                .map(|i| {
                    let a = i as f32 * 2.399 + phase;
                    [i as f32 * 0.001, 0.005 * a.cos(), 0.005 * a.sin()]
                })
                .collect(),
        )
    };
    let r = reg.register(&rod(0.0), &rod(0.5), &Options::default()).unwrap();
    assert!(r.warnings.iter().any(|w| w.contains("source is nearly a line")), "{:?}", r.warnings);
    still_works(&mut reg);
}

/// Defect 8 (part): a 0-byte OBJ was a 0-point cloud instead of an error; so was any file with
/// no points.
#[test]
fn files_without_points_are_errors() {
    for name in ["a.obj", "a.ply", "a.pcd", "a.xyz", "a.off", "a.stl"] {
        let e = read_point_cloud(b"", name).unwrap_err().to_string();
        assert!(!e.is_empty(), "{name}");
    }
    let e = read_point_cloud(b"", "empty.obj").unwrap_err().to_string();
    assert!(e.contains("OBJ") && e.contains("the file is empty (0 bytes)"), "{e}");
    let e = read_point_cloud(b"# only a comment\ng group\n", "c.obj").unwrap_err().to_string();
    assert!(e.contains("no points"), "{e}");
    let e = read_point_cloud(
        b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        "z.ply",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("no points"), "{e}");
}

/// Readers refuse files declaring more points than a registration accepts, before decoding.
#[test]
fn files_declaring_too_many_points_are_refused_before_decoding() {
    let n = MAX_POINTS_PER_CLOUD as u64 + 1;
    let ply = format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
    let e = read_point_cloud(ply.as_bytes(), "big.ply").unwrap_err();
    assert!(matches!(e, Error::TooLarge(_)), "{e}");
    assert!(e.to_string().contains(&n.to_string()), "{e}");
    let pcd = format!(
        "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary\n"
    );
    assert!(matches!(read_point_cloud(pcd.as_bytes(), "big.pcd").unwrap_err(), Error::TooLarge(_)));
    let off = format!("OFF\n{n} 0 0\n0 0 0\n");
    assert!(matches!(read_point_cloud(off.as_bytes(), "big.off").unwrap_err(), Error::TooLarge(_)));
}

/// Defect 3: a compressed PCD body is decoded only up to the decoding budget.
#[test]
fn compressed_bodies_over_the_decoding_budget_are_refused() {
    let n = 7_000_000u64;
    let mut b = format!(
        "VERSION .7\nFIELDS x y z h\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 40\nWIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary_compressed\n"
    )
    .into_bytes();
    b.extend_from_slice(&4u32.to_le_bytes());
    b.extend_from_slice(&((n * 172) as u32).to_le_bytes());
    b.extend_from_slice(&[0; 4]);
    let e = read_point_cloud(&b, "big.pcd").unwrap_err();
    assert!(matches!(e, Error::TooLarge(_)), "{e}");
    assert!(e.to_string().contains("1204000000 uncompressed bytes"), "{e}");
}

/// Points so far out that squared distances to them overflow f32 (beyond 1e18 from the origin: a
/// sensor's f32::MAX for "no return", here 30 of them) are refused like NaN, naming the first, or
/// dropped with `nonFinite: "drop"`, where they made the cloud "collinear"; what is left registers
/// as the clean cloud does.
#[test]
fn points_beyond_f32_squares_are_refused_or_dropped_like_nan() {
    use arps::NonFinite;
    let mut reg = registrar();
    let target = bumpy_surface(1500, 0.3).transformed(&motion([5.0, -3.0, 4.0], [0.05, 0.0, -0.02]));
    let clean = bumpy_surface(1500, 0.0).points;
    let mut points = clean.clone();
    points.push([2e20, 0.0, 0.0]);
    points.extend(std::iter::repeat_n([0.0, f32::MAX, 0.0], 30));
    let source = PointCloud::new(points);
    let e = reg.register(&source, &target, &Options::default()).unwrap_err().to_string();
    assert!(e.contains("source point 1500 has a coordinate beyond 1e18"), "{e}");
    let drop = Options { non_finite: NonFinite::Drop, ..Options::default() };
    let r = reg.register(&source, &target, &drop).unwrap();
    let c = reg.register(&PointCloud::new(clean), &target, &drop).unwrap();
    assert_eq!((r.T_target_source, r.confidence), (c.T_target_source, c.confidence));
    assert!(!r.warnings.iter().any(|w| w.contains("rounded")), "{:?}", r.warnings);
}
