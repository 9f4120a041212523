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
    for h in ["MRE(deg)", "MTE", "Recall", "RRE(deg)", "RTE", "ms/pair"] {
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
    }
    assert_eq!(v["per_pair"].as_array().unwrap().len(), 2);
    // which start each answer came from
    let first = &v["per_pair"][0]["results"];
    assert_eq!(first[1]["start"], "network");
    assert!(["network", "centroids", "initial"].contains(&first[2]["start"].as_str().unwrap()), "{first}");
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
