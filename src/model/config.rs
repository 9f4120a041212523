//! Model configuration: read from the weights file, with the two named presets of docs/design.md §7.

use crate::limits::{MAX_MODEL_DIM, MAX_MODEL_LAYERS, MAX_MODEL_LIST, MAX_MODEL_PARAMETERS};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// How each ARPS layer picks its reference point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "ModelReference"))]
pub enum Reference {
    /// The paper's rule: the mean of the H points with the largest feature norm (no gradient
    /// through the selection).
    TopH,
    /// Differentiable: a softmax over a learned per-point score (temperature
    /// [`ModelConfig::soft_temperature`]) weights the mean of positions and features.
    Soft,
}

/// Every size of the network. Stored as JSON in the weights file's metadata, with snake_case
/// keys; in JS (`Registrar.modelConfig`) the keys are camelCase (`arps::contract`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "ModelConfig", rename_all = "camelCase"))]
pub struct ModelConfig {
    /// Preset name this config started from (`web`, `paper`, or a custom label).
    pub preset: String,
    /// Network points per cloud, N.
    pub n_points: usize,
    /// Per-point feature width C; attention tokens are `2C` wide (`[f ; phi]`).
    pub feature_dim: usize,
    /// Attention heads; `2C` must be divisible by it.
    pub heads: usize,
    /// Hidden width of each attention block's feed-forward network.
    pub ffn_dim: usize,
    /// Number of ARPS layers, L.
    pub layers: usize,
    /// Top-H size of the `"top_h"` reference rule.
    pub top_h: usize,
    /// Number of Gaussians, J.
    pub gaussians: usize,
    /// Hidden widths of the position MLP `3 -> ... -> C`.
    pub pos_hidden: Vec<usize>,
    /// Hidden width of the step-size MLP `(3 + C) -> hidden -> 1`.
    pub step_hidden: usize,
    /// Hidden widths of the membership head `2C -> ... -> J`.
    pub head_hidden: Vec<usize>,
    /// Reference-point rule.
    pub reference: Reference,
    /// Softmax temperature of the `"soft"` reference rule.
    pub soft_temperature: f32,
    /// LayerNorm epsilon.
    pub layer_norm_eps: f32,
}

impl ModelConfig {
    /// The default shipped size: docs/design.md §7's starting point (C = 64, tokens 128, 4 heads,
    /// L = 4, J = 16) at N = 256 network points and H = N/4. At N = 512 the forward pass costs
    /// 4.5 GFLOP per pair, at N = 256 1.6 GFLOP (attention grows with N^2): the difference between
    /// about 150 ms and 55 ms in WebAssembly, and about 3x in training throughput. ICP refines on
    /// the full clouds, so the network only has to land in ICP's basin. The embedded model was
    /// then fine-tuned at N = 128 (`arps-train --network-points 128`: at equal CPU level for the
    /// full pipeline, a little behind for the network alone, at half the cost; `models/MODEL.md`), so its weights file says N = 128.
    pub fn web() -> Self {
        Self {
            preset: "web".into(),
            n_points: 256,
            feature_dim: 64,
            heads: 4,
            ffn_dim: 256,
            layers: 4,
            top_h: 64,
            gaussians: 16,
            pos_hidden: vec![32, 64],
            step_hidden: 64,
            head_hidden: vec![128, 64],
            reference: Reference::Soft,
            soft_temperature: 1.0,
            layer_norm_eps: 1e-5,
        }
    }

    /// The paper-size reconstruction (docs/design.md §7): C = 256, tokens 512, 4 heads, N = 1024.
    pub fn paper() -> Self {
        Self {
            preset: "paper".into(),
            n_points: 1024,
            feature_dim: 256,
            heads: 4,
            ffn_dim: 512,
            layers: 4,
            top_h: 256,
            gaussians: 16,
            pos_hidden: vec![64, 128],
            step_hidden: 64,
            head_hidden: vec![512, 256, 128],
            reference: Reference::TopH,
            soft_temperature: 1.0,
            layer_norm_eps: 1e-5,
        }
    }

    /// A tiny config for tests and gradient checks.
    pub fn tiny() -> Self {
        Self {
            preset: "tiny".into(),
            n_points: 32,
            feature_dim: 8,
            heads: 2,
            ffn_dim: 16,
            layers: 2,
            top_h: 8,
            gaussians: 4,
            pos_hidden: vec![8],
            step_hidden: 8,
            head_hidden: vec![8],
            reference: Reference::Soft,
            soft_temperature: 1.0,
            layer_norm_eps: 1e-5,
        }
    }

    /// A preset by name.
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "web" => Ok(Self::web()),
            "paper" => Ok(Self::paper()),
            "tiny" => Ok(Self::tiny()),
            other => Err(Error::InvalidOption(format!("unknown model preset '{other}' (expected web, paper or tiny)"))),
        }
    }

    /// Attention token width `2C`.
    pub fn token_dim(&self) -> usize {
        2 * self.feature_dim
    }

    /// Checks that the sizes are consistent and bounded in every dimension, count and size (a
    /// hostile file cannot make the engine allocate without limit): every size at most
    /// [`MAX_MODEL_DIM`], at most [`MAX_MODEL_LAYERS`] layers, at most [`MAX_MODEL_LIST`] entries
    /// in each hidden-width list, a preset name of at most 64 bytes, and at most
    /// [`MAX_MODEL_PARAMETERS`] parameters in all. Runs in time bounded by those limits, before
    /// anything is allocated for the model.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Weights(format!("invalid model config: {m}")));
        for (name, list) in [("pos_hidden", &self.pos_hidden), ("head_hidden", &self.head_hidden)] {
            if list.len() > MAX_MODEL_LIST {
                return bad(format!("{name} lists {} hidden widths; at most {MAX_MODEL_LIST} are allowed", list.len()));
            }
        }
        if self.preset.len() > 64 {
            return bad(format!("preset name is {} bytes long; at most 64 are allowed", self.preset.len()));
        }
        let mut dims: Vec<(&str, usize)> = vec![
            ("n_points", self.n_points),
            ("feature_dim", self.feature_dim),
            ("heads", self.heads),
            ("ffn_dim", self.ffn_dim),
            ("layers", self.layers),
            ("top_h", self.top_h),
            ("gaussians", self.gaussians),
            ("step_hidden", self.step_hidden),
        ];
        dims.extend(self.pos_hidden.iter().map(|&v| ("pos_hidden", v)));
        dims.extend(self.head_hidden.iter().map(|&v| ("head_hidden", v)));
        for (name, v) in dims {
            if v == 0 || v > MAX_MODEL_DIM {
                return bad(format!("{name} = {v} is outside 1..={MAX_MODEL_DIM}"));
            }
        }
        if self.layers > MAX_MODEL_LAYERS {
            return bad(format!("layers = {} is more than {MAX_MODEL_LAYERS}", self.layers));
        }
        let params = self.parameter_count_u64();
        if params > MAX_MODEL_PARAMETERS {
            return bad(format!("the config needs {params} parameters; at most {MAX_MODEL_PARAMETERS} are allowed"));
        }
        if self.n_points < 16 {
            return bad(format!("n_points = {} is fewer than 16", self.n_points));
        }
        if !self.token_dim().is_multiple_of(self.heads) {
            return bad(format!("token width {} is not divisible by heads = {}", self.token_dim(), self.heads));
        }
        if self.top_h > self.n_points {
            return bad(format!("top_h = {} exceeds n_points = {}", self.top_h, self.n_points));
        }
        if !(self.soft_temperature.is_finite() && self.soft_temperature > 0.0) {
            return bad(format!("soft_temperature = {} must be positive", self.soft_temperature));
        }
        if !(self.layer_norm_eps.is_finite() && self.layer_norm_eps > 0.0) {
            return bad(format!("layer_norm_eps = {} must be positive", self.layer_norm_eps));
        }
        Ok(())
    }

    /// Every tensor of the model, in a fixed order: `(name, shape)`. Linear weights are
    /// `[out, in]`; biases `[out]`; LayerNorm `weight`/`bias` are `[dim]`.
    pub fn tensor_specs(&self) -> Vec<(String, Vec<usize>)> {
        let mut specs = Vec::new();
        let linear = |specs: &mut Vec<(String, Vec<usize>)>, name: String, i: usize, o: usize| {
            specs.push((format!("{name}.weight"), vec![o, i]));
            specs.push((format!("{name}.bias"), vec![o]));
        };
        let c = self.feature_dim;
        let d = self.token_dim();
        for l in 0..self.layers {
            let p = format!("layers.{l}");
            let mut prev = 3;
            for (i, &h) in self.pos_hidden.iter().chain(std::iter::once(&c)).enumerate() {
                linear(&mut specs, format!("{p}.pos.{i}"), prev, h);
                prev = h;
            }
            for block in ["self_attn", "cross_attn"] {
                let b = format!("{p}.{block}");
                for proj in ["q", "k", "v", "o"] {
                    linear(&mut specs, format!("{b}.{proj}"), d, d);
                }
                specs.push((format!("{b}.norm1.weight"), vec![d]));
                specs.push((format!("{b}.norm1.bias"), vec![d]));
                linear(&mut specs, format!("{b}.ffn1"), d, self.ffn_dim);
                linear(&mut specs, format!("{b}.ffn2"), self.ffn_dim, d);
                specs.push((format!("{b}.norm2.weight"), vec![d]));
                specs.push((format!("{b}.norm2.bias"), vec![d]));
            }
            linear(&mut specs, format!("{p}.out"), d, c);
            if self.reference == Reference::Soft {
                linear(&mut specs, format!("{p}.score"), c, 1);
            }
            linear(&mut specs, format!("{p}.step.0"), 3 + c, self.step_hidden);
            linear(&mut specs, format!("{p}.step.1"), self.step_hidden, 1);
        }
        let mut prev = 2 * c;
        for (i, &h) in self.head_hidden.iter().chain(std::iter::once(&self.gaussians)).enumerate() {
            linear(&mut specs, format!("head.{i}"), prev, h);
            prev = h;
        }
        specs
    }

    /// Total number of parameters.
    pub fn parameter_count(&self) -> usize {
        self.tensor_specs().iter().map(|(_, s)| s.iter().product::<usize>()).sum()
    }

    /// [`ModelConfig::parameter_count`] by arithmetic, without listing the tensors, saturating
    /// instead of overflowing (for [`ModelConfig::validate`], on sizes not yet bounded).
    fn parameter_count_u64(&self) -> u64 {
        let n = |v: usize| v as u64;
        let linear = |i: u64, o: u64| i.saturating_mul(o).saturating_add(o);
        let (c, d) = (n(self.feature_dim), n(self.token_dim()));
        let mlp = |first: u64, hidden: &[usize], last: u64| {
            let mut prev = first;
            let mut sum = 0u64;
            for h in hidden.iter().map(|&h| n(h)).chain(std::iter::once(last)) {
                sum = sum.saturating_add(linear(prev, h));
                prev = h;
            }
            sum
        };
        let block = 4u64
            .saturating_mul(linear(d, d))
            .saturating_add(4u64.saturating_mul(d))
            .saturating_add(linear(d, n(self.ffn_dim)))
            .saturating_add(linear(n(self.ffn_dim), d));
        let score = if self.reference == Reference::Soft { linear(c, 1) } else { 0 };
        let layer = mlp(3, &self.pos_hidden, c)
            .saturating_add(2u64.saturating_mul(block))
            .saturating_add(linear(d, c))
            .saturating_add(score)
            .saturating_add(linear(3u64.saturating_add(c), n(self.step_hidden)))
            .saturating_add(linear(n(self.step_hidden), 1));
        n(self.layers).saturating_mul(layer).saturating_add(mlp(
            2u64.saturating_mul(c),
            &self.head_hidden,
            n(self.gaussians),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_paper_size_is_close_to_the_paper() {
        for p in ["web", "paper", "tiny"] {
            ModelConfig::preset(p).unwrap().validate().unwrap();
        }
        // The paper reports 13.2M; docs/design.md §7's reconstruction is ~13.8M (its MLPs have no BatchNorm).
        let n = ModelConfig::paper().parameter_count();
        assert!((12_000_000..15_000_000).contains(&n), "{n}");
        assert!(ModelConfig::preset("huge").is_err());
    }

    #[test]
    fn validation_rejects_inconsistent_sizes() {
        let mut c = ModelConfig::web();
        c.heads = 3;
        assert!(c.validate().is_err());
        let mut c = ModelConfig::web();
        c.top_h = 10_000;
        assert!(c.validate().is_err());
        let mut c = ModelConfig::web();
        c.feature_dim = 1 << 20;
        assert!(c.validate().is_err());
    }

    #[test]
    fn arithmetic_parameter_count_matches_the_tensor_list() {
        for c in [ModelConfig::web(), ModelConfig::paper(), ModelConfig::tiny()] {
            assert_eq!(c.parameter_count_u64(), c.parameter_count() as u64, "{}", c.preset);
        }
        let mut c = ModelConfig::paper();
        c.reference = Reference::Soft;
        assert_eq!(c.parameter_count_u64(), c.parameter_count() as u64);
    }

    #[test]
    fn validation_bounds_counts_and_total_size_quickly() {
        // issue 14: two million hidden widths, each valid on its own, made loading allocate
        // without bound (8.4 GB natively) before this was checked
        let mut c = ModelConfig::web();
        c.pos_hidden = vec![64; 2_000_000];
        let t = std::time::Instant::now();
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("pos_hidden lists 2000000 hidden widths"), "{e}");
        assert!(t.elapsed().as_secs_f64() < 0.5);
        let mut c = ModelConfig::web();
        c.head_hidden = vec![8; MAX_MODEL_LIST + 1];
        assert!(c.validate().is_err());
        // every dimension within its own bound, but the whole too large
        let mut c = ModelConfig::web();
        c.feature_dim = 2048;
        c.ffn_dim = 4096;
        c.layers = 16;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("parameters"), "{e}");
        let mut c = ModelConfig::web();
        c.preset = "x".repeat(1000);
        assert!(c.validate().is_err());
    }
}
