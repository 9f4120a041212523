//! Validation with the engine: the current parameters become engine weights
//! ([`crate::train::to_weights`]) and every validation pair goes through
//! [`crate::Registrar::register`] exactly as a user's pair would (default options, seed 0), with ICP
//! off (network only) and, when asked, with the default point-to-plane ICP refining the network's
//! estimate only (`starts: [Network]`, so "+ICP" measures the network, not the multi-start
//! fallbacks, and stays comparable with logs written before multi-start existed). Errors are in
//! the pairs' normalised shape units, recall at 15° and 0.2 (docs/design.md §9).

use super::ValMetrics;
use crate::data::metrics::{pair_error, summarize, PairError};
use crate::data::Pair;
use crate::train::Params;
use crate::{IcpKind, ModelConfig, Options, PointCloud, Registrar, Start, Weights};

/// Recall thresholds (docs/design.md §9).
pub const ROT_THRESHOLD: f64 = 15.0;
/// Translation threshold, normalised units.
pub const TRANS_THRESHOLD: f64 = 0.2;

/// A validation pair, clouds ready for the registrar.
pub struct ValPair {
    /// Source cloud.
    pub source: PointCloud,
    /// Target cloud.
    pub target: PointCloud,
    /// Ground truth.
    pub gt: nalgebra::Matrix4<f64>,
}

impl From<&Pair> for ValPair {
    fn from(p: &Pair) -> Self {
        Self {
            source: PointCloud::new(p.source.clone()),
            target: PointCloud::new(p.target.clone()),
            gt: p.T_target_source,
        }
    }
}

fn errors(pool: &rayon::ThreadPool, weights: &Weights, pairs: &[ValPair], icp: IcpKind) -> Vec<PairError> {
    use rayon::prelude::*;
    let opts = Options { icp, starts: vec![Start::Network], ..Options::default() };
    pool.install(|| {
        pairs
            .par_iter()
            .map_init(
                || Registrar::new(weights).expect("weights validated"),
                |reg, p| match reg.register(&p.source, &p.target, &opts) {
                    Ok(r) => pair_error(&r.T_target_source, &p.gt, 1.0),
                    Err(_) => PairError { rot_deg: 180.0, trans: f64::INFINITY },
                },
            )
            .collect()
    })
}

/// Network-only (and optionally network + ICP) metrics of `params` on `pairs`.
pub fn validate(
    pool: &rayon::ThreadPool,
    config: &ModelConfig,
    params: &Params,
    pairs: &[ValPair],
    with_icp: bool,
) -> crate::Result<ValMetrics> {
    let start = std::time::Instant::now();
    let weights = crate::train::to_weights(params, config, serde_json::Value::Null)?;
    let net = summarize(&errors(pool, &weights, pairs, IcpKind::Off), &[], ROT_THRESHOLD, TRANS_THRESHOLD);
    let mut m = ValMetrics {
        pairs: pairs.len(),
        net_recall: net.recall,
        net_mre: net.mre,
        net_mte: net.mte,
        ..Default::default()
    };
    if with_icp {
        let icp = summarize(&errors(pool, &weights, pairs, IcpKind::Plane), &[], ROT_THRESHOLD, TRANS_THRESHOLD);
        m.icp_recall = Some(icp.recall);
        m.icp_mre = Some(icp.mre);
    }
    m.seconds = start.elapsed().as_secs_f64();
    Ok(m)
}
