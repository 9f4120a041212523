//! The JS/JSON contract (`arps::contract`): the committed TypeScript declarations
//! (`js/arps-contract.d.ts`) are what the Rust types generate (feature `ts`), and a real
//! registration's result and options, serialised to JSON, have exactly the fields those
//! declarations name; transforms and `initialTransform` round-trip in both layouts.

mod common;

use arps::{contract, Options, Registrar, Registration, Search, Start};
use serde_json::Value;
use std::collections::BTreeSet;

const GENERATED: &str = "js/arps-contract.d.ts";

fn generated_file() -> String {
    std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(GENERATED)).unwrap()
}

/// `ARPS_WRITE_TYPES=1` (what `scripts/gen-types.sh` sets) writes the file; otherwise the test
/// fails when the committed file differs from what the Rust types generate.
#[cfg(feature = "ts")]
#[test]
fn generated_typescript_is_current() {
    let fresh = contract::typescript();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(GENERATED);
    if std::env::var_os("ARPS_WRITE_TYPES").is_some_and(|v| v == "1") {
        std::fs::write(&path, &fresh).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != fresh {
        let line = committed.lines().zip(fresh.lines()).position(|(a, b)| a != b).map_or(0, |i| i + 1);
        panic!("{GENERATED} is stale (first difference near line {line}): run scripts/gen-types.sh and commit it");
    }
}

/// The body of `export type NAME = ...;` in the generated declarations (comments dropped).
fn declaration(ts: &str, name: &str) -> String {
    let ts = without_comments(ts);
    let head = format!("export type {name} = ");
    let start = ts.find(&head).unwrap_or_else(|| panic!("no `{head}` in {GENERATED}")) + head.len();
    let rest = &ts[start..];
    rest[..rest.find(";\n").unwrap_or_else(|| panic!("`{name}` does not end"))].to_string()
}

/// Drops `/** ... */` comments.
fn without_comments(s: &str) -> String {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find("/**") {
        out.push_str(&rest[..i]);
        rest = &rest[i + rest[i..].find("*/").expect("unterminated comment") + 2..];
    }
    out + rest
}

/// The field names of an object type `{ a: T, b?: U, ... }` (top level only).
fn ts_fields(ts: &str, name: &str) -> BTreeSet<String> {
    let body = declaration(ts, name);
    let body = body.trim();
    assert!(body.starts_with('{') && body.ends_with('}'), "`{name}` is not an object type: {body}");
    let mut fields = BTreeSet::new();
    let (mut depth, mut field_start) = (0i32, true);
    let mut current = String::new();
    for c in body[1..body.len() - 1].chars() {
        match c {
            '{' | '[' | '(' | '<' => depth += 1,
            '}' | ']' | ')' | '>' => depth -= 1,
            ',' if depth == 0 => field_start = true,
            ':' if depth == 0 && field_start => {
                fields.insert(current.trim().trim_end_matches('?').trim_matches('"').to_string());
                current.clear();
                field_start = false;
            }
            _ if depth == 0 && field_start => current.push(c),
            _ => {}
        }
    }
    fields
}

/// The string literals of a union type `"a" | "b" | ...`.
fn ts_literals(ts: &str, name: &str) -> BTreeSet<String> {
    declaration(ts, name)
        .split('|')
        .map(|v| {
            let v = v.trim();
            assert!(v.starts_with('"') && v.ends_with('"'), "`{name}` is not a union of strings: {v}");
            v.trim_matches('"').to_string()
        })
        .collect()
}

fn keys(v: &Value) -> BTreeSet<String> {
    v.as_object().unwrap_or_else(|| panic!("not an object: {v}")).keys().cloned().collect()
}

/// Every option given (none left at `None`), so that every field shows in the JSON.
fn full_options() -> Options {
    Options {
        network_points: Some(128),
        max_correspondence_distance: Some(0.02),
        voxel_size: Some(0.01),
        initial_transform: Some(arps::transform::to_rows(&common::motion([1.0, 2.0, 3.0], [0.01, 0.0, 0.0]))),
        search: Search::Exhaustive,
        starts: vec![Start::Network, Start::Centroids],
        ..Options::default()
    }
}

#[test]
fn a_real_result_and_options_have_the_declared_fields() {
    let ts = generated_file();
    let (source, target, _) = common::fixture_pair(0);
    let options = full_options();
    let r = Registrar::with_default_model().unwrap().register(&source, &target, &options).unwrap();

    let result = serde_json::to_value(&r).unwrap();
    assert_eq!(keys(&result), ts_fields(&ts, "RegistrationResult"));
    assert_eq!(keys(&result["timings"]), ts_fields(&ts, "RegistrationTimings"));
    assert_eq!(keys(&result["evidence"]), ts_fields(&ts, "RegistrationEvidence"));
    assert!(ts_literals(&ts, "RegistrationStart").contains(result["start"].as_str().unwrap()), "{result}");

    let opts = serde_json::to_value(&options).unwrap();
    assert_eq!(keys(&opts), ts_fields(&ts, "RegisterOptions"));
    assert!(ts_literals(&ts, "RegistrationSearch").contains(opts["search"].as_str().unwrap()));
    assert!(ts_literals(&ts, "IcpKind").contains(opts["icp"].as_str().unwrap()));
    assert!(ts_literals(&ts, "NonFinite").contains(opts["nonFinite"].as_str().unwrap()));
    assert!(ts_literals(&ts, "Outliers").contains(opts["outliers"].as_str().unwrap()));
    assert!(ts_literals(&ts, "SupportPlane").contains(opts["supportPlane"].as_str().unwrap()));

    let config = contract::model_config_json(&arps::ModelConfig::web());
    assert_eq!(keys(&config), ts_fields(&ts, "ModelConfig"));
    assert!(ts_literals(&ts, "ModelReference").contains(config["reference"].as_str().unwrap()));
}

/// The serde names of some enum values.
fn names<T: serde::Serialize>(values: &[T]) -> BTreeSet<String> {
    values.iter().map(|v| serde_json::to_value(v).unwrap().as_str().unwrap().to_string()).collect()
}

#[test]
fn every_enum_value_is_declared() {
    use arps::{IcpKind, NonFinite, Outliers, Stage, Support};
    let ts = generated_file();
    let starts = names(&Start::ALL);
    assert_eq!(starts, ts_literals(&ts, "RegistrationStart"));
    assert!(Start::ALL.iter().all(|s| starts.contains(s.name())));
    assert_eq!(names(&[Search::Adaptive, Search::Exhaustive, Search::Local]), ts_literals(&ts, "RegistrationSearch"));
    assert_eq!(names(&[IcpKind::Off, IcpKind::Point, IcpKind::Plane]), ts_literals(&ts, "IcpKind"));
    assert_eq!(names(&[NonFinite::Error, NonFinite::Drop]), ts_literals(&ts, "NonFinite"));
    assert_eq!(names(&[Outliers::Drop, Outliers::Keep]), ts_literals(&ts, "Outliers"));
    assert_eq!(names(&[Support::Drop, Support::Keep]), ts_literals(&ts, "SupportPlane"));
    assert_eq!(names(&[Stage::Preparing, Stage::Network, Stage::Refining]), ts_literals(&ts, "RegistrationStage"));
    assert_eq!(names(&arps::WarningCode::ALL), ts_literals(&ts, "WarningCode"));
    use arps::FreeMotionKind::{Slide, Turn};
    assert_eq!(names(&[Turn, Slide]), ts_literals(&ts, "FreeMotionKind"));
}

#[test]
fn results_and_options_round_trip_through_json() {
    let (source, target, _) = common::fixture_pair(1);
    let options = full_options();
    let r = Registrar::with_default_model().unwrap().register(&source, &target, &options).unwrap();
    let back: Registration = serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
    assert!((back.T_target_source - r.T_target_source).abs().max() < 1e-12);
    assert!((back.T_target_source_network - r.T_target_source_network).abs().max() < 1e-12);
    assert_eq!((back.start, back.icp_iterations, &back.warnings), (r.start, r.icp_iterations, &r.warnings));
    // the result's transform is column-major: element (row 0, col 3), the x translation, at 12
    let v = serde_json::to_value(&r).unwrap();
    assert_eq!(v["T_target_source"][12].as_f64().unwrap(), r.T_target_source[(0, 3)]);

    let json = serde_json::to_string(&options).unwrap();
    let back: Options = serde_json::from_str(&json).unwrap();
    let (a, b) = (back.initial_transform.unwrap(), options.initial_transform.unwrap());
    assert!(a.iter().flatten().zip(b.iter().flatten()).all(|(x, y)| (x - y).abs() < 1e-15), "{json}");
    assert_eq!(Options { initial_transform: None, ..back }, Options { initial_transform: None, ..options });
}

#[test]
fn initial_transform_reads_both_layouts_and_names_the_expected_shapes() {
    let m = common::motion([10.0, -20.0, 30.0], [1.0, 2.0, 3.0]);
    let rows = arps::transform::to_rows(&m);
    let flat: Vec<f64> = m.as_slice().to_vec();
    let from_flat: Options = serde_json::from_value(serde_json::json!({ "initialTransform": flat })).unwrap();
    let from_rows: Options = serde_json::from_value(serde_json::json!({ "initialTransform": rows })).unwrap();
    assert_eq!(from_flat.initial_transform, Some(rows));
    assert_eq!(from_rows.initial_transform, Some(rows));
    let none: Options = serde_json::from_value(serde_json::json!({ "initialTransform": null })).unwrap();
    assert_eq!(none.initial_transform, None);
    for bad in [
        serde_json::json!([1.0, 2.0, 3.0]),
        serde_json::json!([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        serde_json::Value::from(vec!["a"; 16]),
        serde_json::json!("identity"),
    ] {
        let e = serde_json::from_value::<Options>(serde_json::json!({ "initialTransform": bad })).unwrap_err();
        assert!(e.to_string().contains("16 numbers (column-major) or 4 rows of 4"), "{bad}: {e}");
    }
}
