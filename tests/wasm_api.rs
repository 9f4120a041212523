//! The JS-facing API, run in Node by `wasm-pack test --node` (see scripts/test-wasm.sh):
//! ground-truth registration, options, readers on real bytes, every error case, and the same
//! `Registrar` still working after each error.
#![cfg(target_arch = "wasm32")]

mod wasm_common;

use arps::transform::{rotation_error_deg, translation_error};
use arps::wasm::{parse_point_cloud, version, Registrar};
use js_sys::{Array, Float32Array};
use wasm_bindgen::prelude::*;
use wasm_bindgen_test::wasm_bindgen_test;
use wasm_common::*;

/// Rotation (degrees) and translation errors of a result's `T_target_source` against the ground truth.
fn errors(result: &JsValue) -> (f64, f64) {
    let m = matrix(result, "T_target_source");
    let gt = ground_truth();
    (rotation_error_deg(&m, &gt), translation_error(&m, &gt))
}

fn register_ok(r: &mut Registrar, options: JsValue) -> JsValue {
    match r.register(&source(), &target(), Some(options), None, None, None) {
        Ok(v) => v,
        Err(e) => panic!("register failed: {}", message(e)),
    }
}

/// Asserts the registrar still recovers the fixture transform (used after every error).
fn still_works(r: &mut Registrar) {
    let res = register_ok(r, JsValue::UNDEFINED);
    let (rot, tr) = errors(&res);
    assert!(rot < 1.0 && tr < 0.02, "after an error: rotation error {rot:.3} deg, translation error {tr:.4}");
}

#[wasm_bindgen_test]
fn version_is_the_crate_version() {
    assert_eq!(version(), env!("CARGO_PKG_VERSION"));
}

#[wasm_bindgen_test]
fn known_transform_is_recovered_with_default_options() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let res = register_ok(&mut r, JsValue::UNDEFINED);
    let (rot, tr) = errors(&res);
    assert!(rot < 1.0, "rotation error {rot:.3} deg");
    assert!(tr < 0.02, "translation error {tr:.4} (clouds are ~2 units across)");
    // The rest of the result object.
    let net = matrix(&res, "T_target_source_network");
    assert!(arps::transform::check_rigid(&net, 1e-3).is_ok(), "T_target_source_network is rigid: {net}");
    let fitness = num(&res, "fitness");
    assert!((0.5..=1.0).contains(&fitness), "fitness {fitness}");
    let rmse = num(&res, "inlierRmse");
    assert!(rmse > 0.0 && rmse < num(&res, "maxCorrespondenceDistance"), "inlierRmse {rmse}");
    assert!(num(&res, "icpIterations") >= 1.0);
    assert!(get(&res, "icpConverged").as_bool().is_some());
    let start = get(&res, "start").as_string().unwrap_or_default();
    assert!(
        [
            "network",
            "centroids",
            "initial",
            "turned",
            "turnedInitial",
            "global",
            "globalNetwork",
            "rotations",
            "rotationsNetwork",
        ]
        .contains(&start.as_str()),
        "start {start:?}"
    );
    let timings = get(&res, "timings");
    for k in ["preprocessMs", "networkMs", "gmrMs", "icpMs", "totalMs"] {
        assert!(num(&timings, k) >= 0.0, "timings.{k}");
    }
    assert!(num(&timings, "totalMs") > 0.0, "the performance.now clock is installed");
    assert!(num(&timings, "globalMs") >= 0.0, "timings.globalMs");
    let warnings = strings(&get(&res, "warnings"));
    // How sure the engine is: high on this known pair, so no "low confidence" warning.
    let confidence = num(&res, "confidence");
    assert!((0.8..=1.0).contains(&confidence), "confidence {confidence} on the known pair");
    assert!(!warnings.iter().any(|w| w.starts_with("low confidence")), "{warnings:?}");
    assert!(num(&res, "startsRefined") >= 1.0);
    assert_evidence_is_sane(&get(&res, "evidence"));
}

/// The JS result is the core's `Registration` serialised (`arps::contract`): `JSON.stringify` of it
/// parses back into a `Registration` equal to the core's own answer on the same clouds, with the
/// same fields as the core result's JSON (what `arps register --json` prints).
#[wasm_bindgen_test]
fn the_js_result_is_the_core_result() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let res = register_ok(&mut r, JsValue::UNDEFINED);
    let json = String::from(js_sys::JSON::stringify(&res).unwrap());
    let from_js: arps::Registration = serde_json::from_str(&json).unwrap();
    let src = arps::PointCloud::from_xyz(&source()).unwrap();
    let tgt = arps::PointCloud::from_xyz(&target()).unwrap();
    let core = arps::Registrar::with_default_model().unwrap().register(&src, &tgt, &arps::Options::default()).unwrap();
    assert!((from_js.T_target_source - core.T_target_source).abs().max() < 1e-12);
    assert_eq!(
        (from_js.start, from_js.icp_iterations, from_js.starts_refined),
        (core.start, core.icp_iterations, core.starts_refined)
    );
    let js_keys: serde_json::Value = serde_json::from_str(&json).unwrap();
    let core_keys = serde_json::to_value(&core).unwrap();
    let names = |v: &serde_json::Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
    assert_eq!(names(&js_keys), names(&core_keys));
}

/// On a symmetric shape the result offers the poses that fit about as well (`alternatives`):
/// objects with a column-major `T_target_source`, a `fitness` and an `inlierRmse`; a box answered
/// turned 180 degrees by the local search has the truth among them, ready for a three.js matrix.
/// (The truth leaves none of the box off the other grid, the half turn 2% of it: the adaptive
/// search takes the truth, with the half turn among the alternatives.)
#[wasm_bindgen_test]
fn a_symmetric_shape_offers_its_look_alike_poses() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let flat = |points: Vec<[f32; 3]>| points.concat();
    let (source, target) = (flat(box_grid::box_grid(0.05, 0.0)), flat(box_grid::box_grid(0.05, 0.01)));
    // the truth is the identity; a half turn about y fits as well
    #[rustfmt::skip]
    let turned = nalgebra::Matrix4::new(
        -1.0, 0.0, 0.0, 0.0,
        0.0, 1.0, 0.0, 0.0,
        0.0, 0.0, -1.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    );
    let mut from_turned = |search: &str| {
        let opts = options(&format!(r#"{{"network": false, "starts": ["initial"], "search": "{search}"}}"#));
        js_sys::Reflect::set(&opts, &"initialTransform".into(), &column_major_js(&turned)).unwrap();
        match r.register(&source, &target, Some(opts), None, None, None) {
            Ok(v) => v,
            Err(e) => panic!("register failed: {}", message(e)),
        }
    };
    let adaptive = from_turned("adaptive");
    assert!(rotation_error_deg(&matrix(&adaptive, "T_target_source"), &nalgebra::Matrix4::identity()) < 2.0);
    let turned_among = Array::from(&get(&adaptive, "alternatives"))
        .iter()
        .any(|a| rotation_error_deg(&matrix(&a, "T_target_source"), &turned) < 3.0);
    assert!(turned_among, "the half turn among the adaptive search's alternatives");
    let res = from_turned("local");
    assert!(rotation_error_deg(&matrix(&res, "T_target_source"), &turned) < 3.0, "the answer stays turned");
    let alternatives = get(&res, "alternatives");
    assert!(Array::is_array(&alternatives), "alternatives is an Array");
    let alternatives: Vec<JsValue> = Array::from(&alternatives).iter().collect();
    assert!(!alternatives.is_empty() && num(&get(&res, "evidence"), "alternatives") >= 1.0);
    let identity = nalgebra::Matrix4::identity();
    let mut truth_found = false;
    for a in &alternatives {
        let m = matrix(a, "T_target_source");
        assert!(arps::transform::check_rigid(&m, 1e-6).is_ok(), "rigid: {m}");
        assert!((0.0..=1.0).contains(&num(a, "fitness")) && num(a, "inlierRmse") >= 0.0);
        truth_found |= rotation_error_deg(&m, &identity) < 2.0 && translation_error(&m, &identity) < 0.02;
    }
    assert!(truth_found, "the truth is among the alternatives");
    assert!(strings(&get(&res, "warnings")).iter().any(|w| w.contains("fit")), "the result says it is not unique");
}

/// The result's `evidence`: exactly the core's fields, camelCase, each in its range.
fn assert_evidence_is_sane(evidence: &JsValue) {
    let fractions = ["fitness", "fitnessTight", "fitnessLoose", "fitnessCoarse", "overlapReverse"];
    for k in fractions {
        let v = num(evidence, k);
        assert!((0.0..=1.0).contains(&v), "evidence.{k} = {v}");
    }
    // The fitness curve rises with the distance.
    let curve = ["fitnessTight", "fitness", "fitnessLoose", "fitnessCoarse"].map(|k| num(evidence, k));
    assert!(curve.windows(2).all(|w| w[0] <= w[1]), "fitness curve {curve:?}");
    let rmse_ratio = num(evidence, "rmseRatio");
    assert!((0.0..=1.0).contains(&rmse_ratio), "evidence.rmseRatio = {rmse_ratio}");
    let ambiguity = num(evidence, "ambiguity");
    assert!((0.0..=2.0).contains(&ambiguity), "evidence.ambiguity = {ambiguity}");
    let alternatives = num(evidence, "alternatives");
    assert!(
        alternatives.fract() == 0.0 && (0.0..=9.0).contains(&alternatives),
        "evidence.alternatives = {alternatives}"
    );
    let slide = num(evidence, "slide");
    assert!((0.0..=2.0).contains(&slide), "evidence.slide = {slide}");
    let constraint = num(evidence, "constraint");
    assert!((0.0..=1.0).contains(&constraint), "evidence.constraint = {constraint}");
    let mut keys: Vec<String> =
        js_sys::Object::keys(evidence.unchecked_ref::<js_sys::Object>()).iter().filter_map(|k| k.as_string()).collect();
    keys.sort();
    let mut want: Vec<String> = fractions
        .iter()
        .chain(&["rmseRatio", "ambiguity", "alternatives", "slide", "constraint"])
        .map(|k| k.to_string())
        .collect();
    want.sort();
    assert_eq!(keys, want, "evidence fields");
}

#[wasm_bindgen_test]
fn search_option_and_global_starts() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let adaptive = register_ok(&mut r, JsValue::UNDEFINED);
    let explicit = register_ok(&mut r, options(r#"{"search": "adaptive"}"#));
    assert_eq!(matrix(&adaptive, "T_target_source"), matrix(&explicit, "T_target_source"), "adaptive is the default");
    assert_eq!(num(&adaptive, "startsRefined"), num(&explicit, "startsRefined"));
    // Exhaustive refines every start: at least as many as the adaptive search, which stops early
    // on this easy pair.
    let exhaustive = register_ok(&mut r, options(r#"{"search": "exhaustive"}"#));
    let (rot, tr) = errors(&exhaustive);
    assert!(rot < 1.0 && tr < 0.02, "exhaustive: {rot:.3} deg, {tr:.4}");
    assert!(
        num(&exhaustive, "startsRefined") > num(&adaptive, "startsRefined"),
        "exhaustive refined {} starts, adaptive {}",
        num(&exhaustive, "startsRefined"),
        num(&adaptive, "startsRefined")
    );
    let c = num(&exhaustive, "confidence");
    assert!((0.8..=1.0).contains(&c), "exhaustive confidence {c}");
    assert_evidence_is_sane(&get(&exhaustive, "evidence"));
    // The global starts are accepted by name; the answer is rigid and its confidence a probability.
    for starts in [r#"["global"]"#, r#"["globalNetwork"]"#, r#"["network", "global", "globalNetwork"]"#] {
        let res = register_ok(&mut r, options(&format!(r#"{{"starts": {starts}, "search": "exhaustive"}}"#)));
        assert!(arps::transform::check_rigid(&matrix(&res, "T_target_source"), 1e-3).is_ok(), "starts {starts}");
        let start = get(&res, "start").as_string().unwrap_or_default();
        assert!(["network", "global", "globalNetwork"].contains(&start.as_str()), "starts {starts}: start {start:?}");
        let c = num(&res, "confidence");
        assert!((0.0..=1.0).contains(&c), "starts {starts}: confidence {c}");
    }
    // A bad value: a clear error naming the accepted ones, and the registrar still works.
    for bad in [r#"{"search": "thorough"}"#, r#"{"search": 1}"#] {
        let e = r.register(&source(), &target(), Some(options(bad)), None, None, None).err().map(message).expect(bad);
        assert!(e.starts_with("invalid options"), "{bad}: {e}");
        if bad.contains("thorough") {
            assert!(e.contains("thorough") && e.contains("adaptive") && e.contains("exhaustive"), "{e}");
        }
    }
    still_works(&mut r);
}

#[wasm_bindgen_test]
fn the_network_from_every_turn_is_a_start_that_needs_the_network() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    // named alone: the 24 turns, each refined by the network, then ICP; the known pair recovered
    let res = register_ok(&mut r, options(r#"{"starts": ["rotationsNetwork"]}"#));
    let (rot, tr) = errors(&res);
    assert!(rot < 1.0 && tr < 0.02, "{rot:.3} deg, {tr:.4}");
    assert_eq!(get(&res, "start").as_string().as_deref(), Some("rotationsNetwork"));
    assert!(num(&res, "startsRefined") >= 24.0, "{} starts", num(&res, "startsRefined"));
    let t = get(&res, "timings");
    assert!(num(&t, "networkMs") > 0.0 && num(&t, "networkMs") <= num(&t, "totalMs"), "the turns' passes are timed");
    // without the network it cannot run alone: a clear error, and the registrar still works
    let bad = r#"{"network": false, "starts": ["rotationsNetwork"]}"#;
    let e = r.register(&source(), &target(), Some(options(bad)), None, None, None).err().map(message).expect(bad);
    assert!(e.contains("rotationsNetwork") && e.contains("\"rotations\""), "{e}");
    still_works(&mut r);
}

#[wasm_bindgen_test]
fn empty_and_null_options_mean_defaults_and_results_are_deterministic() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let a = register_ok(&mut r, JsValue::UNDEFINED);
    let b = register_ok(&mut r, JsValue::NULL);
    let c = register_ok(&mut r, empty_object());
    let d = register_ok(&mut r, options(r#"{"seed": 0, "icp": "plane", "icpMaxIterations": 30}"#));
    register_ok(&mut r, options(r#"{"up": [0, 0, 1]}"#));
    // `undefined` and `null` fields are "not given" (JS callers spread optional settings).
    let e_opts = options(r#"{"networkPoints": null, "maxCorrespondenceDistance": null}"#);
    js_sys::Reflect::set(&e_opts, &"seed".into(), &JsValue::UNDEFINED).unwrap();
    js_sys::Reflect::set(&e_opts, &"someFutureOption".into(), &JsValue::UNDEFINED).unwrap();
    let e = register_ok(&mut r, e_opts);
    for other in [&b, &c, &d, &e] {
        assert_eq!(matrix(&a, "T_target_source"), matrix(other, "T_target_source"));
        assert_eq!(matrix(&a, "T_target_source_network"), matrix(other, "T_target_source_network"));
    }
}

#[wasm_bindgen_test]
fn options_are_honoured() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let off = register_ok(&mut r, options(r#"{"icp": "off"}"#));
    assert_eq!(num(&off, "icpIterations"), 0.0);
    assert_eq!(get(&off, "icpConverged").as_bool(), Some(false));
    assert_eq!(
        matrix(&off, "T_target_source"),
        matrix(&off, "T_target_source_network"),
        "with ICP off the answer is the network's"
    );

    let point = register_ok(&mut r, options(r#"{"icp": "point", "seed": 7, "networkPoints": 256}"#));
    let (rot, tr) = errors(&point);
    assert!(rot < 1.0 && tr < 0.02, "point-to-point: {rot:.3} deg, {tr:.4}");

    // ICP alone (the classical baseline): the coarse estimate is the identity.
    let icp_only = register_ok(&mut r, options(r#"{"network": false}"#));
    let coarse = matrix(&icp_only, "T_target_source_network");
    assert!(
        (coarse - nalgebra::Matrix4::identity()).abs().max() < 1e-6,
        "network off: the coarse estimate is the identity, got {coarse}"
    );
    let (rot, tr) = errors(&icp_only);
    assert!(rot < 1.0 && tr < 0.02, "network off: {rot:.3} deg, {tr:.4}");

    // One start: the answer says it came from there.
    let single = register_ok(&mut r, options(r#"{"starts": ["network"]}"#));
    assert_eq!(get(&single, "start").as_string().as_deref(), Some("network"));
    let (rot, tr) = errors(&single);
    assert!(rot < 1.0 && tr < 0.02, "starts [network]: {rot:.3} deg, {tr:.4}");
    let no_net = register_ok(&mut r, options(r#"{"starts": ["network"], "network": false}"#));
    assert_eq!(get(&no_net, "start").as_string().as_deref(), Some("initial"), "no network: the initial transform");
    // The turned starts alone: six turns of the estimate, none of them the estimate itself.
    let turned = register_ok(&mut r, options(r#"{"starts": ["turned"]}"#));
    assert_eq!(get(&turned, "start").as_string().as_deref(), Some("turned"));

    let d = register_ok(&mut r, options(r#"{"maxCorrespondenceDistance": 0.08, "voxelSize": 0}"#));
    assert!((num(&d, "maxCorrespondenceDistance") - 0.08).abs() < 1e-9);

    // initialTransform as the core's row-major rows, and as a column-major Float32Array(16)
    // (three.js `matrix.elements`, or a previous result's `T_target_source`); both start at the answer.
    let gt = ground_truth();
    let rows = serde_json::to_string(&arps::transform::to_rows(&gt)).unwrap();
    let from_rows = register_ok(&mut r, options(&format!(r#"{{"initialTransform": {rows}}}"#)));
    let (rot, tr) = errors(&from_rows);
    assert!(rot < 1.0 && tr < 0.02, "initialTransform rows: {rot:.3} deg, {tr:.4}");
    let opts = options("{}");
    js_sys::Reflect::set(&opts, &"initialTransform".into(), &column_major_js(&gt)).unwrap();
    let from_cm = register_ok(&mut r, opts.clone());
    assert!(
        (matrix(&from_rows, "T_target_source") - matrix(&from_cm, "T_target_source")).abs().max() < 1e-5,
        "rows and column-major (f32) give the same, up to f32 rounding of the initial guess"
    );
    assert!(get(&opts, "initialTransform").is_instance_of::<Float32Array>(), "the caller's object is not modified");
    let flat: Array = transform_flat_array(&gt);
    js_sys::Reflect::set(&opts, &"initialTransform".into(), &flat).unwrap();
    let from_array = register_ok(&mut r, opts);
    assert!(
        (matrix(&from_rows, "T_target_source") - matrix(&from_array, "T_target_source")).abs().max() < 1e-5,
        "a plain array of 16 works too"
    );
}

fn transform_flat_array(m: &nalgebra::Matrix4<f64>) -> Array {
    let mut a = [0.0; 16];
    for c in 0..4 {
        for r in 0..4 {
            a[c * 4 + r] = m[(r, c)];
        }
    }
    a.iter().map(|v| JsValue::from_f64(*v)).collect()
}

#[wasm_bindgen_test]
fn nan_points_can_be_dropped() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let mut src = source();
    src[3 * 10 + 1] = f32::NAN;
    src[3 * 20] = f32::INFINITY;
    let res = r
        .register(&src, &target(), Some(options(r#"{"nonFinite": "drop"}"#)), None, None, None)
        .map_err(message)
        .unwrap();
    let (rot, tr) = errors(&res);
    assert!(rot < 1.0 && tr < 0.02, "{rot:.3} deg, {tr:.4}");
}

#[wasm_bindgen_test]
fn stray_returns_are_left_out_unless_kept() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    // 3 of the source's points far out (ten times its size away): left out, with a warning
    let mut src = source();
    for (k, i) in [5usize, 400, 900].into_iter().enumerate() {
        src[3 * i..3 * i + 3].copy_from_slice(&[20.0 + k as f32, -15.0, 12.0 - k as f32]);
    }
    let res = r.register(&src, &target(), None, None, None, None).map_err(message).unwrap();
    let warnings = strings(&get(&res, "warnings"));
    assert!(warnings.iter().any(|w| w.contains("left out 3 of the source's")), "{warnings:?}");
    // each warning's kind, in the same order, as JS strings
    let codes = strings(&get(&res, "warningCodes"));
    assert_eq!(codes.len(), warnings.len(), "{codes:?}");
    let at = warnings.iter().position(|w| w.contains("left out 3 of the source's")).unwrap();
    assert_eq!(codes[at], "outliersDropped", "{codes:?}");
    let kept = r
        .register(&src, &target(), Some(options(r#"{"outliers": "keep"}"#)), None, None, None)
        .map_err(message)
        .unwrap();
    assert!(!strings(&get(&kept, "warnings")).iter().any(|w| w.contains("left out")));
}

#[wasm_bindgen_test]
fn a_support_plane_under_the_source_alone_is_left_out_unless_kept() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    // a level square under the source, reaching out beyond it on every side (a table), with as
    // many points as the source
    let mut src = source();
    let n = src.len() / 3;
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in src.chunks_exact(3) {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let side = 32;
    for k in 0..side * side {
        let (u, v) = ((k % side) as f32 / (side - 1) as f32, (k / side) as f32 / (side - 1) as f32);
        let x = lo[0] - (hi[0] - lo[0]) + 3.0 * (hi[0] - lo[0]) * u;
        let y = lo[1] - (hi[1] - lo[1]) + 3.0 * (hi[1] - lo[1]) * v;
        src.extend([x, y, lo[2] - 0.01]);
    }
    let res = r.register(&src, &target(), None, None, None, None).map_err(message).unwrap();
    let warnings = strings(&get(&res, "warnings"));
    assert!(
        warnings.iter().any(|w| w.contains(&format!("of the source's {} points", n + side * side))),
        "{warnings:?}"
    );
    let kept = r
        .register(&src, &target(), Some(options(r#"{"supportPlane": "keep"}"#)), None, None, None)
        .map_err(message)
        .unwrap();
    assert!(!strings(&get(&kept, "warnings")).iter().any(|w| w.contains("left out a plane")));
}

/// Each error: a thrown JS `Error` with the core's message, and the same instance still works.
#[wasm_bindgen_test]
fn every_error_throws_and_the_registrar_keeps_working() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let src = source();
    let tgt = target();
    let expect_err = |r: &mut Registrar, s: &[f32], t: &[f32], o: JsValue, needle: &str| {
        let e = r
            .register(s, t, Some(o), None, None, None)
            .err()
            .map(message)
            .unwrap_or_else(|| panic!("expected an error containing {needle:?}"));
        assert!(e.contains(needle), "error {e:?} should contain {needle:?}");
    };
    // Packed length not a multiple of 3, on either side.
    expect_err(
        &mut r,
        &src[..src.len() - 1],
        &tgt,
        JsValue::UNDEFINED,
        "source: invalid point cloud: packed xyz buffer has length",
    );
    expect_err(&mut r, &src, &tgt[..tgt.len() - 2], JsValue::UNDEFINED, "target: invalid point cloud");
    still_works(&mut r);
    // NaN / Inf.
    let mut bad = src.clone();
    bad[3 * 17 + 2] = f32::NAN;
    expect_err(&mut r, &bad, &tgt, JsValue::UNDEFINED, "source point 17 has a non-finite coordinate");
    let mut bad = tgt.clone();
    bad[0] = f32::NEG_INFINITY;
    expect_err(&mut r, &src, &bad, JsValue::UNDEFINED, "target point 0 has a non-finite coordinate");
    still_works(&mut r);
    // Too few points, empty, all coincident.
    expect_err(&mut r, &src[..3 * 5], &tgt, JsValue::UNDEFINED, "source has 5 finite points");
    expect_err(&mut r, &src, &[], JsValue::UNDEFINED, "target has 0 finite points");
    expect_err(&mut r, &[1.0; 3 * 40], &tgt, JsValue::UNDEFINED, "zero extent");
    still_works(&mut r);
    // Bad options: unknown/misspelled field, wrong enum value, wrong type, out of range, not an object.
    expect_err(&mut r, &src, &tgt, options(r#"{"icpMaxIteration": 10}"#), "unknown field `icpMaxIteration`");
    expect_err(&mut r, &src, &tgt, options(r#"{"icp": "planar"}"#), "invalid options: `icp`: unknown variant `planar`");
    expect_err(&mut r, &src, &tgt, options(r#"{"seed": "seven"}"#), "invalid options: `seed`: invalid type");
    expect_err(
        &mut r,
        &src,
        &tgt,
        options(r#"{"icp": "point", "seed": -1}"#),
        "invalid options: `seed`: invalid value: -1",
    );
    expect_err(&mut r, &src, &tgt, options(r#"{"networkPoints": 2}"#), "networkPoints = 2");
    expect_err(&mut r, &src, &tgt, options(r#"{"icpMaxIterations": 100000}"#), "icpMaxIterations");
    expect_err(&mut r, &src, &tgt, options(r#"{"maxCorrespondenceDistance": -1}"#), "maxCorrespondenceDistance");
    expect_err(&mut r, &src, &tgt, options(r#"{"voxelSize": -0.5}"#), "voxelSize");
    expect_err(&mut r, &src, &tgt, options(r#"{"nonFinite": "keep"}"#), "invalid options");
    expect_err(&mut r, &src, &tgt, options(r#"{"outliers": "remove"}"#), "invalid options");
    expect_err(&mut r, &src, &tgt, options(r#"{"supportPlane": "remove"}"#), "invalid options");
    expect_err(&mut r, &src, &tgt, options(r#"{"network": "yes"}"#), "invalid options");
    expect_err(&mut r, &src, &tgt, options(r#"{"starts": []}"#), "starts is empty");
    expect_err(&mut r, &src, &tgt, options(r#"{"starts": ["initial", "initial"]}"#), "starts lists \"initial\" twice");
    expect_err(&mut r, &src, &tgt, options(r#"{"starts": ["identity"]}"#), "invalid options");
    expect_err(&mut r, &src, &tgt, options(r#"{"starts": "network"}"#), "invalid options");
    expect_err(&mut r, &src, &tgt, options(r#"{"up": [0, 0, 0]}"#), "up = [0.0, 0.0, 0.0]");
    expect_err(&mut r, &src, &tgt, options(r#"{"up": [0, 1]}"#), "invalid options");
    expect_err(&mut r, &src, &tgt, options(r#"{"up": [0, 0, 1, 2]}"#), "`up`: expected 3 numbers [x, y, z], got 4");
    // serde-wasm-bindgen's words made the contract's
    expect_err(&mut r, &src, &tgt, options(r#"{"up": "z"}"#), "`up`: invalid type: expected a list");
    expect_err(
        &mut r,
        &src,
        &tgt,
        options(r#"{"up": [[0, 0, 1]]}"#),
        "`up`: invalid type: [0, 0, 1], expected a number",
    );
    expect_err(&mut r, &src, &tgt, options(r#"{"seed": [1]}"#), "`seed`: invalid type: [1], expected a whole number");
    expect_err(&mut r, &src, &tgt, options(r#"{"seed": 9007199254740992}"#), "give it as a bigint");
    expect_err(&mut r, &src, &tgt, options("[1, 2]"), "expected a plain object");
    expect_err(&mut r, &src, &tgt, JsValue::from_f64(3.0), "expected a plain object");
    let scaled = r#"{"initialTransform": [[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]}"#;
    expect_err(&mut r, &src, &tgt, options(scaled), "initialTransform is not rigid");
    expect_err(&mut r, &src, &tgt, options(r#"{"initialTransform": [1, 0, 0]}"#), "invalid options");
    let opts = options("{}");
    js_sys::Reflect::set(&opts, &"initialTransform".into(), &Float32Array::new_with_length(9)).unwrap();
    expect_err(&mut r, &src, &tgt, opts, "initialTransform has 9 elements");
    let fifteen = format!(r#"{{"initialTransform": [{}]}}"#, ["0"; 15].join(","));
    expect_err(&mut r, &src, &tgt, options(&fifteen), "initialTransform has 15 elements");
    // Getters and Proxy traps that throw: this call's error, never an exception through wasm.
    let made = |body: &str| js_sys::Function::new_no_args(body).call0(&JsValue::NULL).unwrap();
    let getter = made("return { get seed() { throw new Error('boom'); } }");
    expect_err(&mut r, &src, &tgt, getter, "invalid options: reading `seed` threw: boom");
    let keys = made("return new Proxy({}, { ownKeys() { throw new Error('no keys'); } })");
    expect_err(&mut r, &src, &tgt, keys, "invalid options: listing them threw: no keys");
    let get = made("return new Proxy({ icp: 'point' }, { get() { throw new Error('no get'); } })");
    expect_err(&mut r, &src, &tgt, get, "invalid options: reading `icp` threw: no get");
    still_works(&mut r);
    // Reader and weights errors do not touch the registrar; it still works after them too.
    assert!(parse_point_cloud(b"\x00\x01garbage", "cloud.unknownext", None).is_err());
    assert!(Registrar::from_bytes(b"not weights").is_err());
    still_works(&mut r);
}

#[wasm_bindgen_test]
fn corrupt_weights_bytes_throw() {
    for (bytes, what) in [
        (&b""[..], "empty"),
        (&b"\x08\x00\x00\x00\x00\x00\x00\x00{}"[..], "tiny header"),
        (&b"definitely not a safetensors file"[..], "text"),
    ] {
        let e = Registrar::from_bytes(bytes).err().map(message).unwrap_or_else(|| panic!("{what}: expected an error"));
        assert!(e.starts_with("weights: "), "{what}: {e}");
    }
    // The real file, truncated and bit-flipped in its header.
    let good = default_model_bytes();
    let e = Registrar::from_bytes(&good[..good.len() / 2]).err().map(message).expect("truncated");
    assert!(e.starts_with("weights: "), "{e}");
    let mut flipped = good.clone();
    flipped[8] ^= 0x55; // the header JSON's opening brace
    let e = Registrar::from_bytes(&flipped).err().map(message).expect("flipped header byte");
    assert!(e.starts_with("weights: "), "{e}");
    // The untouched bytes load and work.
    let mut r = Registrar::from_bytes(&good).map_err(message).unwrap();
    still_works(&mut r);
}

fn default_model_bytes() -> Vec<u8> {
    arps::weights::DEFAULT_MODEL.to_vec()
}

#[wasm_bindgen_test]
fn custom_weights_from_bytes_match_the_default_model() {
    let mut a = Registrar::with_default_model().map_err(message).unwrap();
    let mut b = Registrar::from_bytes(&default_model_bytes()).map_err(message).unwrap();
    let ra = register_ok(&mut a, JsValue::UNDEFINED);
    let rb = register_ok(&mut b, JsValue::UNDEFINED);
    assert_eq!(matrix(&ra, "T_target_source"), matrix(&rb, "T_target_source"));
    // A different (tiny) model loads from bytes, reports its config, and registers.
    let tiny = arps::Weights::random(&arps::ModelConfig::tiny(), 1).unwrap().to_bytes(arps::StoreAs::F32).unwrap();
    let mut t = Registrar::from_bytes(&tiny).map_err(message).unwrap();
    let config = t.model_config().map_err(message).unwrap();
    assert_eq!(get(&config, "preset").as_string().as_deref(), Some("tiny"));
    // camelCase like the rest of the JS API, every field of the core's config
    let tiny_config = arps::ModelConfig::tiny();
    assert_eq!(get(&config, "nPoints").as_f64(), Some(tiny_config.n_points as f64));
    assert_eq!(get(&config, "featureDim").as_f64(), Some(tiny_config.feature_dim as f64));
    assert_eq!(get(&config, "layerNormEps").as_f64().map(|v| v as f32), Some(tiny_config.layer_norm_eps));
    assert!(get(&config, "n_points").is_undefined());
    let keys = js_sys::Object::keys(config.unchecked_ref::<js_sys::Object>()).length();
    let fields = serde_json::to_value(&tiny_config).unwrap().as_object().unwrap().len();
    assert_eq!(keys as usize, fields);
    assert_eq!(get(&t.provenance().map_err(message).unwrap(), "kind").as_string().as_deref(), Some("random"));
    let res = t.register(&source(), &target(), None, None, None, None).map_err(message).unwrap();
    assert!(arps::transform::check_rigid(&matrix(&res, "T_target_source"), 1e-3).is_ok());
}

#[wasm_bindgen_test]
fn parse_point_cloud_reads_real_bytes() {
    let want = source();
    let got = parse_point_cloud(SOURCE_PLY, "source.ply", None).map_err(message).unwrap();
    assert_eq!(got, want, "PLY by extension");
    let got = parse_point_cloud(SOURCE_PLY, "no-extension", None).map_err(message).unwrap();
    assert_eq!(got, want, "PLY sniffed from the content");
    let got = parse_point_cloud(SOURCE_PLY, "SOURCE.PLY", None).map_err(message).unwrap();
    assert_eq!(got, want, "upper-case extension");
    // The readers' output registers as is.
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let tgt = parse_point_cloud(TARGET_PLY, "target.ply", None).map_err(message).unwrap();
    let res = r.register(&got, &tgt, None, None, None, None).map_err(message).unwrap();
    let (rot, tr) = errors(&res);
    assert!(rot < 1.0 && tr < 0.02, "{rot:.3} deg, {tr:.4}");
}

#[wasm_bindgen_test]
fn parse_point_cloud_errors_are_thrown() {
    let e = parse_point_cloud(b"\x00\x01\x02 certainly not a point cloud", "cloud.unknownext", None).err().map(message);
    assert!(e.is_some(), "unknown format throws");
    let e = parse_point_cloud(b"\x00\x01\x02 certainly not a point cloud", "cloud", None).err().map(message);
    assert!(e.is_some(), "unsniffable content throws");
    let truncated = &SOURCE_PLY[..SOURCE_PLY.len() / 2 - 7];
    let e = parse_point_cloud(truncated, "source.ply", None).err().map(message).expect("truncated PLY throws");
    assert!(e.contains("PLY"), "{e}");
    let e =
        parse_point_cloud(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n", "x.ply", None)
            .err()
            .map(message);
    assert!(e.is_some(), "PLY without y/z throws");
}

/// `transformPointCloud` maps a cloud, a `Float32Array` or `{ points, origin }`, by a rigid 4x4
/// (the origin in f64); `writePly` writes it back in doubles when it has an origin, floats when
/// not; bad matrices and clouds throw, and the registrar still works.
#[wasm_bindgen_test]
fn transform_and_write_a_cloud() {
    use arps::wasm::{transform_point_cloud, write_ply};
    let gt = ground_truth();
    let column_major: Vec<f64> = gt.as_slice().to_vec();
    // a Float32Array: the points mapped, origin zero, the same as the core's transform
    let flat = Float32Array::from(&source()[..]);
    let moved = transform_point_cloud(flat.clone().into(), &column_major).map_err(message).unwrap();
    let points = Float32Array::from(get(&moved, "points")).to_vec();
    let core = arps::PointCloud::from_xyz(&source()).unwrap().transformed(&gt);
    assert_eq!(points, core.to_xyz());
    assert_eq!(Array::from(&get(&moved, "origin")).to_vec(), vec![JsValue::from_f64(0.0); 3]);
    // { points, origin } far from zero: the origin mapped in f64, the offsets turned only
    let origin = [1_694_289.25, 1_816_495.5, 5_595.75];
    let far = js_sys::Object::new();
    js_sys::Reflect::set(&far, &"points".into(), &flat).unwrap();
    let o: Array = origin.iter().map(|v| JsValue::from_f64(*v)).collect();
    js_sys::Reflect::set(&far, &"origin".into(), &o).unwrap();
    let moved = transform_point_cloud(far.clone().into(), &column_major).map_err(message).unwrap();
    let want = gt.transform_point(&nalgebra::Point3::from(origin));
    let got: Vec<f64> = Array::from(&get(&moved, "origin")).iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(got, vec![want.x, want.y, want.z]);
    // written: doubles for the far cloud, floats for the local one; both read back
    let ply = write_ply(moved).map_err(message).unwrap();
    assert!(String::from_utf8_lossy(&ply[..150]).contains("property double x"));
    let back = arps::io::read_point_cloud(&ply, "x.ply").unwrap();
    let first = back.point_f64(0);
    let expect = gt.transform_point(&nalgebra::Point3::new(
        origin[0] + source()[0] as f64,
        origin[1] + source()[1] as f64,
        origin[2] + source()[2] as f64,
    ));
    assert!((first[0] - expect.x).abs() < 1e-5 && (first[1] - expect.y).abs() < 1e-5, "{first:?} vs {expect:?}");
    let ply = write_ply(flat.into()).map_err(message).unwrap();
    assert!(String::from_utf8_lossy(&ply[..150]).contains("property float x"));
    assert_eq!(arps::io::read_point_cloud(&ply, "x.ply").unwrap().to_xyz(), source());

    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let mut scaled = column_major.clone();
    scaled[0] *= 2.0;
    let cloud = || -> JsValue { Float32Array::from(&source()[..]).into() };
    for (e, want) in [
        (transform_point_cloud(cloud(), &column_major[..15]).err(), "matrix: expected 16 numbers"),
        (transform_point_cloud(cloud(), &scaled).err(), "matrix is not rigid"),
        (transform_point_cloud(JsValue::from_str("x"), &column_major).err(), "cloud: expected a Float32Array"),
        (write_ply(Float32Array::new_with_length(4).into()).err(), "not a multiple of 3"),
        (write_ply(JsValue::NULL).err(), "cloud: expected a Float32Array"),
    ] {
        let e = message(e.expect(want));
        assert!(e.contains(want), "{e}");
        still_works(&mut r);
    }
    let bad_origin = js_sys::Object::new();
    js_sys::Reflect::set(&bad_origin, &"points".into(), &Float32Array::from(&source()[..])).unwrap();
    for origin in [
        Array::of2(&1.0.into(), &2.0.into()).into(),
        Array::of3(&1.0.into(), &f64::NAN.into(), &0.0.into()).into(),
        JsValue::from_str("here"),
    ] {
        js_sys::Reflect::set(&bad_origin, &"origin".into(), &origin).unwrap();
        let e = message(write_ply(bad_origin.clone().into()).expect_err("a bad origin throws"));
        assert!(e.contains("origin must be 3 finite numbers"), "{e}");
    }
}

/// Degenerate but valid inputs: a finite result or a thrown Error, never a trap (a trap would
/// abort this test run), and the registrar still works afterwards.
#[wasm_bindgen_test]
fn degenerate_inputs_never_trap() {
    let mut r = Registrar::with_default_model().map_err(message).unwrap();
    let mut state = 12345u64;
    let mut rand = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut cloud =
        |n: usize, f: &dyn Fn(usize, f32) -> f32| -> Vec<f32> { (0..3 * n).map(|i| f(i, rand())).collect() };
    let cases: Vec<(&str, Vec<f32>, Vec<f32>)> = vec![
        ("exactly 16 points", cloud(16, &|_, x| x), cloud(16, &|_, x| x)),
        (
            "collinear",
            cloud(100, &|i, x| if i % 3 == 0 { x } else { 0.0 }),
            cloud(100, &|i, x| if i % 3 == 0 { x } else { 0.0 }),
        ),
        (
            "coplanar",
            cloud(200, &|i, x| if i % 3 == 2 { 0.0 } else { x }),
            cloud(200, &|i, x| if i % 3 == 2 { 0.0 } else { x }),
        ),
        ("1e30 coordinates", cloud(100, &|_, x| x * 1e30), cloud(100, &|_, x| x * 1e30)),
        ("near f32::MAX", cloud(100, &|_, x| (x - 0.5) * 3e38), cloud(100, &|_, x| (x - 0.5) * 3e38)),
        ("1e-40 (subnormal)", cloud(100, &|_, x| x * 1e-40), cloud(100, &|_, x| x * 1e-40)),
        ("two distinct points", cloud(100, &|i, _| ((i / 3) % 2) as f32), cloud(100, &|i, _| ((i / 3) % 2) as f32)),
        ("1e6 apart", cloud(100, &|_, x| x), cloud(100, &|_, x| x + 1e6)),
    ];
    for (name, s, t) in &cases {
        for opts in [None, Some(options(r#"{"icp": "point", "voxelSize": 0}"#))] {
            if let Ok(res) = r.register(s, t, opts, None, None, None) {
                let m = matrix(&res, "T_target_source");
                assert!(m.iter().all(|v| v.is_finite()), "{name}: non-finite matrix {m}");
            }
        }
    }
    still_works(&mut r);
}

#[wasm_bindgen_test]
fn progress_callback_sees_each_stage_and_a_throwing_callback_is_reported() {
    let mut r = Registrar::with_default_model().unwrap();
    let seen = Array::new();
    let push = {
        let seen = seen.clone();
        Closure::<dyn FnMut(JsValue)>::new(move |stage: JsValue| {
            seen.push(&stage);
        })
    };
    let f: js_sys::Function = push.as_ref().unchecked_ref::<js_sys::Function>().clone();
    r.register(&source(), &target(), None, Some(f), None, None).map_err(message).unwrap();
    let stages: Vec<String> = seen.iter().map(|s| s.as_string().unwrap()).collect();
    assert_eq!(stages, ["preparing", "network", "refining"]);
    let throwing = js_sys::Function::new_with_args("stage", "throw new Error('boom at ' + stage)");
    let e = message(r.register(&source(), &target(), None, Some(throwing), None, None).unwrap_err());
    assert!(e.contains("onProgress threw: boom at preparing"), "{e}");
    still_works(&mut r);
}

#[wasm_bindgen_test]
fn registrations_onto_the_same_target_equal_a_fresh_registrars() {
    // the registrar keeps the target from one call to the next: a scan, another scan (the source
    // cropped), the first again, and each must be what a registrar that never saw another pair
    // answers (the JS result without its timings)
    let full = source();
    let half: Vec<f32> = full.chunks_exact(3).filter(|p| p[0] > 0.0).flatten().copied().collect();
    let untimed = |v: JsValue| {
        let text = js_sys::JSON::stringify(&v).unwrap().as_string().unwrap();
        let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
        json.as_object_mut().unwrap().remove("timings");
        json
    };
    let fresh = |s: &[f32]| {
        let mut r = Registrar::with_default_model().map_err(message).unwrap();
        untimed(r.register(s, &target(), None, None, None, None).map_err(message).unwrap())
    };
    let mut kept = Registrar::with_default_model().map_err(message).unwrap();
    for s in [&full[..], &half[..], &full[..]] {
        let again = untimed(kept.register(s, &target(), None, None, None, None).map_err(message).unwrap());
        assert_eq!(again, fresh(s));
    }
}

/// Each cloud's origin places its points in the caller's frame: the fixture pair given as offsets
/// from two origins far apart and far from zero comes back in that frame (the truth conjugated
/// by the origins); the identity start is the caller's identity; a bad origin is an error that
/// names the cloud, and the registrar keeps working.
#[wasm_bindgen_test]
fn origins_place_each_cloud_in_the_callers_frame() {
    let mut r = Registrar::with_default_model().unwrap();
    let (a, b) = ([512345.25, 4123456.5, 87.125], [512349.75, 4123450.25, 91.0]);
    let res =
        r.register(&source(), &target(), None, None, Some(a.to_vec()), Some(b.to_vec())).map_err(message).unwrap();
    let shift = |o: [f64; 3]| nalgebra::Matrix4::new_translation(&nalgebra::Vector3::from(o));
    let truth = shift(b) * ground_truth() * shift(a).try_inverse().unwrap();
    let m = matrix(&res, "T_target_source");
    // the error where the clouds are (at the source's origin), not at the frame's zero 4e6 away
    let at = |t: &nalgebra::Matrix4<f64>| t.transform_point(&nalgebra::Point3::from(a));
    assert!((at(&m) - at(&truth)).norm() < 0.02, "{m} vs {truth}");
    // the "initial" start without initialTransform: the identity of the caller's frame
    let alone = options(r#"{"network": false, "starts": ["initial"], "icp": "off"}"#);
    let res = r
        .register(&source(), &source(), Some(alone), None, Some(a.to_vec()), Some(b.to_vec()))
        .map_err(message)
        .unwrap();
    let m = matrix(&res, "T_target_source");
    assert!((m - nalgebra::Matrix4::identity()).abs().max() < 1e-9, "{m}");
    let e = r.register(&source(), &target(), None, None, Some(vec![1.0, 2.0]), None).err().map(message).unwrap();
    assert!(e.contains("source: origin must be 3 finite numbers"), "{e}");
    let e =
        r.register(&source(), &target(), None, None, None, Some(vec![1.0, f64::NAN, 2.0])).err().map(message).unwrap();
    assert!(e.contains("target: origin must be 3 finite numbers"), "{e}");
    still_works(&mut r);
}
