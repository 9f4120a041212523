//! Stage 3: the network + GMR estimate.
//!
//! Takes the network-sampled clouds of [`crate::pipeline::prepare::Prepared`] (normalised units);
//! gives `T_target_source` in normalised units: the memberships of the network's forward pass
//! turned into Gaussian mixtures ([`gmr::gmm_params`]) and solved by weighted Procrustes
//! ([`gmr::solve`]).

use crate::model::{ForwardOutput, Model, ModelWorkspace};
use crate::{gmr, Result};
use nalgebra::Matrix4;

/// The GMR solve for a forward pass's memberships of `source` and `target`.
pub(crate) fn solve(model: &Model, source: &[[f32; 3]], target: &[[f32; 3]], out: &ForwardOutput) -> Matrix4<f64> {
    let j = model.config.gaussians;
    let g_src = gmr::gmm_params(source, &out.gamma_source, j);
    let g_tgt = gmr::gmm_params(target, &out.gamma_target, j);
    gmr::solve(&g_src, &g_tgt)
}

/// The network's forward pass on `source` and `target`, then [`solve`].
pub(crate) fn estimate(
    model: &Model,
    workspace: &mut ModelWorkspace,
    source: &[[f32; 3]],
    target: &[[f32; 3]],
) -> Result<Matrix4<f64>> {
    let out = model.forward(source, target, workspace)?;
    Ok(solve(model, source, target, &out))
}
