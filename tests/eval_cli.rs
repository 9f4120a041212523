//! `arps make-pairs` and `arps eval` end to end, on the committed fixture pairs and on a freshly
//! generated set.
#![cfg(feature = "cli")]

use std::path::Path;
use std::process::Command;

const METHODS: [&str; 7] = [
    "network",
    "network + ICP",
    "network + multi-start ICP",
    "multi-start ICP, no network",
    "ICP from identity",
    "ICP from centroids",
    "untrained network + ICP",
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
    let svg = std::env::temp_dir().join(format!("arps-eval-{}.svg", std::process::id()));
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
    for p in v["per_pair"].as_array().unwrap() {
        let gt = p["gt_fitness"].as_f64().unwrap();
        assert!(gt > 0.1 && gt <= 1.0, "the refined truth overlaps: {p}");
        for r in p["results"].as_array().unwrap() {
            assert!((0.0..=1.0).contains(&r["fitness"].as_f64().unwrap()), "{r}");
        }
    }
    // which start each answer came from
    let first = &v["per_pair"][0]["results"];
    assert_eq!(first[1]["start"], "network");
    assert!(["network", "centroids", "initial", "turned"].contains(&first[2]["start"].as_str().unwrap()), "{first}");
    assert_eq!(first[4]["start"], "initial");
}

#[test]
fn make_pairs_writes_a_set_that_eval_reads() {
    let dir = std::env::temp_dir().join(format!("arps-make-pairs-{}", std::process::id()));
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
    let dir = std::env::temp_dir().join(format!("arps-eval-rounded-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let manifest = dir.join("pairs.tsv");
    std::fs::write(&manifest, format!("{header}\n{}\n", fields.join("\t"))).unwrap();
    let (ok, out, err) = arps(&["eval", manifest.to_str().unwrap(), "--json"]);
    assert!(ok, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["per_pair"][0]["gt_fitness"].as_f64().unwrap() > 0.1, "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}
