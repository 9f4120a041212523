#![cfg(feature = "train")]
//! Equivalence of the engine and the PyTorch trainer (`trainer/arps_torch`), both ways, on a tiny
//! config:
//!
//! * `fixtures/equivalence/torch_*` were written by the PyTorch side
//!   (`python -m arps_torch.fixture`): weights in the engine's format, two clouds, and PyTorch's
//!   memberships, steps, shifts and `T_target_source`. The engine reproduces them within 1e-4.
//! * `fixtures/equivalence/rust_*` are the engine's: this test checks they are current (the
//!   engine on the committed inputs gives the committed outputs) and rewrites them when
//!   `ARPS_WRITE_FIXTURES=1`; `trainer/tests/test_equivalence.py` reproduces them with PyTorch.

use arps::model::{Model, ModelWorkspace};
use arps::{gmr, ModelConfig, StoreAs, Weights};
use nalgebra::Matrix4;
use safetensors::tensor::{Dtype, TensorView};
use safetensors::SafeTensors;
use std::collections::BTreeMap;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/equivalence").join(name)
}

/// The values a fixture holds: inputs and the network's outputs.
struct Io {
    source: Vec<[f32; 3]>,
    target: Vec<[f32; 3]>,
    gamma_source: Vec<f32>,
    gamma_target: Vec<f32>,
    steps: Vec<f32>,
    shifts_source: Vec<[f32; 3]>,
    shifts_target: Vec<[f32; 3]>,
    t12: Matrix4<f64>,
}

fn read_io(name: &str) -> Io {
    let bytes = std::fs::read(fixture(name)).unwrap();
    let st = SafeTensors::deserialize(&bytes).unwrap();
    let f32s = |k: &str| -> Vec<f32> {
        let v = st.tensor(k).unwrap_or_else(|_| panic!("{name}: {k} missing"));
        assert_eq!(v.dtype(), Dtype::F32, "{k}");
        v.data().chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
    };
    let pts = |k: &str| f32s(k).chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect::<Vec<_>>();
    let t = st.tensor("t12").unwrap();
    assert_eq!(t.dtype(), Dtype::F64);
    let t: Vec<f64> = t.data().chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
    Io {
        source: pts("source"),
        target: pts("target"),
        gamma_source: f32s("gamma_source"),
        gamma_target: f32s("gamma_target"),
        steps: f32s("steps"),
        shifts_source: pts("shifts_source"),
        shifts_target: pts("shifts_target"),
        t12: Matrix4::from_fn(|r, c| t[r * 4 + c]),
    }
}

/// The engine on a fixture's clouds: its outputs in the fixture's form.
fn engine(w: &Weights, source: &[[f32; 3]], target: &[[f32; 3]]) -> Io {
    let model = Model::from_weights(w).unwrap();
    let out = model.forward(source, target, &mut ModelWorkspace::default()).unwrap();
    let j = w.config.gaussians;
    let gs = gmr::gmm_params(source, &out.gamma_source, j);
    let gt = gmr::gmm_params(target, &out.gamma_target, j);
    Io {
        source: source.to_vec(),
        target: target.to_vec(),
        t12: gmr::solve(&gs, &gt),
        gamma_source: out.gamma_source,
        gamma_target: out.gamma_target,
        steps: out.steps,
        shifts_source: out.shifts_source,
        shifts_target: out.shifts_target,
    }
}

fn max_diff(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| (x - y).abs() as f64).fold(0.0, f64::max)
}

fn assert_close(got: &Io, want: &Io, tol: f64, what: &str) {
    let flat = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    for (name, d) in [
        ("gamma_source", max_diff(&got.gamma_source, &want.gamma_source)),
        ("gamma_target", max_diff(&got.gamma_target, &want.gamma_target)),
        ("steps", max_diff(&got.steps, &want.steps)),
        ("shifts_source", max_diff(&flat(&got.shifts_source), &flat(&want.shifts_source))),
        ("shifts_target", max_diff(&flat(&got.shifts_target), &flat(&want.shifts_target))),
        ("t12", (got.t12 - want.t12).abs().max()),
    ] {
        eprintln!("{what}: {name} max difference {d:e}");
        assert!(d <= tol, "{what}: {name} differs by {d:e} (> {tol:e})");
    }
}

#[test]
fn engine_reproduces_the_torch_fixture() {
    let w = Weights::from_bytes(&std::fs::read(fixture("torch_tiny.safetensors")).unwrap()).unwrap();
    assert_eq!(w.config, ModelConfig { preset: w.config.preset.clone(), ..ModelConfig::tiny() });
    let torch = read_io("torch_io.safetensors");
    // the memberships must be far from uniform, or agreement would prove little
    let spread = torch.gamma_source.iter().fold(0.0f32, |m, &g| m.max(g)) - 1.0 / w.config.gaussians as f32;
    assert!(spread > 0.1, "fixture memberships are nearly uniform ({spread})");
    let got = engine(&w, &torch.source, &torch.target);
    assert_close(&got, &torch, 1e-4, "engine vs PyTorch");
}

fn write_io(name: &str, io: &Io) {
    let flat = |v: &[[f32; 3]]| v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let (n, m, l) = (io.source.len(), io.target.len(), io.steps.len());
    let j = io.gamma_source.len() / n;
    let t: Vec<u8> = (0..16).flat_map(|i| io.t12[(i / 4, i % 4)].to_le_bytes()).collect();
    let raw: Vec<(&str, Dtype, Vec<usize>, Vec<u8>)> = vec![
        ("source", Dtype::F32, vec![n, 3], flat(&io.source)),
        ("target", Dtype::F32, vec![m, 3], flat(&io.target)),
        ("gamma_source", Dtype::F32, vec![n, j], bytes(&io.gamma_source)),
        ("gamma_target", Dtype::F32, vec![m, j], bytes(&io.gamma_target)),
        ("steps", Dtype::F32, vec![l], bytes(&io.steps)),
        ("shifts_source", Dtype::F32, vec![l, 3], flat(&io.shifts_source)),
        ("shifts_target", Dtype::F32, vec![l, 3], flat(&io.shifts_target)),
        ("t12", Dtype::F64, vec![4, 4], t),
    ];
    let views: Vec<(String, TensorView<'_>)> =
        raw.iter().map(|(k, d, s, b)| (k.to_string(), TensorView::new(*d, s.clone(), b).unwrap())).collect();
    let meta = std::collections::HashMap::from([("written_by".to_string(), "tests/train_equivalence.rs".to_string())]);
    std::fs::write(fixture(name), safetensors::serialize(views, Some(meta)).unwrap()).unwrap();
}

/// A tiny config's weights, scaled up from the engine's initialisation so that the memberships
/// are far from uniform (a test of the whole computation, not of near-constant outputs).
fn rust_weights() -> Weights {
    let mut w = Weights::random(&ModelConfig::tiny(), 11).unwrap();
    let tensors: BTreeMap<String, Vec<f32>> = w
        .tensors
        .iter()
        .map(|(k, v)| {
            let s = if k.starts_with("head.") { 4.0 } else { 1.5 };
            (k.clone(), v.iter().map(|x| x * s).collect())
        })
        .collect();
    w.tensors = tensors;
    w.provenance = serde_json::json!({"fixture": "tests/train_equivalence.rs"});
    w
}

#[test]
fn rust_fixture_is_current() {
    if std::env::var("ARPS_WRITE_FIXTURES").is_ok_and(|v| v == "1") {
        // stored f16 (half the size); the outputs are the engine's on the stored weights
        let bytes = rust_weights().to_bytes(StoreAs::F16).unwrap();
        std::fs::write(fixture("rust_tiny.safetensors"), &bytes).unwrap();
        let w = Weights::from_bytes(&bytes).unwrap();
        let pair = &arps::train::synthetic::pairs(1, 48, 3)[0];
        let target: Vec<[f32; 3]> = pair.target[..40].to_vec(); // clouds of different sizes
        write_io("rust_io.safetensors", &engine(&w, &pair.source, &target));
    }
    let w = Weights::from_bytes(&std::fs::read(fixture("rust_tiny.safetensors")).unwrap()).unwrap();
    let stored = read_io("rust_io.safetensors");
    let spread = stored.gamma_source.iter().fold(0.0f32, |m, &g| m.max(g)) - 1.0 / w.config.gaussians as f32;
    assert!(spread > 0.1, "fixture memberships are nearly uniform ({spread})");
    assert_close(&engine(&w, &stored.source, &stored.target), &stored, 1e-5, "engine vs its committed fixture");
}
