//! Int8 weights: symmetric quantisation with one scale per row (per output channel).
//!
//! A 2-D tensor `NAME` of shape `[rows, cols]` (a Linear layer's weight, `[out, in]`) is stored as
//! dtype `I8` (values in `-127..=127`; `-128` is read as is) together with a tensor
//! `NAME.scale` of shape `[rows]`, dtype `F32` or `F16`, every scale finite and `>= 0`. Element
//! `(r, c)` is `q[r][c] * scale[r]`. Writing picks `scale[r] = max_c |w[r][c]| / 127` and
//! `q = round(w / scale)`, so each value is off by at most `scale[r] / 2` (half a step: 1/254 of the
//! row's largest magnitude). Loading dequantises to `f32` once and keeps the integers: inference
//! computes a layer with int8 weights in integers ([`crate::nn::QuantWeight`]).

use crate::{Error, Result};
use half::f16;
use safetensors::tensor::Dtype;
use safetensors::SafeTensors;

/// Suffix of a scale tensor's name: the scales of `NAME` are in `NAME.scale`.
pub const SCALE_SUFFIX: &str = ".scale";

/// The name of the scale tensor of the `I8` tensor `name`.
pub fn scale_name(name: &str) -> String {
    format!("{name}{SCALE_SUFFIX}")
}

/// Quantises a row-major `[rows, data.len() / rows]` matrix: the `i8` values and one scale per row.
pub fn quantize(data: &[f32], rows: usize) -> (Vec<i8>, Vec<f32>) {
    if rows == 0 || data.is_empty() {
        return (Vec::new(), vec![0.0; rows]);
    }
    let cols = data.len() / rows;
    let mut q = Vec::with_capacity(data.len());
    let mut scales = Vec::with_capacity(rows);
    for row in data.chunks(cols.max(1)) {
        let max = row.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let scale = max / 127.0;
        scales.push(scale);
        q.extend(row.iter().map(|v| if scale > 0.0 { (v / scale).round().clamp(-127.0, 127.0) as i8 } else { 0 }));
    }
    (q, scales)
}

/// Little-endian bytes of `f32`s (a scale tensor's data).
pub fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The `f32` values of the `I8` tensor `name` (its `shape` already checked against the config, `q`
/// its data), using its scale tensor from `file`. Errors name the tensor and what is wrong: not
/// 2-D, the scale tensor missing, of the wrong shape or dtype, or a scale not finite or negative.
pub fn dequantize(name: &str, shape: &[usize], q: &[u8], file: &SafeTensors<'_>) -> Result<Vec<f32>> {
    read(name, shape, q, file).map(|t| t.values)
}

/// An `I8` tensor as read: its `f32` values, and the integers and row scales they come from.
pub struct Int8Tensor {
    /// `q[r][c] * scale[r]`, row-major.
    pub values: Vec<f32>,
    /// The stored integers, row-major.
    pub q: Vec<i8>,
    /// One scale per row.
    pub scale: Vec<f32>,
}

/// [`dequantize`], keeping the integers and scales too (for [`crate::nn::QuantWeight`]).
pub fn read(name: &str, shape: &[usize], q: &[u8], file: &SafeTensors<'_>) -> Result<Int8Tensor> {
    let [rows, cols] = *shape else {
        return Err(Error::Weights(format!(
            "tensor '{name}' has dtype I8 and shape {shape:?}; only 2-D weight matrices may be stored as I8"
        )));
    };
    let scale_name = scale_name(name);
    let view = file.tensor(&scale_name).map_err(|_| {
        Error::Weights(format!("tensor '{name}' has dtype I8 but its scale tensor '{scale_name}' is missing"))
    })?;
    if view.shape() != [rows] {
        return Err(Error::Weights(format!(
            "scale tensor '{scale_name}' has shape {:?}; tensor '{name}' of shape {shape:?} needs [{rows}] (one scale per row)",
            view.shape()
        )));
    }
    let bytes = view.data();
    let scales: Vec<f32> = match view.dtype() {
        Dtype::F32 => bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect(),
        Dtype::F16 => bytes.chunks_exact(2).map(|c| f16::from_le_bytes([c[0], c[1]]).to_f32()).collect(),
        other => {
            return Err(Error::Weights(format!(
                "scale tensor '{scale_name}' has dtype {other:?}; scales must be F32 or F16"
            )))
        }
    };
    if let Some((row, s)) = scales.iter().enumerate().find(|(_, s)| !(s.is_finite() && **s >= 0.0)) {
        return Err(Error::Weights(format!(
            "scale tensor '{scale_name}' has the invalid scale {s} at row {row} (scales must be finite and >= 0)"
        )));
    }
    if q.len() != rows * cols {
        // safetensors checks that a tensor's bytes match its shape; this guards the arithmetic below.
        return Err(Error::Weights(format!("tensor '{name}' has {} bytes, its shape needs {}", q.len(), rows * cols)));
    }
    let mut out = Vec::with_capacity(q.len());
    for (row, scale) in q.chunks(cols.max(1)).zip(&scales) {
        out.extend(row.iter().map(|b| f32::from(*b as i8) * scale));
    }
    Ok(Int8Tensor { values: out, q: q.iter().map(|b| *b as i8).collect(), scale: scales })
}
