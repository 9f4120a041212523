//! The weights file: round trips, and every kind of corrupt or mismatched file gets a clear error.

use arps::model::{ModelConfig, Reference};
use arps::{StoreAs, Weights};
use safetensors::tensor::{Dtype, TensorView};
use std::collections::HashMap;

fn tiny() -> Weights {
    Weights::random(&ModelConfig::tiny(), 7).unwrap()
}

fn err(bytes: &[u8]) -> String {
    Weights::from_bytes(bytes).unwrap_err().to_string()
}

/// Serialises arbitrary tensors with the given metadata (for crafting bad files).
fn craft(tensors: &[(String, Dtype, Vec<usize>, Vec<u8>)], meta: HashMap<String, String>) -> Vec<u8> {
    let views: Vec<(String, TensorView<'_>)> =
        tensors.iter().map(|(n, d, s, b)| (n.clone(), TensorView::new(*d, s.clone(), b).unwrap())).collect();
    safetensors::serialize(views, Some(meta)).unwrap()
}

fn good_meta(config: &ModelConfig) -> HashMap<String, String> {
    HashMap::from([
        ("format".to_string(), "arps-weights".to_string()),
        ("format_version".to_string(), "1".to_string()),
        ("config".to_string(), serde_json::to_string(config).unwrap()),
    ])
}

fn f32_tensors(w: &Weights) -> Vec<(String, Dtype, Vec<usize>, Vec<u8>)> {
    w.config
        .tensor_specs()
        .into_iter()
        .map(|(n, s)| {
            let b = w.tensors[&n].iter().flat_map(|v| v.to_le_bytes()).collect();
            (n, Dtype::F32, s, b)
        })
        .collect()
}

#[test]
fn random_is_deterministic_and_seeded() {
    assert_eq!(tiny(), tiny());
    assert_ne!(tiny().tensors, Weights::random(&ModelConfig::tiny(), 8).unwrap().tensors);
}

#[test]
fn f32_round_trip_is_exact_and_f16_is_close() {
    let w = tiny();
    let back = Weights::from_bytes(&w.to_bytes(StoreAs::F32).unwrap()).unwrap();
    assert_eq!(back, w);
    let half = Weights::from_bytes(&w.to_bytes(StoreAs::F16).unwrap()).unwrap();
    assert_eq!(half.config, w.config);
    for (name, v) in &w.tensors {
        for (a, b) in v.iter().zip(&half.tensors[name]) {
            assert!((a - b).abs() <= 1e-3 * a.abs().max(1e-2), "{name}: {a} vs {b}");
        }
    }
}

#[test]
fn both_reference_kinds_round_trip() {
    let mut c = ModelConfig::tiny();
    c.reference = Reference::TopH;
    let w = Weights::random(&c, 1).unwrap();
    assert!(!w.tensors.keys().any(|k| k.contains(".score.")));
    assert_eq!(Weights::from_bytes(&w.to_bytes(StoreAs::F32).unwrap()).unwrap(), w);
}

#[test]
fn missing_tensor_is_named() {
    let w = tiny();
    let mut t = f32_tensors(&w);
    let removed = t.remove(5).0;
    let e = err(&craft(&t, good_meta(&w.config)));
    assert!(e.contains(&format!("tensor '{removed}' is missing")), "{e}");
}

#[test]
fn wrong_shape_is_named() {
    let w = tiny();
    let mut t = f32_tensors(&w);
    let (name, _, shape, bytes) = t[0].clone();
    t[0] = (name.clone(), Dtype::F32, vec![shape.iter().product::<usize>()], bytes);
    let e = err(&craft(&t, good_meta(&w.config)));
    assert!(e.contains(&format!("tensor '{name}' has shape")), "{e}");
}

#[test]
fn wrong_dtype_is_named() {
    let w = tiny();
    let mut t = f32_tensors(&w);
    let (name, _, shape, bytes) = t[2].clone();
    t[2] = (name.clone(), Dtype::I32, shape, bytes);
    let e = err(&craft(&t, good_meta(&w.config)));
    assert!(e.contains(&format!("tensor '{name}' has dtype")), "{e}");
}

#[test]
fn extra_tensor_is_named() {
    let w = tiny();
    let mut t = f32_tensors(&w);
    t.push(("layers.9.bogus.weight".into(), Dtype::F32, vec![2], vec![0; 8]));
    let e = err(&craft(&t, good_meta(&w.config)));
    assert!(e.contains("layers.9.bogus.weight"), "{e}");
}

#[test]
fn config_mismatch_with_tensors_is_reported() {
    // tensors of the tiny config, metadata claiming a wider model
    let w = tiny();
    let mut c = w.config.clone();
    c.feature_dim = 16;
    let e = err(&craft(&f32_tensors(&w), good_meta(&c)));
    assert!(e.contains("has shape"), "{e}");
}

#[test]
fn non_finite_values_are_rejected() {
    let w = tiny();
    let mut t = f32_tensors(&w);
    t[3].3[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = err(&craft(&t, good_meta(&w.config)));
    assert!(e.contains("non-finite value at element 1"), "{e}");
}

#[test]
fn metadata_problems_are_reported() {
    let w = tiny();
    let t = f32_tensors(&w);
    let mut m = good_meta(&w.config);
    m.insert("format".into(), "something-else".into());
    assert!(err(&craft(&t, m)).contains("format is 'something-else'"));
    let mut m = good_meta(&w.config);
    m.insert("format_version".into(), "99".into());
    assert!(err(&craft(&t, m)).contains("format_version '99'"));
    let mut m = good_meta(&w.config);
    m.remove("config");
    assert!(err(&craft(&t, m)).contains("'config' is missing"));
    let mut m = good_meta(&w.config);
    m.insert("config".into(), "{not json".into());
    assert!(err(&craft(&t, m)).contains("not a valid model config"));
    let mut c = w.config.clone();
    c.heads = 3;
    assert!(err(&craft(&t, good_meta(&c))).contains("invalid model config"));
    assert!(err(&craft(&t, HashMap::new())).contains("missing"));
}

#[test]
fn truncated_and_garbage_files_are_rejected() {
    let bytes = tiny().to_bytes(StoreAs::F32).unwrap();
    for cut in [0, 4, 8, 20, bytes.len() / 2, bytes.len() - 1] {
        let e = err(&bytes[..cut]);
        assert!(e.starts_with("weights:"), "cut {cut}: {e}");
    }
    assert!(err(b"hello world, definitely not safetensors").starts_with("weights:"));
    // a header length far beyond the buffer
    let mut hostile = (u64::MAX / 2).to_le_bytes().to_vec();
    hostile.extend_from_slice(b"{}");
    assert!(err(&hostile).starts_with("weights:"));
}

/// A damaged file whose bytes still parse (a changed weight, a swapped byte) is refused by its
/// checksum, not run with changed weights; a file without a checksum (another tool's) loads.
#[test]
fn tensors_that_do_not_match_the_checksum_are_refused() {
    let w = tiny();
    for store in [StoreAs::F32, StoreAs::F16, StoreAs::I8] {
        let bytes = w.to_bytes(store).unwrap();
        let (_, meta) = safetensors::SafeTensors::read_metadata(&bytes).unwrap();
        let sum = meta.metadata().as_ref().unwrap()["checksum"].clone();
        assert!(sum.starts_with("fnv1a64:") && sum.len() == 24, "{sum}");
        let header = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize + 8;
        // a low mantissa bit of a value in the middle of the data: a finite, plausible weight
        let mut damaged = bytes.clone();
        damaged[(header + (bytes.len() - header) / 2) & !3] ^= 1;
        let e = err(&damaged);
        assert!(e.contains("checksum") && e.contains(&sum) && e.contains("damaged"), "{e}");
    }
    // the same tensors without the key: read as before
    let no_sum = craft(&f32_tensors(&w), good_meta(&w.config));
    assert_eq!(Weights::from_bytes(&no_sum).unwrap().tensors, w.tensors);
    // the key computed by the library's own function over the same tensors: read
    let tensors = f32_tensors(&w);
    let mut meta = good_meta(&w.config);
    meta.insert(
        "checksum".to_string(),
        arps::weights::tensor_checksum(tensors.iter().map(|(n, _, _, b)| (n.as_str(), b.as_slice()))),
    );
    assert_eq!(Weights::from_bytes(&craft(&tensors, meta.clone())).unwrap().tensors, w.tensors);
    meta.insert("checksum".to_string(), "fnv1a64:0000000000000000".to_string());
    assert!(err(&craft(&tensors, meta)).contains("checksum"));
}

#[test]
fn embedded_default_model_loads() {
    let w = Weights::from_bytes(arps::weights::DEFAULT_MODEL).unwrap();
    assert_eq!(w.config.preset, "web");
    w.config.validate().unwrap();
}

/// Issue 14: a 6 MB file whose config lists two million hidden widths (each valid on its own)
/// made loading allocate without bound; now it, and configs over any other bound, fail at once.
#[test]
fn configs_bounded_in_count_and_size_fail_before_allocating() {
    let w = tiny();
    let t = std::time::Instant::now();
    let mut huge = ModelConfig::tiny();
    huge.pos_hidden = vec![8; 2_000_000];
    let e = err(&craft(&f32_tensors(&w), good_meta(&huge)));
    assert!(e.contains("config metadata is") && e.contains("at most 65536"), "{e}");
    let mut long = ModelConfig::tiny();
    long.head_hidden = vec![8; 17];
    let e = err(&craft(&f32_tensors(&w), good_meta(&long)));
    assert!(e.contains("head_hidden lists 17 hidden widths"), "{e}");
    let mut wide = ModelConfig::tiny();
    wide.ffn_dim = 100_000;
    let e = err(&craft(&f32_tensors(&w), good_meta(&wide)));
    assert!(e.contains("ffn_dim = 100000 is outside 1..=4096"), "{e}");
    assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
    // the registrar built after such failures works
    arps::Registrar::new(&w).unwrap();
}
