//! The `arps` command line: `register --json` prints exactly one JSON object, bad input prints one
//! line on stderr and exits non-zero, `info` describes a weights file.
#![cfg(feature = "cli")]

mod common;

use std::process::Command;

fn arps(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_arps")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap()
}

/// `--json` prints the engine's result as the contract says (`arps::contract`): camelCase fields,
/// the transform as 16 column-major numbers, plus the CLI's `wallMs` and the `source` path (as
/// with several sources, so that a batch reads one shape); it parses back into an
/// `arps::Registration` that equals the library's answer on the same pair, and has exactly the
/// library result's fields (and `wallMs`, `source`).
#[test]
fn register_json_is_the_engines_result() {
    let out = arps(&["register", "fixtures/wasm/source.ply", "fixtures/wasm/target.ply", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.trim().lines().count(), 1, "{stdout}");
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let m: Vec<f64> = v["T_target_source"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert_eq!(m.len(), 16);
    // column-major: the bottom row is elements 3, 7, 11, 15
    assert_eq!([m[3], m[7], m[11], m[15]], [0.0, 0.0, 0.0, 1.0]);
    for key in ["fitness", "inlierRmse", "confidence", "maxCorrespondenceDistance", "wallMs"] {
        assert!(v[key].as_f64().is_some(), "{key} missing in {v}");
    }
    assert!(v["icpIterations"].as_u64().is_some() && v["icpConverged"].is_boolean(), "{v}");
    assert!(v["timings"]["totalMs"].as_f64().is_some() && v["evidence"]["fitnessTight"].as_f64().is_some(), "{v}");
    assert!(v["fitness"].as_f64().unwrap() > 0.5);
    assert_eq!(v["source"], "fixtures/wasm/source.ply", "{v}");

    let parsed: arps::Registration = serde_json::from_str(stdout.trim()).unwrap();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |p: &str| arps::io::read_path(&dir.join(p)).unwrap();
    let lib = arps::Registrar::with_default_model()
        .unwrap()
        .register(&read("fixtures/wasm/source.ply"), &read("fixtures/wasm/target.ply"), &arps::Options::default())
        .unwrap();
    let mut expected: Vec<String> = serde_json::to_value(&lib).unwrap().as_object().unwrap().keys().cloned().collect();
    expected.extend(["wallMs".into(), "source".into()]);
    expected.sort();
    let mut got: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    got.sort();
    assert_eq!(got, expected);
    let err = (parsed.T_target_source - lib.T_target_source).abs().max();
    assert!(err < 1e-9, "CLI {} vs library {}", parsed.T_target_source, lib.T_target_source);
    assert_eq!(
        (parsed.start, parsed.icp_iterations, parsed.starts_refined),
        (lib.start, lib.icp_iterations, lib.starts_refined)
    );
}

#[test]
fn icp_kinds_and_human_output() {
    for icp in ["point", "plane", "off"] {
        let out = arps(&["register", "fixtures/wasm/source.ply", "fixtures/wasm/target.ply", "--icp", icp]);
        assert!(out.status.success(), "{icp}: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.contains("T_target_source") && text.contains("fitness"), "{text}");
    }
}

/// A box pair (the target turned 30 degrees about z and moved): the answer is one of four poses
/// that fit as well, so the human output lists the others under "alternative k" with their
/// matrices, with the warning, and the JSON carries them as objects with a column-major
/// `T_target_source`.
#[test]
fn register_lists_the_poses_that_fit_as_well() {
    let dir = common::scratch("cli-box");
    std::fs::create_dir_all(&dir).unwrap();
    let gt = common::motion([0.0, 0.0, 30.0], [0.4, -0.2, 0.1]);
    let source = arps::PointCloud::new(common::box_grid::box_grid(0.05, 0.0));
    let target = arps::PointCloud::new(common::box_grid::box_grid(0.05, 0.01)).transformed(&gt);
    let (src, tgt) = (dir.join("box-source.ply"), dir.join("box-target.ply"));
    std::fs::write(&src, arps::io::write_ply_binary(&source)).unwrap();
    std::fs::write(&tgt, arps::io::write_ply_binary(&target)).unwrap();
    let (src, tgt) = (src.to_str().unwrap(), tgt.to_str().unwrap());
    let out = arps(&["register", src, tgt]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("alternative 1 (fits about as well): fitness"), "{text}");
    assert!(text.contains("fit about as well (a symmetric or repeating shape?)"), "{text}");
    let out = arps(&["register", src, tgt, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let alternatives = v["alternatives"].as_array().unwrap();
    assert_eq!(text.matches("alternative ").count(), alternatives.len(), "{text}");
    for a in alternatives {
        let m: Vec<f64> = a["T_target_source"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        assert_eq!((m.len(), [m[3], m[7], m[11], m[15]]), (16, [0.0, 0.0, 0.0, 1.0]), "column-major: {a}");
        assert!(a["fitness"].as_f64().unwrap() > 0.5 && a["inlierRmse"].as_f64().is_some(), "{a}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `--surface-points N` reads a mesh file as its surface: a scan of a CAD part (an STL) registers
/// onto it with a far better fit than onto its vertices.
#[test]
fn register_reads_a_mesh_as_its_surface() {
    let dir = common::scratch("cli-mesh");
    std::fs::create_dir_all(&dir).unwrap();
    let model = "fixtures/formats/angle_block_binary_solid.stl";
    let bytes = std::fs::read(model).unwrap();
    let gt = common::motion([10.0, -20.0, 30.0], [0.5, 0.2, -0.3]);
    let scan = arps::io::read_mesh(&bytes, "block.stl").unwrap().sample_surface(8000, 7).unwrap();
    let scan_path = dir.join("scan.ply");
    std::fs::write(&scan_path, arps::io::write_ply_binary(&scan.transformed(&arps::transform::rigid_inverse(&gt))))
        .unwrap();
    let fit = |extra: &[&str]| {
        let out = arps(&[&["register", scan_path.to_str().unwrap(), model, "--json"], extra].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice::<arps::Registration>(&out.stdout).unwrap()
    };
    let surface = fit(&["--surface-points", "20000"]);
    let vertices = fit(&[]);
    assert!(arps::transform::rotation_error_deg(&surface.T_target_source, &gt) < 1.0, "{}", surface.T_target_source);
    assert!(surface.fitness > 0.8 && vertices.fitness < 0.2, "{} against {}", surface.fitness, vertices.fitness);
    // read as its vertices, the model is named in a warning that points to --surface-points
    let said = |r: &arps::Registration| r.warnings.iter().any(|w| w.contains("is a mesh, read as its vertices"));
    assert!(said(&vertices) && !said(&surface), "{:?} / {:?}", vertices.warnings, surface.warnings);
    // a point list saved as OBJ (`v` lines, no faces) is not called a mesh
    let obj: String = scan.points.iter().map(|p| format!("v {} {} {}\n", p[0], p[1], p[2])).collect();
    let obj_path = dir.join("points.obj");
    std::fs::write(&obj_path, obj).unwrap();
    let out = arps(&["register", obj_path.to_str().unwrap(), model, "--surface-points", "20000", "--json"]);
    let r: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
    assert!(!said(&r), "{:?}", r.warnings);
    let bad = arps(&["register", scan_path.to_str().unwrap(), model, "--surface-points", "3"]);
    assert!(
        !bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("surfacePoints = 3 is fewer than 16")
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `--source-scan K` / `--target-scan K` read one scan of an E57 file: the file's second scan
/// registers onto the whole file (both scans, placed by their poses) where it already lies.
#[test]
fn register_reads_one_scan_of_an_e57_file() {
    let e57 = "fixtures/formats/velodyne_two_scans.e57";
    let out = arps(&["register", e57, e57, "--source-scan", "1", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
    let id = nalgebra::Matrix4::identity();
    assert!(arps::transform::rotation_error_deg(&r.T_target_source, &id) < 0.1, "{}", r.T_target_source);
    // where the scan lies (near (512345, 4123456, 87) on the map grid) the answer moves it by little;
    // the translation alone carries the lever of the map's origin
    let at = nalgebra::Point3::new(512_350.0, 4_123_456.0, 87.0);
    let moved = (r.T_target_source.transform_point(&at) - at).norm();
    assert!(moved < 0.05, "the scan moved by {moved}: {}", r.T_target_source);
    // the human report says how far the scan's centre moves, where the translation (that of the
    // far (0, 0, 0)) is large
    let human = arps(&["register", e57, e57, "--source-scan", "1"]);
    let text = String::from_utf8_lossy(&human.stdout);
    let line = text.lines().find(|l| l.starts_with("the source's centre moves by")).expect("a centre line");
    let by: f64 = line.split_whitespace().nth(5).unwrap().parse().unwrap();
    assert!(by < 0.05, "{text}");
    // saved to an .e57 name: an E57 file of that scan alone, moved
    let dir = common::scratch("cli-scan");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scan2-aligned.e57");
    let out = arps(&["register", e57, e57, "--source-scan", "1", "--json", "--aligned", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let m: Vec<f64> = v["T_target_source"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let m = nalgebra::Matrix4::from_column_slice(&m);
    // (the JSON's numbers parse back to within an ulp: the poses' last digits may differ)
    let saved = std::fs::read(&path).unwrap();
    assert_eq!(arps::io::list_scans(&saved, "a.e57").unwrap().len(), 1);
    let scan = arps::io::ReadOptions { scan: Some(1), ..Default::default() };
    let before = arps::io::read_point_cloud_with(&std::fs::read(e57).unwrap(), e57, &scan).unwrap();
    let after = arps::io::read_point_cloud(&saved, "a.e57").unwrap();
    assert_eq!(before.len(), after.len());
    for i in 0..before.len() {
        let want = m.transform_point(&nalgebra::Point3::from(before.point_f64(i)));
        assert!((nalgebra::Point3::from(after.point_f64(i)) - want).norm() < 1e-3, "point {i}");
    }
    let bad = arps(&["register", e57, e57, "--target-scan", "2"]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("scan = 2, but the E57 file holds 2 scans"), "{err}");
    // a scan chosen in a file of one cloud is refused, the flag named
    let ply = "fixtures/scans/velodyne-small.ply";
    for (flag, args) in [("--source-scan", [ply, e57]), ("--target-scan", [e57, ply])] {
        let bad = arps(&["register", args[0], args[1], flag, "1"]);
        let err = String::from_utf8_lossy(&bad.stderr);
        assert!(!bad.status.success(), "{flag}: {err}");
        assert!(err.contains(&format!("{ply}: invalid option: {flag} (1) chooses among an E57 file's scans")), "{err}");
    }
}

/// `--source-classes` / `--target-classes`: the ground (class 2) of a LAS survey registers onto
/// the whole survey about where it lies; a class the file does not hold, and classes of a PLY file, are
/// refused with the flag named.
#[test]
fn register_reads_the_classes_of_a_las_file() {
    let las = "fixtures/formats/simple.las";
    let out = arps(&["register", las, las, "--source-classes", "2", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
    // (a sparse 4 km survey, 1065 points, judged at 58 m: its ground lands within 2 m)
    let at = nalgebra::Point3::new(637_000.0, 851_000.0, 430.0);
    assert!((r.T_target_source.transform_point(&at) - at).norm() < 2.0, "{}", r.T_target_source);
    let bad = arps(&["register", las, las, "--target-classes", "6,9"]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("none of its 1065 points is of classes 6, 9"), "{err}");
    let ply = "fixtures/scans/velodyne-small.ply";
    let bad = arps(&["register", ply, las, "--source-classes", "2"]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("--source-classes keeps points of some LAS classes, but this is a PLY file"), "{err}");
    // `--source-min-opacity` / `--target-min-opacity`: splats only; the flag named
    let bad = arps(&["register", ply, ply, "--target-min-opacity", "0.5"]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("--target-min-opacity keeps the opaque splats"), "{err}");
    assert!(err.contains("this PLY has no vertex 'opacity' property"), "{err}");
    let bad = arps(&["register", las, las, "--source-min-opacity", "2"]);
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("--source-min-opacity 2 must be a number in [0, 1]"), "{err}");
}

#[test]
fn bad_input_is_one_line_on_stderr_and_a_failure_exit() {
    let dir = common::scratch("cli");
    std::fs::create_dir_all(&dir).unwrap();
    let broken = dir.join("broken.ply");
    std::fs::write(&broken, b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n2\n").unwrap();
    let tiny = dir.join("tiny.xyz");
    std::fs::write(&tiny, b"0 0 0\n1 0 0\n0 1 0\n").unwrap();
    let broken = broken.to_str().unwrap();
    let tiny = tiny.to_str().unwrap();
    let nan = dir.join("nan.xyz");
    let rows: String = (0..40)
        .map(|i| format!("{} {} {}\n", i % 7, i / 7, if i == 5 { "nan".into() } else { (i % 3).to_string() }))
        .collect();
    std::fs::write(&nan, rows).unwrap();
    let nan = nan.to_str().unwrap();
    let (src, tgt) = ("fixtures/wasm/source.ply", "fixtures/wasm/target.ply");
    let cases: [(&[&str], &str); 11] = [
        // the engine's options named by this command's flags
        (&["register", nan, tgt], "; drop such points with --drop-non-finite)"),
        (&["register", src, tgt, "--initial-transform", "1,0,0"], "--initial-transform: expected 16 numbers"),
        (
            &["register", src, tgt, "--initial-transform", "2,0,0,0,0,2,0,0,0,0,2,0,0,0,0,1"],
            "--initial-transform is not rigid",
        ),
        (&["register", "does-not-exist.ply", "fixtures/wasm/target.ply"], "does-not-exist.ply"),
        (&["register", src, tgt, "--icp-max-iterations", "20000"], "--icp-max-iterations = 20000 is more than 10000"),
        (&["register", broken, "fixtures/wasm/target.ply", "--json"], "PLY parse error"),
        // a cloud the engine refuses is named by its file
        (&["register", tiny, "fixtures/wasm/target.ply"], "tiny.xyz: invalid point cloud: source has 3 finite points"),
        (&["register", "fixtures/wasm/source.ply", "fixtures/wasm/target.ply", "--weights", broken], "weights"),
        (&["info", "fixtures/wasm/source.ply"], "weights"),
        (&["register", src, tgt, "--voxel-size", "-1"], "--voxel-size = -1"),
        (&["register", src, tgt, "--source-overlap", "2"], "--source-overlap = 2 must be a number in (0, 1]"),
    ];
    for (args, hint) in cases {
        let out = arps(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        if args.contains(&"--json") {
            // with --json the failure is on stdout too, as JSON
            let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert!(line["error"].as_str().unwrap().contains(hint), "{args:?}: {line}");
        } else {
            assert!(out.stdout.is_empty(), "{args:?} printed on stdout");
        }
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("arps: ") && err.contains(hint), "{args:?}: {err}");
    }
}

/// `--initial-transform` (16 numbers, row by row) with `--starts initial`: ICP from that guess
/// alone, here the answer of a first run, which it keeps.
#[test]
fn register_starts_from_an_initial_transform() {
    let (src, tgt) = ("fixtures/wasm/source.ply", "fixtures/wasm/target.ply");
    let answer = |args: &[&str]| {
        let out = arps(args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let r: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
        r
    };
    let first = answer(&["register", src, tgt, "--json"]);
    let rows = arps::transform::to_rows(&first.T_target_source);
    let guess = rows.iter().flatten().map(|v| format!("{v}")).collect::<Vec<_>>().join(",");
    let again = answer(&["register", src, tgt, "--json", "--starts", "initial", "--initial-transform", &guess]);
    assert_eq!(again.start, arps::Start::Initial);
    let turn = arps::transform::rotation_error_deg(&again.T_target_source, &first.T_target_source);
    assert!(turn < 0.5, "{turn} degrees from the first answer");
}

#[test]
fn info_describes_the_default_model() {
    let out = arps(&["info", "models/web.safetensors"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for needle in ["parameters", "preset        web", "provenance"] {
        assert!(text.contains(needle), "{needle} not in {text}");
    }
}

/// Without `--starts` the CLI refines the engine's default starts (`Options::default().starts`,
/// which includes `turned`): the same answer as the library. Fixture pair 6 is one where a turned
/// start wins with the embedded model, so a CLI default that drifted from the engine's shows.
#[test]
fn register_defaults_to_the_engines_starts() {
    let (src, tgt) = ("fixtures/pairs/00006_source.ply", "fixtures/pairs/00006_target.ply");
    let out = arps(&["register", src, tgt, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();

    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |p: &str| arps::io::read_path(&dir.join(p)).unwrap();
    let lib = arps::Registrar::with_default_model()
        .unwrap()
        .register(&read(src), &read(tgt), &arps::Options::default())
        .unwrap();
    assert_eq!(v["start"], serde_json::to_value(lib.start).unwrap(), "{v}");
    // (serde_json's default float parsing may be off by an ulp)
    assert!((v["fitness"].as_f64().unwrap() - lib.fitness).abs() < 1e-12, "{v} vs {}", lib.fitness);

    // the iteration cap reaches the engine: at 1 a stage, three stages and at most three more
    let one = arps(&["register", src, tgt, "--json", "--starts", "network", "--icp-max-iterations", "1"]);
    assert!(one.status.success(), "{}", String::from_utf8_lossy(&one.stderr));
    let o: serde_json::Value = serde_json::from_slice(&one.stdout).unwrap();
    let iterations = o["icpIterations"].as_u64().unwrap();
    assert!((1..=6).contains(&iterations), "{o}");

    let three = arps(&["register", src, tgt, "--json", "--starts", "network,centroids,initial"]);
    let t: serde_json::Value = serde_json::from_slice(&three.stdout).unwrap();
    assert_ne!(t["start"], "turned", "{t}");
}

#[test]
fn a_closed_stdout_ends_quietly() {
    // `arps register ... | head -c0`: the reader is gone before the first line is written (the
    // read end is closed right after the spawn; registering takes milliseconds).
    let mut child = Command::new(env!("CARGO_BIN_EXE_arps"))
        .args(["register", "fixtures/wasm/source.ply", "fixtures/wasm/target.ply"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "status {:?}, stderr: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `quantize` writes a loadable file at each precision, records it in the provenance, and
/// refuses other bit widths with one line on stderr.
#[test]
fn quantize_writes_each_precision_and_refuses_others() {
    let dir = common::scratch("quantize");
    std::fs::create_dir_all(&dir).unwrap();
    let input = "fuzz/seeds/weights_from_bytes/tiny_f32.safetensors";
    let original = arps::Weights::from_bytes(&std::fs::read(input).unwrap()).unwrap();
    let mut sizes = Vec::new();
    for bits in ["8", "16", "32"] {
        let out_path = dir.join(format!("w{bits}.safetensors"));
        let out = arps(&["quantize", input, out_path.to_str().unwrap(), "--bits", bits]);
        assert!(out.status.success(), "{bits}: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.starts_with("wrote ") && text.contains("largest change"), "{text}");
        let bytes = std::fs::read(&out_path).unwrap();
        let w = arps::Weights::from_bytes(&bytes).unwrap();
        assert_eq!(w.config, original.config);
        assert_eq!(w.provenance["quantized"]["bits"], bits.parse::<u32>().unwrap());
        if original.provenance.is_object() {
            let stored_as = match bits {
                "8" => "int8",
                "16" => "f16",
                _ => "f32",
            };
            assert_eq!(w.provenance["stored_as"], stored_as);
        }
        sizes.push(bytes.len());
    }
    assert!(sizes[0] < sizes[1] && sizes[1] < sizes[2], "{sizes:?}");
    let out = arps(&["quantize", input, dir.join("w4.safetensors").to_str().unwrap(), "--bits", "4"]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end(), "arps: --bits 4 is not supported: use 8 (int8), 16 (f16) or 32 (f32)");
    let out = arps(&["quantize", "fixtures/wasm/source.ply", dir.join("x.safetensors").to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8(out.stderr).unwrap().starts_with("arps: fixtures/wasm/source.ply: weights: "));
    std::fs::remove_dir_all(&dir).ok();
}

/// Several sources onto one target: one JSON line per source, in order, each naming its source and
/// equal to registering that source alone (the target read and kept once); a source that cannot
/// be read gets an error line, the others are still registered, and the exit status says one
/// failed. The text report names each source.
#[test]
fn register_takes_several_sources_onto_one_target() {
    let (a, b, target) = ("fixtures/wasm/source.ply", "fixtures/any/00084_source.ply", "fixtures/wasm/target.ply");
    let untimed = |mut v: serde_json::Value| {
        let o = v.as_object_mut().unwrap();
        for key in ["wallMs", "timings", "source"] {
            o.remove(key);
        }
        v
    };
    let alone = |s: &str| {
        let out = arps(&["register", s, target, "--json"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        untimed(serde_json::from_slice(&out.stdout).unwrap())
    };
    let out = arps(&["register", a, b, a, "missing.ply", target, "--json"]);
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("1 of 4 sources failed"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<serde_json::Value> = stdout.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), 4, "{stdout}");
    for (line, source) in lines.iter().zip([a, b, a, "missing.ply"]) {
        assert_eq!(line["source"], source, "{line}");
    }
    assert!(lines[3]["error"].as_str().unwrap().contains("missing.ply"), "{}", lines[3]);
    // one source that fails: the same line on stdout, the error on stderr, exit status 2
    let out = arps(&["register", "missing.ply", target, "--json"]);
    assert_eq!(out.status.code(), Some(2));
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["source"], "missing.ply", "{line}");
    assert!(line["error"].as_str().unwrap().contains("missing.ply"), "{line}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.ply"));
    // a target that cannot be read: `{"target", "error"}`
    let out = arps(&["register", a, "missing-target.ply", "--json"]);
    assert_eq!(out.status.code(), Some(2));
    let line: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(line["target"], "missing-target.ply", "{line}");
    assert!(line["error"].as_str().unwrap().contains("missing-target.ply"), "{line}");
    let (alone_a, alone_b) = (alone(a), alone(b));
    assert_eq!(untimed(lines[0].clone()), alone_a);
    assert_eq!(untimed(lines[1].clone()), alone_b);
    assert_eq!(untimed(lines[2].clone()), alone_a);
    // the text report: a "source" line before each result
    let out = arps(&["register", a, b, target]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("source ")).count(), 2, "{text}");
    assert_eq!(text.matches("T_target_source").count(), 2, "{text}");
}

/// A registration whose `--aligned` file cannot be written (here its path is a folder) prints its
/// answer with the error (`alignedError` in JSON) and exits 2: the answer is not lost.
#[test]
fn an_aligned_file_that_cannot_be_written_keeps_the_answer() {
    let dir = common::scratch("cli-aligned-blocked");
    let blocked = dir.join("blocked-aligned.ply");
    std::fs::create_dir_all(&blocked).unwrap();
    let (source, target) = ("fixtures/wasm/source.ply", "fixtures/wasm/target.ply");
    let out = arps(&["register", source, target, "--json", "--aligned", blocked.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["T_target_source"].as_array().map(Vec::len), Some(16), "{v}");
    assert!(v["alignedError"].as_str().is_some_and(|e| e.contains("blocked-aligned.ply")), "{v}");
    assert!(v.get("aligned").is_none() && v.get("error").is_none(), "{v}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("blocked-aligned.ply"));
    let out = arps(&["register", source, target, "--aligned", blocked.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("T_target_source") && text.contains("the aligned source was not written"), "{text}");
}

/// `--aligned PATH` writes the source moved by its answer as binary PLY: every point as read,
/// mapped in f64, so a map-grid survey comes back in doubles to the last digit and a local scan
/// in floats; the JSON names the file. With several sources `{stem}` names each one. An input
/// file is never overwritten, several sources need `{stem}`, and two sources may not share a file:
/// each refused before anything is registered.
#[test]
fn register_writes_the_aligned_source() {
    let dir = common::scratch("cli-aligned");
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let matrix = |v: &serde_json::Value| {
        let m: Vec<f64> = v["T_target_source"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        nalgebra::Matrix4::from_column_slice(&m)
    };
    let apply = |m: &nalgebra::Matrix4<f64>, p: [f64; 3]| {
        let q = m.transform_point(&nalgebra::Point3::from(p));
        [q.x, q.y, q.z]
    };

    // a georeferenced survey (about 1.7e6 from zero) onto a copy of itself moved, in f64
    let survey = "fixtures/formats/1_4_w_evlr.laz";
    let cloud = arps::io::read_path(&root.join(survey)).unwrap();
    assert!(!cloud.origin_is_zero());
    let c: [f64; 3] = std::array::from_fn(|k| cloud.origin[k] + cloud.centroid()[k]);
    let truth = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(c[0] + 4.0, c[1] - 3.0, c[2] + 0.5))
        * nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), 0.2).to_homogeneous()
        * nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(-c[0], -c[1], -c[2]));
    let moved = dir.join("survey-moved.ply");
    std::fs::write(&moved, arps::io::write_ply_binary(&cloud.transformed(&truth))).unwrap();
    let out_path = dir.join("survey-aligned.ply");
    let out = arps(&["register", survey, moved.to_str().unwrap(), "--json", "--aligned", out_path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["aligned"], out_path.to_str().unwrap());
    let m = matrix(&v);
    let bytes = std::fs::read(&out_path).unwrap();
    assert!(String::from_utf8_lossy(&bytes[..200]).contains("property double x"), "doubles for a survey");
    let written = arps::io::read_point_cloud(&bytes, "survey-aligned.ply").unwrap();
    assert_eq!(written.len(), cloud.len());
    let mut worst = 0.0f64;
    for i in 0..cloud.len() {
        let (want, got) = (apply(&m, cloud.point_f64(i)), written.point_f64(i));
        worst = (0..3).map(|k| (want[k] - got[k]).abs()).fold(worst, f64::max);
    }
    // f32 offsets from a nearby origin: a hair off f64 arithmetic on the absolute points
    assert!(worst < 1e-4, "the written survey is up to {worst} from the answer applied in f64");
    // the answer itself lands the survey on its moved copy (a strip of 1,000 points: a few tenths)
    let centre_off = (0..3).map(|k| apply(&m, c)[k] - apply(&truth, c)[k]).map(|d| d * d).sum::<f64>().sqrt();
    assert!(centre_off < 1.0, "centre off by {centre_off}");

    // several local scans: floats, one file per source stem, each the source moved by its answer
    let (a, b, target) = ("fixtures/wasm/source.ply", "fixtures/any/00084_source.ply", "fixtures/wasm/target.ply");
    let pattern = dir.join("{stem}-aligned.ply");
    let out = arps(&["register", a, b, target, "--json", "--aligned", pattern.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    for (line, (source, stem)) in stdout.lines().zip([(a, "source"), (b, "00084_source")]) {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let path = dir.join(format!("{stem}-aligned.ply"));
        assert_eq!(v["aligned"], path.to_str().unwrap());
        let bytes = std::fs::read(&path).unwrap();
        assert!(String::from_utf8_lossy(&bytes[..200]).contains("property float x"), "floats for a local scan");
        let written = arps::io::read_point_cloud(&bytes, "x.ply").unwrap();
        let src = arps::io::read_path(&root.join(source)).unwrap();
        assert_eq!(written.len(), src.len());
        let m = matrix(&v);
        for i in 0..src.len() {
            let (want, got) = (apply(&m, src.point_f64(i)), written.point_f64(i));
            assert!((0..3).all(|k| (want[k] - got[k]).abs() < 1e-5), "point {i}: {want:?} vs {got:?}");
        }
    }
    // a PLY source is written as its own file moved: its normals, colours and faces kept
    let frag = "fixtures/formats/frag_115_2000_binary.ply";
    let out_path = dir.join("frag-aligned.ply");
    let out = arps(&["register", frag, frag, "--json", "--aligned", out_path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (before, after) = (std::fs::read(root.join(frag)).unwrap(), std::fs::read(&out_path).unwrap());
    assert_eq!(after, arps::io::transform_ply(&before, &matrix(&v)).unwrap());
    assert!(String::from_utf8_lossy(&after[..400]).contains("property uchar red") && after.len() == before.len());
    // a LAS source to a .las name: the survey file itself moved (its attributes kept); to .ply:
    // its points
    let las = "fixtures/formats/simple.las";
    let (las_out, ply_out) = (dir.join("simple-aligned.las"), dir.join("simple-aligned.ply"));
    for out_path in [&las_out, &ply_out] {
        let out = arps(&["register", las, las, "--json", "--aligned", out_path.to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        if out_path == &las_out {
            let bytes = std::fs::read(root.join(las)).unwrap();
            assert_eq!(std::fs::read(out_path).unwrap(), arps::io::transform_las(&bytes, &matrix(&v)).unwrap());
        } else {
            assert!(std::fs::read(out_path).unwrap().starts_with(b"ply\n"));
        }
    }
    // a PCD, a CSV and an E57 source to their own format: the file itself moved (io::transform_file)
    for (source, name) in [
        ("fixtures/formats/velodyne_2000_binary.pcd", "velo-aligned.pcd"),
        ("fixtures/formats/eth_car_1000.csv", "car.xyz"),
        ("fixtures/formats/velodyne_two_scans.e57", "two-aligned.e57"),
    ] {
        let out_path = dir.join(name);
        let out = arps(&["register", source, source, "--json", "--aligned", out_path.to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let bytes = std::fs::read(root.join(source)).unwrap();
        let want = arps::io::transform_file(&bytes, source, &matrix(&v)).unwrap();
        assert_eq!(std::fs::read(&out_path).unwrap(), want, "{source}");
    }
    let pcd_to_obj = arps(&[
        "register",
        "fixtures/formats/velodyne_2000_binary.pcd",
        target,
        "--aligned",
        dir.join("v.obj").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&pcd_to_obj.stderr);
    assert!(stderr.contains("v.obj is not a name it can write for"), "{stderr}");
    assert!(stderr.contains("name a .pcd (the source moved as it is) or .ply (its points) file"), "{stderr}");
    // a LAZ source comes back as LAZ (to a .laz name; a .las name is refused, and the other way)
    let laz = "fixtures/formats/simple.laz";
    let laz_out = dir.join("simple-aligned.laz");
    let laz_to_laz = arps(&["register", laz, las, "--json", "--aligned", laz_out.to_str().unwrap()]);
    assert!(laz_to_laz.status.success(), "{}", String::from_utf8_lossy(&laz_to_laz.stderr));
    let v: serde_json::Value = serde_json::from_slice(&laz_to_laz.stdout).unwrap();
    let bytes = std::fs::read(root.join(laz)).unwrap();
    assert_eq!(std::fs::read(&laz_out).unwrap(), arps::io::transform_las(&bytes, &matrix(&v)).unwrap());
    for (source, name, message) in
        [(laz, "x.las", "name a .laz (the source moved as it is) or .ply"), (las, "x.laz", "name a .las (the source")]
    {
        let out = arps(&["register", source, las, "--aligned", dir.join(name).to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.contains(message), "{stderr}");
    }
    // the text report says where it wrote
    let out = arps(&["register", a, target, "--aligned", dir.join("one.ply").to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("wrote the aligned source to"), "{out:?}");

    // refused before registering: an input as output (however named), several sources without
    // {stem}, two sources onto one file, a name that is not .ply; nothing is written
    let before = std::fs::read(root.join(target)).unwrap();
    let as_input = format!("{}/../wasm/target.ply", root.join("fixtures/any").display());
    let several = dir.join("all.ply");
    let twice = dir.join("{stem}.ply");
    // a hard link to an input is that input
    let copy = dir.join("copy.ply");
    std::fs::copy(root.join(a), &copy).unwrap();
    let link = dir.join("link.ply");
    std::fs::remove_file(&link).ok();
    std::fs::hard_link(&copy, &link).unwrap();
    let copied = std::fs::read(&copy).unwrap();
    let no_folder = dir.join("no-such-folder").join("out.ply");
    for (args, message) in [
        (vec!["register", a, target, "--aligned", &as_input], "is an input file"),
        (vec!["register", copy.to_str().unwrap(), target, "--aligned", link.to_str().unwrap()], "is an input file"),
        (vec!["register", a, target, "--aligned", no_folder.to_str().unwrap()], "the folder"),
        (vec!["register", a, b, target, "--aligned", several.to_str().unwrap()], "must hold {stem}"),
        (vec!["register", a, a, target, "--aligned", twice.to_str().unwrap()], "would both be written to"),
        (vec!["register", a, target, "--aligned", dir.join("aligned.las").to_str().unwrap()], "name a .ply file"),
    ] {
        let out = arps(&args);
        assert!(!out.status.success() && out.stdout.is_empty(), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(message) && stderr.lines().count() == 1, "{args:?}: {stderr}");
    }
    assert_eq!(std::fs::read(root.join(target)).unwrap(), before, "the target file is untouched");
    assert_eq!(std::fs::read(&copy).unwrap(), copied, "the linked input is untouched");
    assert!(!several.exists() && !dir.join("source.ply").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// `--source-scale F` takes the source into the target's unit: a source in metres onto a target
/// in millimetres registers with F = 1000 (the answer maps the file's points in metres into the
/// target in millimetres: the truth's rotation times 1000, its translation times 1000), where
/// without it the engine warns that the sizes differ; a factor that is not a finite number > 0 is
/// refused.
#[test]
fn register_scales_a_source_in_another_unit() {
    let dir = common::scratch("cli-scale");
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let target = arps::io::read_path(&root.join("fixtures/wasm/target.ply")).unwrap();
    let target_mm = dir.join("target-mm.ply");
    std::fs::write(
        &target_mm,
        arps::io::write_ply_binary(&target.transformed(&nalgebra::Matrix4::new_scaling(1000.0))),
    )
    .unwrap();
    let (src, tgt) = ("fixtures/wasm/source.ply", target_mm.to_str().unwrap());
    let truth = {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(root.join("fixtures/wasm/pair.json")).unwrap()).unwrap();
        let rows: Vec<Vec<f64>> = serde_json::from_value(v["T_target_source"].clone()).unwrap();
        let mut m = nalgebra::Matrix4::from_fn(|r, c| rows[r][c]);
        m.fixed_view_mut::<3, 1>(0, 3).scale_mut(1000.0);
        m
    };
    // its rigid part: the 3x3 part divided by the factor
    let rigid = |m: &nalgebra::Matrix4<f64>| {
        let mut m = *m;
        m.fixed_view_mut::<3, 3>(0, 0).unscale_mut(1000.0);
        m
    };
    let aligned = dir.join("aligned.ply");
    let out = arps(&["register", src, tgt, "--source-scale", "1000", "--json", "--aligned", aligned.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
    let (rot, tr) = (
        arps::transform::rotation_error_deg(&rigid(&r.T_target_source), &truth),
        arps::transform::translation_error(&r.T_target_source, &truth),
    );
    arps::transform::check_near_rigid(&rigid(&r.T_target_source)).unwrap();
    assert!(rot < 1.0 && tr < 20.0, "rotation error {rot} deg, translation error {tr} mm");
    assert!(!r.warnings.iter().any(|w| w.contains("differ in size")), "{:?}", r.warnings);
    assert!(!r.warning_codes.contains(&arps::WarningCode::SizeMismatch), "{:?}", r.warning_codes);
    // the aligned source is in millimetres: the file's points moved by the answer
    let written = arps::io::read_path(&aligned).unwrap();
    let source = arps::io::read_path(&root.join(src)).unwrap();
    let p = source.point_f64(7);
    let want = r.T_target_source.transform_point(&nalgebra::Point3::new(p[0], p[1], p[2]));
    let got = written.point_f64(7);
    assert!((0..3).all(|k| (got[k] - want[k]).abs() < 1e-2), "{got:?} vs {want:?}");
    // the JSON gives the factor; the text says what the matrix holds
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["sourceScale"], 1000.0, "{json}");
    let text = arps(&["register", src, tgt, "--source-scale", "1000"]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("rotation times 1000 (--source-scale)"));

    let out = arps(&["register", src, tgt, "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json.get("sourceScale").is_none(), "{json}");
    let r: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
    assert!(r.warnings.iter().any(|w| w.contains("differ in size by 10")), "{:?}", r.warnings);
    // the JSON gives each warning's kind, in the warnings' order
    let codes = json["warningCodes"].as_array().unwrap();
    assert_eq!(codes.len(), r.warnings.len(), "{json}");
    let at = r.warnings.iter().position(|w| w.contains("differ in size")).unwrap();
    assert_eq!(codes[at], "sizeMismatch", "{json}");
    // `--min-confidence`: the unscaled source (fits anywhere, at most 0.25) fails the batch after
    // its answer is printed; the scaled one passes; a bound outside [0, 1] is refused
    let out = arps(&["register", src, tgt, "--json", "--min-confidence", "0.5"]);
    assert_eq!(out.status.code(), Some(1), "below --min-confidence: 1; {}", String::from_utf8_lossy(&out.stdout));
    assert!(serde_json::from_slice::<arps::Registration>(&out.stdout).unwrap().confidence < 0.5);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("1 of 1 answers have a confidence below --min-confidence 0.5")
    );
    let out = arps(&["register", src, tgt, "--source-scale", "1000", "--min-confidence", "0.5"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = arps(&["register", src, tgt, "--min-confidence", "2"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--min-confidence: expected a number in [0, 1]"));
    assert_eq!(out.status.code(), Some(2), "an error: 2");
    let out = arps(&["register", "no-such-file.ply", tgt, "--min-confidence", "0.5"]);
    assert_eq!(out.status.code(), Some(2), "an error: 2, whatever --min-confidence");
    for bad in ["0", "-2", "NaN", "inf"] {
        let out = arps(&["register", src, tgt, "--source-scale", bad]);
        assert!(!out.status.success() && out.stdout.is_empty(), "{bad}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains("--source-scale: expected a finite number > 0"), "{bad}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `arps scans FILE` lists an E57 file's scans (index, name, records; `--json` as `listScans`
/// gives them), says a file of another format holds one cloud, and names a file it cannot read.
#[test]
fn scans_lists_an_e57_files_scans() {
    let out = arps(&["scans", "fixtures/formats/velodyne_two_scans.e57"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout), "0  scan 1  1000 points\n1  scan 2  1000 points\n");
    let out = arps(&["scans", "fixtures/formats/velodyne_two_scans.e57", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v, serde_json::json!([{ "name": "scan 1", "records": 1000 }, { "name": "scan 2", "records": 1000 }]));
    let out = arps(&["scans", "fixtures/formats/simple.las"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("one cloud (only E57 files hold several scans)"));
    let out = arps(&["scans", "fixtures/formats/missing.e57"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("missing.e57"));
}

/// `--seed` seeds the registration alone; the surface sampling of `--surface-points` has its own
/// `--surface-seed` (0 by default, as the library's and the JS package's read options): the CLI
/// with `--seed 7` answers as the library does on the mesh read with seed 0 and registered with
/// seed 7.
#[test]
fn the_registration_seed_leaves_the_surface_sampling_alone() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (mesh, scan) = ("fixtures/formats/fuze.obj", "fixtures/formats/fuze_binary.ply");
    let out = arps(&["register", scan, mesh, "--surface-points", "3000", "--seed", "7", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let cli: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
    let surface =
        |seed| arps::io::ReadOptions { surface_points: Some(3000), seed, scan: None, classes: None, min_opacity: None };
    let read = |p: &str, o: &arps::io::ReadOptions| arps::io::read_path_with(&dir.join(p), o).unwrap();
    let lib = |read_seed| {
        arps::Registrar::with_default_model()
            .unwrap()
            .register(
                &read(scan, &surface(read_seed)),
                &read(mesh, &surface(read_seed)),
                &arps::Options { seed: 7, ..arps::Options::default() },
            )
            .unwrap()
    };
    assert!((cli.T_target_source - lib(0).T_target_source).abs().max() < 1e-9);
    let out =
        arps(&["register", scan, mesh, "--surface-points", "3000", "--surface-seed", "7", "--seed", "7", "--json"]);
    let cli: arps::Registration = serde_json::from_slice(&out.stdout).unwrap();
    assert!((cli.T_target_source - lib(7).T_target_source).abs().max() < 1e-9);
}
