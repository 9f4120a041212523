//! The DGMR-ARPS network: ARPS layers (position MLP, self and cross attention, reference point,
//! step size, shifting) and the membership head (docs/design.md §4).
//!
//! One forward pass takes a source and a target cloud (normalised units, at least 16 points
//! each, usually the config's N) and returns each point's soft membership in J Gaussians; the GMM
//! parameters and the rigid solve are in [`crate::gmr`].

pub mod config;
mod layer;

pub use config::{ModelConfig, Reference};
pub use layer::{ArpsLayer, LayerWorkspace};

use crate::nn::{softmax_rows_inplace, workspace::take, Mlp};
use crate::weights::Weights;
use crate::{Error, Result};

/// What one forward pass returns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ForwardOutput {
    /// Source memberships `[N_source, J]`, rows sum to 1.
    pub gamma_source: Vec<f32>,
    /// Target memberships `[N_target, J]`, rows sum to 1.
    pub gamma_target: Vec<f32>,
    /// Step size `sigmoid(alpha)` of each layer.
    pub steps: Vec<f32>,
    /// Source shift `d^l = s^l * mu_x^l` of each layer (the reference point estimate is their sum,
    /// in the pre-centred source frame).
    pub shifts_source: Vec<[f32; 3]>,
    /// Target shift of each layer.
    pub shifts_target: Vec<[f32; 3]>,
}

/// A loaded network.
#[derive(Clone, Debug)]
pub struct Model {
    /// The sizes.
    pub config: ModelConfig,
    /// The ARPS layers.
    pub layers: Vec<ArpsLayer>,
    /// The membership head `2C -> ... -> J` (ReLU between layers, softmax after).
    pub head: Mlp,
}

/// Reusable buffers for [`Model::forward`].
#[derive(Default, Debug, Clone)]
pub struct ModelWorkspace {
    layer: LayerWorkspace,
    head_in: Vec<f32>,
    a: Vec<f32>,
    b: Vec<f32>,
}

impl Model {
    /// Builds the network from validated weights.
    pub fn from_weights(w: &Weights) -> Result<Self> {
        w.config.validate()?;
        let layers = (0..w.config.layers).map(|l| ArpsLayer::from_weights(w, l)).collect();
        let head = layer::mlp(w, "head", w.config.head_hidden.len() + 1, false);
        Ok(Self { config: w.config.clone(), layers, head })
    }

    /// Runs the network on a pair. Points are in normalised units; each cloud is pre-centred
    /// here (its own mean subtracted), so the output does not depend on where the clouds sit.
    /// Each cloud needs at least [`Model::min_points`] points (`max(top_h, 16)`), else
    /// [`Error::InvalidCloud`].
    pub fn forward(&self, source: &[[f32; 3]], target: &[[f32; 3]], ws: &mut ModelWorkspace) -> Result<ForwardOutput> {
        let min = self.min_points();
        for (what, c) in [("source", source), ("target", target)] {
            if c.len() < min {
                return Err(Error::InvalidCloud(format!(
                    "{what} has {} points; the network needs at least {min}",
                    c.len()
                )));
            }
        }
        let c = self.config.feature_dim;
        let (ns, nt) = (source.len(), target.len());
        let lw = &mut ws.layer;
        lw.reset(source, target, c);
        let mut out = ForwardOutput::default();
        for layer in &self.layers {
            let (step, ds, dt) = layer.forward(&self.config, lw);
            out.steps.push(step);
            out.shifts_source.push(ds);
            out.shifts_target.push(dt);
        }
        let j = self.config.gaussians;
        for (f, n, gamma) in [(&lw.source.f, ns, &mut out.gamma_source), (&lw.target.f, nt, &mut out.gamma_target)] {
            let h = take(&mut ws.head_in, n * 2 * c);
            let mut max = vec![f32::NEG_INFINITY; c];
            for row in f[..n * c].chunks_exact(c) {
                for (m, v) in max.iter_mut().zip(row) {
                    *m = m.max(*v);
                }
            }
            for (hr, fr) in h.chunks_exact_mut(2 * c).zip(f.chunks_exact(c)) {
                hr[..c].copy_from_slice(fr);
                hr[c..].copy_from_slice(&max);
            }
            gamma.resize(n * j, 0.0);
            self.head.forward(h, n, gamma, &mut ws.a, &mut ws.b);
            softmax_rows_inplace(gamma, j);
        }
        Ok(out)
    }

    /// Floating-point operations of one forward pass on `ns` + `nt` points (multiply-adds count
    /// as 2; matrix products only, which dominate).
    pub fn flops(&self, ns: usize, nt: usize) -> u64 {
        let c = &self.config;
        let (ns, nt) = (ns as u64, nt as u64);
        let lin = |rows: u64, i: usize, o: usize| 2 * rows * i as u64 * o as u64;
        let d = c.token_dim();
        let block = |nq: u64, nk: u64| {
            lin(nq, d, d) * 2
                + lin(nk, d, d) * 2
                + 4 * nq * nk * d as u64
                + lin(nq, d, c.ffn_dim)
                + lin(nq, c.ffn_dim, d)
        };
        let mut per_cloud_pos = 0;
        let mut prev = 3;
        for &h in c.pos_hidden.iter().chain(std::iter::once(&c.feature_dim)) {
            per_cloud_pos += lin(1, prev, h);
            prev = h;
        }
        let mut head = 0;
        let mut prev = 2 * c.feature_dim;
        for &h in c.head_hidden.iter().chain(std::iter::once(&c.gaussians)) {
            head += lin(1, prev, h);
            prev = h;
        }
        let layer = per_cloud_pos * (ns + nt)
            + block(ns, ns)
            + block(nt, nt)
            + block(ns, nt)
            + block(nt, ns)
            + lin(ns + nt, d, c.feature_dim);
        layer * c.layers as u64 + head * (ns + nt)
    }

    /// Fewest points per cloud the network accepts (the top-H size, and at least 16).
    pub fn min_points(&self) -> usize {
        self.config.top_h.max(16)
    }
}
