//! Stage 6: the answer in the caller's frame.
//!
//! Takes the [`Prepared`] clouds, the network's estimate and the search's [`Chosen`] answer
//! (normalised units); gives the [`Registration`] in the caller's frame and units: the
//! normalisation, the initial guess's rotation and the clouds' origins undone, both transforms
//! checked finite, a warning added when the confidence is low. The timings are the caller's.

use super::prepare::Prepared;
use super::search::Chosen;
use crate::origin;
use crate::refine::Candidate;
use crate::register::{Registration, Timings};
use crate::{checks, Result};
use nalgebra::Matrix4;

/// Confidence below which a warning says the alignment may be wrong.
const LOW_CONFIDENCE: f64 = 0.5;

/// Maps the chosen answer back to the caller (see the module docs).
#[allow(non_snake_case)]
pub(crate) fn finish(
    prepared: &Prepared,
    t_net_n: &Matrix4<f64>,
    chosen: Chosen,
    mut warnings: Vec<String>,
    timings: Timings,
) -> Result<Registration> {
    let p = prepared;
    let s = p.norm.scale;
    let d_final = p.d_final;
    let Chosen { candidate, evidence, confidence, starts_refined } = chosen;
    let Candidate { start, T_target_source: t_n, fitness, inlier_rmse: rmse_n, iterations, converged } = candidate;
    let to_caller = |t: &Matrix4<f64>| {
        origin::to_caller(&(p.norm.denormalize(t) * p.rotate_init), p.origin_source, p.origin_target)
    };
    let T_target_source = to_caller(&t_n);
    let T_target_source_network = to_caller(t_net_n);
    checks::finite_transform(&T_target_source, "the result")?;
    checks::finite_transform(&T_target_source_network, "the network's estimate")?;
    if confidence < LOW_CONFIDENCE {
        // the evidence of another pose fitting as well, when there is some
        let others = match evidence.alternatives as usize {
            0 => String::new(),
            1 => "; another pose fits about as well (a symmetric shape?)".to_string(),
            k => format!("; {k} other poses fit about as well (a symmetric shape?)"),
        };
        warnings.push(format!(
            "low confidence {confidence:.2}: the alignment may be wrong (fitness {fitness:.2} within {:.3}, reverse overlap {:.2}{others})",
            d_final * s,
            evidence.overlap_reverse
        ));
    }
    Ok(Registration {
        T_target_source,
        T_target_source_network,
        start,
        fitness,
        inlier_rmse: rmse_n * s,
        icp_iterations: iterations,
        icp_converged: converged,
        max_correspondence_distance: d_final * s,
        timings,
        warnings,
        confidence,
        evidence,
        starts_refined,
    })
}
