//! Int8 weights (`StoreAs::I8`, `weights::int8`): quantise then load gives every weight within
//! half a quantisation step, the file is about half of f16, and every malformed scale, shape or
//! dtype gets an error that names the tensor.

use arps::model::ModelConfig;
use arps::{StoreAs, Weights};
use half::f16;
use safetensors::tensor::{Dtype, TensorView};
use safetensors::SafeTensors;
use std::collections::HashMap;

type Raw = (String, Dtype, Vec<usize>, Vec<u8>);

fn tiny() -> Weights {
    Weights::random(&ModelConfig::tiny(), 7).unwrap()
}

fn err(bytes: &[u8]) -> String {
    Weights::from_bytes(bytes).unwrap_err().to_string()
}

/// The tensors of a serialised file, as (name, dtype, shape, bytes), in file order.
fn tensors_of(bytes: &[u8]) -> (Vec<Raw>, HashMap<String, String>) {
    let st = SafeTensors::deserialize(bytes).unwrap();
    let (_, meta) = SafeTensors::read_metadata(bytes).unwrap();
    let raw = st
        .tensors()
        .into_iter()
        .map(|(n, v)| (n.to_string(), v.dtype(), v.shape().to_vec(), v.data().to_vec()))
        .collect();
    (raw, meta.metadata().clone().unwrap())
}

fn craft(tensors: &[Raw], meta: HashMap<String, String>) -> Vec<u8> {
    let views: Vec<(String, TensorView<'_>)> =
        tensors.iter().map(|(n, d, s, b)| (n.clone(), TensorView::new(*d, s.clone(), b).unwrap())).collect();
    safetensors::serialize(views, Some(meta)).unwrap()
}

/// The tiny model stored as I8, then edited by `edit` and serialised again (with the checksum
/// of the edited tensors, as a tool that writes the file would).
fn edited(edit: impl FnOnce(&mut Vec<Raw>)) -> Vec<u8> {
    let (mut raw, mut meta) = tensors_of(&tiny().to_bytes(StoreAs::I8).unwrap());
    edit(&mut raw);
    let sum = arps::weights::tensor_checksum(raw.iter().map(|(n, _, _, b)| (n.as_str(), b.as_slice())));
    meta.insert("checksum".to_string(), sum);
    craft(&raw, meta)
}

/// The name of an I8 matrix with more than four rows, the first by name, so that every test
/// edits the same tensor whatever order the file lists them in (and a wrong scale shape such as
/// `[1]` or `[2, 2]` cannot match the matrix's row count by chance).
fn first_i8() -> String {
    let (raw, _) = tensors_of(&tiny().to_bytes(StoreAs::I8).unwrap());
    raw.iter().filter(|t| t.1 == Dtype::I8 && t.2[0] > 4).map(|t| t.0.clone()).min().unwrap()
}

fn index(raw: &[Raw], name: &str) -> usize {
    raw.iter().position(|t| t.0 == name).unwrap_or_else(|| panic!("{name} not in the file"))
}

#[test]
fn round_trip_is_within_half_a_step_per_row() {
    let w = tiny();
    let bytes = w.to_bytes(StoreAs::I8).unwrap();
    let (raw, _) = tensors_of(&bytes);
    let back = Weights::from_bytes(&bytes).unwrap();
    assert_eq!(back.config, w.config);
    let specs = w.config.tensor_specs();
    let mut matrices = 0;
    for (name, shape) in &specs {
        let (a, b) = (&w.tensors[name], &back.tensors[name]);
        let dtype = raw[index(&raw, name)].1;
        if shape.len() == 2 {
            matrices += 1;
            assert_eq!(dtype, Dtype::I8, "{name}");
            for (r, (ra, rb)) in a.chunks(shape[1]).zip(b.chunks(shape[1])).enumerate() {
                let step = ra.iter().fold(0.0f32, |m, v| m.max(v.abs())) / 127.0;
                let worst = ra.iter().zip(rb).fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
                assert!(worst <= 0.5 * step * (1.0 + 1e-5) + 1e-12, "{name} row {r}: off by {worst}, step {step}");
                // The largest magnitude of each row is kept (it defines the scale).
                let i = ra.iter().enumerate().max_by(|x, y| x.1.abs().total_cmp(&y.1.abs())).unwrap().0;
                assert!((ra[i] - rb[i]).abs() <= 1e-6 * ra[i].abs(), "{name} row {r}");
            }
        } else {
            assert_eq!(dtype, Dtype::F16, "{name}");
            for (x, y) in a.iter().zip(b) {
                assert_eq!(*y, f16::from_f32(*x).to_f32(), "{name}");
            }
        }
    }
    assert!(matrices > 0);
    // Quantising again what was loaded changes nothing beyond f32 rounding: the grid is stable.
    let again = Weights::from_bytes(&back.to_bytes(StoreAs::I8).unwrap()).unwrap();
    for (name, v) in &back.tensors {
        for (x, y) in v.iter().zip(&again.tensors[name]) {
            assert!((x - y).abs() <= 1e-6 * x.abs(), "{name}: {x} requantised to {y}");
        }
    }
}

#[test]
fn the_web_model_is_about_half_of_f16() {
    let w = Weights::random(&ModelConfig::preset("web").unwrap(), 3).unwrap();
    let i8 = w.to_bytes(StoreAs::I8).unwrap().len();
    let f16 = w.to_bytes(StoreAs::F16).unwrap().len();
    let params = w.config.parameter_count();
    assert!(i8 < f16 * 55 / 100, "int8 {i8} bytes vs f16 {f16}");
    assert!(i8 < params + params / 10, "int8 {i8} bytes for {params} parameters");
}

#[test]
fn values_are_q_times_the_row_scale_with_f32_or_f16_scales() {
    let name = first_i8();
    for f16_scales in [false, true] {
        let bytes = edited(|raw| {
            let i = index(raw, &name);
            let (rows, cols) = (raw[i].2[0], raw[i].2[1]);
            raw[i].3 = (0..rows * cols).map(|k| ((k % 255) as i32 - 127) as i8 as u8).collect();
            let s = index(raw, &format!("{name}.scale"));
            let scales: Vec<f32> = (0..rows).map(|r| 0.5 + r as f32 * 0.25).collect();
            raw[s] = if f16_scales {
                let b = scales.iter().flat_map(|v| f16::from_f32(*v).to_le_bytes()).collect();
                (raw[s].0.clone(), Dtype::F16, vec![rows], b)
            } else {
                (raw[s].0.clone(), Dtype::F32, vec![rows], scales.iter().flat_map(|v| v.to_le_bytes()).collect())
            };
        });
        let w = Weights::from_bytes(&bytes).unwrap();
        let shape = &w.config.tensor_specs().into_iter().find(|(n, _)| *n == name).unwrap().1;
        let cols = shape[1];
        for (k, v) in w.tensors[&name].iter().enumerate() {
            let want = ((k % 255) as i32 - 127) as f32 * (0.5 + (k / cols) as f32 * 0.25);
            assert_eq!(*v, want, "element {k} (f16 scales: {f16_scales})");
        }
    }
}

#[test]
fn a_missing_scale_tensor_is_named() {
    let name = first_i8();
    let e = err(&edited(|raw| {
        raw.remove(index(raw, &format!("{name}.scale")));
    }));
    assert!(e.contains(&format!("tensor '{name}' has dtype I8 but its scale tensor '{name}.scale' is missing")), "{e}");
}

#[test]
fn a_scale_of_the_wrong_shape_is_named() {
    let name = first_i8();
    for shape in [vec![1], vec![0], vec![2, 2]] {
        let e = err(&edited(|raw| {
            let s = index(raw, &format!("{name}.scale"));
            let n: usize = shape.iter().product();
            raw[s] = (raw[s].0.clone(), Dtype::F32, shape.clone(), vec![0; 4 * n]);
        }));
        assert!(e.contains(&format!("scale tensor '{name}.scale' has shape {shape:?}")), "{shape:?}: {e}");
        assert!(e.contains("one scale per row"), "{e}");
    }
}

#[test]
fn a_scale_of_the_wrong_dtype_is_named() {
    let name = first_i8();
    for dtype in [Dtype::I32, Dtype::I8, Dtype::F64] {
        let e = err(&edited(|raw| {
            let s = index(raw, &format!("{name}.scale"));
            let rows = raw[s].2[0];
            raw[s] = (raw[s].0.clone(), dtype, vec![rows], vec![0; dtype.bitsize() / 8 * rows]);
        }));
        assert!(
            e.contains(&format!("scale tensor '{name}.scale' has dtype {dtype:?}; scales must be F32 or F16")),
            "{e}"
        );
    }
}

#[test]
fn negative_and_non_finite_scales_are_rejected() {
    let name = first_i8();
    for (bad, shown) in [(-1.0f32, "-1"), (f32::NAN, "NaN"), (f32::INFINITY, "inf")] {
        let e = err(&edited(|raw| {
            let s = index(raw, &format!("{name}.scale"));
            raw[s].3[4..8].copy_from_slice(&bad.to_le_bytes());
        }));
        assert!(e.contains(&format!("'{name}.scale' has the invalid scale {shown} at row 1")), "{e}");
    }
    // A huge scale is finite, but its products overflow: caught as a non-finite weight.
    let e = err(&edited(|raw| {
        let s = index(raw, &format!("{name}.scale"));
        raw[s].3[0..4].copy_from_slice(&f32::MAX.to_le_bytes());
        let i = index(raw, &name);
        raw[i].3[0] = 127;
    }));
    assert!(e.contains(&format!("tensor '{name}' has a non-finite value at element 0")), "{e}");
}

#[test]
fn i8_is_only_for_matrices_and_scales_only_for_i8_tensors() {
    // An I8 bias (1-D), even with a scale tensor.
    let bias = first_i8().replace(".weight", ".bias");
    let e = err(&edited(|raw| {
        let i = index(raw, &bias);
        let n = raw[i].2[0];
        raw[i] = (bias.clone(), Dtype::I8, vec![n], vec![1; n]);
        raw.push((format!("{bias}.scale"), Dtype::F32, vec![n], vec![0; 4 * n]));
    }));
    assert!(e.contains(&format!("tensor '{bias}' has dtype I8 and shape")), "{e}");
    assert!(e.contains("only 2-D weight matrices may be stored as I8"), "{e}");
    // A scale next to a tensor stored as f16: not part of the file format.
    let name = first_i8();
    let e = err(&edited(|raw| {
        let i = index(raw, &name);
        let n: usize = raw[i].2.iter().product();
        raw[i] = (name.clone(), Dtype::F16, raw[i].2.clone(), vec![0; 2 * n]);
    }));
    assert!(e.contains(&format!("tensor '{name}.scale' is a scale, but tensor '{name}' is not stored as I8")), "{e}");
    // A scale of no tensor at all.
    let e = err(&edited(|raw| raw.push(("nothing.weight.scale".into(), Dtype::F32, vec![1], vec![0; 4]))));
    assert!(e.contains("tensor 'nothing.weight.scale' is not part of the declared config"), "{e}");
}

#[test]
fn an_i8_matrix_of_the_wrong_shape_is_named() {
    let name = first_i8();
    let e = err(&edited(|raw| {
        let i = index(raw, &name);
        let n: usize = raw[i].2.iter().product();
        raw[i].2 = vec![n];
    }));
    assert!(e.contains(&format!("tensor '{name}' has shape")), "{e}");
}

#[test]
fn requantised_default_model_registers_like_the_loaded_one() {
    let original = Weights::from_bytes(arps::weights::DEFAULT_MODEL).unwrap();
    let quantised = Weights::from_bytes(&original.to_bytes(StoreAs::I8).unwrap()).unwrap();
    let (source, target, truth) = common::fixture_pair(0);
    let options = arps::Options { icp: arps::IcpKind::Off, starts: vec![arps::Start::Network], ..Default::default() };
    let a = arps::Registrar::new(&original).unwrap().register(&source, &target, &options).unwrap();
    let b = arps::Registrar::new(&quantised).unwrap().register(&source, &target, &options).unwrap();
    // The network's estimates (no ICP) of the two models are close to each other.
    let between = arps::transform::rotation_angle_deg(&(a.T_target_source.try_inverse().unwrap() * b.T_target_source));
    assert!(between < 2.0, "the int8 model's network estimate is {between} deg from the original's");
    // With the default pipeline the int8 model recovers the ground truth.
    let r = arps::Registrar::new(&quantised).unwrap().register(&source, &target, &Default::default()).unwrap();
    let off = arps::transform::rotation_angle_deg(&(truth.try_inverse().unwrap() * r.T_target_source));
    assert!(off < 5.0, "int8 model: {off} deg from the truth");
}

mod common;

/// Every linear layer of a model.
fn matrices(m: &arps::model::Model) -> Vec<&arps::nn::Linear> {
    let mut all: Vec<&arps::nn::Linear> = m.head.layers.iter().collect();
    for l in &m.layers {
        all.extend(l.pos.layers.iter().chain(&l.step.layers));
        all.push(&l.out);
        for b in [&l.self_attn, &l.cross_attn] {
            all.extend([&b.attn.q, &b.attn.k, &b.attn.v, &b.attn.o, &b.ffn1, &b.ffn2]);
        }
    }
    all
}

#[test]
fn an_int8_model_computes_in_integers_and_close_to_its_f32_values() {
    let loaded = Weights::from_bytes(arps::weights::DEFAULT_MODEL).unwrap();
    assert!(!loaded.int8.is_empty(), "the default model is stored as int8");
    let mut as_f32 = loaded.clone();
    as_f32.int8.clear();
    let ints = arps::model::Model::from_weights(&loaded).unwrap();
    let floats = arps::model::Model::from_weights(&as_f32).unwrap();
    assert!(matrices(&ints).iter().all(|l| l.quant.is_some()));
    assert!(matrices(&floats).iter().all(|l| l.quant.is_none()));
    // the network's memberships on a real pair (N points each, pre-centred by the model)
    let (source, target, _) = common::fixture_pair(0);
    let n = loaded.config.n_points;
    let (s, t) = (arps::refine::even_sample(&source.points, n), arps::refine::even_sample(&target.points, n));
    let mut ws = arps::model::ModelWorkspace::default();
    let a = ints.forward(&s, &t, &mut ws).unwrap();
    let b = floats.forward(&s, &t, &mut ws).unwrap();
    let gap = |x: &[f32], y: &[f32]| x.iter().zip(y).fold(0.0f32, |m, (u, v)| m.max((u - v).abs()));
    let (gs, gt) = (gap(&a.gamma_source, &b.gamma_source), gap(&a.gamma_target, &b.gamma_target));
    assert!(gs < 2e-3 && gt < 2e-3, "memberships differ by {gs} / {gt}");
    assert!(gs > 0.0 || gt > 0.0, "the integer path gave the f32 path's bits: was it used?");
    // weights edited after loading no longer match their integers: those layers compute in f32
    let mut edited = loaded.clone();
    edited.tensors.get_mut("head.0.weight").unwrap()[0] += 0.5;
    let m = arps::model::Model::from_weights(&edited).unwrap();
    assert!(m.head.layers[0].quant.is_none() && m.head.layers[1].quant.is_some());
}
