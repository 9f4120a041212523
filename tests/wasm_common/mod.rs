//! Helpers shared by the wasm tests (`tests/wasm_*.rs`), which run in Node under
//! `wasm-pack test --node` and call the exported JS-facing functions of `arps::wasm`.
#![allow(dead_code)]

use arps::transform;
use js_sys::{Array, Float32Array, Object, Reflect};
use nalgebra::Matrix4;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

#[path = "../common/box_grid.rs"]
pub mod box_grid;

pub const SOURCE_PLY: &[u8] = include_bytes!("../../fixtures/wasm/source.ply");
pub const TARGET_PLY: &[u8] = include_bytes!("../../fixtures/wasm/target.ply");
pub const PAIR_JSON: &str = include_str!("../../fixtures/wasm/pair.json");

/// Minimal ASCII-PLY reader for the test fixtures (independent of the core readers, so the
/// registration checks do not depend on them and the reader checks have a reference).
pub fn ascii_ply_xyz(bytes: &[u8]) -> Vec<f32> {
    let text = std::str::from_utf8(bytes).expect("fixture is UTF-8");
    let (_, body) = text.split_once("end_header\n").expect("fixture has a PLY header");
    body.split_ascii_whitespace().map(|v| v.parse::<f32>().expect("fixture number")).collect()
}

pub fn source() -> Vec<f32> {
    ascii_ply_xyz(SOURCE_PLY)
}

pub fn target() -> Vec<f32> {
    ascii_ply_xyz(TARGET_PLY)
}

/// The fixture pair's ground truth `T_target_source`.
pub fn ground_truth() -> Matrix4<f64> {
    let v: serde_json::Value = serde_json::from_str(PAIR_JSON).expect("pair.json");
    let rows: [[f64; 4]; 4] = serde_json::from_value(v["T_target_source"].clone()).expect("rows");
    transform::from_rows(&rows)
}

/// The message of a thrown JS `Error`.
pub fn message(e: JsError) -> String {
    let v: JsValue = e.into();
    assert!(v.is_instance_of::<js_sys::Error>(), "a JS Error is thrown, got {v:?}");
    v.unchecked_into::<js_sys::Error>().message().into()
}

pub fn get(obj: &JsValue, key: &str) -> JsValue {
    Reflect::get(obj, &JsValue::from_str(key)).expect("Reflect.get")
}

pub fn num(obj: &JsValue, key: &str) -> f64 {
    get(obj, key).as_f64().unwrap_or_else(|| panic!("{key} is a number"))
}

/// A result transform field (an `Array` of 16 numbers, column-major) as a `Matrix4`.
pub fn matrix(obj: &JsValue, key: &str) -> Matrix4<f64> {
    let v = get(obj, key);
    assert!(Array::is_array(&v), "{key} is an Array");
    let a: Array = v.unchecked_into();
    assert_eq!(a.length(), 16, "{key} has 16 elements");
    let mut m = [0.0f64; 16];
    for (i, x) in a.iter().enumerate() {
        m[i] = x.as_f64().unwrap_or_else(|| panic!("{key}[{i}] is not a number"));
    }
    transform::from_column_major(&m)
}

/// Builds a JS options object from JSON text (as a JS caller would write it).
pub fn options(json: &str) -> JsValue {
    js_sys::JSON::parse(json).expect("valid JSON")
}

/// An empty JS object.
pub fn empty_object() -> JsValue {
    Object::new().into()
}

/// Column-major `Float32Array` of a transform (what three.js `matrix.elements` holds).
pub fn column_major_js(m: &Matrix4<f64>) -> Float32Array {
    Float32Array::from(&transform::to_column_major_f32(m)[..])
}

pub fn strings(v: &JsValue) -> Vec<String> {
    assert!(Array::is_array(v), "an array");
    Array::from(v).iter().map(|s| s.as_string().expect("a string")).collect()
}
