//! `arps make-pairs` and `arps eval` end to end, on the committed fixture pairs and on a freshly
//! generated set.
#![cfg(feature = "cli")]

mod common;
use std::path::Path;
use std::process::Command;

const METHODS: [&str; 10] = [
    "network",
    "network + ICP",
    "network + multi-start ICP",
    "multi-start ICP, no network",
    "ICP from identity",
    "ICP from centroids",
    "untrained network + ICP",
    "FPFH + RANSAC + ICP",
    "FPFH + RANSAC + network + ICP",
    "exhaustive multi-start ICP",
];

fn arps(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_arps")).args(args).output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn eval_prints_the_table_for_every_method_on_the_fixture_pairs() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pairs/pairs.tsv");
    let scratch = common::scratch("eval");
    let svg = scratch.join("curves.svg");
    let (ok, out, err) = arps(&["eval", manifest.to_str().unwrap(), "--limit", "6", "--svg", svg.to_str().unwrap()]);
    assert!(ok, "stdout:\n{out}\nstderr:\n{err}");
    assert!(out.contains("6 pairs"), "{out}");
    for h in ["MRE(deg)", "MTE", "Recall", "RRE(deg)", "RTE", "ms/pair", "fit>=GT"] {
        assert!(out.contains(h), "missing column {h}:\n{out}");
    }
    for m in METHODS {
        assert!(out.lines().any(|l| l.starts_with(&format!("{m} "))), "missing method {m}:\n{out}");
    }
    assert!(out.contains("normalised shape units"), "{out}");
    assert!(out.contains("network + multi-start ICP: chosen start "), "{out}");
    let s = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(s.matches("<polyline").count(), 2 * METHODS.len());
    let _ = std::fs::remove_file(&svg);
}

#[test]
fn eval_json_and_perturbation() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pairs/pairs.tsv");
    let (ok, out, err) = arps(&["eval", manifest.to_str().unwrap(), "--limit", "2", "--perturb", "3", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["pairs"], 2);
    assert_eq!(v["perturb"], 3);
    assert_eq!(v["perturb_angle_deg"], 45.0);
    let methods = v["methods"].as_array().unwrap();
    assert_eq!(methods.len(), METHODS.len());
    for (m, name) in methods.iter().zip(METHODS) {
        assert_eq!(m["name"], name);
        let r = m["summary"]["recall"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&r));
        assert!(m["summary"]["mre"].as_f64().unwrap() >= 0.0);
        // ambiguous misses are misses
        let missed = ((1.0 - r) * 2.0).round() as u64;
        assert!(m["fit_ge_gt"].as_u64().unwrap() <= missed, "{m}");
    }
    assert_eq!(v["per_pair"].as_array().unwrap().len(), 2);
    assert_eq!(v["truth_refined_recall"], 1.0);
    for p in v["per_pair"].as_array().unwrap() {
        let gt = p["gt_fitness"].as_f64().unwrap();
        assert!(gt > 0.1 && gt <= 1.0, "the refined truth overlaps: {p}");
        // the fixtures' truth, refined, stays where it is (perturbed sources carry the truth with them)
        let (re, te) = (p["gt_refined"]["rot_deg"].as_f64().unwrap(), p["gt_refined"]["trans"].as_f64().unwrap());
        assert!(re < 2.0 && te < 0.05, "ICP from the truth stays near it: {p}");
        for r in p["results"].as_array().unwrap() {
            assert!((0.0..=1.0).contains(&r["fitness"].as_f64().unwrap()), "{r}");
        }
    }
    // which start each answer came from
    let first = &v["per_pair"][0]["results"];
    assert_eq!(first[1]["start"], "network");
    assert!(
        ["network", "centroids", "initial", "turned", "turnedInitial", "global", "rotations"]
            .contains(&first[2]["start"].as_str().unwrap()),
        "{first}"
    );
    assert_eq!(first[4]["start"], "initial");
}

#[test]
fn eval_perturb_angle_is_validated() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pairs/pairs.tsv");
    let m = manifest.to_str().unwrap();
    let (ok, _, err) = arps(&["eval", m, "--limit", "1", "--perturb", "1", "--perturb-angle", "200"]);
    assert!(!ok && err.contains("--perturb-angle must be in (0, 180]"), "{err}");
    let (ok, _, err) = arps(&["eval", m, "--limit", "1", "--perturb", "1", "--perturb-angle", "0"]);
    assert!(!ok && err.contains("--perturb-angle"), "{err}");
    // without --perturb there is nothing to turn
    let (ok, _, err) = arps(&["eval", m, "--limit", "1", "--perturb-angle", "90"]);
    assert!(!ok && err.contains("--perturb"), "{err}");
    let (ok, out, err) = arps(&[
        "eval",
        m,
        "--limit",
        "1",
        "--perturb",
        "1",
        "--perturb-angle",
        "180",
        "--methods",
        "network",
        "--json",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["perturb_angle_deg"], 180.0);
}

#[test]
fn make_pairs_writes_a_set_that_eval_reads() {
    let dir = common::scratch("make-pairs");
    let _ = std::fs::remove_dir_all(&dir);
    let (ok, out, err) =
        arps(&["make-pairs", "--out", dir.to_str().unwrap(), "--count", "3", "--seed", "5", "--procedural-only"]);
    assert!(ok, "{out}{err}");
    let tsv = std::fs::read_to_string(dir.join("pairs.tsv")).unwrap();
    assert_eq!(tsv.lines().count(), 4);
    let entries = arps::data::manifest::parse(&tsv).unwrap();
    let sidecar: arps::data::manifest::Sidecar =
        serde_json::from_str(&std::fs::read_to_string(dir.join("pairs.json")).unwrap()).unwrap();
    assert_eq!(sidecar.units, "normalized");
    assert_eq!(sidecar.pairs.len(), 3);
    for (e, meta) in entries.iter().zip(&sidecar.pairs) {
        let s = arps::io::read_path(&dir.join(&e.source)).unwrap();
        let t = arps::io::read_path(&dir.join(&e.target)).unwrap();
        assert_eq!((s.len(), t.len()), (1024, 1024));
        assert!(meta.overlap >= 0.7);
        // the files hold exactly the generated pair
        let src = arps::data::ShapeSource::procedural();
        let idx = (5u64 << 32) + entries.iter().position(|x| x.name == e.name).unwrap() as u64;
        let pair = src.pair(arps::data::Split::Val, idx, &arps::data::PairParams::default()).unwrap();
        assert_eq!(s.points, pair.source);
        assert_eq!(t.points, pair.target);
        assert_eq!(e.T_target_source, pair.T_target_source);
        // (serde_json's default float parsing may be off by an ulp)
        for a in 0..3 {
            assert!((meta.centroid_target[a] - pair.centroid_target[a]).abs() < 1e-12);
        }
    }
    let (ok, out, err) = arps(&["eval", dir.join("pairs.tsv").to_str().unwrap(), "--limit", "1"]);
    assert!(ok, "{out}{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--rotation-range 180` (an alias of `--max-angle`) makes any-pose pairs: the relative
/// rotation reaches past 90 degrees; ranges outside [0, 180] are refused with a clear error.
#[test]
fn make_pairs_makes_any_pose_pairs_and_checks_the_range() {
    let dir = common::scratch("any-pose");
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    let (ok, out, err) = arps(&[
        "make-pairs",
        "--out",
        d,
        "--count",
        "8",
        "--seed",
        "2",
        "--procedural-only",
        "--rotation-range",
        "180",
    ]);
    assert!(ok, "{out}{err}");
    let entries = arps::data::manifest::parse(&std::fs::read_to_string(dir.join("pairs.tsv")).unwrap()).unwrap();
    let angles: Vec<f64> = entries.iter().map(|e| arps::transform::rotation_angle_deg(&e.T_target_source)).collect();
    assert!(angles.iter().any(|&a| a > 90.0), "{angles:?}");
    let sidecar: arps::data::manifest::Sidecar =
        serde_json::from_str(&std::fs::read_to_string(dir.join("pairs.json")).unwrap()).unwrap();
    assert_eq!(sidecar.params.max_angle_deg, 180.0);
    let _ = std::fs::remove_dir_all(&dir);
    for bad in ["200", "-1", "NaN"] {
        let arg = format!("--rotation-range={bad}");
        let (ok, _, err) = arps(&["make-pairs", "--out", d, "--count", "1", &arg]);
        assert!(!ok && err.contains("--max-angle") && err.contains("[0, 180]"), "{bad}: {err}");
        assert!(!dir.exists(), "nothing written for {bad}");
    }
}

/// `--dense-points` sets the surface sample both clouds are drawn from: at the protocol's 4,096
/// many points of the two clouds are the same sample (twins), at 65,536 few are; the files hold
/// exactly the pairs of those parameters, and sizes out of range are refused.
#[test]
fn make_pairs_dense_points_sets_the_shared_samples() {
    let dir = common::scratch("dense-points");
    let d = dir.to_str().unwrap();
    let src = arps::data::ShapeSource::procedural();
    let mut shared = Vec::new();
    for dense in [4096usize, 65536] {
        let _ = std::fs::remove_dir_all(&dir);
        let n = dense.to_string();
        let (ok, out, err) =
            arps(&["make-pairs", "--out", d, "--count", "3", "--seed", "4", "--procedural-only", "--dense-points", &n]);
        assert!(ok, "{out}{err}");
        let entries = arps::data::manifest::parse(&std::fs::read_to_string(dir.join("pairs.tsv")).unwrap()).unwrap();
        let params = arps::data::PairParams { dense_points: dense, ..Default::default() };
        let mut twins = 0;
        for (i, e) in entries.iter().enumerate() {
            let pair = src.pair(arps::data::Split::Val, (4u64 << 32) + i as u64, &params).unwrap();
            assert_eq!(arps::io::read_path(&dir.join(&e.source)).unwrap().points, pair.source);
            let target: std::collections::HashSet<u32> = pair.target_dense_index.iter().copied().collect();
            twins += pair.source_dense_index.iter().filter(|i| target.contains(i)).count();
        }
        shared.push(twins as f64 / (3.0 * 1024.0));
    }
    assert!(shared[0] > 0.15 && shared[1] < 0.05, "shared samples {shared:?}");
    let _ = std::fs::remove_dir_all(&dir);
    for bad in ["3", "0", "9999999"] {
        let (ok, _, err) = arps(&["make-pairs", "--out", d, "--count", "1", "--dense-points", bad]);
        assert!(!ok && err.contains("--dense-points"), "{bad}: {err}");
        assert!(!dir.exists(), "nothing written for {bad}");
    }
    let (ok, _, err) = arps(&["make-pairs", "--out", d, "--count", "1", "--points", "2000000"]);
    assert!(!ok && err.contains("--points 2000000") && err.contains("--dense-points"), "{err}");
    assert!(!dir.exists());
}

/// Clouds larger than the protocol's get a dense sample of 4x their points by default, so no
/// cloud repeats a surface sample (at the protocol's 4,096, a 4,096-point cloud would be its
/// crop's 2,870 samples and 1,200 noisy copies of them).
#[test]
fn make_pairs_large_clouds_repeat_no_sample() {
    let dir = common::scratch("large-dense");
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    let (ok, out, err) =
        arps(&["make-pairs", "--out", d, "--count", "2", "--seed", "6", "--procedural-only", "--points", "4096"]);
    assert!(ok, "{out}{err}");
    let sidecar: arps::data::manifest::Sidecar =
        serde_json::from_str(&std::fs::read_to_string(dir.join("pairs.json")).unwrap()).unwrap();
    assert_eq!(sidecar.params.dense_points, 16384);
    let src = arps::data::ShapeSource::procedural();
    for i in 0..2u64 {
        let pair = src.pair(arps::data::Split::Val, (6u64 << 32) + i, &sidecar.params).unwrap();
        for idx in [&pair.source_dense_index, &pair.target_dense_index] {
            let distinct: std::collections::HashSet<u32> = idx.iter().copied().collect();
            assert_eq!((idx.len(), distinct.len()), (4096, 4096));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Scans onto a model: `--keep` sets the source's crop, `--target-keep 1` makes the target the
/// whole shape and `--target-points` its size; the scan's samples are then all the model's.
#[test]
fn make_pairs_makes_scans_onto_a_model() {
    let dir = common::scratch("scan-model");
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_str().unwrap();
    let args = ["--count", "2", "--seed", "3", "--procedural-only", "--points", "512", "--target-points", "2048"];
    let (ok, out, err) =
        arps(&[&["make-pairs", "--out", d, "--keep", "0.4", "--target-keep", "1"][..], &args].concat());
    assert!(ok, "{out}{err}");
    let sidecar: arps::data::manifest::Sidecar =
        serde_json::from_str(&std::fs::read_to_string(dir.join("pairs.json")).unwrap()).unwrap();
    assert_eq!((sidecar.params.keep_ratio, sidecar.params.target_keep_ratio), (0.4, Some(1.0)));
    assert_eq!(
        (sidecar.params.points, sidecar.params.target_points, sidecar.params.dense_points),
        (512, Some(2048), 8192)
    );
    let src = arps::data::ShapeSource::procedural();
    for (i, e) in arps::data::manifest::parse(&std::fs::read_to_string(dir.join("pairs.tsv")).unwrap())
        .unwrap()
        .iter()
        .enumerate()
    {
        let pair = src.pair(arps::data::Split::Val, (3u64 << 32) + i as u64, &sidecar.params).unwrap();
        assert_eq!(arps::io::read_path(&dir.join(&e.target)).unwrap().points, pair.target);
        assert_eq!((pair.source.len(), pair.target.len(), pair.overlap), (512, 2048, 1.0));
        // the target's samples cover the whole shape: far more distinct ones than the scan's crop
        let distinct = |idx: &[u32]| idx.iter().copied().collect::<std::collections::HashSet<u32>>().len();
        assert!(distinct(&pair.target_dense_index) > 3 * distinct(&pair.source_dense_index) / 2);
    }
    let _ = std::fs::remove_dir_all(&dir);
    for bad in [["--keep", "0"], ["--target-keep", "1.5"], ["--target-points", "0"]] {
        let (ok, _, err) = arps(&[&["make-pairs", "--out", d, "--count", "1"][..], &bad[..]].concat());
        assert!(!ok && err.contains(bad[0]), "{bad:?}: {err}");
        assert!(!dir.exists(), "nothing written for {bad:?}");
    }
}

/// `arps eval MANIFEST --methods global --json` with `extra` arguments, its JSON.
fn eval_global(manifest: &Path, extra: &[&str]) -> serde_json::Value {
    let (ok, out, err) =
        arps(&[&["eval", manifest.to_str().unwrap(), "--methods", "global", "--json"][..], extra].concat());
    assert!(ok, "{err}");
    serde_json::from_str(out.trim()).unwrap()
}

/// The first pair's first answer (`T_target_source`) of an `arps eval --json` result.
fn first_answer(result: &serde_json::Value) -> serde_json::Value {
    result["per_pair"][0]["results"][0]["T_target_source"].clone()
}

/// Pairs made into `dir` with `extra` arguments and into `clean` without (both with `args`),
/// checked to be the same pairs with `extra_points` (source, target) appended after each cloud's
/// 1,024: the same manifest, the same surface points. Per pair: its entry, its source and target
/// as made with `extra`, and its target without.
#[allow(clippy::type_complexity)]
fn made_with_extra(
    dir: &Path,
    clean: &Path,
    args: &[&str],
    extra: &[&str],
    extra_points: (usize, usize),
) -> Vec<(arps::data::manifest::Entry, Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[f32; 3]>)> {
    for (d, more) in [(dir, extra), (clean, &[][..])] {
        let _ = std::fs::remove_dir_all(d);
        let (ok, out, err) = arps(&[&["make-pairs", "--out", d.to_str().unwrap()][..], args, more].concat());
        assert!(ok, "{out}{err}");
    }
    let read = |d: &Path, f: &str| arps::io::read_path(&d.join(f)).unwrap().points;
    let tsv = std::fs::read_to_string(dir.join("pairs.tsv")).unwrap();
    assert_eq!(tsv, std::fs::read_to_string(clean.join("pairs.tsv")).unwrap());
    let mut out = Vec::new();
    for e in arps::data::manifest::parse(&tsv).unwrap() {
        let (s, s0, t, t0) =
            (read(dir, &e.source), read(clean, &e.source), read(dir, &e.target), read(clean, &e.target));
        assert_eq!((s.len(), t.len()), (1024 + extra_points.0, 1024 + extra_points.1));
        assert_eq!((&s[..1024], &t[..1024]), (&s0[..], &t0[..]));
        out.push((e, s, t, t0));
    }
    out
}

/// Stray returns: `--stray` and `--target-stray` append that share of points scattered over three
/// times the shape's size, the surface points and the truth staying the pair's; eval's default
/// leaves them out, `--keep-outliers` keeps them.
#[test]
fn make_pairs_adds_stray_returns_that_eval_leaves_out() {
    let dir = common::scratch("stray");
    let clean = common::scratch("stray-clean");
    let args = ["--count", "2", "--seed", "4", "--procedural-only"];
    for (_, s, _, _) in made_with_extra(&dir, &clean, &args, &["--stray", "0.05", "--target-stray", "0.1"], (51, 102)) {
        // the strays spread over the cube of half-side 3 (the shape fits [-1, 1]^3)
        assert!(s[1024..].iter().any(|p| p.iter().any(|v| v.abs() > 1.5)));
        assert!(s[1024..].iter().all(|p| p.iter().all(|v| v.abs() <= 3.0)));
    }
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("pairs.json")).unwrap()).unwrap();
    assert_eq!(
        (sidecar["generator"]["stray"].as_f64(), sidecar["generator"]["target_stray"].as_f64()),
        (Some(0.05), Some(0.1))
    );
    let manifest = dir.join("pairs.tsv");
    let eval = |extra: &[&str]| eval_global(&manifest, extra);
    let (dropped, kept) = (eval(&[]), eval(&["--keep-outliers"]));
    let recall = |v: &serde_json::Value| v["methods"][0]["summary"]["recall"].as_f64().unwrap();
    assert!(recall(&dropped) >= recall(&kept), "{dropped}\n{kept}");
    assert_ne!(first_answer(&dropped), first_answer(&kept));
    for bad in [["--stray", "1.01"], ["--target-stray", "nan"]] {
        let (ok, _, err) =
            arps(&[&["make-pairs", "--out", dir.to_str().unwrap(), "--count", "1"][..], &bad[..]].concat());
        assert!(!ok && err.contains(bad[0]), "{bad:?}: {err}");
    }
    for d in [&dir, &clean] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Support planes: `--support` and `--target-support` append a level square under the object
/// (the same plane in both frames, or with `--support-moved` the target's own), the surface
/// points and the truth staying the pair's; eval's default leaves a plane only one cloud stands
/// on out, `--keep-support` keeps it.
#[test]
fn make_pairs_adds_support_planes_that_eval_leaves_out() {
    let dir = common::scratch("support");
    let moved = common::scratch("support-moved");
    let clean = common::scratch("support-clean");
    let args = ["--count", "2", "--seed", "5", "--procedural-only", "--max-tilt", "0"];
    let support = ["--support", "0.5", "--target-support", "0.25"];
    let with_moved = made_with_extra(&moved, &clean, &args, &[&support[..], &["--support-moved"]].concat(), (512, 256));
    for ((e, s, t, t0), (_, _, tm, _)) in
        made_with_extra(&dir, &clean, &args, &support, (512, 256)).into_iter().zip(with_moved)
    {
        // the source's plane is level (z) under its surface points, reaching out beyond them
        let (lo, hi) = arps::PointCloud::new(s[..1024].to_vec()).bounds();
        let plane = &s[1024..];
        assert!(plane.iter().all(|p| p[2] <= lo[2] + 0.05), "a level plane under the object");
        assert!(plane.iter().any(|p| p[0] < lo[0]) && plane.iter().any(|p| p[0] > hi[0]));
        // the same plane in the target: the source's moved by the truth
        let inverse = arps::transform::rigid_inverse(&e.T_target_source);
        let back = arps::PointCloud::new(t[1024..].to_vec()).transformed(&inverse);
        let z = |pts: &[[f32; 3]]| pts.iter().map(|p| p[2] as f64).sum::<f64>() / pts.len() as f64;
        assert!((z(&back.points) - z(plane)).abs() < 0.01);
        // moved: the target's plane is level in the target's own frame, under its points
        let (tlo, _) = arps::PointCloud::new(t0.clone()).bounds();
        assert!(tm[1024..].iter().all(|p| p[2] <= tlo[2] + 0.05));
    }
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("pairs.json")).unwrap()).unwrap();
    assert_eq!(
        (sidecar["generator"]["support"].as_f64(), sidecar["generator"]["target_support"].as_f64()),
        (Some(0.5), Some(0.25))
    );
    // a plane in the sources only: the default leaves it out, --keep-support keeps it
    let only = common::scratch("support-only");
    let _ = std::fs::remove_dir_all(&only);
    let (ok, out, err) =
        arps(&[&["make-pairs", "--out", only.to_str().unwrap(), "--support", "0.5"][..], &args].concat());
    assert!(ok, "{out}{err}");
    let manifest = only.join("pairs.tsv");
    let eval = |extra: &[&str]| eval_global(&manifest, extra);
    let (dropped, kept) = (eval(&[]), eval(&["--keep-support"]));
    assert_ne!(first_answer(&dropped), first_answer(&kept));
    for bad in [["--support", "1.5"], ["--target-support", "nan"]] {
        let (ok, _, err) =
            arps(&[&["make-pairs", "--out", dir.to_str().unwrap(), "--count", "1"][..], &bad[..]].concat());
        assert!(!ok && err.contains(bad[0]), "{bad:?}: {err}");
    }
    for d in [&dir, &moved, &clean, &only] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Real manifests store the truth to a few digits (`../shared/data/scans/pairs.tsv`): a ground
/// truth that is rigid only to 1e-3 is still evaluated, not rejected.
#[test]
fn eval_accepts_a_ground_truth_rounded_to_a_few_digits() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pairs");
    let text = std::fs::read_to_string(fixtures.join("pairs.tsv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let mut fields: Vec<String> = lines.next().unwrap().split('\t').map(String::from).collect();
    let rounded: Vec<String> =
        fields[5].split_whitespace().map(|x| format!("{:.3}", x.parse::<f64>().unwrap())).collect();
    fields[5] = rounded.join(" ");
    for f in [1, 2] {
        fields[f] = fixtures.join(&fields[f]).display().to_string();
    }
    let dir = common::scratch("eval-rounded");
    std::fs::create_dir_all(&dir).unwrap();
    let manifest = dir.join("pairs.tsv");
    std::fs::write(&manifest, format!("{header}\n{}\n", fields.join("\t"))).unwrap();
    let (ok, out, err) = arps(&["eval", manifest.to_str().unwrap(), "--json"]);
    assert!(ok, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["per_pair"][0]["gt_fitness"].as_f64().unwrap() > 0.1, "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// One pair of a hand-made eval result: name, the truth's fitness, and `(rot_deg, fitness)` of
/// methods `a` and `b`.
type PairRow<'a> = (&'a str, f64, [(f64, f64); 2]);

/// An `arps eval --json` result with two methods (`a`, `b`) on the given pairs, TE 0.
fn eval_json(pairs: &[PairRow]) -> String {
    let per_pair: Vec<serde_json::Value> = pairs
        .iter()
        .map(|(name, gt, r)| {
            let results: Vec<serde_json::Value> = ["a", "b"]
                .iter()
                .zip(r)
                .map(|(m, (rot, fit))| {
                    serde_json::json!({
                        "method": m, "rot_deg": rot, "trans": 0.0, "ms": 1.0, "start": "network",
                        "fitness": fit, "error": null,
                    })
                })
                .collect();
            serde_json::json!({ "name": name, "te_scale": 1.0, "gt_fitness": gt, "results": results })
        })
        .collect();
    serde_json::json!({
        "manifest": "x", "pairs": pairs.len(), "weights": "w", "rot_threshold_deg": 15.0,
        "trans_threshold": 0.2, "ambiguity_margin": 0.01,
        "methods": [{"name": "a"}, {"name": "b"}], "per_pair": per_pair,
    })
    .to_string()
}

fn write_temp(tag: &str, text: &str) -> std::path::PathBuf {
    let p = std::env::temp_dir().join(format!("arps-compare-{}-{tag}.json", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn compare_counts_discordant_pairs_ambiguity_and_categories() {
    // method a: A registers pairs 0 and 1, B registers 2; B's miss on 0 fits as well as the truth
    let a = eval_json(&[
        ("00000-cone-1", 0.9, [(2.0, 0.9), (1.0, 0.9)]),
        ("00001-cone-2", 0.9, [(3.0, 0.9), (1.0, 0.9)]),
        ("00002-bank-x", 0.9, [(40.0, 0.5), (1.0, 0.9)]),
        ("00003-bank-y", 0.9, [(40.0, 0.5), (1.0, 0.9)]),
    ]);
    let b = eval_json(&[
        ("00000-cone-1", 0.9, [(30.0, 0.895), (1.0, 0.9)]),
        ("00001-cone-2", 0.9, [(30.0, 0.5), (1.0, 0.9)]),
        ("00002-bank-x", 0.9, [(4.0, 0.9), (1.0, 0.9)]),
        ("00003-bank-y", 0.9, [(40.0, 0.5), (1.0, 0.9)]),
    ]);
    let (pa, pb) = (write_temp("a", &a), write_temp("b", &b));
    let (ok, out, err) =
        arps(&["compare", pa.to_str().unwrap(), pb.to_str().unwrap(), "--by-category", "--methods", "a,b"]);
    assert!(ok, "{err}");
    let row = |m: &str| out.lines().find(|l| l.starts_with(&format!("{m} "))).unwrap_or_else(|| panic!("{out}"));
    let cols: Vec<&str> = row("a").split_whitespace().collect();
    // method, recall A, recall B, A only (unambiguous), B only (unambiguous), p
    assert_eq!(&cols[..7], ["a", "0.5000", "0.2500", "2", "(1)", "1", "(1)"], "{out}");
    assert!((cols[7].parse::<f64>().unwrap() - 1.0).abs() < 1e-12, "{out}");
    let cols: Vec<&str> = row("b").split_whitespace().collect();
    assert_eq!(&cols[..7], ["b", "1.0000", "1.0000", "0", "(0)", "0", "(0)"], "{out}");
    assert!(row("cone").contains("1.000 / 0.000"), "{out}");
    assert!(row("bank").contains("0.000 / 0.500"), "{out}");

    // a file on other pairs, an unknown method and a file that is not an eval result are errors
    let other = write_temp("c", &eval_json(&[("00000-cone-1", 0.9, [(2.0, 0.9), (1.0, 0.9)])]));
    for (args, msg) in [
        (vec![pa.to_str().unwrap(), other.to_str().unwrap()], "not on the same pairs"),
        (vec![pa.to_str().unwrap(), pb.to_str().unwrap(), "--methods", "network"], "no method `network`"),
        (vec![pa.to_str().unwrap(), write_temp("d", "{\"pairs\": 3}").to_str().unwrap()], "not an `arps eval --json`"),
        (vec![pa.to_str().unwrap(), "/nonexistent/eval.json"], "/nonexistent/eval.json"),
        (
            vec![
                pa.to_str().unwrap(),
                write_temp("e", &a.replace("\"pairs\":4", "\"perturb\":1,\"pairs\":4")).to_str().unwrap(),
            ],
            "--perturb null and 1",
        ),
        (
            vec![
                write_temp("f", &a.replace("\"pairs\":4", "\"perturb\":1,\"pairs\":4")).to_str().unwrap(),
                write_temp("g", &a.replace("\"pairs\":4", "\"perturb\":1,\"perturb_angle_deg\":180.0,\"pairs\":4"))
                    .to_str()
                    .unwrap(),
            ],
            "--perturb 1 --perturb-angle 45 and 1 --perturb-angle 180",
        ),
    ] {
        let mut full = vec!["compare"];
        full.extend(args);
        let (ok, out, err) = arps(&full);
        assert!(!ok, "{full:?} should fail:\n{out}");
        assert!(err.starts_with("arps: ") && err.contains(msg) && err.trim().lines().count() == 1, "{full:?}: {err}");
    }
    for t in ["a", "b", "c", "d", "e", "f", "g"] {
        let _ =
            std::fs::remove_file(std::env::temp_dir().join(format!("arps-compare-{}-{t}.json", std::process::id())));
    }
}

#[test]
fn compare_reads_what_eval_writes() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pairs/pairs.tsv");
    let (ok, json, err) = arps(&["eval", manifest.to_str().unwrap(), "--limit", "2", "--json"]);
    assert!(ok, "{err}");
    let p = write_temp("eval", &json);
    let (ok, out, err) = arps(&["compare", p.to_str().unwrap(), p.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("arps compare: 2 pairs"), "{out}");
    assert!(out.contains("multi-start: network, global, centroids, initial, turned, turnedInitial"), "{out}");
    for m in METHODS {
        let line = out.lines().find(|l| l.starts_with(&format!("{m} "))).unwrap_or_else(|| panic!("{m}:\n{out}"));
        // a result against itself: no discordant pairs
        assert!(line.contains(" 0 (0) ") && line.trim_end().ends_with("1.00e0"), "{line}");
    }
    // eval's method keys select rows too
    let (ok, out, err) =
        arps(&["compare", p.to_str().unwrap(), p.to_str().unwrap(), "--methods", "multi-start,network-icp"]);
    assert!(ok, "{err}");
    let rows: Vec<&str> = out.lines().filter(|l| l.starts_with("network")).collect();
    assert_eq!(rows.len(), 2, "{out}");
    assert!(rows[0].starts_with("network + ICP ") && rows[1].starts_with("network + multi-start ICP "), "{out}");
    let _ = std::fs::remove_file(&p);
}

#[test]
fn eval_runs_the_chosen_methods_with_the_given_starts() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pairs/pairs.tsv");
    let m = manifest.to_str().unwrap();
    let args = ["eval", m, "--limit", "2", "--methods", "multi-start,network", "--starts", "network,turnedInitial"];
    let (ok, out, err) = arps(&[&args[..], &["--json"]].concat());
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let names: Vec<&str> = v["methods"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["network", "network + multi-start ICP"], "table order, not argument order");
    assert_eq!(v["starts"], serde_json::json!(["network", "turnedInitial"]));
    for p in v["per_pair"].as_array().unwrap() {
        let r = &p["results"][1];
        assert!(["network", "turnedInitial"].contains(&r["start"].as_str().unwrap()), "{r}");
        // each answer says where its time went and how many starts it refined
        let total = r["timings"]["totalMs"].as_f64().unwrap();
        assert!(total > 0.0 && r["timings"]["icpMs"].as_f64().unwrap() <= total, "{r}");
        assert!(r["starts_refined"].as_u64().unwrap() >= 1, "{r}");
        // and gives its transform: rigid, rows of four
        for r in p["results"].as_array().unwrap() {
            let t: Vec<Vec<f64>> = serde_json::from_value(r["T_target_source"].clone()).unwrap();
            assert_eq!(t.len(), 4, "{r}");
            assert_eq!(t[3], [0.0, 0.0, 0.0, 1.0], "{r}");
            for i in 0..3 {
                for j in 0..3 {
                    let dot: f64 = (0..3).map(|k| t[i][k] * t[j][k]).sum();
                    assert!((dot - if i == j { 1.0 } else { 0.0 }).abs() < 1e-6, "{r}");
                }
            }
        }
    }
    let (ok, out, _) = arps(&args);
    assert!(ok);
    assert!(out.contains("network + multi-start ICP starts: network, turnedInitial"), "{out}");
    assert!(out.contains("network + multi-start ICP: median ms network "), "{out}");
    assert_eq!(out.lines().filter(|l| l.starts_with("network")).count(), 2, "two rows:\n{out}");

    // unknown names are usage errors that list the known ones
    let (ok, _, err) = arps(&["eval", m, "--starts", "network,sideways"]);
    assert!(!ok && err.contains("sideways") && err.contains("turnedInitial"), "{err}");
    // repeated starts are refused before any pair runs, with the engine's message
    let (ok, out, err) = arps(&["eval", m, "--starts", "network,turned,network"]);
    assert!(!ok && out.is_empty(), "{out}");
    assert!(err.starts_with("arps: --starts:") && err.contains("\"network\" twice"), "{err}");
    let (ok, _, err) = arps(&["eval", m, "--methods", "fastest"]);
    assert!(!ok && err.contains("fastest") && err.contains("multi-start"), "{err}");
}
