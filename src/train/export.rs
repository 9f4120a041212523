//! Parameters <-> the engine's weights.

use super::model::{check_params, Params};
use crate::model::ModelConfig;
use crate::{Result, Weights};

/// The engine's weights for trained parameters (validated against `config`). Save with
/// [`Weights::to_bytes`]; the engine loads them with [`crate::Registrar::from_bytes`].
pub fn to_weights(params: &Params, config: &ModelConfig, provenance: serde_json::Value) -> Result<Weights> {
    config.validate()?;
    check_params(config, params)?;
    Ok(Weights { config: config.clone(), provenance, tensors: params.clone(), int8: Default::default() })
}

/// Parameters to start from: the engine's deterministic random initialisation
/// ([`Weights::random`]).
pub fn init_params(config: &ModelConfig, seed: u64) -> Result<Params> {
    Ok(Weights::random(config, seed)?.tensors)
}
