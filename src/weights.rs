//! The weights file: safetensors with `f32`, `f16` or int8-quantised tensors and JSON metadata.
//!
//! Metadata keys (all strings, as safetensors requires):
//! * `format` = `"arps-weights"`, `format_version` = `"1"`;
//! * `config` = the [`ModelConfig`] as JSON;
//! * `provenance` = free-form JSON describing how the weights were made (trainer, steps, data,
//!   date, or `"random"` with its seed);
//! * `checksum` = `"fnv1a64:"` and 16 hex digits: FNV-1a (64-bit) of every tensor's name and
//!   stored bytes, tensors in name order ([`tensor_checksum`]). Written on every save; files
//!   without it (made by other tools) still load.
//!
//! Tensors are stored as `F32`, `F16`, or `I8` with a scale per row (see [`int8`]: a 2-D tensor
//! `NAME` of dtype `I8` comes with a tensor `NAME.scale`, `F32` or `F16`, one positive scale per
//! row; the value is `q * scale[row]`). Every tensor is `f32` once loaded; the integers of `I8`
//! tensors are kept too ([`Weights::int8`]), and the network computes those layers in integers
//! ([`crate::nn::QuantWeight`]: each input row quantised to 16 bits, exact 32-bit sums).
//!
//! Loading checks the format and version, validates the config, and checks that every tensor the
//! config needs is present with the right shape and a supported dtype, that every `I8` tensor has
//! its valid scale tensor (and that there are no other tensors), reporting the first mismatch by
//! name, and last that the tensors' bytes match the checksum, so that a file damaged in a
//! download or a copy is refused rather than run with changed weights.

pub mod int8;

use crate::model::config::ModelConfig;
use crate::{Error, Result};
use half::f16;
use rand::Rng;
use safetensors::tensor::{Dtype, TensorView};
use safetensors::SafeTensors;
use std::collections::{BTreeMap, HashMap};

/// Value of the `format` metadata key.
pub const FORMAT: &str = "arps-weights";
/// The format version this engine reads and writes.
pub const FORMAT_VERSION: u32 = 1;
/// Metadata key of the tensors' checksum ([`tensor_checksum`]).
pub const CHECKSUM_KEY: &str = "checksum";

/// The checksum of a file's tensors, as the `checksum` metadata holds it: `"fnv1a64:"` and 16
/// lower-case hex digits of FNV-1a (64-bit) over each tensor's name and then its stored bytes,
/// tensors in byte order of their names. `tensors` may come in any order.
pub fn tensor_checksum<'a>(tensors: impl IntoIterator<Item = (&'a str, &'a [u8])>) -> String {
    let mut sorted: Vec<(&str, &[u8])> = tensors.into_iter().collect();
    sorted.sort_unstable_by_key(|(name, _)| *name);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in sorted.iter().flat_map(|(name, data)| name.as_bytes().iter().chain(data.iter())) {
        h = (h ^ u64::from(*byte)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("fnv1a64:{h:016x}")
}

/// The embedded default model (`models/web.safetensors`; see `models/MODEL.md` for how it was made).
/// Only with the `embed-model` feature (on by default); the npm package's `.wasm` is built without
/// it and loads the same file as a separate asset.
#[cfg(feature = "embed-model")]
pub const DEFAULT_MODEL: &[u8] = include_bytes!("../models/web.safetensors");

/// Storage precision when saving.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreAs {
    /// 32-bit floats (exact).
    F32,
    /// 16-bit floats (half the size).
    F16,
    /// 8-bit integers with an `f32` scale per row ([`int8`]) for the 2-D weight matrices (a
    /// quarter of the size of `f32`), `f16` for the vectors (biases, LayerNorm).
    I8,
}

/// A model's configuration, provenance and tensors (always held as `f32` in memory).
#[derive(Clone, Debug, PartialEq)]
pub struct Weights {
    /// The network sizes.
    pub config: ModelConfig,
    /// How these weights were made (free-form JSON).
    pub provenance: serde_json::Value,
    /// Tensors by name, row-major `f32`.
    pub tensors: BTreeMap<String, Vec<f32>>,
    /// The tensors read from `I8` storage ([`int8`]), by name: their integers and row scales
    /// (their values are in `tensors` too). Inference computes those layers in integers
    /// ([`crate::nn::QuantWeight`]); empty for weights not read from such a file.
    pub int8: BTreeMap<String, (Vec<i8>, Vec<f32>)>,
}

impl Weights {
    /// Deterministic random initialisation for a config: Linear weights and biases uniform in
    /// `±1/sqrt(in)` (PyTorch's default), LayerNorm scale 1 and shift 0, the step MLP's output bias 0
    /// (so the first step is sigmoid(0) = 0.5). Same seed, same weights, on every platform.
    pub fn random(config: &ModelConfig, seed: u64) -> Result<Self> {
        config.validate()?;
        let mut tensors = BTreeMap::new();
        for (i, (name, shape)) in config.tensor_specs().into_iter().enumerate() {
            let len: usize = shape.iter().product();
            let mut rng = crate::sampling::rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(i as u64));
            let is_norm = name.contains(".norm");
            let data = if is_norm {
                vec![if name.ends_with(".weight") { 1.0 } else { 0.0 }; len]
            } else if name.contains(".step.1.bias") {
                vec![0.0; len]
            } else {
                // fan-in is the last dim of the weight; biases use their layer's weight fan-in.
                let fan_in = if name.ends_with(".weight") {
                    shape[1]
                } else {
                    let w = name.trim_end_matches(".bias").to_string() + ".weight";
                    config.tensor_specs().iter().find(|(n, _)| *n == w).map_or(1, |(_, s)| s[1])
                };
                let bound = 1.0 / (fan_in as f32).sqrt();
                (0..len).map(|_| rng.random_range(-bound..bound)).collect()
            };
            tensors.insert(name, data);
        }
        Ok(Self {
            config: config.clone(),
            provenance: serde_json::json!({
                "kind": "random",
                "seed": seed,
                "note": "untrained: deterministic random initialisation, for development and tests"
            }),
            tensors,
            int8: BTreeMap::new(),
        })
    }

    /// The tensor `name`. Panics if absent: loaded and random weights always hold every tensor
    /// of their config (checked at load).
    pub fn get(&self, name: &str) -> &[f32] {
        self.tensors.get(name).map(|v| v.as_slice()).unwrap_or_else(|| panic!("tensor {name} missing"))
    }

    /// Parses and validates a weights file.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let st = SafeTensors::deserialize(bytes)
            .map_err(|e| Error::Weights(format!("not a valid safetensors file: {e}")))?;
        let (_, meta) =
            SafeTensors::read_metadata(bytes).map_err(|e| Error::Weights(format!("bad safetensors header: {e}")))?;
        let meta = meta.metadata().clone().unwrap_or_default();
        let get = |k: &str| {
            meta.get(k)
                .ok_or_else(|| Error::Weights(format!("metadata key '{k}' is missing (not an arps weights file?)")))
        };
        let format = get("format")?;
        if format != FORMAT {
            return Err(Error::Weights(format!("metadata format is '{format}', expected '{FORMAT}'")));
        }
        let version = get("format_version")?;
        if version.parse::<u32>().ok() != Some(FORMAT_VERSION) {
            return Err(Error::Weights(format!(
                "format_version '{version}' is not supported (this engine reads version {FORMAT_VERSION})"
            )));
        }
        let config_json = get("config")?;
        if config_json.len() > crate::limits::MAX_MODEL_CONFIG_BYTES {
            return Err(Error::Weights(format!(
                "config metadata is {} bytes long; at most {} are allowed",
                config_json.len(),
                crate::limits::MAX_MODEL_CONFIG_BYTES
            )));
        }
        let config: ModelConfig = serde_json::from_str(config_json)
            .map_err(|e| Error::Weights(format!("config metadata is not a valid model config: {e}")))?;
        config.validate()?;
        let provenance = match meta.get("provenance") {
            Some(p) => {
                serde_json::from_str(p).map_err(|e| Error::Weights(format!("provenance metadata is not JSON: {e}")))?
            }
            None => serde_json::Value::Null,
        };
        let specs = config.tensor_specs();
        let mut tensors = BTreeMap::new();
        let mut int8s = BTreeMap::new();
        for (name, shape) in &specs {
            let view = st
                .tensor(name)
                .map_err(|_| Error::Weights(format!("tensor '{name}' is missing (config needs shape {shape:?})")))?;
            if view.shape() != shape.as_slice() {
                return Err(Error::Weights(format!(
                    "tensor '{name}' has shape {:?}, config needs {shape:?}",
                    view.shape()
                )));
            }
            let data = if view.dtype() == Dtype::I8 {
                let t = int8::read(name, shape, view.data(), &st)?;
                int8s.insert(name.clone(), (t.q, t.scale));
                t.values
            } else {
                decode(name, &view)?
            };
            if let Some(i) = data.iter().position(|v| !v.is_finite()) {
                return Err(Error::Weights(format!("tensor '{name}' has a non-finite value at element {i}")));
            }
            tensors.insert(name.clone(), data);
        }
        let scales = specs
            .iter()
            .filter(|(n, _)| st.tensor(n).is_ok_and(|v| v.dtype() == Dtype::I8))
            .map(|(n, _)| int8::scale_name(n))
            .collect::<std::collections::HashSet<_>>();
        if st.len() != specs.len() + scales.len() {
            let known: std::collections::HashSet<&str> = specs.iter().map(|(n, _)| n.as_str()).collect();
            let extra = st
                .names()
                .into_iter()
                .find(|n| !known.contains(n) && !scales.contains(*n))
                .unwrap_or_default()
                .to_string();
            return Err(Error::Weights(match extra.strip_suffix(int8::SCALE_SUFFIX) {
                Some(of) if known.contains(of) => {
                    format!("tensor '{extra}' is a scale, but tensor '{of}' is not stored as I8")
                }
                _ => format!("tensor '{extra}' is not part of the declared config (wrong config or wrong file)"),
            }));
        }
        if let Some(expected) = meta.get(CHECKSUM_KEY) {
            let names = st.names();
            let found = tensor_checksum(names.iter().filter_map(|n| Some((*n, st.tensor(n).ok()?.data()))));
            if &found != expected {
                return Err(Error::Weights(format!(
                    "the tensors' checksum is {found}, the file's metadata says {expected}: the file was \
                     damaged (in a download or a copy?) or its tensors changed after it was written"
                )));
            }
        }
        Ok(Self { config, provenance, tensors, int8: int8s })
    }

    /// Serialises to safetensors bytes.
    pub fn to_bytes(&self, store: StoreAs) -> Result<Vec<u8>> {
        let mut raw: Vec<(String, Dtype, Vec<usize>, Vec<u8>)> = Vec::new();
        for (name, shape) in self.config.tensor_specs() {
            let data = self.tensors.get(&name).ok_or_else(|| Error::Weights(format!("tensor '{name}' is missing")))?;
            match store {
                StoreAs::F32 => {
                    raw.push((name, Dtype::F32, shape, data.iter().flat_map(|v| v.to_le_bytes()).collect()))
                }
                StoreAs::I8 if shape.len() == 2 => {
                    let (q, scale) = int8::quantize(data, shape[0]);
                    raw.push((int8::scale_name(&name), Dtype::F32, vec![shape[0]], int8::f32_bytes(&scale)));
                    raw.push((name, Dtype::I8, shape, q.iter().map(|v| *v as u8).collect()));
                }
                StoreAs::F16 | StoreAs::I8 => raw.push((
                    name,
                    Dtype::F16,
                    shape,
                    data.iter().flat_map(|v| f16::from_f32(*v).to_le_bytes()).collect(),
                )),
            }
        }
        let views = raw
            .iter()
            .map(|(n, d, s, b)| {
                Ok((n.clone(), TensorView::new(*d, s.clone(), b).map_err(|e| Error::Weights(format!("{n}: {e}")))?))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut meta = HashMap::new();
        meta.insert("format".to_string(), FORMAT.to_string());
        meta.insert("format_version".to_string(), FORMAT_VERSION.to_string());
        meta.insert(
            "config".to_string(),
            serde_json::to_string(&self.config).map_err(|e| Error::Weights(e.to_string()))?,
        );
        meta.insert("provenance".to_string(), self.provenance.to_string());
        meta.insert(
            CHECKSUM_KEY.to_string(),
            tensor_checksum(raw.iter().map(|(n, _, _, b)| (n.as_str(), b.as_slice()))),
        );
        safetensors::serialize(views, Some(meta)).map_err(|e| Error::Weights(format!("serialising: {e}")))
    }
}

/// An `F32` or `F16` tensor's values.
fn decode(name: &str, view: &TensorView<'_>) -> Result<Vec<f32>> {
    let data = view.data();
    match view.dtype() {
        Dtype::F32 => Ok(data.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()),
        Dtype::F16 => Ok(data.chunks_exact(2).map(|c| f16::from_le_bytes([c[0], c[1]]).to_f32()).collect()),
        other => Err(Error::Weights(format!(
            "tensor '{name}' has dtype {other:?}; only F32, F16 and I8 (with a scale tensor) are supported"
        ))),
    }
}
